"""A discriminative correlation filter on light- and blur-robust features: the box model's LIS proposal.

The box model (:mod:`~vistrack.models.box.model`) learns, besides its colour histogram and grey template, a
multi-channel correlation filter (MOSSE, Bolme et al. 2010, with several feature channels as DSST's
translation filter, Danelljan et al. 2014) trained online in the Fourier domain around the estimate.
Its response over a search region about the dynamics' prediction is the observation put into the
proposal (thesis 001, §4.5: LIS's importance function ``q_{X,Y}``), and a term of the likelihood.

Features (per pixel of a patch resampled so that the object's ``sqrt(w h)`` is ``cell_size``
pixels, computed once per patch into reused buffers)
    the grey level normalised for brightness and contrast (zero mean, unit std over the patch) and
    ``n_orient`` channels of gradient orientation (unsigned, soft-binned magnitude), each summed over
    a 4x4 cell and divided by the gradient energy of the surrounding 8x8 block (HOG-like: Dalal and
    Triggs 2005), so that a change of light or a blur scales them little.
Filter
    with ``F_k`` the DFT of feature channel ``k`` under a Hann window and ``G`` that of a Gaussian
    label peaked on the object, ``A_k = conj(G) F_k`` and ``B = Σ_k F_k conj(F_k)``, each adapted as
    ``(1 - η) old + η new`` on frames where the model says the object is there; the filter applied is
    ``(1 - γ)`` of the adapted one plus ``γ`` of the first frame's (the anchor against drift). The
    response to a patch ``Z`` is ``y = IDFT(Σ_k conj(A_k) Z_k / (B + λ))``, about 1 at the object.
Scale
    the response is computed at ``n_scales`` scales about the current one (steps of ``scale_step``),
    a scale search as SAMF's; a state ``(cx, cy, l)`` reads the response at its centre bilinearly
    and between scales linearly in ``l`` (:meth:`DCFResponse.read`).
"""

from __future__ import annotations

import cv2
import numpy as np
import scipy.fft as sfft

from .. import kernels
from .features import greedy_peaks
from .filter_features import as_grey as _grey
from .filter_features import compiled_kernels as _compiled
from .filter_features import dcf_features, shrunk_grey

__all__ = ["CorrelationFilter", "DCFResponse", "dcf_features", "shrunk_grey"]


