"""The box model's per-frame bookkeeping (:mod:`~vistrack.models.box.model`), compiled: one call each
where numpy makes a dozen small ones.

- :func:`predicted_roi` is ``Box.observe``'s region: ``Appearance.roi`` of the boxes of
  ``Box.predict_mean`` of the particles, grown by the reach (the same arithmetic in the same
  order; ``math.exp`` where numpy may use its own SIMD ``exp``: the integers agree unless a
  bound falls within an ulp of an integer).
- :func:`window_texture` and :func:`window_labels` are ``AppearanceFrame``'s maps after the grey and HSV
  conversions, over a window of the region each: the texture (grey level and its 3x3 Sobel gradient,
  ``BORDER_REFLECT``: sums of integers, equal to OpenCV's), and the colour labels and their bin integrals
  (equal); :func:`window_grey_labels` the same for a grey video's grey-level bins.
- :func:`adapt_template` is ``Appearance.adapt`` up to the colour histogram's update: the patch
  of the estimate sampled as ``cv2.remap`` samples it (:func:`~vistrack.appearance.cue_kernels.ncc`'s
  sampling), its correlation with the template, the new template and the box's bin counts
  (sums in sample order where numpy's BLAS sums in another: 1e-12 relative,
  ``tests/models/box/test_kernels_box.py``).
- :func:`shrink_area` is ``cv2.resize(image, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)`` of a BGR
  image for a non-integer ``1 / f`` (``Appearance``'s regions): OpenCV's ``resizeArea_`` (its tap tables,
  float sums in its order, rounding to nearest even), with each source row's horizontal pass made once
  where OpenCV makes it once per output row it touches (equal, ``tests/models/box/test_kernels_box.py``), over a
  window of the output if asked (each pixel's sum in the same order: equal to that part of the whole).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..kernels.sampling import NONFINITE, corner_float, fma_lerp, inside, lerp_fma, pairwise_sum
from .cue_kernels import box_count, colour_labels
from .features import GREY_BINS

#: grey levels per grey-level bin (:func:`~vistrack.appearance.features.colour_bins` with ``grey=True``)
_GREY_STEP = 256 // GREY_BINS

__all__ = ["predicted_roi", "adapt_template", "window_texture", "window_labels", "window_grey_labels",
           "window_integrals", "shrink_area", "boxes_window", "states_window"]


@njit(cache=True, nogil=True, error_model="numpy")
def predicted_roi(states, damping, size0, reach_sd, reach_factor, ring, out):
    """``out (4,)`` int64: ``(x0, y0, x1, y1)``, the bounding box of the boxes ``(cx, cy, w_0 e^l,
    h_0 e^l)`` of the predicted means ``z + d (z - z')`` of ``states (N, 6)``, grown by
    ``reach_sd e^{max l} reach_factor`` and by ``ring / 2`` times the largest ``w + h`` (floor / ceil)."""
    lo_x = lo_y = np.inf
    hi_x = hi_y = top_wh = top_l = -np.inf
    for n in range(states.shape[0]):
        cx = states[n, 0] + damping[0] * (states[n, 0] - states[n, 3])
        cy = states[n, 1] + damping[1] * (states[n, 1] - states[n, 4])
        lv = states[n, 2] + damping[2] * (states[n, 2] - states[n, 5])
        e = math.exp(lv)
        w, h = size0[0] * e, size0[1] * e
        lo_x, hi_x = min(lo_x, cx - w / 2), max(hi_x, cx + w / 2)
        lo_y, hi_y = min(lo_y, cy - h / 2), max(hi_y, cy + h / 2)
        top_wh, top_l = max(top_wh, w + h), max(top_l, lv)
    g = reach_sd * math.exp(top_l) * reach_factor + ring * 0.5 * top_wh
    out[0], out[1] = math.floor(lo_x - g), math.floor(lo_y - g)
    out[2], out[3] = math.ceil(hi_x + g), math.ceil(hi_y + g)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _patch(texture, box, gx, gy, x0, y0, f, out):
    """The raw samples of ``Appearance.patches`` for one ``box (4,)``: grey levels ``out[:M]`` and the
    gradient ``(gx, gy)`` interleaved in ``out[M:]``, row-major over the grid."""
    mx, my = gx.shape[0], gy.shape[0]
    m = mx * my
    zero, nan = np.float32(0.0), np.float32(np.nan)
    h, w = texture.shape[0], texture.shape[1]
    for r in range(my):
        for c in range(mx):
            i = r * mx + c
            ix, _, a, _ = corner_float(np.float32((box[0] + gx[c] * box[2] - x0) * f - 0.5), zero)
            _, iy, _, b = corner_float(zero, np.float32((box[1] + gy[r] * box[3] - y0) * f - 0.5))
            for k in range(3):
                if ix != NONFINITE and iy != NONFINITE and inside(ix, iy, w, h):
                    y0_, x0_ = np.uint64(iy), np.uint64(ix)
                    y1_, x1_ = y0_ + np.uint64(1), x0_ + np.uint64(1)
                    s = fma_lerp(texture[y0_, x0_, k], texture[y0_, x1_, k], texture[y1_, x0_, k],
                                 texture[y1_, x1_, k], a, b)
                else:
                    jx, jy = (NONFINITE, NONFINITE) if ix == NONFINITE or iy == NONFINITE else (ix, iy)
                    s = lerp_fma(texture, jx, jy, a, b, k, zero, nan)
                out[i if k == 0 else m + 2 * i + k - 1] = np.float64(s)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _unit(v, lo, hi, centre):
    """``v[lo:hi]`` made zero-mean (``centre``) and unit-norm in place (``_unit_rows``; norm floor 1e-6)."""
    if centre:
        mean = pairwise_sum(v, lo, hi) / (hi - lo)
        for i in range(lo, hi):
            v[i] = v[i] - mean
    sq = 0.0
    for i in range(lo, hi):
        sq += v[i] * v[i]
    norm = max(math.sqrt(sq), 1e-6)
    for i in range(lo, hi):
        v[i] = v[i] / norm


@njit(cache=True, nogil=True, error_model="numpy")
def adapt_template(texture, ii, box, gx, gy, x0, y0, f, template, rate, min_ncc, new_template, counts):
    """``Appearance.adapt`` of ``box (4,)`` (cx, cy, w, h; frame px): returns the estimate's ``ncc``
    with ``template``; where it is at least ``min_ncc`` writes ``unit((1 - rate) T + rate v)`` into
    ``new_template (3M,)`` and the box's bin counts (from the integral image ``ii``) into ``counts``."""
    m = gx.shape[0] * gy.shape[0]
    v = _patch(texture, box, gx, gy, x0, y0, f, np.empty(3 * m))
    _unit(v, 0, m, True)
    _unit(v, m, 3 * m, False)
    ncc = 0.0
    for i in range(3 * m):
        v[i] = v[i] * np.sqrt(0.5)
        ncc += v[i] * template[i]
    if not ncc >= min_ncc:
        return ncc
    for i in range(3 * m):
        new_template[i] = (1 - rate) * template[i] + rate * v[i]
    _unit(new_template, 0, m, True)
    _unit(new_template, m, 3 * m, False)
    for i in range(3 * m):
        new_template[i] = new_template[i] * np.sqrt(0.5)
    u, w = (box[0] - x0) * f, (box[1] - y0) * f
    hw, hh = 0.5 * f * box[2], 0.5 * f * box[3]
    ix0, iy0, ix1, iy1 = int(np.rint(u - hw)), int(np.rint(w - hh)), int(np.rint(u + hw)), int(np.rint(w + hh))
    for b in range(ii.shape[2]):
        counts[b] = box_count(ii, ix0, iy0, ix1, iy1, b)
    return ncc


@njit(cache=True, forceinline=True, error_model="numpy")
def _reflect(i, n):
    """``BORDER_REFLECT`` of an index one step outside ``[0, n)``."""
    return 0 if i < 0 else (n - 1 if i >= n else i)


@njit(cache=True, nogil=True, error_model="numpy")
def window_texture(grey, a0, b0, r0, r1, c0, c1, texture):
    """Rows ``[r0, r1)`` and columns ``[c0, c1)`` of a region's ``texture (H, W, 3)`` float32 = (grey, Sobel x,
    Sobel y) of the grey levels (3x3, ``BORDER_REFLECT`` at the region's edges: sums of integers, equal to
    OpenCV's). ``grey (h, w)`` uint8 holds the region's rows ``a0..`` and columns ``b0..``: the window and the
    pixels about it that the gradient reads."""
    h, w = texture.shape[0], texture.shape[1]
    for y in range(r0, r1):
        ya, yb = _reflect(y - 1, h) - a0, _reflect(y + 1, h) - a0
        yy = y - a0
        for x in range(c0, c1):
            xa, xb, xx = _reflect(x - 1, w) - b0, _reflect(x + 1, w) - b0, x - b0
            dx = (2 * (int(grey[yy, xb]) - int(grey[yy, xa])) + int(grey[ya, xb]) - int(grey[ya, xa])
                  + int(grey[yb, xb]) - int(grey[yb, xa]))
            dy = (2 * (int(grey[yb, xx]) - int(grey[ya, xx])) + int(grey[yb, xa]) - int(grey[ya, xa])
                  + int(grey[yb, xb]) - int(grey[ya, xb]))
            texture[y, x, 0] = np.float32(grey[yy, xx])
            texture[y, x, 1] = np.float32(dx)
            texture[y, x, 2] = np.float32(dy)
    return texture


@njit(cache=True, nogil=True, error_model="numpy")
def window_labels(hsv, a0, b0, r0, r1, c0, c1, labels, ii):
    """Rows ``[r0, r1)`` and columns ``[c0, c1)`` of a region's colour bins ``labels (H, W)`` of the HSV pixels
    (:func:`colour_labels`) and ``ii (H + 1, W + 1, n_bins)`` their bin integrals from the window's corner
    (:func:`bin_integrals` of the window's labels, written at ``ii[r0:r1 + 1, c0:c1 + 1]``: a box inside the
    window counts what it counts in the whole region's). ``hsv (h, w, 3)`` uint8 holds the region's rows
    ``a0..`` and columns ``b0..``."""
    colour_labels(hsv[r0 - a0:r1 - a0, c0 - b0:c1 - b0], labels[r0:r1, c0:c1])
    return window_integrals(labels, r0, r1, c0, c1, ii)


@njit(cache=True, nogil=True, error_model="numpy")
def window_grey_labels(grey, a0, b0, r0, r1, c0, c1, labels, ii):
    """:func:`window_labels` for grey-level bins (``colour_bins(grey=True)``: the grey level over 16) of the grey
    pixels ``grey (h, w)`` uint8, which hold the region's rows ``a0..`` and columns ``b0..``."""
    for y in range(r0, r1):
        for x in range(c0, c1):
            labels[y, x] = grey[y - a0, x - b0] // _GREY_STEP
    return window_integrals(labels, r0, r1, c0, c1, ii)


@njit(cache=True, nogil=True, error_model="numpy")
def window_integrals(labels, r0, r1, c0, c1, ii):
    """The bin integrals ``ii`` of ``labels`` inside rows ``[r0, r1)`` and columns ``[c0, c1)``, counted from the
    window's corner (:func:`window_labels`)."""
    n_bins = ii.shape[2]
    row = np.zeros(n_bins, np.int32)
    ii[r0, c0:c1 + 1, :] = 0
    for y in range(r0, r1):
        row[:] = 0
        ii[y + 1, c0, :] = 0
        for x in range(c0, c1):
            row[labels[y, x]] += 1
            for b in range(n_bins):
                ii[y + 1, x + 1, b] = ii[y, x + 1, b] + row[b]
    return ii


@njit(cache=True, nogil=True, error_model="numpy")
def _area_taps(ssize, dsize, scale, di, si, al):
    """OpenCV's ``computeResizeAreaTab`` (``cn = 1``): the taps ``(destination, source, weight)`` of an
    area resize by ``scale`` source pixels per destination pixel; returns their number."""
    k = 0
    for dx in range(dsize):
        fsx1 = dx * scale
        fsx2 = fsx1 + scale
        cell = min(scale, ssize - fsx1)
        sx1, sx2 = math.ceil(fsx1), math.floor(fsx2)
        sx2 = min(sx2, ssize - 1)
        sx1 = min(sx1, sx2)
        if sx1 - fsx1 > 1e-3:
            di[k], si[k], al[k] = dx, sx1 - 1, np.float32((sx1 - fsx1) / cell)
            k += 1
        for sx in range(sx1, sx2):
            di[k], si[k], al[k] = dx, sx, np.float32(1.0 / cell)
            k += 1
        if fsx2 - sx2 > 1e-3:
            di[k], si[k], al[k] = dx, sx2, np.float32(min(min(fsx2 - sx2, 1.0), cell) / cell)
            k += 1
    return k


@njit(cache=True, forceinline=True, error_model="numpy")
def _round_u8(v):
    """``saturate_cast<uchar>(float)``: to nearest, ties to even, clipped to [0, 255]."""
    return np.uint8(min(max(np.rint(v), np.float32(0.0)), np.float32(255.0)))  # selects: the loops vectorise


@njit(cache=True, nogil=True, error_model="numpy")
def _row_passes(src, sy0, sy1, xdi, xsi, xal, k0, k1, c0, c1):
    """The horizontal pass of :func:`shrink_area` over source rows ``[sy0, sy1)`` and destination columns
    ``[c0, c1)`` (taps ``k0..k1``): ``(sy1 - sy0, c1 - c0, 3)`` float32, each column's taps summed in their
    order from 0, as OpenCV sums them. Every column gets as many taps as the most any has, the extra ones of
    weight 0 (adding ``+0`` changes no sum of these non-negative terms), and two rows go at once: the sums
    are in registers, with no branch on the number of taps."""
    nc = c1 - c0
    nt = 0
    k = k0
    while k < k1:
        e = k
        while e < k1 and xdi[e] == xdi[k]:
            e += 1
        nt, k = max(nt, e - k), e
    tap, wt = np.empty((nc, nt), np.int64), np.zeros((nc, nt), np.float32)
    k = k0
    while k < k1:
        d, e = xdi[k] - c0, k
        while e < k1 and xdi[e] == xdi[k]:
            tap[d, e - k], wt[d, e - k] = xsi[e], xal[e]
            e += 1
        tap[d, e - k:] = xsi[e - 1]
        k = e
    out = np.empty((sy1 - sy0, nc, 3), np.float32)
    zero = np.float32(0.0)
    for r in range(0, sy1 - sy0, 2):
        ra, rb = src[sy0 + r], src[min(sy0 + r + 1, sy1 - 1)]  # the last row of an odd count twice
        oa, ob = out[r], out[min(r + 1, sy1 - sy0 - 1)]
        for d in range(nc):
            a0 = a1 = a2 = b0 = b1 = b2 = zero
            for t in range(nt):
                x, al = tap[d, t], wt[d, t]
                a0 = a0 + np.float32(ra[x, 0]) * al
                a1 = a1 + np.float32(ra[x, 1]) * al
                a2 = a2 + np.float32(ra[x, 2]) * al
                b0 = b0 + np.float32(rb[x, 0]) * al
                b1 = b1 + np.float32(rb[x, 1]) * al
                b2 = b2 + np.float32(rb[x, 2]) * al
            oa[d, 0], oa[d, 1], oa[d, 2] = a0, a1, a2
            ob[d, 0], ob[d, 1], ob[d, 2] = b0, b1, b2
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def shrink_area(src, f, dst, r0, r1, c0, c1):
    """Rows ``[r0, r1)`` and columns ``[c0, c1)`` of ``dst (round(f H), round(f W), 3)`` uint8 = ``src (H, W,
    3)`` uint8 shrunk by ``f`` as OpenCV's ``INTER_AREA`` does for a non-integer ``1 / f`` (module docstring);
    the rest of ``dst`` is left as it was. Each destination pixel sums its taps in the order the whole
    image's resize sums them, so a window equals that part of the whole."""
    h, w = src.shape[0], src.shape[1]
    dh, dw = dst.shape[0], dst.shape[1]
    scale = 1.0 / f
    xdi, xsi, xal = np.empty(2 * w, np.int64), np.empty(2 * w, np.int64), np.empty(2 * w, np.float32)
    ydi, ysi, yal = np.empty(2 * h, np.int64), np.empty(2 * h, np.int64), np.empty(2 * h, np.float32)
    nx = _area_taps(w, dw, scale, xdi, xsi, xal)
    ny = _area_taps(h, dh, scale, ydi, ysi, yal)
    k0, k1 = np.searchsorted(xdi[:nx], c0), np.searchsorted(xdi[:nx], c1)  # the taps of the window's columns
    j0, j1 = np.searchsorted(ydi[:ny], r0), np.searchsorted(ydi[:ny], r1)
    if k0 >= k1 or j0 >= j1:
        return dst
    sy0 = ysi[j0]
    rows = _row_passes(src, sy0, ysi[j1 - 1] + 1, xdi, xsi, xal, k0, k1, c0, c1)
    nc = c1 - c0
    acc = np.zeros((nc, 3), np.float32)
    prev_dy = ydi[j0]
    for j in range(j0, j1):  # the vertical pass: each destination row's taps in order
        beta, dy, row = yal[j], ydi[j], rows[ysi[j] - sy0]
        if dy != prev_dy:
            for d in range(nc):
                for c in range(3):
                    dst[prev_dy, c0 + d, c] = _round_u8(acc[d, c])
                    acc[d, c] = beta * row[d, c]
            prev_dy = dy
        else:
            for d in range(nc):
                for c in range(3):
                    acc[d, c] += beta * row[d, c]
    for d in range(nc):
        for c in range(3):
            dst[prev_dy, c0 + d, c] = _round_u8(acc[d, c])
    return dst


@njit(cache=True, nogil=True, error_model="numpy")
def boxes_window(boxes, ring, x0, y0, f, hh, ww):
    """``AppearanceFrame.window`` of ``boxes (N, 4)`` (cx, cy, w, h; frame px) grown by ``ring (w + h) / 2``:
    ``(r0, r1, c0, c1)``, the working rows and columns their histograms and template samples read with two
    pixels to spare, or ``(0, hh, 0, ww)`` (the whole region) if a box is not finite."""
    lo_u = lo_v = np.inf
    hi_u = hi_v = -np.inf
    for n in range(boxes.shape[0]):
        u, v = (boxes[n, 0] - x0) * f, (boxes[n, 1] - y0) * f
        g = f * ring * 0.5 * (boxes[n, 2] + boxes[n, 3])
        hw, hh2 = 0.5 * f * boxes[n, 2] + g, 0.5 * f * boxes[n, 3] + g
        lo_u, hi_u = min(lo_u, u - hw), max(hi_u, u + hw)
        lo_v, hi_v = min(lo_v, v - hh2), max(hi_v, v + hh2)
        if not (math.isfinite(u) and math.isfinite(v) and math.isfinite(hw) and math.isfinite(hh2)):
            return 0, hh, 0, ww
    if boxes.shape[0] == 0:
        return 0, 0, 0, 0
    return (int(max(math.floor(lo_v) - 2, -1)), int(min(math.ceil(hi_v) + 2, hh + 1)),
            int(max(math.floor(lo_u) - 2, -1)), int(min(math.ceil(hi_u) + 2, ww + 1)))


@njit(cache=True, nogil=True, error_model="numpy")
def states_window(states, size0, ring, x0, y0, f, hh, ww):
    """:func:`boxes_window` of the boxes ``(cx, cy, w_0 e^l, h_0 e^l)`` of ``states (N, >=3)``."""
    boxes = np.empty((states.shape[0], 4))
    for n in range(states.shape[0]):
        e = math.exp(states[n, 2])
        boxes[n, 0], boxes[n, 1], boxes[n, 2], boxes[n, 3] = states[n, 0], states[n, 1], size0[0] * e, size0[1] * e
    return boxes_window(boxes, ring, x0, y0, f, hh, ww)
