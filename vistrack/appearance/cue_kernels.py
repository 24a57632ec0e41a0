"""The appearance cues (:mod:`~vistrack.appearance.cues`), compiled.

- :func:`colour_labels` is :func:`~vistrack.appearance.features.colour_bins` of an HSV image (integer
  arithmetic: equal).
- :func:`bin_integrals` is :func:`~vistrack.appearance.features.bin_integrals` without the one-hot array
  (integer counts: equal).
- :func:`ncc` is :meth:`Appearance.ncc <vistrack.appearance.cues.Appearance.ncc>`: the texture
  sampled as ``cv2.remap`` samples it (bit for bit) and the dot products and norms summed in
  sample order (numpy's BLAS sums in another order: 1e-12 relative).
- :func:`colour_loglik` is ``AppearanceFrame.histograms`` and ``TargetColour.loglik`` in one pass
  (the counts equal; the dot products with the back-projection in bin order: 1e-15 relative).
- :func:`box_loglik` is :meth:`Appearance.loglik_states <vistrack.appearance.cues.Appearance.loglik_states>`:
  the boxes of box-model states, the colour term and the template correlation;
- :func:`map_scores` is the end of :meth:`Appearance.proposal_map <vistrack.appearance.cues.Appearance.proposal_map>`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..kernels.sampling import NONFINITE, corner_float, fma_lerp, inside, lerp_fma, pairwise_sum

__all__ = ["colour_labels", "bin_integrals", "ncc", "colour_loglik", "box_count", "box_ring_counts", "affinity",
           "contrast", "box_loglik", "map_scores"]

#: as :mod:`vistrack.appearance.features`: hue x saturation bins, value bins, and the chroma thresholds
_HUE, _SAT, _VALUE, _MIN_S, _MIN_V = 8, 3, 4, 48, 40


@njit(cache=True, nogil=True, error_model="numpy")
def colour_labels(hsv, out):
    """Colour bins ``out (H, W)`` uint8 of an OpenCV HSV image ``hsv (H, W, 3)`` uint8 (hue 0..179)."""
    for y in range(hsv.shape[0]):
        for x in range(hsv.shape[1]):
            h, s, v = int(hsv[y, x, 0]), int(hsv[y, x, 1]), int(hsv[y, x, 2])
            if s >= _MIN_S and v >= _MIN_V:
                out[y, x] = (h * _HUE // 180) * _SAT + (s - _MIN_S) * _SAT // (256 - _MIN_S)
            else:
                out[y, x] = _HUE * _SAT + v // (256 // _VALUE)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def bin_integrals(labels, n_bins):
    """``ii (H + 1, W + 1, n_bins)`` int32: ``ii[y, x, b]`` counts the pixels of bin ``b`` in
    ``[0, x) x [0, y)`` (each row the one above plus the row's running counts, over flat rows)."""
    h, w = labels.shape
    ii = np.empty((h + 1, w + 1, n_bins), np.int32)
    ii[0, :, :] = 0
    row = np.zeros(n_bins, np.int32)
    for y in range(h):
        row[:] = 0
        ii[y + 1, 0, :] = 0
        prev, cur = ii[y].reshape(-1), ii[y + 1].reshape(-1)
        for x in range(w):
            row[labels[y, x]] += 1
            o = (x + 1) * n_bins
            for b in range(n_bins):
                cur[o + b] = prev[o + b] + row[b]
    return ii


@njit(cache=True, nogil=True, error_model="numpy")
def ncc(texture, boxes, gx, gy, x0, y0, f, template, out):
    """Template correlation ``out (N,)`` of ``boxes (N, 4)`` (cx, cy, w, h; frame px) on the working
    texture ``(H, W, 3)`` float32 (grey level, gx, gy) of a region at ``(x0, y0)``, scale ``f``:
    ``√½ [g·T_g / |g - ḡ| + d·T_d / |d|]`` over the grid points ``(gx[c], gy[r])`` (box units) in
    row-major order (the template's). A point's coordinates depend on its column or its row only:
    they are computed once per column and row, with the same arithmetic as per point."""
    mx, my = gx.shape[0], gy.shape[0]
    m = mx * my
    zero = np.float32(0.0)
    nan = np.float32(np.nan)
    h, w = texture.shape[0], texture.shape[1]
    cu, ca = np.empty(mx, np.int64), np.empty(mx, np.float32)
    rv, rb = np.empty(my, np.int64), np.empty(my, np.float32)
    for n in range(boxes.shape[0]):
        cx, cy, bw, bh = boxes[n, 0], boxes[n, 1], boxes[n, 2], boxes[n, 3]
        for c in range(mx):
            ix, _, a, _ = corner_float(np.float32((cx + gx[c] * bw - x0) * f - 0.5), zero)
            cu[c], ca[c] = ix, a
        for r in range(my):
            _, iy, _, b = corner_float(zero, np.float32((cy + gy[r] * bh - y0) * f - 0.5))
            rv[r], rb[r] = iy, b
        gs = gg = gt = dd = dt = 0.0
        for r in range(my):
            iy, b = rv[r], rb[r]
            for c in range(mx):
                i = r * mx + c
                ix, a = cu[c], ca[c]
                if ix != NONFINITE and iy != NONFINITE and inside(ix, iy, w, h):
                    y0_, x0_ = np.uint64(iy), np.uint64(ix)
                    y1_, x1_ = y0_ + np.uint64(1), x0_ + np.uint64(1)
                    g = np.float64(fma_lerp(texture[y0_, x0_, 0], texture[y0_, x1_, 0], texture[y1_, x0_, 0],
                                            texture[y1_, x1_, 0], a, b))
                    dx = np.float64(fma_lerp(texture[y0_, x0_, 1], texture[y0_, x1_, 1], texture[y1_, x0_, 1],
                                             texture[y1_, x1_, 1], a, b))
                    dy = np.float64(fma_lerp(texture[y0_, x0_, 2], texture[y0_, x1_, 2], texture[y1_, x0_, 2],
                                             texture[y1_, x1_, 2], a, b))
                else:
                    if ix == NONFINITE or iy == NONFINITE:
                        ix = iy = NONFINITE
                    g = np.float64(lerp_fma(texture, ix, iy, a, b, 0, zero, nan))
                    dx = np.float64(lerp_fma(texture, ix, iy, a, b, 1, zero, nan))
                    dy = np.float64(lerp_fma(texture, ix, iy, a, b, 2, zero, nan))
                gs += g
                gg += g * g
                gt += g * template[i]
                dd += dx * dx + dy * dy
                dt += dx * template[m + 2 * i] + dy * template[m + 2 * i + 1]
        g_norm = np.sqrt(max(gg - gs * gs / m, 0.0))
        d_norm = np.sqrt(dd)
        out[n] = np.sqrt(0.5) * (gt / max(g_norm, 1e-6) + dt / max(d_norm, 1e-6))
    return out


@njit(cache=True, forceinline=True, error_model="numpy")
def box_count(ii, x0, y0, x1, y1, b):
    """Bin ``b``'s count in the box ``[x0, x1) x [y0, y1)`` (rounded corners) clipped to the map
    (:func:`~vistrack.appearance.features.box_sums`)."""
    h, w = ii.shape[0] - 1, ii.shape[1] - 1
    x0, x1 = min(max(x0, 0), w), min(max(x1, 0), w)
    y0, y1 = min(max(y0, 0), h), min(max(y1, 0), h)
    return ii[y1, x1, b] - ii[y0, x1, b] - ii[y1, x0, b] + ii[y0, x0, b]


@njit(cache=True, nogil=True, error_model="numpy")
def affinity(counts, bg_weight, q, scratch):
    """``Σ_u sqrt(p_u q_u)`` of the background-weighted, normalised ``counts`` (``TargetColour.normalise``) and
    ``q``, the sums in numpy's order (``scratch``: ``(B,)`` work space)."""
    n = counts.shape[0]
    for k in range(n):
        scratch[k] = counts[k] * bg_weight[k]
    s = pairwise_sum(scratch, 0, n)
    s = s if s > 0 else 1.0
    for k in range(n):
        scratch[k] = np.sqrt(scratch[k] / s * q[k])
    return pairwise_sum(scratch, 0, n)


@njit(cache=True, nogil=True, error_model="numpy")
def _d2(counts, bg_weight, q, scratch):
    """``1 - Σ sqrt(normalise(counts) q)`` (``TargetColour.d2``), the sums in numpy's order."""
    return 1.0 - affinity(counts, bg_weight, q, scratch)


@njit(cache=True, nogil=True, error_model="numpy")
def box_ring_counts(ii, x0, y0, f, cx, cy, w, h, ring, inner, outer):
    """The bin counts ``inner (B,)`` of the box ``(cx, cy, w, h)`` (frame px) and ``outer (B,)`` of the ring of
    width ``ring (w + h) / 2`` about it, from the per-bin integral image ``ii`` of a region at ``(x0, y0)``,
    scale ``f`` (``AppearanceFrame.histograms``: the corners rounded at the working resolution)."""
    u, v = (cx - x0) * f, (cy - y0) * f
    hw, hh = 0.5 * f * w, 0.5 * f * h
    g = f * (ring * 0.5 * (w + h))
    ix0, iy0, ix1, iy1 = int(np.rint(u - hw)), int(np.rint(v - hh)), int(np.rint(u + hw)), int(np.rint(v + hh))
    ox0, oy0 = int(np.rint(u - hw - g)), int(np.rint(v - hh - g))
    ox1, oy1 = int(np.rint(u + hw + g)), int(np.rint(v + hh + g))
    for b in range(ii.shape[2]):
        inner[b] = box_count(ii, ix0, iy0, ix1, iy1, b)
        outer[b] = box_count(ii, ox0, oy0, ox1, oy1, b) - inner[b]


@njit(cache=True, nogil=True, error_model="numpy")
def contrast(inner, outer, bp):
    """The back-projection ``bp``'s mean over the counts ``inner`` less over ``outer`` (``(B,)`` each), the dot
    products in bin order."""
    n_bins = inner.shape[0]
    dot_in = dot_out = 0.0
    for b in range(n_bins):
        dot_in += inner[b] * bp[b]
        dot_out += outer[b] * bp[b]
    n_in = max(pairwise_sum(inner, 0, n_bins), 1.0)
    n_out = max(pairwise_sum(outer, 0, n_bins), 1.0)
    return dot_in / n_in - dot_out / n_out


@njit(cache=True, nogil=True, error_model="numpy")
def colour_loglik(ii, x0, y0, f, boxes, ring, bg_weight, q, bp, lam, kappa, out):
    """The colour term ``log r_c (N,)`` of ``boxes (N, 4)`` (cx, cy, w, h; frame px) from the per-bin
    integral image ``ii`` of a region at ``(x0, y0)``, scale ``f`` (``AppearanceFrame.histograms``
    and ``TargetColour.loglik``): the counts equal, the sums in numpy's order but the dot product
    with ``bp`` in bin order (1e-15)."""
    n_bins = ii.shape[2]
    inner, outer = np.empty(n_bins), np.empty(n_bins)
    scratch = np.empty(n_bins)
    for n in range(boxes.shape[0]):
        box_ring_counts(ii, x0, y0, f, boxes[n, 0], boxes[n, 1], boxes[n, 2], boxes[n, 3], ring, inner, outer)
        d = _d2(inner, bg_weight, q, scratch) + kappa * (1.0 - _d2(outer, bg_weight, q, scratch))
        out[n] = lam * (contrast(inner, outer, bp) - d)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def box_loglik(states, size0, ii, texture, x0, y0, f, ring, bg_weight, q, bp, lam_c, kappa, gx, gy, template,
               lam_t, out):
    """``Box.loglik``: ``log r (N,)`` of ``states (N, >=3)`` whose boxes are ``(cx, cy, w_0 e^l, h_0 e^l)``:
    the colour term (:func:`~vistrack.appearance.cue_kernels.colour_loglik`) plus ``λ_t (ncc - 1)``
    (:func:`~vistrack.appearance.cue_kernels.ncc`)."""
    n = states.shape[0]
    boxes = np.empty((n, 4))
    for i in range(n):
        e = math.exp(states[i, 2])
        boxes[i, 0], boxes[i, 1] = states[i, 0], states[i, 1]
        boxes[i, 2], boxes[i, 3] = size0[0] * e, size0[1] * e
    rc = colour_loglik(ii, x0, y0, f, boxes, ring, bg_weight, q, bp, lam_c, kappa, np.empty(n))
    c = ncc(texture, boxes, gx, gy, x0, y0, f, template, np.empty(n))
    for i in range(n):
        out[i] = rc[i] + lam_t * (c[i] - 1.0)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def map_scores(ncc, s_in, s_out, g, area_in, area_ring, lam_t, lam_c, out):
    """The end of ``Appearance.proposal_map`` in float32, as numpy computes it with Python-float
    scalars: ``λ_t (nan_to_num(ncc) - 1) + λ_c (s_in / area_in - (s_out shifted by g - s_in) / area_ring)``
    into ``out (hh, ww)`` (``ncc``'s shape; ``s_out`` read ``g`` rows and columns back, 0 before)."""
    one, lt, lc = np.float32(1.0), np.float32(lam_t), np.float32(lam_c)
    ai, ar = np.float32(area_in), np.float32(area_ring)
    big = np.finfo(np.float32).max
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            v = ncc[i, j]
            if np.isnan(v):
                v = np.float32(0.0)
            elif np.isinf(v):
                v = big if v > 0 else -big
            o = s_out[i - g, j - g] if i >= g and j >= g else np.float32(0.0)
            out[i, j] = lt * (v - one) + lc * (s_in[i, j] / ai - (o - s_in[i, j]) / ar)
    return out
