"""The contour model's LMS local search (``Contour.local_search``, thesis 001 §4.3.1), compiled in
two passes around the one matrix product ``ẑ = W_m⁺ (p̂ - p0)`` (left to numpy, whose BLAS
order of sums the track depends on):

- :func:`search_lines`: per pose, the long measurement lines placed (:func:`~.contour.place`),
  their edge strengths (:func:`~.contour.profiles`), the grid likelihood and its argmax
  (:func:`~.contour.grid`), the LMS nearest edges (:func:`~.contour.nearest_edge`), the fitted
  points ``p̂ - p0`` and ``log r`` at the prediction from the lines' middle samples
  (:func:`~.contour.loglik_profiles`);
- :func:`accept`: the ``λ`` bound and eq. 4.1's check (``Contour._accept``), with ``log r`` at the
  moved poses (:func:`~.contour.loglik`).

Both compute what the separate kernels and numpy steps compute, in the same order (equal bit for
bit, ``tests/models/contour/test_kernels_contour_search.py``), without the ``(N, M, 2)`` and ``(N, G)`` arrays
between them and the two dozen Python-level calls per frame. They release the GIL (``nogil``), so
that the decoding thread runs beside them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...kernels.sampling import pairwise_sum
from .kernels import grid_pose, line_sums, one_feature, pose_profiles

__all__ = ["search_lines", "accept"]


@njit(cache=True, nogil=True)
def _place_one(z, k, pts0, n0, q, nrm, q32, nrm32):
    """Pose ``k`` of ``z`` placed as :func:`~.contour.place` places it: float64 ``q, nrm (M, 2)`` and
    their float32 casts ``q32, nrm32 (1, M, 2)``."""
    c, s = 1.0 + z[k, 2], z[k, 3]
    r = math.hypot(c, s)
    r = r if r > 1e-12 or np.isnan(r) else 1e-12
    cn, sn = c / r, s / r
    for i in range(pts0.shape[0]):
        px, py = pts0[i, 0], pts0[i, 1]
        q[i, 0] = (z[k, 0] + c * px) - s * py
        q[i, 1] = (z[k, 1] + s * px) + c * py
        nx, ny = n0[i, 0], n0[i, 1]
        nrm[i, 0] = cn * nx - sn * ny
        nrm[i, 1] = sn * nx + cn * ny
        for a in range(2):
            q32[0, i, a] = np.float32(q[i, a])
            nrm32[0, i, a] = np.float32(nrm[i, a])


@njit(cache=True, nogil=True)
def _argmax(v):
    """``np.argmax`` of a 1-D array (the first maximum; the first NaN if any)."""
    at = 0
    for j in range(v.shape[0]):
        if v[j] != v[j]:
            return j
        if v[j] > v[at]:
            at = j
    return at


@njit(cache=True, nogil=True)
def _nearest(feats, nf, off, shift, reach):
    """:func:`~.contour.nearest_edge` of one line whose ``nf`` edge features are at samples ``feats``
    (ascending): the offset of the feature nearest to ``shift`` (the first on a tie) minus ``shift``
    when within ``reach``, else 0."""
    best, at = np.inf, -1
    for f in range(nf):
        d = abs(off[feats[f]] - shift)
        if d < best:
            best, at = d, feats[f]
    return off[at] - shift if at >= 0 and best <= reach else 0.0


@njit(cache=True, nogil=True)
def search_lines(gxy, z, pts0, n0, off, line, polarity, cos2, thresh, grid, grid32, kern, c, pairs, reach, gn, d,
                 z_t, ll_x):
    """The search up to the matrix product, for poses ``z (N, >=4)`` (module docstring).

    ``pts0, n0 (M, 2)``: the template's measurement points and normals; ``off (L,)`` float64 the
    long lines' offsets (1 px apart); ``line = (lo, kernel (n,), c)``: the likelihood's middle
    samples ``lo .. lo + n``, its Gaussian and constant; ``grid (G, 2)`` float64 the translations
    (``grid32`` its float32 cast), ``kern (L, L)`` float32 and ``c`` float32 the grid's pair kernel
    and constant, ``pairs (L, L)`` its table of two-feature terms (:func:`~.contour.grid`; NaN where not
    computed yet, filled here); ``reach`` the LMS reach. Fills ``gn (N, M, L)`` float32, ``d (N, 2M)`` (``p̂ - p0``,
    x then y), ``z_t (N, 4)`` (the poses moved by the best translation) and ``ll_x (N,)`` (``log r``
    at ``z``); returns ``d``."""
    n_lines, n_samples = pts0.shape[0], off.shape[0]
    q, nrm = np.empty((n_lines, 2)), np.empty((n_lines, 2))
    q32, nrm32 = np.empty((1, n_lines, 2), np.float32), np.empty((1, n_lines, 2), np.float32)
    off32 = off.astype(np.float32)
    start = np.float32(off[0] - 0.5)
    feats, nfeat = np.empty((n_lines, n_samples), np.int64), np.empty(n_lines, np.int64)
    idx, table = np.empty(grid.shape[0], np.int64), np.empty(n_samples, np.float32)
    stamp, single = np.full(n_samples, -1, np.int64), np.empty(n_samples, np.float32)
    for k in range(n_samples):
        single[k] = np.log1p((np.float32(0.0) + kern[0, k]) * c)
    lo, lkern, lc = line
    lsingle, v = one_feature(lkern, lc), np.empty(n_lines)
    vals = np.empty(grid.shape[0], np.float32)
    used = 0
    for n in range(z.shape[0]):
        _place_one(z, n, pts0, n0, q, nrm, q32, nrm32)
        pose_profiles(gxy, q32, nrm32, 0, off32, polarity, cos2, gn[n])
        used = grid_pose(gn[n], thresh, start, nrm32[0], grid32, kern, c, single, pairs, feats, nfeat, idx, table,
                          stamp, used, vals)
        best = _argmax(vals)
        dx, dy = grid[best, 0], grid[best, 1]
        for a in range(4):
            z_t[n, a] = z[n, a]
        z_t[n, 0] += dx
        z_t[n, 1] += dy
        for m in range(n_lines):
            nu = _nearest(feats[m], nfeat[m], off, nrm[m, 0] * dx + nrm[m, 1] * dy, reach)
            d[n, m] = ((q[m, 0] + dx) + nu * nrm[m, 0]) - pts0[m, 0]
            d[n, n_lines + m] = ((q[m, 1] + dy) + nu * nrm[m, 1]) - pts0[m, 1]
        line_sums(gn[n], lo, lkern.shape[0], thresh, lkern, lc, lsingle, v)
        ll_x[n] = pairwise_sum(v, 0, n_lines)
    return d


@njit(cache=True, nogil=True)
def accept(gxy, states, z_hat, z_else, lam, pts0, n0, off, polarity, cos2, thresh, kern, c, check, ll_x, cand, ll):
    """``Contour._accept`` after the LMS fit: ``cand`` (a copy of ``states``) gets ``z_hat`` where
    within ``lam (4,)`` of the prediction in every coordinate, else ``z_else``; ``ll`` its ``log r``
    on the lines at ``off (L,)`` float32 (Gaussian ``kern``, constant ``c``); with ``check``, a move
    that lowers ``log r`` below ``ll_x`` (at the prediction) goes back to the prediction."""
    n_lines = pts0.shape[0]
    q, nrm = np.empty((n_lines, 2)), np.empty((n_lines, 2))
    q32, nrm32 = np.empty((1, n_lines, 2), np.float32), np.empty((1, n_lines, 2), np.float32)
    prof = np.empty((n_lines, off.shape[0]), np.float32)
    single, v = one_feature(kern, c), np.empty(n_lines)
    for n in range(states.shape[0]):
        near = True
        for a in range(4):
            near = near and abs(z_hat[n, a] - states[n, a]) <= lam[a]
        for a in range(4):
            cand[n, a] = z_hat[n, a] if near else z_else[n, a]
        _place_one(cand, n, pts0, n0, q, nrm, q32, nrm32)
        pose_profiles(gxy, q32, nrm32, 0, off, polarity, cos2, prof)
        line_sums(prof, 0, off.shape[0], thresh, kern, c, single, v)
        ll[n] = pairwise_sum(v, 0, n_lines)
        if check and ll[n] < ll_x[n]:
            for a in range(states.shape[1]):
                cand[n, a] = states[n, a]
            ll[n] = ll_x[n]
    return cand, ll
