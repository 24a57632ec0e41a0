"""The background-aware filter's ADMM steps per frequency, compiled (:mod:`~vistrack.models.box.bacf`).

:func:`g_step` is the ``ĝ`` update (Sherman–Morrison per frequency over the channels) and
:func:`l_step` the multipliers' update, each one pass over the spectra where numpy makes a dozen
temporaries; the Fourier transforms between them stay with scipy. The same arithmetic as
:meth:`BackgroundAwareFilter._solve_numpy <vistrack.models.box.bacf.BackgroundAwareFilter>` up to the order of
complex operations (equal to 1e-12 relative, ``tests``).
"""

from __future__ import annotations

from numba import njit

__all__ = ["g_step", "l_step", "conj_products"]


@njit(cache=True, nogil=True, error_model="numpy")
def g_step(xf, sxx, yf, lf, h, T, mu, g):
    """``g = (1/(Tμ)) ŷ x̂ - l/μ + h - x̂ [(1/(Tμ)) S_xx ŷ - S_lx / μ + S_hx] / (S_xx + Tμ)`` with
    ``S_lx = Σ_c conj(x̂_c) l_c`` and ``S_hx = Σ_c conj(x̂_c) h_c``; arrays ``(C, H, W2)`` complex, ``sxx`` and
    ``yf`` ``(H, W2)``."""
    nc, nh, nw = xf.shape
    inv_tmu = 1.0 / (T * mu)
    inv_mu = 1.0 / mu
    for i in range(nh):
        for j in range(nw):
            slx = 0j
            shx = 0j
            for c in range(nc):
                xc = xf[c, i, j].conjugate()
                slx += xc * lf[c, i, j]
                shx += xc * h[c, i, j]
            s = sxx[i, j]
            y = yf[i, j]
            common = (inv_tmu * s * y - inv_mu * slx + shx) / (s + T * mu)
            for c in range(nc):
                x = xf[c, i, j]
                g[c, i, j] = inv_tmu * y * x - inv_mu * lf[c, i, j] + h[c, i, j] - x * common
    return g


@njit(cache=True, nogil=True, error_model="numpy")
def l_step(lf, g, h, mu, out):
    """``l + μ (g - h)`` into ``out`` (may be ``lf``); and ``μ g + l_new`` is not formed here."""
    nc, nh, nw = lf.shape
    for c in range(nc):
        for i in range(nh):
            for j in range(nw):
                out[c, i, j] = lf[c, i, j] + mu * (g[c, i, j] - h[c, i, j])
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def conj_products(g, zf, out):
    """``Σ_c conj(g_c) ẑ_{s,c}`` for every scale ``s``: ``g (C, H, W2)``, ``zf (S, C, H, W2)`` -> ``out (S, H, W2)``."""
    ns, nc, nh, nw = zf.shape
    for s in range(ns):
        for i in range(nh):
            for j in range(nw):
                acc = 0j
                for c in range(nc):
                    acc += g[c, i, j].conjugate() * zf[s, c, i, j]
                out[s, i, j] = acc
    return out
