"""One frame's appearance maps over a region at the working resolution (:class:`AppearanceFrame`), made
where they are read, into buffers lent from frame to frame (:class:`MapBuffers`): the box model's
observation (:mod:`~vistrack.models.box.appearance` documents the maps and the likelihood they serve).
"""

from __future__ import annotations

import functools
import weakref

import cv2
import numpy as np

from ... import kernels
from ...features import bin_integrals, box_sums, colour_bins, n_colour_bins, remap_points

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


def _compiled_shrink(image, f, interpolation):
    """Whether :func:`shrink` takes the compiled area resize (which can also make a window of the result)."""
    h, w = image.shape[:2]
    return (interpolation == cv2.INTER_AREA and kernels.use() and image.ndim == 3 and image.shape[2] == 3
            and image.dtype == np.uint8 and 0 < f < 1.0 and abs(1.0 / f - round(1.0 / f)) > 1e-9
            and (round(h * f), round(w * f)) != (h, w) and round(h * f) >= 1 and round(w * f) >= 1)


@functools.cache
def _compiled():
    """The compiled kernels (:mod:`~vistrack.models.box.frame_kernels`), imported on first use."""
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
    redetected = False
    _texture = _labels = _ii = _work = None  # the maps (see :meth:`maps`) and the working image's buffer

    def __init__(self, frame, roi, f, grey, work=None, interpolation=cv2.INTER_AREA, buffers=None):
        x0, y0, x1, y1 = roi
        self.f = f
        src = None  # the frame's region, where its working image is made on demand
        if work is not None and f < 1.0:
            (h, w), (wh, ww) = frame.shape[:2], work.shape[:2]
            c0, r0 = min(int(np.floor(x0 * f)), ww - 1), min(int(np.floor(y0 * f)), wh - 1)
            c1, r1 = max(min(int(np.ceil(x1 * f)), ww), c0 + 1), max(min(int(np.ceil(y1 * f)), wh), r0 + 1)
            crop = work[r0:r1, c0:c1]
            x0, y0 = c0 / f, r0 / f
            x1, y1 = (w if c1 == ww else c1 / f), (h if r1 == wh else r1 / f)
        else:
            crop = frame[y0:y1, x0:x1]
            if f < 1.0:
                if _compiled_shrink(crop, f, interpolation):
                    src, crop = crop, None
                else:
                    crop = shrink(crop, f, interpolation)
        self.x0, self.y0 = x0, y0
        #: the region ``(x0, y0, x1, y1)`` in frame pixels
        self.roi = (x0, y0, x1, y1)
        #: the LIS proposal map of this frame (:meth:`Appearance.proposal_map`, ``()`` where there is
        #: none), set by the box model on first use
        self.proposal = None
        self.n_bins = n_colour_bins(grey)
        self._src, self._image, self._grey, self._buffers = src, crop, None, buffers
        #: the region's size ``(H, W)`` at the working resolution
        self.shape = (crop.shape[:2] if src is None else (round(src.shape[0] * f), round(src.shape[1] * f)))
        self._window = None  # the rows and columns ``(r0, r1, c0, c1)`` whose maps are made
        if not (kernels.use() and not grey and (src is not None or crop.ndim == 3)):  # the numpy path: all at once
            grey_f = self.grey.astype(np.float32)
            gx = cv2.Sobel(grey_f, cv2.CV_32F, 1, 0, ksize=3, borderType=cv2.BORDER_REFLECT)
            gy = cv2.Sobel(grey_f, cv2.CV_32F, 0, 1, ksize=3, borderType=cv2.BORDER_REFLECT)
            self._texture = cv2.merge([grey_f, gx, gy])  # grey level and its gradient, for the template
            self._labels = colour_bins(self.image, grey)
            self._ii = bin_integrals(self._labels, self.n_bins)
            self._window = (0, self.shape[0], 0, self.shape[1])

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
        """Colour bins ``(H, W)`` uint8 over the whole region (:func:`~vistrack.features.colour_bins`)."""
        return self._whole()._labels

    @property
    def ii(self):
        """Their bin integrals ``(H + 1, W + 1, B)`` over the whole region
        (:func:`~vistrack.features.bin_integrals`)."""
        return self._whole()._ii

    def maps(self, window=None):
        """``(texture, ii)``, right inside ``window = (r0, r1, c0, c1)`` (working rows and columns,
        clipped to the region; ``None``: all of it).

        The compiled path makes the maps only where they are read: the particles' boxes cover about a
        third of a region that holds every place they can reach (:meth:`window`). Until the whole region
        is made, the arrays are region-sized and right inside the windows asked for so far only (the bin
        integrals count from the window's corner, so a box inside it sums as in the whole region's);
        the properties above make the whole region."""
        self._cover(window)
        return self._texture, self._ii

    def forget(self):
        """Drop the maps made so far (their arrays are lent to another frame): they are made again, in
        arrays of this frame's own, where they are read next."""
        self._window = self._texture = self._labels = self._ii = self._work = self._buffers = None

    def _whole(self):
        """The maps over the whole region, the frame's own from now on (:meth:`MapBuffers.give_up`)."""
        if self._buffers is not None:
            self._buffers.give_up(self)
            self._buffers = None
        return self._cover(None)

    def _cover(self, window):
        """Make the maps over ``window`` if they are not made there yet; returns ``self``."""
        hh, ww = self.shape
        r0, r1, c0, c1 = (0, hh, 0, ww) if window is None else window
        r0, c0 = min(max(r0, 0), hh), min(max(c0, 0), ww)
        r1, c1 = min(max(r1, r0), hh), min(max(c1, c0), ww)
        done = self._window
        if done is not None:
            if done[0] <= r0 and r1 <= done[1] and done[2] <= c0 and c1 <= done[3]:
                return self
            r0, r1, c0, c1 = min(r0, done[0]), max(r1, done[1]), min(c0, done[2]), max(c1, done[3])
        if self._texture is None:
            shapes = [((hh, ww, 3), np.float32), ((hh, ww), np.uint8), ((hh + 1, ww + 1, self.n_bins), np.int32),
                      ((hh, ww, 3), np.uint8)]
            lend = self._buffers.lend if self._buffers is not None else None
            self._texture, self._labels, self._ii, self._work = (
                lend(self, shapes) if lend else [np.empty(shape, dtype) for shape, dtype in shapes])
        if r0 >= r1 or c0 >= c1:  # nothing to make (the arrays are there for a caller that reads none of them)
            return self
        fk = _compiled()
        a0, a1, b0, b1 = max(r0 - 1, 0), min(r1 + 1, hh), max(c0 - 1, 0), min(c1 + 1, ww)  # the gradient's reach
        if self._image is not None:
            img = self._image[a0:a1, b0:b1]
        else:
            img = fk.shrink_area(self._src, float(self.f), self._work, a0, a1, b0, b1)[a0:a1, b0:b1]
        fk.window_features(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), cv2.cvtColor(img, cv2.COLOR_BGR2HSV), a0, b0,
                        r0, r1, c0, c1, self._texture, self._labels, self._ii)
        self._window = (r0, r1, c0, c1)
        return self

    def window(self, boxes, ring=0.0):
        """The working rows and columns ``(r0, r1, c0, c1)`` that ``boxes (N, 4)`` (cx, cy, w, h; frame px)
        grown by ``ring (w + h) / 2`` px read: their histograms' corners and their template's samples, with
        two pixels to spare (the whole region if a box is not finite)."""
        return _compiled().boxes_window(np.ascontiguousarray(boxes, float).reshape(-1, 4), float(ring), float(self.x0),
                            float(self.y0), float(self.f), *self.shape)

    def states_window(self, states, size0, ring=0.0):
        """:meth:`window` of the boxes ``(cx, cy, w_0 e^l, h_0 e^l)`` of ``states (N, >=3)``
        (``size0 = (w_0, h_0)``)."""
        return _compiled().states_window(states, np.asarray(size0, float), float(ring), float(self.x0), float(self.y0),
                             float(self.f), *self.shape)

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
        texture, _ = self.maps(_span(u, u, v, v))
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
