"""The shared step of the history-sampling family (thesis 001, §3.2, Figs. 3.2, 3.4, 3.5, 3.7).

Under Assumptions 3.2.1-3.2.3 the state is an innovation ``X_{t,1}`` and a history
``X_{t,2} = f(X_{t-1})``, the proposal ``π(X_{t,1a} | Y_t)`` looks at the image only and
``r`` depends on the innovation only (:class:`~vistrack.models.protocol.InnovationSplit`).
The innovations are drawn first; what differs between the algorithms is which history each
innovation is joined to and how it is weighted. Every algorithm here:

1. resamples ``(X_{t-1}, w_{t-1})`` by the filter's policy (ESS threshold, scheme, birth
   reserve; HS-SIR: never, its pair draw is its resampling) and groups the result into
   the ``C`` distinct histories ``X̂^{(l)}`` with their summed weights ``ŵ_l``
   (:class:`Histories`), so that the ``O(C·N)`` kernel evaluations are one array
   operation over the ``(N, C)`` pairs, in log space;
2. draws innovations from the model's ``innovation_proposal`` and joins them to histories;
3. weights them; the first step is the same step with ``p_0`` in the place of ``K``
   (one history, :mod:`vistrack.core.transition`).

Weights keep the convention of the other filters: after a step, ``Σ_k w_k h(X_k)`` is an
unbiased estimate of ``∫ h r K p(X_{t-1} | Y_{0:t-1})`` times the previous weights' sum.

History indices are drawn from each innovation's row of the ``(N, C)`` law by inverse CDF
with the uniforms of the filter's resampling scheme (§3.2.2: the low-variance schemes adapt
directly): ``multinomial`` draws them i.i.d.; ``stratified`` / ``systematic`` take
``(σ(k) + U_k) / N`` / ``(σ(k) + U) / N`` with ``σ`` a random permutation, so each row's
draw has the exact law and rows with similar laws spread over it as a resampling would
(``residual`` and custom schemes: stratified).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.particles import ParticleSet, checked_weights, logsumexp
from ..core.resampling import multinomial, systematic
from ..models.protocol import InnovationSplit, StateSpaceModel
from .base import ParticleFilter

__all__ = ["HistorySampling", "Histories", "associate", "draw_rows", "row_uniforms"]


@dataclass
class Histories:
    """The distinct histories of a step.

    Attributes
    ----------
    states : ndarray (C, d)
        The distinct ``X̂_{t-1}^{(l)}`` (on the first step one dummy state: ``p_0`` ignores it).
    log_w : ndarray (C,)
        ``log ŵ_l``: the summed weights of each one's copies.
    member : ndarray (N,)
        The history of the ``k``-th resampled particle (an index into ``states``).
    member_log_w : ndarray (N,)
        The ``k``-th resampled particle's own log-weight.
    """

    states: np.ndarray
    log_w: np.ndarray
    member: np.ndarray
    member_log_w: np.ndarray

    @classmethod
    def group(cls, states, idx, log_w):
        """Histories of the resampled particles ``states[idx]`` with log-weights ``log_w``."""
        uniq, member = np.unique(idx, return_inverse=True)
        m = np.max(log_w)
        with np.errstate(divide="ignore"):
            group_w = np.log(np.bincount(member, weights=np.exp(log_w - m), minlength=len(uniq))) + m
        return cls(states[uniq], group_w, member, log_w)


def row_uniforms(scheme, n, rng):
    """``n`` uniforms in ``[0, 1)``, each marginally uniform, coupled as ``scheme``'s (module docstring)."""
    if scheme is multinomial:
        return rng.random(n)
    perm = rng.permutation(n)
    return (perm + (rng.random() if scheme is systematic else rng.random(n))) / n


def draw_rows(log_p, rng, scheme=systematic, u=None):
    """One column per row of ``log_p (N, C)``, drawn ∝ ``exp(log_p)`` by inverse CDF with
    :func:`row_uniforms` (or the given uniforms ``u (N,)``); a row without a positive entry
    gets column 0."""
    m = np.max(log_p, axis=1, keepdims=True)
    p = np.exp(log_p - np.where(np.isfinite(m), m, 0.0))
    cdf = np.cumsum(p, axis=1)
    u = row_uniforms(scheme, len(p), rng) if u is None else u
    return np.minimum(np.sum(cdf <= (u * cdf[:, -1])[:, None], axis=1), p.shape[1] - 1)


def associate(law, n, c, rng, scheme, budget=1 << 21):
    """History indices ``(N,)`` drawn from the rows of the ``(N, C)`` law and the rows' log-sums
    ``(N,)``; ``law(rows) -> (len(rows), C)`` is evaluated in blocks of about ``budget`` pairs,
    so memory stays bounded (the draws do not depend on the blocks)."""
    u = row_uniforms(scheme, n, rng)
    idx, log_sum = np.empty(n, np.intp), np.empty(n)
    for rows in row_blocks(n, c, budget):
        block = law(rows)
        log_sum[rows] = logsumexp(block, axis=1)
        idx[rows] = draw_rows(block, rng, u=u[rows])
    return idx, log_sum


