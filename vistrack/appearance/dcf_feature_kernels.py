"""The box model's correlation-filter features (:func:`~vistrack.appearance.correlation.dcf_features`), compiled.

- :func:`gradient_cells` is :func:`~vistrack.appearance.correlation.dcf_features`'s gradient (``cv2.Sobel``,
  ``ksize=1``), its polar form (``cv2.cartToPolar``: OpenCV's ``fastAtan32f`` polynomial in fused multiply-adds,
  as its vector code computes it on FMA CPUs; equal to OpenCV's on every integer gradient a grey patch can
  give and on fractional ones, probed at import: :data:`POLAR_EXACT`) and :func:`orientation_cells` in one pass;
  :func:`grey_gradient_cells` also makes the grey patch from the BGR one (OpenCV's fixed point) and its sums.
- :func:`orientation_cells` is :func:`~vistrack.appearance.correlation.dcf_features`'s soft binning of the
  gradient magnitude by unsigned orientation, one pass over the pixels where numpy makes two masked
  products per channel, into the channels side by side ``(H, W, n)``: one ``cv2.boxFilter`` call then
  sums the cells of all of them (as it sums each alone), and :func:`normalised_cells` divides them by
  the block energy back into ``(n + 1, H, W)`` (the same float32 arithmetic: equal,
  ``tests/models/box/test_box_dcf.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..kernels.sampling import fma

__all__ = ["orientation_cells", "gradient_cells", "grey_gradient_cells", "polar", "POLAR_EXACT", "normalised_cells"]


@njit(cache=True, forceinline=True, error_model="numpy")
def _bin_row(mag_row, ang_row, n_orient, out_row, sq_row, lo, hi, wl, wh):
    """:func:`orientation_cells` of one row."""
    pi = np.float32(np.pi)
    scale = np.float32(n_orient / np.pi)
    one, zero = np.float32(1.0), np.float32(0.0)
    w = mag_row.shape[0]
    for j in range(w):
        a = ang_row[j]
        if a >= pi:
            a -= pi
        pos = a * scale
        k = np.int32(pos)
        frac = pos - np.float32(k)
        if k >= n_orient or k < 0:
            k = k % n_orient
        lo[j] = k
        hi[j] = k + 1 if k + 1 < n_orient else k + 1 - n_orient
        m = mag_row[j]
        sq_row[j] = m * m
        wl[j], wh[j] = m * (one - frac), m * frac
    out_row[:, :] = zero
    for j in range(w):
        if lo[j] == hi[j]:  # one bin
            out_row[j, lo[j]] = wl[j] + wh[j]
        else:
            out_row[j, lo[j]] = wl[j] + zero
            out_row[j, hi[j]] = zero + wh[j]


@njit(cache=True, nogil=True, error_model="numpy")
def orientation_cells(mag, ang, n_orient, out, sq):
    """The soft binning of the magnitude ``mag (H, W)`` between the two bins about
    ``(ang mod π) n_orient / π`` (``ang (H, W)`` radians in ``[0, 2π)``, float32: ``a mod π`` is exact,
    Sterbenz) in proportion to the distance, into ``out (H, W, n_orient)`` float32 (channel ``k`` at
    ``[..., k]``), each channel written once per pixel (the magnitude's share or 0, as the numpy path's
    sum of its two ``np.where``), and ``sq (H, W)`` = ``mag * mag`` (float32)."""
    h, w = mag.shape
    lo, hi = np.empty(w, np.int64), np.empty(w, np.int64)
    wl, wh = np.empty(w, np.float32), np.empty(w, np.float32)
    for i in range(h):
        _bin_row(mag[i], ang[i], n_orient, out[i], sq[i], lo, hi, wl, wh)
    return out


_PI = 3.1415926535897932384626433832795
#: OpenCV's ``fastAtan32f`` polynomial (degrees), its coefficients as OpenCV rounds them to float32
_P1 = np.float32(np.float32(0.9997878412794807) * np.float32(180 / _PI))
_P3 = np.float32(np.float32(-0.3258083974640975) * np.float32(180 / _PI))
_P5 = np.float32(np.float32(0.1555786518463281) * np.float32(180 / _PI))
_P7 = np.float32(np.float32(-0.04432655554792128) * np.float32(180 / _PI))
_EPS = np.float32(2.220446049250313e-16)  # (float)DBL_EPSILON
_RAD = np.float32(_PI / 180)


@njit(cache=True, forceinline=True, error_model="numpy")
def _polar(x, y):
    """``cv2.cartToPolar``'s magnitude and angle (radians) of one float32 gradient ``(x, y)`` as its
    vector code computes them on FMA CPUs: ``sqrt(fma(x, x, y y))`` and the polynomial in fused multiply-adds."""
    ax, ay = abs(x), abs(y)
    c = min(ax, ay) / (max(ax, ay) + _EPS)
    cc = c * c
    a = fma(fma(fma(cc, _P7, _P5), cc, _P3), cc, _P1) * c
    a = a if ax >= ay else np.float32(90.0) - a  # selects, not branches: the loops vectorise
    a = np.float32(180.0) - a if x < np.float32(0.0) else a
    a = np.float32(360.0) - a if y < np.float32(0.0) else a
    return np.sqrt(fma(x, x, y * y)), a * _RAD


@njit(cache=True, nogil=True, error_model="numpy")
def polar(x, y, mag, ang):
    """:func:`_polar` of every element of ``x, y (H, W)`` float32 into ``mag, ang`` (:data:`POLAR_EXACT`'s probe)."""
    for i in range(x.shape[0]):
        for j in range(x.shape[1]):
            mag[i, j], ang[i, j] = _polar(x[i, j], y[i, j])


@njit(cache=True, nogil=True, error_model="numpy")
def grey_gradient_cells(bgr, n_orient, grey, out, sq):
    """``grey (H, W)`` float32 = ``cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)`` of ``bgr (H, W, 3)`` uint8 (OpenCV's
    fixed point, ``(3735 B + 19235 G + 9798 R + 2^14) >> 15``: equal on every colour), then
    :func:`gradient_cells` of it; returns the grey levels' sum and sum of squares (integers: exact)."""
    h, w = grey.shape
    total = squares = 0
    for i in range(h):
        for j in range(w):
            v = (3735 * np.int64(bgr[i, j, 0]) + 19235 * np.int64(bgr[i, j, 1]) + 9798 * np.int64(bgr[i, j, 2])
                 + 16384) >> 15
            grey[i, j] = np.float32(v)
            total += v
            squares += v * v
    gradient_cells(grey, n_orient, out, sq)
    return float(total), float(squares)


@njit(cache=True, nogil=True, error_model="numpy")
def gradient_cells(patch, n_orient, out, sq):
    """:func:`orientation_cells` of the gradient of ``patch (H, W)`` float32: ``cv2.Sobel``'s ``ksize=1``
    differences (``BORDER_REFLECT``: one subtraction each, as OpenCV's) and ``cv2.cartToPolar`` (:func:`_polar`;
    equal where :data:`POLAR_EXACT`) in the same pass, where OpenCV makes four."""
    h, w = patch.shape
    lo, hi = np.empty(w, np.int64), np.empty(w, np.int64)
    wl, wh = np.empty(w, np.float32), np.empty(w, np.float32)
    mag, ang = np.empty(w, np.float32), np.empty(w, np.float32)
    gx, gy = np.empty(w, np.float32), np.empty(w, np.float32)
    for i in range(h):
        ia, ib = (i - 1 if i > 0 else 0), (i + 1 if i + 1 < h else h - 1)
        row, up, down = patch[i], patch[ia], patch[ib]
        gx[0], gx[w - 1] = row[min(1, w - 1)] - row[0], row[w - 1] - row[max(w - 2, 0)]
        for j in range(1, w - 1):
            gx[j] = row[j + 1] - row[j - 1]
        for j in range(w):
            gy[j] = down[j] - up[j]
        for j in range(w):
            mag[j], ang[j] = _polar(gx[j], gy[j])
        _bin_row(mag, ang, n_orient, out[i], sq[i], lo, hi, wl, wh)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def normalised_cells(patch, mean, inv_std, cells, energy, window, windowed, out):
    """``out[0] = (patch - mean) inv_std`` and ``out[k + 1] = cells[..., k] * norm`` with ``norm = 1 / sqrt(energy
    + 0.01)`` (float32, ``energy (H, W)``: correctly rounded square root and division, as numpy's), each then
    times ``window (H, W)`` if ``windowed``: the numpy path's products in its order."""
    h, w, n = cells.shape
    one, eps = np.float32(1.0), np.float32(1e-2)
    norm = np.empty(w, np.float32)
    for i in range(h):
        for j in range(w):
            v = (patch[i, j] - mean) * inv_std
            out[0, i, j] = v * window[i, j] if windowed else v
            norm[j] = one / np.sqrt(energy[i, j] + eps)
        for k in range(n):
            for j in range(w):
                v = cells[i, j, k] * norm[j]
                out[k + 1, i, j] = v * window[i, j] if windowed else v
    return out


def _polar_exact():
    """Whether :func:`polar` computes ``cv2.cartToPolar`` on this CPU (its vector code uses fused multiply-adds
    where the CPU has them): probed on integer gradients (what grey patches give) and on fractional ones,
    where the fused and the plain products differ."""
    import cv2

    rng = np.random.default_rng(0)
    x = np.concatenate([rng.integers(-255, 256, 4096), rng.random(4096) * 510 - 255]).astype(np.float32)
    y = np.concatenate([rng.integers(-255, 256, 4096), rng.random(4096) * 510 - 255]).astype(np.float32)
    x, y = x.reshape(64, 128), y.reshape(64, 128)
    mag, ang = np.empty_like(x), np.empty_like(x)
    polar(x, y, mag, ang)
    want = cv2.cartToPolar(x, y)
    return bool(np.array_equal(mag, want[0]) and np.array_equal(ang, want[1]))


#: whether :func:`gradient_cells` computes what ``cv2.Sobel`` and ``cv2.cartToPolar`` give on this CPU
POLAR_EXACT = _polar_exact()
