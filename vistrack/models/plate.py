"""License-plate template likelihood (thesis 001, §1.3.2, Table 1.1) — issue 6 groundwork.

``r = r^h · r^v · r^c`` with (Table 1.1's pixel sets from a
:class:`~vistrack.models.plate_layout.PlateLayout`)

    log r^h = κ (mean_{P^{h,e}} |∇_y I| - mean_{P^{h,fe}} (|G_s I| + |G_l I|))
    log r^v = κ (mean_{P^{v,e}} |∇_x I| - mean_{P^{v,fe}} (|G_s I| + |G_l I|))
    log r^c = κ (mean_{P^{sc}} |G_s I| + mean_{P^{bc}} |G_l I|)

``∇_y I`` responds to horizontal edges (the thesis's "horizontal edge image"),
``G_s``, ``G_l`` are the box-filter DoGs at two scales. Every map is divided
by its mean over the frame, so the terms are "times the frame's average" and
lighting changes cancel; ``κ`` (the thesis's proportionality) sets the
sharpness. Each pixel set is sampled on a regular grid of points inside its
rectangles (bilinear, one ``cv2.remap`` of a 4-channel map for all
particles), which handles the sheared parallelogram exactly.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..features import remap_points
from .plate_layout import LAYOUTS, plate_points

__all__ = ["PlateLikelihood"]

_SETS = ("h_edge", "h_free", "v_edge", "v_free", "small", "big")


def _grid_points(rects, per_unit=24):
    """Sample points (unit-square coords) inside each rectangle, about ``per_unit`` per unit length."""
    pts = []
    for r in rects:
        x0, y0, x1, y1 = r
        nx = max(2, int(np.ceil((x1 - x0) * per_unit)))
        ny = max(2, int(np.ceil((y1 - y0) * per_unit)))
        a = x0 + (np.arange(nx) + 0.5) * (x1 - x0) / nx
        b = y0 + (np.arange(ny) + 0.5) * (y1 - y0) / ny
        aa, bb = np.meshgrid(a, b)
        pts.append(np.stack([aa.ravel(), bb.ravel()], axis=1))
    return np.concatenate(pts)


class PlateLikelihood:
    """The plate likelihood ``r(y | u, w, θ, s)`` for poses ``(N, 4)`` (or states whose first
    four columns are the pose).

    Parameters
    ----------
    layout : str or PlateLayout
    kappa : float
        Sharpness ``κ``.
    per_unit : int
        Sample points per unit length of the plate square in each pixel set.
    """

    def __init__(self, layout="jp", *, kappa=2.0, per_unit=24):
        self.layout = LAYOUTS[layout] if isinstance(layout, str) else layout
        self.kappa = float(kappa)
        sets = self.layout.sets()
        self.points = {k: _grid_points(sets[k], per_unit) for k in _SETS}
        self._all = np.concatenate([self.points[k] for k in _SETS])
        bounds = np.cumsum([0] + [len(self.points[k]) for k in _SETS])
        self._slices = {k: slice(bounds[i], bounds[i + 1]) for i, k in enumerate(_SETS)}

    def maps(self, obs):
        """The 4-channel map ``(|∇_x I|, |∇_y I|, |G_s I|, |G_l I|)``, each over its frame mean (cached)."""
        m = getattr(obs, "_plate_maps", None)
        if m is None:
            chans = [np.abs(obs.gx), np.abs(obs.gy), np.abs(obs.dog_small), np.abs(obs.dog_large)]
            chans = [c / max(float(cv2.mean(c)[0]), 1e-6) for c in chans]
            m = cv2.merge([c.astype(np.float32) for c in chans])
            obs._plate_maps = m
        return m

    def terms(self, obs, states):
        """``(log r^h, log r^v, log r^c)`` as three ``(N,)`` arrays."""
        pose = np.atleast_2d(states)[:, :4]
        pts = plate_points(pose, self._all, self.layout.aspect)  # (N, P, 2)
        # outside the frame: no edges, and strong "lines" where stripes must be free of them
        v = remap_points(self.maps(obs), pts[..., 0].astype(np.float32), pts[..., 1].astype(np.float32),
                         border=(0.0, 0.0, 5.0, 5.0))
        sl = self._slices

        def mean(name, ch):
            return v[:, sl[name], ch].mean(axis=1)

        k = self.kappa
        lines_h = mean("h_free", 2) + mean("h_free", 3)
        lines_v = mean("v_free", 2) + mean("v_free", 3)
        log_h = k * (mean("h_edge", 1) - lines_h)
        log_v = k * (mean("v_edge", 0) - lines_v)
        log_c = k * (mean("small", 2) + mean("big", 3))
        return log_h, log_v, log_c

    def term(self, obs, states, which):
        """One factor, ``log r^h`` (``which="h"``) or ``log r^v`` (``"v"``), sampling only its two
        pixel sets (what the §4.5.2 proposal needs along its lines)."""
        edge, free, ch = ("h_edge", "h_free", 1) if which == "h" else ("v_edge", "v_free", 0)
        pose = np.atleast_2d(states)[:, :4]
        pts_e, pts_f = self.points[edge], self.points[free]
        pts = plate_points(pose, np.concatenate([pts_e, pts_f]), self.layout.aspect)
        v = remap_points(self.maps(obs), pts[..., 0].astype(np.float32), pts[..., 1].astype(np.float32),
                         border=(0.0, 0.0, 5.0, 5.0))
        ne = len(pts_e)
        return self.kappa * (v[:, :ne, ch].mean(axis=1) - (v[:, ne:, 2] + v[:, ne:, 3]).mean(axis=1))

    def loglik(self, obs, states):
        """``log r = log r^h + log r^v + log r^c`` ``(N,)``."""
        h, v, c = self.terms(obs, states)
        return h + v + c


class Plate:
    """License-plate tracking model (thesis 001, §1.3.2, §4.5.2).

    State ``(u, w, θ, s, u', w', θ', s')``: centre, angle of the non-vertical
    sides, width (px), and their previous values. Dynamics: with probability
    0.9 a factored AR(2), ``z_t = z_{t-1} + d (z_{t-1} - z_{t-2}) + σ ε``; with
    probability 0.1 a new car entering, ``z_t ~ N(m_e, diag(σ_e²))`` with zero
    velocity (previous = current). Likelihood: :class:`PlateLikelihood`.
    Local moves act on translation ``(u, w)`` only (§4.5.2); an entering
    particle moves its previous pose along (it stays a zero-velocity start).

    Parameters
    ----------
    frame_size : tuple of int
    layout : str
    enter_weight : float
        Weight of the entering-car component (0.1).
    """

    dim = 8
    first_step = False

    def __init__(self, frame_size, layout="jp", *, enter_weight=0.1, damping=(0.8, 0.8, 0.5, 0.5), sigma=None,
                 enter_mean=None, enter_std=None, kappa=2.0):
        w, h = frame_size
        self.frame_size = (int(w), int(h))
        self.lik = PlateLikelihood(layout, kappa=kappa)
        self.layout = self.lik.layout
        self.enter_weight = float(enter_weight)
        self.damping = np.asarray(damping, float)
        self.sigma = np.asarray(sigma if sigma is not None else (0.012 * w, 0.008 * h, 0.02, 0.015 * w), float)
        self.enter_mean = np.asarray(enter_mean if enter_mean is not None else (0.5 * w, 0.68 * h, 0.0, 0.13 * w),
                                     float)
        self.enter_std = np.asarray(enter_std if enter_std is not None else (0.35 * w, 0.1 * h, 0.1, 0.03 * w), float)
        self.prior_mean = np.concatenate([self.enter_mean, self.enter_mean])
        #: plate widths (px) the model allows; the dynamics clip to it
        self.scale_range = (0.05 * w, 0.4 * w)

    # -- dynamics ----------------------------------------------------------------
    def _enter(self, n, rng):
        z = self.enter_mean + self.enter_std * rng.standard_normal((n, 4))
        z[:, 3] = np.clip(z[:, 3], *self.scale_range)
        return np.concatenate([z, z], axis=1)

    #: optional ``(mean, std)`` of the first pose (``--init``); else the entering density
    start = None
    #: the estimate is reported visible when ``log r`` at it exceeds this
    visible_loglik = 10.0

    def sample_prior(self, n, rng):
        if self.start is None:
            return self._enter(n, rng)
        mean, std = self.start
        z = mean + std * rng.standard_normal((n, 4))
        return np.concatenate([z, z], axis=1)

    def _logn(self, x, mean, std):
        e = (x - mean) / std
        return -0.5 * np.sum(e * e, axis=-1) - np.sum(np.log(std)) - 2 * np.log(2 * np.pi)

    def prior_logpdf(self, states):
        mean, std = self.start if self.start is not None else (self.enter_mean, self.enter_std)
        return self._logn(states[:, :4], mean, std)

    def predict_mean(self, states):
        z1, z2 = states[:, :4], states[:, 4:]
        return np.concatenate([z1 + self.damping * (z1 - z2), z1], axis=1)

    def predict(self, states, rng):
        n = len(states)
        out = self.predict_mean(states)
        out[:, :4] += self.sigma * rng.standard_normal((n, 4))
        out[:, 3] = np.clip(out[:, 3], *self.scale_range)
        enter = rng.random(n) < self.enter_weight
        if enter.any():
            out[enter] = self._enter(int(enter.sum()), rng)
        return out

    @staticmethod
    def entering(states):
        """Particles that are a fresh entering-car draw (previous pose = current pose)."""
        return np.all(states[:, 4:] == states[:, :4], axis=1)

    def transition_logpdf(self, new, old):
        """``log K(new|old)`` for the branch ``new`` came from (AR(2) or entering car)."""
        ar = np.log1p(-self.enter_weight) + self._logn(new[:, :4], self.predict_mean(old)[:, :4], self.sigma)
        ent = np.log(self.enter_weight) + self._logn(new[:, :4], self.enter_mean, self.enter_std)
        return np.where(self.entering(new), ent, ar)

    # -- likelihood and output ------------------------------------------------------
    def loglik(self, obs, states):
        return self.lik.loglik(obs, states)

    def vertices(self, states):
        from .plate_layout import plate_vertices

        return plate_vertices(np.atleast_2d(states)[:, :4], self.layout.aspect)

    def outline(self, states):
        return self.vertices(states)

    def box(self, states):
        v = self.vertices(states)
        lo, hi = v.min(axis=1), v.max(axis=1)
        return np.concatenate([lo, hi - lo], axis=1)

    def visible(self, obs, state):
        """Whether a plate is reported at ``state``: ``log r`` above :attr:`visible_loglik`
        (provisional: to be calibrated on the synthetic suite)."""
        return bool(self.loglik(obs, np.asarray(state, float).reshape(1, -1))[0] > self.visible_loglik)

    def describe(self, state):
        s = np.asarray(state, float).reshape(1, -1)
        v = self.vertices(s)[0]
        lo, hi = v.min(axis=0), v.max(axis=0)
        row = {"cx": s[0, 0], "cy": s[0, 1], "w": hi[0] - lo[0], "h": hi[1] - lo[1],
               "angle_deg": float(np.rad2deg(s[0, 2])), "scale": s[0, 3]}
        for i in range(4):
            row[f"x{i}"], row[f"y{i}"] = v[i]
        return row

    # -- local moves on translation (§4.5.2) -------------------------------------
    def local_coords(self, states):
        return states[:, :2]

    def with_local(self, states, u):
        out = states.copy()
        ent = self.entering(states)
        out[:, :2] = u
        out[ent, 4:6] = u[ent]
        return out

    with_local_prior = with_local

    def plate_size(self, states):
        """Plate width and height ``(N, 2)`` (px)."""
        s = states[:, 3]
        return np.stack([s, s / self.layout.aspect], axis=1)

    def lis_proposal(self):
        return PlateLISProposal(self)

    def lls_window(self):
        from ..filters.lls import Window

        size = self.enter_mean[3]
        return Window("box", (size, size / self.layout.aspect), grid=9)


class PlateLISProposal:
    """The §4.5.2 proposal: ``W' ~ r^h(Y|U, ·, θ) g_1(W - ·)``, then ``U' ~ r^v(Y|·, W', θ) g_0(U - ·)``,
    with ``g_0``, ``g_1`` boxes of half-width the plate's width and height (an interval of twice
    the plate size). Both conditionals are sampled on a grid of cells (``cells`` per axis; the
    density is piecewise constant, used exactly), so ``α = 1`` and the weight is
    ``r(Z) / (q^h q^v) · K(Z)/K(X)`` (filters/lis.py computes ``α r / q · K/K``).
    """

    def __init__(self, model, cells=32):
        self.model = model
        self.cells = int(cells)

    def _conditional(self, log_vals, rng):
        """Draw a cell per row ∝ exp(log_vals) and return (index, log prob of the cell)."""
        from ..particles import logsumexp

        lz = logsumexp(log_vals, axis=1)
        j = np.argmax(log_vals + rng.gumbel(size=log_vals.shape), axis=1)
        return j, log_vals[np.arange(len(j)), j] - lz

    def sample(self, x, obs, rng):
        m, k = self.model, self.cells
        n = len(x)
        half = m.plate_size(x)  # (N, 2): half-widths of the boxes = plate width, height
        frac = (np.arange(k) + 0.5) / k * 2 - 1  # cell centres in [-1, 1]
        # 1. vertical: r^h along the vertical line through the predicted centre
        cand = np.repeat(x, k, axis=0)
        cand[:, 1] = (x[:, 1:2] + frac * half[:, 1:2]).ravel()
        log_h = m.lik.term(obs, cand, "h").reshape(n, k)
        jh, lqh = self._conditional(log_h, rng)
        cell_h = 2 * half[:, 1] / k
        w_new = x[:, 1] + frac[jh] * half[:, 1] + cell_h * (rng.random(n) - 0.5)
        # 2. horizontal: r^v along the horizontal line at the new height
        cand = np.repeat(x, k, axis=0)
        cand[:, 1] = np.repeat(w_new, k)
        cand[:, 0] = (x[:, 0:1] + frac * half[:, 0:1]).ravel()
        log_v = m.lik.term(obs, cand, "v").reshape(n, k)
        jv, lqv = self._conditional(log_v, rng)
        cell_v = 2 * half[:, 0] / k
        u_new = x[:, 0] + frac[jv] * half[:, 0] + cell_v * (rng.random(n) - 0.5)
        z = m.with_local(x, np.stack([u_new, w_new], axis=1))
        log_q = lqh - np.log(cell_h) + lqv - np.log(cell_v)  # piecewise-constant densities
        return z, np.zeros(n), log_q
