"""A correlation filter trained against its background (BACF): the box model's translation filter.

A plain correlation filter (:mod:`~vistrack.models.box.correlation`) learns from the circular shifts of
one patch, so its search region must stay small (the shifts of a large patch are mostly background
wrapped around) and every shift counts as a negative, real or not. Kiani Galoogahi, Fagg and Lucey
(*Learning background-aware correlation filters for visual tracking*, ICCV 2017) learn a filter ``h``
of the object's size (``D`` cells) against the real shifts of a patch ``T`` cells large (here the box
grown by ``padding`` of its side on each side) by constraining the filter to the object's support
``P``:

    ``min_h  ½ ‖y - Σ_k x_k ⋆ Pᵀh_k‖² + λ/2 Σ_k ‖h_k‖²``,

solved by ADMM with ``g = Pᵀh`` in the Fourier domain (a rank-one system per frequency, Sherman–Morrison),
a few iterations a frame from zero, on the running average of the patches' spectra
``x̂ <- (1 - η) x̂ + η x̂_t`` (the model's memory). The response to a patch ``Z`` is
``y = IDFT(Σ_k conj(ĝ_k) Ẑ_k)``, about 1 at the object.

Features
    :func:`~vistrack.models.box.correlation.dcf_features` (brightness-normalised grey and gradient
    orientations, each cell-summed and block-normalised) read at the centres of ``cell × cell`` cells,
    times a Hann window over the cells: the filter works on cells, the response is read bilinearly
    between them.
Scale
    the response at ``n_scales`` scales about the current one (one by default: the box model's scale
    filter, :mod:`~vistrack.models.box.scale_filter`, measures the scale).
"""

from __future__ import annotations

import cv2
import numpy as np
import scipy.fft as sfft

from .correlation import DCFResponse, dcf_features
from .patches import patch

__all__ = ["BackgroundAwareFilter"]


