"""The box model's correlation-filter features (:mod:`~vistrack.models.box.correlation`), compiled.

- :func:`orientation_bins` is :func:`~vistrack.models.box.correlation.dcf_features`'s soft binning of the
  gradient magnitude by unsigned orientation, one pass over the pixels where numpy makes two masked
  products per channel (the same float32 arithmetic: equal, ``tests/test_box_dcf.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["orientation_bins"]


@njit(cache=True, nogil=True)
def orientation_bins(mag, ang, n_orient, out):
    """``out (n_orient + 1, H, W) float32``, channels ``1..n_orient``: the magnitude ``mag (H, W)`` split
    between the two bins about ``(ang mod π) n_orient / π`` (``ang (H, W)`` radians in ``[0, 2π)``, float32) in
    proportion to the distance, as ``dcf_features``' numpy path; channel 0 untouched."""
    h, w = mag.shape
    pi = np.float32(np.pi)
    scale = np.float32(n_orient / np.pi)
    one = np.float32(1.0)
    for k in range(1, n_orient + 1):
        for i in range(h):
            for j in range(w):
                out[k, i, j] = 0.0
    for i in range(h):
        for j in range(w):
            a = ang[i, j]  # in [0, 2 pi) from cv2.cartToPolar: a mod pi is exact (Sterbenz)
            if a >= pi:
                a -= pi
            pos = a * scale
            lo = np.int32(pos)
            frac = pos - np.float32(lo)
            lo = lo % n_orient
            hi = (lo + 1) % n_orient
            m = mag[i, j]
            out[lo + 1, i, j] += m * (one - frac)
            out[hi + 1, i, j] += m * frac
    return out
