"""The tracking loop: frames -> feature maps -> one filter step per frame.

Feature maps are computed once per frame and shared by every particle
(DESIGN.md). The loop owns nothing but timing; what to do with each frame's
result (CSV row, annotated frame, progress) is the caller's business.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .features import FeatureMaps
from .particles import ParticleSet

__all__ = ["FrameResult", "track", "top_particles"]


@dataclass
class FrameResult:
    """The filter's state after one frame."""

    index: int
    frame: np.ndarray
    particles: ParticleSet
    estimate: np.ndarray
    ms: float
    maps: object = None

    @property
    def ess(self):
        return self.particles.ess


def top_particles(particles, k):
    """States of the ``k`` highest-weight particles, best first."""
    k = min(int(k), particles.n)
    if k <= 0:
        return particles.states[:0]
    idx = np.argpartition(-particles.log_weights, k - 1)[:k]
    idx = idx[np.argsort(-particles.log_weights[idx])]
    return particles.states[idx]


def track(frames, filt, n, rng, *, estimator=None):
    """Run ``filt`` with ``n`` particles over ``frames`` (an iterable of ``(index, BGR frame)``).

    Yields a :class:`FrameResult` per frame. The first frame observes
    ``X_1 ~ p_0`` (``filt.first_step``). ``estimator(particles)`` gives the point
    estimate (default: the model's ``estimate`` if it has one, else the weighted
    mean). A model with an ``observe(maps, previous_particles)`` method turns
    each frame's maps into its observation ``Y_t`` (landmarks: blob detection
    and association); otherwise the maps are the observation. A model with an
    ``adapt(obs, estimate)`` method (the box model's appearance) is told each frame's
    estimate after the step. The feature maps of a frame live in
    buffers that the next frame overwrites: use them before asking for the next.
    """
    particles = None
    estimator = estimator or getattr(filt.model, "estimate", None)
    observe = getattr(filt.model, "observe", None)
    adapt = getattr(filt.model, "adapt", None)
    buffers = {}  # feature-map buffers reused from frame to frame
    for i, frame in frames:
        t0 = time.perf_counter()
        maps = FeatureMaps(frame, buffers=buffers)
        obs = observe(maps, particles) if observe else maps
        if particles is None:
            particles = filt.first_step(obs, n, rng)
        else:
            particles = filt.step(particles, obs, rng)
        est = estimator(particles) if estimator else particles.mean()
        if adapt:
            adapt(obs, est)
        ms = (time.perf_counter() - t0) * 1e3
        yield FrameResult(i, frame, particles, est, ms, maps)
