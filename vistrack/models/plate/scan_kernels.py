"""The plate LIS proposal's draws (:mod:`~vistrack.models.plate.proposal`), compiled.

- :func:`draw_cells` is ``PlateLISProposal._conditional`` given its Gumbel draws: a cell per row
  ∝ ``exp(β v)`` by Gumbel-max, and the cell's log probability from numpy's log-sum-exp
  (``max`` shift, ``exp``, a pairwise sum as ``np.sum``'s, ``log``): equal to the numpy path.
- :func:`line_scans` is ``PlateLISProposal._line_scans`` for all particles in one call: the
  vertical scan's ``log r^h`` at the cell centres (the pixel-set means of
  :func:`~vistrack.models.plate.kernels.means_at`, ``log1p``, the coefficients summed in the numpy
  path's order), its Gaussian prior factor, a cell drawn as :func:`draw_cells` draws it and a
  point uniform in it, then the horizontal scan at the drawn ``w``: equal to the numpy path given
  the same Gumbel and uniform draws, which the caller makes with the generator in the numpy
  path's order.
- :func:`sparse_draw` is ``PlateLikelihood.loglik_sparse`` followed by ``_conditional``: the
  means, ``log1p``, the coefficients' dot product summed as numpy's ``einsum`` sums it on x86-64
  (two running sums over lanes, blocks of eight taken last pair first, without FMA — found by
  matching it) and the bias, then the cells drawn as :func:`draw_cells`: equal to the numpy path
  on this machine.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...kernels.sampling import pairwise_sum
from .kernels import means_at, place, set_index

__all__ = ["draw_cells", "line_scans", "sparse_draw"]


@njit(cache=True, forceinline=True)
def _draw_row(vals, lo, k, beta, gum, tmp):
    """Row ``vals[lo:lo + k]`` (scaled by ``beta`` in place): the cell ``argmax(β v + gum)`` and
    ``β v_j - logsumexp(β v)``, numpy's arithmetic (``tmp``: k floats of scratch)."""
    m = -np.inf
    nan = False
    for i in range(k):
        v = beta * vals[lo + i]
        vals[lo + i] = v
        if v != v:
            nan = True
        elif v > m:
            m = v
    if nan:
        m = np.nan
    shift = m if np.isfinite(m) else 0.0
    for i in range(k):
        tmp[i] = np.exp(vals[lo + i] - shift)
    s = pairwise_sum(tmp, 0, k)
    lz = np.inf if m == np.inf else shift + np.log(s)
    j, best = 0, -np.inf
    for i in range(k):
        g = vals[lo + i] + gum[lo + i]
        if g != g:  # argmax takes the first NaN
            j = i
            break
        if g > best or i == 0:
            j, best = i, g
    return j, vals[lo + j] - lz


@njit(cache=True, nogil=True)
def draw_cells(vals, beta, gum, idx, lq):
    """For each row of ``vals (n, k)`` the cell ``idx[i]`` and its log probability ``lq[i]`` of
    ``PlateLISProposal._conditional`` with the Gumbel draws ``gum (n, k)``."""
    n, k = vals.shape
    flat, g = vals.reshape(-1).copy(), gum.reshape(-1)
    tmp = np.empty(k)
    for i in range(n):
        j, q = _draw_row(flat, i * k, k, beta, g, tmp)
        idx[i], lq[i] = j, q
    return idx, lq


@njit(cache=True, forceinline=True)
def _log1p32(m):
    """``log1p`` of a float32 mean as :func:`~vistrack.models.plate.likelihood.log1p32` computes it."""
    return np.float32(np.log1p(np.float64(m)))


@njit(cache=True, forceinline=True)
def _scan_value(img, base, ox, oy, tab, index, coef, n, log1p, border, buf, means):
    """``Σ_f coef[n, f] t(mean_f)`` at the placed points shifted by ``(ox, oy)``, summed from 0 in
    feature order as the numpy path's ``sum``; ``t`` is ``log1p`` (float32) or the identity."""
    pts, sets, feats = tab
    means_at(img, base, ox, oy, sets, feats, index, border, buf, means, 0)
    acc = 0.0
    for f in range(feats.shape[0]):
        m = _log1p32(means[f]) if log1p else means[f]
        acc = acc + coef[n, f] * np.float64(m)
    return acc


