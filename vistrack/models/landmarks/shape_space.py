"""Landmark shapes in the tangent space (seed 000 §3): regular polygons, the tangent basis at a
shape (batched Gram–Schmidt), one shape step ``g``, and the initial basis."""

from __future__ import annotations

import numpy as np

__all__ = ["regular_polygon", "tangent_basis", "shape_step", "initial_basis", "per_entry"]


def regular_polygon(k, phase=0.0):
    """The regular ``k``-gon as a shape: centred, unit norm, ``z_m = e^{j(2πm/k + phase)}/√k``."""
    return np.exp(1j * (2 * np.pi * np.arange(k) / k + phase)) / np.sqrt(k)


def tangent_basis(u_prev, z_prev):
    """``U_t = g(U_{t-1}, z_{t-1})`` (§3.1), batched over leading axes.

    Gram–Schmidt of the columns of ``U_{t-1}`` against ``1_K``, ``z_{t-1}`` and
    the columns already done, done as one batched QR of ``[1_K/√K, z, U_{t-1}]``
    whose columns are rephased so that ``R`` has a positive real diagonal —
    exactly the paper's recursion, plus the explicit ``⟂ 1_K`` it keeps in exact
    arithmetic.

    Parameters
    ----------
    u_prev : complex ndarray (..., K, K-2)
    z_prev : complex ndarray (..., K)
    """
    k = z_prev.shape[-1]
    ones = np.full(z_prev.shape + (1,), 1.0 / np.sqrt(k), dtype=complex)
    a = np.concatenate([ones, z_prev[..., None], u_prev], axis=-1)
    q, r = np.linalg.qr(a)
    d = np.diagonal(r, axis1=-2, axis2=-1)
    phase = d / np.maximum(np.abs(d), 1e-300)
    return (q * phase[..., None, :])[..., 2:]


def shape_step(z_prev, u, c):
    """``z_t = f(z_{t-1}, U_t, c_t) = (1 - cᵀc)^{1/2} z_{t-1} + U_t (c_re + j c_im)`` (eq. 5)."""
    m = u.shape[-1]
    ct = c[..., :m] + 1j * c[..., m:]
    g = np.sqrt(np.clip(1.0 - np.sum(c * c, axis=-1), 0.0, None))
    return g[..., None] * z_prev + np.einsum("...km,...m->...k", u, ct)


def initial_basis(z0):
    """An orthonormal basis ``(K, K-2)`` of the tangent space at ``z0`` (⟂ z0, ⟂ 1_K).

    Starts from the Fourier vectors ``e^{2πj m k/K}/√K``, ``m = 2..K-1``: for the
    regular polygon (``m = 1``) they already are that basis.
    """
    k = len(z0)
    f = np.exp(2j * np.pi * np.outer(np.arange(k), np.arange(2, k)) / k) / np.sqrt(k)
    return tangent_basis(f, np.asarray(z0, complex))


def per_entry(v, d):
    """``v`` (a number, or ``(d,)``) as ``d`` entries ``(d,)``: a number repeated, an array copied."""
    v = np.asarray(v, float)
    return np.full(d, float(v)) if v.ndim == 0 else v.copy()
