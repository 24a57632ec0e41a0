"""The box model's local moves (thesis 001 §4.3–4.5): the window on the centre (LLS, LIS), the
colour/template map as LIS's grid proposal (the proposal before the correlation filter, ``dcf=False``,
and on the first frame: :meth:`~vistrack.appearance.cues.Appearance.proposal_map` tempered, read by
:class:`~vistrack.proposals.MapProposal`, and LIS's whole step with it in two compiled calls), and the
mean-shift local search ``LS_λ``. A mixin of :class:`~vistrack.models.box.model.Box`."""

from __future__ import annotations

import numpy as np

from ...appearance.features import remap_points
from ...core.transition import is_prior
from ...proposals import Window

__all__ = ["BoxMoves"]


class BoxMoves:
    """The local moves of :class:`~vistrack.models.box.model.Box` (module docstring)."""

    def window_std(self, states=None, kernel=None):
        """Window std on the centre (px): ``window`` innovation stds of ``kernel`` (``p_0`` on
        the first step, :mod:`~vistrack.core.transition`), per particle ``(N,)`` with ``states``,
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
        calls (:func:`~vistrack.models.box.kernels.lis_predict`, :func:`~vistrack.models.box.kernels.lis_weigh`) about
        the proposal map: the same draws in the same order and the same arithmetic as the calls one
        by one. Returns ``(z, log_incr, x, log r(z))``."""
        from .kernels import lis_predict, lis_weigh

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
                  f, float(app.ring), c.bg_weight, c.q, c.bp, float(c.lambda_colour), float(c.kappa), *app.grid_axes,
                  app.template, float(app.lambda_template), z, log_incr, ll)
        return z, log_incr, x, ll

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
