"""License-plate template likelihood (thesis 001, §1.3.2, Table 1.1).

``r = r^h · r^v · r^c`` with (Table 1.1's pixel sets from a
:class:`~vistrack.models.plate.layout.PlateLayout`)

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

from ... import kernels
from ...appearance.features import remap_points
from .layout import LAYOUTS, plate_points
from .observation import PlateObservation

__all__ = ["PlateLikelihood", "PlateObservation", "plate_map", "thesis_weights", "scale_band", "LEARNT_WEIGHTS"]

#: the maps' values outside the frame (Sobel channels 0, DoG channels 5: a plate half outside scores low)
_BORDER = (0.0, 0.0, 5.0, 5.0)
#: the same as the compiled paths take it
BORDER = np.array(_BORDER, np.float32)


def plate_map(maps):
    """The 4-channel map ``(|∇_x I|, |∇_y I|, |G_s I|, |G_l I|)`` of a frame's
    :class:`~vistrack.appearance.features.FeatureMaps`, each channel over its frame mean (float32 ``(H, W, 4)``).
    Compiled where numba is (:func:`vistrack.models.plate.kernels.plate_map`, equal), into the maps'
    buffer pool."""
    if kernels.use():
        from .kernels import plate_map as compiled

        f = maps.frame
        g8 = f if f.ndim == 2 else cv2.cvtColor(f, cv2.COLOR_BGR2GRAY, dst=maps.buffer("gray8", f.shape[:2], np.uint8))
        h, w = g8.shape
        gx = cv2.Sobel(g8, cv2.CV_32F, 1, 0, dst=maps.buffer("plate_gx", (h, w)), ksize=3,
                       borderType=cv2.BORDER_REFLECT)
        gy = cv2.Sobel(g8, cv2.CV_32F, 0, 1, dst=maps.buffer("plate_gy", (h, w)), ksize=3,
                       borderType=cv2.BORDER_REFLECT)
        sizes = maps.dog_sizes["small"] + maps.dog_sizes["large"]
        sums = maps.buffer("plate_box", (4, h, w), np.int32)
        for k, size in enumerate(sizes):
            cv2.boxFilter(g8, cv2.CV_32S, (size, size), dst=sums[k], normalize=False, borderType=cv2.BORDER_REFLECT)
        out = maps.buffer("plate", (h, w, 4))
        compiled(gx, gy, sums, np.array(sizes, np.int64), out)
        return out
    chans = [np.abs(maps.gx), np.abs(maps.gy), np.abs(maps.dog_small), np.abs(maps.dog_large)]
    chans = [c / max(float(cv2.mean(c)[0]), 1e-6) for c in chans]
    return cv2.merge([c.astype(np.float32) for c in chans])


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



def log1p32(v):
    """``log(1 + v)`` of float32 means, computed in float64 and rounded to float32: the same
    bits as the compiled kernels' on any CPU (numpy's float32 ``log1p`` is a SIMD routine on
    AVX-512 machines that differs from libm's by an ulp; rounding the float64 value hides the
    float64 routines' differences)."""
    return np.log1p(np.asarray(v, dtype=np.float64)).astype(np.float32)

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
    are coefficients fitted on synthetic clips (:mod:`~vistrack.models.plate.fitting`),
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
        self.transform = log1p32 if self.learnt else (lambda v: v)
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
        #: the compiled path's point, set and feature tables per (point sets, features)
        self._kernel_tables = {}

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
        """The 4-channel map ``(|∇_x I|, |∇_y I|, |G_s I|, |G_l I|)``, each over its frame mean: a
        :class:`PlateObservation`'s, else computed from the :class:`~vistrack.appearance.features.FeatureMaps`
        (:func:`plate_map`)."""
        return obs.plate if isinstance(obs, PlateObservation) else plate_map(obs)

    #: the Table 1.1 columns of :meth:`features` (an instance's ``FEATURES`` adds the layout's extra sets)
    BASE_FEATURES = ("h_edge", "h_free_s", "h_free_l", "v_edge", "v_free_s", "v_free_l", "small_s", "small_l",
                     "big_s", "big_l")

    def features(self, obs, states):
        """The pixel-set means ``(N, len(FEATURES))``: Table 1.1's edge bands on their Sobel channel,
        free stripes and character areas on each DoG separately, then the layout's extra sets
        (columns :attr:`FEATURES`)."""
        return self._means(obs, np.atleast_2d(states)[:, :4], self.points, (self._all, self._slices))

    def _means(self, obs, pose, points, stacked):
        """The pixel-set means ``(N, F)`` at ``pose`` on the point sets ``points`` (stacked as
        ``stacked = (points, slices)`` for the numpy path): compiled where numba is."""
        if kernels.use():
            return self._kernel_means(obs, pose, points, np.zeros((len(pose), 1, 2)))[:, 0]
        pts = plate_points(pose, stacked[0], self.layout.aspect)
        v = remap_points(self.maps(obs), pts[..., 0].astype(np.float32), pts[..., 1].astype(np.float32),
                         border=_BORDER)
        return self._set_means(v, stacked[1])

    def _set_means(self, v, sl):
        return np.stack([v[:, sl[ps], ch].mean(axis=1) for _, ps, ch, _ in self.spec], axis=1)

    def _kernel_means(self, obs, pose, points, offsets, cols=None):
        """:func:`vistrack.models.plate.kernels.set_means` of the features ``cols`` (default all) on the
        point sets ``points`` (:attr:`points` or :attr:`scan_points`) at ``pose`` shifted by
        ``offsets (N, C, 2)``: ``(N, C, F)``."""
        from .kernels import set_means

        pts, sets, feats = self.kernel_table(points, cols)
        out = np.empty(offsets.shape[:2] + (len(feats),), np.float32)
        return set_means(self.maps(obs), np.ascontiguousarray(pose, float), np.tan(pose[:, 2]),
                         float(self.layout.aspect), pts, sets, feats, np.ascontiguousarray(offsets, float), BORDER, out)

    def kernel_table(self, points, cols=None):
        """The compiled path's ``(points (P, 2), sets (S, 2), features (F, 2))`` of the features
        ``cols`` (default all) on the point sets ``points`` (:attr:`points` or :attr:`scan_points`):
        the sets' unit-square points stacked, each set's ``(start, count)``, each feature's set and
        map channel (:func:`vistrack.models.plate.kernels.set_means`)."""
        key = (id(points), cols)
        if key not in self._kernel_tables:
            names = tuple(dict.fromkeys(self.spec[i][1] for i in (cols or range(len(self.spec)))))
            pts, sl = self._stack(points, names)
            sets = np.array([[sl[k].start, sl[k].stop - sl[k].start] for k in names], np.int64)
            feats = np.array([[names.index(self.spec[i][1]), self.spec[i][2]] for i in (cols or range(len(self.spec)))],
                             np.int64)
            self._kernel_tables[key] = (pts, sets, feats)
        return self._kernel_tables[key]

    def scan_table(self, which):
        """The line scan ``which`` ("h" or "v") for the compiled path: its :meth:`kernel_table` on
        :attr:`scan_points` and the indices of its features (columns of :meth:`coef`)."""
        idx = tuple(int(i) for i in self._terms[which])
        return self.kernel_table(self.scan_points, idx), np.array(idx)

    def _shifted_samples(self, obs, states, points, offsets):
        """The 4 maps at the plate points ``points`` of every pose shifted by ``offsets (N, C, 2)``
        px: ``(N, C, P, 4)`` (the points are placed once per pose, then shifted)."""
        base = plate_points(np.atleast_2d(states)[:, :4], points, self.layout.aspect)  # (N, P, 2)
        mx = (base[:, None, :, 0] + offsets[:, :, None, 0]).astype(np.float32)  # (N, C, P)
        my = (base[:, None, :, 1] + offsets[:, :, None, 1]).astype(np.float32)
        return remap_points(self.maps(obs), mx, my, border=_BORDER)

    def loglik_sparse(self, obs, states, offsets):
        """``log r`` from the sparser point sets of the scans (``scan_per_unit``) at every pose
        shifted by ``offsets (N, C, 2)`` px: ``(N, C)``. The entering particles' coarse 2-D search of
        the proposal (any exactly computed density will do)."""
        if self._sparse is None:
            self._sparse = self._stack(self.scan_points)
        points, sl = self._sparse
        n, c = offsets.shape[:2]
        if kernels.use():
            means = self._kernel_means(obs, np.atleast_2d(states)[:, :4], self.scan_points, offsets)
        else:
            means = self._set_means(self._shifted_samples(obs, states, points, offsets).reshape(n * c, -1, 4), sl)
        w, b = self.coef(states)
        f = self.transform(means).reshape(n, c, -1)
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
        t, w = self.transform, self.coef(states)[0]
        if kernels.use():
            idx = tuple(i for _, _, i in cols)
            means = self._kernel_means(obs, np.atleast_2d(states)[:, :4], self.scan_points, offsets, idx)
            return sum(w[:, i, None] * t(means[..., j]) for j, i in enumerate(idx))
        v = self._shifted_samples(obs, states, pts, offsets)
        return sum(w[:, i, None] * t(v[..., sl, ch].mean(axis=-1)) for sl, ch, i in cols)

    def loglik(self, obs, states):
        """``log r = log r^h + log r^v + log r^c`` ``(N,)``."""
        h, v, c = self.terms(obs, states)
        return h + v + c

    #: the pixel sets of each half of the plate (:meth:`half_loglik`), built on first use
    _halves = None

    def half_loglik(self, obs, states):
        """``log r`` of the plate's left and right halves alone ``(N, 2)``: each pixel set keeps its
        points with ``a < 1/2`` (left) or ``a ≥ 1/2`` (right; a set with no point in a half keeps all
        of them), and the coefficients of :meth:`loglik` take the means over those. A plate wholly in
        view scores about its whole ``log r`` in both halves; one a car in front covers from one side
        scores low in that side's half, whatever the whole plate's ``log r`` (the report test of
        :class:`~vistrack.models.plate.plates.Plates`)."""
        if self._halves is None:
            halves = tuple({k: (p[m] if m.any() else p) for k, p in self.points.items()
                            for m in [(p[:, 0] < 0.5) if left else (p[:, 0] >= 0.5)]} for left in (True, False))
            self._halves = tuple((h, self._stack(h)) for h in halves)
        pose = np.atleast_2d(states)[:, :4]
        w, b = self.coef(pose)
        return np.stack([np.einsum("nf,nf->n", self.transform(self._means(obs, pose, points, stacked)), w) + b
                         for points, stacked in self._halves], axis=1)
