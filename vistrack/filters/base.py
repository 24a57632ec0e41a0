"""The shared step of every particle filter (thesis 001, Figs. 2.3, 3.1, 4.11, 4.13, B.1).

A filter is ``step(particles, obs, rng) -> particles``. The skeleton is the
same for all algorithms of the thesis:

1. an optional first stage (:meth:`ParticleFilter.look_ahead`): the auxiliary
   weights ``log p̂(Y_t|X_{t-1})`` of AVPF (App. B) tilt the weights before
   resampling, and are divided out of the offspring's weights after;
2. resample ``(Z_{t-1}, w_{t-1})`` if the policy says so
   (:mod:`~vistrack.filters.resampler`: the ESS threshold, the scheme, the
   birth reserve of models with births);
3. ``propose``: draw new states with the step's kernel (``K``, or ``p_0`` on
   the first step: :mod:`vistrack.core.transition`) and compute the log weight
   increment — the one part that differs between algorithms;
4. add the increment to the log-weights; a step in which every weight is zero
   or NaN is reported (:class:`~vistrack.core.particles.DegenerateWeightsWarning`)
   and recovered from by keeping the equally weighted prediction.
"""

from __future__ import annotations

from operator import methodcaller

import numpy as np

from ..core.particles import ParticleSet, checked_weights
from ..core.transition import PriorKernel, Transition
from ..models.protocol import offers, require
from .resampler import make_resampler

__all__ = ["ParticleFilter", "filter_steps"]


class ParticleFilter:
    """Base class: first stage, resample, ``propose``, weight.

    Parameters
    ----------
    model : object
        Supplies ``sample_prior(n, rng)``, ``predict(states, rng)``,
        ``transition_logpdf(new, old)`` and ``loglik(obs, states)``, all
        vectorised over particles (:class:`~vistrack.models.protocol.StateSpaceModel`).
    resample : str or callable
        Resampling scheme (``multinomial``, ``residual``, ``stratified``,
        ``systematic``).
    ess_threshold : float or None
        Resample every step when ``None`` (or ``>= 1``), else when
        ``ESS < ess_threshold * N``.
    birth_reserve : float or None
        Share ``ε`` of the resampled particles kept for the newest births of a
        model with births (:class:`~vistrack.filters.resampler.BirthReserve`);
        ``None`` takes ``model.birth_reserve`` (default 0).
    """

    name = "base"
    #: the model protocols this filter needs (:mod:`vistrack.models.protocol`)
    needs = ()
    #: parts whose default the model builds per kernel: attribute -> (the protocol that offers it,
    #: its method's name)
    model_parts = {}
    #: the local proposal in use (filters with one set it from the model or the caller)
    proposal = None
    #: protocols a part the caller may pass in needs of the model when none is passed (LS-N-IPS's
    #: search)
    part_needs = ()
    #: the working memory of a step per particle, in units of the model's (its ``bytes_per_particle``)
    memory_factor = 1

    def __init__(self, model, *, resample="systematic", ess_threshold=None, birth_reserve=None):
        require(model, self.needs, self.name)
        self.model = model
        self.resampler = make_resampler(model, resample, ess_threshold, birth_reserve)
        self.kernel = Transition(model)
        self.prior_kernel = PriorKernel(model)
        self._given = {}  # parts passed in: attribute -> value (None: the model builds it)
        self._built = {}  # (attribute, first) -> the part the model built for that kernel

    @classmethod
    def required(cls):
        """Every protocol the filter needs of a model that builds all its parts: :attr:`needs`, the
        protocols of :attr:`model_parts` and :attr:`part_needs` (what the registry checks a model
        class against, :mod:`vistrack.registry.filter_specs`)."""
        parts = (protocol for protocol, _ in cls.model_parts.values())
        return tuple(dict.fromkeys((*cls.needs, *parts, *cls.part_needs)))

    @property
    def ess_threshold(self):
        """The resampler's threshold: resample when ``ESS < ess_threshold · N`` (``None``: every step)."""
        return self.resampler.ess_threshold

    @property
    def resample_scheme(self):
        """The resampler's scheme, ``scheme(w, n, rng) -> idx`` (:mod:`vistrack.core.resampling`)."""
        return self.resampler.scheme

    def _set_part(self, attr, value):
        """Use ``value`` as part ``attr``, or (``None``) what the model builds for each kernel;
        ``self.<attr>`` is the part of ``K``."""
        protocol, method = self.model_parts[attr]
        if value is None and not offers(self.model, protocol):
            raise ValueError(f"{self.name} needs a model with {method} (its {attr}); "
                             f"{type(self.model).__name__} does not supply it")
        self._given[attr] = value
        setattr(self, attr, self.part(attr, self.kernel))

    def part(self, attr, kernel):
        """Part ``attr`` for a step with ``kernel``: the one given, else the model's
        ``model_parts[attr]`` built for ``kernel`` (once; e.g. a window matched to ``p_0``)."""
        value = self._given[attr]
        if value is not None:
            return value
        key = (attr, kernel.first)
        if key not in self._built:
            self._built[key] = methodcaller(self.model_parts[attr][1], kernel)(self.model)
        return self._built[key]

    def first_step(self, obs, n, rng):
        """``n`` particles ``X_1 ~ p_0`` updated with the first observation ``Y_1``: the
        ordinary step with ``p_0`` in the place of ``K`` (:class:`~vistrack.core.transition.PriorKernel`)."""
        if n < 1:
            raise ValueError(f"number of particles must be positive, got {n}")
        prior = ParticleSet(np.zeros((n, self.model.dim)))
        return self._update(prior, obs, rng, self.prior_kernel)

    def look_ahead(self, particles, obs, rng, kernel):
        """First stage: ``(parent (M,), log p̂ (M,))``, candidates descending from
        ``particles.states[parent]`` and their look-ahead log-likelihoods, or ``None``
        (no first stage; the default)."""
        return None

    def _ancestors(self, particles, obs, rng, kernel):
        """Ancestor indices ``(N,)`` and the log-weights ``(N,)`` the new particles start from."""
        look = self.look_ahead(particles, obs, rng, kernel)
        if look is None:
            return self.resampler(particles, rng)
        parent, log_mu = look
        loglik = None if particles.loglik is None else particles.loglik[parent]
        tilted = ParticleSet(particles.states[parent], particles.log_weights[parent] + log_mu, loglik=loglik)
        k, log_w = self.resampler(tilted, rng, particles.n)
        return parent[k], log_w - log_mu[k]

    def propose(self, prev, obs, rng, kernel):
        """Draw new states from ``prev (N, d)`` with ``kernel`` (``K``, or ``p_0`` on the first step).

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
        return self._update(particles, obs, rng, self.kernel)

    def _update(self, particles, obs, rng, kernel):
        idx, log_w = self._ancestors(particles, obs, rng, kernel)
        new, log_incr, predicted, loglik = self.propose(particles.states[idx], obs, rng, kernel)
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
