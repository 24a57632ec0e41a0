"""Auxiliary variable particle filter (thesis 001, Appendix B, Fig. B.1; Pitt & Shephard).

First stage: ``mu_i`` the mean (or a draw) of ``K(.|X_{t-1}^{(i)})`` and
``lambda_i ∝ w_{t-1}^{(i)} r(Y_t|mu_i)`` over ``M >= N`` candidates; draw
auxiliary indices ``k_j ~ lambda``; then ``X_t^{(j)} ~ K(.|X_{t-1}^{(k_j)})`` with
weight ``r(Y_t|X_t^{(j)}) / r(Y_t|mu_{k_j})``.
"""

from __future__ import annotations

import numpy as np

from ..particles import ParticleSet, checked_weights, normalized_weights
from ..models.protocol import PredictMean, StateSpaceModel, offers
from .base import ParticleFilter

__all__ = ["AVPF"]


class AVPF(ParticleFilter):
    """Auxiliary variable particle filter.

    Parameters
    ----------
    first_stage : int or None
        Number ``M`` of first-stage candidates (``M >= N``); ``None`` uses ``N``.
        Candidate ``i`` descends from particle ``i mod N``.
    point : {"mean", "sample"}
        ``mu_i`` is the mean of ``K`` (``model.predict_mean``) or a draw from it.
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

    def step(self, particles, obs, rng):
        n = particles.n
        m = n if self.first_stage is None else max(int(self.first_stage), n)
        parent = np.arange(m) % n
        prev = particles.states[parent]
        if self.point == "mean":
            mu = self.model.predict_mean(prev)
        else:
            mu = self.model.predict(prev, rng)
        loglik_mu = self.model.loglik(obs, mu)
        lam = normalized_weights(particles.log_weights[parent] + loglik_mu)
        if lam is None:  # first stage carries no information: fall back to the weights
            lam = normalized_weights(particles.log_weights[parent])
            loglik_mu = np.zeros(m)
        k = self.resample_scheme(lam, n, rng)
        x = self.model.predict(prev[k], rng)
        ll = self.model.loglik(obs, x)
        log_w, degenerate = checked_weights(ll - loglik_mu[k], self.name)
        return ParticleSet(x, log_w, degenerate, None if degenerate else ll)
