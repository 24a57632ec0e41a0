"""Finding license plates in a whole frame, without a box: the detection stage that
gives the plate model its first pose on real footage.

Two stages, both on the grey frame:

1. **Candidates** (several scales): the vertical-edge map ``|∇_x I|`` (the thesis's plate cue:
   character strokes are dense vertical edges, §1.3.2) thresholded, closed with horizontal
   rectangles as wide as a character gap at each scale, and its connected components kept where
   they are plate-shaped (height ≥ 8 px, aspect 1.3–10, filled).
2. **Character row** (the verification): each candidate's region, resized to a fixed character
   height, is binarised (Otsu, both polarities: dark-on-light and light-on-dark plates) and its
   connected components grouped into a row of characters — similar heights, a common centre
   line, at least :attr:`PlateDetector.min_chars` of them, spanning most of the candidate. A row
   of identical blobs at an even pitch (a building's windows, a grille) is rejected, as is a row
   with another row of the same height stacked right above or below it (text blocks, windows).
   A plate-layout-specific second row of smaller characters above the main row (the Japanese
   layout's top line, Fig. 1.5) makes the candidate ``jp``; otherwise it is ``single-row``.

The plate's outline follows from the character row through the layout's geometry
(:data:`ROW_IN_PLATE`): the big characters' rectangle of the layout in unit-plate coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ...scoring.metrics import iou

__all__ = ["Detection", "PlateDetector", "PlateSearch", "ROW_IN_PLATE", "acquire", "plate_from_row", "refine_outline"]

#: where the main character row lies in the unit plate square, per layout ``(a0, b0, a1, b1)``:
#: single-row plates' characters span most of the width and about 60 % of the height (the
#: SINGLE_ROW layout's ``small`` + ``big`` sets, 0.06–0.94 × 0.2–0.8); the Japanese layout's four
#: large digits (JP ``big``, 0.24–0.92 × 0.51–0.89)
ROW_IN_PLATE = {"single-row": (0.1, 0.2, 0.9, 0.8), "jp": (0.24, 0.51, 0.92, 0.89)}


@dataclass
class Detection:
    """A plate found in a frame.

    Attributes
    ----------
    box : ndarray of shape (4,)
        The plate's outline as ``(x, y, w, h)`` px.
    score : float
        Strength of the character row: the number of characters times the row's span.
    layout : str
        ``"jp"`` (a second row of small characters above the main row) or ``"single-row"``.
    chars : int
        Characters in the main row.
    """

    box: np.ndarray
    score: float
    layout: str
    chars: int


class PlateDetector:
    """Plates in a whole frame (module docstring): candidates from the vertical-edge density at
    several scales, verified by a row of characters.

    Parameters
    ----------
    min_chars : int
        Characters a row needs (5: every layout has at least four large digits and more marks;
        the text signs of the synthetic scenes have four letters).
    gaps : tuple of int
        Widths (px, at the working resolution) of the closing rectangles: one per scale.
    max_side : int
        Frames larger than this (px, the longer side) are searched at a reduced size.
    char_height : int
        Height (px) a candidate is resized to for the character row.
    split : bool
        Cut touching characters apart (off: see :attr:`split`).
    """

    def __init__(self, min_chars=5, gaps=(5, 9, 15), max_side=720, char_height=32, split=False, classifier="default"):
        self.min_chars = int(min_chars)
        #: the learned test of the rectangle candidates (:class:`~vistrack.models.plate.classifier.PlateClassifier`;
        #: ``None``: the character-row path alone)
        if classifier == "default":
            from .classifier import PlateClassifier

            classifier = PlateClassifier()
        self.classifier = classifier
        #: cut components wider than tall into characters (:func:`_split_touching`): it finds 0.57 of
        #: 40 rendered single-row plates against 0.43, but makes the dashcam plate's first boxes 20 %
        #: narrower (IoU 0.78 against 0.94) and loses its no-box track on most frames: off
        self.split = bool(split)
        self.gaps = tuple(int(g) for g in gaps)
        self.max_side = int(max_side)
        self.char_height = int(char_height)

    # -- stage 1 ---------------------------------------------------------------------
    def candidates(self, gray):
        """Plate-shaped regions of dense vertical edges in ``gray (H, W) uint8``: boxes ``(M, 4)``
        ``(x, y, w, h)`` px, duplicates across scales removed."""
        gx = cv2.convertScaleAbs(cv2.Sobel(gray, cv2.CV_16S, 1, 0, ksize=3))
        thr = max(30.0, 2.5 * float(cv2.mean(gx)[0]))
        _, bw = cv2.threshold(gx, thr, 255, cv2.THRESH_BINARY)
        out = []
        for g in self.gaps:
            c = cv2.morphologyEx(bw, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_RECT, (g, 3)))
            c = cv2.morphologyEx(c, cv2.MORPH_OPEN, cv2.getStructuringElement(cv2.MORPH_RECT, (max(3, g // 2), 5)))
            _, _, st, _ = cv2.connectedComponentsWithStats(c, connectivity=8)
            st = st[1:]
            w, h, a = st[:, 2], st[:, 3], st[:, 4]
            keep = (h >= 8) & (w >= 24) & (w >= 1.3 * h) & (w <= 10 * h) & (a >= 0.4 * w * h)
            out.append(st[keep, :4])
        boxes = np.concatenate(out).astype(float) if out else np.zeros((0, 4))
        return _unique(boxes)

    # -- stage 2 ---------------------------------------------------------------------
    def char_row(self, gray, box):
        """The row of characters in ``box (x, y, w, h)`` of ``gray``, or ``None``: a dict with
        ``chars`` (count), ``span`` (its width over the box's), ``row`` (its box ``(x, y, w, h)``
        in frame px) and ``layout``."""
        x, y, w, h = (float(v) for v in box)
        m = 0.35 * h + 2
        x0, y0 = int(max(0, x - m)), int(max(0, y - m))
        x1, y1 = int(min(gray.shape[1], x + w + m)), int(min(gray.shape[0], y + h + m))
        f = self.char_height / h
        crop = gray[y0:y1, x0:x1]
        if crop.size == 0:
            return None
        crop = cv2.resize(crop, None, fx=f, fy=f, interpolation=cv2.INTER_AREA if f < 1 else cv2.INTER_LINEAR)
        best = None
        for inv in (cv2.THRESH_BINARY_INV, cv2.THRESH_BINARY):
            _, b = cv2.threshold(crop, 0, 255, inv | cv2.THRESH_OTSU)
            _, _, st, _ = cv2.connectedComponentsWithStats(b, connectivity=8)
            row = self._row(st[1:], w * f)
            if row is not None and (best is None or row[0] > best[0]):
                best = row
        if best is None:
            return None
        n, span, (rx, ry, rw, rh), layout = best
        return {"chars": n, "span": span, "layout": layout,
                "row": np.array([x0 + rx / f, y0 + ry / f, rw / f, rh / f])}

    def _row(self, st, box_w):
        """The best row among the components ``st (K, 5)`` (x, y, w, h, area) of a binarised
        candidate resized to :attr:`char_height`; ``(count, span, row box, layout)`` or ``None``."""
        H = self.char_height
        st = _split_touching(st.astype(float)) if self.split else np.column_stack([st, np.zeros(len(st))]).astype(float)
        cw, ch, area = st[:, 2], st[:, 3], st[:, 4]
        # character strokes: not solid blobs (windows, lights) nor thin slivers
        ok = (ch >= 0.3 * H) & (ch <= 1.3 * H) & (cw >= 0.06 * ch) & (cw <= 1.0 * ch) & (area >= 0.12 * cw * ch) \
            & (area <= 0.92 * cw * ch)
        s = st[ok]
        if len(s) < self.min_chars:
            return None
        cy = s[:, 1] + s[:, 3] / 2
        best = None
        for k in range(len(s)):  # rows seeded at each component: same height, same centre line
            mh = s[k, 3]
            r = (np.abs(s[:, 3] - mh) <= 0.2 * mh) & (np.abs(cy - cy[k]) <= 0.15 * mh)
            if best is None or r.sum() > best.sum():
                best = r
        row = s[best]
        n = len(row)
        if n < self.min_chars - 1 or np.sum(row[:, 5] == 0) < 3:  # at least three characters whole
            return None
        order = np.argsort(row[:, 0])
        row = row[order]
        left, right = row[:, 0].min(), (row[:, 0] + row[:, 2]).max()
        span = (right - left) / box_w
        if span < 0.45:
            return None
        top, bottom = row[:, 1].min(), (row[:, 1] + row[:, 3]).max()
        mh = float(np.median(row[:, 3]))
        cy_row = 0.5 * (top + bottom)
        others = s[~best]
        ocy = others[:, 1] + others[:, 3] / 2
        inside = (others[:, 0] >= left - mh) & (others[:, 0] + others[:, 2] <= right + mh)
        # another row of the same height stacked right above or below: a block of text or windows
        stacked = inside & (np.abs(others[:, 3] - mh) <= 0.2 * mh) \
            & (np.abs(np.abs(ocy - cy_row) - 1.6 * mh) <= 0.7 * mh)
        if stacked.sum() >= 3:
            return None
        # a second row of smaller characters above (the Japanese layout's top line)
        small = inside & (others[:, 3] >= 0.35 * mh) & (others[:, 3] <= 0.8 * mh) & (ocy < top) & (ocy > top - 1.2 * mh)
        layout = "jp" if small.sum() >= 3 else "single-row"
        if layout == "single-row" and n < self.min_chars:  # four large digits need the top row
            return None
        return n, span, (left, top, right - left, bottom - top), layout

    def _classified(self, small, k, shape):
        """The rectangle candidates of ``small`` (the frame at scale ``k``) that :attr:`classifier`
        takes for plates, as :class:`Detection` s in frame px: the plate's box is the rectangle's,
        the layout the one nearest its aspect ratio, the score ``10 +`` the log-odds (ranked above
        the character-row path's, whose scores are at most the characters in the row), ``chars`` 0."""
        from .classifier import rectangle_candidates

        if self.classifier is None:
            return []
        boxes = rectangle_candidates(small)
        if len(boxes) == 0:
            return []
        s = self.classifier.score(small, boxes)
        out = []
        for b, v in zip(boxes, s):
            plate = b / k
            if v > self.classifier.threshold and _inside(plate, shape, 2.0):
                out.append(Detection(plate, 10.0 + float(v), _layout_of(plate), 0))
        return out

    # -- the whole frame ---------------------------------------------------------------
    def detect(self, frame):
        """The plates in ``frame`` (BGR or grey), best first: a list of :class:`Detection`."""
        gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        k = min(1.0, self.max_side / max(gray.shape))
        small = gray if k == 1.0 else cv2.resize(gray, None, fx=k, fy=k, interpolation=cv2.INTER_AREA)
        found = []
        for box in self.candidates(small):
            r = self.char_row(small, box)
            if r is None:
                continue
            plate = refine_outline(small, plate_from_row(r["row"], r["layout"]), r["row"]) / k
            if not _inside(plate, gray.shape, 2.0):
                continue
            found.append(Detection(plate, r["chars"] * min(r["span"], 1.0), r["layout"], r["chars"]))
        found += self._classified(small, k, gray.shape)
        found.sort(key=lambda d: -d.score)
        keep = []
        for d in found:  # one detection per plate: the strongest
            if all(iou(d.box, e.box) < 0.3 for e in keep):
                keep.append(d)
        return keep


def _layout_of(box):
    """The layout whose aspect ratio is nearest the box's ``w / h`` (in log)."""
    from .layout import LAYOUTS

    r = float(box[2]) / max(float(box[3]), 1e-9)
    return min(LAYOUTS, key=lambda name: abs(np.log(LAYOUTS[name].aspect / r)))


def _split_touching(st, aspect=0.62):
    """Components ``st (K, 5)`` (x, y, w, h, area) with those wider than their height (characters
    that touch after binarisation, at low resolution or in bold fonts) cut into ``round(w / (aspect
    h))`` equal pieces, each with its share of the area."""
    st = np.column_stack([st, np.zeros(len(st))])  # column 5: 1 for a piece of a cut component
    fill = st[:, 4] / np.maximum(st[:, 2] * st[:, 3], 1)
    wide = (st[:, 2] > 1.0 * st[:, 3]) & (st[:, 2] <= 4 * st[:, 3]) & (fill >= 0.3) & (fill <= 0.7)
    if not wide.any():
        return st
    parts = [st[~wide]]
    for x, y, w, h, a, _ in st[wide]:
        k = int(max(2, round(w / (aspect * h))))
        parts.append(np.column_stack([x + w / k * np.arange(k), np.full(k, y), np.full(k, w / k), np.full(k, h),
                                      np.full(k, a / k), np.ones(k)]))
    return np.concatenate(parts)


def plate_from_row(row, layout):
    """The plate's box ``(x, y, w, h)`` of a character row's box ``row (x, y, w, h)`` in ``layout``
    (:data:`ROW_IN_PLATE`)."""
    a0, b0, a1, b1 = ROW_IN_PLATE[layout]
    x, y, w, h = row
    pw, ph = w / (a1 - a0), h / (b1 - b0)
    return np.array([x - a0 * pw, y - b0 * ph, pw, ph])


def refine_outline(gray, plate, row, reach=0.35, contrast=1.5):
    """The plate's box ``plate (x, y, w, h)`` (from :func:`plate_from_row`) moved side by side onto
    the plate's borders in ``gray``: each side goes to the strongest edge across it (``|∇_y I|``
    for the top and bottom, ``|∇_x I|`` for the left and right) between the character row ``row``
    and ``reach`` plate heights beyond the predicted side, where that edge is at least ``contrast``
    times the window's median; else it stays where the layout puts it."""
    x, y, w, h = plate
    rx, ry, rw, rh = row
    H, W = gray.shape
    x0, y0 = int(max(0, x - reach * w - 2)), int(max(0, y - reach * h - 2))
    x1, y1 = int(min(W, x + w + reach * w + 3)), int(min(H, y + h + reach * h + 3))
    if x1 - x0 < 4 or y1 - y0 < 4:
        return plate
    g = gray[y0:y1, x0:x1].astype(np.float32)
    gx = np.abs(cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3))
    gy = np.abs(cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3))
    cols = slice(int(rx + 0.1 * rw) - x0, int(rx + 0.9 * rw) - x0)
    rows = slice(int(ry + 0.15 * rh) - y0, int(ry + 0.85 * rh) - y0)
    prof_y = gy[:, cols].mean(axis=1)  # per image row
    prof_x = gx[rows, :].mean(axis=0)  # per image column

    def side(prof, lo, hi, default):
        lo, hi = int(max(0, lo)), int(min(len(prof), hi))
        if hi - lo < 3:
            return default
        win = prof[lo:hi]
        k = int(np.argmax(win))
        return lo + k if win[k] >= contrast * max(float(np.median(win)), 1e-3) else default

    d, dx = reach * h, reach * w
    top = side(prof_y, y - d - y0, ry - 1 - y0, y - y0) + y0
    bottom = side(prof_y, ry + rh + 1 - y0, y + h + d - y0, y + h - y0) + y0
    left = side(prof_x, x - dx - x0, rx - 0.1 * rh - x0, x - x0) + x0
    right = side(prof_x, rx + rw + 0.1 * rh - x0, x + w + dx - x0, x + w - x0) + x0
    return np.array([left, top, right - left, bottom - top], float)


