"""What a model offers and what a filter needs: the model protocols.

A filter states the protocols it needs (``ParticleFilter.needs``) and fails at construction
with one clear line when the model lacks a part (:func:`require`); nothing probes a model
for optional parts. Shapes: ``N`` particles, ``d`` the state dimension, ``m`` the number of
local coordinates; each method's docstring gives its arguments and results.

* :class:`StateSpaceModel`: every filter (thesis 001 §2.1).
* :class:`PredictMean`: AVPF's first stage (§4.5.4, App. B).
* :class:`LocalSearch`: LS-N-IPS (§4.3).
* :class:`LocalMoves`: LLS and LIS, which act on local coordinates (§4.4.3).
* :class:`LLSModel`, :class:`GridLikelihood`: LLS's window (§4.4) and an optional speed-up.
* :class:`LISModel`: LIS's local proposal (§4.5); :class:`LocalMixture`, :class:`MapLogQ`: what the
  Gauss-mixture and the grid proposals read.
* :class:`Births`, :class:`ReservedLineages`: the birth reserve of a model with entering
  objects (the plate model's entering cars, §4.5.3).
* :class:`LaplaceModel`, :class:`EISModel`: PF-Doucet, PF-EIS, PF-EIS-MT (seed 000 §2–3).
* :class:`SIRModel`: plain SIR's proposal (§3.1).
* :class:`Partitions`, :class:`PartitionLIS`: partitioned and branched partitioned sampling
  (App. C): the state as τ partitions with kernels ``K_j``, importance functions ``π_j`` and
  (for LIS inside each partition) local proposals ``q_j``.
* :class:`InnovationSplit`: the history-sampling family (§3.2): innovation, history and the
  1a/1b subspace split, with the image-only proposal of the innovation.
* :class:`~vistrack.core.hooks.Confidence`: a calibrated confidence in the estimate (the track CSV's
  ``confidence``, ``vistrack.Tracker.confidence``).
* :class:`VideoModel`: the frame loop, ``run``, ``eval`` and ``vistrack.Tracker``. Subclass
  :class:`VideoModelBase` for the defaults (the maps are the observation, no adaptation,
  the weighted mean, always visible, lost where ``visible`` says no; ``check_lost``
  once per frame: :mod:`vistrack.models.collapse`).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

# the checks and the optional hooks live in the core (proposals and filters use them without
# importing the models); re-exported here, with every protocol of the models
from ..core.hooks import FusedLISStep, FusedPropose, LookAhead, ProposalMap, Redetects, missing_parts, offers, require

__all__ = ["StateSpaceModel", "PredictMean", "LocalSearch", "LearnedSearch", "LocalMoves", "LLSModel", "GridLikelihood",
           "LISModel", "Births", "ReservedLineages", "LaplaceModel", "EISModel", "SIRModel", "InnovationSplit",
           "VideoModel", "VideoModelBase", "require", "offers", "missing_parts"]
__all__ += ["LocalMixture", "MapLogQ", "Partitions", "PartitionLIS", "LookAhead", "FusedPropose", "FusedLISStep",
            "ProposalMap", "Redetects"]


@runtime_checkable
class StateSpaceModel(Protocol):
    """The state-space model every filter needs (thesis 001 §2.1): ``p_0``, ``K`` and ``r``,
    vectorised over particles (``states``: an ``(N, d)`` array, one row per particle).

    Attributes
    ----------
    dim : int
        The state dimension ``d``.
    """

    dim: int

    def sample_prior(self, n, rng):
        """``n`` draws ``(n, d)`` from the prior ``p_0`` (``rng``: a ``numpy.random.Generator``)."""

    def prior_logpdf(self, states):
        """``log p_0`` of ``states (N, d)`` -> ``(N,)`` (up to a constant shared by all states)."""

    def predict(self, states, rng):
        """One draw ``X_t ~ K(.|x_{t-1})`` per row of ``states (N, d)`` -> ``(N, d)``: the dynamics."""

    def transition_logpdf(self, new, old):
        """``log K(new|old)`` row by row; ``new, old (N, d)`` -> ``(N,)`` (on the support of ``K``)."""

    def loglik(self, obs, states):
        """``log r(Y_t|x)`` of ``states (N, d)`` -> ``(N,)`` (``-inf`` where impossible).

        ``obs`` is the observation ``Y_t``; for a video model, what :meth:`VideoModel.observe`
        returns.
        """


@runtime_checkable
class PredictMean(Protocol):
    """The mean of the dynamics, for AVPF's first stage (thesis 001 §4.5.4, App. B)."""

    def predict_mean(self, states):
        """The mean of ``K(.|x)`` per row of ``states (N, d)`` -> ``(N, d)``."""


