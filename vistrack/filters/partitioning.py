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
step returns the weighted set (its mean has no resampling noise). Resampling keeps a group's
total weight (the offspring share it), so groups resampled apart (the branches of
:mod:`~vistrack.filters.branched_partitioned`) are joined at the normalisation, and the
unnormalised weights stay unbiased for ``p(Y_t | Y_{1:t-1})``. Every resampling uses the
filter's resampler (its scheme and ESS policy).
"""

from __future__ import annotations

import numpy as np

from ..models.protocol import PartitionLIS, Partitions, StateSpaceModel
from ..particles import ParticleSet, checked_weights, logsumexp
from .base import ParticleFilter

__all__ = ["PartitionedBase"]


class PartitionedBase(ParticleFilter):
    """Partitioned sampling's step; subclasses say which particles sample the partitions in
    which order (:meth:`groups`). ``local = "lis"`` moves each partition by its LIS proposal."""

    needs = (StateSpaceModel, Partitions)
    #: ``None``: draw each partition from ``K_j``; ``"lis"``: LIS within each partition
    local = None

    def __init__(self, model, **kwargs):
        super().__init__(model, **kwargs)
        self.tau = len(model.partitions)
        self._proposals = {}

    def groups(self, n, rng):
        """``[(rows, order), ...]``: which particles (rows of the resampled set, int arrays
        covering ``0..n-1`` once) sample the partitions in which order (a permutation of
        ``0..τ-1``)."""
        raise NotImplementedError

    def _update(self, particles, obs, rng, kernel):
        idx, log_w = self._ancestors(particles, obs, rng, kernel)
        prev = particles.states[idx]
        new = prev.copy()
        log_w = np.array(log_w, dtype=float)
        lam = np.zeros((len(prev), self.tau))
        for rows, order in self.groups(len(prev), rng):
            new[rows], log_w[rows], lam[rows] = self._chain(prev[rows], log_w[rows], order, obs, rng, kernel)
        if self.model.factorised_likelihood:
            loglik = lam.sum(axis=1)
        else:
            loglik = self.model.loglik(obs, new)
            with np.errstate(invalid="ignore"):
                log_w = log_w + loglik - lam.sum(axis=1)
        log_w, degenerate = checked_weights(log_w, self.name)
        if degenerate:
            new, loglik = kernel.predict(prev, rng), None
        return ParticleSet(new, log_w, degenerate, loglik)

    def _chain(self, x, log_w, order, obs, rng, kernel):
        """Sample the partitions of ``x (n, d)`` (rows holding ``X_{t-1}``) in ``order``,
        resampling before every partition after the first; returns ``(x_t (n, d), log_w (n,),
        λ (n, τ))`` with ``λ[:, j] = log π_j`` at the particle's partition ``j``."""
        x = x.copy()
        lam = np.zeros((len(x), self.tau))
        for k, j in enumerate(order):
            if k > 0:
                idx, log_w = self._resample(x, log_w, rng)
                x, lam = x[idx], lam[idx]
            incr, lam[:, j] = self._move(x, j, obs, rng, kernel)
            log_w = log_w + incr
        return x, log_w, lam

    def _resample(self, x, log_w, rng):
        """The resampler on ``(x, log_w)``; the offspring share the set's total weight."""
        total = logsumexp(log_w)
        if not np.isfinite(total):
            return np.arange(len(x)), log_w
        idx, lw = self.resampler(ParticleSet(x, log_w - total), rng)
        return idx, lw + total

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

