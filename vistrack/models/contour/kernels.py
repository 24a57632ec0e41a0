"""The contour model's measurement lines (:mod:`~vistrack.models.contour.model`), compiled.

Shapes: ``N`` poses, ``M`` lines, ``L`` samples per line. ``gxy (H, W, 2)`` float32 is the
gradient map (:meth:`~vistrack.appearance.features.FeatureMaps.gradient`); points ``q`` and unit normals
``nrm`` ``(N, M, 2)`` are float32, as the numpy path casts them; offsets ``off (K, L)`` float32
with ``K`` 1 (shared) or ``N`` (per pose).

- :func:`profiles` is ``Contour.edge_profiles`` (samples bit for bit those of ``cv2.remap``, the
  same float32 arithmetic): equal to the numpy path.
- :func:`loglik` and :func:`loglik_profiles` are ``Contour._loglik_from_profiles`` of the
  profiles (fused: no ``(N, M, L)`` array): the same edge features; the sum of the Gaussian
  kernel over a line's features in index order (numpy's matrix product may add three or more in
  another order) and the sum over lines in numpy's order, so within a few ulps (1e-12 relative).
- :func:`grid` is ``Contour._grid_from_peaks`` without the ``(N, M, L) @ (L, L)`` product: each
  line's smoothed feature train is summed at the samples the grid reads only. The float32 sums
  may differ from BLAS's in the last bits (1e-5 relative).
- :func:`nearest_edge` is the LMS step of ``Contour.local_search``: equal to the numpy path.

The entry points release the GIL (``nogil``): the decoding thread of ``vistrack run`` runs beside them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...kernels.sampling import corner, lerp4, pairwise_sum

__all__ = ["profiles", "loglik", "loglik_profiles", "grid", "nearest_edge", "place", "pose_profiles", "one_feature",
           "line_sums", "grid_pose"]

_ZERO = np.float32(0.0)


@njit(cache=True, forceinline=True)
def _inside(w, h, x, y):
    """Whether the four pixels ``cv2.remap`` reads about float32 point ``(x, y)`` lie in a ``w x h`` map."""
    ix, iy, _, _ = corner(x, y)
    return 0 <= ix < w - 1 and 0 <= iy < h - 1


@njit(cache=True, forceinline=True)
def _edge(g0, g1, nx, ny, polarity, cos2):
    """Edge strength of gradient ``(g0, g1)`` along the normal (``Contour.edge_profiles``)."""
    gn = g0 * nx
    gn += g1 * ny
    if polarity != 0:
        gn *= np.float32(polarity)
        if gn < 0:
            gn = _ZERO
    else:
        gn = abs(gn)
    if gn * gn < (g0 * g0 + g1 * g1) * cos2:
        gn = _ZERO
    return gn


@njit(cache=True, nogil=True)
def pose_profiles(gxy, q, nrm, n, off, polarity, cos2, out):
    """Pose ``n``'s edge strengths ``out (M, L)`` along its lines (``Contour.edge_profiles``). A line
    whose two ends read inside the map reads inside everywhere (the corners are monotone along
    it) and takes the unchecked loop (no array passed to a function per sample: numba would
    count references on every call)."""
    h, w = gxy.shape[0], gxy.shape[1]
    p = gxy.reshape(-1)
    row, two, one = np.uint64(w * 2), np.uint64(2), np.uint64(1)
    n_samples = off.shape[0]
    lo, hi = off[0], off[n_samples - 1]
    for m in range(q.shape[1]):
        qx, qy, nx, ny = q[n, m, 0], q[n, m, 1], nrm[n, m, 0], nrm[n, m, 1]
        if _inside(w, h, qx + nx * lo, qy + ny * lo) and _inside(w, h, qx + nx * hi, qy + ny * hi):
            for k in range(n_samples):  # finite and inside: corner() without its checks
                xi = int(np.rint((qx + nx * off[k]) * np.float32(32.0)))
                yi = int(np.rint((qy + ny * off[k]) * np.float32(32.0)))
                ix, iy = xi >> 5, yi >> 5
                ax, ay = np.float32(xi & 31) * np.float32(0.03125), np.float32(yi & 31) * np.float32(0.03125)
                bx, by = np.float32(1.0) - ax, np.float32(1.0) - ay
                w00, w01, w10, w11 = by * bx, by * ax, ay * bx, ay * ax
                i = np.uint64(iy) * row + np.uint64(ix) * two
                g0 = p[i] * w00 + p[i + two] * w01 + p[i + row] * w10 + p[i + row + two] * w11
                i += one
                g1 = p[i] * w00 + p[i + two] * w01 + p[i + row] * w10 + p[i + row + two] * w11
                out[m, k] = _edge(g0, g1, nx, ny, polarity, cos2)
        else:
            for k in range(n_samples):
                ix, iy, ax, ay = corner(qx + nx * off[k], qy + ny * off[k])
                g0 = lerp4(gxy, ix, iy, ax, ay, 0, _ZERO, _ZERO)
                g1 = lerp4(gxy, ix, iy, ax, ay, 1, _ZERO, _ZERO)
                out[m, k] = _edge(g0, g1, nx, ny, polarity, cos2)


@njit(cache=True, nogil=True)
def profiles(gxy, q, nrm, off, polarity, cos2, out):
    """Edge strengths ``out (N, M, L)`` float32 along the lines (module docstring)."""
    for n in range(q.shape[0]):
        pose_profiles(gxy, q, nrm, n, off[n] if off.shape[0] > 1 else off[0], polarity, cos2, out[n])
    return out


@njit(cache=True, forceinline=True)
def _is_peak(v, prev, nxt, k, n, thresh):
    """Whether sample ``k`` of ``n`` (value ``v``, neighbours ``prev``, ``nxt``) is an edge feature
    (``spline.edge_peaks``)."""
    return v > thresh and (k == 0 or v >= prev) and (k == n - 1 or v > nxt)


@njit(cache=True, nogil=True)
def one_feature(kern, c):
    """``log(1 + c kern[k])`` for every ``k``: a line's term when its one edge feature is at ``k``."""
    out = np.empty(kern.shape[0])
    for k in range(kern.shape[0]):
        out[k] = np.log1p(c * (0.0 + kern[k]))
    return out


