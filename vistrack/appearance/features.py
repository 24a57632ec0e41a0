"""Per-frame feature maps, computed once and lazily, shared by every particle (docs/architecture.md).

Grayscale ``float32``; Sobel ``gx``, ``gy`` (3x3, unnormalised: a unit step
gives 4) and magnitude, also of the image smoothed by a Gaussian
(:meth:`FeatureMaps.gradient`); difference-of-boxes DoG at two scales (thesis §1.3.2:
"2D DoG filters approximated by the difference of two 2D box-filters"), and
integral images of any map. All computed with OpenCV (5-15x faster than the
scipy/scikit-image equivalents, docs/architecture.md, performance notes).

Coordinates: maps are indexed ``[row, col] = [y, x]``; the API speaks ``(x, y)``.
"""

from __future__ import annotations

from functools import cached_property

import cv2
import numpy as np

from .. import kernels

__all__ = ["FeatureMaps", "box_dog", "remap_points", "blob_peaks", "greedy_peaks", "is_grey", "colour_bins",
           "n_colour_bins", "bin_integrals", "box_sums"]

#: colour binning (hue x saturation for chromatic pixels, value for the rest; grey levels for grey video)
HUE_BINS, SAT_BINS, VALUE_BINS, GREY_BINS = 8, 3, 4, 16
#: a pixel is chromatic when its HSV saturation and value are at least these (of 255)
MIN_SATURATION, MIN_VALUE = 48, 40