class DCFResponse:
    """The filter's responses on one frame: ``maps (S, H, W) float32`` at log-scales ``log_scales (S,)``
    (ascending), map pixel ``(i, j)`` of scale ``k`` at frame point
    ``centre + ((j, i) - anchor) / px[k]`` (``px[k]``: map pixels per frame pixel)."""

    #: the search's spectra, centre, log-scales and scale factors (:meth:`CorrelationFilter.adapt` with ``reuse``)
    source = None

    def __init__(self, maps, log_scales, centre, anchor, px):
        self.maps = maps
        self.log_scales = np.asarray(log_scales, float)
        self.centre = np.asarray(centre, float)
        self.anchor = np.asarray(anchor, float)
        self.px = np.asarray(px, float)
        k = int(np.argmax(maps.reshape(len(maps), -1).max(axis=1)))
        #: the best scale's index and its peak value and frame position
        self.best = k
        self.peak = float(maps[k].max())
        i, j = np.unravel_index(int(np.argmax(maps[k])), maps[k].shape)
        self.peak_xy = self.centre + (np.array([j, i], float) - self.anchor) / self.px[k]
        self._log_p = {}

    def read(self, states):
        """Response ``(N,)`` at the centres ``states[:, :2]`` (frame px), bilinear in position and linear
        in the log-scale ``states[:, 2]`` between the two nearest scales (held beyond the end ones);
        zero outside the maps."""
        s = np.asarray(states, float)
        ls = self.log_scales
        if kernels.use():
            return _compiled().response_read(self.maps, ls, self.centre, self.anchor, self.px, np.ascontiguousarray(s),
                                 np.empty(len(s)))
        if len(ls) == 1:
            k0 = np.zeros(len(s), np.intp)
            t = np.zeros(len(s))
        else:
            pos = np.clip(np.interp(s[:, 2], ls, np.arange(len(ls))), 0, len(ls) - 1)
            k0 = np.minimum(pos.astype(np.intp), len(ls) - 2)
            t = pos - k0
        out = np.zeros(len(s))
        for k, wk in ((k0, 1 - t), (k0 + 1, t)):  # the two scales about each state, all states at once
            k = np.minimum(k, len(ls) - 1)
            u = (s[:, 0] - self.centre[0]) * self.px[k] + self.anchor[0]
            v = (s[:, 1] - self.centre[1]) * self.px[k] + self.anchor[1]
            out += wk * _bilinear(self.maps, k, u, v)
        return out

    # -- the proposal's density over the best scale's map --------------------------------------------
    def cell_log_p(self, tempering, floor):
        """``log`` probabilities ``(H W,)`` of the best map's cells: ``(1 - s) e / Σ e + s / (H W)`` with
        ``e = exp(t (y - max y))`` (``t, s = tempering, floor``)."""
        key = (float(tempering), float(floor))
        if key not in self._log_p:  # kept: the proposal's draws and its density read it on the same frame
            if kernels.use():  # the arithmetic about numpy's exp and log in two compiled passes (equal)
                dk = _compiled()
                e = np.exp(dk.cell_scores(self.maps[self.best], float(tempering), np.empty(self.maps[0].size)))
                self._log_p[key] = np.log(dk.cell_probabilities(e, float(floor), e))
            else:
                m = self.maps[self.best].astype(float).ravel()
                e = np.exp(tempering * (m - m.max()))
                self._log_p[key] = np.log((1 - floor) * e / e.sum() + floor / e.size)
        return self._log_p[key]

    def cell_cumulative(self, tempering, floor):
        """The cumulative sums ``(H W,)`` of ``exp`` of :meth:`cell_log_p` (the proposal's draws by inversion)."""
        key = ("cumulative", float(tempering), float(floor))
        if key not in self._log_p:
            e = np.exp(self.cell_log_p(tempering, floor))
            self._log_p[key] = _compiled().cumulative(e, np.empty_like(e)) if kernels.use() else np.cumsum(e)
        return self._log_p[key]

    def cell_origin(self):
        """Frame position ``(x, y)`` of the best map's cell ``(0, 0)``'s centre and the cell's side (frame px)."""
        side = 1.0 / self.px[self.best]
        return self.centre - self.anchor * side, side


def _bilinear(maps, k, u, v):
    """Bilinear samples of ``maps[k] (N of (H, W))`` at ``(u, v)`` (column, row; pixel centres at
    integers), one map per point; 0 outside."""
    h, w = maps.shape[1:]
    u0, v0 = np.floor(u).astype(np.intp), np.floor(v).astype(np.intp)
    a, b = u - u0, v - v0
    flat, base = maps.reshape(-1), k * (h * w)
    out = np.zeros(len(u))
    for du, dv, wt in ((0, 0, (1 - a) * (1 - b)), (1, 0, a * (1 - b)), (0, 1, (1 - a) * b), (1, 1, a * b)):
        uu, vv = u0 + du, v0 + dv
        ok = (uu >= 0) & (uu < w) & (vv >= 0) & (vv < h)
        out += np.where(ok, wt * flat[np.where(ok, base + vv * w + uu, 0)], 0.0)
    return out


