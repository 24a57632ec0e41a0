"""A local proposal read from a per-frame map on a grid of translations (thesis 001, §4.5).

LIS perturbs the prediction ``X_t`` to ``Z_t ~ q(.) g(X_t - .) / alpha``. Here ``q`` is a
map over translations that the model computes once per frame (``model.proposal_map``), read
bilinearly at the centres ``c_j = u + σ o_j`` of a grid of cells around each particle's
translation ``u`` (``o_j``: the unit grid of a Gaussian :class:`~vistrack.proposals.Window`,
``σ``: the particle's window std). A cell is drawn ``∝ q(c_j) g(σ o_j)`` and ``Z`` uniformly
inside it, so the sampling density is ``h(Z) = q(c_j) g(σ o_j) / alpha_hat`` with
``alpha_hat = Σ_k q(c_k) g(σ o_k) |cell|``. The proper LIS weight
``r(Z) K(Z|.) g(X - Z) / (K(X|.) h(Z))`` is LIS's ``alpha r / q · K(Z)/K(X)`` with
``log_alpha = log alpha_hat + log g(X - Z)`` and ``log_q = log q(c_j) + log g(σ o_j)``,
however coarse the grid or rough the map.

The cell is drawn by inversion of each row's cumulative ``q g`` with one uniform per particle
(``rng.random((N, 3))``: the cell, then the point in it; the same distribution as Gumbel-max with
one draw per cell, with 81 times fewer ``log`` pairs).

With the compiled kernels (:mod:`vistrack.kernels`), a model whose ``q`` is a map read
bilinearly (``proposal_work``, ``proposal_qmap`` and ``proposal_tempering``, as the box model's)
is sampled in two compiled calls (:func:`~vistrack.kernels.map_draws.grid_points`,
:func:`~vistrack.kernels.map_draws.map_sample`) from the same draws, and a model with ``lis_step``
runs LIS's whole proposal step itself (:meth:`MapProposal.propose`).
"""

from __future__ import annotations

import numpy as np

from .. import kernels
from ..core.hooks import FusedLISStep, ProposalMap, offers
from ..core.particles import logsumexp
from ..core.transition import Transition

__all__ = ["MapProposal", "categorical_rows", "inverse_cdf_rows"]

_LOG2PI = np.log(2 * np.pi)


def categorical_rows(log_p, rng):
    """One index per row of ``log_p (N, K)`` drawn ∝ ``exp(log_p)`` (Gumbel-max)."""
    return np.argmax(log_p + rng.gumbel(size=log_p.shape), axis=1)


def inverse_cdf_rows(log_p, u):
    """One index per row of ``log_p (N, K)`` drawn ∝ ``exp(log_p)`` by inversion: the first ``k``
    whose cumulative sum exceeds ``u (N,)`` (uniforms) times the row's total."""
    p = np.exp(log_p - log_p.max(axis=1, keepdims=True))
    c = np.cumsum(p, axis=1)
    return np.minimum(np.sum(c <= u[:, None] * c[:, -1:], axis=1), log_p.shape[1] - 1)


