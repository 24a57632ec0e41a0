"""Auxiliary variable particle filter (thesis 001, Appendix B, Fig. B.1; Pitt & Shephard).

First stage: ``mu_i`` the mean (or a draw) of ``K(.|X_{t-1}^{(i)})`` and
``lambda_i ∝ w_{t-1}^{(i)} r(Y_t|mu_i)`` over ``M >= N`` candidates; draw
auxiliary indices ``k_j ~ lambda``; then ``X_t^{(j)} ~ K(.|X_{t-1}^{(k_j)})`` with
weight ``r(Y_t|X_t^{(j)}) / r(Y_t|mu_{k_j})``.

The first stage is the shared step's :meth:`~vistrack.filters.base.ParticleFilter.look_ahead`:
``log r(Y_t|mu_i)`` tilts the weights that the resampler sees, so the resampling policy
(``ess_threshold``, the birth reserve) applies to ``lambda``. When the policy keeps the set
(``M = N``), each particle keeps ``w_{t-1} r(Y_t|mu) / r(Y_t|mu)``: the step is the
bootstrap filter's.
"""

from __future__ import annotations

import numpy as np

from ..models.protocol import PredictMean, StateSpaceModel, offers
from .bootstrap import Bootstrap

__all__ = ["AVPF"]


class AVPF(Bootstrap):
    """Auxiliary variable particle filter.

    Parameters
    ----------
    first_stage : int or None
        Number ``M`` of first-stage candidates (``M >= N``); ``None`` uses ``N``.
        Candidate ``i`` descends from particle ``i mod N``; ``M > N`` resamples every step.
    point : {"mean", "sample"}
        ``mu_i`` is the mean of ``K`` (``predict_mean``) or a draw from it.
    """

    name = "avpf"
    needs = (StateSpaceModel,)

    def __init__(self, model, *, first_stage=None, point="mean", **kwargs):
        super().__init__(model, **kwargs)
        if point not in ("mean", "sample"):
            raise ValueError(f"point must be 'mean' or 'sample', got {point!r}")
        if point == "mean" and not offers(model, PredictMean):
            point = "sample"
        self.first_stage = first_stage
        self.point = point

    def look_ahead(self, particles, obs, rng, kernel):
        """Candidates ``i mod N`` and ``log r(Y_t|mu_i) (M,)``; zeros when no candidate has a
        finite first-stage weight (the first stage carries no information)."""
        n = particles.n
        m = n if self.first_stage is None else max(int(self.first_stage), n)
        parent = np.arange(m) % n
        prev = particles.states[parent]
        mu = kernel.predict_mean(prev) if self.point == "mean" else kernel.predict(prev, rng)
        log_mu = self.model.loglik(obs, mu)
        if not np.isfinite(np.max(particles.log_weights[parent] + log_mu)):
            log_mu = np.zeros(m)
        return parent, log_mu
