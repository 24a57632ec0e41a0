"""Local likelihood sampling particle filter (thesis 001, §4.4, Figs. 4.7 and 4.11).

Predict ``X_t ~ K(.|Z_{t-1})``, perturb ``Z_t ~ r(Y_t|.) g(X_t - .) / alpha_t`` with
``alpha_t = ∫ r(Y_t|x) g(X_t - x) dx``, weight ``alpha_t K(Z_t|Z_{t-1}) / K(X_t|Z_{t-1})``.

The window ``g`` acts on the model's *local coordinates* only
(``model.local_coords`` / ``model.with_local``; e.g. translation, §4.4.3), and
the product ``r g`` has no closed form in general, so it is sampled on a local
grid of the window: a cell ``j`` is drawn with probability ``∝ r(c_j) g(o_j)``
and ``Z`` uniformly inside it. That sampling density ``h_X`` is used exactly in
the weight, ``w = r(Z) g(X - Z) K(Z|.) / (K(X|.) h_X(Z))`` with
``1 / h_X(Z) = alpha_hat / (r(c_j) g(o_j))`` and ``alpha_hat = Σ_k r(c_k) g(o_k) |cell|``:
the proposal of LIS with a piecewise-constant ``q``, so the pairs stay properly
weighted (Prop. 4.5.1) however coarse the grid; for a fine grid the correction
factor tends to one and this is Fig. 4.11.
"""

from __future__ import annotations

import numpy as np

from ..core.particles import logsumexp
from ..models.protocol import GridLikelihood, LLSModel, LocalMoves, StateSpaceModel, offers
from ..proposals import Window, categorical_rows
from .base import ParticleFilter

__all__ = ["LLS", "Window"]


class LLS(ParticleFilter):
    """LLS-based particle filter with a grid-sampled ``r g``.

    Parameters
    ----------
    window : Window or None
        The window; ``None`` asks the model (``model.lls_window(kernel)``, one per kernel).
    """

    name = "lls"
    needs = (StateSpaceModel, LocalMoves)
    #: the likelihood on a grid of the window for every particle
    memory_factor = 8
    model_parts = {"window": (LLSModel, "lls_window")}

    def __init__(self, model, window=None, **kwargs):
        super().__init__(model, **kwargs)
        self._set_part("window", window)

    def _grid_loglik(self, obs, x, u, win, kernel):
        """``log r`` at the grid cell centres ``(N, G)``. A model may supply
        ``loglik_local_grid(obs, x, offsets)`` (e.g. from measurements it has
        already made); any approximation there only changes the proposal, as
        the weight uses the exact ``r`` at the drawn point."""
        model = self.model
        if offers(model, GridLikelihood):
            return model.loglik_local_grid(obs, x, win.offsets)
        n, k = x.shape[0], win.offsets.shape[0]
        cand_u = (u[:, None, :] + win.offsets[None]).reshape(n * k, -1)
        cand = kernel.with_local(np.repeat(x, k, axis=0), cand_u)
        return model.loglik(obs, cand).reshape(n, k)

    def propose(self, prev, obs, rng, kernel):
        """Fig. 4.11 with a grid-sampled ``r g``: ``X_t ~ K``, a window cell drawn ∝ ``r(c_j) g(o_j)``
        and ``Z_t`` uniform in it; the exact sampling density enters the weight (module docstring).

        Parameters and returns as :meth:`ParticleFilter.propose`: ``prev (N, d)`` ->
        ``(new (N, d), log_incr (N,), predicted (N, d), loglik (N,))``.
        """
        model, win = self.model, self.part("window", kernel)
        x = kernel.predict(prev, rng)
        n = x.shape[0]
        u = model.local_coords(x)  # (N, m)
        log_rg = self._grid_loglik(obs, x, u, win, kernel) + win.log_g_offsets
        log_alpha = logsumexp(log_rg, axis=1) + win.log_cell
        ok = np.isfinite(log_alpha)
        j = categorical_rows(log_rg, rng)
        z_u = u + win.offsets[j] + win.cell * (rng.random(u.shape) - 0.5)
        z = kernel.with_local(x, z_u)
        ll = model.loglik(obs, z)
        log_incr = (
            log_alpha
            + ll
            + win.logpdf(u - z_u)
            - log_rg[np.arange(n), j]
            + kernel.logpdf(z, prev)
            - kernel.logpdf(x, prev)
        )
        log_incr = np.where(ok, log_incr, -np.inf)
        return z, log_incr, x, ll
