"""Frames handed to the Python API: converted once into what the models read (what ``vistrack run``
decodes), or refused with one line.

:func:`as_frame` takes what a user may reasonably pass to :class:`vistrack.Tracker` — a numpy array
or nested lists; ``uint8``; ``uint16`` (its top 8 bits, as OpenCV reads a 16-bit image); any other
integer type holding 0..255 (nested lists of ints); floats in 0..1 or 0..255; grey ``(H, W)`` or
``(H, W, 1)``, colour ``(H, W, 3)`` (BGR, OpenCV's order) or ``(H, W, 4)`` (BGRA: the alpha dropped,
as OpenCV's ``IMREAD_COLOR`` does) — and gives a ``uint8`` ``(H, W)`` grey or ``(H, W, 3)`` BGR
frame. Anything else (bool, complex, text, another shape, NaN, values out of range) is a
``ValueError`` naming the dtype, the shape or the values.

A float frame's range is decided on the first frame (:class:`FrameFormat`): values all within 0..1
mean 0..1 (scaled by 255), else 0..255; a later frame is read in the same range. The format of the
first frame (size, grey or colour) is the sequence's: a later frame of another size or kind is a
``ValueError`` (as ``vistrack run`` refuses an image folder whose frames change size).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["as_frame", "FrameFormat"]


@dataclass(frozen=True)
class FrameFormat:
    """What the first frame of a sequence was: ``size`` ``(width, height)``, ``colour`` (BGR or
    grey) and ``scale`` (255 for floats in 0..1, else 1)."""

    size: tuple
    colour: bool
    scale: float = 1.0

    def describe(self):
        """E.g. ``"160x120 colour"``."""
        return f"{self.size[0]}x{self.size[1]} {'colour' if self.colour else 'grey'}"


def as_frame(frame, fmt=None, what="frame"):
    """``(uint8 frame, FrameFormat)``: ``frame`` converted once (module docstring); with ``fmt``
    (the first frame's format) a frame of another size or kind is a ``ValueError``."""
    a = _array(frame, what)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] not in (3, 4)) or 0 in a.shape[:2]:
        raise ValueError(f"a {what} must be an (H, W) grey, (H, W, 1), (H, W, 3) BGR or (H, W, 4) BGRA array, "
                         f"got shape {a.shape}")
    scale = fmt.scale if fmt is not None else None
    a, scale = _to_uint8(a, scale, what)
    if a.ndim == 3 and a.shape[2] == 4:
        a = np.ascontiguousarray(a[:, :, :3])
    got = FrameFormat((a.shape[1], a.shape[0]), a.ndim == 3, scale)
    if fmt is not None and (got.size, got.colour) != (fmt.size, fmt.colour):
        raise ValueError(f"this {what} is {got.describe()}, but the tracker started on {fmt.describe()} frames: "
                         "give frames of one size and kind (start again with init for another video)")
    return a, got


def _array(frame, what):
    try:
        a = np.asarray(frame)
    except ValueError:  # ragged nested lists
        raise ValueError(f"a {what} must be a rectangular array of pixels; got ragged nested lists") from None
    if a.dtype == object or a.dtype.kind not in "uif":
        raise ValueError(f"a {what} must hold numbers (uint8, uint16, or floats in 0..1 or 0..255), got dtype "
                         f"{a.dtype}")
    return a


def _to_uint8(a, scale, what):
    """``(a as uint8, scale)``; ``scale``: a float frame's, decided here when ``None``."""
    if a.dtype == np.uint8:
        return np.ascontiguousarray(a), 1.0 if scale is None else scale
    if a.dtype == np.uint16:
        return np.ascontiguousarray((a >> 8).astype(np.uint8)), 1.0 if scale is None else scale
    lo, hi = (a.min(), a.max()) if a.size else (0, 0)
    if a.dtype.kind == "f":
        if not np.isfinite(lo) or not np.isfinite(hi):
            raise ValueError(f"a {what} of dtype {a.dtype} holds NaN or infinite values")
        first = scale is None
        if first:
            scale = 255.0 if hi <= 1.0 else 1.0
        top = 255.0 / scale
        if lo < 0 or hi > top:
            within = "0..1 or 0..255" if first else f"0..{top:g} (the range of the first frame)"
            raise ValueError(f"a {what} of dtype {a.dtype} must hold values in {within}, got {lo:g}..{hi:g}")
        return np.rint(a * scale).astype(np.uint8), scale
    if lo < 0 or hi > 255:
        raise ValueError(f"a {what} of dtype {a.dtype} must hold values in 0..255 (uint16: any), got {lo}..{hi}")
    return a.astype(np.uint8), 1.0 if scale is None else scale
