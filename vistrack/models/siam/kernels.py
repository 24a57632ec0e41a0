"""The siam model's filter step (:mod:`~vistrack.models.siam.model`, LIS), compiled: one call per frame.

:func:`lis_step` does what :meth:`ResponseProposal.propose <vistrack.models.siam.proposal.ResponseProposal.propose>`
does with its numpy parts — ``K``'s draw, the response mixture's draw, ``log K`` of both, the mixture's density
and ``log r`` — from the same random draws (made by numpy, in the same order), with the same arithmetic per
particle; :func:`mode_mean` is :meth:`Siam.estimate <vistrack.models.siam.model.Siam.estimate>`. Sums run in
another order than numpy's (``tests/models/siam/test_siam_kernels.py``: 1e-12 relative).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["lis_step", "mode_mean", "cell_boxes_into", "cloud_stats", "map_cues", "pose_terms", "mixture_into"]

_LOG_2PI = math.log(2.0 * math.pi)


@njit(cache=True, nogil=True, error_model="numpy")
def _log_k(new, old, damping, sig_c, jump, eps, sig_s, sig_a):
    """``log K(new|old)`` of one particle (:meth:`Siam.transition_logpdf`; ``jump``: ``σ_j / σ_c``, ``eps``:
    ``ε_j``)."""
    sc = sig_c * math.exp((old[2] + old[3]) / 2)
    dx = new[0] - (old[0] + damping * (old[0] - old[4]))
    dy = new[1] - (old[1] + damping * (old[1] - old[5]))
    r2 = dx * dx + dy * dy
    centre = -0.5 * r2 / (sc * sc) - 2 * math.log(sc)
    if eps > 0:
        sj = sc * jump
        a, b = math.log1p(-eps) + centre, math.log(eps) - 0.5 * r2 / (sj * sj) - 2 * math.log(sj)
        hi = max(a, b)
        centre = hi + math.log1p(math.exp(min(a, b) - hi))
    l0, l1 = new[2] - old[2], new[3] - old[3]
    ds = (l0 + l1) / 2 / sig_s
    da = (l0 - l1) / sig_a
    return centre - 0.5 * (ds * ds + da * da) - math.log(sig_s * sig_a) - 2 * _LOG_2PI


@njit(cache=True, nogil=True, error_model="numpy")
def _terms(z, logit, boxes, cx, cy, k, half, floor, bs0, bs1, w0, h0, gate):
    """``(ℓ, a)`` of one pose ``z``: the logit bilinearly interpolated at its centre (``floor`` outside the map) and
    its box's agreement with the nearest cell's (:meth:`Siam.loglik`, :meth:`Siam.box_agreement`)."""
    m = logit.shape[0]
    u = (z[0] - cx) * k + half
    v = (z[1] - cy) * k + half
    if u > -0.5 and u < m - 0.5 and v > -0.5 and v < m - 0.5:
        uc, vc = min(max(u, 0.0), m - 1.0), min(max(v, 0.0), m - 1.0)
        i0, j0 = min(int(math.floor(vc)), m - 2), min(int(math.floor(uc)), m - 2)
        fu, fv = uc - j0, vc - i0
        top = logit[i0, j0] * (1 - fu) + logit[i0, j0 + 1] * fu
        bottom = logit[i0 + 1, j0] * (1 - fu) + logit[i0 + 1, j0 + 1] * fu
        lg = top * (1 - fv) + bottom * fv
    else:
        lg = floor
    cu = int(min(max(np.rint(u), 0.0), m - 1.0))
    cv = int(min(max(np.rint(v), 0.0), m - 1.0))
    b = boxes[cv * m + cu]
    dx = (z[0] - b[0]) / (bs0 * w0 * math.exp(b[2]))
    dy = (z[1] - b[1]) / (bs0 * h0 * math.exp(b[3]))
    d2 = (z[2] - b[2]) / bs1
    d3 = (z[3] - b[3]) / bs1
    agree = -0.5 * (dx * dx + dy * dy + d2 * d2 + d3 * d3)
    if gate:
        agree = agree / (1.0 + math.exp(-logit[cv, cu]))
    return lg, agree


@njit(cache=True, nogil=True, error_model="numpy")
def _loglik(z, logit, boxes, cx, cy, k, half, floor, lam, bs0, bs1, w0, h0, gate):
    """``log r`` of one particle (:meth:`Siam.loglik`): ``λ`` times the bilinear logit plus the box agreement."""
    lg, agree = _terms(z, logit, boxes, cx, cy, k, half, floor, bs0, bs1, w0, h0, gate)
    return lam * lg + agree


@njit(cache=True, nogil=True, error_model="numpy")
def pose_terms(z, logit, boxes, cx, cy, k, half, floor, bs0, bs1, w0, h0, gate, out):
    """``(ℓ, a)`` of one pose into ``out (2,)`` (:func:`_terms`; the confidence's cues)."""
    out[0], out[1] = _terms(z, logit, boxes, cx, cy, k, half, floor, bs0, bs1, w0, h0, gate)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def lis_step(prev, e_k, u_k, u, e, beta, damping, sig_c, jump, eps, sig_s, sig_a, cum, log_pi, mu, sd, logit, boxes,
             cx, cy, k, half, floor, lam, bs0, bs1, w0, h0, gate, z, x, incr, ll):
    """One LIS step of the siam model over ``prev (N, 8)``: the prediction ``x`` (``K``'s normals ``e_k (N, 4)``;
    ``u_k (N,)``: the centre's component where ``eps`` > 0), the draw ``z`` (uniforms ``u (N, 2)``, normals
    ``e (N, 4)``: the response mixture ``(cum (C,), log π, μ (C, 4), σ (C, 4))`` with probability ``β``, else
    ``z = x``), ``log r(z)`` into ``ll`` and the log increment ``log r - log q + log K(z)`` into ``incr``
    (``-inf`` where ``log K(x)`` is not finite)."""
    n = prev.shape[0]
    c = cum.shape[0]
    log_b = math.log(beta) if beta > 0 else -np.inf
    log_1b = math.log1p(-beta) if beta < 1 else -np.inf
    for i in range(n):
        p = prev[i]
        sc = sig_c * math.exp((p[2] + p[3]) / 2)
        if eps > 0 and u_k[i] < eps:
            sc = sc * jump
        x[i, 0] = p[0] + damping * (p[0] - p[4]) + sc * e_k[i, 0]
        x[i, 1] = p[1] + damping * (p[1] - p[5]) + sc * e_k[i, 1]
        ds, da = sig_s * e_k[i, 2], sig_a * e_k[i, 3]
        x[i, 2] = p[2] + (ds + da / 2)
        x[i, 3] = p[3] + (ds - da / 2)
        for j in range(4):
            x[i, 4 + j] = p[j]
        log_kx = _log_k(x[i], p, damping, sig_c, jump, eps, sig_s, sig_a)
        for j in range(8):
            z[i, j] = x[i, j]
        if u[i, 0] < beta:
            t = u[i, 1] * cum[c - 1]
            kk = 0
            while kk < c and cum[kk] <= t:
                kk += 1
            kk = min(kk, c - 1)
            for j in range(4):
                z[i, j] = mu[kk, j] + sd[kk, j] * e[i, j]
        log_kz = _log_k(z[i], p, damping, sig_c, jump, eps, sig_s, sig_a)
        top = -np.inf
        comps = np.empty(c)
        for kk in range(c):
            s = 0.0
            logsd = 0.0
            for j in range(4):
                d = (z[i, j] - mu[kk, j]) / sd[kk, j]
                s += d * d
                logsd += math.log(sd[kk, j])
            comps[kk] = log_pi[kk] - 0.5 * s - logsd - 2 * _LOG_2PI
            top = max(top, comps[kk])
        acc = 0.0
        for kk in range(c):
            acc += math.exp(comps[kk] - top)
        log_qy = top + math.log(acc)
        a, b = log_b + log_qy, log_1b + log_kz
        hi = max(a, b)
        log_q = hi + math.log1p(math.exp(min(a, b) - hi)) if hi > -np.inf else -np.inf
        ll[i] = _loglik(z[i], logit, boxes, cx, cy, k, half, floor, lam, bs0, bs1, w0, h0, gate)
        incr[i] = ll[i] - log_q + log_kz if math.isfinite(log_kx) else -np.inf
    return z


@njit(cache=True, nogil=True, error_model="numpy")
def mode_mean(states, w, side0, radius, out):
    """:meth:`Siam.estimate`: the weighted mean of the particles within ``radius`` box sides of the particle whose
    neighbours in that radius weigh most (the first of equal ones), into ``out (8,)``."""
    n, d = states.shape
    best, kbest = -1.0, 0
    r2 = np.empty(n)
    for i in range(n):
        s = radius * side0 * math.exp((states[i, 2] + states[i, 3]) / 2)
        r2[i] = s * s
    for i in range(n):
        mass = 0.0
        for j in range(n):
            dx, dy = states[i, 0] - states[j, 0], states[i, 1] - states[j, 1]
            if dx * dx + dy * dy <= r2[i]:
                mass += w[j]
        if mass > best:
            best, kbest = mass, i
    tot = 0.0
    for j in range(d):
        out[j] = 0.0
    for j in range(n):
        dx, dy = states[kbest, 0] - states[j, 0], states[kbest, 1] - states[j, 1]
        if dx * dx + dy * dy <= r2[kbest]:
            tot += w[j]
            for q in range(d):
                out[q] += w[j] * states[j, q]
    for q in range(d):
        out[q] /= tot
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def cell_boxes_into(ltrb, points, cx, cy, scale, w0, h0, out):
    """:func:`~vistrack.models.siam.observation.cell_boxes` into ``out (M*M, 4)``: each cell's box
    ``(cx, cy, log w/w_0, log h/h_0)`` from the head's distances ``ltrb (4, M, M)`` (float64)."""
    m = ltrb.shape[1]
    for i in range(m):
        for j in range(m):
            k = i * m + j
            le, to, ri, bo = ltrb[0, i, j], ltrb[1, i, j], ltrb[2, i, j], ltrb[3, i, j]
            out[k, 0] = cx + (points[k, 0] + (ri - le) / 2) / scale
            out[k, 1] = cy + (points[k, 1] + (bo - to) / 2) / scale
            out[k, 2] = math.log(max(le + ri, 1e-3) / scale / w0)
            out[k, 3] = math.log(max(to + bo, 1e-3) / scale / h0)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def cloud_stats(states, w, damping, out):
    """The weighted mean of the dynamics' mean predictions ``(cx, cy, lw, lh)`` into ``out[:4]`` and the cloud's
    weighted centre spread ``sqrt(Σ w |c - c̄|²)`` into ``out[4]`` (:meth:`Siam.observe`)."""
    n = states.shape[0]
    mx = my = 0.0
    for q in range(4):
        out[q] = 0.0
    for i in range(n):
        s = states[i]
        out[0] += w[i] * (s[0] + damping * (s[0] - s[4]))
        out[1] += w[i] * (s[1] + damping * (s[1] - s[5]))
        out[2] += w[i] * s[2]
        out[3] += w[i] * s[3]
        mx += w[i] * s[0]
        my += w[i] * s[1]
    v = 0.0
    for i in range(n):
        dx, dy = states[i, 0] - mx, states[i, 1] - my
        v += w[i] * (dx * dx + dy * dy)
    out[4] = math.sqrt(v)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def map_cues(logit, half_psr, half_rival, out):
    """The logit map's peak, its peak-to-sidelobe ratio (outside ``(2 half_psr + 1)²`` about the peak) and the peak's
    lead over the best cell outside ``(2 half_rival + 1)²`` into ``out (3,)`` (:func:`~vistrack.models.siam.lost.psr`,
    :func:`~vistrack.models.siam.lost.rival`)."""
    m0, m1 = logit.shape
    bi, bj, best = 0, 0, -np.inf
    for i in range(m0):
        for j in range(m1):
            if logit[i, j] > best:
                best, bi, bj = logit[i, j], i, j
    s = s2 = 0.0
    cnt = 0
    second = -np.inf
    for i in range(m0):
        for j in range(m1):
            v = logit[i, j]
            if abs(i - bi) > half_psr or abs(j - bj) > half_psr:
                s += v
                s2 += v * v
                cnt += 1
            if (abs(i - bi) > half_rival or abs(j - bj) > half_rival) and v > second:
                second = v
    out[0] = best
    if cnt > 0:
        mean = s / cnt
        var = max(s2 / cnt - mean * mean, 0.0)
        out[1] = (best - mean) / math.sqrt(var) if var > 0 else 0.0
    else:
        out[1] = 0.0
    out[2] = best - second if second > -np.inf else 0.0
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def mixture_into(flat, boxes, tempering, sc, sl, w0, h0, log_pi, mu, sd):
    """:func:`~vistrack.models.siam.proposal.mixture_parts`: the ``C`` (``len(log_pi)``) strongest cells of the
    logits ``flat (M*M,)`` (ties by index), their weights ``log π`` and Gaussians ``μ``, ``σ`` (``(C, 4)``)."""
    c = log_pi.shape[0]
    top = np.argsort(-flat, kind="mergesort")[:c]
    amax = tempering * flat[top[0]]
    acc = 0.0
    for q in range(c):
        acc += math.exp(tempering * flat[top[q]] - amax)
    norm = amax + math.log(acc)
    for q in range(c):
        k = top[q]
        log_pi[q] = tempering * flat[k] - norm
        for j in range(4):
            mu[q, j] = boxes[k, j]
        sd[q, 0] = sc * math.exp(boxes[k, 2]) * w0
        sd[q, 1] = sc * math.exp(boxes[k, 3]) * h0
        sd[q, 2] = sl
        sd[q, 3] = sl
    return log_pi