@runtime_checkable
class LocalSearch(Protocol):
    """The local search ``LS_λ`` of LS-N-IPS (thesis 001 §4.3, eq. 4.1)."""

    def local_search(self, obs, states):
        """Move each prediction ``X_t`` (rows of ``states (N, d)``) to a nearby local maximum of
        ``r(Y_t|.)``, at most ``λ`` away.

        Returns the moved states ``Z_t (N, d)``, or ``(Z_t, log r(Y_t|Z_t) (N,))`` (which saves
        the filter a likelihood evaluation).
        """


@runtime_checkable
class LocalMoves(Protocol):
    """Local coordinates that LLS and LIS perturb (thesis 001 §4.4.3, e.g. translation)."""

    def local_coords(self, states):
        """The local coordinates ``u (N, m)`` of ``states (N, d)``."""

    def with_local(self, states, u):
        """A copy of ``states (N, d)`` with the local coordinates set to ``u (N, m)``, kept on
        the support of ``K`` (e.g. an AR(2) state keeps its velocity consistent)."""

    def with_local_prior(self, states, u):
        """:meth:`with_local` for the first step (``X_1 ~ p_0``): a state that carries the
        previous pose moves it too (a zero initial velocity); ``(N, d)``, ``(N, m)`` -> ``(N, d)``."""


@runtime_checkable
class LearnedSearch(Protocol):
    """A learned local search for LS-N-IPS (thesis 001 §4.3.1, Fig. 4.5): the contour model's
    neural network."""

    def searcher(self, search):
        """``local_search(obs, states (N, d)) -> (states (N, d), loglik (N,))`` with the search
        named ``search`` (``"lms"`` or ``"nn"``)."""


@runtime_checkable
class LLSModel(Protocol):
    """LLS's window ``g`` on the local coordinates (thesis 001 §4.4)."""

    def lls_window(self, kernel=None):
        """The :class:`~vistrack.proposals.Window` over the ``m`` local coordinates for a step
        with ``kernel`` (``g`` matched to its spread, §4.4.1; ``None``: ``K``;
        :mod:`~vistrack.core.transition`)."""


@runtime_checkable
class GridLikelihood(Protocol):
    """An optional speed-up for LLS: ``r`` on the window's grid from shared measurements."""

    def loglik_local_grid(self, obs, states, offsets):
        """``log r (N, G)`` of every state of ``states (N, d)`` moved by every row of
        ``offsets (G, m)`` in local coordinates. Only LLS's proposal reads it; the weight takes
        the exact ``r`` at the drawn point, so an approximation here stays properly weighted."""


@runtime_checkable
class LISModel(Protocol):
    """LIS's local proposal ``q_{X,Y}`` with its window ``g`` (thesis 001 §4.5, Prop. 4.5.1)."""

    def lis_proposal(self, kernel=None):
        """The local proposal for a step with ``kernel`` (``K``, or ``p_0`` on the first step;
        ``None``: ``K``; :mod:`~vistrack.core.transition`).

        Returns an object with ``sample(x (N, d), obs, rng, prev (N, d)) -> (z (N, d),
        log_alpha (N,), log_q (N,))``: ``z`` drawn from ``q g(x - .) / α`` about the predictions
        ``x`` (``prev``, the resampled ``Z_{t-1}``, lets a window follow ``K`` itself).
        """


@runtime_checkable
class LocalMixture(Protocol):
    """A Gaussian-mixture local proposal (:class:`~vistrack.proposals.GaussMixtureProposal`; the
    contour, bearings and toy models): ``local_mixture(obs, states) -> (log_p (N, B, n),
    mu (N, B, n, k), ...)`` about each state (the proposal's docstring gives the full form)."""

    def local_mixture(self, obs, states): ...


@runtime_checkable
class MapLogQ(Protocol):
    """The grid proposal's map (:class:`~vistrack.proposals.MapProposal`; the box model):
    ``proposal_log_q(obs, states (N, d), points (N, G, 2)) -> log q (N, G)`` at translations."""

    def proposal_log_q(self, obs, states, points): ...


@runtime_checkable
class Births(Protocol):
    """A model with births (the plate model's entering cars, thesis 001 §4.5.3): the resampling
    reserve (:class:`~vistrack.filters.resampler.BirthReserve`) keeps a share
    ``birth_reserve`` ``ε`` in ``[0, 1)`` of the draws for them."""

    birth_reserve: float

    def entering(self, states):
        """Which rows of ``states (N, d)`` are fresh births (entering draws): bool ``(N,)``."""


@runtime_checkable
class ReservedLineages(Protocol):
    """The births the reserve keeps, chosen on the particle set (e.g. young lineages)."""

    def reserved(self, particles):
        """Which particles of the :class:`~vistrack.core.particles.ParticleSet` the birth reserve
        keeps: bool ``(N,)``."""