def is_grey(frame, tol=6.0):
    """Whether a frame carries no colour: one channel, or BGR channels that differ by
    less than ``tol`` grey levels on average (a grey video stored as colour)."""
    f = np.asarray(frame)
    if f.ndim == 2 or f.shape[2] == 1:
        return True
    small = f[:: max(1, f.shape[0] // 64), :: max(1, f.shape[1] // 64)].astype(np.int16)
    spread = small.max(axis=2) - small.min(axis=2)
    return float(spread.mean()) < tol


def n_colour_bins(grey):
    """Number of bins of :func:`colour_bins`."""
    return GREY_BINS if grey else HUE_BINS * SAT_BINS + VALUE_BINS


def colour_bins(image, grey=False, dst=None):
    """Quantised colour of every pixel, ``uint8`` labels in ``[0, n_colour_bins(grey))``.

    Colour (``grey=False``; BGR input): HSV, robust to lighting through hue and
    saturation. A chromatic pixel (saturation >= 48 and value >= 40 of 255) gets one of
    ``8 x 3`` hue-saturation bins; the others (grey, white, black: hue is noise there)
    one of 4 value bins after them. Grey (``grey=True``): 16 grey-level bins.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3) uint8 BGR, or (H, W) uint8 grey
    grey : bool
    dst : ndarray of shape (H, W) uint8, optional
        Output buffer.

    Returns
    -------
    ndarray of shape (H, W) uint8
    """
    if grey:
        g = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        return np.floor_divide(g, 256 // GREY_BINS, out=dst, dtype=np.uint8, casting="unsafe")
    hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
    if kernels.use():
        from .cue_kernels import colour_labels

        return colour_labels(hsv, np.empty(hsv.shape[:2], np.uint8) if dst is None else dst)
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    hue = (h.astype(np.uint16) * HUE_BINS // 180).astype(np.uint8)
    sat = ((s.astype(np.uint16) - MIN_SATURATION).clip(0) * SAT_BINS // (256 - MIN_SATURATION)).astype(np.uint8)
    chroma = (s >= MIN_SATURATION) & (v >= MIN_VALUE)
    out = np.where(chroma, hue * SAT_BINS + sat, HUE_BINS * SAT_BINS + v // (256 // VALUE_BINS))
    if dst is None:
        return out.astype(np.uint8)
    dst[...] = out
    return dst


def bin_integrals(labels, n_bins):
    """Per-bin integral images of a label map: ``ii[y, x, b]`` counts the pixels of bin
    ``b`` in ``[0, x) x [0, y)``, so the histogram of any upright box is four lookups of
    ``n_bins`` values (:func:`box_sums`).

    Parameters
    ----------
    labels : ndarray of shape (H, W) uint8
    n_bins : int (at most 512, OpenCV's channel limit)

    Returns
    -------
    ndarray of shape (H + 1, W + 1, n_bins) int32
    """
    if kernels.use():
        from .cue_kernels import bin_integrals as compiled

        return compiled(np.ascontiguousarray(labels), int(n_bins))
    onehot = np.eye(n_bins, dtype=np.uint8)[labels]
    return cv2.integral(onehot, sdepth=cv2.CV_32S)


def box_sums(ii, x0, y0, x1, y1):
    """Sums over the boxes ``[x0, x1) x [y0, y1)`` of the map whose integral image is ``ii``.

    Parameters
    ----------
    ii : ndarray of shape (H + 1, W + 1) or (H + 1, W + 1, C)
    x0, y0, x1, y1 : array_like of int, broadcastable to one shape ``S``
        Box corners in pixels, clipped to the map.

    Returns
    -------
    ndarray of shape ``S`` or ``S + (C,)``
    """
    h, w = ii.shape[0] - 1, ii.shape[1] - 1
    x0 = np.clip(x0, 0, w)
    x1 = np.clip(x1, 0, w)
    y0 = np.clip(y0, 0, h)
    y1 = np.clip(y1, 0, h)
    return ii[y1, x1] - ii[y0, x1] - ii[y1, x0] + ii[y0, x0]


def box_dog(gray, inner, outer):
    """``box_inner(gray) - box_outer(gray)``: mean over an ``inner``-wide square minus
    the mean over an ``outer``-wide square (odd sizes, ``inner < outer``)."""
    if not (0 < inner < outer):
        raise ValueError(f"need 0 < inner < outer, got {inner}, {outer}")
    a = cv2.boxFilter(gray, cv2.CV_32F, (inner, inner), borderType=cv2.BORDER_REFLECT)
    b = cv2.boxFilter(gray, cv2.CV_32F, (outer, outer), borderType=cv2.BORDER_REFLECT)
    return a - b


def greedy_peaks(score, half, k):
    """The ``k`` best places of a map ``score (H, W)``, best first: each the maximum left once the boxes
    of ``(4 half_x + 1) × (4 half_y + 1)`` cells about the better ones are taken out (``half = (half_x,
    half_y)``, an object's half box: two places at least an object's box apart). Returns a list of ``(i, j,
    value)`` (row, column), fewer where the map runs out. ``score`` is left as it was."""
    total = np.array(score, np.float32)
    hx, hy = half
    out = []
    for _ in range(int(k)):
        i, j = np.unravel_index(int(np.argmax(total)), total.shape)
        if not np.isfinite(total[i, j]):
            break
        out.append((int(i), int(j), float(total[i, j])))
        total[max(0, i - 2 * hy):i + 2 * hy + 1, max(0, j - 2 * hx):j + 2 * hx + 1] = -np.inf
    return out


def blob_peaks(response, threshold, radius=3):
    """Bright-blob centres: local maxima of ``response`` (a DoG map) above ``threshold``.

    A pixel is a peak when it equals the maximum of its ``(2r+1)²`` neighbourhood
    (``cv2.dilate``); its position is refined to sub-pixel by a parabola
    through the neighbours along x and along y. Returns ``(M, 2)`` float
    ``(x, y)`` and the ``(M,)`` peak values, strongest first.
    """
    r = np.asarray(response, np.float32)
    k = 2 * int(radius) + 1
    dil = cv2.dilate(r, np.ones((k, k), np.uint8))
    ys, xs = np.nonzero((r >= dil) & (r > threshold))
    h, w = r.shape
    keep = (xs > 0) & (xs < w - 1) & (ys > 0) & (ys < h - 1)
    xs, ys = xs[keep], ys[keep]
    c = r[ys, xs].astype(float)

    def vertex(a, b):  # offset of the parabola through (-1, a), (0, c), (1, b)
        den = a - 2 * c + b
        return np.where(den < 0, 0.5 * (a - b) / np.where(den < 0, den, -1.0), 0.0)

    dx = np.clip(vertex(r[ys, xs - 1], r[ys, xs + 1]), -0.5, 0.5)
    dy = np.clip(vertex(r[ys - 1, xs], r[ys + 1, xs]), -0.5, 0.5)
    order = np.argsort(-c)
    return np.column_stack([xs + dx, ys + dy])[order], c[order]


_REMAP_COLS = 1024


def remap_points(img, x, y, border=0):
    """Bilinear samples of ``img`` at points ``(x, y)`` with ``cv2.remap``.

    The points are laid out as a ``(rows, 1024)`` map (remap wants both sides
    below 32767) and padded with an outside point; outside samples are ``border``
    (a scalar or one value per channel).
    """
    shape = np.shape(x)
    m = int(np.prod(shape))
    limit = 32000 * _REMAP_COLS
    if m > limit:  # remap's size limit: in chunks
        xf, yf = np.ravel(x), np.ravel(y)
        parts = [remap_points(img, xf[i:i + limit], yf[i:i + limit], border) for i in range(0, m, limit)]
        out = np.concatenate(parts)
        return out.reshape(shape + out.shape[1:])
    rows = max(1, -(-m // _REMAP_COLS))
    mx = np.empty(rows * _REMAP_COLS, np.float32)
    my = np.empty(rows * _REMAP_COLS, np.float32)
    mx[:m] = np.ravel(x)
    my[:m] = np.ravel(y)
    mx[m:] = -10.0
    my[m:] = -10.0
    out = cv2.remap(img, mx.reshape(rows, _REMAP_COLS), my.reshape(rows, _REMAP_COLS), cv2.INTER_LINEAR,
                    borderMode=cv2.BORDER_CONSTANT, borderValue=border)
    ch = out.shape[2:] if out.ndim == 3 else ()
    return out.reshape((rows * _REMAP_COLS,) + ch)[:m].reshape(shape + ch)


class FeatureMaps:
    """Lazily computed feature maps of one frame.

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W) gray
    dog_small, dog_large : tuple of int
        ``(inner, outer)`` box sizes of the thin- and thick-line DoG filters.
    """

    def __init__(self, frame, *, dog_small=(3, 7), dog_large=(5, 13), buffers=None):
        self.frame = frame
        self.dog_sizes = {"small": tuple(dog_small), "large": tuple(dog_large)}
        self._integrals = {}
        self._gradients = {}
        self._labels = {}
        self._buffers = buffers

    def buffer(self, name, shape, dtype=np.float32):
        """An output array for a map of this frame: from the buffer pool (overwritten by the next
        frame's), or a fresh one without a pool."""
        b = self._buf(name, shape, dtype)
        return np.empty(shape, dtype) if b is None else b

    def _buf(self, name, shape, dtype=np.float32):
        """A reusable output array (fresh arrays cost a page fault per 4 KiB, docs/architecture.md);
        without a buffer pool, ``None`` (cv2 allocates)."""
        if self._buffers is None:
            return None
        key = (name, shape, np.dtype(dtype))
        b = self._buffers.get(key)
        if b is None:
            b = self._buffers[key] = np.empty(shape, dtype)
        return b

    @property
    def shape(self):
        """``(H, W)`` of the frame."""
        return self.frame.shape[:2]

    @cached_property
    def gray(self):
        """Grayscale, float32 in [0, 255]."""
        f = self.frame
        if f.ndim == 3:
            f = cv2.cvtColor(f, cv2.COLOR_BGR2GRAY, dst=self._buf("gray8", f.shape[:2], np.uint8))
        out = self._buf("gray", f.shape)
        if out is None:
            return f.astype(np.float32)
        out[...] = f
        return out

    @cached_property
    def gx(self):
        """Sobel derivative along x (columns)."""
        return cv2.Sobel(self.gray, cv2.CV_32F, 1, 0, dst=self._buf("gx", self.shape), ksize=3,
                         borderType=cv2.BORDER_REFLECT)

    @cached_property
    def gy(self):
        """Sobel derivative along y (rows)."""
        return cv2.Sobel(self.gray, cv2.CV_32F, 0, 1, dst=self._buf("gy", self.shape), ksize=3,
                         borderType=cv2.BORDER_REFLECT)

    @cached_property
    def mag(self):
        """Gradient magnitude ``sqrt(gx^2 + gy^2)``."""
        return cv2.magnitude(self.gx, self.gy, magnitude=self._buf("mag", self.shape))

    @cached_property
    def gxy(self):
        """``gx`` and ``gy`` as one 2-channel map (one bilinear lookup gives both)."""
        return cv2.merge([self.gx, self.gy], dst=self._buf("gxy", self.shape + (2,)))

    @cached_property
    def mean_mag(self):
        """Mean gradient magnitude over the frame (a contrast scale for edge thresholds)."""
        return float(cv2.mean(self.mag)[0])

    def gradient(self, sigma=0.0):
        """``(gx, gy)`` as one 2-channel map, of the image smoothed by a Gaussian of std
        ``sigma`` px first (``0``: :attr:`gxy`), and its mean magnitude. Cached per ``sigma``.

        Smoothing before differentiating suppresses sensor noise and makes an edge's
        gradient peak depend less on how sharp the edge is (motion blur).
        """
        sigma = float(sigma)
        if sigma <= 0:
            return self.gxy, self.mean_mag
        if sigma not in self._gradients:
            key = f"{sigma:g}"
            sm = cv2.GaussianBlur(self.gray, (0, 0), sigma, dst=self._buf("smooth" + key, self.shape),
                                  borderType=cv2.BORDER_REFLECT)
            gx = cv2.Sobel(sm, cv2.CV_32F, 1, 0, dst=self._buf("sgx" + key, self.shape), ksize=3,
                           borderType=cv2.BORDER_REFLECT)
            gy = cv2.Sobel(sm, cv2.CV_32F, 0, 1, dst=self._buf("sgy" + key, self.shape), ksize=3,
                           borderType=cv2.BORDER_REFLECT)
            mean = float(cv2.mean(cv2.magnitude(gx, gy, magnitude=self._buf("smag" + key, self.shape)))[0])
            self._gradients[sigma] = (cv2.merge([gx, gy], dst=self._buf("sgxy" + key, self.shape + (2,))), mean)
        return self._gradients[sigma]

    def sample_gradient(self, x, y, sigma=0.0):
        """Bilinear ``(gx, gy)`` at float pixel coordinates ``x, y`` (any equal shapes),
        of the image smoothed with std ``sigma`` (:meth:`gradient`); zero outside the
        frame. Returns an array of shape ``x.shape + (2,)``."""
        return remap_points(self.gradient(sigma)[0], x, y)

    def colour_labels(self, grey=False):
        """:func:`colour_bins` of the frame, ``(H, W) uint8`` (cached per ``grey``)."""
        grey = bool(grey) or self.frame.ndim == 2
        if grey not in self._labels:
            self._labels[grey] = colour_bins(self.frame, grey,
                                             dst=self._buf(f"labels{int(grey)}", self.shape, np.uint8))
        return self._labels[grey]

    @cached_property
    def dog_small(self):
        """Thin-line DoG ``G_s I``."""
        return box_dog(self.gray, *self.dog_sizes["small"])

    @cached_property
    def dog_large(self):
        """Thick-line DoG ``G_l I``."""
        return box_dog(self.gray, *self.dog_sizes["large"])

    def integral(self, name):
        """Integral image (float64, shape ``(H+1, W+1)``) of the map ``name``
        (``gray``, ``gx``, ``abs_gx``, ``abs_gy``, ``mag``, ``abs_dog_small``, ...): its sums over boxes are
        :func:`box_sums`'s."""
        if name not in self._integrals:
            if name.startswith("abs_"):
                src = np.abs(getattr(self, name[4:]))
            else:
                src = getattr(self, name)
            self._integrals[name] = cv2.integral(src, sdepth=cv2.CV_64F)
        return self._integrals[name]
