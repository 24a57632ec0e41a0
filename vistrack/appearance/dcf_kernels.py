"""The box model's correlation-filter features (:mod:`~vistrack.appearance.correlation`), compiled.

- The features' kernels (:func:`gradient_cells`, :func:`grey_gradient_cells`, :func:`orientation_cells`,
  :func:`normalised_cells`) are in :mod:`~vistrack.appearance.dcf_feature_kernels`, imported here.
- :func:`response_read` is :meth:`DCFResponse.read <vistrack.appearance.correlation.DCFResponse.read>`:
  ``np.interp`` of the log-scale, then the two nearest scale maps read bilinearly, per state in one
  pass where numpy makes some forty small calls (the same float64 arithmetic in the same order:
  equal, ``tests/models/box/test_box_dcf.py``).
- :func:`correlate` and :func:`adapt_filter` are ``CorrelationFilter.detect``'s ``Σ_k conj(A_k) Z_k / (B + λ)``
  per scale and ``CorrelationFilter.adapt``'s learning, blending and applied filter, one pass each where
  numpy makes a temporary per operation: numpy's complex products are fused multiply-adds on FMA CPUs
  (``re = fma(a_r, b_r, -(a_i b_i))``, ``im = fma(a_r, b_i, a_i b_r)``) and plain elsewhere; which, is
  probed at import (:data:`EXACT`, :data:`NUMPY_FMA`) and these do the same (equal,
  ``tests/models/box/test_box_dcf.py``); a complex divided by a real is the product with its inverse.
- :func:`correlation_draws` is the correlation proposal's draws from the response and its density
  there (``CorrelationProposal.draw`` and ``log_density``, :mod:`~vistrack.models.box.correlation_proposal`), per
  particle in one pass (the same arithmetic: equal, ``tests/models/box/test_box_dcf.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..kernels.sampling import fma, pairwise_sum
from .dcf_feature_kernels import (
    POLAR_EXACT,
    gradient_cells,
    grey_gradient_cells,
    normalised_cells,
    orientation_cells,
    polar,
)

__all__ = ["orientation_cells", "gradient_cells", "grey_gradient_cells", "polar", "POLAR_EXACT", "normalised_cells",
           "response_read", "cell_scores", "cell_probabilities", "cumulative", "correlate", "adapt_filter",
           "correlation_draws", "EXACT", "NUMPY_FMA", "NUMPY_FMA32"]


@njit(cache=True, nogil=True, error_model="numpy")
def _interp_pos(x, xp):
    """``np.interp(x, xp, arange(len(xp)))`` for one ``x`` (``xp`` ascending, at least 2 long): numpy's
    arithmetic (``arr_interp``: the slope times the offset plus the left value, the end values held)."""
    n = xp.shape[0]
    if x != x:
        return x
    if x < xp[0]:
        return 0.0
    if x >= xp[n - 1]:
        return float(n - 1)
    j = 0
    while x >= xp[j + 1]:
        j += 1
    if xp[j] == x:
        return float(j)
    slope = (float(j + 1) - float(j)) / (xp[j + 1] - xp[j])
    return slope * (x - xp[j]) + float(j)


@njit(cache=True, nogil=True, error_model="numpy")
def _bilinear_at(maps, k, u, v):
    """``_bilinear`` of :mod:`~vistrack.appearance.correlation` for one point: map ``k`` at ``(u, v)``, the four
    corners added in its order to a zero start (``0.0`` for a corner outside)."""
    h, w = maps.shape[1], maps.shape[2]
    fu, fv = math.floor(u), math.floor(v)
    a, b = u - fu, v - fv
    out = 0.0
    if not (abs(fu) < 2.0**62 and abs(fv) < 2.0**62):  # non-finite or far: numpy's index is outside too
        return out + 0.0 + 0.0 + 0.0 + 0.0
    u0, v0 = int(fu), int(fv)
    for c in range(4):
        du, dv = c & 1, c >> 1
        if c == 0:
            wt = (1 - a) * (1 - b)
        elif c == 1:
            wt = a * (1 - b)
        elif c == 2:
            wt = (1 - a) * b
        else:
            wt = a * b
        uu, vv = u0 + du, v0 + dv
        if 0 <= uu < w and 0 <= vv < h:
            out += wt * np.float64(maps[k, vv, uu])
        else:
            out += 0.0
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def response_read(maps, log_scales, centre, anchor, px, states, out):
    """``DCFResponse.read``: ``out (N,)``, the responses ``maps (S, H, W)`` float32 at the centres
    ``states[:, :2]`` (bilinear) and linear in ``states[:, 2]`` between the two nearest of the ascending
    ``log_scales (S,)`` (held beyond the ends); map pixel ``(i, j)`` of scale ``k`` at
    ``centre + ((j, i) - anchor) / px[k]``; 0 outside the maps."""
    s = log_scales.shape[0]
    for n in range(states.shape[0]):
        if s == 1:
            k0, t = 0, 0.0
        else:
            pos = _interp_pos(states[n, 2], log_scales)
            pos = min(max(pos, 0.0), float(s - 1))
            if pos != pos:
                out[n] = np.nan
                continue
            k0 = min(int(pos), s - 2)
            t = pos - k0
        acc = 0.0
        for side in range(2):
            k = min(k0 + side, s - 1)
            wk = 1 - t if side == 0 else t
            u = (states[n, 0] - centre[0]) * px[k] + anchor[0]
            v = (states[n, 1] - centre[1]) * px[k] + anchor[1]
            acc += wk * _bilinear_at(maps, k, u, v)
        out[n] = acc
    return out



@njit(cache=True, nogil=True, error_model="numpy")
def cell_scores(m, tempering, out):
    """``tempering * (y - y.max())`` of the map ``m (H, W)`` float32 as float64, flat into ``out (H W,)``
    (``DCFResponse.cell_log_p``'s numpy arithmetic: equal)."""
    h, w = m.shape
    top = -np.inf
    for i in range(h):
        for j in range(w):
            top = max(top, np.float64(m[i, j]))
    for i in range(h):
        for j in range(w):
            out[i * w + j] = tempering * (np.float64(m[i, j]) - top)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def cell_probabilities(e, floor, out):
    """``(1 - floor) * e / e.sum() + floor / e.size`` (numpy's pairwise sum, its order of operations: equal)."""
    n = e.shape[0]
    total = pairwise_sum(e, 0, n)
    keep, spread = 1.0 - floor, floor / n
    for i in range(n):
        out[i] = keep * e[i] / total + spread
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def cumulative(x, out):
    """``np.cumsum(x)`` of ``x (n,)`` float64 into ``out``: the same sequential sums, without numpy's
    generic accumulate loop (5x faster at the response's 5400 cells)."""
    if x.shape[0] == 0:
        return out
    s = out[0] = x[0]
    for i in range(1, x.shape[0]):
        s += x[i]
        out[i] = s
    return out


def _numpy_complex_fma(dtype):
    """Whether numpy's complex product of ``dtype`` is ``(fma(a_r, b_r, -(a_i b_i)), fma(a_r, b_i, a_i b_r))``
    on this CPU (its SIMD loops on FMA CPUs) rather than the plain products: probed on values where the
    two differ (exact rational arithmetic gives the fused results)."""
    from fractions import Fraction

    real = np.float64 if dtype == np.complex128 else np.float32
    rng = np.random.default_rng(0)
    a = (rng.standard_normal(64) + 1j * rng.standard_normal(64)).astype(dtype)
    b = (rng.standard_normal(64) + 1j * rng.standard_normal(64)).astype(dtype)
    got = a * b

    def fused(x, y, z):
        return real(Fraction(float(x)) * Fraction(float(y)) + Fraction(float(z)))

    same_fma = same_plain = True
    for p, q, g in zip(a, b, got):
        fma_r = fused(p.real, q.real, -(p.imag * q.imag))
        fma_i = fused(p.real, q.imag, p.imag * q.real)
        same_fma &= bool(g.real == fma_r and g.imag == fma_i)
        same_plain &= bool(g.real == p.real * q.real - p.imag * q.imag and g.imag == p.real * q.imag + p.imag * q.real)
    return True if same_fma else (False if same_plain else None)


#: numpy's complex128 / complex64 products fused (True), plain (False) or neither (None: the models keep numpy)
NUMPY_FMA, NUMPY_FMA32 = _numpy_complex_fma(np.complex128), _numpy_complex_fma(np.complex64)
_FUSED, _FUSED32 = bool(NUMPY_FMA), bool(NUMPY_FMA32)
#: whether :func:`correlate` and :func:`adapt_filter` compute numpy's products on this CPU
EXACT = NUMPY_FMA is not None and NUMPY_FMA32 is not None


@njit(cache=True, forceinline=True, error_model="numpy")
def _cmul(ar, ai, br, bi):
    """numpy's complex128 product ``(a_r + i a_i)(b_r + i b_i)`` on this CPU (:data:`NUMPY_FMA`)."""
    if _FUSED:
        return fma(ar, br, -(ai * bi)), fma(ar, bi, ai * br)
    return ar * br - ai * bi, ar * bi + ai * br


@njit(cache=True, forceinline=True, error_model="numpy")
def _abs2_32(fr, fi):
    """The real part of numpy's complex64 product ``f conj(f)`` on this CPU (:data:`NUMPY_FMA32`)."""
    if _FUSED32:
        return fma(fr, fr, fi * fi)
    return fr * fr + fi * fi


@njit(cache=True, nogil=True, error_model="numpy")
def correlate(conj_a, z, den, out):
    """``out (H, W') complex128 = Σ_k conj_a[k] z[k] / den``: ``conj_a (C, H, W') complex128``, the spectra
    ``z (C, H, W') complex64`` (as numpy promotes them), summed over ``k`` in order, divided by ``den (H, W')
    float32`` as numpy divides a complex by a real one (times ``1 / den``)."""
    c_n, h, w = z.shape
    sr, si = np.empty(w), np.empty(w)
    for i in range(h):  # a row at a time, channel by channel: each element's sum in channel order, vectorised
        a0, z0 = conj_a[0, i], z[0, i]
        for j in range(w):
            sr[j], si[j] = _cmul(a0[j].real, a0[j].imag, np.float64(z0[j].real), np.float64(z0[j].imag))
        for c in range(1, c_n):
            ac, zc = conj_a[c, i], z[c, i]
            for j in range(w):
                pr, pi = _cmul(ac[j].real, ac[j].imag, np.float64(zc[j].real), np.float64(zc[j].imag))
                sr[j] += pr
                si[j] += pi
        for j in range(w):
            scl = 1.0 / np.float64(den[i, j])
            out[i, j] = complex(sr[j] * scl, si[j] * scl)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def adapt_filter(f, conj_g, a, b, a0, b0, rate, anchor, lam, conj_applied, den):
    """``CorrelationFilter.adapt`` on the spectra ``f (C, H, W') complex64`` of the new patch, in place:
    ``a = (1 - η) a + η conj(G) f`` (complex128) and ``b = (1 - η) b + η Σ_k |f_k|²`` (float32, the
    squares as numpy's complex64 product and summed over ``k`` in order); then the applied filter
    ``(1 - γ) a + γ a0`` conjugated into ``conj_applied`` and ``(1 - γ) b + γ b0 + λ`` (float32) into ``den``
    (what ``detect`` divides by)."""
    c_n, h, w = f.shape
    r1, r = 1.0 - rate, rate
    g1, g = 1.0 - anchor, anchor
    r1f, rf, g1f, gf, lamf = np.float32(r1), np.float32(r), np.float32(g1), np.float32(g), np.float32(lam)
    sq = np.empty(w, np.float32)
    for i in range(h):  # a row at a time, channel by channel (each element's squares summed in channel order)
        for c in range(c_n):
            fc, ac, a0c, out = f[c, i], a[c, i], a0[c, i], conj_applied[c, i]
            for j in range(w):
                fr, fi = fc[j].real, fc[j].imag
                nr, ni = _cmul(conj_g[i, j].real, conj_g[i, j].imag, np.float64(fr), np.float64(fi))
                ar = r1 * ac[j].real + r * nr
                ai = r1 * ac[j].imag + r * ni
                ac[j] = complex(ar, ai)
                pr = g1 * ar + g * a0c[j].real
                pi = g1 * ai + g * a0c[j].imag
                out[j] = complex(pr, -pi)
                e = _abs2_32(fr, fi)  # (f conj(f)).real as numpy's complex64 product
                sq[j] = e if c == 0 else sq[j] + e
        for j in range(w):
            bb = r1f * b[i, j] + rf * sq[j]
            b[i, j] = bb
            den[i, j] = (g1f * bb + gf * b0[i, j]) + lamf
    return a


@njit(cache=True, nogil=True, error_model="numpy")
def correlation_draws(x, u, e, beta, cum, log_p, ox, oy, a, w, h, best, sd, two_log_a, log_sd, log_sqrt_2pi, z,
                      log_qy):
    """``CorrelationProposal``'s draws and density: ``z (N, d)`` = ``x`` with the rows where ``u[:, 0] < beta``
    drawn from the response (the cell by inversion of ``cum`` at ``u[:, 1]``, the first cumulative sum above
    it, as ``searchsorted(side="right")``; the point uniform in it from ``u[:, 2:4]``; the log-scale
    ``best + sd e``), and ``log_qy (N,)`` = ``log q_Y(z)``: ``log_p`` of the cell of ``z`` (a ``w`` wide,
    ``h`` high grid of side ``a`` with its cell ``(0, 0)`` centred at ``(ox, oy)``) minus ``2 log a``,
    ``d² / 2`` (``d = (l - best) / sd``), ``log √(2π)`` and ``log sd`` in that order; ``-inf`` outside."""
    n_c = cum.shape[0]
    total = cum[n_c - 1]
    for n in range(x.shape[0]):
        for k in range(x.shape[1]):
            z[n, k] = x[n, k]
        if u[n, 0] < beta:
            v = u[n, 1] * total
            lo, hi = 0, n_c
            while lo < hi:  # the first index whose cumulative sum is above v
                mid = (lo + hi) // 2
                if cum[mid] <= v:
                    lo = mid + 1
                else:
                    hi = mid
            k = min(lo, n_c - 1)
            z[n, 0] = ox + a * (np.float64(k % w) + u[n, 2] - 0.5)
            z[n, 1] = oy + a * (np.float64(k // w) + u[n, 3] - 0.5)
            z[n, 2] = best + sd * e[n]
        fj = math.floor((z[n, 0] - ox) / a + 0.5)
        fi = math.floor((z[n, 1] - oy) / a + 0.5)
        if not (0.0 <= fj < w and 0.0 <= fi < h):
            log_qy[n] = -np.inf
            continue
        d = (z[n, 2] - best) / sd
        log_qy[n] = (((log_p[int(fi) * w + int(fj)] - two_log_a) - 0.5 * (d * d)) - log_sqrt_2pi) - log_sd
    return z