@runtime_checkable
class LaplaceModel(Protocol):
    """The Laplace approximation of the optimal proposal (seed 000 §2–3, eqs. 3–4 and 8)."""

    def laplace(self, obs, states, **kwargs):
        """Mode and Hessian of ``L = -log p(Y_t|X) - log p(X|X_{t-1})`` in the sampled part
        (``p`` components) of the state, for each previous state of ``states (N, d)``.

        ``free="all"`` (PF-Doucet: motion and shape velocity) or ``free="c"`` (PF-EIS: the
        shape velocity given ``motion=(s (N,), θ (N,))``). Returns ``(mode (N, p), hessian
        (N, p, p), u)``: the Hessian is positive definite (its inverse is ``Σ_IS``) and ``u``
        the deterministic part of the move (the landmark model's ``U_t``) for :meth:`advance`.
        """

    def advance(self, states, *args, **kwargs):
        """New states ``(N, d)`` from the previous ``states (N, d)`` and the sampled parts (the
        landmark model: ``s (N,)``, ``θ (N,)``, ``c (N, p)``, ``u=``): the deterministic rest of
        the dynamics, ``U_t = g(U_{t-1}, z_{t-1})``, ``z_t = f(z_{t-1}, U_t, c_t)`` (§3.1)."""


@runtime_checkable
class EISModel(Protocol):
    """PF-EIS's split of the state: motion from its prior, the rest importance-sampled
    (seed 000 §2.2, §3.3)."""

    def sample_motion(self, states, rng):
        """The broad part of the state drawn from its state-transition prior given the previous
        ``states (N, d)`` (step 1 of §3.3); the landmark model: ``(s_t (N,), θ_t (N,))``."""

    def c_logpdf(self, c, states):
        """``log N(c; A_c c_{t-1}, Σ_c) (N,)`` of the importance-sampled part ``c (N, p)`` given
        the previous ``states (N, d)`` (the STP of §3.1)."""


@runtime_checkable
class SIRModel(Protocol):
    """Plain SIR's proposal ``π(.|X_{t-1}, Y_t)`` (thesis 001 §3.1, Fig. 3.1)."""

    def sir_proposal(self, kernel=None):
        """The proposal for a step with ``kernel``: an object with ``sample(prev (N, d), obs,
        rng) -> (N, d)`` and ``logpdf(new (N, d), prev (N, d), obs) -> (N,)``, positive wherever
        ``K`` is."""


@runtime_checkable
class InnovationSplit(Protocol):
    """A state split into innovation and history for the history-sampling family (thesis 001 §3.2,
    Assumption 3.2.1); see the module docstring."""
    innovation_dim: int
    subspace_dim: int

    def history(self, prev):
        """The history part ``X_{t,2} = f(X_{t-1})`` of new states, from ``prev (..., d)``."""

    def subspace_logpdf(self, x1a, prev):
        """``log K_1a(x1a | prev)`` broadcast over leading axes: ``x1a (N, 1, a)`` against ``prev (1, C, d)``
        gives ``(N, C)``."""

    def rest_logpdf(self, x1b, x1a, prev):
        """``log K_1b(x1b | x1a, prev)``, broadcast as :meth:`subspace_logpdf`."""

    def sample_rest(self, x1a, prev, rng):
        """A draw of ``X_{t,1b} ~ K_1b(. | x1a, prev)``."""

    def prior_subspace_logpdf(self, x1a):
        """``log p_0`` of ``x1a``, for the first step."""

    def prior_rest_logpdf(self, x1b, x1a):
        """``log p_0(x1b | x1a)``, for the first step."""

    def sample_prior_rest(self, x1a, rng):
        """A draw of ``X_{1,1b}`` from ``p_0`` given ``x1a``."""

    def join_prior(self, x1):
        """The state ``(N, d)`` of innovation ``x1 (N, k)`` with the history ``p_0`` gives it."""

    def innovation_proposal(self, kernel=None):
        """``π(X_{t,1a} | Y_t)``: an object with ``sample(n, obs, rng) -> (n, a)`` and ``logpdf(x1a, obs) -> (n,)``
        (§3.2.5's colour blobs)."""


