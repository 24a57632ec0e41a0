"""A generic box model for any object started from an ``--init`` box (real footage; beyond the seeds).

State
    ``(cx, cy, l, cx', cy', l')``, shape ``(N, 6)``: the box centre (px) and its log-scale
    ``l`` relative to the first box (``w = w_0 e^l``, ``h = h_0 e^l``), and the previous
    frame's values.
Dynamics (AR(2), as the contour and plate models)
    ``c_t = c_{t-1} + d (c_{t-1} - c_{t-2}) + σ_c e^{l_{t-1}} ε`` on the centre (``d = 0.5``,
    ``σ_c = sigma_xy · sqrt(w_0 h_0)``), a random walk ``l_t = l_{t-1} + σ_l ε`` on the
    log-scale. The prior ``p_0`` is a Gaussian about the first box with zero velocity.
Likelihood
    :class:`~vistrack.models.appearance.Appearance`: colour histogram against the ring
    around the box (Bhattacharyya) + normalised cross-correlation with a grey template,
    learned from the first frame and adapted on confident frames.
Local moves (thesis 001, §4.3–4.5)
    ``ls-n-ips``: ``LS_λ`` = mean shift on the back-projection of the target histogram
    (:meth:`Appearance.mean_shift`), the move rejected when it goes further than ``λ``
    (half the box's mean side) or lowers ``r`` (eq. 4.1). ``lis``: a grid of translations
    about the prediction with ``q`` from one per-frame map
    (:meth:`Appearance.proposal_map`; :class:`~vistrack.proposals.MapProposal`; the cell
    drawn by inversion of the cumulative ``q g``, the LIS step compiled in two calls:
    :meth:`lis_step`).
    ``lls``: the exact ``r`` on a grid of the window (:class:`~vistrack.proposals.Window`).
Lost
    ``visible=0`` where ``log r`` at the estimate falls far below its running level, the
    scale below a floor or the centre leaves the frame (:mod:`~vistrack.models.collapse`).
"""

from __future__ import annotations

import numpy as np

from .. import kernels
from ..features import remap_points
from ..gaussian import diag_logpdf
from ..proposals import MapProposal, Window
from ..proposals.translation import TranslationMoves
from .appearance import Appearance
from .innovation import ARInnovation
from .kernel import is_prior
from .collapse import CollapseCheck
from .protocol import VideoModelBase

__all__ = ["Box"]


