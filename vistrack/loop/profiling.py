"""Where a run's time goes: per-stage timers (exclusive time) and the stage split of a tracking run.

Stages: ``decode`` (reading frames), ``features`` (feature maps: Sobel/DoG/colour maps, the
appearance maps over the region of interest), ``likelihood`` (``log r``), ``proposal`` (local
proposals and searches, minus the likelihood calls inside them; the contour's LMS search computes
its likelihoods inside its compiled passes, and they count as proposal), ``resampling``, ``adapt``
(appearance update) and ``other`` (the rest of the filter step: prediction, weights, the
estimate). A timed call inside another timed call counts once, in its own stage.
"""

from __future__ import annotations

import time
from collections import defaultdict
from contextlib import contextmanager

from ..models.protocol import (
    FusedLISStep,
    GridLikelihood,
    LocalMixture,
    LocalSearch,
    MapLogQ,
    StateSpaceModel,
    VideoModel,
    offers,
)

__all__ = ["Timer", "STAGES", "instrument"]

STAGES = ("decode", "features", "likelihood", "proposal", "resampling", "adapt")


class Timer:
    """Accumulates exclusive seconds per stage; :meth:`timed` wraps a callable.

    Parameters
    ----------
    clock : callable
        Seconds now (default :func:`time.perf_counter`; tests pass a fake clock).
    """

    def __init__(self, clock=time.perf_counter):
        self.clock = clock
        self.t = defaultdict(float)
        self._stack = []  # [stage, seconds of nested timed calls]

    def wrap(self, owner, name, part):
        """Time ``owner.name`` as ``part``; returns the original (restore with ``setattr``)."""
        fn = getattr(owner, name)
        setattr(owner, name, self.timed(fn, part))
        return fn

    def timed(self, fn, part):
        """``fn`` wrapped so that its exclusive time (less that of nested timed calls) adds to stage ``part``."""
        def timed(*a, **k):
            self._stack.append([part, 0.0])
            t0 = self.clock()
            try:
                return fn(*a, **k)
            finally:
                dt = self.clock() - t0
                _, nested = self._stack.pop()
                self.t[part] += dt - nested
                if self._stack:
                    self._stack[-1][1] += dt

        return timed

    def timed_iter(self, iterable, part):
        """``iterable``'s items, the time to produce each counted as ``part``."""
        it = iter(iterable)
        while True:
            t0 = self.clock()
            try:
                item = next(it)
            except StopIteration:
                return
            finally:
                self.t[part] += self.clock() - t0
            yield item


#: what each stage times: the model's methods, each with the protocol that offers it
_MODEL_PARTS = {"features": ((VideoModel, "observe"),),
                "likelihood": ((StateSpaceModel, "loglik"), (GridLikelihood, "loglik_local_grid")),
                "proposal": ((LocalSearch, "local_search"), (LocalMixture, "local_mixture"),
                             (MapLogQ, "proposal_log_q"), (FusedLISStep, "lis_step")),
                "adapt": ((VideoModel, "adapt"),)}
#: (``lis_step``: the box model's compiled LIS step, its likelihood inside: counted as proposal)
_MAP_PARTS = ("gradient", "colour_labels", "integral")


@contextmanager
def instrument(model, filt, timer):
    """Within the block, time ``model``'s and ``filt``'s stages (module docstring) into ``timer``.

    The methods are wrapped on their classes (the model's, its proposal's and
    :class:`~vistrack.appearance.features.FeatureMaps`), so that the parts the first step builds
    (:meth:`~vistrack.filters.base.ParticleFilter.part`) are timed too and the track is
    exactly as without profiling; use in one thread. Everything is restored after."""
    from ..appearance.features import FeatureMaps

    restore = []

    def wrap_class(cls, name, part):
        if not isinstance(vars(cls).get(name), (staticmethod, classmethod)):
            restore.append((cls, name, timer.wrap(cls, name, part), name in vars(cls)))

    for part, entries in _MODEL_PARTS.items():
        for protocol, name in entries:
            if offers(model, protocol):
                wrap_class(type(model), name, part)
    restore.append((filt.resampler, "scheme", timer.wrap(filt.resampler, "scheme", "resampling"), True))
    if filt.proposal is not None:
        wrap_class(type(filt.proposal), "sample", "proposal")
    for name in _MAP_PARTS:
        wrap_class(FeatureMaps, name, "features")
    try:
        yield timer
    finally:
        for owner, name, fn, own in reversed(restore):
            if own:
                setattr(owner, name, fn)
            else:
                delattr(owner, name)