def _inside(box, shape, margin):
    x, y, w, h = box
    return x >= margin and y >= margin and x + w <= shape[1] - margin and y + h <= shape[0] - margin


def _unique(boxes, thr=0.7):
    """``boxes (M, 4)`` without near-duplicates (IoU above ``thr`` with one kept before)."""
    keep = []
    for b in boxes:
        if all(iou(b, k) <= thr for k in keep):
            keep.append(b)
    return np.array(keep).reshape(-1, 4)


def acquire(frames, detector=None, *, within=30, confirm=2):
    """Search ``frames`` (iterable of ``(index, frame)``) for a plate: the first detection that
    is seen again at the same place (IoU ≥ 0.3) in ``confirm`` consecutive frames, within the
    first ``within`` frames.

    Returns ``(found, searched)``: ``found`` is ``(index, frame, Detection)`` of the frame where it
    is confirmed, or ``None``; ``searched`` the ``(index, frame)`` pairs before it (all of them
    when nothing was found)."""
    detector = detector or PlateDetector()
    searched, chains = [], []
    for i, frame in frames:
        dets = detector.detect(frame)
        new = []
        for d in dets:
            run = 1 + max((n for b, n in chains if iou(d.box, b) >= 0.3), default=0)
            if run >= confirm:
                return (i, frame, d), searched
            new.append((d.box, run))
        chains = new
        searched.append((i, frame))
        if len(searched) >= within:
            break
    return None, searched


class PlateSearch:
    """A plate model still to be started: ``vistrack run VIDEO`` on real footage without a box.
    :meth:`start` searches the first frames for a plate (:func:`acquire`) and builds the model at
    the one it confirms.

    Parameters
    ----------
    build : callable
        ``build(frame, detection) -> Plate``: the model started from a :class:`Detection` in
        ``frame`` (its layout, unless one was given, and its appearance learned there).
    within : int
        Frames searched before giving up (30).
    detector : PlateDetector or None
    """

    def __init__(self, build, within=30, detector=None):
        self.build, self.within = build, int(within)
        self.detector = detector or PlateDetector()

    def start(self, frames):
        """Search ``frames`` (iterable of ``(index, frame)``): ``(model, found, searched)`` with the
        model started at the confirmed detection (``None`` when nothing passed the test in the
        first :attr:`within` frames), ``found = (index, frame, Detection)`` and the frames searched
        before it (:func:`acquire`)."""
        found, searched = acquire(frames, self.detector, within=self.within)
        if found is None:
            return None, None, searched
        return self.build(found[1], found[2]), found, searched
