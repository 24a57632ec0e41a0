"""One frame's appearance maps over a region at the working resolution (:class:`AppearanceFrame`), made
where they are read, into buffers lent from frame to frame (:class:`MapBuffers`): the box model's
observation (:mod:`~vistrack.appearance.cues` documents the maps and the likelihood they serve).
"""

from __future__ import annotations

import functools
import weakref

import cv2
import numpy as np

from .. import kernels
from .features import bin_integrals, box_sums, colour_bins, n_colour_bins, remap_points

__all__ = ["AppearanceFrame", "MapBuffers", "shrink"]


def shrink(image, f, interpolation=cv2.INTER_AREA):
    """``image`` shrunk by ``f < 1`` (``INTER_AREA`` unless ``interpolation``) to ``round(f W) x round(f H)``
    pixels, its content
    placed by ``f`` itself: frame coordinate ``x`` at working ``x f`` on both axes, as
    :meth:`AppearanceFrame.to_work` reads it. Given the size, OpenCV scales by the rounded size's
    ratio instead, which put content up to half a working pixel off at the far side of the region
    (the dashcam plate, 15 working px high, sat about a frame pixel high: ``docs/experiments.md``)."""
    h, w = image.shape[:2]
    if round(w * f) >= 1 and round(h * f) >= 1:
        if _compiled_shrink(image, f, interpolation):
            from .frame_kernels import shrink_area  # OpenCV's area resize, its source rows passed once

            dh, dw = round(h * f), round(w * f)
            return shrink_area(np.ascontiguousarray(image), float(f), np.empty((dh, dw, 3), np.uint8), 0, dh, 0, dw)
        return cv2.resize(image, None, fx=f, fy=f, interpolation=interpolation)
    return cv2.resize(image, (max(1, int(round(w * f))), max(1, int(round(h * f)))), interpolation=interpolation)


def _block_factor(image, f, interpolation):
    """``k`` where a BGR uint8 region is shrunk by a whole factor ``k >= 2`` (``f = 1 / k``) with ``INTER_AREA``
    (OpenCV averages ``k x k`` blocks: ``AppearanceFrame`` makes the working image block by block where it is
    read), else 0."""
    if not (0 < f <= 0.5 and interpolation == cv2.INTER_AREA and image.ndim == 3 and image.shape[2] == 3
            and image.dtype == np.uint8):
        return 0
    k = round(1.0 / f)
    return k if abs(1.0 / f - k) < 1e-9 and min(image.shape[:2]) >= k else 0


def _compiled_shrink(image, f, interpolation):
    """Whether :func:`shrink` takes the compiled area resize (which can also make a window of the result)."""
    h, w = image.shape[:2]
    return (interpolation == cv2.INTER_AREA and kernels.use() and image.ndim == 3 and image.shape[2] == 3
            and image.dtype == np.uint8 and 0 < f < 1.0 and abs(1.0 / f - round(1.0 / f)) > 1e-9
            and (round(h * f), round(w * f)) != (h, w) and round(h * f) >= 1 and round(w * f) >= 1)


@functools.cache
def _compiled():
    """The compiled kernels (:mod:`~vistrack.appearance.frame_kernels`), imported on first use."""
    from . import frame_kernels

    return frame_kernels


class MapBuffers:
    """Work arrays lent to one :class:`AppearanceFrame` at a time, so that a frame's maps are written into
    the memory the last frame's were (warm in the cache) rather than into new pages.

    A frame borrows them when it makes its first window (:meth:`lend`). Lending them to the next frame
    takes them back from the last one, which forgets its windows and makes any it is asked for again in
    arrays of its own (:meth:`AppearanceFrame.forget`): nothing reads a map that was overwritten. A frame
    whose maps are read whole (its ``texture``, ``labels`` or ``ii``, which a caller may keep) keeps
    them (:meth:`give_up`), and the next frame gets new ones."""

    def __init__(self):
        self._borrower, self._flat = None, []  # a weak reference to the frame that has them, flat arrays

    def __reduce__(self):  # a copy starts with nothing lent
        return MapBuffers, ()

    def lend(self, frame, shapes):
        """Arrays of ``shapes`` (``[(shape, dtype)]``) for ``frame``."""
        last = self._borrower() if self._borrower is not None else None
        if last is not None and last is not frame:
            last.forget()
        self._borrower = weakref.ref(frame)
        out = []
        for k, (shape, dtype) in enumerate(shapes):
            n = int(np.prod(shape))
            if k == len(self._flat):
                self._flat.append(np.empty(0, dtype))
            if self._flat[k].size < n or self._flat[k].dtype != dtype:
                self._flat[k] = np.empty(max(n, 1), dtype)
            out.append(self._flat[k][:n].reshape(shape))
        return out

    def give_up(self, frame):
        """``frame`` keeps the arrays it was lent: they are never lent again."""
        if self._borrower is not None and self._borrower() is frame:
            self._borrower, self._flat = None, []


