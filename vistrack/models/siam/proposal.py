"""LIS's local proposal from the Siamese network's response (thesis 001 §4.5, Prop. 4.5.1).

The observation goes into the proposal: with probability ``β`` a particle is drawn from the network's
strongest cells, else from the dynamics ``K``. The response part is a Gaussian mixture over the ``C``
cells of highest logit: cell ``k`` with probability ``π_k ∝ exp(τ ℓ_k)`` (normalised over the ``C``), then
the pose from ``N(b_k, Σ_k)`` about the head's box ``b_k = (cx, cy, lw, lh)`` of that cell, with
``Σ_k = diag((s_c w_k)², (s_c h_k)², s_l², s_l²)`` (``w_k``, ``h_k`` the box's size in px). Its density

``q_Y(z) = Σ_k π_k N(z; b_k, Σ_k)``

integrates to 1 exactly; the proposal's density is the mixture ``q(z | z') = β q_Y(z) + (1 - β) K(z | z')``,
and the weight is the proper ``r(Y|z) K(z|z') / q(z|z')`` (the previous pose of ``z`` is the current pose of
``z'`` in both components, as ``K`` sets it). In LIS's terms (:meth:`LIS.propose
<vistrack.filters.lis.LIS.propose>`) this returns ``log α = log K(x|z')`` and ``log q = log q(z|z')``.

Draws per step: ``K``'s own, then ``rng.random((N, 2))`` (component, cell) and ``rng.standard_normal((N, 4))``
(the pose about the cell's box).
"""

from __future__ import annotations

import numpy as np

from ... import kernels
from ...core.transition import is_prior

__all__ = ["ResponseProposal", "mixture_parts"]

_LOG_2PI = np.log(2 * np.pi)


def mixture_parts(obs, cells, tempering, spread):
    """The response mixture of ``obs`` (:class:`~vistrack.models.siam.observation.SiamFrame`): ``(log π (C,),
    means (C, 4), stds (C, 4))`` over its ``cells`` strongest cells (module docstring; ``spread = (s_c, s_l)``).
    Kept on the observation: every particle and the confidence read the same mixture."""
    key = ("mixture", cells, tempering, spread)
    if key not in obs._cache:
        flat = obs.logit.ravel()
        c = min(int(cells), flat.size)
        if kernels.use():
            from .kernels import mixture_into

            log_pi, mu, sd = np.empty(c), np.empty((c, 4)), np.empty((c, 4))
            mixture_into(flat, obs.boxes, float(tempering), float(spread[0]), float(spread[1]), float(obs.size0[0]),
                         float(obs.size0[1]), log_pi, mu, sd)
        else:
            top = np.argsort(-flat, kind="stable")[:c]  # the strongest cells, ties by index
            a = tempering * flat[top]
            log_pi = a - (a.max() + np.log(np.exp(a - a.max()).sum()))
            mu = obs.boxes[top]
            size = np.exp(mu[:, 2:]) * obs.size0
            sd = np.concatenate([spread[0] * size, np.full((c, 2), spread[1])], axis=1)
        obs._cache[key] = (log_pi, mu, sd)
    return obs._cache[key]


def mixture_logpdf(z, log_pi, mu, sd):
    """``log q_Y`` ``(N,)`` of poses ``z (N, >=4)`` under the mixture ``(log π (C,), means (C, 4), stds (C, 4))``."""
    d = (z[:, None, :4] - mu[None]) / sd[None]
    comp = log_pi[None] - 0.5 * np.einsum("nck,nck->nc", d, d) - np.log(sd).sum(axis=1)[None] - 2 * _LOG_2PI
    m = comp.max(axis=1)
    return m + np.log(np.exp(comp - m[:, None]).sum(axis=1))


