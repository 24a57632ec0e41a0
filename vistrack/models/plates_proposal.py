"""LIS proposals of the multi-plate model (:class:`~vistrack.models.plates.Plates`): the single
plate's §4.5.2 proposal (:class:`~vistrack.models.plate_proposal.PlateLISProposal`) on one slot —
a partition of partitioned sampling (thesis App. C: "combined with LLS or LIS") — or on every
slot at once (joint LIS)."""

from __future__ import annotations

import numpy as np

from .kernel import PriorKernel, Transition, is_prior
from .plate_proposal import PlateLISProposal

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
        """Draw ``z (N, 10K)`` from the predictions ``x (N, 10K)``, moving slot ``j`` only.

        Returns ``(z, log_alpha (N,), log_q (N,))`` as LIS's proposals do (``prev``: the resampled
        ``Z_{t-1}``, centring the dynamics window)."""
        m, j = self.model, self.j
        z = x.copy()
        log_alpha, log_q = np.zeros(len(x)), np.zeros(len(x))
        pres = np.flatnonzero(m.present(x, j))
        if len(pres):
            cols = m.cols(j)
            ps = None if prev is None else prev[pres, cols]
            zs, la, lq = self.inner.sample(x[pres, cols], obs, rng, ps)
            z[pres, cols] = zs
            log_alpha[pres], log_q[pres] = la, lq
        return z, log_alpha, log_q


class JointLISProposal:
    """LIS's local proposal for every slot at once (joint LIS, no resampling between slots): the
    slots' :class:`SlotLISProposal` in turn, their ``log α`` and ``log q`` summed (each moves its
    own slot and ``q`` factorises over them)."""

    def __init__(self, model, kernel=None, **params):
        self.slots = [SlotLISProposal(model, j, kernel, **params) for j in range(model.k)]

    def sample(self, x, obs, rng, prev=None):
        """Draw ``z (N, 10K)`` about ``x (N, 10K)``; returns ``(z, log_alpha, log_q)``."""
        log_alpha, log_q = np.zeros(len(x)), np.zeros(len(x))
        for p in self.slots:
            x, la, lq = p.sample(x, obs, rng, prev)
            log_alpha += la
            log_q += lq
        return x, log_alpha, log_q
