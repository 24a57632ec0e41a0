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
from ..proposals import Window
from .protocol import VideoModelBase
from .plate_layout import LAYOUTS, plate_points

__all__ = ["PlateLikelihood", "thesis_weights", "scale_band", "LEARNT_WEIGHTS"]


def thesis_weights(kappa=2.0):
    """The thesis's coefficients (§1.3.2): ``+κ`` on the edge bands and the character areas
    (small characters on ``G_s``, large on ``G_l``), ``-κ`` on both DoGs over the free stripes."""
    k = float(kappa)
    return ({"h_edge": k, "h_free_s": -k, "h_free_l": -k, "v_edge": k, "v_free_s": -k, "v_free_l": -k,
             "small_s": k, "big_l": k}, 0.0)


#: coefficients fitted by ``vistrack fit-plate CLIPS --scales 40,80`` on 16 synthetic
#: clips (seeds 101-108 at 640x480, 113-116 at 480x360 and 109-112 at 320x240, disjoint from the
#: evaluation seeds 1-10), per layout (on ``log(1 + mean)`` of each pixel set, which keeps strong
#: edges — headlights, sign borders — from outweighing the characters); the JP layout's extra
#: pixel sets included. Scale-banded: each coefficient is a pair (at plate widths 40 and 80 px,
#: interpolated in log s), because the DoGs have a fixed size in pixels and a feature's
#: response depends on the plate's size in the image
LEARNT_WEIGHTS = {
    "jp": ({"h_edge": (2.6559, 2.6363), "h_free_s": (-0.8900, -3.5501), "h_free_l": (1.0721, 0.5335),
            "v_edge": (1.6775, 3.0946), "v_free_s": (-1.5943, -1.9355), "v_free_l": (0.4612, 0.5801),
            "small_s": (0.8666, -0.0751), "small_l": (-1.3295, 0.2651), "big_s": (0.1278, -0.0674),
            "big_l": (-0.0637, -0.0201), "top_s": (1.0265, 0.2587), "top_l": (-1.2003, 0.6549),
            "glyph_s": (0.4641, 0.7775), "glyph_l": (-0.7687, 0.2466), "above_s": (1.5114, 0.1199),
            "above_l": (-0.4306, 0.5454), "below_s": (-0.7127, -0.8213), "below_l": (-0.0973, -0.2676),
            "sides_s": (-1.7393, -0.6101), "sides_l": (-1.7632, -0.9433), "big_gx": (1.3041, 0.7587),
            "big_gy": (1.7978, 1.1251), "top_gx": (0.3682, 0.8996), "h_edge_gx": (-0.3523, -0.7162),
            "v_edge_gy": (-3.6481, -3.7614)},
           (-9.3638, -10.7008), (40.0, 80.0)),
}


def scale_band(s, scales):
    """Where plate widths ``s`` lie between the two widths ``scales = (s_0, s_1)`` of scale-banded
    coefficients: ``a = log(s / s_0) / log(s_1 / s_0)`` clipped to [0, 1] (the coefficients are
    ``(1 - a) w_0 + a w_1``)."""
    s0, s1 = scales
    return np.clip(np.log(np.asarray(s, float) / s0) / np.log(s1 / s0), 0.0, 1.0)


_SETS = ("h_edge", "h_free", "v_edge", "v_free", "small", "big")