def row_blocks(n, c, budget=1 << 21):
    """Slices of ``n`` rows with about ``budget`` of the ``(N, C)`` pairs each."""
    step = max(1, budget // max(c, 1))
    return [slice(start, min(n, start + step)) for start in range(0, n, step)]


class HistorySampling(ParticleFilter):
    """Base of ``basic-sir``, ``hs-sir``, ``rb-hs-sir`` and ``rb-ss-hs-sir`` (module docstring).

    Parameters
    ----------
    model : InnovationSplit
    proposal : object or None
        ``π(X_{t,1a} | Y_t)``: ``sample(n, obs, rng) -> (n, subspace_dim)`` and
        ``logpdf(x1a, obs) -> (n,)``; ``None`` asks the model (``model.innovation_proposal``,
        e.g. the colour blob of §3.2.5).
    **kwargs
        ``resample``, ``ess_threshold``, ``birth_reserve`` (:class:`ParticleFilter`).
    """

    needs = (StateSpaceModel, InnovationSplit)
    model_parts = {"proposal": (InnovationSplit, "innovation_proposal")}
    #: whether the step starts by resampling by the policy (HS-SIR's pair draw resamples instead)
    resamples_first = True

    def __init__(self, model, proposal=None, **kwargs):
        super().__init__(model, **kwargs)
        self._set_part("proposal", proposal)
        self.a, self.k = int(model.subspace_dim), int(model.innovation_dim)

    def histories(self, particles, rng, kernel):
        """The step's :class:`Histories` (one on the first step)."""
        if kernel.first:
            n = particles.n
            return Histories(particles.states[:1], np.array([logsumexp(particles.log_weights)]), np.zeros(n, int),
                             particles.log_weights)
        if self.resamples_first:
            idx, log_w = self.resampler(particles, rng)
        else:
            idx, log_w = np.arange(particles.n), particles.log_weights
        return Histories.group(particles.states, idx, log_w)

    def innovations(self, hist, obs, rng, kernel):
        """``N`` whole innovations ``x1 (N, n1)`` and ``log π(x1) (N,)``: ``x_1a`` from the
        image-only proposal and, where the model has a ``1b`` part, ``x_1b`` from the predictive
        mixture ``Σ_l ŵ_l K_1b(. | x_1a, X̂^{(l)}) / Σ ŵ`` (it depends on the previous set as a
        whole, not on the history an innovation will take, so the §3.2 arguments hold)."""
        n = len(hist.member)
        x1a, log_pi = self._proposed(n, obs, rng)
        if self.k == self.a:
            return x1a, log_pi
        cdf = np.cumsum(np.exp(hist.log_w - np.max(hist.log_w)))
        u = row_uniforms(self.resampler.scheme, n, rng) * cdf[-1]
        src = hist.states[np.minimum(np.searchsorted(cdf, u, side="right"), len(cdf) - 1)]
        x1b = kernel.sample_rest(x1a, src, rng)
        mix = np.empty(n)
        for rows in row_blocks(n, len(hist.log_w)):
            k1b = kernel.rest_logpdf(x1b[rows, None], x1a[rows, None], hist.states[None])
            mix[rows] = logsumexp(hist.log_w + k1b, axis=1)
        return np.concatenate([x1a, x1b], axis=1), log_pi + mix - logsumexp(hist.log_w)

    def _proposed(self, n, obs, rng):
        """``n`` draws ``x_1a`` of the image-only proposal and their ``log π``."""
        proposal = self.part("proposal", self.kernel)
        x1a = proposal.sample(n, obs, rng)
        return x1a, proposal.logpdf(x1a, obs)

    def pair_logpdf(self, x1, hist, kernel):
        """``log K_1(x1^{(k)} | X̂^{(l)})`` for every pair, ``(N, C)``; ``x1`` may hold ``x_1a``
        only (``log K_1a``)."""
        x1a, prev = x1[:, None, :self.a], hist.states[None]
        out = kernel.subspace_logpdf(x1a, prev)
        if x1.shape[1] > self.a:
            out = out + kernel.rest_logpdf(x1[:, None, self.a:], x1a, prev)
        return out

    def sample(self, hist, obs, rng, kernel):
        """``(new (N, d), log_w (N,), loglik (N,))``: the algorithm's part of the step."""
        raise NotImplementedError

    def _update(self, particles, obs, rng, kernel):
        hist = self.histories(particles, rng, kernel)
        new, log_w, loglik = self.sample(hist, obs, rng, kernel)
        log_w, degenerate = checked_weights(log_w, self.name)
        if degenerate:
            new, loglik = kernel.predict(hist.states[hist.member], rng), None
        return ParticleSet(new, log_w, degenerate, loglik)

    def _loglik(self, obs, x1, hist, kernel):
        """``log r(Y_t | x1)`` of innovations (Assumption 3.2.3: the history does not enter)."""
        return self.model.loglik(obs, kernel.join(x1, hist.states[np.zeros(len(x1), int)]))
