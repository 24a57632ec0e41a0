"""The bearings ξ proposal's move and first stage in one loop (:mod:`vistrack.models.bearings.xi`).

Per particle and ship, the same arithmetic as :class:`~vistrack.models.bearings.xi.XiProposal`'s
numpy path (``frame``, ``parts``, ``mixture``, ``_log_mix``), on scalars: about 150 numpy calls
per LIS step become one. The uniforms and the normal quantiles come from the caller (the same
draws as the numpy path). Equal to it within 1e-12 relative (``tests/models/bearings/test_bearings_xi.py``):
``math``'s transcendental functions and numpy's may differ in the last bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .laplace_parts import laplace_parts

__all__ = ["xi_move", "xi_look_ahead"]

_LOG_SQRT_2PI = 0.5 * math.log(2 * math.pi)


@njit(cache=True, nogil=True)
def _logaddexp(x, y):
    hi = max(x, y)
    return hi + math.log1p(math.exp(min(x, y) - hi))


#: the ξ proposal's Laplace parts, compiled from the numpy path's own function
_parts = njit(cache=True)(laplace_parts)


@njit(cache=True, nogil=True)
def _conditional(x, prev, i, k, ck, sk, idx, prior, s_k, first):
    """``a, u, m, s`` of ``XiProposal.frame`` for particle ``i``, ship ``k``; ``idx`` the
    ``(4, M)`` indices of x1, x3, v1, v3, ``prior`` the ``(4, M)`` prior means and variances of
    x1, x3."""
    px, py = x[i, idx[0, k]], x[i, idx[1, k]]
    a, u = px * ck + py * sk, py * ck - px * sk
    if first:
        mx, my, vx, vy = prior[0, k], prior[1, k], prior[2, k], prior[3, k]
        vdd, vdn = vx * ck * ck + vy * sk * sk, (vy - vx) * ck * sk
        m = my * ck - mx * sk + vdn / vdd * (a - mx * ck - my * sk)
        return a, u, m, math.sqrt(vx * sk * sk + vy * ck * ck - vdn * vdn / vdd)
    qx = prev[i, idx[0, k]] + prev[i, idx[2, k]]
    qy = prev[i, idx[1, k]] + prev[i, idx[3, k]]
    return a, u, qy * ck - qx * sk, s_k


@njit(cache=True, nogil=True)
def xi_move(x, prev, c, sn, w0, w1, gz, gam, s_k, first, idx, prior):
    """``(z, log_alpha, log_q)`` of ``XiProposal.sample``: ``x, prev (N, 4M)``, ``c, sn (M,)`` the
    rays, ``w0, w1 (N, M)`` uniforms, ``gz (N, M)`` their normal quantiles ``ndtri(w1)``."""
    n, nm = x.shape[0], c.shape[0]
    z = x.copy()
    log_alpha, log_q = np.zeros(n), np.zeros(n)
    for i in range(n):
        for k in range(nm):
            ck, sk = c[k], sn[k]
            a, u, m, s = _conditional(x, prev, i, k, ck, sk, idx, prior, s_k, first)
            a = max(a, 1e-12)
            log_m1, log_m2, u_b, s_b = _parts(a, m, s, gam)
            log_p1 = -_logaddexp(0.0, log_m2 - log_m1)
            h = 2.0 / (gam * a) ** 2 + 1.0 / (s * s)
            d0 = math.atan(m / (s * s * h * a))
            g = math.sqrt(2.0 / h) / a
            lo, hi = math.atan((-0.5 * math.pi - d0) / g), math.atan((0.5 * math.pi - d0) / g)
            if w0[i, k] < math.exp(log_p1):
                uz = a * math.tan(d0 + g * math.tan(lo + w1[i, k] * (hi - lo)))
            else:
                uz = u_b + s_b * gz[i, k]
            e = (math.atan(uz / a) - d0) / g
            log_t = math.log(a / (g * (hi - lo) * (a * a + uz * uz))) - math.log1p(e * e)
            zb, za = (uz - u_b) / s_b, (u - m) / s
            log_n = log_m2 - log_m1 + log_p1 - 0.5 * zb * zb - math.log(s_b) - _LOG_SQRT_2PI
            log_q[i] += _logaddexp(log_p1 + log_t, log_n)
            log_alpha[i] += -0.5 * za * za - math.log(s) - _LOG_SQRT_2PI
            du = uz - u
            z[i, idx[0, k]] -= du * sk
            z[i, idx[1, k]] += du * ck
            if not first:  # velocities follow: Δv = 2 Δp (on the support of K)
                z[i, idx[2, k]] -= 2 * du * sk
                z[i, idx[3, k]] += 2 * du * ck
    return z, log_alpha, log_q


@njit(cache=True, nogil=True)
def xi_look_ahead(prev, c, sn, gam, s_k, idx):
    """``XiProposal.look_ahead`` under ``K``: ``log p̂(y | Z_{t-1}) (N,)`` for ``prev (N, 4M)``."""
    n, nm = prev.shape[0], c.shape[0]
    out = np.zeros(n)
    for i in range(n):
        for k in range(nm):
            qx = prev[i, idx[0, k]] + prev[i, idx[2, k]]
            qy = prev[i, idx[1, k]] + prev[i, idx[3, k]]
            a = max(qx * c[k] + qy * sn[k], 1e-12)
            log_m1, log_m2, _, _ = _parts(a, qy * c[k] - qx * sn[k], s_k, gam)
            out[i] += _logaddexp(log_m1, log_m2)
    return out