#: Table 1.1's features: (name, pixel set, map channel, term) — channels 0 |∇_x I|, 1 |∇_y I|,
#: 2 the small DoG, 3 the large DoG; the term is r^h, r^v or r^c
_BASE_SPEC = (("h_edge", "h_edge", 1, "h"), ("h_free_s", "h_free", 2, "h"), ("h_free_l", "h_free", 3, "h"),
              ("v_edge", "v_edge", 0, "v"), ("v_free_s", "v_free", 2, "v"), ("v_free_l", "v_free", 3, "v"),
              ("small_s", "small", 2, "c"), ("small_l", "small", 3, "c"), ("big_s", "big", 2, "c"),
              ("big_l", "big", 3, "c"))


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

    ``log r`` is a weighted sum of the pixel-set means of :meth:`features`
    plus a bias: ``log r^h`` takes the horizontal-edge band and the horizontal
    free stripes, ``log r^v`` the vertical ones, ``log r^c`` the character
    areas and the bias — Table 1.1's ten means, plus the layout's extra pixel
    sets that have a coefficient, each in the term its layout entry names.
    ``weights="thesis"`` is the thesis's form above, every
    coefficient ``±κ``; ``weights="learnt"`` (default where the layout has them)
    are coefficients fitted on synthetic clips (:mod:`~vistrack.models.plate_fit`),
    for which ``log r`` is the log-odds of a plate at the pose.

    Parameters
    ----------
    layout : str or PlateLayout
    kappa : float
        Sharpness ``κ`` of the thesis weights.
    weights : {"learnt", "thesis"}, (dict, float) or (dict, (float, float), (s_0, s_1))
        Coefficients per feature name and bias; or scale-banded: a pair per name and for the
        bias, their values at plate widths ``s_0`` and ``s_1`` px, interpolated in log s
        (:meth:`coef`; the learnt JP weights are of this kind).
    per_unit : int
        Sample points per unit length of the plate square in each pixel set (half that in the
        extra sets, which are larger and smoother).
    sharpness : float
        ``log r`` is this times the weighted sum (the thesis's ``κ`` for the learnt log-odds).
        On 10 clips × 10 runs (Table 1.1's ten features, box window), 1 / 2 / 3 gave LIS-100
        P(lost) 0.245 / 0.176 / 0.156 and bootstrap-750 0.377 / 0.451 / 0.520: a sharper ``r``
        helps LIS and hurts bootstrap
        (vertex error LIS 5.95 / 5.97 / 6.73, bootstrap 4.31 / 5.42 / 6.58 px). 1 keeps
        ``log r`` the calibrated log-odds.
    """

    #: point sets of the scans, built on first use (:meth:`loglik_sparse`, :meth:`scan`)
    _sparse = None
    _scan_sets = None

    def __init__(self, layout="jp", *, kappa=2.0, weights="learnt", per_unit=24, scan_per_unit=6, sharpness=1.0):
        self.layout = LAYOUTS[layout] if isinstance(layout, str) else layout
        self.kappa = float(kappa)
        if isinstance(weights, str):
            if weights not in ("learnt", "thesis"):
                raise ValueError(f"weights must be 'learnt', 'thesis' or (dict, bias), got {weights!r}")
            learnt = LEARNT_WEIGHTS.get(self.layout.name)
            weights = learnt if weights == "learnt" and learnt is not None else thesis_weights(self.kappa)
        coef, bias, *scales = weights
        #: the two plate widths (px) of scale-banded weights, or None: the coefficients at a pose are
        #: interpolated in log s between the values at these widths (constant outside them)
        self.scales = tuple(float(v) for v in scales[0]) if scales else None
        #: the layout's extra pixel sets that have a coefficient (see ``PlateLayout.extra``)
        self.extra = tuple(e for e in self.layout.extra if np.any(coef.get(e[0], 0.0)))
        # extra features on the same rectangles share one pixel set (named after the first)
        set_of = {}
        for name, rects, _, _ in self.extra:
            set_of.setdefault(tuple(map(tuple, rects)), name)
        self._extra_sets = {k: np.array(r, float) for r, k in set_of.items()}
        #: (name, pixel set, channel, term) of each column of :meth:`features`
        self.spec = _BASE_SPEC + tuple((name, set_of[tuple(map(tuple, rects))], ch, term)
                                       for name, rects, ch, term in self.extra)
        #: names of the columns of :meth:`features`: Table 1.1's ten, then the extra sets
        self.FEATURES = tuple(f[0] for f in self.spec)
        self._terms = {t: np.array([i for i, f in enumerate(self.spec) if f[3] == t], int) for t in "hvc"}
        #: coefficients ``(2, F)`` and bias ``(2,)`` at the two widths of :attr:`scales` (equal rows
        #: when the weights do not depend on the scale)
        self.w = np.array([np.broadcast_to(coef.get(n, 0.0), 2) for n in self.FEATURES], float).T
        self.bias = np.broadcast_to(np.asarray(bias, float), 2).copy()
        self.learnt = weights is not None and weights is LEARNT_WEIGHTS.get(self.layout.name)
        #: learnt weights apply to ``log(1 + mean)``, the thesis's to the means themselves
        self.transform = np.log1p if self.learnt else (lambda v: v)
        #: ``log r = sharpness · (w · features + bias)`` (the learnt coefficients give log-odds at 1)
        self.sharpness = float(sharpness)
        self.w *= self.sharpness
        self.bias *= self.sharpness
        sets = self.layout.sets()
        extra_sets = self._extra_sets
        # the extra sets are larger and smoother: half the density
        self.points = {k: _grid_points(sets[k], per_unit) for k in _SETS}
        self.points.update({k: _grid_points(r, per_unit // 2) for k, r in extra_sets.items()})
        #: sparser point sets for the proposal's scans (:meth:`scan`)
        self.scan_points = {k: _grid_points(sets[k], scan_per_unit) for k in _SETS}
        self.scan_points.update({k: _grid_points(r, max(2, scan_per_unit // 2)) for k, r in extra_sets.items()})
        self._all, self._slices = self._stack(self.points)

    def _stack(self, points, names=None):
        """The sample points of pixel sets ``names`` (default all) in one array, and each set's slice."""
        names = names or _SETS + tuple(self._extra_sets)
        bounds = np.cumsum([0] + [len(points[k]) for k in names])
        return np.concatenate([points[k] for k in names]), {k: slice(bounds[i], bounds[i + 1])
                                                           for i, k in enumerate(names)}

    def coef(self, states):
        """The coefficients ``(N, F)`` and bias ``(N,)`` at each pose's scale ``s``: with
        scale-banded weights ``(1 - a) w_0 + a w_1``, ``a = log(s / s_0) / log(s_1 / s_0)`` clipped
        to [0, 1]; the same row for every pose otherwise."""
        n = len(np.atleast_2d(states))
        if self.scales is None:
            return np.broadcast_to(self.w[0], (n, self.w.shape[1])), np.full(n, self.bias[0])
        a = scale_band(np.atleast_2d(states)[:, 3], self.scales)
        return (1 - a)[:, None] * self.w[0] + a[:, None] * self.w[1], (1 - a) * self.bias[0] + a * self.bias[1]

    def maps(self, obs):
        """The 4-channel map ``(|∇_x I|, |∇_y I|, |G_s I|, |G_l I|)``, each over its frame mean (cached)."""
        m = getattr(obs, "_plate_maps", None)
        if m is None:
            chans = [np.abs(obs.gx), np.abs(obs.gy), np.abs(obs.dog_small), np.abs(obs.dog_large)]
            chans = [c / max(float(cv2.mean(c)[0]), 1e-6) for c in chans]
            m = cv2.merge([c.astype(np.float32) for c in chans])
            obs._plate_maps = m
        return m

    #: the Table 1.1 columns of :meth:`features` (an instance's ``FEATURES`` adds the layout's extra sets)
    BASE_FEATURES = ("h_edge", "h_free_s", "h_free_l", "v_edge", "v_free_s", "v_free_l", "small_s", "small_l",
                     "big_s", "big_l")

    def features(self, obs, states):
        """The pixel-set means ``(N, len(FEATURES))``: Table 1.1's edge bands on their Sobel channel,
        free stripes and character areas on each DoG separately, then the layout's extra sets
        (columns :attr:`FEATURES`)."""
        pose = np.atleast_2d(states)[:, :4]
        pts = plate_points(pose, self._all, self.layout.aspect)
        v = remap_points(self.maps(obs), pts[..., 0].astype(np.float32), pts[..., 1].astype(np.float32),
                         border=(0.0, 0.0, 5.0, 5.0))
        return self._set_means(v, self._slices)

    def _set_means(self, v, sl):
        return np.stack([v[:, sl[ps], ch].mean(axis=1) for _, ps, ch, _ in self.spec], axis=1)

    def _shifted_samples(self, obs, states, points, offsets):
        """The 4 maps at the plate points ``points`` of every pose shifted by ``offsets (N, C, 2)``
        px: ``(N, C, P, 4)`` (the points are placed once per pose, then shifted)."""
        base = plate_points(np.atleast_2d(states)[:, :4], points, self.layout.aspect)  # (N, P, 2)
        mx = (base[:, None, :, 0] + offsets[:, :, None, 0]).astype(np.float32)  # (N, C, P)
        my = (base[:, None, :, 1] + offsets[:, :, None, 1]).astype(np.float32)
        return remap_points(self.maps(obs), mx, my, border=(0.0, 0.0, 5.0, 5.0))

    def loglik_sparse(self, obs, states, offsets):
        """``log r`` from the sparser point sets of the scans (``scan_per_unit``) at every pose
        shifted by ``offsets (N, C, 2)`` px: ``(N, C)``. The entering particles' coarse 2-D search of
        the proposal (any exactly computed density will do)."""
        if self._sparse is None:
            self._sparse = self._stack(self.scan_points)
        points, sl = self._sparse
        n, c = offsets.shape[:2]
        v = self._shifted_samples(obs, states, points, offsets).reshape(n * c, -1, 4)
        w, b = self.coef(states)
        f = self.transform(self._set_means(v, sl)).reshape(n, c, -1)
        return np.einsum("ncf,nf->nc", f, w) + b[:, None]

    def terms(self, obs, states):
        """``(log r^h, log r^v, log r^c)`` as three ``(N,)`` arrays (the bias is in ``log r^c``)."""
        w, b = self.coef(states)
        f = self.transform(self.features(obs, states)) * w
        h, v, c = (f[:, self._terms[t]].sum(axis=1) for t in "hvc")
        return h, v, c + b

    def scan(self, obs, states, which, offsets):
        """``log r^h`` (``which="h"``) or ``log r^v`` at every pose shifted by ``offsets (N, k, 2)`` px.

        The proposal's line scans (§4.5.2): the sample points of the term's pixel
        sets are placed once per particle and shifted, and the sets are sampled
        more sparsely (``scan_per_unit``) than in :meth:`loglik` — the proposal
        may be any density computed exactly; the weight uses the full ``r``.
        Returns ``(N, k)``.
        """
        if self._scan_sets is None:
            self._scan_sets = {}
            for t in "hv":
                idx = self._terms[t]
                names = tuple(dict.fromkeys(self.spec[i][1] for i in idx))
                pts, sl = self._stack(self.scan_points, names)
                self._scan_sets[t] = (pts, [(sl[self.spec[i][1]], self.spec[i][2], i) for i in idx])
        pts, cols = self._scan_sets[which]
        v = self._shifted_samples(obs, states, pts, offsets)
        t, w = self.transform, self.coef(states)[0]
        return sum(w[:, i, None] * t(v[..., sl, ch].mean(axis=-1)) for sl, ch, i in cols)

    def loglik(self, obs, states):
        """``log r = log r^h + log r^v + log r^c`` ``(N,)``."""
        h, v, c = self.terms(obs, states)
        return h + v + c


class Plate(VideoModelBase):
    """License-plate tracking model (thesis 001, §1.3.2, §4.5.2).

    State ``(u, w, θ, s, u', w', θ', s', a)``: centre, angle of the non-vertical
    sides, width (px), their previous values, and the lineage's age ``a`` — frames
    since its entering draw (0 for a draw of the entering component, +1 per AR(2)
    step; it changes neither ``K`` nor ``r``, only what the resampling reserve keeps). Dynamics: with probability
    0.9 a factored AR(2), ``z_t = z_{t-1} + d (z_{t-1} - z_{t-2}) + σ ε``; with
    probability 0.1 a new car entering, ``z_t ~ N(m_e, diag(σ_e²))`` with zero
    velocity (previous = current). Likelihood: :class:`PlateLikelihood`.
    Local moves act on translation ``(u, w)`` (§4.5.2), and for an entering particle also on
    the scale; an entering particle moves its previous pose along (it stays a zero-velocity start).

    Parameters
    ----------
    frame_size : tuple of int
    layout : str
    enter_weight : float
        Weight of the entering-car component (0.1).
    sharpness : float
        Multiplies ``log r`` (:class:`PlateLikelihood`); :meth:`visible` still thresholds the
        log-odds.
    enter_mean, enter_std : array_like of 4 floats
        The entering-car Gaussian over ``(u, w, θ, s)``. Default: ``u`` over the frame (0.5 W,
        sd 0.35 W); ``w``, ``θ``, ``s`` from the plates of the 16 training clips
        (:mod:`~vistrack.models.plate_fit`'s seeds): their mean ``w`` 0.69 H and ``s`` 0.125 W,
        with twice their spread (sd 0.025 H and 0.010 W there: 0.05 H and 0.02 W) and ``θ`` sd
        0.1 rad (0.06 there). The earlier hand-set 0.1 H and 0.03 W left most births 20–50 %
        off the entering plate's scale, where the entering search does not reach it (births
        at the suite's entering frames ended within a third of the plate height 9.4 % of the
        time, 16 % now); on 10 clips × 10 runs LIS-100 P(lost) 0.055 → 0.038, mean acquisition
        delay 2.1 → 1.4 frames. A scene where plates appear elsewhere or at other sizes needs
        its own values.
    enter_sides : float
        Share of the entering component placed where cars come in — Gaussians at the
        left and right borders (``u`` at 0.1 W and 0.9 W, sd 0.07 W), the rest the broad
        Gaussian over the road (§1.3.2: "cars appear on one side of the image and
        disappear at the other end").
    birth_reserve : float
        Share ``ε`` of the resampled particles that goes to the young lineages
        (:meth:`reserved`), ∝ their likelihood, with the offspring weights corrected (unbiased).
        A plate that enters while the track sits on a sign or a lane mark is found by the
        births, but the entering density's small mass at the plate's pose (about e^-12 of
        the tracked pose's) lets plain resampling drop them; kept with a small weight, they
        take over in the next frames. On 10 clips × 10 runs, ε = 0.05 for the fresh births
        gave LIS-100 P(lost) 0.085 instead of 0.105 (bootstrap-750: 0.178 instead of 0.226);
        0.15 gave no further gain.
    reserve_age : int
        Lineages younger than this many frames are reserved. Reserving only the fresh
        births kept a birth through one resampling, and its offspring — still at a small
        weight, with a rough pose — were dropped at the next. On 10 clips × 10 runs (with the
        refined entering search), ages < 1 / 3 / 5 frames: acquired within 10 frames 99 / 99
        / 100 % of 300 appearances.
    """

    dim = 9
    first_step = False

    def __init__(self, frame_size, layout="jp", *, enter_weight=0.1, damping=(0.8, 0.8, 0.5, 0.5), sigma=None,
                 enter_mean=None, enter_std=None, enter_sides=0.5, kappa=2.0, weights="learnt", sharpness=1.0,
                 birth_reserve=0.05, reserve_age=5):
        w, h = frame_size
        self.frame_size = (int(w), int(h))
        self.lik = PlateLikelihood(layout, kappa=kappa, weights=weights, sharpness=sharpness)
        #: the estimate is reported visible when ``log r`` at it exceeds this: with the learnt
        #: coefficients log-odds 2.5, the lowest with no false report on the 16 training clips
        #: (LIS-100 × 5 runs: 1 / 1.5 / 2 / 2.5 / 3 gave 37 / 30 / 13 / 0 / 0 false reports in 80
        #: runs, all on one sign, at P(lost) 0.053 / 0.055 / 0.058 / 0.062 / 0.068);
        #: 10 for the thesis's coefficients (not calibrated)
        self.visible_loglik = 2.5 if self.lik.learnt else 10.0
        self.visible_margin = 4.0
        self.layout = self.lik.layout
        self.enter_weight = float(enter_weight)
        self.damping = np.asarray(damping, float)
        self.sigma = np.asarray(sigma if sigma is not None else (0.012 * w, 0.008 * h, 0.01, 0.004 * w), float)
        self.enter_mean = np.asarray(enter_mean if enter_mean is not None else (0.5 * w, 0.69 * h, 0.0, 0.125 * w),
                                     float)
        self.enter_std = np.asarray(enter_std if enter_std is not None else (0.35 * w, 0.05 * h, 0.1, 0.02 * w),
                                    float)
        self.enter_sides = float(enter_sides)
        #: share of the resampled particles kept for the entering-car births (see
        #: :meth:`~vistrack.filters.base.ParticleFilter.resampling_probs`)
        self.birth_reserve = float(birth_reserve)
        #: lineages younger than this many frames since their entering draw are in the reserve
        self.reserve_age = int(reserve_age)
        #: entering components: (weight, mean, std) — the broad one and one per side
        side_std = np.array([0.07 * w, self.enter_std[1], self.enter_std[2], self.enter_std[3]])
        self._enter_parts = [(1.0 - self.enter_sides, self.enter_mean, self.enter_std)] + [
            (self.enter_sides / 2, np.array([fx * w, *self.enter_mean[1:]]), side_std) for fx in (0.1, 0.9)]
        self.prior_mean = np.concatenate([self.enter_mean, self.enter_mean, [0.0]])
        #: plate widths (px) the model allows; the dynamics clip to it
        self.scale_range = (0.05 * w, 0.4 * w)

    # -- dynamics ----------------------------------------------------------------
    def _enter(self, n, rng):
        weights = np.array([p[0] for p in self._enter_parts])
        comp = rng.choice(len(weights), size=n, p=weights / weights.sum())
        means = np.array([p[1] for p in self._enter_parts])[comp]
        stds = np.array([p[2] for p in self._enter_parts])[comp]
        z = means + stds * rng.standard_normal((n, 4))
        z[:, 3] = np.clip(z[:, 3], *self.scale_range)
        return np.concatenate([z, z, np.zeros((n, 1))], axis=1)

    def enter_logpdf(self, z):
        """Log density of the entering-car mixture at poses ``z (N, 4)``."""
        parts = [np.log(wt) + self._logn(z, m, sd) for wt, m, sd in self._enter_parts if wt > 0]
        return np.logaddexp.reduce(np.stack(parts), axis=0)

    #: optional ``(mean, std)`` of the first pose (``--init``); else the entering density
    start = None

    def sample_prior(self, n, rng):
        if self.start is None:
            return self._enter(n, rng)
        mean, std = self.start
        z = mean + std * rng.standard_normal((n, 4))
        return np.concatenate([z, z, np.zeros((n, 1))], axis=1)

    def _logn(self, x, mean, std):
        """``log N(x; mean, diag(std²))`` over the last axis."""
        e = (x - mean) / std
        return -0.5 * np.sum(e * e, axis=-1) - np.sum(np.log(std)) - 0.5 * x.shape[-1] * np.log(2 * np.pi)

    def prior_logpdf(self, states):
        if self.start is None:
            return self.enter_logpdf(states[:, :4])
        mean, std = self.start
        return self._logn(states[:, :4], mean, std)

    def predict_mean(self, states):
        z1, z2 = states[:, :4], states[:, 4:8]
        return np.concatenate([z1 + self.damping * (z1 - z2), z1, states[:, 8:] + 1], axis=1)

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
        return np.all(states[:, 4:8] == states[:, :4], axis=1)

    def reserved(self, particles):
        """The particles the resampling reserve keeps (:attr:`birth_reserve`): the lineages
        younger than :attr:`reserve_age` frames since their entering draw (the fresh births
        when the states carry no age)."""
        x = particles.states
        return x[:, 8] < self.reserve_age if x.shape[1] > 8 else self.entering(x)

    def transition_logpdf(self, new, old):
        """``log K(new|old)`` for the branch ``new`` came from (AR(2) or entering car)."""
        ar = np.log1p(-self.enter_weight) + self._logn(new[:, :4], self.predict_mean(old)[:, :4], self.sigma)
        ent = np.log(self.enter_weight) + self.enter_logpdf(new[:, :4])
        return np.where(self.entering(new), ent, ar)

    def estimate(self, particles):
        """The weighted mean of the particles about the posterior's main mode: those within half
        a plate (centre) and 25 % (scale) of the highest-weight particle. With one plate in the
        model a posterior split between the plate and a plate-like sign would otherwise put the
        mean between them."""
        x, w = particles.states, particles.weights
        best = x[np.argmax(w)]
        near = (np.hypot(x[:, 0] - best[0], x[:, 1] - best[1]) <= 0.5 * best[3]) & \
            (np.abs(x[:, 3] - best[3]) <= 0.25 * best[3])
        return (w[near] @ x[near]) / w[near].sum()

    # -- appearance learned from an --init box (real footage) -------------------------
    #: :class:`~vistrack.models.appearance.Appearance` of the plate in the first frame
    #: (:meth:`learn_appearance`); ``None``: the plate likelihood alone
    app = None

    def learn_appearance(self, frame, box, **params):
        """Add the box model's appearance term, learned from the plate at ``box (x, y, w, h)``
        in the first ``frame``: ``log r = log r_plate + log r_app`` on the parallelogram's
        bounding box. The plate likelihood was fitted to rendered plates; the learned colour
        and template follow a plate of any colour and font (a yellow plate, a white plate on
        a white car). Returns the :class:`~vistrack.models.appearance.Appearance`."""
        from .appearance import Appearance

        self.app = Appearance(frame, box, **params)
        return self.app

    def observe(self, maps, particles):
        """The feature maps, with (when the model has an appearance) the appearance maps of the
        whole frame at the appearance's working resolution as ``maps.appearance`` (entering
        cars can be anywhere)."""
        if self.app is not None:
            h, w = maps.shape
            maps.appearance = self.app.frame(maps.frame, (0, 0, w, h))
        return maps

    def _app_boxes(self, states):
        x, y, w, h = self.box(states).T
        return np.stack([x + w / 2, y + h / 2, w, h], axis=1)

    def adapt(self, obs, estimate):
        """Adapt the appearance on a confident frame (:meth:`Appearance.adapt`)."""
        if self.app is None:
            return False
        return self.app.adapt(obs.appearance, self._app_boxes(estimate)[0])

    # -- likelihood and output ------------------------------------------------------
    def loglik(self, obs, states):
        ll = self.lik.loglik(obs, states)
        if self.app is not None:
            ll = ll + self.app.loglik(obs.appearance, self._app_boxes(states))
        return ll

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
        """Whether a plate is reported at ``state``: ``log r`` above :attr:`visible_loglik` and the
        whole parallelogram at least :attr:`visible_margin` px inside the frame (the ground truth
        counts a plate as in view when it is wholly inside; an estimate at the border is as
        likely a plate half gone). With a learned appearance (:meth:`learn_appearance`), also
        when the estimate matches the first frame's plate: the template's ``ncc`` at least the
        appearance's adaptation bar (0.6)."""
        s = np.asarray(state, float).reshape(1, -1)
        v = self.vertices(s)[0]
        w, h = self.frame_size
        d = self.visible_margin
        inside = bool(np.all((v[:, 0] >= d) & (v[:, 0] <= w - 1 - d) & (v[:, 1] >= d) & (v[:, 1] <= h - 1 - d)))
        if not inside:
            return False
        if bool(self.lik.loglik(obs, s)[0] / self.lik.sharpness > self.visible_loglik):
            return True
        if self.app is None:
            return False
        _, _, ncc = self.app.terms(obs.appearance, self._app_boxes(s))
        return bool(ncc[0] >= self.app.adapt_min_ncc)

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

    def loglik_local_grid(self, obs, states, offsets):
        """LLS's grid (:class:`~vistrack.filters.lls.LLS`): ``log r`` at every pose shifted by the
        translation ``offsets (G, 2)``, from the sparse point sets of the LIS scans — ``(N, G)``.
        Only LLS's proposal uses it; its weight takes the full ``r`` at the drawn pose."""
        off = np.broadcast_to(np.asarray(offsets, float)[None], (len(states),) + np.shape(offsets))
        return self.lik.loglik_sparse(obs, states, off)

    def lls_window(self):
        size = self.enter_mean[3]
        return Window("box", (size, size / self.layout.aspect), grid=9)


class PlateLISProposal:
    """The §4.5.2 proposal: ``W' ~ r^h(Y|U, ·, θ) g_1(·)``, then ``U' ~ r^v(Y|·, W', θ) g_0(·)``.

    Two kinds of window ``g``:

    * ``window="dynamics"`` (default) for a particle that follows a plate: ``g_1``, ``g_0`` are the
      (w, u) factors of the AR(2) kernel itself, ``N(·; m, σ)`` about the predicted mean ``m``
      (from ``prev``), over ``± window_sigmas σ`` (at most the plate size; the 0.3 % of ``K``'s
      mass per axis beyond 3σ is left out: 4σ was worse, with coarser cells). Then
      ``q(Z) = K_{θ,s}(Z) q^h(W') q^v(U'|W')`` and the weight is ``r(Z) N_{u,w}(Z) / (q^h q^v)``:
      the draw of ``X``'s translation is integrated out, so its factor ``K(Z)/K(X)`` — which spans
      e^±4.5 over a ±3σ box and was the largest part of the log-weight variance (6.1 of 14.6
      on tracked plate frames) — is gone (ESS 28 instead of 10 of 100 on the synthetic suite).
    * ``window="box"``, and always for a particle of the entering-car component: boxes about ``X``
      with half-widths ``window_sigmas`` σ of the AR(2) noise (tracked; at most the plate size) or
      the plate's width and height (entering: over twice the plate size the entering density is
      nearly flat), with ``g`` the box's uniform density in the weight
      ``r(Z) g / (q^h q^v) · K(Z)/K(X)`` — boxes of different sizes would otherwise favour the
      particles with the larger box. An entering particle first draws a cell of its window from
      a coarse grid, ∝ the full likelihood at the cell centres (sparsely sampled), then a cell
      of ``log s`` ∝ the same at that centre, then runs the line scans inside it (:meth:`_search`).

    All conditionals are sampled on grids of ``cells`` cells per line (the density is piecewise
    constant and used exactly). ``filters/lis.py`` computes ``α r / q · K(Z)/K(X)`` with
    ``α = 1``; the returned ``log q`` is set so that this is the weight above.
    """

    def __init__(self, model, cells=24, window_sigmas=3.0, coarse=(12, 6), fine=8, window="dynamics",
                 scale_cells=5, scale_span=0.35, scale_fine=5, angle_cells=9, angle_span=0.25, rescan=True,
                 birth_beta=2.0):
        if window not in ("dynamics", "box"):
            raise ValueError(f"window must be 'dynamics' or 'box', got {window!r}")
        self.model = model
        #: entering particles also search the scale: ``scale_cells`` cells of ``log s`` over
        #: ``± scale_span`` about the drawn scale (1 cell, or span 0: translation only), each
        #: refined into ``scale_fine`` sub-cells after the line scans
        self.scale_cells = int(scale_cells) if scale_span > 0 else 1
        self.scale_span = float(scale_span) if self.scale_cells > 1 else 0.0
        self.scale_fine = max(int(scale_fine), 1)
        #: ... and the angle: ``angle_cells`` cells over ``± angle_span`` rad about the drawn angle
        self.angle_cells = int(angle_cells) if angle_span > 0 else 1
        self.angle_span = float(angle_span) if self.angle_cells > 1 else 0.0
        #: scan (u, w) again inside the coarse cell at the refined angle and scale
        self.rescan = bool(rescan)
        #: the entering search draws its cells ∝ r^β (β > 1: tempered towards the best cell)
        self.birth_beta = float(birth_beta)
        self.cells = int(cells)
        self.window = window
        self.window_sigmas = float(window_sigmas)
        self.coarse = tuple(int(c) for c in coarse)
        self.fine = int(fine)

    def _conditional(self, log_vals, rng, beta=1.0):
        """Draw a cell per row ∝ exp(log_vals) and return (index, log prob of the cell)."""
        from ..particles import logsumexp

        log_vals = beta * log_vals

        lz = logsumexp(log_vals, axis=1)
        j = np.argmax(log_vals + rng.gumbel(size=log_vals.shape), axis=1)
        return j, log_vals[np.arange(len(j)), j] - lz

    def sample(self, x, obs, rng, prev=None):
        m = self.model
        n = len(x)
        ent = m.entering(x)
        uv, log_q = np.empty((n, 2)), np.zeros(n)
        half = m.plate_size(x)
        dyn = ~ent & (self.window == "dynamics") & (prev is not None)
        box = ~ent & ~dyn
        if dyn.any():
            sig = m.sigma[:2]
            mean = m.predict_mean(prev[dyn])[:, :2]
            half[dyn] = np.minimum(half[dyn], self.window_sigmas * sig)
            uv[dyn], lq = self._line_scans(x[dyn], obs, rng, mean, half[dyn], self.cells, prior=(mean, sig))
            # LIS adds K(Z)/K(X) = N_uw(Z)/N_uw(X) (same θ, s): take N_uw(X) out of q
            log_q[dyn] = lq - m._logn(x[dyn, :2], mean, sig)
        if box.any():
            half[box] = np.minimum(half[box], self.window_sigmas * m.sigma[:2])
            uv[box], log_q[box] = self._line_scans(x[box], obs, rng, x[box, :2], half[box], self.cells)
        angle, scale = x[:, 2].copy(), x[:, 3].copy()
        if ent.any():
            uv[ent], angle[ent], scale[ent], log_q[ent] = self._search(x[ent], obs, rng)
        # a box window g is the box's uniform density, 1 / area: with boxes of different sizes
        # (entering or not, plate scale) it must be in the weight, w = r g K(Z) / (K(X) q)
        log_q[~dyn] += np.log(4 * half[~dyn, 0] * half[~dyn, 1])
        z = m.with_local(x, uv)
        z[ent, 2] = z[ent, 6] = angle[ent]  # an entering particle stays a zero-velocity start
        z[ent, 3] = z[ent, 7] = scale[ent]
        return z, np.zeros(n), log_q

    def _line_scans(self, x, obs, rng, centre, half, k, prior=None, beta=1.0):
        """§4.5.2: ``W'`` from ``r^h`` along the vertical line through ``centre`` (``± half[:, 1]``),
        then ``U'`` from ``r^v`` along the horizontal line at ``W'`` (``± half[:, 0]``); ``k`` cells
        per line, each ∝ the scan likelihood at its centre (times the Gaussian ``prior = (mean, std)``
        of (u, w) there, if given). Returns the new ``(u, w)`` and their log density."""
        m = self.model
        n = len(x)
        rows = np.arange(n)
        frac = (np.arange(k) + 0.5) / k * 2 - 1  # cell centres in [-1, 1]
        off = np.zeros((n, k, 2))
        wc = centre[:, 1:2] + frac * half[:, 1:2]  # (n, k) cell centres on the vertical line
        off[:, :, 0] = (centre[:, 0] - x[:, 0])[:, None]
        off[:, :, 1] = wc - x[:, 1:2]
        log_h = m.lik.scan(obs, x, "h", off)
        if prior is not None:
            log_h = log_h - 0.5 * ((wc - prior[0][:, 1:2]) / prior[1][1]) ** 2
        jh, lqh = self._conditional(log_h, rng, beta)
        cell_h = 2 * half[:, 1] / k
        w_new = wc[rows, jh] + cell_h * (rng.random(n) - 0.5)
        uc = centre[:, 0:1] + frac * half[:, 0:1]
        off[:, :, 0] = uc - x[:, 0:1]
        off[:, :, 1] = (w_new - x[:, 1])[:, None]
        log_v = m.lik.scan(obs, x, "v", off)
        if prior is not None:
            log_v = log_v - 0.5 * ((uc - prior[0][:, 0:1]) / prior[1][0]) ** 2
        jv, lqv = self._conditional(log_v, rng, beta)
        cell_v = 2 * half[:, 0] / k
        u_new = uc[rows, jv] + cell_v * (rng.random(n) - 0.5)
        return np.stack([u_new, w_new], axis=1), lqh - np.log(cell_h) + lqv - np.log(cell_v)

    def _draw_cell(self, obs, x, col, values, rng, offsets=None):
        """For each pose of ``x``, one of ``values (n, k)`` of its state column ``col``, drawn ∝ the
        sparse ``r^β`` with that value (at ``offsets (n, 2)`` px from the pose, if given).
        Returns (index, log prob of the cell)."""
        n, k = values.shape
        xs = np.repeat(x, k, axis=0)
        xs[:, col] = values.ravel()
        at = np.zeros((n * k, 1, 2)) if offsets is None else np.repeat(offsets, k, axis=0)[:, None]
        return self._conditional(self.model.lik.loglik_sparse(obs, xs, at).reshape(n, k), rng, self.birth_beta)

    def _search(self, x, obs, rng):
        """Entering particles: a coarse cell of the window drawn ∝ the sparse full ``r`` at its
        centre — the line scans alone lock onto bumpers and grilles, which have the plate's
        horizontal edges but no characters — then the line scans inside that cell.

        1. One of the ``coarse`` cells in (u, w) about ``X`` (± the plate size at ``X``'s scale),
           ∝ the sparse ``r`` at its centre.
        2. One of ``scale_cells`` cells of ``log s`` (± ``scale_span`` about ``X``'s), ∝ the sparse
           ``r`` at that centre: an entering scale 20 % off the plate's scores far below it (the
           entering density's scale sd is 23 %).
        3. The line scans inside the (u, w) cell, at the scale cell's centre.
        4. One of ``angle_cells`` cells of ``θ`` (± ``angle_span`` about ``X``'s), ∝ the sparse ``r``
           at the scanned (u, w), uniform inside the cell.
        5. One of ``scale_fine`` sub-cells of the scale cell, ∝ the same, uniform in ``log s`` inside.
        6. With ``rescan``, the line scans of step 3 again at the refined angle and scale. The
           first scan's ``(u, w)`` is then an auxiliary variable whose backward kernel is its
           own density (a function of ``X`` and of the cells that hold ``Z``), so it cancels:
           ``q`` counts the second scan only.

        Every cell is drawn ∝ ``r^β`` (``birth_beta``; β = 2 tempers the draws towards the best
        cell, and ``q`` is that distribution). Steps 1–3 alone (the scale uniform in its 14 %
        cell, the angle the entering draw's) left the births 5–10 px per vertex off the plate
        at log-odds −2 to −4 where the plate scores 6, so a track on a car's body or a sign
        kept the lead for up to 10 frames after a plate came in; births drawn about a plate
        (25 px, 12 px, 0.1 rad, 20 % off) on 15 suite frames ended within a third of the plate
        height 11 % of the time, and 22 % with the whole search. Every step draws a cell of a
        fixed partition, so ``q`` is exact: the product of the cells' probabilities over their
        sizes (``1 / s_Z`` for the uniform density in ``log s``). For the weight, the backward
        window ``g(X|Z)`` is the box of the plate size at ``X``'s scale about ``Z`` times the
        uniform densities of ``log s_X`` on ``log s_Z ± scale_span`` (``1 / (2 span s_X)`` in
        ``s_X``) and of ``θ_X`` on ``θ_Z ± angle_span``. Returns ``(u, w)``, the angle, the scale
        and ``log q(Z|X) - log g_{θ,s}(X|Z)``."""
        m = self.model
        cu, cw = self.coarse
        n = len(x)
        rows = np.arange(n)
        half = m.plate_size(x)
        gu = ((np.arange(cu) + 0.5) / cu * 2 - 1)
        gw = ((np.arange(cw) + 0.5) / cw * 2 - 1)
        du, dw = np.meshgrid(gu, gw, indexing="ij")
        offs = np.stack([du.ravel(), dw.ravel()], axis=1)[None] * half[:, None, :]  # (n, C, 2) px
        j, log_q = self._conditional(m.lik.loglik_sparse(obs, x, offs), rng, self.birth_beta)
        centre = x[:, :2] + offs[rows, j]
        xz = x.copy()
        k, span = self.scale_cells, self.scale_span
        log_s = np.log(x[:, 3])
        if k > 1:
            gs = ((np.arange(k) + 0.5) / k * 2 - 1) * span  # log-scale cell centres
            js, lqs = self._draw_cell(obs, x, 3, x[:, 3:4] * np.exp(gs), rng, centre - x[:, :2])
            log_s = log_s + gs[js]
            xz[:, 3] = np.exp(log_s)
            log_q += lqs
        cell_half = half / np.array([cu, cw])
        uv, lq = self._line_scans(xz, obs, rng, centre, cell_half, self.fine, beta=self.birth_beta)
        if not self.rescan:
            log_q += lq
        xz[:, :2] = uv
        if self.angle_cells > 1:
            ka, span_a = self.angle_cells, self.angle_span
            ga = ((np.arange(ka) + 0.5) / ka * 2 - 1) * span_a
            ja, lqa = self._draw_cell(obs, xz, 2, xz[:, 2:3] + ga, rng)
            cell = 2 * span_a / ka
            xz[:, 2] += ga[ja] + cell * (rng.random(n) - 0.5)
            log_q += lqa - np.log(cell) + np.log(2 * span_a)
        if k > 1:
            cell = 2 * span / k  # the scale cell about log_s, in kf sub-cells
            kf = self.scale_fine
            gf = ((np.arange(kf) + 0.5) / kf - 0.5) * cell
            jf, lqf = self._draw_cell(obs, xz, 3, np.exp(log_s[:, None] + gf), rng)
            sub = cell / kf
            log_s = log_s + gf[jf] + sub * (rng.random(n) - 0.5)
            xz[:, 3] = np.exp(log_s)
            # q's density of s_Z in its sub-cell over g's density of s_X: (1 / (sub s_Z)) / (1 / (2 span s_X))
            log_q += lqf - np.log(sub) - log_s + np.log(2 * span) + np.log(x[:, 3])
        if self.rescan:
            uv, lq = self._line_scans(xz, obs, rng, centre, cell_half, self.fine, beta=self.birth_beta)
            log_q += lq
            xz[:, :2] = uv
        return xz[:, :2], xz[:, 2], xz[:, 3], log_q
