"""Branched partitioned sampling (thesis 001 App. C, Fig. C.2; MacCormick).

Partitioned sampling (:mod:`~vistrack.filters.partitioned`) impoverishes the partitions it
draws first: every later resampling thins them. Branched partitioning gives the particles
different orderings ``σ`` of the partitions, so that every partition is drawn last by some
of them: after the step's resampling each particle draws an ordering, the particles with
the same ordering (``H_σ``) sample the partitions in that order, the weighted resampling
between stages runs over all ``N`` particles (an offspring keeps its parent's ordering) and
the orderings are joined at the weight normalisation (:mod:`~vistrack.filters.partition_step`).

The orderings are the ``τ`` cyclic shifts ``(s, s+1, ..., τ-1, 0, ..., s-1)`` of the model's
order unless given (e.g. only those that respect an occlusion order, App. C); each must
satisfy eq. C.2. They are drawn balanced: a uniformly random permutation of the particles is
cut into as many consecutive blocks as there are orderings, of sizes ``⌈N/S⌉`` then ``⌊N/S⌋``
(``numpy.array_split``), and block ``s`` takes ordering ``s``, so every ordering starts with
about ``N/S`` particles.
``branched-partitioned-lis`` moves each partition by its LIS proposal.

All groups at once. Where the model draws and weighs one partition per particle in one call
(:class:`~vistrack.models.partitions.StackedPartitions`, e.g. bearings) and no local proposal
is used, stage ``k`` of a step draws partition ``σ_i(k)`` of every particle ``i`` in one model
call and resamples every group within itself in one call (:func:`~vistrack.core.resampling.grouped`,
each group with its own ESS test and total weight): the same draws, in distribution, as the
groups one after the other, at the cost of partitioned sampling (``τ`` model calls and ``τ - 1``
resamplings per step, not ``S τ`` and ``S (τ - 1)``). The particles come back sorted by group.
"""

from __future__ import annotations

import numpy as np

from ..core.resampling import Groups, grouped, needs_resampling
from ..models.partitions import StackedPartitions
from .partition_step import PartitionedBase, PartitionedLISMixin
from .resampler import BirthReserve

__all__ = ["BranchedPartitioned", "BranchedPartitionedLIS", "cyclic_orderings"]


def cyclic_orderings(tau):
    """The ``τ`` cyclic shifts of ``0..τ-1``: every partition comes last in exactly one."""
    return [tuple((s + k) % tau for k in range(tau)) for s in range(tau)]


class BranchedPartitioned(PartitionedBase):
    """Fig. C.2: groups of particles sample the partitions in different orders.

    Parameters
    ----------
    orderings : sequence of sequences of int, optional
        The orderings ``σ`` (permutations of ``0..τ-1``); default :func:`cyclic_orderings`.
    **kwargs
        As :class:`~vistrack.filters.base.ParticleFilter`.
    """

    name = "branched-partitioned"

    def __init__(self, model, orderings=None, **kwargs):
        super().__init__(model, **kwargs)
        orderings = cyclic_orderings(self.tau) if orderings is None else [tuple(int(j) for j in o) for o in orderings]
        for o in orderings:
            if sorted(o) != list(range(self.tau)):
                raise ValueError(f"ordering {list(o)} is not a permutation of the partitions 0..{self.tau - 1}")
        if not orderings:
            raise ValueError("branched partitioning needs at least one ordering")
        self.orderings = orderings

    def assign(self, n, rng):
        """The ordering of each of ``n`` particles, ``(n,)``: a random permutation of the particles
        cut into one block per ordering (sizes ``⌈n/S⌉`` then ``⌊n/S⌋``)."""
        labels = np.empty(n, dtype=np.intp)
        for s, rows in enumerate(np.array_split(rng.permutation(n), len(self.orderings))):
            labels[rows] = s
        return labels

    def _partitions(self, prev, log_w, obs, rng, kernel):
        """Fig. C.2 with every group at once (module docstring) where the model stacks its
        partitions and no local proposal is used; else the groups one after the other."""
        m, n = self.model, len(prev)
        if self.local is not None or not isinstance(m, StackedPartitions):
            return super()._partitions(prev, log_w, obs, rng, kernel)
        labels = self.assign(n, rng)
        order = np.argsort(labels, kind="stable")
        x, log_w, labels = prev[order], log_w[order], labels[order]
        sizes = np.bincount(labels, minlength=len(self.orderings))
        groups = Groups(sizes[sizes > 0])
        sigma, rows = np.asarray(self.orderings)[labels], np.arange(n)
        lam = np.zeros((n, self.tau))
        for k in range(self.tau):
            if k > 0:
                idx, log_w = self._resample_groups(x, log_w, groups, rng)
                x, lam = x[idx], lam[idx]
            parts = sigma[:, k]
            draw = m.sample_prior_parts(x, parts, rng) if kernel.first else m.predict_parts(x, parts, rng)
            m.scatter_parts(x, parts, draw)
            lam[rows, parts] = incr = m.loglik_parts(obs, draw, x, parts)
            log_w = log_w + incr
        return x, log_w, lam

    def _resample_groups(self, x, log_w, groups, rng):
        """Ancestors ``(n,)`` and offspring log-weights ``(n,)`` of the :class:`~vistrack.core.resampling.Groups`
        of ``x (n, d)``, each resampled within itself as :meth:`_resample` would (its ESS test;
        the offspring share the group's total weight), in one call where the scheme has a
        grouped form (:func:`~vistrack.core.resampling.grouped`)."""
        starts, of, sizes = groups.starts, groups.of, groups.sizes
        top = np.maximum.reduceat(log_w, starts)
        live = np.isfinite(top)
        w = np.exp(log_w - np.where(live, top, 0.0)[of])
        if not live.all():
            w[~live[of]] = 1.0
        total = np.add.reduceat(w, starts)
        w /= total[of]
        redo = live & needs_resampling(1.0 / np.add.reduceat(w * w, starts), sizes, self.ess_threshold)
        idx = None if isinstance(self.resampler, BirthReserve) else grouped(self.resample_scheme, w, groups, rng)
        if idx is None:  # no grouped form: one group after the other
            out = [self._resample(x[a:a + s], log_w[a:a + s], rng) for a, s in zip(starts, sizes)]
            return np.concatenate([i + a for (i, _), a in zip(out, starts)]), np.concatenate([lw for _, lw in out])
        with np.errstate(divide="ignore"):
            shared = (top + np.log(total) - np.log(sizes))[of]
        if redo.all():
            return idx, shared
        return np.where(redo[of], idx, np.arange(len(of))), np.where(redo[of], shared, log_w)


class BranchedPartitionedLIS(PartitionedLISMixin, BranchedPartitioned):
    """Fig. C.2 with LIS (Prop. 4.5.1) within each partition."""

    name = "branched-partitioned-lis"
