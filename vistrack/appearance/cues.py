"""Appearance of an object learned from its first box (for real footage; beyond the seeds).

Working resolution
    Everything is computed on the frame's region of interest (the boxes the particles can
    reach), resized so that the object is about ``work_size`` px across
    (:class:`AppearanceFrame`). A box ``(cx, cy, w, h)`` in frame pixels maps to
    ``((cx - x0) f, (cy - y0) f, w f, h f)`` there.
Colour term (Pérez, Hue, Vermaak and Gangnet 2002)
    Histograms over :func:`~vistrack.appearance.features.colour_bins` (hue x saturation, value for
    achromatic pixels; grey levels for grey video), from per-bin integral images. The
    target's histogram ``q`` and every candidate's are weighted by Comaniciu's background
    weights ``v_u = min(1, b* / b_u)`` (``b``: the histogram of the ring around the first
    box, ``b*`` its smallest non-zero bin), so colours the background also has count less.
    With ``d²(p, q) = 1 - Σ_u sqrt(p_u q_u)`` (squared Bhattacharyya distance),

        log r_c = -λ_c [d²(h_in, q) + κ (1 - d²(h_ring, q))],

    ``h_in`` inside the box and ``h_ring`` in the ring around it (width ``ring`` times the
    mean side): a box inside the object sees the object in its ring as well, so the
    second part keeps the scale from shrinking. Plus the back-projection contrast
    ``+ λ_c (mean_in β - mean_ring β)``, with ``β_u = q_u / (q_u + b_u + 10⁻³)`` per bin
    (the target's share of each colour in the first frame, ``b`` the ring's histogram):
    the same contrast the LIS proposal map scores (:meth:`Appearance.proposal_map`), so
    proposal and likelihood agree (4 seeds on the real clips: hand_vot2013 AUC 0.45
    against 0.27 without the contrast, mean of the four 0.70 against 0.66; ``docs/experiments.md``).
Template term (spatial layout; grey levels)
    The grey image sampled bilinearly on an ``m_x x m_y`` grid over the box (about
    ``template_points`` points, the grid's aspect the box's), zero-mean and unit-norm:
    ``log r_t = λ_t (ncc - 1)`` with ``ncc`` its correlation with the template. Normalised
    cross-correlation is invariant to gain and offset of the grey levels (lighting).
Likelihood
    ``log r = log r_c + log r_t`` (grey video: the colour term runs on grey-level bins).
Adaptation (optional, on by default)
    After a frame whose estimate has ``ncc >= adapt_min_ncc``, the template moves towards
    the estimate's patch, ``t <- unit((1 - α) t + α v)`` with ``α = adapt_rate``, and the
    histogram ``q <- (1 - α/2) q + (α/2) h_in``. Frames below the bar (occlusion, drift)
    leave the model as it is.
"""

from __future__ import annotations

import cv2
import numpy as np

from .. import kernels
from .features import box_sums, is_grey
from .frame_maps import AppearanceFrame, MapBuffers, shrink
from .target_colour import TargetColour

__all__ = ["Appearance", "AppearanceFrame", "TargetColour"]


def _unit_rows(v):
    """Rows of ``v (..., M)`` made zero-mean and unit-norm (a flat row stays zero)."""
    v = v - v.mean(axis=-1, keepdims=True)
    norm = np.sqrt(np.einsum("...i,...i->...", v, v))[..., None]
    return v / np.maximum(norm, 1e-6)