@njit(cache=True, nogil=True)
def line_sums(g, lo, n, thresh, kern, c, single, out):
    """``out[m] = log(1 + c Σ kern[k])`` over the edge features ``k`` of ``g[m, lo:lo + n]``
    (``g (M, L)``); the kernel summed in index order; ``single`` is :func:`one_feature`."""
    for m in range(g.shape[0]):
        s, nf, at = 0.0, 0, 0
        for k in range(n):
            v = g[m, lo + k]
            if _is_peak(v, g[m, lo + k - 1] if k > 0 else v, g[m, lo + k + 1] if k < n - 1 else v, k, n, thresh):
                s += kern[k]
                nf += 1
                at = k
        out[m] = 0.0 if nf == 0 else (single[at] if nf == 1 else np.log1p(c * s))


@njit(cache=True, nogil=True)
def loglik(gxy, q, nrm, off, polarity, cos2, thresh, kern, c, out):
    """``log r (N,)`` of the lines at ``off (L,)``: ``Σ_lines log(1 + c Σ_features kern)``."""
    prof = np.empty((q.shape[1], off.shape[0]), np.float32)
    v = np.empty(q.shape[1])
    single = one_feature(kern, c)
    for n in range(q.shape[0]):
        pose_profiles(gxy, q, nrm, n, off, polarity, cos2, prof)
        line_sums(prof, 0, off.shape[0], thresh, kern, c, single, v)
        out[n] = pairwise_sum(v, 0, v.shape[0])
    return out


@njit(cache=True, nogil=True)
def loglik_profiles(gn, lo, n_samples, thresh, kern, c, out):
    """``log r (N,)`` from the samples ``lo .. lo + n_samples`` of the profiles ``gn (N, M, L)``."""
    v = np.empty(gn.shape[1])
    single = one_feature(kern, c)
    for n in range(gn.shape[0]):
        line_sums(gn[n], lo, n_samples, thresh, kern, c, single, v)
        out[n] = pairwise_sum(v, 0, v.shape[0])
    return out


@njit(cache=True, nogil=True)
def grid_pose(g, thresh, start, nrm, offsets, kern, c, single, pairs, feats, nfeat, idx, table, stamp, line, out):
    """:func:`grid` for one pose: edge strengths ``g (M, L)``, normals ``nrm (M, 2)``, into ``out (G,)``;
    each line's features into ``feats (M, L)`` (their sample indices, ``nfeat (M,)`` of them); returns
    the last line number used in ``stamp``. ``pairs (L, L)``: the term of a line with two features at
    distances ``d0, d1`` from the sample, ``log(1 + c (kern(d0) + kern(d1)))`` summed as below, filled
    where NaN on first use (it depends on ``kern`` and ``c`` only: it may serve many calls)."""
    n_samples, n_grid = g.shape[1], offsets.shape[0]
    top = np.float32(n_samples - 1)
    out[:] = 0.0
    for m in range(g.shape[0]):
        nf = 0
        for k in range(n_samples):
            v = g[m, k]
            if _is_peak(v, g[m, k - 1] if k > 0 else v, g[m, k + 1] if k < n_samples - 1 else v, k, n_samples,
                        thresh):
                feats[m, nf] = k
                nf += 1
        nfeat[m] = nf
        if nf == 0:
            continue  # log(1 + 0) on every shift
        line += 1
        nx, ny = nrm[m, 0], nrm[m, 1]
        for j in range(n_grid):
            idx[j] = int(min(max(nx * offsets[j, 0] + ny * offsets[j, 1] - start, _ZERO), top))
        f0, f1 = feats[m, 0], feats[m, 1]
        if nf == 1:
            for j in range(n_grid):
                out[j] += single[abs(idx[j] - f0)]
        elif nf == 2:
            for j in range(n_grid):
                d0, d1 = abs(idx[j] - f0), abs(idx[j] - f1)
                if pairs[d0, d1] != pairs[d0, d1]:
                    pairs[d0, d1] = np.log1p(((_ZERO + kern[f0, idx[j]]) + kern[f1, idx[j]]) * c)
                out[j] += pairs[d0, d1]
        else:
            for j in range(n_grid):
                i = idx[j]
                if stamp[i] != line:
                    acc = _ZERO
                    for f in range(nf):
                        acc += kern[feats[m, f], i]
                    table[i] = np.log1p(acc * c)
                    stamp[i] = line
                out[j] += table[i]
    return line


