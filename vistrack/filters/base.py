"""The shared step of every particle filter (thesis 001, Figs. 2.3, 3.1, 4.11, 4.13).

A filter is ``step(particles, obs, rng) -> particles``. The skeleton is the
same for all algorithms of the thesis:

1. resample ``(Z_{t-1}, w_{t-1})`` if the policy says so;
2. ``propose``: draw new states and compute the log weight increment — the
   one part that differs between algorithms;
3. add the increment to the log-weights; a step in which every weight is zero
   or NaN is reported (:class:`~vistrack.particles.DegenerateWeightsWarning`)
   and recovered from by keeping the equally weighted prediction.
"""

from __future__ import annotations

import copy

import numpy as np

from ..models.protocol import Births, LocalMoves, ReservedLineages, offers, require
from ..particles import ParticleSet, checked_weights, logsumexp
from ..resampling import get_scheme, needs_resampling

__all__ = ["ParticleFilter", "filter_steps", "prior_as_kernel"]


def prior_as_kernel(model):
    """The model seen by the first step, where ``Y_1`` observes ``X_1 ~ p_0``.

    ``predict`` draws from the prior ``p_0`` and ``transition_logpdf`` is
    ``log p_0``, so every algorithm's first update is its ordinary step with
    ``p_0`` in the place of ``K`` (Figs. 2.3, 4.11, 4.13 start from ``p_0``).
    Local moves use ``model.with_local_prior`` when the model has one (a move
    that need not keep the support of ``K``); ``first_step = True`` tells a
    model to scale its windows to ``p_0`` rather than to ``K``.
    """
    m = copy.copy(model)
    m.first_step = True
    m.predict = lambda prev, rng: model.sample_prior(len(prev), rng)
    m.predict_mean = lambda prev: np.broadcast_to(model.prior_mean, prev.shape).copy()
    m.transition_logpdf = lambda new, old: model.prior_logpdf(new)
    if offers(model, LocalMoves):
        m.with_local = model.with_local_prior
    return m