@njit(cache=True, forceinline=True)
def map_value(m, a, x, y):
    """The bilinear value of the map ``m`` at the frame point ``(x, y)``, as
    :func:`~vistrack.models.plate.proposal.map_values` computes it."""
    hh, ww = m.shape
    u = min(max(a[0] * x + a[1], 0.0), ww - 1.0)
    v = min(max(a[2] * y + a[3], 0.0), hh - 1.0)
    j0, i0 = int(np.floor(u)), int(np.floor(v))
    j1, i1 = min(j0 + 1, ww - 1), min(i0 + 1, hh - 1)
    fu, fv = u - j0, v - i0
    m00, m01 = np.float64(m[i0, j0]), np.float64(m[i0, j1])
    m10, m11 = np.float64(m[i1, j0]), np.float64(m[i1, j1])
    top = m00 + fu * (m01 - m00)
    bot = m10 + fu * (m11 - m10)
    return top + fv * (bot - top)


@njit(cache=True, forceinline=True)
def _one_scan(img, x, n, tab, index, base, coef, axis, centre, half, other, k, prior, sig, beta, gum, u,
              log1p, border, work, has_map, amap, a):
    """One line of :func:`line_scans` for particle ``n``: the cells along ``axis`` (0: u, 1: w) of
    ``centre ± half`` with the other coordinate at ``other``; returns the drawn coordinate, the
    log probability of its cell and the cell's width."""
    buf, means, vals, tmp = work
    for j in range(k):
        c = centre[n, axis] + ((j + 0.5) / k * 2 - 1) * half[n, axis]
        ox, oy = (c - x[n, 0], other - x[n, 1]) if axis == 0 else (other - x[n, 0], c - x[n, 1])
        v = _scan_value(img, base, ox, oy, tab, index, coef, n, log1p, border, buf, means)
        if has_map:
            v = v + (map_value(amap, a, c, other) if axis == 0 else map_value(amap, a, other, c))
        if prior:
            d = (c - centre[n, axis]) / sig[axis]
            v = v - 0.5 * (d * d)
        vals[j] = v
    j, lq = _draw_row(vals, 0, k, beta, gum[n], tmp)
    cell = 2 * half[n, axis] / k
    return centre[n, axis] + ((j + 0.5) / k * 2 - 1) * half[n, axis] + cell * (u - 0.5), lq, cell


@njit(cache=True, nogil=True)
def line_scans(img, x, tan, aspect, tab_h, coef_h, tab_v, coef_v, centre, half, k, prior, sig, beta, gum, unif,
               log1p, border, uv, log_q, has_map, amap, a):
    """``PlateLISProposal._line_scans`` of the poses ``x (n, 4)`` (``tan (n,)`` their ``tan θ``):
    ``w`` from ``r^h`` on the vertical line through ``centre (n, 2)`` (``± half[:, 1]``, ``k``
    cells), then ``u`` from ``r^v`` on the horizontal line at it; with ``prior`` each cell's value
    also takes ``-(c - centre)² / (2 sig²)`` on its axis. ``tab_h``, ``tab_v`` are the scans'
    ``(points, sets, features)`` tables, ``coef_h (n, F_h)``, ``coef_v`` their coefficients,
    ``gum (2, n, k)`` and ``unif (2, n)`` the two draws' Gumbel and uniform variates; with
    ``has_map`` each cell's value also takes the learned appearance's map ``amap`` at the cell
    centre (:func:`map_value` with ``a``). Writes the new ``uv (n, 2)`` and their ``log_q (n,)``."""
    ih, iv = set_index(tab_h[1], tab_h[2]), set_index(tab_v[1], tab_v[2])
    nf = max(tab_h[2].shape[0], tab_v[2].shape[0])
    work = (np.empty(nf * max(ih[2], iv[2]), np.float32), np.empty(nf, np.float32), np.empty(k), np.empty(k))
    base_h, base_v = np.empty((tab_h[0].shape[0], 2)), np.empty((tab_v[0].shape[0], 2))
    for n in range(x.shape[0]):
        place(tab_h[0], x[n, 0], x[n, 1], x[n, 3], tan[n], aspect, base_h)
        place(tab_v[0], x[n, 0], x[n, 1], x[n, 3], tan[n], aspect, base_v)
        w, lqh, cell_h = _one_scan(img, x, n, tab_h, ih, base_h, coef_h, 1, centre, half, centre[n, 0], k, prior,
                                   sig, beta, gum[0], unif[0, n], log1p, border, work, has_map, amap, a)
        u, lqv, cell_v = _one_scan(img, x, n, tab_v, iv, base_v, coef_v, 0, centre, half, w, k, prior, sig, beta,
                                   gum[1], unif[1, n], log1p, border, work, has_map, amap, a)
        uv[n, 0], uv[n, 1] = u, w
        log_q[n] = lqh - np.log(cell_h) + lqv - np.log(cell_v)
    return uv, log_q