class Appearance:
    """Colour histogram + grey template of one object, learned from the first frame.

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W)
    box : tuple of float
        ``(x, y, w, h)`` of the object in ``frame``.
    work_size : float, > 0
        The object's size ``sqrt(w h)`` at the working resolution (px); the frame is
        never enlarged.
    lambda_colour, kappa, ring : float, >= 0
        ``λ_c``, ``κ`` and the ring's width as a share of the mean side (module docstring).
    lambda_template : float, >= 0
        ``λ_t``.
    template_points : int, >= 1
        About this many grid points for the template.
    adapt_rate : float in [0, 1]
        Adaptation rate ``α`` (0: never adapt).
    adapt_min_ncc : float in [-1, 1]
        The confidence bar: the estimate's patch correlates at least this much with the template.
    anchor_min_ncc : float in [-1, 1] or None
        The first view as anchor: a frame adapts only if the estimate's patch also correlates
        at least this much with the first frame's template (``None``: no such test), so that a
        template that has drifted cannot keep adapting to what it drifted onto.
    grey : bool or None
        Force grey-level bins; ``None``: from :func:`~vistrack.appearance.features.is_grey`.
    interpolation : {"area", "linear"}
        How a region is shrunk to the working resolution (:func:`shrink`): ``cv2.INTER_AREA`` (averages every
        frame pixel) or ``cv2.INTER_LINEAR`` (bilinear samples: 5-10x cheaper, 0.50 -> 0.05 ms a frame on
        the 1280x720 ball1 clip; tried as the box model's default and not kept, ``docs/experiments.md``).
    whole_factor : bool
        Where the region is shrunk two times or more, shrink it by the nearest whole factor ``k`` (``f = 1 / k``,
        the object ``work_size · k f₀`` px across, within about 20 % of ``work_size``): ``INTER_AREA`` by a whole
        factor averages ``k × k`` blocks, OpenCV's own vectorised path, about a fifth of the time of a fractional
        factor's on a large object (``docs/experiments.md``).
    """

    #: the template as a resized image for the proposal map, with what it was made from
    #: (:func:`~vistrack.appearance.cue_map.proposal_map` keeps it; ``None`` until then)
    map_template = None

    def __init__(self, frame, box, *, work_size=32.0, lambda_colour=35.0, kappa=1.0, ring=0.3,
                 lambda_template=25.0, template_points=256, adapt_rate=0.1, adapt_min_ncc=0.6, grey=None,
                 anchor_min_ncc=None, interpolation="area", whole_factor=False):
        x, y, w, h = (float(v) for v in box)
        if not (w > 0 and h > 0 and np.isfinite([x, y, w, h]).all()):
            raise ValueError(f"the box needs a finite position and positive size, got {box}")
        self.grey = is_grey(frame) if grey is None else bool(grey)
        modes = {"area": cv2.INTER_AREA, "linear": cv2.INTER_LINEAR}
        if interpolation not in modes:
            raise ValueError(f"interpolation must be one of {', '.join(modes)}, got {interpolation!r}")
        self.interpolation = modes[interpolation]
        self._buffers = MapBuffers()  # the maps' memory, from frame to frame
        self.size = np.array([w, h])
        self.f = min(1.0, work_size / np.sqrt(w * h))
        if whole_factor and self.f <= 0.5:
            self.f = 1.0 / round(1.0 / self.f)
        self.lambda_colour, self.kappa, self.ring = lambda_colour, kappa, ring
        self.lambda_template = lambda_template
        self.adapt_rate, self.adapt_min_ncc = adapt_rate, adapt_min_ncc
        self.anchor_min_ncc = anchor_min_ncc
        a = w / h
        mx = int(np.clip(round(np.sqrt(template_points * a)), 4, 64))
        my = int(np.clip(round(template_points / mx), 4, 64))
        #: the grid's axes (box units) and its points ``(M, 2)``, row-major
        self.grid_axes = ((np.arange(mx) + 0.5) / mx - 0.5, (np.arange(my) + 0.5) / my - 0.5)
        self.grid = np.stack(np.meshgrid(*self.grid_axes), axis=-1).reshape(-1, 2)
        self.grid_shape = (my, mx)
        cx, cy = x + w / 2, y + h / 2
        obs = self.frame(frame, self.roi(np.array([[cx, cy, w, h]]), margin=1.5 * (w + h)))
        inner, ring_counts = obs.histograms(np.array([cx]), np.array([cy]), w, h, grow=0.75 * (w + h))
        self.colour = TargetColour(inner[0], ring_counts[0], lambda_colour=lambda_colour, kappa=kappa)
        self.template = self.patches(obs, np.array([[cx, cy, w, h]]))[0]
        self.template_first = self.template.copy()

    @property
    def backprojection(self):
        """``β (B,)``: the target's share of each colour bin in the first frame."""
        return self.colour.backprojection

    # -- per frame ---------------------------------------------------------------------
    def roi(self, boxes, margin):
        """``(x0, y0, x1, y1)``: the bounding box of ``boxes (N, 4)`` (cx, cy, w, h) grown by
        ``margin`` px and by the ring, as integers (unclipped: :meth:`frame` clips)."""
        b = np.asarray(boxes, float)
        g = margin + self.ring * 0.5 * (b[:, 2] + b[:, 3]).max()
        x0 = np.min(b[:, 0] - b[:, 2] / 2) - g
        x1 = np.max(b[:, 0] + b[:, 2] / 2) + g
        y0 = np.min(b[:, 1] - b[:, 3] / 2) - g
        y1 = np.max(b[:, 1] + b[:, 3] / 2) + g
        return tuple(int(v) for v in (np.floor(x0), np.floor(y0), np.ceil(x1), np.ceil(y1)))

    def frame(self, frame, roi, work=None):
        """The :class:`AppearanceFrame` of ``frame`` over ``roi`` clipped to the frame (cut from
        ``work``, :meth:`work_image` of the frame, when given)."""
        h, w = frame.shape[:2]
        x0, y0, x1, y1 = roi
        x0, x1 = min(max(x0, 0), w - 1), min(max(x1, 1), w)
        y0, y1 = min(max(y0, 0), h - 1), min(max(y1, 1), h)
        return AppearanceFrame(frame, (x0, y0, max(x1, x0 + 1), max(y1, y0 + 1)), self.f, self.grey, work,
                               self.interpolation, self._buffers)

    def work_image(self, frame):
        """The whole ``frame`` at the working resolution (as :meth:`frame` over the whole frame resizes it)."""
        return frame if self.f >= 1.0 else shrink(frame, self.f, self.interpolation)

    # -- the likelihood ------------------------------------------------------------------
    def patches(self, obs, boxes):
        """Template vectors ``(N, 3M)`` of ``boxes (N, 4)`` (cx, cy, w, h): the grey levels on the
        grid and the gradient ``(gx, gy)`` there, each part unit-norm and scaled by ``1/√2``,
        so that a dot product is the mean of the grey and the gradient correlations."""
        b = np.asarray(boxes, float)
        x = b[:, None, 0] + self.grid[None, :, 0] * b[:, None, 2]
        y = b[:, None, 1] + self.grid[None, :, 1] * b[:, None, 3]
        t = obs.sample_texture(x, y).astype(float)  # (N, M, 3)
        grey = _unit_rows(t[..., 0])
        grad = t[..., 1:].reshape(len(b), -1)
        grad = grad / np.maximum(np.linalg.norm(grad, axis=1, keepdims=True), 1e-6)
        return np.concatenate([grey, grad], axis=1) * np.sqrt(0.5)

    def ncc(self, obs, boxes):
        """``patches(obs, boxes) @ template`` ``(N,)`` without forming the patches: with raw
        samples ``g`` (grey) and ``d`` (gradient), and the template's parts ``T_g`` (zero-mean)
        and ``T_d``, ``√½ [g·T_g / |g - ḡ| + d·T_d / |d|]`` (the sum of ``T_g`` is zero, so the
        mean drops out of the dot product)."""
        b = np.asarray(boxes, float)
        if kernels.use():
            from .cue_kernels import ncc

            texture, _ = obs.maps((0, 0, 0, 0), obs.window(b))
            return ncc(texture, np.ascontiguousarray(b), *self.grid_axes, float(obs.x0), float(obs.y0),
                       float(obs.f), self.template, np.empty(len(b)))
        x = b[:, None, 0] + self.grid[None, :, 0] * b[:, None, 2]
        y = b[:, None, 1] + self.grid[None, :, 1] * b[:, None, 3]
        t = obs.sample_texture(x, y)  # (N, M, 3) float32
        m = len(self.grid)
        g = t[..., 0].astype(float)
        d = t[..., 1:].reshape(len(b), -1).astype(float)
        g_norm = np.sqrt(np.maximum(np.einsum("ij,ij->i", g, g) - g.sum(axis=1) ** 2 / m, 0.0))
        d_norm = np.sqrt(np.einsum("ij,ij->i", d, d))
        return np.sqrt(0.5) * ((g @ self.template[:m]) / np.maximum(g_norm, 1e-6)
                               + (d @ self.template[m:]) / np.maximum(d_norm, 1e-6))

    def terms(self, obs, boxes):
        """``(log r_c, log r_t, ncc)`` of ``boxes (N, 4)``, each of shape ``(N,)``."""
        b = np.asarray(boxes, float)
        if kernels.use():
            from .cue_kernels import colour_loglik

            c = self.colour
            _, ii = obs.maps(obs.window(b, self.ring))
            log_rc = colour_loglik(ii, float(obs.x0), float(obs.y0), float(obs.f), np.ascontiguousarray(b),
                                   float(self.ring), c.bg_weight, c.q, c.bp, float(c.lambda_colour), float(c.kappa),
                                   np.empty(len(b)))
        else:
            grow = self.ring * 0.5 * (b[:, 2] + b[:, 3])
            inner, ring = obs.histograms(b[:, 0], b[:, 1], b[:, 2], b[:, 3], grow=grow)
            log_rc = self.colour.loglik(inner, ring)
        ncc = self.ncc(obs, b)
        return log_rc, self.lambda_template * (ncc - 1.0), ncc

    def loglik(self, obs, boxes):
        """``log r`` of ``boxes (N, 4)`` (cx, cy, w, h), shape ``(N,)``."""
        log_rc, log_rt, _ = self.terms(obs, boxes)
        return log_rc + log_rt

    def loglik_states(self, obs, states, size0):
        """:meth:`loglik` of the boxes ``(cx, cy, w_0 e^l, h_0 e^l)`` of ``states (N, >=3)``
        (``(cx, cy, l)`` first; ``size0 = (w_0, h_0)``) in one compiled call
        (:func:`~vistrack.models.box.kernels.box_loglik`)."""
        from .cue_kernels import box_loglik

        c = self.colour
        texture, ii = obs.maps(obs.states_window(states, size0, self.ring), obs.states_window(states, size0))
        return box_loglik(states, size0, ii, texture, float(obs.x0), float(obs.y0), float(obs.f),
                          float(self.ring), c.bg_weight, c.q, c.bp, float(c.lambda_colour), float(c.kappa),
                          *self.grid_axes, self.template, float(self.lambda_template), np.empty(len(states)))

    def adapt(self, obs, box):
        """Move the template and histogram towards the estimate ``box (4,)`` on a
        confident frame; returns whether it adapted."""
        if self.adapt_rate <= 0:
            return False
        if self.anchor_min_ncc is not None and not self.anchor_ncc(obs, box) >= self.anchor_min_ncc:
            return False
        if kernels.use():
            return self._adapt_compiled(obs, np.ascontiguousarray(box, float))
        b = np.asarray(box, float)[None]
        v = self.patches(obs, b)[0]
        if not float(v @ self.template) >= self.adapt_min_ncc:
            return False
        a = self.adapt_rate
        t = (1 - a) * self.template + a * v
        m = len(self.grid)
        self.template = np.concatenate([_unit_rows(t[:m]), t[m:] / max(np.linalg.norm(t[m:]), 1e-6)]) * np.sqrt(0.5)
        inner, _ = obs.histograms(b[:, 0], b[:, 1], b[:, 2], b[:, 3])
        self.colour.adapt(inner[0], a / 2)
        return True

    def anchor_ncc(self, obs, box):
        """The correlation of the patch at ``box (4,)`` with the first frame's template."""
        template, self.template = self.template, self.template_first
        try:
            return float(self.ncc(obs, np.asarray(box, float).reshape(1, 4))[0])
        finally:
            self.template = template

    def _adapt_compiled(self, obs, box):
        """:meth:`adapt` in one compiled call (:func:`~vistrack.appearance.frame_kernels.adapt_template`)."""
        from .frame_kernels import adapt_template

        new, counts = np.empty_like(self.template), np.empty(obs.n_bins)
        texture, ii = obs.maps(obs.window(box))
        ncc = adapt_template(texture, ii, box, *self.grid_axes, float(obs.x0), float(obs.y0), float(obs.f),
                             self.template, float(self.adapt_rate), float(self.adapt_min_ncc), new, counts)
        if not ncc >= self.adapt_min_ncc:
            return False
        self.template = new
        self.colour.adapt(counts, self.adapt_rate / 2)
        return True

    # -- maps for local moves ------------------------------------------------------------
    def proposal_map(self, obs, w, h, span=None, stride=1):
        """``log q̃`` over the working region for a box of size ``(w, h)`` (frame px) centred at each
        working pixel, from the template and the back-projection's contrast
        (:func:`~vistrack.appearance.cue_map.proposal_map`, which documents the arguments)."""
        from .cue_map import proposal_map

        return proposal_map(self, obs, w, h, span, stride)

    def mean_shift(self, obs, boxes, iterations=3):
        """Mean shift of box centres on the back-projection (Comaniciu, Ramesh and Meer 2000):
        each step moves the centre to the back-projection's centroid inside the box. All boxes
        at once through integral images of ``bp``, ``bp u`` and ``bp v``. Returns ``(N, 2)``
        centres in frame px."""
        bp = self.backprojection[obs.labels].astype(np.float64)
        hh, ww = bp.shape
        vv, uu = np.mgrid[0:hh, 0:ww]
        ii = cv2.integral(np.dstack([bp, bp * (uu + 0.5), bp * (vv + 0.5)]), sdepth=cv2.CV_64F)
        b = np.asarray(boxes, float)
        u, v = obs.to_work(b[:, 0], b[:, 1])
        hw, hh2 = 0.5 * obs.f * b[:, 2], 0.5 * obs.f * b[:, 3]
        for _ in range(iterations):
            s = box_sums(ii, *(np.rint(a).astype(np.intp) for a in (u - hw, v - hh2, u + hw, v + hh2)))
            ok = s[:, 0] > 1e-6
            u = np.where(ok, s[:, 1] / np.where(ok, s[:, 0], 1.0), u)
            v = np.where(ok, s[:, 2] / np.where(ok, s[:, 0], 1.0), v)
        return np.stack([u / obs.f + obs.x0, v / obs.f + obs.y0], axis=1)

