"""The grid proposal's draws (:class:`~vistrack.proposals.map_proposal.MapProposal`), compiled.

- :func:`grid_points` and :func:`map_sample`: :meth:`MapProposal.sample
  <vistrack.proposals.map_proposal.MapProposal.sample>` for a model whose ``q`` is a map read bilinearly
  (the box model's ``proposal_log_q``): the grid's points and their span in working pixels, then the
  map (``exp`` of the tempered scores) read as ``cv2.remap`` reads it, over each row's maximum and
  floored, the cell drawn by inversion of the cumulative ``q g`` in the linear domain (no
  ``log``/``exp`` per cell), the point in its cell, ``log alpha`` and ``log q``
  (``tests/models/box/test_kernels_box.py`` compares them with the numpy path).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .sampling import corner_float, fma_lerp, lerp_fma

__all__ = ["grid_points", "map_sample"]

_LOG2PI = float(np.log(2.0 * np.pi))  # as vistrack.core.gaussian and vistrack.proposals.map_proposal


@njit(cache=True, nogil=True, error_model="numpy")
def grid_points(states, sig, offsets, x0, y0, f, uw, vw, span):
    """The grid points ``c + σ o_j`` of each state's centre in working pixels ``uw, vw (N, G)``
    (``(x - x0) f``) and their span ``(u_min, u_max, v_min, v_max)`` into ``span (4,)``."""
    for n in range(states.shape[0]):
        for j in range(offsets.shape[0]):
            uw[n, j] = ((states[n, 0] + sig[n] * offsets[j, 0]) - x0) * f
            vw[n, j] = ((states[n, 1] + sig[n] * offsets[j, 1]) - y0) * f
    span[0], span[1], span[2], span[3] = uw.min(), uw.max(), vw.min(), vw.max()
    return span


@njit(cache=True, forceinline=True, error_model="numpy")
def _nanmax(top, x):
    """The running maximum as ``np.max`` keeps it: NaN once a NaN was met."""
    if x != x or x > top:
        return x if top == top else top
    return top


@njit(cache=True, nogil=True, error_model="numpy")
def _q_rows(qmap, u0, v0, step, border, uw, vw, keep, floor, out):
    """The box's ``proposal_log_q`` before its ``log``, into ``out (N, G)``: the map ``qmap (H, W, 1)``
    float32 (``exp`` of the tempered scores) read at ``((uw - u0) / step, (vw - v0) / step)`` as
    ``cv2.remap`` reads it (``border`` outside), over each row's maximum (1 where that is not
    positive), mixed with a flat floor: ``keep val / max + floor``."""
    h, w = qmap.shape[0], qmap.shape[1]
    nan, border = np.float32(np.nan), np.float32(border)
    for n in range(uw.shape[0]):
        for j in range(uw.shape[1]):
            ix, iy, a, b = corner_float(np.float32((uw[n, j] - u0) / step), np.float32((vw[n, j] - v0) / step))
            if 0 <= ix < w - 1 and 0 <= iy < h - 1:
                y0_, x0_ = np.uint64(iy), np.uint64(ix)
                y1_, x1_ = y0_ + np.uint64(1), x0_ + np.uint64(1)
                s = fma_lerp(qmap[y0_, x0_, 0], qmap[y0_, x1_, 0], qmap[y1_, x0_, 0],
                             qmap[y1_, x1_, 0], a, b)
            else:
                s = lerp_fma(qmap, ix, iy, a, b, 0, border, nan)
            out[n, j] = np.float64(s)
        top = out[n, 0]
        for j in range(1, uw.shape[1]):
            top = _nanmax(top, out[n, j])
        for j in range(uw.shape[1]):
            out[n, j] = keep * (out[n, j] / top) + floor if top > 0 else keep + floor
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def map_sample(states, sig, offsets, g_unit, log_g_unit, cell, uw, vw, qmap, u0, v0, step, border, keep, floor,
               draws, z_u, log_alpha, log_q):
    """:meth:`MapProposal.sample <vistrack.proposals.map_proposal.MapProposal.sample>` with the box's map
    ``q`` (``qmap`` with ``qmap.shape[0] == 0``: a flat ``q = 1``): the cell of each row drawn by
    inversion of the cumulative sums of ``q_k g_k`` (``g_unit = exp(log_g_unit)``) at ``draws[n, 0]``,
    the point uniform in it from ``draws[n, 1:3]``; writes ``z_u (N, 2)`` (frame px), ``log_alpha (N,)``
    and ``log_q (N,)``."""
    n_rows, g = uw.shape
    q = np.ones((n_rows, g))
    if qmap.shape[0] > 0:
        _q_rows(qmap, u0, v0, step, border, uw, vw, keep, floor, q)
    cum = np.empty(g)
    for n in range(n_rows):
        two_log_sig = 2 * math.log(sig[n])
        total = 0.0
        for k in range(g):
            total += q[n, k] * g_unit[k]
            cum[k] = total
        target, j = draws[n, 0] * total, g - 1
        for k in range(g):
            if cum[k] > target:
                j = k
                break
        dd = 0.0
        for c in range(2):
            zc = (states[n, c] + sig[n] * offsets[j, c]) + sig[n] * cell * (draws[n, 1 + c] - 0.5)
            z_u[n, c] = zc
            r = (states[n, c] - zc) / sig[n]
            dd = r * r if c == 0 else dd + r * r
        log_g = -0.5 * dd - _LOG2PI - two_log_sig
        log_alpha[n] = (math.log(total) - two_log_sig) + 2 * math.log(cell * sig[n]) + log_g
        log_q[n] = (math.log(q[n, j]) + log_g_unit[j]) - two_log_sig
    return z_u
