"""``vistrack.Tracker``: the OpenCV tracker shape over vistrack's particle filters.

    t = vistrack.Tracker(model="box", algo="lis", particles=100, seed=0)
    t.init(frame, (x, y, w, h))
    ok, box = t.update(frame)

Frames are numpy BGR (or grey) arrays, as ``cv2.VideoCapture`` gives them, so it drops into
code written for ``cv2.TrackerMIL``; other frames a user may pass (``uint16``, floats in 0..1 or
0..255, ``(H, W, 1)``, BGRA, nested lists) are converted once (:func:`vistrack.io.frames.as_frame`),
and a frame of another size or kind than the first is an error, as in ``vistrack run``. It runs the
same code as ``vistrack run`` (:func:`~vistrack.registry.builders.model_from_box`,
:class:`~vistrack.loop.stepper.Stepper`): the same options and seed give the same track. Every
argument is checked when the tracker is made: a bad one is one ``ValueError`` naming it.
"""

from __future__ import annotations

import inspect
import math
import numbers

import numpy as np

from ..core.resampling import SCHEMES
from ..io.frames import as_frame
from ..loop.stepper import Stepper
from ..registry import (
    DEFAULT_MODEL,
    DEFAULT_PARTICLES,
    check_algo,
    check_particle_memory,
    get_model_spec,
    make_filter,
    model_from_box,
)
from ..registry.option_types import check_model_options

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
        Number of particles ``N``, an integer ``>= 1`` (default
        :data:`~vistrack.registry.catalog.DEFAULT_PARTICLES`).
    seed : int or numpy.random.Generator
        Random seed (an integer ``>= 0``, or a Generator, SeedSequence or BitGenerator): the same
        seed gives the same track.
    resample : str
        Resampling scheme (:data:`vistrack.core.resampling.SCHEMES`).
    ess_threshold : float or None
        Resample when ``ESS < threshold N``, a number in ``[0, 1]`` as ``run --ess-threshold``
        (``None``: every frame).
    **model_options
        Passed to the model (e.g. ``layout`` for plates, ``lambda_template`` for boxes); checked
        here by building the model once on a blank frame, an unknown one named with the model's.

    Raises
    ------
    ValueError
        One line naming the argument: an unknown model, algorithm, scheme or option; particles
        not an integer ``>= 1`` (or beyond memory); a negative or non-integer seed; an
        ``ess_threshold`` outside ``[0, 1]``. :meth:`init` and :meth:`update` refuse a frame they
        cannot convert, a box that is not four finite numbers inside the frame, and a frame of
        another size or kind than the first.

    Attributes
    ----------
    particles : ParticleSet or None
        The particle set after the last frame.
    result : FrameResult or None
        The last frame's result (estimate, ESS, milliseconds).

    Every attribute of the last frame (:attr:`particles`, :attr:`result`, :attr:`box`,
    :attr:`box_estimate`, :attr:`visible`, :attr:`confidence`, :attr:`lost_reason`) is ``None`` before
    :meth:`init`.
    """

    def __init__(self, model=DEFAULT_MODEL, algo=None, particles=DEFAULT_PARTICLES, seed=0, *, resample="systematic",
                 ess_threshold=None, **model_options):
        spec = get_model_spec(model)
        if not spec.box_init:
            raise ValueError(f"the {model} model does not start from a box")
        self.algo = algo or spec.default_algo
        check_algo(model, self.algo, who=f"algorithm {self.algo!r}")
        if isinstance(particles, bool) or not isinstance(particles, numbers.Integral) or particles < 1:
            raise ValueError(f"particles must be an integer >= 1, got {particles!r}")
        check_particle_memory(int(particles), spec.bytes_per_particle, self.algo)
        self.model_name, self.n, self.seed = model, int(particles), _checked_seed(seed)
        if resample not in SCHEMES:
            raise ValueError(f"unknown resampling scheme {resample!r}; choose from {', '.join(SCHEMES)}")
        if ess_threshold is not None and not (isinstance(ess_threshold, numbers.Real) and 0 <= ess_threshold <= 1):
            raise ValueError(f"ess_threshold must be a number in [0, 1] (or None: resample every frame), got "
                             f"{ess_threshold!r}")
        self.filter_options = {"resample": resample, "ess_threshold": ess_threshold}
        self.model_options = model_options
        if model_options:
            check_model_options(spec, model_options)  # the declared types and ranges, NaN refused
            _check_options(model, spec, model_options)
        self.model = None
        self.result = None
        self._stepper = None
        self._format = None

    @property
    def particles(self):
        """The :class:`~vistrack.core.particles.ParticleSet` after the last frame (``None`` before :meth:`init`)."""
        return None if self._stepper is None else self._stepper.particles

    def init(self, frame, box):
        """Start on ``frame`` with the object in ``box`` ``(x, y, w, h)``; the first filter step
        observes this frame. Returns ``True``."""
        frame, fmt = as_frame(frame)
        box = _checked_box(box)
        self.model = model_from_box(self.model_name, frame, box, **self.model_options)
        self._format = fmt
        filt = make_filter(self.algo, self.model, **self.filter_options)
        self._stepper = Stepper(filt, self.n, np.random.default_rng(self.seed))
        self._index = 0
        self.result = self._stepper.step(0, frame)
        return True

    def update(self, frame):
        """Track ``frame``; returns ``(ok, (x, y, w, h))`` (integers, as :attr:`box`) with ``ok``
        whether the model reports the object (``False`` where its estimate collapsed: :attr:`lost_reason`)."""
        if self._stepper is None:
            raise RuntimeError("call init(frame, box) before update(frame)")
        frame, _ = as_frame(frame, self._format)
        self._index += 1
        self.result = self._stepper.step(self._index, frame)
        return self.visible, self.box

    @property
    def box(self):
        """The last estimate's box as ``(x, y, w, h)`` integers, as OpenCV's trackers give it (it
        draws with ``cv2.rectangle(frame, tracker.box, colour)``); :attr:`box_estimate` has the floats.
        ``None`` before :meth:`init`."""
        box = self.box_estimate
        return None if box is None else tuple(int(round(v)) for v in box)

    @property
    def box_estimate(self):
        """The last estimate as ``(x, y, w, h)`` floats (sub-pixel; what ``vistrack run`` writes); ``None``
        before :meth:`init`."""
        if self.result is None:
            return None
        return tuple(float(v) for v in self.model.box(self.result.estimate)[0])

    def __repr__(self):
        where = "not started" if self.result is None else f"frame {self._index}, box={self.box}, " \
            f"visible={self.visible}"
        return (f"Tracker(model={self.model_name!r}, algo={self.algo!r}, particles={self.n}, seed={self.seed!r}; "
                f"{where})")

    @property
    def visible(self):
        """Whether the last frame reports the object (``update``'s ``ok``); ``None`` before :meth:`init`."""
        return None if self.result is None else self.result.visible

    @property
    def confidence(self):
        """The last frame's calibrated confidence in ``[0, 1]`` that the box lies on the object (the box
        model's, :mod:`vistrack.models.box.confidence`; the track CSV's ``confidence``), ``None`` for a
        model without one, and before :meth:`init`."""
        return None if self.result is None else self.result.confidence

    @property
    def lost_reason(self):
        """``""``, or why the last frame does not report the object
        (:data:`~vistrack.models.collapse.REASONS`); ``None`` before :meth:`init`."""
        return None if self.result is None else self.result.lost_reason


def _checked_seed(seed):
    """``seed`` if numpy seeds a generator from it and it is not negative; else ``ValueError``."""
    if isinstance(seed, (np.random.Generator, np.random.BitGenerator, np.random.SeedSequence)):
        return seed
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0 or a numpy Generator, got {seed!r}")
    return seed


def _checked_box(box):
    """``box`` as four finite floats ``(x, y, w, h)``; else one ``ValueError``."""
    try:
        values = [float(v) for v in box]
    except (TypeError, ValueError):
        raise ValueError(f"box must be four numbers (x, y, w, h), got {box!r}") from None
    if len(values) != 4:
        raise ValueError(f"box must be four numbers (x, y, w, h), got {len(values)}: {box!r}")
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"box must be four finite numbers (x, y, w, h), got {box!r}")
    return tuple(values)


