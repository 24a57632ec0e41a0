"""A one-dimensional correlation filter over scales (DSST's scale filter): the box model's scale cue.

The translation filter (:mod:`~vistrack.appearance.correlation`) sees the object with a margin of
background at three scales; its peak value moves little with the object's size and, on footage where
the object deforms (a walker, a car under changing light), drifts towards larger boxes. Danelljan et
al. (*Accurate scale estimation for robust visual tracking*, BMVC 2014) learn a second filter over
scales only: ``S`` samples of the object's box (no margin) at sizes ``a^k`` about the current one,
each described by the same grid of feature cells, form a ``d × S`` signal ``F`` (times a Hann window
over ``k``); with a Gaussian label ``g`` over ``k`` peaked at the current size, MOSSE's closed form
along ``k``:

    ``A = conj(G) F``,  ``B = Σ_d |F|²``  (DFT along the scales),
    ``y = IDFT(Σ_d conj(A) Z / (B + λ))``,

adapted as ``(1 - η) old + η new`` on frames where the object is reported, and applied as ``(1 - γ)``
of the adapted filter plus ``γ`` of the first frame's. ``y`` over the scales is about 1 at the
object's size; the box model reads it as a term of ``log r`` in the state's log-scale (linearly
between samples) and draws its proposal's log-scale about its peak.

Samples
    The features (:func:`~vistrack.appearance.correlation.dcf_features`) are computed once a frame, on
    one patch about the centre that holds the largest sample (the box at ``a^{S//2}``) and a margin,
    at the resolution where the box at the reference scale is the model's size (about
    ``model_area`` px). Sample ``k``'s cells are the feature map read bilinearly at the cells' centres
    scaled by ``a^k`` (fDSST's economy: one feature extraction for every scale). The DFTs along the scales
    are one matrix product (:meth:`ScaleFilter.spectrum`, their first half: the samples are real), and the
    adaptation reuses the detection's samples with the label moved to the estimate's scale.
"""

from __future__ import annotations

import cv2
import numpy as np

from ... import kernels
from .patches import patch

__all__ = ["ScaleFilter", "ScaleResponse"]


class ScaleResponse:
    """The scale filter's response ``values (S,)`` at log-scales ``log_scales (S,)`` (ascending), with
    its peak (``best``: the index, ``peak``: the value, ``peak_log_scale``: refined by a parabola
    through the peak and its neighbours)."""

    #: the samples' spectra and the log-scale they were taken about (:meth:`ScaleFilter.adapt`)
    source = None

    def __init__(self, log_scales, values):
        self.log_scales = np.asarray(log_scales, float)
        self.values = np.asarray(values, float)
        k = int(np.argmax(self.values))
        self.best, self.peak = k, float(self.values[k])
        off = 0.0
        if 0 < k < len(self.values) - 1:
            a, b, c = self.values[k - 1: k + 2]
            den = a - 2 * b + c
            if den < 0:
                off = float(np.clip(0.5 * (a - c) / den, -0.5, 0.5))
        step = self.log_scales[1] - self.log_scales[0] if len(self.log_scales) > 1 else 0.0
        self.peak_log_scale = float(self.log_scales[k] + off * step)

    def read(self, log_scale):
        """The response ``(N,)`` at log-scales ``log_scale (N,)``: linear between samples, the end values
        held beyond them."""
        return np.interp(np.asarray(log_scale, float), self.log_scales, self.values)


class _FeatureMap:
    """One frame's feature channels ``feat (C, H, W)`` about ``centre`` at ``log_scale``: map pixel
    ``(i, j)`` at frame point ``centre + ((j, i) - anchor) / (px e^{-log_scale})``."""

    def __init__(self, feat, centre, log_scale, anchor, px):
        self.feat, self.centre, self.log_scale, self.anchor, self.px = feat, centre, log_scale, anchor, px


