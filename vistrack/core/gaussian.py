"""Batched Gaussian densities and products of Gaussians (thesis 001, Appendix D).

Arrays carry any number of leading batch axes: means ``(..., m)``, covariances
``(..., m, m)``. Everything is computed through Cholesky factors, which stays
accurate for the very anisotropic proposals of the bearings problem.
"""

from __future__ import annotations

import numpy as np

from .particles import logsumexp

__all__ = ["diag_logpdf", "mvn_logpdf", "mvn_sample", "gaussian_product", "gm_logpdf"]

_LOG2PI = np.log(2.0 * np.pi)


def _solve_lower(L, b):
    """``L^{-1} b`` for batched lower-triangular ``L (..., m, m)`` and ``b (..., m)``."""
    m = L.shape[-1]
    if m == 1:
        return b / L[..., 0, :]
    if m == 2:
        y0 = b[..., 0] / L[..., 0, 0]
        y1 = (b[..., 1] - L[..., 1, 0] * y0) / L[..., 1, 1]
        return np.stack([y0, y1], axis=-1)
    return np.linalg.solve(L, b[..., None])[..., 0]


def _cholesky(cov):
    """Batched Cholesky factor; closed form for 1x1 and 2x2 (numpy's call overhead
    dominates for the small batches of a particle filter)."""
    m = cov.shape[-1]
    if m == 1:
        return np.sqrt(cov)
    if m == 2:
        l00 = np.sqrt(cov[..., 0, 0])
        l10 = cov[..., 1, 0] / l00
        l11 = np.sqrt(cov[..., 1, 1] - l10 * l10)
        L = np.zeros(cov.shape)
        L[..., 0, 0], L[..., 1, 0], L[..., 1, 1] = l00, l10, l11
        return L
    return np.linalg.cholesky(cov)


def _inv_spd(s):
    """Batched inverse of symmetric positive-definite matrices (closed form up to 2x2)."""
    m = s.shape[-1]
    if m == 1:
        return 1.0 / s
    if m == 2:
        a, b, c = s[..., 0, 0], s[..., 0, 1], s[..., 1, 1]
        det = a * c - b * b
        inv = np.empty(s.shape)
        inv[..., 0, 0], inv[..., 1, 1] = c / det, a / det
        inv[..., 0, 1] = inv[..., 1, 0] = -b / det
        return inv
    return np.linalg.inv(s)


def diag_logpdf(x, mean, std):
    """Log-density of ``N(mean, diag(std²))`` at ``x (..., d)``, over the last axis.

    ``mean`` and ``std`` broadcast against ``x`` (``std`` per coordinate ``(d,)`` or per
    row ``(..., d)``); returns ``(...,)``.
    """
    e = (x - mean) / std
    return -0.5 * np.sum(e * e, axis=-1) - np.sum(np.log(std), axis=-1) - 0.5 * e.shape[-1] * _LOG2PI


def mvn_logpdf(x, mean, cov):
    """Log-density of ``N(mean, cov)`` at ``x``; broadcasts over leading axes."""
    L = _cholesky(cov)
    z = _solve_lower(L, np.asarray(x) - mean)
    m = z.shape[-1]
    logdet = 2.0 * np.sum(np.log(np.diagonal(L, axis1=-2, axis2=-1)), axis=-1)
    return -0.5 * (np.sum(z * z, axis=-1) + logdet + m * _LOG2PI)


def mvn_sample(mean, cov, rng):
    """One draw from each ``N(mean[...], cov[...])``, shape of ``mean``."""
    L = _cholesky(cov)
    e = rng.standard_normal(np.shape(mean))
    return mean + np.einsum("...ij,...j->...i", L, e)


def gaussian_product(mu1, cov1, mu2, cov2):
    """Product of two Gaussian densities (Appendix D).

    ``N(x; mu1, cov1) N(x; mu2, cov2) = c N(x; mu, cov)`` with
    ``cov = (cov1^-1 + cov2^-1)^-1``, ``mu = cov cov1^-1 mu1 + cov cov2^-1 mu2`` and
    ``c = N(mu1; mu2, cov1 + cov2)`` — the normalising factor of App. D,
    ``((2 pi)^d |S1||S2|/|S|)^(-1/2) exp(-K/2)``, written in its stable form.

    Returns
    -------
    mu : ndarray (..., m)
    cov : ndarray (..., m, m)
    log_c : ndarray (...)
    """
    s = cov1 + cov2
    log_c = mvn_logpdf(mu1, mu2, s)
    # gain form: cov = cov1 - cov1 s^-1 cov1, mu = mu1 + cov1 s^-1 (mu2 - mu1)
    gain = cov1 @ _inv_spd(s)
    mu = mu1 + np.einsum("...ij,...j->...i", gain, mu2 - mu1)
    cov = cov1 - gain @ cov1
    cov = 0.5 * (cov + np.swapaxes(cov, -1, -2))
    return mu, cov, log_c


def gm_logpdf(x, log_p, mu, cov):
    """Log-density of a Gaussian mixture at ``x``.

    Parameters
    ----------
    x : ndarray (..., m)
    log_p : ndarray (..., n)    log mixture weights (normalised)
    mu : ndarray (..., n, m)
    cov : ndarray (..., n, m, m)
    """
    return logsumexp(log_p + mvn_logpdf(np.asarray(x)[..., None, :], mu, cov), axis=-1)
