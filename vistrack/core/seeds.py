"""The random streams of runs: one rule for ``vistrack run --seed S`` and ``eval``'s runs.

All of a run's randomness comes from one :class:`numpy.random.Generator`. ``vistrack run --seed S``
(and :class:`vistrack.Tracker` with ``seed=S``) draws from ``SeedSequence(S)``, what
``numpy.random.default_rng(S)`` gives. ``eval --seed S`` gives its run ``r`` on every clip, for
every algorithm and N (common random numbers), the stream :func:`run_seed` ``(S, r)``:
``SeedSequence(S)`` itself for run 0, ``SeedSequence([S, r])`` for the later runs. So
``eval --runs 1 --seed S`` tracks each clip as ``vistrack run CLIP --init-gt --seed S`` does, and
its run ``r`` as ``vistrack run CLIP --init-gt --seed S --run r``; the streams of different runs
and seeds are independent, and the results do not depend on the number of workers or the order of
the tasks.
"""

from __future__ import annotations

import numpy as np

__all__ = ["run_seed", "run_rng"]


def run_seed(seed, run=0):
    """The :class:`numpy.random.SeedSequence` of run ``run`` under seed ``seed``: ``SeedSequence(seed)``
    for run 0, ``SeedSequence([seed, run])`` after."""
    seed, run = int(seed), int(run)
    if seed < 0 or run < 0:
        raise ValueError(f"a seed and a run number are non-negative integers, got seed {seed}, run {run}")
    return np.random.SeedSequence(seed if run == 0 else [seed, run])


def run_rng(seed, run=0):
    """The generator of run ``run`` under seed ``seed`` (:func:`run_seed`)."""
    return np.random.default_rng(run_seed(seed, run))