class ScaleFilter:
    """DSST's scale filter of one object (module docstring).

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W)
        The first frame.
    box : tuple of float
        ``(x, y, w, h)`` of the object.
    n_scales : int
        ``S``, the samples over scales (made odd).
    scale_step : float
        ``a``, the ratio of neighbouring samples' sizes.
    model_area : float
        The box at the reference scale covers about this many feature pixels (the object's aspect).
    cell : int
        Feature cells' side (feature px): a sample is the channels at its ``n_x × n_y`` cells' centres.
    lam : float
        ``λ``.
    rate : float
        ``η``.
    anchor : float
        ``γ``, the first frame's share of the filter applied.
    sigma : float
        The label's std in samples.
    n_orient : int
        Orientation channels of :func:`~vistrack.appearance.correlation.dcf_features`.
    window : bool
        Multiply the samples by a Hann window over the scales (DSST's; without it the 18 real clips'
        mean AUC falls by 0.013, ``docs/experiments.md``).

    Notes
    -----
    ``model_area`` 1024 and ``anchor`` 0.2 were chosen by leave-one-clip-out cross-validation over the
    real clips (``benchmarks/tune_box.py``; 512 and 0: mean AUC 0.525 against 0.556–0.563).
    """

    def __init__(self, frame, box, *, n_scales=17, scale_step=1.03, model_area=1024.0, cell=4, lam=1e-2,
                 rate=0.01, anchor=0.2, sigma=0.75, n_orient=6, window=True):
        x, y, w, h = (float(v) for v in box)
        self.size0 = np.array([w, h])
        n_scales = int(n_scales) | 1
        steps = np.arange(n_scales) - n_scales // 2
        self.log_steps = steps * np.log(scale_step)
        f = np.sqrt(model_area / (w * h))
        self.cell = int(cell)
        #: cells across and down the box
        self.cells = tuple(max(2, int(round(v * f / self.cell))) for v in (w, h))
        #: feature px per frame px at log-scale 0 (x, y): the box at the model's size
        self.px = np.array([self.cells[0] * self.cell / w, self.cells[1] * self.cell / h])
        # the patch: the largest sample's box, a cell of gradient support and two cells to move the estimate
        reach = np.exp(self.log_steps[-1])
        self.shape = tuple(int(np.ceil(reach * n * self.cell + 4 * self.cell)) for n in self.cells[::-1])
        self.anchor_px = np.array([self.shape[1] / 2, self.shape[0] / 2])
        self.n_orient = int(n_orient)
        self.lam, self.rate, self.anchor = float(lam), float(rate), float(anchor)
        self.sigma = float(sigma)
        self._conj_g = self._label(0.0)
        j = np.arange(n_scales // 2 + 1)[:, None] * np.arange(n_scales)[None, :] * (2 * np.pi / n_scales)
        self._dft = np.vstack([np.cos(j), -np.sin(j)])  # the real DFT's first half: real parts, then imaginary
        self.window = np.hanning(n_scales + 2)[1:-1] if window else np.ones(n_scales)
        self._applied = None  # conj(A) and B + λ of the filter applied, until the next adapt
        centre = np.array([x + w / 2, y + h / 2])
        F = self.spectrum(self.samples(self.feature_map(np.asarray(frame), centre, 0.0), centre, 0.0))
        self.A = self._conj_g * F
        self.B = _power(F)
        self.A0, self.B0 = self.A.copy(), self.B.copy()

    def feature_map(self, frame, centre, log_scale):
        """The summed-area tables of the per-pixel channels of the grey patch about ``centre`` (frame px) at
        ``log_scale`` that every sample is read from (:class:`_FeatureMap`; ``feat``:
        :func:`~vistrack.models.box.scale_kernels.pixel_channels`)."""
        ph, pw = self.shape
        img = patch(frame, centre, self.px * np.exp(-log_scale), (pw, ph), self.anchor_px)
        grey = (cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.ndim == 3 else img).astype(np.float32)
        if kernels.use():
            from .scale_kernels import N_EXTRA, pixel_channels

            ii = pixel_channels(grey, self.n_orient, np.empty((ph + 1, pw + 1, N_EXTRA + self.n_orient)))
        else:
            ii = grey
        return _FeatureMap(ii, np.asarray(centre, float).copy(), float(log_scale), self.anchor_px, self.px)

    def samples(self, fmap, centre, log_scale):
        """The descriptors ``(S, d)`` of the boxes about ``centre`` at ``log_scale + log_steps``, read from
        ``fmap`` (:func:`~vistrack.models.box.scale_kernels.scale_samples`), each times the scales' Hann window."""
        rel = np.exp(log_scale + self.log_steps - fmap.log_scale)
        nx, ny = self.cells
        widths, heights = nx * self.cell * rel, ny * self.cell * rel  # patch px
        # the point in the tables' coordinates (a pixel's left edge at its index): patch coordinates + 0.5
        ax, ay = fmap.anchor + (np.asarray(centre, float) - fmap.centre) * fmap.px * np.exp(-fmap.log_scale) + 0.5
        if kernels.use():
            from .scale_kernels import scale_samples

            vals = scale_samples(fmap.feat, float(ax), float(ay), widths, heights, nx, ny, self.n_orient,
                                 np.empty((len(rel), self.n_orient + 1, ny, nx), np.float32))
        else:
            from .scale_kernels import scale_samples_numpy

            vals = scale_samples_numpy(fmap.feat, float(ax), float(ay), widths, heights, nx, ny, self.n_orient)
        return vals.reshape(len(rel), -1) * self.window[:, None]

    def spectrum(self, samples):
        """The DFT along the scales ``(S // 2 + 1, d)`` of real ``samples (S, d)``: its first half, the rest its
        conjugate mirror (every product and sum below keeps that symmetry, so the half carries all of it). The
        transform of ``d`` signals of ``S`` samples is one product with the DFT's real and imaginary parts
        ``(2 (S // 2 + 1), S)``: ten times quicker than an FFT of each (``docs/experiments.md``)."""
        k = self._dft.shape[0] // 2
        parts = self._dft @ samples
        out = np.empty((k, samples.shape[1]), complex)
        out.real, out.imag = parts[:k], parts[k:]
        return out

    def _label(self, shift):
        """``conj(G)``: the DFT's conjugate (:meth:`spectrum`'s half) of the Gaussian label over the samples,
        peaked ``shift`` samples after the middle one."""
        k = np.arange(len(self.log_steps)) - len(self.log_steps) // 2 - shift
        return np.conj(np.fft.rfft(np.exp(-0.5 * (k / self.sigma) ** 2)))[:, None]

    def applied(self):
        """``(conj(A), B + λ)`` of the filter applied, ``(1 - γ)`` of the adapted one plus ``γ`` of the first
        frame's, kept until the next :meth:`adapt`."""
        if self._applied is None:
            g = self.anchor
            self._applied = np.conj((1 - g) * self.A + g * self.A0), (1 - g) * self.B + g * self.B0 + self.lam
        return self._applied

    def detect(self, frame, centre, log_scale):
        """The :class:`ScaleResponse` of the boxes about ``centre`` at the scales about ``log_scale``."""
        fmap = self.feature_map(frame, centre, log_scale)
        Z = self.spectrum(self.samples(fmap, centre, log_scale))
        conj_a, den = self.applied()
        y = np.fft.irfft(np.einsum("kd,kd->k", conj_a, Z) / den, n=len(self.log_steps))
        out = ScaleResponse(log_scale + self.log_steps, y)
        out.source = (Z, float(log_scale))
        return out

    def adapt(self, frame, centre, log_scale, response=None):
        """Adapt ``A, B`` towards the samples about the estimate at ``log_scale``: the samples of the detection
        that gave ``response`` (a :class:`ScaleResponse` of this filter) with the label moved to ``log_scale``
        (within two samples of where they were taken; else, or without ``response``, samples about ``centre``
        anew)."""
        last = None if response is None else response.source
        step = self.log_steps[1] - self.log_steps[0]
        if last is not None and abs(log_scale - last[1]) <= 2 * step:
            F, conj_g = last[0], self._label((log_scale - last[1]) / step)
        else:
            F = self.spectrum(self.samples(self.feature_map(frame, centre, log_scale), centre, log_scale))
            conj_g = self._conj_g
        r = self.rate
        self.A = (1 - r) * self.A + r * (conj_g * F)
        self.B = (1 - r) * self.B + r * _power(F)
        self._applied = None


def _power(F):
    """``Σ_d |F_d|²`` over the columns of spectra ``F (K, d)`` -> ``(K,)``."""
    return np.einsum("kd,kd->k", F.real, F.real) + np.einsum("kd,kd->k", F.imag, F.imag)
