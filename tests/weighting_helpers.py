"""Shared by the proper-weighting tests: many independent one-step runs of a filter from one particle
set, each with its own seeded generator (``default_rng(r)`` for run ``r``), and a statistic of each."""

import numpy as np


def one_step_runs(filt, prev, reps, stat, first=None):
    """``np.array([stat(p_r) for r in range(reps)])`` where ``p_r`` is ``filt.step(prev, None,
    default_rng(r))`` (``first=N``: ``filt.first_step(None, N, default_rng(r))`` instead); ``stat``
    maps a :class:`~vistrack.core.particles.ParticleSet` to a number, a list or a dict (dicts give a dict
    of arrays)."""
    runs = []
    for r in range(reps):
        rng = np.random.default_rng(r)
        p = filt.first_step(None, first, rng) if first else filt.step(prev, None, rng)
        runs.append(stat(p))
    if isinstance(runs[0], dict):
        return {k: np.array([m[k] for m in runs]) for k in runs[0]}
    return np.array(runs)
