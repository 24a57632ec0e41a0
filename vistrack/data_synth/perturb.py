"""Stressed copies of real clips, their ground truth transformed exactly.

The failure modes seen on footage a tracker has not been tuned on — light that changes, motion
blur, a shaking camera, an object that changes size, a low frame rate — applied to any clip with
box ground truth (``vistrack synth perturb CLIP --out DIR``):

``light``
    ``"ramp"``: a global gain going linearly from ``gain[0]`` to ``gain[1]`` over the clip (from
    dark into light by default, ×0.3 → ×1.6, saturating); ``"flicker"``: an independent gain per
    frame, log-uniform in ``gain``.
``blur``
    Motion blur with a line kernel ``blur`` pixels long, along a random direction per frame.
``shake``
    Camera shake: each frame translated by a uniform random ``(dx, dy)`` in ``[-shake, shake]²``.
``zoom``
    ``(a, b)``: the frame scaled about the object's centre by ``s_t = a (b / a)^(t / (T - 1))``, so
    the object's size goes from ``a`` to ``b`` times its own while its centre stays where the camera
    saw it.
``drop``
    Every ``drop``-th frame removed (frames ``drop - 1, 2 drop - 1, ...``), with its ground-truth row.

Geometry (zoom, then shake) is one affine map per frame ``M_t: x -> s_t x + d_t`` in pixel-centre
coordinates, applied to the frame with :func:`cv2.warpAffine` and to the box exactly: a box
``(x, y, w, h)`` (edges ``x`` and ``x + w`` in pixel-edge coordinates, pixel ``i`` covering
``[i, i + 1)``) maps to ``(s_t (x - 1/2) + d_t + 1/2, ..., s_t w, s_t h)``. Blur and light then act
on pixel values only and leave the ground truth as it is. Frames without the object keep the
``0,0,0,0`` row.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np

from vistrack.io.video import VideoWriter, find_groundtruth, groundtruth_origin, open_video, read_rects

from .scene import atomic_clip, motion_blur

__all__ = ["Perturbation", "perturb_frames", "perturb_clip", "STRESS_PRESETS", "PerturbWarning", "DEFAULT_GAIN"]

LIGHTS = ("ramp", "flicker")
#: the gain range of a light stress unless one is given: from dark into light
DEFAULT_GAIN = (0.3, 1.6)


class PerturbWarning(UserWarning):
    """A stress that leaves the copy of little use (the object out of view)."""


@dataclass(frozen=True)
class Perturbation:
    """What to do to a clip (every field off by default; see the module doc for each)."""

    light: str | None = None
    #: the gain range of ``light`` (``None``: :data:`DEFAULT_GAIN`); only with a ``light``
    gain: tuple[float, float] | None = None
    blur: int = 0
    shake: float = 0.0
    zoom: tuple[float, float] | None = None
    drop: int = 0
    seed: int = 0

    def __post_init__(self):
        if self.light is not None and self.light not in LIGHTS:
            raise ValueError(f"light must be one of {', '.join(LIGHTS)}, got {self.light!r}")
        # (a gain equal to the default is what every perturbation holds: one remade from its fields passes)
        if self.gain is not None and self.light is None and tuple(self.gain) != DEFAULT_GAIN:
            raise ValueError("--gain sets the range of --light: give --light ramp or --light flicker with it")
        if self.gain is None:
            object.__setattr__(self, "gain", DEFAULT_GAIN)
        g0, g1 = self.gain
        if not (0 < g0 < 100 and 0 < g1 < 100):
            raise ValueError(f"gain must be two positive factors below 100, got {g0}:{g1}")
        if self.blur < 0 or self.blur > 200:
            raise ValueError(f"blur must be a kernel length of 0 to 200 px, got {self.blur}")
        if not (0 <= self.shake <= 1000):
            raise ValueError(f"shake must be 0 to 1000 px, got {self.shake}")
        if self.zoom is not None and not all(0.05 <= z <= 20 for z in self.zoom):
            raise ValueError(f"zoom factors must lie in 0.05..20, got {self.zoom[0]}:{self.zoom[1]}")
        if self.drop == 1 or self.drop < 0:
            raise ValueError(f"drop must be 0 (none) or at least 2 (every K-th frame), got {self.drop}")

    @property
    def name(self):
        """A short label of what is on, e.g. ``"ramp+blur9"`` (``"none"`` when nothing is)."""
        parts = [self.light] if self.light else []
        parts += [f"blur{self.blur}"] if self.blur else []
        parts += [f"shake{self.shake:g}"] if self.shake else []
        parts += [f"zoom{self.zoom[0]:g}-{self.zoom[1]:g}"] if self.zoom else []
        parts += [f"drop{self.drop}"] if self.drop else []
        return "+".join(parts) or "none"

    def kept(self, n):
        """How many of ``n`` frames the stressed copy keeps (``drop`` removes every ``drop``-th)."""
        return n - (n // self.drop if self.drop else 0)


#: the stresses the real-clip benchmark reports beside each original clip
STRESS_PRESETS = {
    "ramp": Perturbation(light="ramp"),
    "blur": Perturbation(blur=9),
    "shake": Perturbation(shake=6.0),
    "zoom": Perturbation(zoom=(1.6, 1.0)),  # the object shrinks to 0.6 of its first size; no border shows
    "flicker": Perturbation(light="flicker"),
    "drop": Perturbation(drop=2),
}


def _centres(gt):
    """Object centres ``(T, 2)`` in pixel-edge coordinates; frames without the object hold the last
    centre seen (the first seen before it; the frame origin when there is none)."""
    c = gt[:, :2] + gt[:, 2:] / 2
    seen = (gt[:, 2] > 0) & (gt[:, 3] > 0)
    if not seen.any():
        return np.zeros_like(c)
    idx = np.where(seen, np.arange(len(gt)), -1)
    idx = np.maximum.accumulate(idx)
    idx[idx < 0] = np.argmax(seen)
    return c[idx]


def geometry(p, gt, rng):
    """Per-frame scale ``s (T,)`` and offset ``d (T, 2)`` of the map ``x -> s x + d`` (pixel-centre
    coordinates) for ground truth ``gt (T, 4)``; draws the shake from ``rng``."""
    n = len(gt)
    s = np.ones(n)
    d = np.zeros((n, 2))
    if p.zoom is not None:
        a, b = p.zoom
        s = a * (b / a) ** (np.arange(n) / max(n - 1, 1))
        c = _centres(gt) - 0.5  # pixel-centre coordinates
        d = c * (1 - s[:, None])
    if p.shake:
        d = d + rng.uniform(-p.shake, p.shake, (n, 2))
    return s, d


def transform_boxes(gt, s, d):
    """Boxes ``(T, 4)`` under ``x -> s_t x + d_t``; rows without the object stay ``0,0,0,0``."""
    out = np.array(gt, dtype=float)
    seen = (gt[:, 2] > 0) & (gt[:, 3] > 0)
    out[:, :2] = s[:, None] * (gt[:, :2] - 0.5) + d + 0.5
    out[:, 2:] = s[:, None] * gt[:, 2:]
    out[~seen] = 0.0
    return out


def perturb_frames(frames, gt, p):
    """Apply ``p`` to a clip.

    Parameters
    ----------
    frames : iterable of ndarray
        ``(H, W, 3)`` or ``(H, W)`` uint8 frames, as many as rows of ``gt``.
    gt : ndarray, shape (T, 4)
        0-based ``x, y, w, h`` per frame (``0,0,0,0``: not in view).
    p : Perturbation

    Yields
    ------
    t : int
        Index of the source frame (dropped frames are skipped).
    frame : ndarray
        The stressed frame, same shape and dtype.
    box : ndarray, shape (4,)
        Its exact ground truth.
    """
    gt = np.asarray(gt, dtype=float).reshape(-1, 4)
    n = len(gt)
    rng = np.random.default_rng(p.seed)
    s, d = geometry(p, gt, rng)
    boxes = transform_boxes(gt, s, d)
    angle = rng.uniform(0.0, np.pi, n)
    if p.light == "ramp":
        gain = np.linspace(p.gain[0], p.gain[1], n)
    elif p.light == "flicker":
        gain = np.exp(rng.uniform(np.log(min(p.gain)), np.log(max(p.gain)), n))
    else:
        gain = np.ones(n)
    for t, frame in enumerate(frames):
        if t >= n:
            break
        if p.drop and t % p.drop == p.drop - 1:
            continue
        img = np.asarray(frame)
        if s[t] < 1.0:  # a camera zooming out integrates over the finer pixels: no aliasing
            img = cv2.GaussianBlur(img, (0, 0), 0.5 * np.sqrt(1.0 / s[t] ** 2 - 1.0) + 1e-3,
                                   borderType=cv2.BORDER_REPLICATE)
        if s[t] != 1.0 or d[t].any():
            m = np.array([[s[t], 0.0, d[t, 0]], [0.0, s[t], d[t, 1]]])
            img = cv2.warpAffine(img, m, (img.shape[1], img.shape[0]), flags=cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_REPLICATE)
        if p.blur:
            img = motion_blur(img, p.blur * np.array([np.cos(angle[t]), np.sin(angle[t])]), border=cv2.BORDER_REPLICATE)
        if gain[t] != 1.0:
            img = np.clip(np.rint(img.astype(np.float32) * gain[t]), 0, 255).astype(np.uint8)
        yield t, img, _in_view(boxes[t], img.shape[1], img.shape[0])


def _in_view(box, w, h):
    """``box`` (0-based ``x, y, w, h``), or ``0,0,0,0`` (not in view) where the geometry moved it
    wholly out of the ``w`` x ``h`` frame."""
    x, y, bw, bh = box
    if bw > 0 and bh > 0 and (x >= w or y >= h or x + bw <= 0 or y + bh <= 0):
        return np.zeros(4)
    return box


def read_clip(clip):
    """``(video path, fps, frames iterator, gt (T, 4) 0-based)`` of a clip folder or video with box
    ground truth beside it."""
    src = Path(clip)
    gt_path = find_groundtruth(src)
    if gt_path is None:
        raise ValueError(f"{src} has no box ground truth (groundtruth_rect.txt or groundtruth.txt)")
    gt = read_rects(gt_path, origin=groundtruth_origin(gt_path))
    video = open_video(src)
    return video, gt


@atomic_clip
def perturb_clip(out, clip, p, progress=None):
    """Write a stressed copy of ``clip`` into the folder ``out``: ``<name>.mp4`` (H.264),
    ``groundtruth_rect.txt`` (0-based ``x,y,w,h``, exact) and ``perturb.json`` (the source and ``p``).

    Returns the number of frames written.
    """
    src = Path(clip)
    video, gt = read_clip(src)
    name = (src if src.is_dir() else src.parent).name
    out.mkdir(parents=True)
    rows, kept, writer = [], [], None
    try:
        for t, img, box in perturb_frames((f for _, f in video), gt, p):
            kept.append(t)
            if writer is None:
                writer = VideoWriter(out / f"{name}.mp4", video.fps or 30.0, (img.shape[1], img.shape[0]),
                                     codec="auto")
            writer.write(img)
            rows.append(box)
            if progress is not None:
                progress(1)
    finally:
        if writer is not None:
            writer.close()
    if not rows:
        raise ValueError(f"{src}: no frame to write")
    gone = sum(1 for t, box in zip(kept, rows) if gt[t, 2] > 0 and gt[t, 3] > 0 and not box[2] > 0)
    if gone:
        warnings.warn(f"the {p.name} stress moves the object wholly out of the frame in {gone} of the {len(rows)} "
                      "frames: their ground truth is 0,0,0,0 (not in view)", PerturbWarning, stacklevel=2)
    np.savetxt(out / "groundtruth_rect.txt", np.array(rows), fmt="%.3f", delimiter=",")
    meta = {"source": str(src.resolve()), "video": f"{name}.mp4", "frames_in": int(len(gt)), "frames_out": len(rows),
            **asdict(p)}
    (out / "perturb.json").write_text(json.dumps(meta, indent=2) + "\n")
    return len(rows)
