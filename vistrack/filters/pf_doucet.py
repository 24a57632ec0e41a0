"""PF-Doucet: Laplace approximation of the optimal proposal ``p*`` over the whole state (seed 000, §1, [3]).

``m = argmin L(s, θ, c)`` with ``L = -log p(Y|X) - log p(X|X_{t-1})``, sample
``(s, θ, c) ~ N(m, [∇²L(m)]⁻¹)``, weight ``p(Y|X) p(X|X_{t-1}) / N(X; m, Σ_IS)``.
When ``p*`` is multimodal in ``(s, θ)`` the Gaussian sits on one mode — the
failure PF-EIS avoids (§4, Fig. 2c).
"""

from __future__ import annotations

from ..models.protocol import LaplaceModel, StateSpaceModel
from .laplace import LaplaceFilter, sample_laplace

__all__ = ["PFDoucet"]


class PFDoucet(LaplaceFilter):
    """Gaussian proposal at the mode of ``p*(s, θ, c)``."""

    name = "pf-doucet"
    needs = (StateSpaceModel, LaplaceModel)

    def propose(self, prev, obs, rng, kernel):
        """``(s, θ, c) ~ N(m, Σ_IS)`` at the mode of ``L`` over the whole sampled state (seed 000 §1,
        [3]), log increment ``log p(Y_t|X_t) + log p(X_t|X_{t-1}) - log N(X_t; m, Σ_IS)``.

        Parameters and returns as :meth:`ParticleFilter.propose`: ``prev (N, d)`` ->
        ``(new (N, d), log_incr (N,), predicted (N, d), loglik (N,))``.
        """
        model = self.model
        mode, hess, u = model.laplace(obs, prev, free="all")
        x, log_q = sample_laplace(mode, hess, rng)
        new = model.advance(prev, x[:, 0], x[:, 1], x[:, 2:], u=u)
        ll = model.loglik(obs, new)
        return new, ll + kernel.logpdf(new, prev) - log_q, new, ll
