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
"""

from __future__ import annotations

from .kernel import PriorKernel, Transition, is_prior

__all__ = ["IndependentTargets", "TargetProposal"]


class IndependentTargets:
    """:class:`~vistrack.models.protocol.Partitions` of independent targets (module docstring).

    The mixing class supplies ``partitions``, ``target_model(j)`` and ``target_obs(obs, j)``;
    target ``j``'s model sees ``states[:, partitions[j]]`` and ``target_obs(obs, j)``.
    """

    #: ``log r = Σ_j log π_j``: independent targets observed apart
    factorised_likelihood = True

    def _target(self, states, j):
        return self.target_model(j), states[:, self.partitions[j]]

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