class CorrelationFilter:
    """A multi-channel correlation filter of one object (module docstring).

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W)
        The first frame.
    box : tuple of float
        ``(x, y, w, h)`` of the object.
    cell_size : float
        The object's ``sqrt(w h)`` in feature pixels.
    padding : float
        The search region is the box grown by ``padding sqrt(w h)`` on each side.
    sigma : float
        The label's std as a share of ``cell_size``.
    lam : float
        ``λ``, the regulariser.
    rate : float
        ``η``, the adaptation rate (0.004, with the box model's collapse ``drop`` of 28:
        ``docs/experiments.md``).
    anchor : float
        ``γ``, the first frame's share of the filter applied.
    n_scales, scale_step : int, float
        The scale search.
    n_orient : int
        Orientation channels.
    reuse : bool
        Adapt on the last search's patch at the scale nearest the estimate's, the label moved to the
        estimate (a phase ramp on its DFT), rather than on a new patch about the estimate (one feature
        extraction and DFT fewer per frame).
    """

    def __init__(self, frame, box, *, cell_size=24.0, padding=1.0, sigma=0.1, lam=1e-2, rate=0.004, anchor=0.2,
                 n_scales=3, scale_step=1.04, n_orient=6, reuse=False):
        x, y, w, h = (float(v) for v in box)
        self.size0 = np.array([w, h])
        self.f = cell_size / np.sqrt(w * h)  # feature px per frame px at scale 1
        side = np.sqrt(w * h)
        pw, ph = (int(np.ceil((v + 2 * padding * side) * self.f)) for v in (w, h))
        self.shape = (cv2.getOptimalDFTSize(ph), cv2.getOptimalDFTSize(pw))
        ph, pw = self.shape
        self.anchor_px = np.array([pw // 2, ph // 2], float)
        self.n_orient = int(n_orient)
        self.lam, self.rate, self.anchor = float(lam), float(rate), float(anchor)
        self.log_scales = (np.arange(n_scales) - (n_scales - 1) / 2) * np.log(scale_step)
        self.hann = np.outer(np.hanning(ph + 2)[1:-1], np.hanning(pw + 2)[1:-1]).astype(np.float32)
        sg = sigma * cell_size
        yy, xx = np.mgrid[0:ph, 0:pw]
        label = np.exp(-0.5 * ((xx - pw // 2) ** 2 + (yy - ph // 2) ** 2) / sg**2)
        self.G = sfft.rfft2(label)
        self._conj_g = np.conj(self.G)
        self._fy, self._fx = sfft.fftfreq(ph)[:, None], sfft.rfftfreq(pw)[None, :]
        self.reuse = bool(reuse)
        self._last = None  # the last search's spectra, centre, log-scales and scale factors
        self._applied = None  # the filter applied (:meth:`filter`)
        self._terms = None  # detect's conj(A) and B + λ of the applied filter, where the compiled adapt made them
        self._feat = {}  # the features of 1 or S patches, by their number
        self._scratch = {}  # dcf_features' work arrays
        self._search = {}  # the whole-frame search's taps and their spectra (:meth:`search_taps`), until adapt
        a, b = self._learn(np.asarray(frame), np.array([x + w / 2, y + h / 2]), 0.0)
        self.A, self.B = a, b
        self.A0, self.B0 = a.copy(), b.copy()

    # -- patches ---------------------------------------------------------------------------------
    def patch(self, frame, centre, log_scale):
        """The grey patch ``(ph, pw) float32`` of ``frame`` (BGR or grey) about ``centre`` (frame px) at
        ``log_scale``: map pixel ``(i, j)`` at frame point ``centre + ((j, i) - anchor) / (f e^l)``."""
        return _grey(self.warp(frame, centre, log_scale))

    def warp(self, frame, centre, log_scale):
        """:meth:`patch` before it is made grey: the frame's pixels there ``(ph, pw[, 3])`` uint8 (or its dtype)."""
        s = self.f * np.exp(-log_scale)
        ph, pw = self.shape
        m = np.array([[1 / s, 0, centre[0] - self.anchor_px[0] / s],
                      [0, 1 / s, centre[1] - self.anchor_px[1] / s]], np.float64)
        return cv2.warpAffine(frame, m, (pw, ph), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                              borderMode=cv2.BORDER_REPLICATE)

    def spectrum(self, frame, centre, log_scales):
        """The windowed features' DFT ``(C, ph, pw // 2 + 1)`` of the patch about ``centre`` at ``log_scales``
        (a float), or ``(S, C, ph, pw // 2 + 1)`` of the patches at each of ``log_scales (S,)`` (one
        batched transform: each the same as on its own)."""
        scales = np.atleast_1d(log_scales)
        if len(scales) not in self._feat:
            self._feat[len(scales)] = np.empty((len(scales), self.n_orient + 1) + self.shape, np.float32)
        feat = self._feat[len(scales)]
        for k, ls in enumerate(scales):
            dcf_features(self.warp(frame, centre, ls), self.n_orient, out=feat[k], scratch=self._scratch,
                         window=self.hann)
        out = sfft.rfft2(feat)
        return out if np.ndim(log_scales) else out[0]

    def _learn(self, frame, centre, log_scale):
        F = self.spectrum(frame, centre, log_scale)
        return self._conj_g * F, np.sum((F * np.conj(F)).real, axis=0)

    # -- detection and adaptation ------------------------------------------------------------------
    def filter(self):
        """``(A, B)`` applied: the adapted filter mixed with the first frame's by ``γ`` (kept until the
        next :meth:`adapt`)."""
        if self._applied is None:
            g = self.anchor
            self._applied = (1 - g) * self.A + g * self.A0, (1 - g) * self.B + g * self.B0
        return self._applied

    def detect(self, frame, centre, log_scale, scales=None):
        """The :class:`DCFResponse` of a search region about ``centre`` at the scales about ``log_scale``
        (``scales``: at ``log_scale`` plus these log-scales instead of the filter's ``n_scales``)."""
        if self._terms is not None:  # made by the compiled adapt
            conj_a, den = self._terms
        else:
            A, B = self.filter()
            den, conj_a = B + self.lam, np.conj(A)
        steps = self.log_scales if scales is None else np.asarray(scales, float)
        spectra = self.spectrum(frame, centre, log_scale + steps)
        if _exact_filter_kernels():
            y = np.empty((len(spectra),) + den.shape, complex)
            for k, Z in enumerate(spectra):
                _compiled().correlate(conj_a, Z, den, y[k])
        else:
            y = np.stack([np.sum(conj_a * Z, axis=0) / den for Z in spectra])
        maps = sfft.irfft2(y, s=self.shape).astype(np.float32)
        px = self.f * np.exp(-(log_scale + steps))
        self._last = (spectra, np.asarray(centre, float).copy(), log_scale + steps, px)
        resp = DCFResponse(maps, log_scale + steps, centre, self.anchor_px, px)
        resp.source = self._last
        return resp

    def adapt(self, frame, centre, log_scale, response=None):
        """Adapt ``A, B`` towards the patch of ``frame`` about the estimate ``centre`` (frame px) at
        ``log_scale`` (on a frame where the object is reported); with ``reuse``, the patch of the search that
        gave ``response`` (a :class:`DCFResponse` of this filter; ``None``: the last search)."""
        last, self._last = self._last if response is None else response.source, None
        self._search = {}
        if self.reuse and last is not None:  # the last search's patch at the nearest scale, the label moved
            spectra, c0, scales, px = last
            k = int(np.argmin(np.abs(scales - log_scale)))
            dx, dy = (np.asarray(centre, float) - c0) * px[k]
            F = spectra[k]
            conj_g = np.conj(self.G * (np.exp(-2j * np.pi * self._fy * dy) * np.exp(-2j * np.pi * self._fx * dx)))
        else:
            F, conj_g = self.spectrum(frame, centre, log_scale), self._conj_g
        if _exact_filter_kernels():  # learn, blend and the applied filter's terms in one compiled pass
            if self._terms is None:
                self._terms = (np.empty(self.A.shape, complex), np.empty(self.B.shape, np.float32))
            _compiled().adapt_filter(F, conj_g, self.A, self.B, self.A0, self.B0, self.rate, self.anchor,
                                     self.lam, *self._terms)
            self._applied = None
            return
        a, b = conj_g * F, np.sum((F * np.conj(F)).real, axis=0)
        r = self.rate
        self.A = (1 - r) * self.A + r * a
        self.B = (1 - r) * self.B + r * b
        self._applied = self._terms = None

    def search(self, frame, log_scale, stride=2, crop=None, peaks=1):
        """Whole-frame search at ``log_scale``: the applied filter's spatial taps (``crop``: those over the
        object's box grown ``crop`` times; ``None``: all, the surroundings too, which on a still background find
        where the object was) correlated with the features of the frame, made grey and shrunk to the filter's
        resolution divided by ``stride``. Returns ``(x, y, value)``: the best centre (frame px) and its response;
        with ``peaks`` > 1, a list of the ``peaks`` best places (:func:`~vistrack.appearance.features.greedy_peaks`),
        best first.

        The channels' correlations are summed in the Fourier domain (one inverse transform for all of them,
        the frame's features zero beyond its edges); the taps and their spectra are kept until the filter
        adapts (:meth:`search_taps`), so a run of searches on the frames of a lost track makes them once."""
        s = self.f * np.exp(-log_scale) / stride
        img = shrunk_grey(frame, s)
        feat = dcf_features(img, self.n_orient)
        ih, iw = img.shape
        taps, (ay, ax) = self.search_taps(stride, crop)
        shape = (sfft.next_fast_len(ih + taps.shape[1] - 1, real=True),
                 sfft.next_fast_len(iw + taps.shape[2] - 1, real=True))
        key = (stride, crop, shape)
        if key not in self._search:  # the taps' conjugate spectra at this size
            self._search[key] = np.conj(sfft.rfft2(taps, s=shape))
        corr = sfft.irfft2(np.einsum("cij,cij->ij", sfft.rfft2(feat, s=shape), self._search[key]), s=shape)
        total = corr[(np.arange(ih) - ay) % shape[0]][:, (np.arange(iw) - ax) % shape[1]]
        half = [int(np.ceil(v)) for v in 0.5 * self.size0 * self.f / stride]  # the object's half box there
        out = [((j + 0.5) / s, (i + 0.5) / s, v) for i, j, v in greedy_peaks(total, half, peaks)]
        return out[0] if peaks == 1 else out

    def search_taps(self, stride, crop):
        """The taps :meth:`search` correlates ``(C, kh, kw) float32`` and the point of them on a frame pixel
        ``(ay, ax)``: ``y[n] = Σ_m h[m] z[n + m - a]``. The applied filter's taps (the object's centre at their
        middle), zero outside the object's box grown ``crop`` times, resized to the filter's resolution divided
        by ``stride`` (``INTER_AREA``, times ``stride²``) and cut to the rows and columns not all zero; kept
        until the filter adapts."""
        if (stride, crop) not in self._search:
            A, B = self.filter()
            taps = sfft.irfft2(A / (B + self.lam)[None], s=self.shape)  # h (C, ph, pw): y[n] = sum_m h[m] z[m + n]
            taps = sfft.fftshift(taps, axes=(1, 2))  # the object's centre at the middle (label at anchor)
            (ph, pw) = self.shape
            if crop is not None:  # zero outside the object's box grown crop times about the middle
                hx, hy = 0.5 * crop * self.size0 * self.f
                taps = taps * np.outer(np.abs(np.arange(ph) - ph // 2) <= hy, np.abs(np.arange(pw) - pw // 2) <= hx)
            k = (max(3, int(round(pw / stride))), max(3, int(round(ph / stride))))
            small = np.stack([cv2.resize(np.ascontiguousarray(t), k, interpolation=cv2.INTER_AREA) for t in taps])
            small = (small * np.float32(stride**2)).astype(np.float32)
            rows, cols = np.flatnonzero(np.abs(small).sum(axis=(0, 2))), np.flatnonzero(np.abs(small).sum(axis=(0, 1)))
            r0, r1 = (rows[0], rows[-1] + 1) if len(rows) else (0, 1)
            c0, c1 = (cols[0], cols[-1] + 1) if len(cols) else (0, 1)
            anchor = (k[1] // 2 - r0, k[0] // 2 - c0)  # filter2D's default anchor, the kernel's middle
            self._search[(stride, crop)] = (np.ascontiguousarray(small[:, r0:r1, c0:c1]), anchor)
        return self._search[(stride, crop)]


def _exact_filter_kernels():
    """Whether ``detect`` and ``adapt`` take the compiled path: the kernels are on and compute numpy's
    complex products on this CPU (:data:`vistrack.appearance.dcf_kernels.EXACT`)."""
    if not kernels.use():
        return False
    return _compiled().EXACT
