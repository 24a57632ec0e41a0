"""Shared by the proper-weighting tests: many independent one-step runs of a filter from one particle
set, each with its own seeded generator (``default_rng(r)`` for run ``r``), and a statistic of each."""

import numpy as np

from vistrack.core.gaussian import gaussian_product


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


def exact_moments(model, prev=None, weights=None):
    """The :class:`~vistrack.models.toy.AR2Toy`'s closed form: ``∫ h(X_t) r K_1(. | X_{t-1}) p(dX_{t-1})`` for
    ``p = Σ_l weights_l δ(prev_l)`` (``prev`` ``None``: ``∫ h r p_0``, the first step) and ``h = 1, u_t, u_t²,
    u_{t-1}, u_t u_{t-1}`` and (``rest``) ``v_t, v_t u_{t-1}``; a dict."""
    if prev is None:
        m, var, weights = model.init_pose[None], model.prior_var, np.ones(1)
    else:
        m, var = model.predict_mean(np.asarray(prev, float))[:, :model.k], model.q  # (C, k)
    mu, cov, log_c = gaussian_product(model.mu[:, None, None], model.var[:, None, None, None],
                                      m[None, :, :1], np.full((1, len(m), 1, 1), var))
    c = np.exp(model.log_p[:, None] + log_c) * np.asarray(weights)[None]  # (I, C)
    mean_u, mean_u2 = mu[..., 0], mu[..., 0] ** 2 + cov[..., 0, 0]
    u1 = mean_u if prev is None else np.asarray(prev)[None, :, 0]  # p_0 starts at rest
    out = {"1": c.sum(), "u": np.sum(c * mean_u), "u2": np.sum(c * mean_u2), "hist": np.sum(c * u1),
           "u_hist": np.sum(c * (mean_u2 if prev is None else mean_u * u1))}
    if model.k == 2:
        out["v"] = np.sum(c * m[:, 1])
        out["v_hist"] = np.sum(c * m[:, 1] * u1)
    return out