@runtime_checkable
class Partitions(Protocol):
    """The state as ``τ`` partitions sampled one after the other (thesis 001 App. C, Figs. C.1–C.2).

    Partition ``j`` owns the columns ``partitions[j]``; ``K_j`` draws them given a state whose
    partitions sampled before ``j`` hold ``X_t`` and the rest ``X_{t-1}`` (eq. C.2; ``p_0``
    factorises alike on the first step). ``π_j`` (:meth:`loglik_part`) weights partition
    ``j`` before the next resampling: for independent targets, target ``j``'s likelihood
    factor. Branched partitioning needs eq. C.2 in each of its orders (independent targets:
    any). Vectorised over particles (``states (N, d)``; ``d_j`` the partition's width).

    Attributes
    ----------
    partitions : sequence of int arrays
        The columns of each partition, ``τ`` disjoint arrays covering ``0..d-1``.
    factorised_likelihood : bool
        Whether ``log r(Y_t|x) = Σ_j log π_j`` exactly; the final weights then reuse the
        ``l_{t,j}`` (Fig. C.1's note) instead of evaluating ``r``.
    """

    partitions: tuple
    factorised_likelihood: bool

    def predict_part(self, states, j, rng):
        """A draw ``(N, d_j)`` of partition ``j`` from ``K_j(.|states)`` (``states (N, d)``: the
        partitions sampled before ``j`` new, the others previous)."""

    def part_logpdf(self, new, states, j):
        """``log K_j(new|states)``; ``new (N, d_j)``, ``states (N, d)`` -> ``(N,)``."""

    def sample_prior_part(self, states, j, rng):
        """A draw ``(N, d_j)`` of partition ``j`` from ``p_0``'s factor given the partitions
        sampled before it (columns of ``states (N, d)``; the rest is not read)."""

    def prior_part_logpdf(self, new, states, j):
        """``log p_0``'s factor ``j`` of ``new (N, d_j)`` given ``states (N, d)`` -> ``(N,)``."""

    def loglik_part(self, obs, states, j):
        """``log π_j(x_j | x_{1:j-1}, Y_t)`` of ``states (N, d)`` -> ``(N,)``: for independent
        targets, target ``j``'s likelihood factor (``-inf`` where impossible)."""


@runtime_checkable
class PartitionLIS(Protocol):
    """A local proposal per partition, for LIS inside partitioned sampling (App. C's closing
    remark; Prop. 4.5.1 applied to ``K_j`` and ``π_j``)."""

    def lis_part_proposal(self, j, kernel=None):
        """Partition ``j``'s local proposal for a step with ``kernel`` (``None``: ``K``): an
        object with ``sample(x (N, d), obs, rng, prev (N, d_j)) -> (z (N, d_j), log_alpha (N,),
        log_q (N,))``, ``z`` drawn from ``q_j g(x_j - .) / α`` about partition ``j`` of the
        predictions ``x`` (``prev``: partition ``j`` before it was predicted)."""


@runtime_checkable
class VideoModel(Protocol):
    """What tracking on video needs beyond the state-space model: a frame's observation, the
    estimate, its box and outline, the track-file columns."""

    def observe(self, maps, particles):
        """The frame's observation ``Y_t`` (what :meth:`StateSpaceModel.loglik` reads) from its
        :class:`~vistrack.appearance.features.FeatureMaps`; ``particles``: the previous frame's
        :class:`~vistrack.core.particles.ParticleSet` (``None`` on the first frame)."""

    def adapt(self, obs, estimate):
        """Learn from the frame's ``estimate (d,)`` (e.g. update an appearance template);
        returns whether anything changed."""

    def estimate(self, particles):
        """The frame's point estimate ``(d,)`` from its :class:`~vistrack.core.particles.ParticleSet`."""

    def visible(self, obs, state):
        """Whether the object is reported at ``state (d,)`` in the frame observed as ``obs``."""

    def check_lost(self, obs, state):
        """``(reason, detail)`` for the frame's estimate ``state (d,)``, asked once per frame in
        order: ``("", "")`` when the object is reported, else a reason of
        :data:`vistrack.models.collapse.REASONS` (a collapsed scale, a likelihood far below its
        running level, ...) and a detail for the user."""

    def box(self, states):
        """Axis-aligned boxes ``(N, 4)`` ``(x, y, w, h)`` (top-left corner, pixels) of
        ``states (N, d)`` or one state ``(d,)``."""

    def outline(self, states):
        """Points ``(N, P, 2)`` ``(x, y)`` to draw per state (box corners, contour points, plate
        vertices) of ``states (N, d)`` or ``(d,)``."""

    def describe(self, state):
        """The track-file columns of one ``state (d,)``: a dict with ``cx, cy, w, h, angle_deg,
        scale`` and the model's own columns (e.g. support points or plate vertices)."""

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

    def redetected(self, obs):
        """Whether the frame observed as ``obs`` found a lost object again (here: never)."""
        return False

    def check_lost(self, obs, state):
        """``(reason, detail)`` for the frame's estimate ``state``: ``("", "")`` when
        :meth:`visible`, else ``("not found", ...)``."""
        if self.visible(obs, state):
            return "", ""
        return "not found", "no object passes the model's test at the estimate"
