"""The plate likelihood's maps and pixel-set means (:mod:`~vistrack.models.plate.likelihood`), compiled.

- :func:`plate_map` is ``PlateLikelihood.maps``: ``(|∇_x I|, |∇_y I|, |G_s I|, |G_l I|)`` in one pass from
  the Sobel maps and the box filters' integer sums (scaled in double as OpenCV's normalised box filter does),
  and the four means (summed in double: the sums of these values are exact, so their order does not
  matter), then each channel divided by its mean (by its reciprocal in double: the same float32):
  equal to the numpy path.
- :func:`set_means` is ``PlateLikelihood._set_means`` of the sampled points: the points placed
  as ``plate_points`` places them (the same float64 arithmetic, ``tan θ`` given), each sampled in
  the channels its pixel set's features read only, as ``cv2.remap`` samples (bit for bit), and each
  feature's mean a float32 pairwise sum as ``np.mean``'s: equal to the numpy path.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...kernels.sampling import corner_float, fma_lerp, inside, lerp_fma, pairwise_sum

__all__ = ["plate_map", "set_means", "set_index", "place", "means_at"]


@njit(cache=True, nogil=True)
def plate_map(gx, gy, sums, sizes, out):
    """The 4-channel map ``out (H, W, 4)`` float32, each channel over its frame mean: ``|gx|``, ``|gy|``
    (Sobel, float32) and the two DoGs ``|box_i - box_o|`` from the box sums ``sums (4, H, W)`` int32
    of the boxes ``sizes`` (s_inner, s_outer, l_inner, l_outer), each ``float32(sum / size²)`` as
    OpenCV's normalised box filter (in double). Returns the four channels' means (summed in double);
    :func:`_normalise` divides."""
    h, w = out.shape[0], out.shape[1]
    k0, k1 = 1.0 / (sizes[0] * sizes[0]), 1.0 / (sizes[1] * sizes[1])
    k2, k3 = 1.0 / (sizes[2] * sizes[2]), 1.0 / (sizes[3] * sizes[3])
    m0 = m1 = m2 = m3 = 0.0
    for y in range(h):
        for x in range(w):
            a = abs(gx[y, x])
            b = abs(gy[y, x])
            c = abs(np.float32(sums[0, y, x] * k0) - np.float32(sums[1, y, x] * k1))
            d = abs(np.float32(sums[2, y, x] * k2) - np.float32(sums[3, y, x] * k3))
            out[y, x, 0], out[y, x, 1], out[y, x, 2], out[y, x, 3] = a, b, c, d
            m0 += a
            m1 += b
            m2 += c
            m3 += d
    scale = 1.0 / (h * w)
    means = np.array([m0 * scale, m1 * scale, m2 * scale, m3 * scale])
    _normalise(out.reshape(-1), means)
    return means


@njit(cache=True, nogil=True)
def _normalise(flat, means):
    """Each channel of the interleaved ``flat (4 P,)`` over ``float32(max(mean, 1e-6))``, as the numpy
    path divides: ``c / d`` as ``float32(c · (1 / d))`` in double (a multiplication instead of a
    division), which rounds as the float32 division does — the exact quotient of two float32 lies
    at least about 2^-49 (relative) from a float32 rounding boundary, farther than the two double
    roundings can move it."""
    r0 = 1.0 / np.float64(np.float32(max(means[0], 1e-6)))
    r1 = 1.0 / np.float64(np.float32(max(means[1], 1e-6)))
    r2 = 1.0 / np.float64(np.float32(max(means[2], 1e-6)))
    r3 = 1.0 / np.float64(np.float32(max(means[3], 1e-6)))
    for i in range(0, flat.shape[0], 4):
        flat[i] = np.float32(flat[i] * r0)
        flat[i + 1] = np.float32(flat[i + 1] * r1)
        flat[i + 2] = np.float32(flat[i + 2] * r2)
        flat[i + 3] = np.float32(flat[i + 3] * r3)


@njit(cache=True, nogil=True)
def set_index(sets, feats):
    """The features of each pixel set: ``per_set (S,)`` how many, ``which (S, F)`` which, and the widest
    set's point count (one sample row of that width per feature)."""
    n_sets, n_feats = sets.shape[0], feats.shape[0]
    per_set = np.zeros(n_sets, np.int64)
    which = np.empty((n_sets, n_feats), np.int64)
    for f in range(n_feats):
        k = feats[f, 0]
        which[k, per_set[k]] = f
        per_set[k] += 1
    width = 0
    for k in range(n_sets):
        width = max(width, sets[k, 1])
    return per_set, which, width