@njit(cache=True, nogil=True)
def grid(gn, thresh, start, nrm, offsets, kern, c, out):
    """``log r`` on the translations ``offsets (G, 2)`` float32 of every pose: ``out (N, G)`` float32.

    For line ``i`` and shift ``δ`` the smoothed features ``S_i = Σ_j kern[j, ·]`` are read at the
    sample nearest ``n_i · δ`` (index ``floor(n_i · δ - start)``, ``start = off[0] - 0.5``,
    clipped to the line), each sample's ``log(1 + c S_i)`` computed once per line. ``kern (L, L)``
    depends on ``|j - i|`` only (1-px samples), so a line with one or two features reads a table by
    distance."""
    n_samples = gn.shape[2]
    feats, nfeat = np.empty((gn.shape[1], n_samples), np.int64), np.empty(gn.shape[1], np.int64)
    idx, table = np.empty(offsets.shape[0], np.int64), np.empty(n_samples, np.float32)
    stamp = np.full(n_samples, -1, np.int64)
    single = np.empty(n_samples, np.float32)
    for d in range(n_samples):
        single[d] = np.log1p((_ZERO + kern[0, d]) * c)
    pairs = np.full((n_samples, n_samples), np.nan, np.float32)
    line = 0
    for n in range(gn.shape[0]):
        line = grid_pose(gn[n], thresh, start, nrm[n], offsets, kern, c, single, pairs, feats, nfeat, idx, table,
                          stamp, line, out[n])
    return out


@njit(cache=True, nogil=True)
def nearest_edge(gn, thresh, off, shift, reach, out):
    """Per line, the edge feature nearest to ``shift (N, M)`` (offsets ``off (L,)``, first in
    index order on a tie): ``out (N, M)`` its offset minus ``shift`` when within ``reach``, else 0."""
    n_samples = gn.shape[2]
    for n in range(gn.shape[0]):
        for m in range(gn.shape[1]):
            best, at = np.inf, -1
            for k in range(n_samples):
                v = gn[n, m, k]
                if _is_peak(v, gn[n, m, k - 1] if k > 0 else v, gn[n, m, k + 1] if k < n_samples - 1 else v, k,
                            n_samples, thresh):
                    d = abs(off[k] - shift[n, m])
                    if d < best:
                        best, at = d, k
            out[n, m] = off[at] - shift[n, m] if at >= 0 and best <= reach else 0.0
    return out


@njit(cache=True, nogil=True)
def place(z, pts0, n0, q, nrm):
    """``Contour.place_points`` and ``Contour._turn`` in one pass: template points ``pts0 (M, 2)`` under the
    poses ``z (N, >=4)`` into ``q (N, M, 2)`` and the unit vectors ``n0 (M, 2)`` rotated by their
    angles into ``nrm (N, M, 2)``, float64, with numpy's arithmetic in numpy's order (equal)."""
    for k in range(z.shape[0]):
        c, s = 1.0 + z[k, 2], z[k, 3]
        r = math.hypot(c, s)
        r = r if r > 1e-12 or np.isnan(r) else 1e-12
        cn, sn = c / r, s / r
        for i in range(pts0.shape[0]):
            px, py = pts0[i, 0], pts0[i, 1]
            q[k, i, 0] = (z[k, 0] + c * px) - s * py
            q[k, i, 1] = (z[k, 1] + s * px) + c * py
            nx, ny = n0[i, 0], n0[i, 1]
            nrm[k, i, 0] = cn * nx - sn * ny
            nrm[k, i, 1] = sn * nx + cn * ny
    return q, nrm
