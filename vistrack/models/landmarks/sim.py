"""Simulated landmark sequences by the model (5)-(6) of seed 000 (§3-4): states and observations."""

from __future__ import annotations

import numpy as np

__all__ = ["simulate", "sample_observations"]


def sample_observations(model, h, rng):
    """Observations of configurations ``h (T, K)`` by (6): each landmark is the true one plus
    ``CN(0, σ_o²)`` noise with probability ``1 - p``, else clutter ``CN(0, σ_clutter²)``."""
    h = np.atleast_2d(h)
    shape = h.shape
    noise = np.sqrt(model.sigma2_o / 2) * (rng.standard_normal(shape) + 1j * rng.standard_normal(shape))
    clutter = np.sqrt(model.clutter_var / 2) * (rng.standard_normal(shape) + 1j * rng.standard_normal(shape))
    is_clutter = rng.random(shape) < model.p
    return np.where(is_clutter, clutter, h + noise)


def simulate(model, steps, rng):
    """A state and observation sequence of the landmark model from its known ``X_0``.

    Returns
    -------
    states : ndarray (steps + 1, dim)
        ``X_0 .. X_T`` (packed, see :class:`~vistrack.models.landmarks.model.Landmarks`).
    obs : complex ndarray (steps, K)
        ``Y_1 .. Y_T``.
    """
    x = model.prior_mean[None].copy()
    states = [x[0]]
    for _ in range(steps):
        x = model.predict(x, rng)
        states.append(x[0])
    states = np.array(states)
    return states, sample_observations(model, model.configuration(states[1:]), rng)