class MapProposal:
    """LIS local proposal on translation from a per-frame map (module docstring).

    Parameters
    ----------
    model : object
        Supplies ``local_coords(x) (N, 2)``, ``with_local(x, u)``, ``window_std(x, kernel) (N,)``
        (px) and ``proposal_log_q(obs, x, points (N, G, 2)) -> (N, G)``, the map's
        ``log q`` at translations.
    grid : int
        Cells per axis.
    truncate : float
        The grid spans ``± truncate`` window stds.
    kernel : Transition or None
        The step's kernel (:mod:`vistrack.core.transition`): its ``with_local`` moves the
        particles and the window follows its spread; ``None``: the model's ``K``.
    """

    def __init__(self, model, grid=9, truncate=2.5, kernel=None):
        self.model = model
        self.kernel = kernel
        self.with_local = model.with_local if kernel is None else kernel.with_local
        cell = 2.0 * truncate / grid
        axis = -truncate + cell * (np.arange(grid) + 0.5)
        self.offsets = np.stack(np.meshgrid(axis, axis), axis=-1).reshape(-1, 2)  # (G, 2), unit std
        self.cell = cell
        self.log_g_unit = -0.5 * np.sum(self.offsets**2, axis=1) - _LOG2PI
        self.g_unit = np.exp(self.log_g_unit)

    def sample(self, x, obs, rng, prev=None):
        """Draw ``z (N, d)`` about the predictions ``x (N, d)`` from the map on the grid (module
        docstring); returns ``(z, log_alpha (N,), log_q (N,))`` for LIS's weight. ``prev`` is unused.
        The draws: ``rng.random((N, 3))``, the cell by inversion of each row's cumulative ``q g``
        (:func:`inverse_cdf_rows`), then the point in the cell."""
        model = self.model
        if kernels.use() and offers(model, ProposalMap):
            return self._sample_map(x, obs, rng)
        u = model.local_coords(x)
        sig = model.window_std(x, self.kernel)[:, None]  # (N, 1)
        pts = u[:, None, :] + sig[..., None] * self.offsets[None]
        log_qg = model.proposal_log_q(obs, x, pts) + self.log_g_unit - 2 * np.log(sig)
        draws = rng.random((len(u), 3))
        j = inverse_cdf_rows(log_qg, draws[:, 0])
        z_u = pts[np.arange(len(u)), j] + sig * self.cell * (draws[:, 1:] - 0.5)
        d = (u - z_u) / sig
        log_g = -0.5 * np.sum(d * d, axis=1) - _LOG2PI - 2 * np.log(sig[:, 0])
        log_alpha = logsumexp(log_qg, axis=1) + 2 * np.log(self.cell * sig[:, 0]) + log_g
        log_q = log_qg[np.arange(len(u)), j]
        return self.with_local(x, z_u), log_alpha, log_q

    def propose(self, prev, obs, rng, kernel):
        """LIS's whole proposal step (:meth:`LIS.propose <vistrack.filters.lis.LIS.propose>`) where the
        model fuses it with the compiled kernels (``model.lis_step(prev, obs, rng, proposal)``, the box
        model's) for its own ``K``; ``None`` otherwise (the filter then calls the parts one by one)."""
        if not (offers(self.model, FusedLISStep) and kernels.use() and type(kernel) is Transition
                and kernel.model is self.model):
            return None
        return self.model.lis_step(prev, obs, rng, self)

    def _sample_map(self, x, obs, rng):
        """:meth:`sample` for a model whose ``q`` is its map read bilinearly (module docstring),
        compiled: the same draws, ``q g`` summed in the linear domain."""
        from ..kernels.map_draws import grid_points, map_sample

        model = self.model
        x = np.ascontiguousarray(x, dtype=float)
        n, g = len(x), len(self.offsets)
        sig = np.ascontiguousarray(model.window_std(x, self.kernel), dtype=float)
        x0, y0, f = model.proposal_work(obs)
        uw, vw = np.empty((n, g)), np.empty((n, g))
        span = grid_points(x, sig, self.offsets, x0, y0, f, uw, vw, np.empty(4))
        qmap = model.proposal_qmap(obs, x, tuple(span))
        m, u0, v0, step = qmap if qmap else (np.zeros((0, 1), np.float32), 0.0, 0.0, 1.0)
        floor = model.proposal_tempering[1]
        z_u, log_alpha, log_q = np.empty((n, 2)), np.empty(n), np.empty(n)
        map_sample(x, sig, self.offsets, self.g_unit, self.log_g_unit, float(self.cell), uw, vw, m[..., None],
                   float(u0), float(v0), float(step), float(m.min()) if qmap else 0.0, 1.0 - floor, float(floor),
                   rng.random((n, 3)), z_u, log_alpha, log_q)
        return self.with_local(x, z_u), log_alpha, log_q
