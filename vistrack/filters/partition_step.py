"""The step shared by partitioned and branched partitioned sampling (thesis 001 App. C).

A model with partitions (:class:`~vistrack.models.protocol.Partitions`) builds ``X_t`` one
partition at a time (eq. C.2): partition ``j`` is drawn from ``K_j`` (``p_0``'s factor on
the first step) and weighted by ``l_{t,j} = π_j``, and the particles are resampled by these
weights before the next partition is drawn, so that the next partition is drawn from the
particles whose earlier partitions fit ``Y_t``. With LIS inside each partition (App. C's
closing remark, :class:`~vistrack.models.protocol.PartitionLIS`) partition ``j`` is moved by
its local proposal and weighted by Prop. 4.5.1's increment with ``K_j`` and ``π_j``.

Weights. Each partition multiplies the weights by its ``l_{t,j}`` (the SMC form of Fig. C.1's
weighted resampling: resampling ∝ ``w l`` leaves equal weights, where Fig. C.1 resamples ∝
``l`` and carries ``w / l``; both select the same particles when the weights entering a step
are equal, which they are for a factorised likelihood). After the last partition the weights
are multiplied by ``r(Y_t|X_t) / Π_j π_j``: ``1`` where the likelihood factorises
(``factorised_likelihood``: the ``l_{t,j}`` are reused and ``r`` is never evaluated).
Fig. C.1's resampling after the last partition is the next step's ordinary resampling, so a
step returns the weighted set (its mean has no resampling noise). Resampling keeps the total
weight (the offspring share it), so the unnormalised weights stay unbiased for
``p(Y_t | Y_{1:t-1})``; it uses the filter's resampler (its scheme and ESS policy).

Orderings (Fig. C.2). Every particle follows one ordering ``σ`` of the partitions (partitioned
sampling: all the model's order). The particles with the same ordering (a group ``H_σ``)
sample the partitions in that order, resampled within the group; a group keeps its total
weight through its resamplings, so after the last partition every group's weights are
proper for the posterior on the same scale, and the groups are joined at the normalisation.
"""

from __future__ import annotations

import numpy as np

from ..core.particles import ParticleSet, checked_weights
from ..core.resampling import needs_resampling
from ..models.protocol import PartitionLIS, Partitions, StateSpaceModel
from .base import ParticleFilter
from .resampler import BirthReserve

__all__ = ["PartitionedBase"]


class PartitionedBase(ParticleFilter):
    """Partitioned sampling's step; subclasses give the orderings (:attr:`orderings`) and which
    particle follows which (:meth:`assign`). ``local = "lis"`` moves each partition by its LIS
    proposal."""

    needs = (StateSpaceModel, Partitions)
    #: ``None``: draw each partition from ``K_j``; ``"lis"``: LIS within each partition
    local = None

    def __init__(self, model, **kwargs):
        super().__init__(model, **kwargs)
        self.tau = len(model.partitions)
        #: the orderings ``σ`` (permutations of ``0..τ-1``) the particles sample the partitions in
        self.orderings = [tuple(range(self.tau))]
        self._proposals = {}

    def assign(self, n, rng):
        """The ordering (an index into :attr:`orderings`) of each of ``n`` particles, ``(n,)``."""
        return np.zeros(n, dtype=np.intp)

    def _update(self, particles, obs, rng, kernel):
        idx, log_w = self._ancestors(particles, obs, rng, kernel)
        prev = particles.states[idx]
        x, log_w, lam = self._partitions(prev, np.array(log_w, dtype=float), obs, rng, kernel)
        if self.model.factorised_likelihood:
            loglik = lam.sum(axis=1)
        else:
            loglik = self.model.loglik(obs, x)
            with np.errstate(invalid="ignore"):
                log_w = log_w + loglik - lam.sum(axis=1)
        log_w, degenerate = checked_weights(log_w, self.name)
        if degenerate:
            x, loglik = kernel.predict(prev, rng), None
        return ParticleSet(x, log_w, degenerate, loglik)

    def _partitions(self, prev, log_w, obs, rng, kernel):
        """Sample the partitions of ``prev (n, d)`` (``X_{t-1}``): the particles of each ordering
        (a group ``H_σ``) in that order, resampled within the group before every partition
        after the first (Fig. C.2). Returns ``(X_t (n, d), log_w (n,), λ (n, τ))``,
        ``λ[:, j] = log π_j`` at the particle's partition ``j``."""
        x = prev.copy()
        lam = np.zeros((len(x), self.tau))
        labels = self.assign(len(x), rng)
        for g, order in enumerate(self.orderings):
            rows = slice(None) if len(self.orderings) == 1 else np.flatnonzero(labels == g)
            xs, lw, ls = x[rows], log_w[rows], lam[rows]
            for k, j in enumerate(order if len(xs) else ()):
                if k > 0:
                    idx, lw = self._resample(xs, lw, rng)
                    xs, ls = xs[idx], ls[idx]
                incr, ls[:, j] = self._move(xs, j, obs, rng, kernel)
                lw = lw + incr
            x[rows], log_w[rows], lam[rows] = xs, lw, ls
        return x, log_w, lam

    def _resample(self, x, log_w, rng):
        """Ancestors ``(n,)`` and offspring log-weights ``(n,)`` of the particles ``x (n, d)`` from
        the filter's resampler (its scheme, ESS policy and birth reserve); the offspring share
        the group's total weight."""
        n, top = len(log_w), np.max(log_w)
        if not np.isfinite(top):
            return np.arange(n), log_w
        w = np.exp(log_w - top)
        total = w.sum()
        w /= total
        if not needs_resampling(1.0 / np.dot(w, w), n, self.ess_threshold):
            return np.arange(n), log_w
        log_total = top + np.log(total)
        if isinstance(self.resampler, BirthReserve):
            idx, lw = self.resampler(ParticleSet(x, log_w - log_total), rng)
            return idx, lw + log_total
        return self.resample_scheme(w, n, rng), np.full(n, log_total - np.log(n))

    def _move(self, x, j, obs, rng, kernel):
        """Draw partition ``j`` of ``x (n, d)`` in place; returns ``(log weight increment (n,),
        log π_j (n,))``."""
        m, cols, first = self.model, self.model.partitions[j], kernel.first
        draw = m.sample_prior_part(x, j, rng) if first else m.predict_part(x, j, rng)
        if self.local is None:
            x[:, cols] = draw
            lam = m.loglik_part(obs, x, j)
            return lam, lam
        old = x[:, cols].copy()
        x[:, cols] = draw
        z, log_alpha, log_q = self._proposal(j, kernel).sample(x, obs, rng, old)
        x[:, cols] = old
        logpdf = m.prior_part_logpdf if first else m.part_logpdf
        k_ratio = logpdf(z, x, j) - logpdf(draw, x, j)
        x[:, cols] = z
        lam = m.loglik_part(obs, x, j)
        with np.errstate(invalid="ignore"):
            incr = np.where(np.isfinite(log_alpha), log_alpha + lam - log_q + k_ratio, -np.inf)
        return incr, lam

    def _proposal(self, j, kernel):
        key = (j, kernel.first)
        if key not in self._proposals:
            self._proposals[key] = self.model.lis_part_proposal(j, kernel)
        return self._proposals[key]


class PartitionedLISMixin:
    """LIS within each partition (App. C's closing remark): needs a local proposal per partition."""

    needs = (StateSpaceModel, Partitions, PartitionLIS)
    local = "lis"

