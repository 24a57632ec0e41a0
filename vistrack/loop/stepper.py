"""The tracking loop: frames -> feature maps -> one filter step per frame.

Feature maps are computed once per frame and shared by every particle
(docs/architecture.md). The loop owns nothing but timing; what to do with each frame's
result (CSV row, annotated frame, progress) is the caller's business.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..appearance.features import FeatureMaps
from ..core.hooks import Confidence, Reseeds
from ..core.particles import ParticleSet
from ..models.protocol import Redetects, VideoModel, offers, require
from ..registry import make_filter
from ..scoring.metrics import best_ms

__all__ = ["FrameResult", "Stepper", "top_particles", "warm_up", "filter_ms"]


@dataclass
class FrameResult:
    """The filter's state after one frame."""

    index: int
    frame: np.ndarray
    particles: ParticleSet
    estimate: np.ndarray
    ms: float
    maps: object = None
    #: the model's observation of the frame (``model.observe``; what ``visible`` and ``loglik`` read)
    obs: object = None
    #: ``""`` when the object is reported at the estimate, else why not
    #: (:data:`~vistrack.models.collapse.REASONS`), and a sentence with the numbers
    lost_reason: str = ""
    lost_detail: str = ""
    #: a model of several targets (:class:`~vistrack.scoring.mot.MultiTarget`): the frame's reported
    #: targets as ``(ids (M,), states (M, d1))``, the ids kept from frame to frame
    #: (:class:`~vistrack.scoring.mot.Identities`); ``None`` for a single-target model
    targets: tuple = None
    #: the model re-found the object on this frame after a loss (a whole-frame search, the box model's
    #: ``redetect``) and reports it here (the track CSV's ``redetected``)
    redetected: bool = False
    #: the model's calibrated confidence in the estimate, in ``[0, 1]``
    #: (:class:`~vistrack.core.hooks.Confidence`; the track CSV's ``confidence``), ``None`` without one
    confidence: float | None = None

    @property
    def ess(self):
        """Effective sample size of the frame's particle set (thesis 001 §2.4)."""
        return self.particles.ess

    @property
    def visible(self):
        """Whether the object is reported at the estimate (the track CSV's ``visible``)."""
        return not self.lost_reason

    def __repr__(self):
        est = np.array2string(np.asarray(self.estimate, float), precision=2, separator=", ", max_line_width=10**6)
        lost = f", lost_reason={self.lost_reason!r}" if self.lost_reason else ""
        return (f"FrameResult(index={self.index}, estimate={est}, ess={self.ess:.1f}, ms={self.ms:.2f}, "
                f"particles={self.particles.n}{lost})")


def top_particles(particles, k):
    """States of the ``k`` highest-weight particles, best first."""
    k = min(int(k), particles.n)
    if k <= 0:
        return particles.states[:0]
    idx = np.argpartition(-particles.log_weights, k - 1)[:k]
    idx = idx[np.argsort(-particles.log_weights[idx])]
    return particles.states[idx]


