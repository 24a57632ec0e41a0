"""Sequential importance resampling with a user proposal (thesis 001, §3.1, Fig. 3.1).

``X_t ~ pi(.|X_{t-1}, Y_t)``, ``w_t = w_{t-1} r(Y_t|X_t) K(X_t|X_{t-1}) / pi(X_t|X_{t-1}, Y_t)``.
"""

from __future__ import annotations

from ..models.protocol import SIRModel, StateSpaceModel
from .base import ParticleFilter

__all__ = ["SIR"]


class SIR(ParticleFilter):
    """SIR filter.

    Parameters
    ----------
    model : object
        The tracking model (see :class:`~vistrack.filters.base.ParticleFilter`).
    proposal : object or None
        ``sample(prev, obs, rng) -> new (N, d)`` and
        ``logpdf(new, prev, obs) -> (N,)``; must be positive wherever ``K`` is.
        ``None`` asks the model (``model.sir_proposal(kernel)``).
    """

    name = "sir"
    needs = (StateSpaceModel,)
    model_parts = {"proposal": (SIRModel, "sir_proposal")}

    def __init__(self, model, proposal=None, **kwargs):
        super().__init__(model, **kwargs)
        self._set_part("proposal", proposal)

    def propose(self, prev, obs, rng, kernel):
        """Fig. 3.1: ``X_t ~ π(.|Z_{t-1}, Y_t)``, log increment ``log r(Y_t|X_t) + log K(X_t|Z_{t-1}) -
        log π(X_t|Z_{t-1}, Y_t)``; the fallback prediction is a draw from ``K``.

        Parameters and returns as :meth:`ParticleFilter.propose`: ``prev (N, d)`` ->
        ``(new (N, d), log_incr (N,), predicted (N, d), loglik (N,))``.
        """
        proposal = self.part("proposal", kernel)
        x = proposal.sample(prev, obs, rng)
        ll = self.model.loglik(obs, x)
        log_incr = ll + kernel.logpdf(x, prev) - proposal.logpdf(x, prev, obs)
        return x, log_incr, kernel.predict(prev, rng), ll
