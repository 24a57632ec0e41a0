"""Partitioned sampling (thesis 001 App. C, Fig. C.1; MacCormick and Blake).

The partitions of the state (:class:`~vistrack.models.protocol.Partitions`) are drawn in
the model's order ``1..τ``: partition ``j`` from ``K_j``, weighted by its importance function
``π_j`` (for independent targets, target ``j``'s likelihood factor), and the particles are
resampled by these weights before partition ``j + 1`` is drawn, so that the later
partitions are drawn from particles whose earlier partitions fit ``Y_t``. The weights and
the resampling are those of :mod:`~vistrack.filters.partition_step`. The partitions drawn
first go through the most resamplings and lose their diversity (App. C's impoverishment);
:mod:`~vistrack.filters.branched_partitioned` varies the order between particles.
``partitioned-lis`` moves each partition by its LIS proposal (App. C's closing remark).
"""

from __future__ import annotations

from .partition_step import PartitionedBase, PartitionedLISMixin

__all__ = ["Partitioned", "PartitionedLIS"]


class Partitioned(PartitionedBase):
    """Fig. C.1: every particle samples the partitions in the model's order (:attr:`orderings`:
    ``[(0, 1, ..., τ-1)]``)."""

    name = "partitioned"


class PartitionedLIS(PartitionedLISMixin, Partitioned):
    """Fig. C.1 with LIS (Prop. 4.5.1) within each partition."""

    name = "partitioned-lis"