class Box(CollapseCheck, TranslationMoves, ARInnovation, VideoModelBase):
    """Box tracking model with appearance learned from the first frame.

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W)
        The first frame.
    box : tuple of float
        ``(x, y, w, h)`` of the object in ``frame``.
    sigma_xy : float
        Std of the centre's innovation per frame, as a share of ``sqrt(w_0 h_0)``.
    sigma_scale : float
        Std of the log-scale's innovation per frame.
    damping : float
        ``d``: share of the last frame's velocity carried over.
    prior_std : tuple of float
        Std of ``p_0`` on the centre (share of ``sqrt(w_0 h_0)``) and on the log-scale.
    window : float
        LIS/LLS window std as a multiple of the innovation's std.
    map_stride : int
        The LIS proposal map's step in working pixels (:meth:`Appearance.proposal_map`): 2 makes
        ``cv2.matchTemplate`` about 4x cheaper (0.46 -> 0.12 ms on girl_otb) but lowered the success
        AUC on the real clips (girl 0.650 -> 0.632, 12 seeds; hand 0.44 -> 0.39, 24 and 36 seeds; car4
        0.819 -> 0.813): 1 by default (``docs/experiments.md``, speed, third pass).
    **appearance
        Passed to :class:`~vistrack.models.appearance.Appearance`.
    """

    dim = 6
    #: lost (``visible=0``) when ``log r`` at the estimate falls 55 below its running level
    #: (:mod:`~vistrack.models.collapse`): the largest fall while tracking girl, hand and car4
    #: (27 runs) was 43, an object that vanishes from a textured background falls by 75
    collapse_options = {"drop": 55.0}

    def __init__(self, frame, box, *, sigma_xy=0.06, sigma_scale=0.002, damping=0.5, prior_std=(0.04, 0.02),
                 window=2.5, map_stride=1, **appearance):
        x, y, w, h = (float(v) for v in box)
        if not (np.isfinite([x, y, w, h]).all() and w > 0 and h > 0):
            raise ValueError(f"the init box needs a finite position and a positive size, got {tuple(box)}")
        self.frame_size = (frame.shape[1], frame.shape[0])
        self.size0 = np.array([w, h])
        self.app = Appearance(frame, (x, y, w, h), **appearance)
        side = float(np.sqrt(w * h))
        self.sigma = np.array([sigma_xy * side, sigma_xy * side, sigma_scale])
        self.damping = np.array([damping, damping, 0.0])
        self.prior_std = np.array([prior_std[0] * side, prior_std[0] * side, prior_std[1]])
        self.init_pose = np.array([x + w / 2, y + h / 2, 0.0])
        self.prior_mean = np.concatenate([self.init_pose, self.init_pose])
        self.window = float(window)
        self.map_stride = int(map_stride)
        self.blob_cell = 0.25 * side  # the colour-blob proposal's cell (frame px)
        self.learn_blob(frame, _inner_ellipse(frame.shape[:2], (x, y, w, h)))

    # -- geometry ---------------------------------------------------------------------
    def boxes(self, states):
        """``(N, 4)`` boxes ``(cx, cy, w, h)`` of ``states``."""
        s = np.atleast_2d(states)
        wh = self.size0 * np.exp(s[:, 2:3])
        return np.concatenate([s[:, :2], wh], axis=1)

    def box(self, states):
        """``(N, 4)`` boxes ``(x, y, w, h)`` (top-left corner) of ``states``."""
        b = self.boxes(states)
        return np.concatenate([b[:, :2] - b[:, 2:] / 2, b[:, 2:]], axis=1)

    def outline(self, states):
        """Box corners ``(N, 4, 2)`` for drawing."""
        x, y, w, h = self.box(states).T
        return np.stack([np.stack([x, y], 1), np.stack([x + w, y], 1), np.stack([x + w, y + h], 1),
                         np.stack([x, y + h], 1)], axis=1)

    def describe(self, state):
        """Track-file fields of one state: ``cx, cy, w, h, angle_deg, scale``."""
        cx, cy, w, h = self.boxes(state)[0]
        return {"cx": cx, "cy": cy, "w": w, "h": h, "angle_deg": 0.0, "scale": float(np.exp(np.ravel(state)[2]))}

    # -- dynamics ---------------------------------------------------------------------
    def _std(self, old):
        """Innovation std ``(N, 3)``: the centre's scales with the old box."""
        sd = np.broadcast_to(self.sigma, (len(old), 3)).copy()
        sd[:, :2] *= np.exp(old[:, 2:3])
        return sd

    def innovation_std(self, old):
        """Std ``(N, 3)`` of the current values given ``old`` (:class:`~vistrack.models.innovation.ARInnovation`)."""
        return self._std(old)

    def blob_image(self, obs):
        """The colour-blob proposal looks at the observation's region at the working resolution."""
        return obs.image, obs.x0, obs.y0, obs.f

    def sample_prior(self, n, rng):
        """``n`` states ``(n, 6)`` from ``p_0``: a Gaussian about the first box, zero velocity (previous = current)."""
        z = self.init_pose + self.prior_std * rng.standard_normal((n, 3))
        return np.concatenate([z, z], axis=1)

    def prior_logpdf(self, states):
        """``log p_0`` of the current pose of ``states (N, 6)`` -> ``(N,)``."""
        return diag_logpdf(states[:, :3], self.init_pose, self.prior_std)

    def predict_mean(self, states):
        """The mean of the AR(2) ``K``: ``z + d (z - z')``, with ``z`` as the new previous pose; ``(N, 6)`` ->
        ``(N, 6)``."""
        z1, z2 = states[:, :3], states[:, 3:]
        return np.concatenate([z1 + self.damping * (z1 - z2), z1], axis=1)

    def predict(self, states, rng):
        """A draw from ``K``: the mean plus ``σ_c e^{l}`` noise on the centre and ``σ_l`` on the log-scale;
        ``(N, 6)`` -> ``(N, 6)``."""
        noise = rng.standard_normal((len(states), 3))
        if kernels.use():
            from ..kernels.box import ar2_predict

            return ar2_predict(np.ascontiguousarray(states, float), self.damping, self.sigma, noise,
                               np.empty((len(states), 6)))
        out = self.predict_mean(states)
        out[:, :3] += self._std(states) * noise
        return out

    def transition_logpdf(self, new, old):
        """``log K(new|old)``: Gaussian in the current values; the previous values of ``new``
        are the current values of ``old``."""
        if kernels.use():
            from ..kernels.box import ar2_logpdf

            return ar2_logpdf(np.ascontiguousarray(new, float), np.ascontiguousarray(old, float), self.damping,
                              self.sigma, np.empty(len(new)))
        return diag_logpdf(new[:, :3], self.predict_mean(old)[:, :3], self._std(old))

    # -- observation --------------------------------------------------------------------
    def observe(self, maps, particles):
        """The frame's :class:`~vistrack.models.appearance.AppearanceFrame` over the region the
        particles can reach: their predicted boxes grown by 4 innovation stds, the LIS window's
        reach and the velocity (the first box and the prior's spread on the first frame)."""
        if particles is None:
            states = self.prior_mean[None]
            reach = 4 * self.prior_std[0] * (1 + self.window)
        elif kernels.use():
            from ..kernels.box_frame import predicted_roi

            roi = predicted_roi(np.ascontiguousarray(particles.states, float), self.damping, self.size0,
                                4 * self.sigma[0], 1 + self.window, float(self.app.ring), np.empty(4, np.int64))
            return self.app.frame(maps.frame, tuple(int(v) for v in roi))
        else:
            states = self.predict_mean(particles.states)
            reach = 4 * self.sigma[0] * np.exp(states[:, 2].max()) * (1 + self.window)
        return self.app.frame(maps.frame, self.app.roi(self.boxes(states), reach))

    def loglik(self, obs, states):
        """``log r`` of ``states (N, 6)``, shape ``(N,)``."""
        if kernels.use():
            return self.app.loglik_states(obs, np.ascontiguousarray(states, float), self.size0)
        return self.app.loglik(obs, self.boxes(states))

    def estimate(self, particles):
        """The weighted mean state."""
        return particles.mean()

    def adapt(self, obs, estimate):
        """Adapt the appearance to the estimate on a confident frame (:meth:`Appearance.adapt`)."""
        return self.app.adapt(obs, self.boxes(estimate)[0])

    # -- local moves ------------------------------------------------------------------
    def window_std(self, states=None, kernel=None):
        """Window std on the centre (px): ``window`` innovation stds of ``kernel`` (``p_0`` on
        the first step, :mod:`~vistrack.models.kernel`), per particle ``(N,)`` with ``states``,
        else the scalar at scale 1."""
        base = self.window * (self.prior_std[0] if is_prior(kernel) else self.sigma[0])
        return base if states is None else base * np.exp(states[:, 2])

    #: the LIS map's tempering and flat share: ``q = (1 - s) e / max e + s`` with ``e = exp(t (m - max m))``
    #: the tempered map read bilinearly and ``max e`` over each particle's grid (``(t, s)``)
    proposal_tempering = (0.5, 0.05)

    def proposal_work(self, obs):
        """``(x0, y0, f)``: frame px ``x`` is working px ``(x - x0) f`` of the proposal map."""
        return float(obs.x0), float(obs.y0), float(obs.f)

    def proposal_qmap(self, obs, states, span):
        """The LIS proposal map of the frame ``(e (H', W') float32, u0, v0, step)`` (map pixel ``(i, j)``
        at working centre ``(u0 + step j, v0 + step i)``) or ``()``: ``exp(t (m - max m))`` of
        :meth:`Appearance.proposal_map` ``m`` at the mean size of ``states`` and stride
        :attr:`map_stride`, over the working ``span`` ``(u_min, u_max, v_min, v_max)`` the points read
        (:attr:`proposal_tempering`); computed on the first call of the frame and kept on ``obs``."""
        if obs.proposal is None:
            w, h = self.size0 * np.exp(np.mean(states[:, 2]))
            pm = self.app.proposal_map(obs, w, h, span=span, stride=self.map_stride)
            if pm:
                m = pm[0]
                pm = (np.exp(np.float32(self.proposal_tempering[0]) * (m - m.max())),) + tuple(pm[1:])
            obs.proposal = pm or ()
        return obs.proposal

    def proposal_log_q(self, obs, states, points):
        """The map's ``log q`` at centres ``points (N, G, 2)`` (frame px), for the LIS proposal:
        :meth:`proposal_qmap` read bilinearly, over its maximum on each row, mixed with 5 % of a
        flat floor (a defensive share; :attr:`proposal_tempering`)."""
        u, v = obs.to_work(points[..., 0], points[..., 1])
        qmap = self.proposal_qmap(obs, states, (u.min(), u.max(), v.min(), v.max()))
        n, g, _ = points.shape
        if not qmap:
            return np.zeros((n, g))
        e, u0, v0, step = qmap
        floor = self.proposal_tempering[1]
        val = remap_points(e, (u - u0) / step, (v - v0) / step, border=float(e.min())).astype(float)
        top = val.max(axis=1, keepdims=True)
        return np.log((1 - floor) * np.divide(val, top, out=np.ones_like(val), where=top > 0) + floor)

    def lis_step(self, prev, obs, rng, proposal):
        """``LIS.propose`` with ``proposal`` (this model's :class:`MapProposal` of ``K``) in two compiled
        calls (:func:`~vistrack.kernels.box.lis_predict`, :func:`~vistrack.kernels.box.lis_weigh`) about
        the proposal map: the same draws in the same order and the same arithmetic as the calls one
        by one. Returns ``(z, log_incr, x, log r(z))``."""
        from ..kernels.box import lis_predict, lis_weigh

        prev = np.ascontiguousarray(prev, float)
        n, g = len(prev), len(proposal.offsets)
        x, sig, uw, vw = np.empty((n, 6)), np.empty(n), np.empty((n, g)), np.empty((n, g))
        x0, y0, f = self.proposal_work(obs)
        span = lis_predict(prev, self.damping, self.sigma, rng.standard_normal((n, 3)), self.window * self.sigma[0],
                           proposal.offsets, x0, y0, f, x, sig, uw, vw, np.empty(4))
        qmap = self.proposal_qmap(obs, x, tuple(span))
        m, u0, v0, step = qmap if qmap else (np.zeros((0, 1), np.float32), 0.0, 0.0, 1.0)
        floor, app, c = self.proposal_tempering[1], self.app, self.app.colour
        z, log_incr, ll = np.empty((n, 6)), np.empty(n), np.empty(n)
        lis_weigh(prev, x, sig, proposal.offsets, proposal.g_unit, proposal.log_g_unit, float(proposal.cell), uw, vw,
                  m[..., None], float(u0), float(v0), float(step), float(m.min()) if qmap else 0.0, 1.0 - floor,
                  float(floor), rng.random((n, 3)), self.damping, self.sigma, self.size0, obs.ii, obs.texture, x0, y0,
                  f, float(app.ring), c.bg_weight, c.q, c._bp, float(c.lambda_colour), float(c.kappa), *app.grid_axes,
                  app.template, float(app.lambda_template), z, log_incr, ll)
        return z, log_incr, x, ll

    def lis_proposal(self, kernel=None):
        """LIS's proposal for a step with ``kernel``: the colour/template map on a grid."""
        return MapProposal(self, kernel=kernel)

    def lls_window(self, kernel=None):
        """LLS's Gaussian window on the centre, :meth:`window_std` of ``kernel``."""
        return Window("gaussian", [self.window_std(kernel=kernel)] * 2, grid=5, truncate=2.5)

    def local_search(self, obs, states):
        """``LS_λ``: mean shift of the centres on the back-projection; a move longer than ``λ``
        (half the box's mean side) or one that lowers ``r`` is rejected (eq. 4.1). Returns the
        states and their ``log r``."""
        b = self.boxes(states)
        c = self.app.mean_shift(obs, b)
        lam = 0.25 * (b[:, 2] + b[:, 3])
        moved = self.with_local(states, c)
        ok = np.all(np.abs(c - states[:, :2]) <= lam[:, None], axis=1)
        ll_x = self.loglik(obs, states)
        ll_z = np.where(ok, self.loglik(obs, moved), -np.inf)
        keep = ll_z >= ll_x
        return np.where(keep[:, None], moved, states), np.where(keep, ll_z, ll_x)


def _inner_ellipse(shape, box, share=0.8):
    """Mask ``(H, W)`` of the ellipse inscribed in ``share`` of the box (its corners are background)."""
    import cv2

    x, y, w, h = box
    mask = np.zeros(shape, np.uint8)
    cv2.ellipse(mask, (int(round(x + w / 2)), int(round(y + h / 2))),
                (max(1, int(round(share * w / 2))), max(1, int(round(share * h / 2)))), 0, 0, 360, 1, -1)
    return mask
