"""The kernel a filter step predicts with (thesis 001, §2.1; Figs. 2.3, 4.11, 4.13).

Every step moves the particles by the model's Markov kernel ``K(.|Z_{t-1})``,
except the first: there ``Y_1`` observes ``X_1 ~ p_0``, and every algorithm's
first update is its ordinary step with ``p_0`` in the place of ``K`` (the
figures start from ``p_0``). :class:`Transition` is ``K``;
:class:`PriorKernel` is ``p_0`` seen as a kernel that ignores the previous
state. A filter hands the step's kernel to its proposal, and the model parts
whose spread follows the kernel's (the LIS and LLS windows, §4.4.1: ``g``
matched to the spread of ``K``) are built per kernel
(``model.lis_proposal(kernel)``, ``model.lls_window(kernel)``). The history-sampling
filters (§3.2) read ``K_1 = K_1b K_1a`` and the history through the kernel too, so their
first step is their ordinary step with ``p_0``'s split
(:class:`~vistrack.models.protocol.InnovationSplit`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["Transition", "PriorKernel", "is_prior"]


class Transition:
    """``K(x_t | x_{t-1})`` of ``model``: the kernel of every step after the first.

    Parameters
    ----------
    model : StateSpaceModel
        Supplies ``predict``, ``transition_logpdf`` and, where used,
        ``predict_mean`` and ``with_local``.
    """

    #: whether this is ``p_0`` (the first step) rather than ``K``
    first = False

    def __init__(self, model):
        self.model = model

    def predict(self, prev, rng):
        """Draw ``X_t ~ K(.|prev)``; ``prev (N, d)`` -> ``(N, d)``."""
        return self.model.predict(prev, rng)

    def predict_mean(self, prev):
        """The mean of ``K(.|prev)``, ``(N, d)`` (AVPF's first stage, §4.5.4)."""
        return self.model.predict_mean(prev)

    def logpdf(self, new, old):
        """``log K(new|old)`` per particle; ``new, old (N, d)`` -> ``(N,)``."""
        return self.model.transition_logpdf(new, old)

    def with_local(self, states, u):
        """``states (N, d)`` with their local coordinates set to ``u (N, m)`` (§4.4.3)."""
        return self.model.with_local(states, u)

    # -- the innovation/history split (§3.2); arrays broadcast over leading axes ----------
    def subspace_logpdf(self, x1a, prev):
        """``log K_1a(x1a | prev)``."""
        return self.model.subspace_logpdf(x1a, prev)

    def rest_logpdf(self, x1b, x1a, prev):
        """``log K_1b(x1b | x1a, prev)``."""
        return self.model.rest_logpdf(x1b, x1a, prev)

    def sample_rest(self, x1a, prev, rng):
        """A draw ``x1b ~ K_1b(. | x1a, prev)``."""
        return self.model.sample_rest(x1a, prev, rng)

    def join(self, x1, prev):
        """The new states ``(x1, f(prev))`` of innovations ``x1 (N, n1)`` and histories ``prev (N, d)``."""
        return np.concatenate([x1, self.model.history(prev)], axis=-1)


class PriorKernel(Transition):
    """``p_0`` in the place of ``K``: the kernel of the first step.

    ``predict`` draws from ``p_0`` whatever the previous state, ``logpdf`` is
    ``log p_0(new)``, and local moves use ``model.with_local_prior`` (a move
    that need not keep the support of ``K``, e.g. both poses of an AR(2)
    state at once).
    """

    first = True

    def predict(self, prev, rng):
        """Draw ``X_1 ~ p_0``, one per row of ``prev (N, d)`` (only its length is used) -> ``(N, d)``."""
        return self.model.sample_prior(len(prev), rng)

    def predict_mean(self, prev):
        """The mean of ``p_0`` (``model.prior_mean``) per row of ``prev (N, d)`` -> ``(N, d)``."""
        return np.broadcast_to(self.model.prior_mean, prev.shape).copy()

    def logpdf(self, new, old):
        """``log p_0(new)`` per row, ``(N,)``; ``old`` is ignored."""
        return self.model.prior_logpdf(new)

    def with_local(self, states, u):
        """``model.with_local_prior``: ``states (N, d)`` with local coordinates ``u (N, m)`` on a prior draw."""
        return self.model.with_local_prior(states, u)

    @staticmethod
    def _over(value, prev):
        return np.broadcast_to(value, np.broadcast_shapes(np.shape(value), np.shape(prev)[:-1]))

    def subspace_logpdf(self, x1a, prev):
        """``log p_0`` of ``x1a`` whatever ``prev`` (broadcast to the pairs)."""
        return self._over(self.model.prior_subspace_logpdf(x1a), prev)

    def rest_logpdf(self, x1b, x1a, prev):
        """``log p_0`` of ``x1b`` given ``x1a`` whatever ``prev`` (broadcast to the pairs)."""
        return self._over(self.model.prior_rest_logpdf(x1b, x1a), prev)

    def sample_rest(self, x1a, prev, rng):
        """A draw of ``x1b`` from ``p_0`` given ``x1a``."""
        return self.model.sample_prior_rest(x1a, rng)

    def join(self, x1, prev):
        """The state ``(N, d)`` of innovation ``x1`` with the history ``p_0`` gives it."""
        return self.model.join_prior(x1)


def is_prior(kernel):
    """Whether ``kernel`` is the first step's ``p_0`` (``None`` means ``K``)."""
    return kernel is not None and kernel.first
