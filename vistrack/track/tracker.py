"""``vistrack.Tracker``: the OpenCV tracker shape over vistrack's particle filters.

    t = vistrack.Tracker(model="box", algo="lis", particles=100, seed=0)
    t.init(frame, (x, y, w, h))
    ok, box = t.update(frame)

Frames are numpy BGR (or grey) arrays, as ``cv2.VideoCapture`` gives them, so it drops into
code written for ``cv2.TrackerMIL``. It runs the same code as ``vistrack run``
(:func:`~vistrack.registry.builders.model_from_box`, :class:`~vistrack.track.loop.FrameStepper`): the
same options and seed give the same track.
"""

from __future__ import annotations

import numpy as np

from ..filters import make_filter
from ..registry import (
    DEFAULT_MODEL,
    DEFAULT_PARTICLES,
    check_algo,
    check_particle_memory,
    get_model_spec,
    model_from_box,
)
from .loop import FrameStepper

__all__ = ["Tracker"]


class Tracker:
    """A particle-filter tracker with OpenCV's ``init`` / ``update`` interface.

    Parameters
    ----------
    model : str
        What to track: a registered model that starts from a box (:mod:`vistrack.registry`; default
        ``box``: any object, appearance learned from the first frame).
    algo : str or None
        Particle filter, any that runs on the model (:func:`vistrack.registry.algos_for`: ``lis``,
        ``bootstrap``, ``ls-n-ips``, ``lls``, ``avpf``, ... on a box); ``None``: the model's default.
    particles : int
        Number of particles ``N`` (default :data:`~vistrack.registry.catalog.DEFAULT_PARTICLES`).
    seed : int or numpy.random.Generator
        Random seed: the same seed gives the same track.
    resample : str
        Resampling scheme.
    ess_threshold : float or None
        Resample when ``ESS < threshold N`` (``None``: every frame).
    **model_options
        Passed to the model (e.g. ``layout`` for plates, ``lambda_template`` for boxes).

    Attributes
    ----------
    particles : ParticleSet or None
        The particle set after the last frame.
    result : FrameResult or None
        The last frame's result (estimate, ESS, milliseconds).
    """

    def __init__(self, model=DEFAULT_MODEL, algo=None, particles=DEFAULT_PARTICLES, seed=0, *, resample="systematic",
                 ess_threshold=None, **model_options):
        spec = get_model_spec(model)
        if not spec.box_init:
            raise ValueError(f"the {model} model does not start from a box")
        self.algo = algo or spec.default_algo
        check_algo(model, self.algo, who=f"algorithm {self.algo!r}")
        if int(particles) < 1:
            raise ValueError(f"particles must be a positive integer, got {particles}")
        check_particle_memory(int(particles), spec.bytes_per_particle, self.algo)
        self.model_name, self.n, self.seed = model, int(particles), seed
        self.filter_options = {"resample": resample, "ess_threshold": ess_threshold}
        self.model_options = model_options
        self.model = None
        self.result = None
        self._stepper = None

    @property
    def particles(self):
        """The :class:`~vistrack.core.particles.ParticleSet` after the last frame (``None`` before :meth:`init`)."""
        return None if self._stepper is None else self._stepper.particles

    def init(self, frame, box):
        """Start on ``frame`` with the object in ``box`` ``(x, y, w, h)``; the first filter step
        observes this frame. Returns ``True``."""
        frame = np.asarray(frame)
        if frame.ndim not in (2, 3) or frame.size == 0:
            raise ValueError(f"a frame must be an (H, W) or (H, W, 3) array, got shape {frame.shape}")
        self.model = model_from_box(self.model_name, frame, box, **self.model_options)
        filt = make_filter(self.algo, self.model, **self.filter_options)
        self._stepper = FrameStepper(filt, self.n, np.random.default_rng(self.seed))
        self._index = 0
        self.result = self._stepper.step(0, frame)
        return True

    def update(self, frame):
        """Track ``frame``; returns ``(ok, (x, y, w, h))`` (integers, as :attr:`box`) with ``ok``
        whether the model reports the object (``False`` where its estimate collapsed: :attr:`lost_reason`)."""
        if self._stepper is None:
            raise RuntimeError("call init(frame, box) before update(frame)")
        self._index += 1
        self.result = self._stepper.step(self._index, np.asarray(frame))
        return self.visible, self.box

    @property
    def box(self):
        """The last estimate's box as ``(x, y, w, h)`` integers, as OpenCV's trackers give it (it
        draws with ``cv2.rectangle(frame, tracker.box, colour)``); :attr:`box_estimate` has the floats."""
        return tuple(int(round(v)) for v in self.box_estimate)

    @property
    def box_estimate(self):
        """The last estimate as ``(x, y, w, h)`` floats (sub-pixel; what ``vistrack run`` writes)."""
        return tuple(float(v) for v in self.model.box(self.result.estimate)[0])

    def __repr__(self):
        where = "not started" if self.result is None else f"frame {self._index}, box={self.box}, " \
            f"visible={self.visible}"
        return (f"Tracker(model={self.model_name!r}, algo={self.algo!r}, particles={self.n}, seed={self.seed!r}; "
                f"{where})")

    @property
    def visible(self):
        """Whether the last frame reports the object (``update``'s ``ok``)."""
        return self.result.visible

    @property
    def confidence(self):
        """The last frame's calibrated confidence in ``[0, 1]`` that the box lies on the object (the box
        model's, :mod:`vistrack.models.box.confidence`; the track CSV's ``confidence``), ``None`` for a
        model without one."""
        return self.result.confidence

    @property
    def lost_reason(self):
        """``""``, or why the last frame does not report the object
        (:data:`~vistrack.models.collapse.REASONS`)."""
        return self.result.lost_reason