class ResponseProposal:
    """Mixture of the network's strongest cells and ``K`` (module docstring).

    Parameters
    ----------
    model : Siam
        Supplies ``share`` (``β``), ``cells`` (``C``), ``tempering`` (``τ``) and ``spread`` (``(s_c, s_l)``).
    kernel : Transition
        The step's ``K`` (or ``p_0`` on the first step).
    """

    def __init__(self, model, kernel):
        self.model = model
        self.kernel = kernel

    def parts(self, obs):
        """The response mixture of ``obs`` (:func:`mixture_parts` with the model's settings)."""
        m = self.model
        return mixture_parts(obs, m.cells, m.tempering, m.spread)

    def log_density(self, obs, z):
        """``log q_Y(z)`` ``(N,)`` of states ``z (N, >=4)``."""
        return mixture_logpdf(z, *self.parts(obs))

    def draw(self, obs, u, e):
        """Poses ``(N, 4)`` from ``q_Y`` with uniforms ``u (N,)`` (the cell) and normals ``e (N, 4)``."""
        log_pi, mu, sd = self.parts(obs)
        c = np.cumsum(np.exp(log_pi))
        k = np.minimum(np.searchsorted(c, u * c[-1], side="right"), len(c) - 1)
        return mu[k] + sd[k] * e

    def sample(self, x, obs, rng, prev):
        """``(z, log α, log q)`` for LIS about the predictions ``x (N, 8)`` from ``prev``."""
        z, log_kx, log_q, _ = self._sample(x, obs, rng, prev)
        return z, log_kx, log_q

    def propose(self, prev, obs, rng, kernel):
        """LIS's whole step with ``log K`` of the prediction and of the draw computed once each (LIS's
        ``log α + log r - log q + log K(z) - log K(x)`` with ``log α = log K(x)``); ``None`` for another kernel."""
        if kernel is not self.kernel:
            return None
        if kernels.use() and not is_prior(kernel):
            return self._compiled(prev, obs, rng)
        x = kernel.predict(prev, rng)
        z, log_kx, log_q, log_kz = self._sample(x, obs, rng, prev)
        ll = self.model.loglik(obs, z)
        return z, np.where(np.isfinite(log_kx), ll - log_q + log_kz, -np.inf), x, ll

    def _compiled(self, prev, obs, rng):
        """:meth:`propose` in one compiled call (:func:`vistrack.models.siam.kernels.lis_step`), the same draws."""
        from .kernels import lis_step

        m = self.model
        n = len(prev)
        e_k = rng.standard_normal((n, 4))
        u_k = rng.random(n) if m._jump > 0 else np.empty(n)
        u = rng.random((n, 2))
        e = rng.standard_normal((n, 4))
        log_pi, mu, sd = self.parts(obs)
        z, x, incr, ll = np.empty((n, 8)), np.empty((n, 8)), np.empty(n), np.empty(n)
        (logit, boxes, cx, cy, k, half, floor, bs0, bs1, w0, h0, gate) = m.frame_args(obs)
        lis_step(np.ascontiguousarray(prev, float), e_k, u_k, u, e, float(m.share), m.damping, m.sigma_xy * m.side0,
                 m.sigma_jump / m.sigma_xy, m._jump, m.sigma_scale, m.sigma_aspect, np.cumsum(np.exp(log_pi)), log_pi,
                 mu, sd, logit, boxes, cx, cy, k, half, floor, m.lambda_logit, bs0, bs1, w0, h0, gate, z, x, incr, ll)
        return z, incr, x, ll

    def _sample(self, x, obs, rng, prev):
        beta = float(self.model.share)
        n = len(x)
        u = rng.random((n, 2))
        e = rng.standard_normal((n, 4))
        log_kx = self.kernel.logpdf(x, prev)
        z = np.array(x, float)
        pick = u[:, 0] < beta
        if pick.any():
            z[pick, :4] = self.draw(obs, u[pick, 1], e[pick])
        log_kz = self.kernel.logpdf(z, prev)
        parts = [np.log(beta) + self.log_density(obs, z) if beta > 0 else np.full(n, -np.inf),
                 np.log1p(-beta) + log_kz if beta < 1 else np.full(n, -np.inf)]
        return z, log_kx, np.logaddexp(*parts), log_kz
