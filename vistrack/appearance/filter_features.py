"""The correlation filter's features (:mod:`~vistrack.appearance.correlation`): the per-pixel channels of a patch
(:func:`dcf_features`: brightness-normalised grey and gradient-orientation cells) and the frame made grey and shrunk
for the whole-frame search (:func:`shrunk_grey`)."""

from __future__ import annotations

import functools
import math

import cv2
import numpy as np

from .. import kernels

__all__ = ["dcf_features", "shrunk_grey", "as_grey", "polar_gradient", "compiled_kernels"]


def dcf_features(patch, n_orient=6, cell=4, out=None, scratch=None, window=None):
    """Feature channels ``(n_orient + 1, H, W) float32`` of a grey ``patch (H, W) float32`` (or a BGR or grey
    uint8 one, made grey as :func:`as_grey` makes it), as :mod:`~vistrack.appearance.correlation` describes them:
    brightness-normalised grey, then gradient orientation cells normalised per block; each channel times
    ``window (H, W) float32`` if given (the filter's Hann window). ``scratch``: a dict the compiled path keeps its
    work arrays in from call to call."""
    h, w = patch.shape[:2]
    if out is None:
        out = np.empty((n_orient + 1, h, w), np.float32)
    dk = compiled_kernels() if kernels.use() else None
    if dk is not None:  # the channels side by side (H, W, n): one box filter for all of them
        scratch = {} if scratch is None else scratch
        key = (h, w, n_orient)
        if key not in scratch:
            scratch[key] = (np.empty((h, w, n_orient), np.float32), np.empty((h, w, n_orient), np.float32),
                            np.empty((h, w), np.float32), np.ones((h, w), np.float32), np.empty((h, w), np.float32))
        bins, cells, sq, ones, grey = scratch[key]
        if dk.POLAR_EXACT and patch.dtype == np.uint8 and patch.ndim == 3:  # grey, gradient, bins: one pass
            total, squares = dk.grey_gradient_cells(patch, n_orient, grey, bins, sq)
            mean = total * (1.0 / (h * w))  # cv2.meanStdDev's arithmetic (its sums of integers are exact too)
            m, s = mean, math.sqrt(max(squares * (1.0 / (h * w)) - mean * mean, 0.0))
            patch = grey
        else:
            patch = as_grey(patch) if patch.ndim == 3 or patch.dtype != np.float32 else patch
            m, s = (v[0, 0] for v in cv2.meanStdDev(patch))
            if dk.POLAR_EXACT:  # the gradient, its polar form and the binning in one pass
                dk.gradient_cells(patch, n_orient, bins, sq)
            else:
                dk.orientation_cells(*polar_gradient(patch), n_orient, bins, sq)
        m, inv_s = np.float32(m), np.float32(1.0 / max(float(s), 1.0))
        energy = cv2.boxFilter(sq, -1, (2 * cell, 2 * cell), borderType=cv2.BORDER_REFLECT)
        cv2.boxFilter(bins, -1, (cell, cell), dst=cells, borderType=cv2.BORDER_REFLECT)
        return dk.normalised_cells(patch, m, inv_s, cells, energy, ones if window is None else window,
                                   window is not None, out)
    patch = as_grey(patch) if patch.ndim == 3 or patch.dtype != np.float32 else patch
    m, s = cv2.meanStdDev(patch)
    m, inv_s = np.float32(m[0, 0]), np.float32(1.0 / max(float(s[0, 0]), 1.0))
    np.multiply(patch - m, inv_s, out=out[0])
    mag, ang = polar_gradient(patch)
    energy = cv2.boxFilter(mag * mag, -1, (2 * cell, 2 * cell), borderType=cv2.BORDER_REFLECT)
    norm = np.float32(1.0) / np.sqrt(energy + np.float32(1e-2))
    pos = (ang % np.float32(np.pi)) * np.float32(n_orient / np.pi)  # unsigned orientation in bins
    lo = pos.astype(np.int32)
    frac = pos - lo.astype(np.float32)
    lo %= n_orient
    hi = (lo + 1) % n_orient
    for k in range(n_orient):
        out[k + 1] = np.where(lo == k, mag * (1 - frac), 0) + np.where(hi == k, mag * frac, 0)
    for k in range(n_orient):
        cv2.boxFilter(out[k + 1], -1, (cell, cell), dst=out[k + 1], borderType=cv2.BORDER_REFLECT)
        out[k + 1] *= norm
    if window is not None:
        np.multiply(out, window, out=out)
    return out


@functools.cache
def compiled_kernels():
    """The compiled kernels (:mod:`~vistrack.appearance.dcf_kernels`), imported on first use (their probes of
    numpy's and OpenCV's arithmetic run then, not when vistrack is imported)."""
    from . import dcf_kernels

    return dcf_kernels


def polar_gradient(patch):
    """``cv2.cartToPolar`` (magnitude, angle in radians) of the ``ksize=1`` Sobel gradient of ``patch``."""
    gx = cv2.Sobel(patch, cv2.CV_32F, 1, 0, ksize=1, borderType=cv2.BORDER_REFLECT)
    gy = cv2.Sobel(patch, cv2.CV_32F, 0, 1, ksize=1, borderType=cv2.BORDER_REFLECT)
    return cv2.cartToPolar(gx, gy)


def shrunk_grey(frame, s):
    """``frame`` (BGR or grey) made grey and shrunk by ``s`` to ``max(8, round(s W)) x max(8, round(s H))`` float32:
    halved by ``cv2.pyrDown`` (a 5-tap Gaussian, then every other pixel) while ``s`` is below a half, then read
    bilinearly: a tenth of an ``INTER_AREA`` resize's time on a 1280x720 frame (``docs/experiments.md``)."""
    h, w = frame.shape[:2]
    size = (max(8, int(round(w * s))), max(8, int(round(h * s))))
    img = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    while s < 0.5 and min(img.shape[:2]) >= 16:
        img, s = cv2.pyrDown(img), 2 * s
    return cv2.resize(img, size, interpolation=cv2.INTER_LINEAR).astype(np.float32)


def as_grey(frame):
    """``frame`` (BGR or grey) as grey float32 ``(H, W)``."""
    f = np.asarray(frame)
    g = f if f.ndim == 2 else cv2.cvtColor(f, cv2.COLOR_BGR2GRAY)
    return g.astype(np.float32)
