"""LIS proposals of the multi-plate model (:class:`~vistrack.models.plate.plates.Plates`): the single
plate's §4.5.2 proposal (:class:`~vistrack.models.plate.proposal.PlateLISProposal`) on one slot —
a partition of partitioned sampling (thesis App. C: "combined with LLS or LIS") — or on every
slot at once (joint LIS)."""

from __future__ import annotations

import numpy as np

from ...core.transition import PriorKernel, Transition, is_prior
from .proposal import PlateLISProposal

__all__ = ["SlotLISProposal", "JointLISProposal"]


class SlotLISProposal:
    """LIS's local proposal for slot ``j``: :class:`PlateLISProposal` on the slot's single-plate
    state where the slot is present (line scans about the AR(2) prediction for a tracked plate,
    the entering search for a birth), nothing where it is absent (``Z = X``, ``q = 1``: the weight
    is then the slot's likelihood factor, as bootstrap's).

    Parameters
    ----------
    model : Plates
    j : int
        The slot.
    kernel : Transition, PriorKernel or None
        The step's kernel (``None``: ``K``); the slot's proposal follows the single plate's
        ``K`` or ``p_0`` accordingly.
    **params
        :class:`PlateLISProposal`'s parameters.
    """

    def __init__(self, model, j, kernel=None, **params):
        self.model, self.j = model, int(j)
        plate_kernel = PriorKernel(model.plate) if is_prior(kernel) else Transition(model.plate)
        self.inner = PlateLISProposal(model.plate, kernel=plate_kernel, **params)

    def sample(self, x, obs, rng, prev=None):
        """Draw slot ``j`` ``z (N, 10)`` about the predictions ``x (N, 10K)``.

        Returns ``(z, log_alpha (N,), log_q (N,))`` as LIS's proposals do (``prev (N, 10)``: the
        slot before it was predicted, centring the dynamics window)."""
        m, j = self.model, self.j
        z = x[:, m.partitions[j]].copy()
        log_alpha, log_q = np.zeros(len(x)), np.zeros(len(x))
        pres = np.flatnonzero(z[:, 9] > 0.5)
        if len(pres):
            ps = None if prev is None else prev[pres, :9]
            z[pres, :9], log_alpha[pres], log_q[pres] = self.inner.sample(z[pres, :9], obs, rng, ps)
        return z, log_alpha, log_q


class JointLISProposal:
    """LIS's local proposal for every slot at once (joint LIS, no resampling between slots): the
    slots' :class:`SlotLISProposal` in turn, their ``log α`` and ``log q`` summed (each moves its
    own slot and ``q`` factorises over them)."""

    def __init__(self, model, kernel=None, **params):
        self.model = model
        self.slots = [SlotLISProposal(model, j, kernel, **params) for j in range(model.k)]

    def sample(self, x, obs, rng, prev=None):
        """Draw ``z (N, 10K)`` about ``x (N, 10K)`` (``prev (N, 10K)``: the resampled ``Z_{t-1}``);
        returns ``(z, log_alpha, log_q)``."""
        z = x.copy()
        log_alpha, log_q = np.zeros(len(x)), np.zeros(len(x))
        for cols, p in zip(self.model.partitions, self.slots):
            z[:, cols], la, lq = p.sample(x, obs, rng, None if prev is None else prev[:, cols])
            log_alpha += la
            log_q += lq
        return z, log_alpha, log_q
