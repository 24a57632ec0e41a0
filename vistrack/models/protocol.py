"""What a model offers and what a filter needs: the model protocols.

A filter states the protocols it needs (``ParticleFilter.needs``) and fails at construction
with one clear line when the model lacks a part (:func:`require`); nothing probes a model
for optional parts. Shapes: ``N`` particles, ``d`` the state dimension.

:class:`StateSpaceModel` (every filter; thesis 001 §2.1)
    ``sample_prior(n, rng) -> (n, d)``, ``prior_logpdf(states (N, d)) -> (N,)``,
    ``predict(states (N, d), rng) -> (N, d)`` (a draw from ``K``),
    ``transition_logpdf(new (N, d), old (N, d)) -> (N,)`` (``log K(new|old)``) and
    ``loglik(obs, states (N, d)) -> (N,)`` (``log r(Y_t|X_t)``).
:class:`PredictMean`
    ``predict_mean(states) -> (N, d)``: the mean of ``K`` (AVPF's first stage, §4.5.4).
:class:`LocalSearch` (LS-N-IPS, §4.3)
    ``local_search(obs, states) -> states`` or ``(states, loglik)``: ``LS_λ``.
:class:`LocalMoves` (LLS and LIS act on local coordinates, §4.4.3)
    ``local_coords(states) -> (N, m)`` and ``with_local(states, u (N, m)) -> (N, d)``;
    ``with_local_prior`` is the same for the first step (``X_1 ~ p_0``: a model whose state
    carries the previous pose moves it too, a zero initial velocity).
:class:`LLSModel` (§4.4)
    ``lls_window(kernel) -> Window`` for a step with ``kernel`` (:mod:`~vistrack.models.kernel`).
:class:`GridLikelihood` (optional speed-up for LLS)
    ``loglik_local_grid(obs, states, offsets (G, m)) -> (N, G)``: ``log r`` of every state
    moved by every offset, from shared measurements.
:class:`LISModel` (§4.5)
    ``lis_proposal(kernel)``: an object with ``sample(x, obs, rng, prev) -> (z, log_alpha, log_q)``
    for a step with ``kernel`` (``K``, or ``p_0`` on the first step: :mod:`~vistrack.models.kernel`).
:class:`Births` (the plate model's entering cars)
    ``birth_reserve`` (share ``ε`` of the resampled particles) and
    ``entering(states) -> (N,) bool``: the fresh births, which the reserve keeps; or, with
    :class:`ReservedLineages`, ``reserved(particles) -> (N,) bool``: the young lineages.
:class:`LaplaceModel`, :class:`EISModel` (PF-Doucet, PF-EIS, PF-EIS-MT; seed 000 §2–3)
    ``laplace(obs, states, ...) -> (mode, hessian, u)`` of the likelihood part sampled from
    the Laplace approximation, ``advance(states, ...)``; PF-EIS also
    ``sample_motion(states, rng)`` and ``c_logpdf(c, states)``.
:class:`SIRModel`
    ``sir_proposal(kernel)``: the image-only proposal of plain SIR.
:class:`InnovationSplit` (the history-sampling family, §3.2, Assumption 3.2.1)
    The state is the innovation ``X_{t,1}`` (``innovation_dim`` leading components, e.g. the
    pose) followed by the history ``X_{t,2} = history(X_{t-1})`` (e.g. the previous pose).
    The innovation splits into ``X_{t,1a}`` (the ``subspace_dim`` leading components, where
    the image-only proposal acts: translation) and ``X_{t,1b}`` (the rest: scale, rotation),
    ``K_1 = K_1b(x_1b | x_1a, X_{t-1}) K_1a(x_1a | X_{t-1})``. Broadcasting over leading axes
    (``x (N, 1, ·)`` against ``prev (1, C, d)`` gives the ``(N, C)`` pairs):
    ``subspace_logpdf(x1a, prev)`` (``log K_1a``), ``rest_logpdf(x1b, x1a, prev)``
    (``log K_1b``), ``sample_rest(x1a, prev, rng)`` (a draw from ``K_1b``); for the first
    step's ``p_0``: ``prior_subspace_logpdf(x1a)``, ``prior_rest_logpdf(x1b, x1a)``,
    ``sample_prior_rest(x1a, rng)`` and ``join_prior(x1) -> (N, d)`` (``X_1`` with the
    history ``p_0`` gives it); ``innovation_proposal(kernel)``: ``π(X_{t,1a} | Y_t)``, an
    object with ``sample(n, obs, rng) -> (n, subspace_dim)`` and ``logpdf(x1a, obs) -> (n,)``.
:class:`VideoModel` (the frame loop, ``run``, ``eval`` and ``vistrack.Tracker``)
    ``observe(maps, particles) -> obs`` (the frame's observation ``Y_t`` from its feature
    maps), ``adapt(obs, estimate)``, ``estimate(particles) -> (d,)``, ``visible(obs, state)
    -> bool``, ``box(states) -> (N, 4)`` ``(x, y, w, h)``, ``outline(states)`` (points to
    draw) and ``describe(state) -> dict`` (the track-file columns). Subclass
    :class:`VideoModelBase` for the defaults (the maps are the observation, no adaptation,
    the weighted mean, always visible).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

__all__ = ["StateSpaceModel", "PredictMean", "LocalSearch", "LocalMoves", "LLSModel", "GridLikelihood",
           "LISModel", "Births", "ReservedLineages", "LaplaceModel", "EISModel", "SIRModel", "InnovationSplit", "VideoModel", "VideoModelBase", "require", "offers", "missing_parts"]


@runtime_checkable
class StateSpaceModel(Protocol):
    dim: int

    def sample_prior(self, n, rng): ...

    def prior_logpdf(self, states): ...

    def predict(self, states, rng): ...

    def transition_logpdf(self, new, old): ...

    def loglik(self, obs, states): ...


@runtime_checkable
class PredictMean(Protocol):
    def predict_mean(self, states): ...


@runtime_checkable
class LocalSearch(Protocol):
    def local_search(self, obs, states): ...


@runtime_checkable
class LocalMoves(Protocol):
    def local_coords(self, states): ...

    def with_local(self, states, u): ...

    def with_local_prior(self, states, u): ...


@runtime_checkable
class LLSModel(Protocol):
    def lls_window(self, kernel=None): ...


@runtime_checkable
class GridLikelihood(Protocol):
    def loglik_local_grid(self, obs, states, offsets): ...


@runtime_checkable
class LISModel(Protocol):
    def lis_proposal(self, kernel=None): ...


@runtime_checkable
class Births(Protocol):
    birth_reserve: float

    def entering(self, states): ...


@runtime_checkable
class ReservedLineages(Protocol):
    def reserved(self, particles): ...


@runtime_checkable
class LaplaceModel(Protocol):
    def laplace(self, obs, states, **kwargs): ...

    def advance(self, states, *args, **kwargs): ...


@runtime_checkable
class EISModel(Protocol):
    def sample_motion(self, states, rng): ...

    def c_logpdf(self, c, states): ...


@runtime_checkable
class SIRModel(Protocol):
    def sir_proposal(self, kernel=None): ...


@runtime_checkable
class InnovationSplit(Protocol):
    innovation_dim: int
    subspace_dim: int

    def history(self, prev): ...

    def subspace_logpdf(self, x1a, prev): ...

    def rest_logpdf(self, x1b, x1a, prev): ...

    def sample_rest(self, x1a, prev, rng): ...

    def prior_subspace_logpdf(self, x1a): ...

    def prior_rest_logpdf(self, x1b, x1a): ...

    def sample_prior_rest(self, x1a, rng): ...

    def join_prior(self, x1): ...

    def innovation_proposal(self, kernel=None): ...


@runtime_checkable
class VideoModel(Protocol):
    def observe(self, maps, particles): ...

    def adapt(self, obs, estimate): ...

    def estimate(self, particles): ...

    def visible(self, obs, state): ...

    def box(self, states): ...

    def outline(self, states): ...

    def describe(self, state): ...


class VideoModelBase:
    """Defaults of the :class:`VideoModel` parts that most models share."""

    def observe(self, maps, particles):
        """The frame's observation: its feature maps (``particles``: the previous set, or ``None``)."""
        return maps

    def adapt(self, obs, estimate):
        """Learn from the frame's estimate; returns whether anything changed (here: never)."""
        return False

    def estimate(self, particles):
        """The point estimate ``(d,)``: the weighted mean."""
        return particles.mean()

    def visible(self, obs, state):
        """Whether the object is reported at ``state`` (here: always)."""
        return True


def _members(protocol):
    return sorted(n for n in vars(protocol) if not n.startswith("_") and n not in ("mro",)) + \
        sorted(getattr(protocol, "__annotations__", {}))


def missing_parts(model, protocol):
    """The parts of ``protocol`` that ``model`` lacks (empty when it offers them all)."""
    return [n for n in dict.fromkeys(_members(protocol)) if getattr(model, n, None) is None]


def offers(model, protocol):
    """Whether ``model`` offers every part of ``protocol``."""
    return not missing_parts(model, protocol)


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