class AppearanceFrame:
    """One frame's maps over a region of interest at the working resolution.

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W)
    roi : tuple of int
        ``(x0, y0, x1, y1)`` in frame pixels.
    f : float
        Working scale (``<= 1``: the region is shrunk by ``f``).
    grey : bool
        Grey-level bins instead of colour.
    work : ndarray or None
        The whole frame at the working resolution (:meth:`Appearance.work_image`): the region is
        cut from it (the working pixels that cover ``roi``) rather than resized on its own, so that
        regions of one frame share its resampling (their maps agree where they overlap, away from
        their borders).
    interpolation : int
        The OpenCV interpolation that shrinks the region (:func:`shrink`).
    buffers : MapBuffers or None
        Where the maps are written (``None``: new arrays).
    """

    #: set by ``Box.observe``: the correlation filter's response and share ``β``, a re-detection?, the frame
    dcf = dcf_share = frame_image = None
    #: set by ``Box.observe``: the scale filter's response (or ``None``) and the proposal's log-scale centre
    scale = scale_centre = None
    redetected = False
    #: set by ``Box._redetect`` on a frame whose whole-frame search found the object: the pose found ``(cx, cy, l)``
    found = None
    _texture = _labels = _ii = _work = None  # the maps (see :meth:`maps`) and the working image's buffer

    def __init__(self, frame, roi, f, grey, work=None, interpolation=cv2.INTER_AREA, buffers=None):
        x0, y0, x1, y1 = roi
        self.f = f
        src, k = None, 0  # the frame's region, where its working image is made on demand; a whole factor
        if work is not None and f < 1.0:
            (h, w), (wh, ww) = frame.shape[:2], work.shape[:2]
            c0, r0 = min(int(np.floor(x0 * f)), ww - 1), min(int(np.floor(y0 * f)), wh - 1)
            c1, r1 = max(min(int(np.ceil(x1 * f)), ww), c0 + 1), max(min(int(np.ceil(y1 * f)), wh), r0 + 1)
            crop = work[r0:r1, c0:c1]
            x0, y0 = c0 / f, r0 / f
            x1, y1 = (w if c1 == ww else c1 / f), (h if r1 == wh else r1 / f)
        else:
            crop = frame[y0:y1, x0:x1]
            k = _block_factor(crop, f, interpolation)
            if k:  # whole k x k blocks from the region's corner: any window of them is that part of the whole
                crop = crop[: crop.shape[0] // k * k, : crop.shape[1] // k * k]
                x1, y1 = x0 + crop.shape[1], y0 + crop.shape[0]
                src, crop = crop, None
            elif f < 1.0:
                if _compiled_shrink(crop, f, interpolation):
                    src, crop = crop, None
                else:
                    crop = shrink(crop, f, interpolation)
        self._block = k
        self.x0, self.y0 = x0, y0
        #: the region ``(x0, y0, x1, y1)`` in frame pixels
        self.roi = (x0, y0, x1, y1)
        #: the LIS proposal map of this frame (:meth:`Appearance.proposal_map`, ``()`` where there is
        #: none), set by the box model on first use
        self.proposal = None
        self.n_bins = n_colour_bins(grey)
        self._grey_bins = bool(grey)
        self._src, self._image, self._grey, self._buffers = src, crop, None, buffers
        #: the region's size ``(H, W)`` at the working resolution
        self.shape = (crop.shape[:2] if src is None else (round(src.shape[0] * f), round(src.shape[1] * f)))
        # the rows and columns ``(r0, r1, c0, c1)`` whose labels and bin integrals, texture and working image are made
        self._window = self._twindow = self._swindow = None
        if not (kernels.use() and (src is not None or crop.ndim == 3)):  # the numpy path: all at once
            grey_f = self.grey.astype(np.float32)
            gx = cv2.Sobel(grey_f, cv2.CV_32F, 1, 0, ksize=3, borderType=cv2.BORDER_REFLECT)
            gy = cv2.Sobel(grey_f, cv2.CV_32F, 0, 1, ksize=3, borderType=cv2.BORDER_REFLECT)
            self._texture = cv2.merge([grey_f, gx, gy])  # grey level and its gradient, for the template
            self._labels = colour_bins(self.image, grey)
            self._ii = bin_integrals(self._labels, self.n_bins)
            self._window = self._twindow = (0, self.shape[0], 0, self.shape[1])

    # -- the maps, made where they are read ------------------------------------------------------
    @property
    def image(self):
        """The region at the working resolution ``(H, W, 3)`` uint8 (or ``(H, W)``)."""
        if self._image is None:
            self._image = shrink(self._src, self.f)
        return self._image

    @property
    def grey(self):
        """Its grey levels ``(H, W)`` uint8."""
        if self._grey is None:
            img = self.image
            self._grey = img if img.ndim == 2 else cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        return self._grey

    @property
    def texture(self):
        """Grey level and gradient ``(H, W, 3)`` float32 over the whole region (the template's samples)."""
        return self._whole()._texture

    @property
    def labels(self):
        """Colour bins ``(H, W)`` uint8 over the whole region (:func:`~vistrack.appearance.features.colour_bins`)."""
        return self._whole()._labels

    @property
    def ii(self):
        """Their bin integrals ``(H + 1, W + 1, B)`` over the whole region
        (:func:`~vistrack.appearance.features.bin_integrals`)."""
        return self._whole()._ii

    def maps(self, window=None, texture_window=None):
        """``(texture, ii)``: the bin integrals right inside ``window = (r0, r1, c0, c1)`` (working rows and
        columns, clipped to the region; ``None``: all of it), the texture inside ``texture_window`` (by default
        ``window``; the template's samples read no ring).

        The compiled path makes the maps only where they are read: the particles' boxes cover about a
        third of a region that holds every place they can reach (:meth:`window`). Until the whole region
        is made, the arrays are region-sized and right inside the windows asked for so far only (the bin
        integrals count from the window's corner, so a box inside it sums as in the whole region's);
        the properties above make the whole region."""
        self._cover(window, window if texture_window is None else texture_window)
        return self._texture, self._ii

    def forget(self):
        """Drop the maps made so far (their arrays are lent to another frame): they are made again, in
        arrays of this frame's own, where they are read next."""
        self._window = self._twindow = self._swindow = None
        self._texture = self._labels = self._ii = self._work = self._buffers = None

    def _whole(self):
        """The maps over the whole region, the frame's own from now on (:meth:`MapBuffers.give_up`)."""
        if self._buffers is not None:
            self._buffers.give_up(self)
            self._buffers = None
        return self._cover(None, None)

    def _grown(self, window, done):
        """``window`` clipped to the region, joined to ``done`` (a window made already, or ``None``); ``None``
        where ``done`` holds it or it is empty (``(0, 0, 0, 0)``: no map of that kind is read)."""
        hh, ww = self.shape
        r0, r1, c0, c1 = (0, hh, 0, ww) if window is None else window
        r0, c0 = min(max(r0, 0), hh), min(max(c0, 0), ww)
        r1, c1 = min(max(r1, r0), hh), min(max(c1, c0), ww)
        if r0 >= r1 or c0 >= c1:
            return None
        if done is not None:
            if done[0] <= r0 and r1 <= done[1] and done[2] <= c0 and c1 <= done[3]:
                return None
            r0, r1, c0, c1 = min(r0, done[0]), max(r1, done[1]), min(c0, done[2]), max(c1, done[3])
        return (r0, r1, c0, c1) if r0 < r1 and c0 < c1 else None

    def _cover(self, window, texture_window):
        """Make the labels and bin integrals over ``window`` and the texture over ``texture_window`` where they
        are not made yet, from the working image over both (and the pixel about the texture's window that its
        gradient reads); returns ``self``."""
        hh, ww = self.shape
        if self._texture is None:
            shapes = [((hh, ww, 3), np.float32), ((hh, ww), np.uint8), ((hh + 1, ww + 1, self.n_bins), np.int32),
                      ((hh, ww, 3), np.uint8)]
            lend = self._buffers.lend if self._buffers is not None else None
            self._texture, self._labels, self._ii, self._work = (
                lend(self, shapes) if lend else [np.empty(shape, dtype) for shape, dtype in shapes])
        lab, tex = self._grown(window, self._window), self._grown(texture_window, self._twindow)
        if lab is None and tex is None:  # made already (or nothing to make)
            return self
        fk = _compiled()
        reach = None if tex is None else self._grown((tex[0] - 1, tex[1] + 1, tex[2] - 1, tex[3] + 1), None)
        if self._image is None:  # the working image over both
            need = _union(lab, reach)
            grown = self._grown(need, self._swindow)
            if grown is not None:
                self._swindow = grown
                if self._block:  # OpenCV's block averages of the window's blocks
                    k, (r0, r1, c0, c1) = self._block, grown
                    self._work[r0:r1, c0:c1] = cv2.resize(self._src[k * r0:k * r1, k * c0:k * c1], (c1 - c0, r1 - r0),
                                                          interpolation=cv2.INTER_AREA)
                else:
                    fk.shrink_area(self._src, float(self.f), self._work, *grown)
        img = self._work if self._image is None else self._image
        if tex is not None:
            a0, a1, b0, b1 = reach
            fk.window_texture(cv2.cvtColor(img[a0:a1, b0:b1], cv2.COLOR_BGR2GRAY), a0, b0, *tex, self._texture)
            self._twindow = tex
        if lab is not None:
            r0, r1, c0, c1 = lab
            if self._grey_bins:
                fk.window_grey_labels(cv2.cvtColor(img[r0:r1, c0:c1], cv2.COLOR_BGR2GRAY), r0, c0, *lab, self._labels,
                                      self._ii)
            else:
                fk.window_labels(cv2.cvtColor(img[r0:r1, c0:c1], cv2.COLOR_BGR2HSV), r0, c0, *lab, self._labels,
                                 self._ii)
            self._window = lab
        return self

    def window(self, boxes, ring=0.0):
        """The working rows and columns ``(r0, r1, c0, c1)`` that ``boxes (N, 4)`` (cx, cy, w, h; frame px)
        grown by ``ring (w + h) / 2`` px read: their histograms' corners and their template's samples, with
        two pixels to spare (the whole region if a box is not finite)."""
        return _compiled().boxes_window(np.ascontiguousarray(boxes, float).reshape(-1, 4), float(ring),
                                        float(self.x0), float(self.y0), float(self.f), *self.shape)

    def states_window(self, states, size0, ring=0.0):
        """:meth:`window` of the boxes ``(cx, cy, w_0 e^l, h_0 e^l)`` of ``states (N, >=3)``
        (``size0 = (w_0, h_0)``)."""
        return _compiled().states_window(states, np.asarray(size0, float), float(ring), float(self.x0),
                                         float(self.y0), float(self.f), *self.shape)

    def to_work(self, x, y):
        """Frame pixel coordinates to working coordinates (same continuous convention)."""
        return (np.asarray(x) - self.x0) * self.f, (np.asarray(y) - self.y0) * self.f

    def histograms(self, cx, cy, w, h, grow=None):
        """Bin counts ``(..., B)`` of boxes centred at ``(cx, cy)`` with sides ``(w, h)``
        (frame px), and of the ring of width ``grow`` px around them (``None``: no ring)."""
        u, v = self.to_work(cx, cy)
        hw, hh = 0.5 * self.f * np.asarray(w), 0.5 * self.f * np.asarray(h)
        g = 0.0 if grow is None else self.f * np.asarray(grow)
        _, ii = self.maps(_span(u - hw - g, u + hw + g, v - hh - g, v + hh + g))
        inner = box_sums(ii, *(np.rint(a).astype(np.intp) for a in (u - hw, v - hh, u + hw, v + hh)))
        if grow is None:
            return inner, None
        outer = box_sums(ii, *(np.rint(a).astype(np.intp) for a in (u - hw - g, v - hh - g, u + hw + g, v + hh + g)))
        return inner, outer - inner

    def sample_texture(self, x, y):
        """Bilinear grey level and gradient ``(..., 3)`` at frame coordinates ``x, y`` (pixel
        centres at ``k + 0.5``); zero outside the frame."""
        u, v = self.to_work(x, y)
        texture, _ = self.maps((0, 0, 0, 0), _span(u, u, v, v))
        return remap_points(texture, u - 0.5, v - 0.5)


def _span(lo_u, hi_u, lo_v, hi_v):
    """The working rows and columns ``(r0, r1, c0, c1)`` about the extents ``lo_u.. hi_u``, ``lo_v.. hi_v``
    (arrays: their least and greatest) with two pixels to spare (``None``: one is not finite, the whole region)."""
    if np.size(lo_u) == 0:
        return 0, 0, 0, 0
    b = np.array([np.min(lo_u), np.max(hi_u), np.min(lo_v), np.max(hi_v)], float)
    if not np.isfinite(b).all():
        return None
    return int(np.floor(b[2])) - 2, int(np.ceil(b[3])) + 2, int(np.floor(b[0])) - 2, int(np.ceil(b[1])) + 2


def _union(a, b):
    """The least window ``(r0, r1, c0, c1)`` holding windows ``a`` and ``b`` (either may be ``None``)."""
    if a is None or b is None:
        return a if b is None else b
    return min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3])
