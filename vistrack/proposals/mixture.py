"""Gauss-mixture local proposal with a Gaussian window (thesis 001, Fig. 4.17, App. D)."""

from __future__ import annotations

import numpy as np

from ..core.gaussian import gaussian_product, gm_logpdf, mvn_sample
from ..core.particles import logsumexp

__all__ = ["GaussMixtureProposal"]


class GaussMixtureProposal:
    """Gauss-mixture local proposal with a Gaussian window (Fig. 4.17).

    The model supplies ``local_mixture(obs, x) -> (log_p (N, B, n), mu (N, B, n, k),
    cov (N, B, n, k, k))``: ``q`` is a product over ``B`` independent factors
    (e.g. ships, §4.5.5), each an ``n``-component Gauss mixture over ``k`` of the
    local coordinates (``local_coords`` gives ``(N, B*k)``, factor-major). For
    every particle and factor: ``C_i = (Σ_i^-1 + Σ_g^-1)^-1``,
    ``ν_i = C_i Σ_g^-1 x + C_i Σ_i^-1 μ_i``, ``L_i = p_i N(μ_i; x, Σ_i + Σ_g)``
    (eqs. 4.7–4.9), ``alpha = Σ_i L_i``; draw ``i ∝ L_i`` then ``Z ~ N(ν_i, C_i)``.
    With a product window the factors are sampled independently, and
    ``alpha`` and ``q(Z)`` are the products over factors.

    Parameters
    ----------
    model : object
    window_cov : array_like of shape (k, k) or (B, k, k)
        Covariance ``Σ_g`` of the Gaussian window on one factor (or per factor).
    kernel : Transition or None
        The step's kernel (:mod:`vistrack.core.transition`), whose ``with_local`` moves the
        particles; ``None``: the model's ``K``.
    """

    def __init__(self, model, window_cov, kernel=None):
        self.model = model
        self.with_local = model.with_local if kernel is None else kernel.with_local
        self.window_cov = np.asarray(window_cov, dtype=float)

    def sample(self, x, obs, rng, prev=None):
        """Draw ``z (N, d)`` about the predictions ``x (N, d)`` from ``q g(x - .) / α`` (eqs. 4.7–4.9);
        returns ``(z, log_alpha (N,), log_q (N,))`` for LIS's weight. ``prev`` is unused.
        """
        model = self.model
        log_p, mu, cov = model.local_mixture(obs, x)
        n, b, _, k = mu.shape
        u = model.local_coords(x).reshape(n, b, 1, k)
        win = self.window_cov if self.window_cov.ndim == 2 else self.window_cov[:, None]
        nu, c, log_norm = gaussian_product(mu, cov, u, win)
        log_l = log_p + log_norm  # (N, B, n)
        log_alpha = np.sum(logsumexp(log_l, axis=-1), axis=1)
        ok = np.isfinite(log_alpha)
        if log_l.shape[-1] == 1:
            nu, c = nu[:, :, 0], c[:, :, 0]
        else:
            i = np.argmax(log_l + rng.gumbel(size=log_l.shape), axis=-1)[..., None, None]
            nu = np.take_along_axis(nu, i, axis=2)[:, :, 0]
            c = np.take_along_axis(c, i[..., None], axis=2)[:, :, 0]
        z_u = mvn_sample(nu, c, rng)  # (N, B, k)
        log_q = np.sum(gm_logpdf(z_u, log_p, mu, cov), axis=1)
        log_alpha = np.where(ok, log_alpha, -np.inf)
        return self.with_local(x, z_u.reshape(n, b * k)), log_alpha, log_q
