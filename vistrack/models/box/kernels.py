"""The box model's filter step (:mod:`~vistrack.models.box.model`, LIS), compiled: fewer, larger calls.

Each kernel does what a chain of small numpy calls does per frame, with the same arithmetic in
the same order (``tests/models/box/test_kernels_box.py`` states each tolerance):

- :func:`ar2_predict` and :func:`ar2_logpdf`: ``Box.predict`` (the normal draws made by numpy,
  in the same order) and ``Box.transition_logpdf``;
- :func:`lis_predict` and :func:`lis_weigh`: ``LIS.propose`` with the map proposal
  (:func:`~vistrack.kernels.map_draws.grid_points`, :func:`~vistrack.kernels.map_draws.map_sample`)
  and the likelihood and transition densities in two calls about the proposal map;
- :func:`colour_cues`: the confidence's colour cues (``AppearanceFrame.histograms`` and
  ``TargetColour``'s sums at the estimate).

``exp`` and ``log`` are the C library's here and in numpy's scalar loops (equal where numpy has
no SIMD loop for them: the tests compare with a 1e-12 tolerance).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...appearance.cue_kernels import affinity, box_loglik, box_ring_counts, contrast
from ...kernels.map_draws import grid_points, map_sample

__all__ = ["ar2_predict", "ar2_logpdf", "lis_predict", "lis_weigh", "colour_cues"]

_LOG2PI = float(np.log(2.0 * np.pi))  # as vistrack.core.gaussian and vistrack.proposals.map_proposal


@njit(cache=True, nogil=True, error_model="numpy")
def ar2_predict(states, damping, sigma, noise, out):
    """``Box.predict``: ``out (N, 6)`` = ``(z + d (z - z') + σ e^{l} ε, z)`` with the centre's std
    scaled by ``e^{l}`` of the old state and ``noise (N, 3)`` the normal draws."""
    for n in range(states.shape[0]):
        e = math.exp(states[n, 2])
        for k in range(3):
            z1, z2 = states[n, k], states[n, 3 + k]
            sd = sigma[k] * e if k < 2 else sigma[k]
            out[n, k] = (z1 + damping[k] * (z1 - z2)) + sd * noise[n, k]
            out[n, 3 + k] = z1
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def ar2_logpdf(new, old, damping, sigma, out):
    """``Box.transition_logpdf``: ``log K(new|old) (N,)``, Gaussian in the current values about
    ``z + d (z - z')`` with std ``σ e^{l}`` (centre) and ``σ_l``."""
    for n in range(new.shape[0]):
        e = math.exp(old[n, 2])
        sq = logs = 0.0
        for k in range(3):
            z1, z2 = old[n, k], old[n, 3 + k]
            sd = sigma[k] * e if k < 2 else sigma[k]
            r = (new[n, k] - (z1 + damping[k] * (z1 - z2))) / sd
            if k == 0:
                sq, logs = r * r, math.log(sd)
            else:
                sq += r * r
                logs += math.log(sd)
        out[n] = -0.5 * sq - logs - 0.5 * 3 * _LOG2PI
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def lis_predict(prev, damping, sigma, noise, window_sd, offsets, x0, y0, f, x, sig, uw, vw, span):
    """The first half of the box's LIS proposal step (``LIS.propose`` with :class:`MapProposal
    <vistrack.proposals.map_proposal.MapProposal>`): the prediction ``x (N, 6)`` (:func:`ar2_predict`),
    the window stds ``sig (N,)`` (``Box.window_std``: ``window_sd e^{l}``) and the grid points
    and their span (:func:`grid_points`). Returns ``span``."""
    ar2_predict(prev, damping, sigma, noise, x)
    for n in range(x.shape[0]):
        sig[n] = window_sd * math.exp(x[n, 2])
    return grid_points(x, sig, offsets, x0, y0, f, uw, vw, span)


@njit(cache=True, nogil=True, error_model="numpy")
def lis_weigh(prev, x, sig, offsets, g_unit, log_g_unit, cell, uw, vw, qmap, u0, v0, step, border, keep, floor,
              draws, damping, sigma, size0, ii, texture, x0, y0, f, ring, bg_weight, q, bp, lam_c, kappa, gx, gy,
              template, lam_t, z, log_incr, ll):
    """The second half: ``z (N, 6)`` drawn from the map (:func:`map_sample`), ``log r`` of ``z`` into
    ``ll`` (:func:`box_loglik`) and LIS's log increment ``log α + log r - log q + log K(z|prev) -
    log K(x|prev)`` (``-inf`` where ``log α`` is not finite) into ``log_incr``."""
    n = x.shape[0]
    z_u, log_alpha, log_q = np.empty((n, 2)), np.empty(n), np.empty(n)
    map_sample(x, sig, offsets, g_unit, log_g_unit, cell, uw, vw, qmap, u0, v0, step, border, keep, floor, draws,
               z_u, log_alpha, log_q)
    for i in range(n):
        for k in range(x.shape[1]):
            z[i, k] = x[i, k]
        z[i, 0], z[i, 1] = z_u[i, 0], z_u[i, 1]
    box_loglik(z, size0, ii, texture, x0, y0, f, ring, bg_weight, q, bp, lam_c, kappa, gx, gy, template, lam_t, ll)
    lz = ar2_logpdf(z, prev, damping, sigma, np.empty(n))
    lx = ar2_logpdf(x, prev, damping, sigma, np.empty(n))
    for i in range(n):
        v = (((log_alpha[i] + ll[i]) - log_q[i]) + lz[i]) - lx[i]
        log_incr[i] = v if np.isfinite(log_alpha[i]) else -np.inf
    return z


@njit(cache=True, nogil=True, error_model="numpy")
def colour_cues(ii, x0, y0, f, box, ring, bg_weight, q0, q, bp, out):
    """The confidence's colour cues (:class:`~vistrack.models.box.confidence.BoxConfidence`) of ``box (4,)``
    ``(cx, cy, w, h)`` from the per-bin integral image ``ii`` of a region at ``(x0, y0)``, scale ``f``:
    ``out (3,)`` = ``colour_first`` (the affinity with the first frame's ``q0``), ``colour`` (``1 - d²`` with
    ``q``) and ``contrast`` (the back-projection ``bp``'s mean in the box less in its ring of width
    ``ring (w + h) / 2``); the counts as ``AppearanceFrame.histograms`` makes them, the sums in numpy's order
    but the dot products with ``bp`` in bin order (1e-15)."""
    n_bins = ii.shape[2]
    inner, outer, scratch = np.empty(n_bins), np.empty(n_bins), np.empty(n_bins)
    box_ring_counts(ii, x0, y0, f, box[0], box[1], box[2], box[3], ring, inner, outer)
    out[0] = affinity(inner, bg_weight, q0, scratch)
    out[1] = 1.0 - (1.0 - affinity(inner, bg_weight, q, scratch))
    out[2] = contrast(inner, outer, bp)
    return out