@njit(cache=True, forceinline=True)
def place(pts, u, v, s, t, aspect, base):
    """``base (P, 2)``: the unit-square points ``pts`` placed at the pose ``(u, v, θ, s)`` (``t = tan θ``)
    with the float64 arithmetic of ``plate_points``."""
    for i in range(pts.shape[0]):
        a, b = pts[i, 0], pts[i, 1]
        base[i, 0] = u + (a - 0.5) * s
        base[i, 1] = v + (b - 0.5) * s / aspect + (a - 0.5) * s * t


@njit(cache=True, forceinline=True)
def means_at(img, base, ox, oy, sets, feats, index, border, buf, out, o):
    """The features' means of the placed points ``base`` shifted by ``(ox, oy)`` px into
    ``out[o:o + F]`` (float32): each point sampled as ``cv2.remap`` samples it, in the channels its
    set's features read, each mean a float32 pairwise sum as ``np.mean``'s. ``index`` is
    :func:`set_index`'s, ``buf`` its rows of samples."""
    per_set, which, width = index
    h, w = img.shape[0], img.shape[1]
    nan = np.float32(np.nan)
    for k in range(sets.shape[0]):
        start, count = sets[k, 0], sets[k, 1]
        for i in range(count):
            x = np.float32(base[start + i, 0] + ox)
            y = np.float32(base[start + i, 1] + oy)
            ix, iy, fa, fb = corner_float(x, y)
            fast = inside(ix, iy, w, h)
            if fast:
                y0, x0 = np.uint64(iy), np.uint64(ix)
                y1, x1 = y0 + np.uint64(1), x0 + np.uint64(1)
            for j in range(per_set[k]):
                f = which[k, j]
                ch = feats[f, 1]
                if fast:
                    cc = np.uint64(ch)
                    val = fma_lerp(img[y0, x0, cc], img[y0, x1, cc], img[y1, x0, cc], img[y1, x1, cc], fa, fb)
                else:
                    val = lerp_fma(img, ix, iy, fa, fb, ch, border[ch], nan)
                buf[f * width + i] = val
    for f in range(feats.shape[0]):
        count = sets[feats[f, 0], 1]
        out[o + f] = pairwise_sum(buf, f * width, count) / np.float32(count)


@njit(cache=True, nogil=True)
def set_means(img, pose, tan, aspect, pts, sets, feats, offsets, border, out):
    """Pixel-set means ``out (N, C, F)`` float32 of the 4-channel map ``img`` at the poses
    ``pose (N, 4)`` (u, w, θ, s; ``tan (N,)`` their ``tan θ``) shifted by ``offsets (N, C, 2)`` px.

    ``pts (P, 2)`` are the unit-square points of all sets, set ``k`` at ``sets[k] = (start, count)``;
    ``feats (F, 2)`` the set and channel of each feature; ``border (4,)`` the value outside."""
    index = set_index(sets, feats)
    buf = np.empty(feats.shape[0] * index[2], np.float32)
    base = np.empty((pts.shape[0], 2))
    flat = out.reshape(-1)
    n_feats = feats.shape[0]
    for n in range(pose.shape[0]):
        place(pts, pose[n, 0], pose[n, 1], pose[n, 3], tan[n], aspect, base)  # once per pose, then shifted
        for c in range(offsets.shape[1]):
            means_at(img, base, offsets[n, c, 0], offsets[n, c, 1], sets, feats, index, border, buf, flat,
                     (n * offsets.shape[1] + c) * n_feats)
    return out
