"""What a model or a proposal offers: :func:`offers`, :func:`require`, and the optional hooks that
filters and proposals look for (re-exported by :mod:`vistrack.models.protocol`, with the models'
protocols). A core module: the filters and proposals check hooks with it without importing the
models."""

from __future__ import annotations

import functools
from typing import Protocol, runtime_checkable

__all__ = ["offers", "class_offers", "require", "missing_parts", "LookAhead", "FusedPropose", "FusedLISStep",
           "ProposalMap", "Redetects", "Reseeds", "Confidence"]


@functools.cache
def _members(protocol):
    """The names ``protocol`` asks for, each once (a protocol class does not change: kept)."""
    return tuple(dict.fromkeys(sorted(n for n in vars(protocol) if not n.startswith("_") and n not in ("mro",))
                               + sorted(getattr(protocol, "__annotations__", {}))))


def missing_parts(model, protocol):
    """The parts of ``protocol`` that ``model`` lacks (empty when it offers them all)."""
    return [n for n in _members(protocol) if getattr(model, n, None) is None]


def offers(model, protocol):
    """Whether ``model`` offers every part of ``protocol``."""
    return not missing_parts(model, protocol)


def class_offers(cls, protocol):
    """Whether the instances of class ``cls`` offer the methods of ``protocol`` (its attributes, such
    as a model's ``dim``, are the instances' own: :func:`require` checks them on an instance)."""
    methods = [n for n, v in vars(protocol).items() if not n.startswith("_") and callable(v)]
    return all(callable(getattr(cls, n, None)) for n in methods)


def require(model, protocols, who):
    """Raise ``ValueError`` (one line) unless ``model`` offers every protocol in ``protocols``.

    Parameters
    ----------
    model : object
    protocols : iterable of Protocol classes
    who : str
        Who needs them, for the message (e.g. ``"ls-n-ips"``).
    """
    for p in protocols:
        lack = missing_parts(model, p)
        if lack:
            raise ValueError(f"{who} needs a model with {', '.join(lack)} ({p.__name__}); "
                             f"{type(model).__name__} does not supply {'it' if len(lack) == 1 else 'them'}")


@runtime_checkable
class LookAhead(Protocol):
    """A local proposal's first stage (:meth:`LIS.look_ahead <vistrack.filters.lis.LIS.look_ahead>`):
    ``look_ahead(prev (N, d), obs, kernel) -> log p̂(Y_t|Z_{t-1}) (N,)`` or ``None``."""

    def look_ahead(self, prev, obs, kernel): ...


@runtime_checkable
class FusedPropose(Protocol):
    """A local proposal that does LIS's whole step itself where it can: ``propose(prev, obs, rng,
    kernel) -> (new, log_incr, predicted, loglik)`` or ``None`` (the filter then calls the parts)."""

    def propose(self, prev, obs, rng, kernel): ...


@runtime_checkable
class FusedLISStep(Protocol):
    """A model whose compiled kernels do the grid proposal's LIS step (the box model):
    ``lis_step(prev, obs, rng, proposal)``."""

    def lis_step(self, prev, obs, rng, proposal): ...


@runtime_checkable
class ProposalMap(Protocol):
    """A model that gives the grid proposal a whole map per frame to draw from (the box model):
    ``proposal_qmap(obs, states, span)``."""

    def proposal_qmap(self, obs, states, span): ...


@runtime_checkable
class Redetects(Protocol):
    """A model that searches the frame again for a lost object (the box model: the track CSV's
    ``redetected`` column); ``redetect`` is its acceptance level (``None``: off) and
    ``redetected(obs)`` whether the frame observed as ``obs`` found it again."""

    redetect: float

    def redetected(self, obs): ...


@runtime_checkable
class Reseeds(Protocol):
    """A model that re-seeds the particles where a whole-frame search found a lost object (the box
    model's): ``reseed(obs, particles, rng)`` is the particle set the frame loop steps from on the frame
    observed as ``obs`` (``None``: ``particles`` kept)."""

    def reseed(self, obs, particles, rng): ...


@runtime_checkable
class Confidence(Protocol):
    """A calibrated confidence in the frame's estimate (the box model's,
    :mod:`vistrack.models.box.confidence`; the track CSV's ``confidence``, ``vistrack.Tracker.confidence``):
    asked once per frame, in order, by the frame loop after the step and before the model's ``check_lost``
    (which may report the object lost when it is low)."""

    def confidence(self, obs, state, particles):
        """The probability in ``[0, 1]`` that the estimate ``state (d,)`` lies on the object in the frame
        observed as ``obs``, with the frame's weighted :class:`~vistrack.core.particles.ParticleSet`
        ``particles``; ``None`` where the model has none this time."""
