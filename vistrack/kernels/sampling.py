"""Bilinear sampling as ``cv2.remap`` does it, and numpy's pairwise summation, for the kernels.

``cv2.remap`` with float maps and ``INTER_LINEAR`` (OpenCV 4 and 5) rounds each coordinate to
1/32 px (round half to even), takes the four pixels about it and weights them with products of
the 1-D weights ``(1 - a, a)``, ``a`` a multiple of 1/32 (so the weights are exact), summed as
``((p00 w00 + p01 w01) + p10 w10) + p11 w11`` in float32. With ``BORDER_CONSTANT`` a point whose
four pixels all lie outside the image is the border value, and a pixel outside the image counts
as the border value. :func:`corner` and :func:`lerp4` do exactly that, so a kernel's samples are
``cv2.remap``'s bit for bit (``tests/kernels/test_kernels.py``). A point with a NaN or infinite coordinate
is NaN in a 1-, 3- or 4-channel image and the border value in a 2-channel one (OpenCV 5's
paths differ there); ``lerp4`` returns its ``nonfinite`` argument for it.

``np.sum`` of a 1-D float array (contiguous or strided) is a pairwise sum: 8 running sums under
129 elements, halves (at multiples of 8) above; :func:`pairwise_sum` is the same.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

__all__ = ["corner", "lerp4", "fma", "corner_float", "lerp_fma", "fma_lerp", "inside", "sample", "pairwise_sum",
           "NONFINITE"]

_F32 = np.float32
#: the corner :func:`corner` gives a point with a NaN or infinite coordinate
NONFINITE = -(1 << 40)


@njit(cache=True, forceinline=True, error_model="numpy")
def corner(x, y):
    """``(ix, iy, ax, ay)``: the top-left pixel of float32 map point ``(x, y)`` and the 1/32-px
    fractions (float32) that ``cv2.remap`` uses."""
    if not (np.isfinite(x) and np.isfinite(y)):
        return NONFINITE, NONFINITE, _F32(0.0), _F32(0.0)
    xi = int(np.rint(x * _F32(32.0)))
    yi = int(np.rint(y * _F32(32.0)))
    return xi >> 5, yi >> 5, _F32(xi & 31) * _F32(0.03125), _F32(yi & 31) * _F32(0.03125)


@njit(cache=True, forceinline=True, error_model="numpy")
def _pixels(img, ix, iy, c, border):
    """``(any inside, p00, p01, p10, p11)``: channel ``c`` of the 2×2 pixels of ``img (H, W, C)``
    at the corner ``ix, iy``, ``border`` for those outside the image."""
    h, w = img.shape[0], img.shape[1]
    if 0 <= ix < w - 1 and 0 <= iy < h - 1:  # unsigned indices: no negative-index wraparound
        y0, x0, cc, one = np.uint64(iy), np.uint64(ix), np.uint64(c), np.uint64(1)
        p00, p01 = img[y0, x0, cc], img[y0, x0 + one, cc]
        p10, p11 = img[y0 + one, x0, cc], img[y0 + one, x0 + one, cc]
        return True, p00, p01, p10, p11
    if ix >= w or ix + 1 < 0 or iy >= h or iy + 1 < 0:
        return False, border, border, border, border
    in0, in1 = 0 <= ix < w, 0 <= ix + 1 < w
    r0, r1 = 0 <= iy < h, 0 <= iy + 1 < h
    p00 = img[iy, ix, c] if r0 and in0 else border
    p01 = img[iy, ix + 1, c] if r0 and in1 else border
    p10 = img[iy + 1, ix, c] if r1 and in0 else border
    p11 = img[iy + 1, ix + 1, c] if r1 and in1 else border
    return True, p00, p01, p10, p11


@njit(cache=True, forceinline=True, error_model="numpy")
def lerp4(img, ix, iy, ax, ay, c, border, nonfinite):
    """Channel ``c`` of ``img (H, W, C)`` float32 interpolated at the corner ``ix, iy`` with the
    fractions ``ax, ay`` (:func:`corner`); ``border`` outside, ``nonfinite`` at :data:`NONFINITE`."""
    if ix == NONFINITE:
        return nonfinite
    bx, by = _F32(1.0) - ax, _F32(1.0) - ay
    w00, w01, w10, w11 = by * bx, by * ax, ay * bx, ay * ax
    inside, p00, p01, p10, p11 = _pixels(img, ix, iy, c, border)
    if not inside:
        return border
    return p00 * w00 + p01 * w01 + p10 * w10 + p11 * w11


@intrinsic
def fma(typingctx, a, b, c):
    """``a * b + c`` rounded once (float32 or float64, all three of one type; LLVM's ``llvm.fma``, one
    instruction on FMA CPUs)."""
    if not (a == b == c and a in (types.float32, types.float64)):
        return None
    sig = a(a, b, c)

    def codegen(context, builder, signature, args):
        return builder.fma(*args)

    return sig, codegen


@njit(cache=True, forceinline=True, error_model="numpy")
def corner_float(x, y):
    """``(ix, iy, a, b)``: the top-left pixel of float32 point ``(x, y)`` and the exact fractions
    ``x - floor(x)``, ``y - floor(y)`` (float32), as ``cv2.remap`` takes them for 1-, 3- and
    4-channel images; :data:`NONFINITE` for a NaN or infinite coordinate."""
    if not (np.isfinite(x) and np.isfinite(y)):
        return NONFINITE, NONFINITE, _F32(0.0), _F32(0.0)
    fx, fy = np.floor(x), np.floor(y)
    return int(fx), int(fy), x - fx, y - fy


@njit(cache=True, forceinline=True, error_model="numpy")
def lerp_fma(img, ix, iy, a, b, c, border, nonfinite):
    """Channel ``c`` of ``img (H, W, C)`` float32 at the corner ``ix, iy`` with the fractions
    ``a, b`` (:func:`corner_float`) as ``cv2.remap`` computes it for 1-, 3- and 4-channel images:
    ``t0 = fma(a, p01 - p00, p00)``, ``t1 = fma(a, p11 - p10, p10)``, ``fma(b, t1 - t0, t0)``;
    ``border`` for pixels outside, ``nonfinite`` at :data:`NONFINITE`."""
    if ix == NONFINITE:
        return nonfinite
    inside, p00, p01, p10, p11 = _pixels(img, ix, iy, c, border)
    if not inside:
        return border
    return fma_lerp(p00, p01, p10, p11, a, b)


@njit(cache=True, forceinline=True, error_model="numpy")
def fma_lerp(p00, p01, p10, p11, a, b):
    """``cv2.remap``'s interpolation of four float32 pixels for 1-, 3- and 4-channel images:
    ``t0 = fma(a, p01 - p00, p00)``, ``t1 = fma(a, p11 - p10, p10)``, ``fma(b, t1 - t0, t0)``
    (scalars only: a kernel's inner loop reads the pixels itself, see :func:`inside`)."""
    t0 = fma(a, p01 - p00, p00)
    t1 = fma(a, p11 - p10, p10)
    return fma(b, t1 - t0, t0)


@njit(cache=True, forceinline=True, error_model="numpy")
def inside(ix, iy, w, h):
    """Whether the four pixels at corner ``ix, iy`` lie in a ``w x h`` image (the unchecked path;
    numba counts references on every call that passes an array, so hot loops read pixels inline
    and call :func:`lerp4` / :func:`lerp_fma` only at the border)."""
    return 0 <= ix < w - 1 and 0 <= iy < h - 1


@njit(cache=True, nogil=True, error_model="numpy")
def sample(img, x, y, border):
    """All channels of ``img (H, W, C)`` float32 at float32 points ``x, y (P,)``: ``(P, C)`` float32,
    equal to ``cv2.remap`` (``BORDER_CONSTANT`` with ``border (C,)`` float32, one value per channel)."""
    out = np.empty((x.shape[0], img.shape[2]), np.float32)
    for i in range(x.shape[0]):
        if img.shape[2] == 2:
            ix, iy, ax, ay = corner(x[i], y[i])
            for c in range(2):
                out[i, c] = lerp4(img, ix, iy, ax, ay, c, border[c], border[c])
        else:
            ix, iy, a, b = corner_float(x[i], y[i])
            for c in range(img.shape[2]):
                out[i, c] = lerp_fma(img, ix, iy, a, b, c, border[c], np.float32(np.nan))
    return out


@njit(cache=True, forceinline=True, error_model="numpy")
def _block_sum(a, lo, n):
    """numpy's pairwise sum of ``a[lo:lo + n]`` for ``1 <= n <= 128`` (no split)."""
    if n < 8:
        res = a[lo]  # numpy starts from 0, and 0 + a[lo] is a[lo]
        for i in range(1, n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - n % 8:
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@njit(cache=True, nogil=True, error_model="numpy")
def pairwise_sum(a, lo, n):
    """``np.sum(a[lo:lo + n])`` of a 1-D array, ``n >= 1``, summed in numpy's order (module
    docstring): blocks of at most 128 summed by :func:`_block_sum`, halves (at multiples of 8)
    added, the recursion unrolled on an explicit stack."""
    if n <= 128:
        return _block_sum(a, lo, n)
    # post-order walk of the halving tree: (lo, n, visited) on a stack, partial sums on another
    seg = np.empty((64, 3), np.int64)
    vals = np.empty(64, a.dtype)
    top, nv = 0, 0
    seg[0, 0], seg[0, 1], seg[0, 2] = lo, n, 0
    while top >= 0:
        s_lo, s_n, done = seg[top, 0], seg[top, 1], seg[top, 2]
        if s_n <= 128:
            vals[nv] = _block_sum(a, s_lo, s_n)
            nv += 1
            top -= 1
        elif done:
            vals[nv - 2] = vals[nv - 2] + vals[nv - 1]
            nv -= 1
            top -= 1
        else:
            n2 = s_n // 2
            n2 -= n2 % 8
            seg[top, 2] = 1
            seg[top + 1, 0], seg[top + 1, 1], seg[top + 1, 2] = s_lo + n2, s_n - n2, 0
            seg[top + 2, 0], seg[top + 2, 1], seg[top + 2, 2] = s_lo, n2, 0
            top += 2
    return vals[0]
