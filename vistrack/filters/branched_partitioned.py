"""Branched partitioned sampling (thesis 001 App. C, Fig. C.2; MacCormick).

Partitioned sampling (:mod:`~vistrack.filters.partitioned`) impoverishes the partitions it
draws first: every later resampling thins them. Branched partitioning gives the particles
different orderings ``σ`` of the partitions, so that every partition is drawn last by some
of them: after the step's resampling each particle draws an ordering, the particles with
the same ordering (``H_σ``) sample the partitions in that order, the weighted resampling
between stages runs over all ``N`` particles (an offspring keeps its parent's ordering) and
the orderings are joined at the weight normalisation (:mod:`~vistrack.filters.partitioning`).

The orderings are the ``τ`` cyclic shifts ``(s, s+1, ..., τ-1, 0, ..., s-1)`` of the model's
order unless given (e.g. only those that respect an occlusion order, App. C); each must
satisfy eq. C.2. They are drawn balanced: a uniformly random permutation of the particles is
cut into as many consecutive blocks as there are orderings, of sizes ``⌈N/S⌉`` then ``⌊N/S⌋``
(``numpy.array_split``), and block ``s`` takes ordering ``s``, so every ordering starts with
about ``N/S`` particles.
``branched-partitioned-lis`` moves each partition by its LIS proposal.
"""

from __future__ import annotations

import numpy as np

from .partitioning import PartitionedBase, PartitionedLISMixin

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


class BranchedPartitionedLIS(PartitionedLISMixin, BranchedPartitioned):
    """Fig. C.2 with LIS (Prop. 4.5.1) within each partition."""

    name = "branched-partitioned-lis"
