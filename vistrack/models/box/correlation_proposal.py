"""LIS's importance function from a correlation filter's response (thesis 001, §4.5).

The observation goes into the proposal: with probability ``β`` a particle's new pose is drawn from
the correlation filter's response over the search region (:class:`~vistrack.appearance.correlation.DCFResponse`,
the best scale's map), else from the dynamics ``K``. The response map's cells are drawn with
probabilities ``p_c = (1 - s) e_c / Σ e + s / C`` (``e = exp(t (y - max y))``, ``C`` cells), the
centre uniformly inside the cell (side ``a`` frame px) and the log-scale from
``N(l*, σ_l)`` about the best scale ``l*``, so the density of that component is exactly
``q_Y(z) = p_{c(z)} / a² · N(l_z; l*, σ_l)`` inside the region (0 outside) and integrates to 1. The
proposal's density is the mixture ``q(z | z') = β q_Y(z) + (1 - β) K(z | z')``, and the weight is the
proper ``r(Y|z) K(z|z') / q(z|z')`` (the previous pose of ``z`` is the current pose of ``z'`` in both
components, as ``K`` sets it). In LIS's terms (:meth:`LIS.propose <vistrack.filters.lis.LIS.propose>`:
``log α + log r - log q + log K(z) - log K(x)``) this returns ``log α = log K(x|z')`` and
``log q = log q(z|z')``.

Draws per step: ``rng.random((N, 4))`` (component, cell, position in the cell) and
``rng.standard_normal(N)`` (log-scale), after ``K``'s own.
"""

from __future__ import annotations

import numpy as np

from ... import kernels

__all__ = ["CorrelationProposal"]

_LOG_SQRT_2PI = 0.5 * np.log(2 * np.pi)


class CorrelationProposal:
    """Mixture of the correlation filter's response and ``K`` (module docstring).

    Parameters
    ----------
    model : object
        Supplies ``dcf_share`` (``β``), ``dcf_tempering`` (``(t, s)``) and ``dcf_scale_std`` (``σ_l``);
        the observation supplies ``obs.dcf`` (a :class:`~vistrack.appearance.correlation.DCFResponse` or
        ``None``: then ``z = x``, the bootstrap step) and ``obs.dcf_share`` (``β`` of this frame).
    kernel : Transition
        The step's ``K``.
    """

    def __init__(self, model, kernel):
        self.model = model
        self.kernel = kernel

    @staticmethod
    def _centre(obs):
        """The proposal's log-scale centre ``l*``: the observation's ``scale_centre`` where the model set one,
        else the translation filter's best scale."""
        resp = obs.dcf
        return resp.log_scales[resp.best] if obs.scale_centre is None else obs.scale_centre

    def log_density(self, resp, z, centre=None):
        """``log q_Y(z)`` ``(N,)`` of states ``z (N, >=3)`` (module docstring); ``-inf`` outside the region."""
        t, s = self.model.dcf_tempering
        log_p = resp.cell_log_p(t, s)
        (ox, oy), a = resp.cell_origin()
        h, w = resp.maps.shape[1:]
        j = np.floor((z[:, 0] - ox) / a + 0.5).astype(np.intp)
        i = np.floor((z[:, 1] - oy) / a + 0.5).astype(np.intp)
        inside = (j >= 0) & (j < w) & (i >= 0) & (i < h)
        out = np.full(len(z), -np.inf)
        sd = self.model.dcf_scale_std
        d = (z[:, 2] - (resp.log_scales[resp.best] if centre is None else centre)) / sd
        out[inside] = log_p[i[inside] * w + j[inside]] - 2 * np.log(a) - 0.5 * d[inside] ** 2 - _LOG_SQRT_2PI \
            - np.log(sd)
        return out

    def draw(self, resp, u, e, centre=None):
        """Poses ``(N, 3)`` drawn from ``q_Y`` with uniforms ``u (N, 3)`` (cell, position in it) and normals
        ``e (N,)`` (log-scale)."""
        c = resp.cell_cumulative(*self.model.dcf_tempering)
        k = np.minimum(np.searchsorted(c, u[:, 0] * c[-1], side="right"), len(c) - 1)
        w = resp.maps.shape[2]
        (ox, oy), a = resp.cell_origin()
        x = ox + a * (k % w + u[:, 1] - 0.5)
        y = oy + a * (k // w + u[:, 2] - 0.5)
        l_star = resp.log_scales[resp.best] if centre is None else centre
        return np.stack([x, y, l_star + self.model.dcf_scale_std * e], axis=1)

    def sample(self, x, obs, rng, prev):
        """``(z, log α, log q)`` for LIS (module docstring) about the predictions ``x (N, 6)`` from ``prev``."""
        z, log_kx, log_q, _ = self._sample(x, obs, rng, prev)
        return z, log_kx, log_q

    def propose(self, prev, obs, rng, kernel):
        """LIS's whole step (:meth:`LIS.propose <vistrack.filters.lis.LIS.propose>`, the same draws and
        arithmetic) with ``log K`` of the prediction and of the draw computed once each: LIS's
        ``log α + log r - log q + log K(z) - log K(x)`` with ``log α = log K(x)``. ``None`` for a
        ``kernel`` other than this proposal's (the filter then calls the parts)."""
        if kernel is not self.kernel:
            return None
        x = kernel.predict(prev, rng)
        z, log_kx, log_q, log_kz = self._sample(x, obs, rng, prev)
        ll = self.model.loglik(obs, z)
        log_incr = log_kx + ll - log_q + log_kz - log_kx
        return z, np.where(np.isfinite(log_kx), log_incr, -np.inf), x, ll

    def _sample(self, x, obs, rng, prev):
        """:meth:`sample`'s ``(z, log α, log q)`` and ``log K(z | prev)``."""
        resp = obs.dcf
        log_kx = self.kernel.logpdf(x, prev)
        if resp is None:
            return x, log_kx, log_kx, log_kx
        beta = float(obs.dcf_share)
        n = len(x)
        u = rng.random((n, 4))
        e = rng.standard_normal(n)
        if kernels.use():  # draws and density in one compiled pass, the same arithmetic
            from ...appearance.dcf_kernels import correlation_draws

            t, s = self.model.dcf_tempering
            (ox, oy), a = resp.cell_origin()
            h, w = resp.maps.shape[1:]
            sd = self.model.dcf_scale_std
            z, log_qy = np.empty(np.shape(x)), np.empty(n)
            correlation_draws(np.ascontiguousarray(x, float), u, e, beta, resp.cell_cumulative(t, s),
                              resp.cell_log_p(t, s), float(ox), float(oy), float(a), w, h,
                              float(self._centre(obs)), float(sd), float(2 * np.log(a)), float(np.log(sd)),
                              _LOG_SQRT_2PI, z, log_qy)
        else:
            z = np.array(x, float)
            pick = u[:, 0] < beta
            if pick.any():
                z[pick, :3] = self.draw(resp, u[pick, 1:], e[pick], self._centre(obs))
            log_qy = self.log_density(resp, z, self._centre(obs))
        log_kz = self.kernel.logpdf(z, prev)
        parts = [np.log(beta) + log_qy if beta > 0 else np.full(n, -np.inf),
                 np.log1p(-beta) + log_kz if beta < 1 else np.full(n, -np.inf)]
        return z, log_kx, np.logaddexp(*parts), log_kz
