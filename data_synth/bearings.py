"""State/observation sequences of the bearings-only problem (thesis 001, §4.5.5).

The true initial state ``x_1`` is fixed at the prior mean ("keeping the
initial position fixed") and observed, as in Gordon et al. (1993); the
filters start from the prior ``p_0`` and update it with ``y_1``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["simulate"]


def simulate(model, steps, rng, x0=None):
    """Simulate ``steps`` steps of ``model``.

    Returns
    -------
    states : ndarray (steps, d)
        ``x_1 .. x_T``; ``x_1`` is ``x0`` or the prior mean.
    obs : ndarray (steps, M)
        ``y_1 .. y_T``.
    """
    x = np.array(model.prior_mean if x0 is None else x0, dtype=float)[None, :]
    states, obs = [], []
    for t in range(steps):
        if t > 0:
            x = model.predict(x, rng)
        states.append(x[0])
        obs.append(model.sample_observation(x, rng)[0])
    return np.array(states), np.array(obs)