class Stepper:
    """One filter step per frame: frame -> feature maps -> observation -> step -> estimate.

    The one loop body behind ``vistrack run``, ``eval``, the reproductions and :class:`vistrack.Tracker`:
    :meth:`step` one frame, :meth:`steps` over frames. The first frame observes ``X_1 ~ p_0``
    (``filt.first_step``). The model is a
    :class:`~vistrack.models.protocol.VideoModel`: ``observe(maps, previous_particles)``
    turns each frame's maps into its observation ``Y_t`` (the maps themselves by default;
    landmarks: blob detection and association; box: the appearance maps over the region
    the particles can reach; plate: its 4-channel map and appearance maps), an object of the
    model's own that holds whatever the model computes from the frame (nothing is stored on the
    shared maps), ``estimate(particles)`` gives the point estimate (unless
    ``estimator`` is given), ``check_lost(obs, estimate)`` whether the object is reported
    there (:mod:`vistrack.models.collapse`) and ``adapt(obs, estimate)`` is told each
    frame's estimate after the step (the box model's appearance); a model with a
    :class:`~vistrack.core.hooks.Confidence` is asked for it before ``check_lost``. The feature
    maps of a frame live in buffers that the next frame overwrites: use them before stepping again.
    """

    def __init__(self, filt, n, rng, *, estimator=None):
        self.filt, self.n, self.rng = filt, n, rng
        self.particles = None
        require(filt.model, (VideoModel,), "the frame loop")
        self.model = filt.model
        self.estimator = estimator or filt.model.estimate
        self._buffers = {}  # feature-map buffers reused from frame to frame
        from ..scoring.mot import Identities, MultiTarget

        self.identities = Identities() if offers(self.model, MultiTarget) else None

    def step(self, index, frame):
        """Track one BGR (or grey) ``frame``; returns its :class:`FrameResult`."""
        t0 = time.perf_counter()
        maps = FeatureMaps(frame, buffers=self._buffers)
        obs = self.model.observe(maps, self.particles)
        if self.particles is not None and offers(self.model, Reseeds):  # a lost object found again: re-seeded
            seeded = self.model.reseed(obs, self.particles, self.rng)
            self.particles = self.particles if seeded is None else seeded
        if self.particles is None:
            self.particles = self.filt.first_step(obs, self.n, self.rng)
        else:
            self.particles = self.filt.step(self.particles, obs, self.rng)
        est = self.estimator(self.particles)
        conf = self.model.confidence(obs, est, self.particles) if offers(self.model, Confidence) else None
        reason, detail = self.model.check_lost(obs, est)
        self.model.adapt(obs, est)
        targets = None
        if self.identities is not None:
            states = self.model.targets(obs, est)
            targets = (self.identities.assign(index, self.model.target_box(states)), states)
        ms = (time.perf_counter() - t0) * 1e3
        redetected = offers(self.model, Redetects) and self.model.redetected(obs) and not reason
        return FrameResult(index, frame, self.particles, est, ms, maps, obs, reason, detail, targets, redetected,
                           conf)

    def steps(self, frames):
        """:meth:`step` over ``frames`` (an iterable of ``(index, BGR frame)``): yields a :class:`FrameResult`
        per frame."""
        for i, frame in frames:
            yield self.step(i, frame)


def warm_up(filt, n, frame):
    """Run ``filt``'s first step and one more step with ``n`` particles on a blank frame shaped like
    ``frame``, with a throwaway generator, the model's likelihood at one particle (what the collapse
    test computes at the estimate) and the confidence and an adaptation of a copy of the model, so that the compiled
    kernels the model and filter call (:mod:`vistrack.kernels`) are loaded before tracking starts:
    their loading (0.1–1 s) is start-up, not tracking, and on the first run after an install, when
    they compile (:mod:`vistrack.system.compiling`), nothing is left to compile mid-track. The model
    and filter are left as they were (a model that cannot track a blank frame just skips this: the
    real frames will say what is wrong)."""
    import copy
    import warnings

    from .. import kernels

    if not kernels.use():
        return
    blank = np.zeros_like(np.asarray(frame))
    model, rng = filt.model, np.random.default_rng(0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            particles = filt.first_step(model.observe(FeatureMaps(blank), None), n, rng)
            obs = model.observe(FeatureMaps(blank), particles)
            filt.step(particles, obs, rng)
            model.loglik(obs, np.array(particles.states[:1], float))
            twin = copy.deepcopy(model)  # adapted instead of the model, which stays as it was
            obs, est = twin.observe(FeatureMaps(blank), particles), model.estimate(particles)
            if offers(twin, Confidence):
                twin.confidence(obs, est, particles)
            twin.adapt(obs, est)
        except Exception:  # noqa: BLE001 - best effort: tracking raises the real error itself
            pass


def filter_ms(frames, model, algo, n, repeats=2):
    """The time per frame (ms) of filter ``algo`` with ``n`` particles tracking ``frames`` (a list of
    ``(index, frame)``) on ``model``: a new filter each run from seed 0, the best of ``repeats``
    (:func:`~vistrack.scoring.metrics.best_ms`); what equal-time comparisons measure."""
    def run():
        for _ in Stepper(make_filter(algo, model), n, np.random.default_rng(0)).steps(frames):
            pass

    return best_ms(run, repeats) / len(frames)