@njit(cache=True, forceinline=True)
def _dot(m, coef, n, log1p):
    """``Σ_f t(m_f) coef[n, f]`` as ``np.einsum("ncf,nf->nc")`` sums a row of float32 ``t(m)``
    against float64 coefficients: two lanes (even and odd ``f``), blocks of eight added last pair
    first, separate multiply and add, then lane 0 + lane 1 onto 0."""
    nf = m.shape[0]
    a0 = a1 = 0.0
    k = 0
    while nf - k >= 8:
        for blk in range(3, -1, -1):
            i = k + 2 * blk
            v0 = _log1p32(m[i]) if log1p else m[i]
            v1 = _log1p32(m[i + 1]) if log1p else m[i + 1]
            a0 = np.float64(v0) * coef[n, i] + a0
            a1 = np.float64(v1) * coef[n, i + 1] + a1
        k += 8
    while k < nf:
        v0 = _log1p32(m[k]) if log1p else m[k]
        a0 = np.float64(v0) * coef[n, k] + a0
        if k + 1 < nf:
            v1 = _log1p32(m[k + 1]) if log1p else m[k + 1]
            a1 = np.float64(v1) * coef[n, k + 1] + a1
        k += 2
    return 0.0 + (a0 + a1)


@njit(cache=True, nogil=True)
def sparse_draw(img, pose, tan, aspect, tab, offsets, coef, bias, log1p, k, beta, gum, border, idx, lq):
    """``loglik_sparse`` of the poses ``pose (P, 4)`` (``tan (P,)``) shifted by ``offsets (P, C, 2)``
    on the point sets ``tab = (points, sets, features)`` with coefficients ``coef (P, F)`` and
    ``bias (P,)``, read as rows of ``k`` values (``P C = n k``), and a cell of each row drawn ∝
    ``exp(β v)`` with the Gumbel variates ``gum (n, k)``: writes ``idx (n,)`` and ``lq (n,)``."""
    pts, sets, feats = tab
    index = set_index(sets, feats)
    buf = np.empty(feats.shape[0] * index[2], np.float32)
    means = np.empty(feats.shape[0], np.float32)
    base = np.empty((pts.shape[0], 2))
    c_n = offsets.shape[1]
    vals = np.empty(pose.shape[0] * c_n)
    for p in range(pose.shape[0]):
        place(pts, pose[p, 0], pose[p, 1], pose[p, 3], tan[p], aspect, base)
        for c in range(c_n):
            means_at(img, base, offsets[p, c, 0], offsets[p, c, 1], sets, feats, index, border, buf, means, 0)
            vals[p * c_n + c] = _dot(means, coef, p, log1p) + bias[p]
    g = gum.reshape(-1)
    tmp = np.empty(k)
    for i in range(idx.shape[0]):
        j, q = _draw_row(vals, i * k, k, beta, g, tmp)
        idx[i], lq[i] = j, q
    return idx, lq
