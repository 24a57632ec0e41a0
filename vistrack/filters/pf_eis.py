"""PF-EIS: efficient importance sampling (seed 000, §2.2 and the algorithm of §3.3).

1. ``s_t, θ_t`` from their state-transition prior (broad: sampled, not approximated);
2. ``m = argmin_c L(c)`` of eq. (8) given ``(s_t, θ_t)``, ``Σ_IS = [∇²L(m)]⁻¹``;
3. ``c_t ~ N(m, Σ_IS)``;
4. ``U_t = g(U_{t-1}, z_{t-1})``, ``z_t = f(z_{t-1}, U_t, c_t)``;
5. ``w_t ∝ w_{t-1} p(Y_t|X_t) N(c_t; A_c c_{t-1}, Σ_c) / N(c_t; m, Σ_IS)``.
"""

from __future__ import annotations

from ..models.protocol import EISModel, LaplaceModel, StateSpaceModel
from .laplace import LaplaceFilter, sample_laplace

__all__ = ["PFEIS"]


class PFEIS(LaplaceFilter):
    """Motion ``(s, θ)`` from the prior, shape velocity ``c`` from the Laplace proposal."""

    name = "pf-eis"
    needs = (StateSpaceModel, LaplaceModel, EISModel)

    def sample_c(self, mode, hess, rng):
        """Step 3: ``c ~ N(m, Σ_IS)``; returns ``(c, log q(c))``."""
        return sample_laplace(mode, hess, rng)

    def propose(self, prev, obs, rng, kernel):
        """Steps 1–5 of seed 000 §3.3 (module docstring): ``(s, θ)`` from the STP, ``c`` from the
        Laplace Gaussian of eq. (8), log increment ``log p(Y_t|X_t) + log N(c; A_c c_{t-1}, Σ_c) -
        log N(c; m, Σ_IS)``.

        Parameters and returns as :meth:`ParticleFilter.propose`: ``prev (N, d)`` ->
        ``(new (N, d), log_incr (N,), predicted (N, d), loglik (N,))``.
        """
        model = self.model
        s, theta = model.sample_motion(prev, rng)
        mode, hess, u = model.laplace(obs, prev, free="c", motion=(s, theta))
        c, log_q = self.sample_c(mode, hess, rng)
        new = model.advance(prev, s, theta, c, u=u)
        ll = model.loglik(obs, new)
        return new, ll + model.c_logpdf(c, prev) - log_q, new, ll
