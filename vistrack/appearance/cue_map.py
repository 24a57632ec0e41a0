"""The box model's LIS proposal map (:meth:`Appearance.proposal_map
<vistrack.appearance.cues.Appearance.proposal_map>`): the template's normalised correlation
(``cv2.matchTemplate``) and the back-projection's contrast between a box and its ring, at every
working pixel of the part of the region the proposal reads."""

from __future__ import annotations

import cv2
import numpy as np

from .. import kernels

__all__ = ["proposal_map"]


def proposal_map(app, obs, w, h, span=None, stride=1):
    """``log q̃`` over the working region for a box of size ``(w, h)`` (frame px) centred at
    each working pixel: ``λ_t (ncc - 1)`` from ``cv2.matchTemplate`` of the template plus
    ``λ_c`` times the back-projection's contrast between the box and its ring. Returns
    ``(map (H', W'), u0, v0, stride)`` with map pixel ``(i, j)`` at working centre
    ``(u0 + stride j, v0 + stride i)``: with ``stride > 1`` the texture and back-projection are
    shrunk by ``stride`` (``INTER_AREA``) and the template with them.
    ``span = (u_min, u_max, v_min, v_max)``: when centres in that working range read (bilinearly)
    inside the whole map, only the part they need, with the template's and its ring's reach;
    the values there are those of the whole region's map (up to the filters' float sums)."""
    f = obs.f
    tw, th = max(2, int(round(w * f))), max(2, int(round(h * f)))
    g = max(1, int(round(app.ring * 0.5 * (tw + th))))
    r0, r1, c0, c1 = _map_part(obs.grey.shape, tw, th, g, span)
    tex, bp = obs.texture[r0:r1, c0:c1], app.backprojection[obs.labels[r0:r1, c0:c1]]
    if stride > 1:
        hs, ws = (r1 - r0) // stride, (c1 - c0) // stride
        if hs < 1 or ws < 1:
            return None
        tex = cv2.resize(tex[:hs * stride, :ws * stride], (ws, hs), interpolation=cv2.INTER_AREA)
        bp = cv2.resize(bp[:hs * stride, :ws * stride], (ws, hs), interpolation=cv2.INTER_AREA)
        tw, th, g = max(2, round(tw / stride)), max(2, round(th / stride)), max(1, round(g / stride))
    if tw >= tex.shape[1] or th >= tex.shape[0]:
        return None
    ncc = cv2.matchTemplate(tex, _template_image(app, tw, th), cv2.TM_CCOEFF_NORMED)
    s_in = cv2.boxFilter(bp, -1, (tw, th), normalize=False, anchor=(0, 0), borderType=cv2.BORDER_CONSTANT)
    s_out = cv2.boxFilter(bp, -1, (tw + 2 * g, th + 2 * g), normalize=False, anchor=(0, 0),
                          borderType=cv2.BORDER_CONSTANT)
    hh, ww = ncc.shape
    area_ring = (tw + 2 * g) * (th + 2 * g) - tw * th
    origin = (c0 + stride * tw / 2.0, r0 + stride * th / 2.0, stride)
    if kernels.use() and all(type(v) in (int, float) for v in (app.lambda_template, app.lambda_colour)):
        from .cue_kernels import map_scores

        out = map_scores(ncc, s_in, s_out, g, tw * th, area_ring, app.lambda_template, app.lambda_colour,
                         np.empty((hh, ww), np.float32))
        return (out,) + origin
    inside = s_in[:hh, :ww] / (tw * th)
    # the ring box of the template at (i, j) starts at (i - g, j - g): shifted by g, zeros before
    out_pad = np.zeros((hh, ww), s_out.dtype)
    out_pad[g:, g:] = s_out[:max(hh - g, 0), :max(ww - g, 0)]
    ring = (out_pad - s_in[:hh, :ww]) / area_ring
    log_q = app.lambda_template * (np.nan_to_num(ncc) - 1.0) + app.lambda_colour * (inside - ring)
    return (log_q.astype(np.float32),) + origin


def _template_image(app, tw, th):
    """The template as a ``th x tw`` float32 image (grey, gx, gy), kept until the template or the
    size changes (adaptation replaces the template's array)."""
    kept = app.map_template
    if kept is None or kept[0] is not app.template or kept[1] != (tw, th):
        my, mx = app.grid_shape
        m = my * mx
        img = np.dstack([app.template[:m].reshape(my, mx), app.template[m:].reshape(my, mx, 2)])
        kept = app.template, (tw, th), cv2.resize(img.astype(np.float32), (tw, th), interpolation=cv2.INTER_LINEAR)
        app.map_template = kept
    return kept[2]


def _map_part(shape, tw, th, g, span):
    """``(r0, r1, c0, c1)``: the rows and columns of a working region of ``shape (H, W)`` that a
    proposal map for a ``tw x th`` template with a ring of ``g`` needs when its centres read in
    ``span`` (:meth:`Appearance.proposal_map`): the whole region unless every read lies inside
    the whole map (so that none takes its minimum as the border value)."""
    gh, gw = shape
    if span is None:
        return 0, gh, 0, gw
    u_lo, u_hi, v_lo, v_hi = (np.floor(a - b / 2) for a, b in zip(span, (tw, tw, th, th)))
    if not (u_lo >= 0 and u_hi + 1 <= gw - tw and v_lo >= 0 and v_hi + 1 <= gh - th):
        return 0, gh, 0, gw
    c0 = int(min(max(u_lo - g - 1, 0), gw))
    c1 = int(min(max(u_hi + tw + g + 3, c0), gw))
    r0 = int(min(max(v_lo - g - 1, 0), gh))
    r1 = int(min(max(v_hi + th + g + 3, r0), gh))
    return r0, r1, c0, c1