#: the frame and box the options of a model are tried on when a Tracker is made
_PROBE_SIZE, _PROBE_BOX = (160, 120), (40.0, 40.0, 80.0, 40.0)


def _check_options(name, spec, options):
    """Build model ``name`` once with ``options`` on a blank textured frame: an unknown option is a
    ``ValueError`` naming it and the model's options (those of its ``from_box`` and its class), a
    bad value the model's own ``ValueError``."""
    w, h = _PROBE_SIZE
    frame = np.full((h, w, 3), 100, np.uint8)
    frame[::4] = 160
    try:
        model_from_box(name, frame, _PROBE_BOX, **options)
    except TypeError as e:
        if "unexpected keyword argument" not in str(e):
            raise
        bad = str(e).rpartition("argument")[2].strip(" '")
        known = _option_names(spec.from_box) | _option_names(type(model_from_box(name, frame, _PROBE_BOX)).__init__)
        raise ValueError(f"unknown option {bad!r} for the {name} model; its options include "
                         f"{', '.join(sorted(known))}") from None


def _option_names(fn):
    """The keyword parameters of ``fn`` (not the frame, the box, ``self`` or ``**kwargs``)."""
    skip = {"self", "frame", "box", "frame_size", "init_pose", "template", "size"}
    return {p.name for p in inspect.signature(fn).parameters.values()
            if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and p.name not in skip}
