"""Local importance sampling particle filter (thesis 001, §4.5, Figs. 4.12, 4.13, 4.17).

Predict ``X_t ~ K(.|Z_{t-1})``, perturb ``Z_t ~ q_{X,Y}(.) g(X_t - .) / alpha_t`` with
``alpha_t = (q_{X,Y} * g)(X_t)``, weight
``alpha_t r(Y_t|Z_t) / q_{X,Y}(Z_t) · K(Z_t|Z_{t-1}) / K(X_t|Z_{t-1})`` (Prop. 4.5.1).

The local proposal is model-supplied: any object with
``sample(x, obs, rng, prev) -> (z, log_alpha, log_q)`` where ``z (N, d)`` was drawn from
``q g / alpha`` (``prev``, the resampled ``Z_{t-1}``, lets a window follow ``K`` itself).
:class:`GaussMixtureProposal` is the closed form of Fig. 4.17: a Gauss-mixture ``q``
times a Gaussian window is again a Gauss mixture (App. D).
"""

from __future__ import annotations

import numpy as np

from ..core.hooks import FusedPropose, LookAhead, offers
from ..models.protocol import LISModel, StateSpaceModel
from ..proposals import GaussMixtureProposal
from .base import ParticleFilter

__all__ = ["LIS", "GaussMixtureProposal"]


class LIS(ParticleFilter):
    """LIS-based particle filter (Fig. 4.13).

    Parameters
    ----------
    proposal : object or None
        Local proposal with ``sample(x, obs, rng, prev) -> (z, log_alpha, log_q)``;
        ``None`` asks the model (``model.lis_proposal(kernel)``, one per kernel:
        :meth:`~vistrack.filters.base.ParticleFilter.part`). A proposal that also has
        ``look_ahead(prev, obs, kernel) -> log p̂ (N,) or None`` gives the filter a first stage
        (:meth:`look_ahead`).
    """

    name = "lis"
    needs = (StateSpaceModel,)
    model_parts = {"proposal": (LISModel, "lis_proposal")}

    def __init__(self, model, proposal=None, **kwargs):
        super().__init__(model, **kwargs)
        self._set_part("proposal", proposal)

    def look_ahead(self, particles, obs, rng, kernel):
        """A first stage where the local proposal offers one: ``proposal.look_ahead(prev, obs,
        kernel) -> log p̂(Y_t|Z_{t-1}) (N,)`` (or ``None``) tilts the weights before resampling and
        is divided out after, as in AVPF (App. B); ``None`` (no first stage) otherwise."""
        proposal = self.part("proposal", kernel)
        log_mu = proposal.look_ahead(particles.states, obs, kernel) if offers(proposal, LookAhead) else None
        return None if log_mu is None else (np.arange(particles.n), log_mu)

    def propose(self, prev, obs, rng, kernel):
        """Prop. 4.5.1 / Fig. 4.13: ``X_t ~ K(.|Z_{t-1})``, ``Z_t ~ q g(X_t - .) / α`` from the local
        proposal, log increment ``log α + log r(Y_t|Z_t) - log q(Z_t) + log K(Z_t|Z_{t-1}) -
        log K(X_t|Z_{t-1})``.

        Parameters and returns as :meth:`ParticleFilter.propose`: ``prev (N, d)`` ->
        ``(new (N, d), log_incr (N,), predicted (N, d), loglik (N,))``.
        """
        proposal = self.part("proposal", kernel)
        # the whole step in one pass where the proposal can (the box model's map proposal)
        out = proposal.propose(prev, obs, rng, kernel) if offers(proposal, FusedPropose) else None
        if out is not None:
            return out
        x = kernel.predict(prev, rng)
        z, log_alpha, log_q = proposal.sample(x, obs, rng, prev)
        ll = self.model.loglik(obs, z)
        log_incr = log_alpha + ll - log_q + kernel.logpdf(z, prev) - kernel.logpdf(x, prev)
        log_incr = np.where(np.isfinite(log_alpha), log_incr, -np.inf)
        return z, log_incr, x, ll