class ParticleFilter:
    """Base class: resample, ``propose``, weight.

    Parameters
    ----------
    model : object
        Supplies ``sample_prior(n, rng)``, ``predict(states, rng)``,
        ``transition_logpdf(new, old)`` and ``loglik(obs, states)``, all
        vectorised over particles.
    resample : str or callable
        Resampling scheme (``multinomial``, ``residual``, ``stratified``,
        ``systematic``).
    ess_threshold : float or None
        Resample every step when ``None`` (or ``>= 1``), else when
        ``ESS < ess_threshold * N``.
    birth_reserve : float or None
        Share ``ε`` of the resampled particles kept for the newest births
        (``model.reserved(particles)`` if the model has it, e.g. lineages a few
        frames old, else ``model.entering(states)``, e.g. a car entering the
        scene), drawn ∝ their likelihood; ``None`` takes ``model.birth_reserve``
        (default 0). See :meth:`resampling_probs`.
    """

    name = "base"
    #: the model protocols this filter needs (:mod:`vistrack.models.protocol`)
    needs = ()
    #: parts whose default the model supplies: attribute -> model method name
    model_parts = {}

    def __init__(self, model, *, resample="systematic", ess_threshold=None, birth_reserve=None):
        require(model, self.needs, self.name)
        self.model = model
        self.resample_scheme = get_scheme(resample)
        self.ess_threshold = ess_threshold
        self._birth_reserve = birth_reserve
        self._from_model = set()
        self._first = None  # this filter on the first step's model (prior_as_kernel), built on first use

    def _set_part(self, attr, value):
        """Set ``attr`` to ``value``, or to what the model's default method gives."""
        if value is None:
            method = self.model_parts[attr]
            if getattr(self.model, method, None) is None:
                raise ValueError(f"{self.name} needs a model with {method} (its {attr}); "
                                 f"{type(self.model).__name__} does not supply it")
            value = getattr(self.model, method)()
            self._from_model.add(attr)
        setattr(self, attr, value)

    def bind(self, model):
        """This filter with the same parameters on another ``model``; parts that
        came from the old model's defaults are taken from the new one."""
        other = copy.copy(self)
        other.model = model
        other._first = None
        for attr in self._from_model:
            setattr(other, attr, getattr(model, self.model_parts[attr])())
        return other

    def first_step(self, obs, n, rng):
        """``n`` particles ``X_1 ~ p_0`` updated with the first observation ``Y_1``."""
        if n < 1:
            raise ValueError(f"number of particles must be positive, got {n}")
        if self._first is None:
            self._first = self.bind(prior_as_kernel(self.model))
        prior = ParticleSet(np.zeros((n, self.model.dim)))
        return self._first.step(prior, obs, rng)

    def initialize(self, n, rng):
        """``n`` equally weighted particles from the prior ``p_0``."""
        if n < 1:
            raise ValueError(f"number of particles must be positive, got {n}")
        return ParticleSet(self.model.sample_prior(n, rng))

    @property
    def birth_reserve(self):
        eps = self._birth_reserve
        if eps is None:
            eps = self.model.birth_reserve if offers(self.model, Births) else 0.0
        if not 0.0 <= eps < 1.0:  # ε = 1 would leave the tracked particles no draws (π_i = 0 < w_i)
            raise ValueError(f"birth_reserve must be in [0, 1), got {eps}")
        return float(eps)

    def resampling_probs(self, particles):
        """Resampling probabilities ``π`` and the log-weights ``log(w / π)`` the offspring carry.

        Plain resampling has ``π = w``. With a birth reserve ``ε`` the births ``B``
        (``model.reserved(particles)``, else ``model.entering(states)``) get ``ε`` of
        the draws on top: ``π_i = (1 - ε) w_i + ε ρ_i``, with ``ρ`` on ``B`` ∝ the
        likelihood ``r`` each had at its frame (``particles.loglik``), or ∝ the weights
        where the filter gave none. Every particle with ``w_i > 0`` keeps ``π_i > 0`` and
        its offspring carry ``w_i / π_i``, so the expected weight of its offspring is
        ``w_i`` (the resampled set stays properly weighted).

        A birth on a new object that the tracked particles outweigh — by the entering
        density's small mass at that pose — then survives resampling with a small weight,
        and takes over when the next frames confirm it. The reserve goes ∝ ``r`` rather
        than ∝ ``w``: a birth's weight is about the likelihood's mass in its search window,
        so a birth in a broad plate-less region (``log r`` −10 over the whole window)
        outweighs one on the narrow peak of a plate coming into view (``log r`` −0.6) —
        and would take the reserve's draws.
        """
        w = particles.weights
        eps = self.birth_reserve
        if eps > 0 and (offers(self.model, ReservedLineages) or offers(self.model, Births)):
            if offers(self.model, ReservedLineages):
                born = self.model.reserved(particles)
            else:
                born = self.model.entering(particles.states)
            w_b = float(w[born].sum())
            if 0.0 < w_b < 1.0:
                ll = None if particles.loglik is None else np.where(born, particles.loglik, -np.inf)
                if ll is not None and np.isfinite(ll.max()):
                    rho = np.exp(ll - ll.max())
                else:
                    rho = np.where(born, w, 0.0)
                pi = (1 - eps) * w + eps * rho / rho.sum()
                log_w = particles.log_weights - logsumexp(particles.log_weights)
                with np.errstate(divide="ignore", invalid="ignore"):
                    return pi, np.where(pi > 0, log_w - np.log(pi), -np.inf)
        return w, np.zeros(particles.n)

    def _resampled(self, particles, rng):
        """States and log-weights after the resampling policy."""
        n = particles.n
        if needs_resampling(particles.ess, n, self.ess_threshold):
            pi, log_w = self.resampling_probs(particles)
            idx = self.resample_scheme(pi, n, rng)
            return particles.states[idx], log_w[idx] - np.log(n)
        return particles.states, particles.log_weights

    def propose(self, prev, obs, rng):
        """Draw new states from ``prev (N, d)``.

        Returns
        -------
        new : ndarray (N, d)
            The new particle positions ``Z_t``.
        log_incr : ndarray (N,)
            Log weight increment.
        predicted : ndarray (N, d)
            The plain prediction ``X_t ~ K(.|prev)`` used if the step degenerates.
        loglik : ndarray (N,) or None
            ``log r(Y_t|Z_t)`` of the new states where the filter computed it.
        """
        raise NotImplementedError

    def step(self, particles, obs, rng):
        """One filtering step ``S_{t-1} -> S_t``."""
        prev, log_w = self._resampled(particles, rng)
        new, log_incr, predicted, loglik = self.propose(prev, obs, rng)
        log_w, degenerate = checked_weights(log_w + log_incr, self.name)
        if degenerate:
            new, loglik = predicted, None
        return ParticleSet(new, log_w, degenerate, loglik)


def filter_steps(filt, observations, n, rng, particles=None):
    """Run ``filt`` over ``observations``; yield the particle set after each step.

    Without ``particles`` the first observation is of ``X_1 ~ p_0``
    (:meth:`ParticleFilter.first_step`); with them, every observation follows a
    prediction from the given set.
    """
    for obs in observations:
        if particles is None:
            particles = filt.first_step(obs, n, rng)
        else:
            particles = filt.step(particles, obs, rng)
        yield particles
