"""Bootstrap filter / CONDENSATION / N-IPS (thesis 001, §2.6, Fig. 2.3).

Predict with the dynamics ``K``, weight with the likelihood ``r``, resample.
"""

from __future__ import annotations

from ..models.protocol import StateSpaceModel
from .base import ParticleFilter

__all__ = ["Bootstrap"]


class Bootstrap(ParticleFilter):
    """``Z_t ~ K(.|Z_{t-1})``, ``w_t = r(Y_t|Z_t)``."""

    name = "bootstrap"
    needs = (StateSpaceModel,)

    def propose(self, prev, obs, rng, kernel):
        """``Z_t = X_t ~ K(.|Z_{t-1})`` with log weight increment ``log r(Y_t|Z_t)`` (Fig. 2.3).

        Parameters and returns as :meth:`ParticleFilter.propose`: ``prev (N, d)`` ->
        ``(new (N, d), log_incr (N,), predicted (N, d), loglik (N,))``.
        """
        x = kernel.predict(prev, rng)
        ll = self.model.loglik(obs, x)
        return x, ll, x, ll
