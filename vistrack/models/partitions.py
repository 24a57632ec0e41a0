"""Partitions of a model of independent targets (thesis 001 App. C, eq. C.2).

When ``M`` targets move independently and each is observed apart, the joint state is the
product of the targets' states: partition ``j`` is target ``j``'s columns, ``K_j`` its own
dynamics, ``π_j`` its own likelihood factor, and ``r = Π_j π_j`` (the final weights reuse
the ``l_{t,j}``, Fig. C.1's note). :class:`IndependentTargets` implements
:class:`~vistrack.models.protocol.Partitions` and
:class:`~vistrack.models.protocol.PartitionLIS` from a one-target model per partition: a
model mixes it in and supplies ``partitions`` (the columns of each target),
``target_model(j)`` (a state-space model of target ``j`` alone) and ``target_obs(obs, j)``
(the part of ``Y_t`` that observes it). The bearings model (one partition per ship) is one.

:class:`StackedPartitions` is the optional form in which every particle draws and weighs its
own partition in one call (a partition index per particle), for branched partitioning's
stages over all its groups at once (:mod:`~vistrack.filters.branched_partitioned`).
"""

from __future__ import annotations

from functools import cached_property
from typing import Protocol, runtime_checkable

import numpy as np

from ..core.transition import PriorKernel, Transition, is_prior

__all__ = ["IndependentTargets", "StackedPartitions", "TargetProposal"]


@runtime_checkable
class StackedPartitions(Protocol):
    """Partitions of equal width ``w`` drawn and weighed with one partition per particle.

    ``parts (N,)`` holds each particle's partition ``j_i``; the methods equal
    :class:`~vistrack.models.protocol.Partitions`' ``sample_prior_part``, ``predict_part`` and
    ``loglik_part`` applied to row ``i`` with ``j = j_i`` (the same distributions, in one call).
    :class:`IndependentTargets` supplies :meth:`scatter_parts` (and ``gather_parts``).
    """

    def sample_prior_parts(self, states, parts, rng):
        """Row ``i``'s partition ``parts[i]`` drawn from ``p_0``'s factor, ``(N, w)``."""

    def predict_parts(self, states, parts, rng):
        """Row ``i``'s partition ``parts[i]`` drawn from ``K_j(.|states[i])``, ``(N, w)``."""

    def loglik_parts(self, obs, values, states, parts):
        """``log π_{parts[i]}`` of row ``i`` of ``states (N, d)``, ``(N,)``; ``values (N, w)`` is
        row ``i``'s partition ``parts[i]`` (already in ``states``)."""

    def scatter_parts(self, states, parts, values):
        """Write ``values (N, w)`` into row ``i``'s partition ``parts[i]`` of ``states (N, d)``."""


class IndependentTargets:
    """:class:`~vistrack.models.protocol.Partitions` of independent targets (module docstring).

    The mixing class supplies ``partitions``, ``target_model(j)`` and ``target_obs(obs, j)``;
    target ``j``'s model sees ``states[:, partitions[j]]`` and ``target_obs(obs, j)``.
    """

    #: ``log r = Σ_j log π_j``: independent targets observed apart
    factorised_likelihood = True

    def _target(self, states, j):
        return self.target_model(j), states[:, self.partitions[j]]

    @cached_property
    def part_columns(self):
        """``(τ, w)``: the columns of every partition, stacked (equal widths only)."""
        return np.stack(self.partitions)

    @cached_property
    def _consecutive_parts(self):
        cols = self.part_columns
        return np.array_equal(cols.ravel(), np.arange(cols.size))

    def gather_parts(self, states, parts):
        """Row ``i``'s partition ``parts[i]`` of ``states (N, d)``, ``(N, w)``."""
        rows = np.arange(len(states))
        if self._consecutive_parts:  # partition j is columns j w .. (j + 1) w - 1
            return states.reshape(len(states), *self.part_columns.shape)[rows, parts]
        return states[rows[:, None], self.part_columns[parts]]

    def scatter_parts(self, states, parts, values):
        """Write ``values (N, w)`` into row ``i``'s partition ``parts[i]`` of ``states (N, d)``."""
        rows = np.arange(len(states))
        if self._consecutive_parts and states.flags.c_contiguous:
            states.reshape(len(states), *self.part_columns.shape)[rows, parts] = values
        else:
            states[rows[:, None], self.part_columns[parts]] = values

    def predict_part(self, states, j, rng):
        """Target ``j``'s dynamics from its columns of ``states (N, d)`` -> ``(N, d_j)``."""
        model, x = self._target(states, j)
        return model.predict(x, rng)

    def part_logpdf(self, new, states, j):
        """``log K_j(new (N, d_j) | states (N, d))`` -> ``(N,)``: target ``j``'s transition density."""
        model, x = self._target(states, j)
        return model.transition_logpdf(new, x)

    def sample_prior_part(self, states, j, rng):
        """Target ``j``'s prior, ``(N, d_j)`` (one row per row of ``states``; independent of them)."""
        return self.target_model(j).sample_prior(len(states), rng)

    def prior_part_logpdf(self, new, states, j):
        """``log p_0`` of target ``j``'s ``new (N, d_j)`` -> ``(N,)``."""
        return self.target_model(j).prior_logpdf(new)

    def loglik_part(self, obs, states, j):
        """Target ``j``'s likelihood factor ``log r_j(Y_{t,j} | x_j)`` of ``states (N, d)`` -> ``(N,)``."""
        model, x = self._target(states, j)
        return model.loglik(self.target_obs(obs, j), x)

    def lis_part_proposal(self, j, kernel=None):
        """Target ``j``'s LIS proposal (its model's ``lis_proposal`` for the matching kernel) on
        partition ``j`` (:class:`TargetProposal`)."""
        model = self.target_model(j)
        inner = model.lis_proposal(PriorKernel(model) if is_prior(kernel) else Transition(model))
        return TargetProposal(inner, self.partitions[j], lambda obs: self.target_obs(obs, j))


class TargetProposal:
    """A one-target local proposal acting on its partition of the joint state.

    Parameters
    ----------
    inner : object
        The target's proposal, ``sample(x (N, d_j), obs_j, rng, prev (N, d_j)) -> (z, log_alpha, log_q)``.
    cols : int array
        The partition's columns.
    obs_of : callable
        ``obs_of(obs)``: the target's part of the observation.
    """

    def __init__(self, inner, cols, obs_of):
        self.inner, self.cols, self.obs_of = inner, cols, obs_of

    def sample(self, x, obs, rng, prev):
        """``(z (N, d_j), log_alpha (N,), log_q (N,))`` about partition ``j`` of ``x (N, d)``
        (``prev (N, d_j)``: the partition before it was predicted)."""
        return self.inner.sample(x[:, self.cols], self.obs_of(obs), rng, prev)