class BackgroundAwareFilter:
    """BACF of one object (module docstring); the interface of
    :class:`~vistrack.models.box.correlation.CorrelationFilter` (``detect``, ``adapt``, ``search``).

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W)
        The first frame.
    box : tuple of float
        ``(x, y, w, h)`` of the object.
    cell_size : float
        The object's ``sqrt(w h)`` in feature pixels.
    cell : int
        The cells' side (feature px).
    padding : float
        The patch is the box grown by ``padding sqrt(w h)`` on each side.
    sigma : float
        The label's std as a share of the object's ``sqrt(w h)`` in cells.
    lam : float
        ``λ``.
    rate : float
        ``η``, the model's adaptation rate.
    anchor : float
        ``γ``: the first frame's share in the spectra the filter is solved on.
    iterations : int
        ADMM iterations a frame.
    n_scales, scale_step : int, float
        The detection's scales.
    n_orient : int
        Orientation channels.
    """

    def __init__(self, frame, box, *, cell_size=32.0, cell=4, padding=1.5, sigma=1 / 16, lam=1e-2, rate=0.013,
                 anchor=0.0, iterations=2, n_scales=1, scale_step=1.02, n_orient=6, mu=1.0, beta=10.0, mu_max=1e4):
        x, y, w, h = (float(v) for v in box)
        self.size0 = np.array([w, h])
        self.cell = int(cell)
        self.f = cell_size / np.sqrt(w * h)  # feature px per frame px at scale 1
        side = np.sqrt(w * h)
        cw, ch = (int(np.ceil((v + 2 * padding * side) * self.f / self.cell)) for v in (w, h))
        cw, ch = cw + cw % 2, ch + ch % 2
        self.cells = (ch, cw)
        self.shape = (ch * self.cell, cw * self.cell)  # the patch in feature px
        self.anchor_px = np.array([cw // 2, ch // 2], float)  # the response map's zero displacement (cells)
        self.support = tuple(max(1, int(round(v * self.f / self.cell))) for v in (h, w))  # D: the filter's cells
        self.n_orient = int(n_orient)
        self.lam, self.rate, self.anchor = float(lam), float(rate), float(anchor)
        self.iterations, self.mu, self.beta, self.mu_max = int(iterations), float(mu), float(beta), float(mu_max)
        self.log_scales = (np.arange(n_scales) - (n_scales - 1) / 2) * np.log(scale_step)
        self.window = np.outer(np.hanning(ch + 2)[1:-1], np.hanning(cw + 2)[1:-1]).astype(np.float32)
        sg = sigma * np.sqrt(np.prod(self.support))
        yy = np.minimum(np.arange(ch), ch - np.arange(ch))[:, None]  # circular distance to the origin
        xx = np.minimum(np.arange(cw), cw - np.arange(cw))[None, :]
        self.yf = sfft.rfft2(np.exp(-0.5 * (xx**2 + yy**2) / sg**2))
        rows, cols = (slice(c // 2 - s // 2, c // 2 - s // 2 + s) for c, s in zip(self.cells, self.support))
        self._crop = (slice(None), rows, cols)
        self._scratch = {}
        self.x0 = self.spectrum(np.asarray(frame), np.array([x + w / 2, y + h / 2]), 0.0)
        self.model = self.x0.copy()
        self.g = self._solve(self.model)

    # -- features ---------------------------------------------------------------------------------
    def warp(self, frame, centre, log_scale):
        """The frame's pixels about ``centre`` at ``log_scale``: the patch ``(ph, pw[, 3])``, feature pixel
        ``(i, j)`` at frame point ``centre + ((j, i) + 0.5 - (pw, ph) / 2) / (f e^{-l})`` (:func:`~.patches.patch`)."""
        ph, pw = self.shape
        return patch(frame, centre, self.f * np.exp(-log_scale), (pw, ph), (pw / 2 - 0.5, ph / 2 - 0.5))

    def features(self, frame, centre, log_scale):
        """The windowed cell features ``(C, ch, cw) float32`` of the patch about ``centre`` at ``log_scale``."""
        feat = dcf_features(self.warp(frame, centre, log_scale), self.n_orient, cell=self.cell, scratch=self._scratch)
        c = self.cell
        return feat[:, c // 2::c, c // 2::c] * self.window

    def spectrum(self, frame, centre, log_scale):
        """``rfft2`` of :meth:`features`: ``(C, ch, cw // 2 + 1)``."""
        return sfft.rfft2(self.features(frame, centre, log_scale))

    # -- learning ---------------------------------------------------------------------------------
    def _solve(self, xf):
        """``ĝ`` of the model spectra ``xf (C, ch, cw//2+1)`` by ADMM (module docstring)."""
        if self.anchor:
            xf = (1 - self.anchor) * xf + self.anchor * self.x0
        T = float(np.prod(self.cells))
        yf = self.yf
        sxx = np.sum((xf.conj() * xf).real, axis=0)
        g = np.zeros_like(xf)
        h = np.zeros_like(xf)
        lf = np.zeros_like(xf)
        mu = self.mu
        for _ in range(self.iterations):
            b = sxx + T * mu
            slx = np.sum(xf.conj() * lf, axis=0)
            shx = np.sum(xf.conj() * h, axis=0)
            g = ((1 / (T * mu)) * yf * xf - lf / mu + h
                 - ((1 / (T * mu)) * xf * (sxx * yf) - xf * slx / mu + xf * shx) / b)
            hs = (T / (mu * T + self.lam)) * sfft.irfft2(mu * g + lf, s=self.cells)
            t = np.zeros_like(hs)
            t[self._crop] = hs[self._crop]
            h = sfft.rfft2(t)
            lf = lf + mu * (g - h)
            mu = min(self.beta * mu, self.mu_max)
        # the response to the model itself made 1 at the object (a few iterations from zero leave it well below)
        y0 = sfft.irfft2(np.sum(g.conj() * xf, axis=0), s=self.cells)[0, 0]
        return g / y0 if y0 > 0 else g

    # -- detection and adaptation -------------------------------------------------------------------
    def detect(self, frame, centre, log_scale):
        """The :class:`~vistrack.models.box.correlation.DCFResponse` of the patch about ``centre`` at the scales
        about ``log_scale`` (maps in cells, zero displacement at the map's middle)."""
        scales = log_scale + self.log_scales
        zf = np.stack([self.spectrum(frame, centre, ls) for ls in scales])
        y = sfft.irfft2(np.sum(self.g.conj()[None] * zf, axis=1), s=self.cells)
        maps = np.ascontiguousarray(sfft.fftshift(y, axes=(1, 2))).astype(np.float32)
        px = self.f * np.exp(-scales) / self.cell  # cells per frame px
        return DCFResponse(maps, scales, centre, self.anchor_px, px)

    def adapt(self, frame, centre, log_scale):
        """Move the model's spectra towards the patch about the estimate and solve the filter anew."""
        r = self.rate
        self.model = (1 - r) * self.model + r * self.spectrum(frame, centre, log_scale)
        self.g = self._solve(self.model)

    def search(self, frame, log_scale, stride=1):
        """Whole-frame search at ``log_scale``: the filter's cells correlated with the frame's cell features.
        Returns ``(x, y, value)``: the best centre (frame px) and its response."""
        taps = sfft.fftshift(sfft.irfft2(self.g, s=self.cells), axes=(1, 2))[self._crop].astype(np.float32)
        s = self.f * np.exp(-log_scale)
        h, w = frame.shape[:2]
        img = cv2.resize(frame, (max(8, int(round(w * s))), max(8, int(round(h * s)))), interpolation=cv2.INTER_AREA)
        c = self.cell
        feat = dcf_features(img, self.n_orient, cell=c)[:, c // 2::c, c // 2::c]
        total = np.zeros(feat.shape[1:], np.float32)
        for k in range(len(feat)):
            total += cv2.filter2D(np.ascontiguousarray(feat[k]), -1, taps[k], borderType=cv2.BORDER_CONSTANT)
        i, j = np.unravel_index(int(np.argmax(total)), total.shape)
        return (j * c + c / 2) / s, (i * c + c / 2) / s, float(total[i, j])
