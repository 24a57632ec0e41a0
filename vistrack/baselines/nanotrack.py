"""NanoTrack v3 as its authors' tracker runs it: a baseline to compare vistrack with (not a particle filter).

The logic of ``NanoTrack/nanotrack/tracker/nano_tracker.py`` (HonglinChu/SiamTrackers, Apache-2.0) with its
settings (``configv3.yaml``: exemplar 127, search 255, context 0.5, window influence 0.455, ``penalty_k``
0.138, ``lr`` 0.348), on the network vistrack ships (:class:`~vistrack.models.siam.network.SiamNetwork`):

1. a search crop of side ``s_x = s_z · 255 / 127`` about the last position (``s_z``: the exemplar's side of
   the last size, :func:`~vistrack.models.siam.network.context_side`);
2. per cell, the object's softmax score ``p``, the head's box, a penalty
   ``exp(-(r_c s_c - 1) k)`` on the change of scale ``s_c`` and aspect ``r_c`` from the last size, and a
   Hann window: ``(1 - w) p · penalty + w · hann``;
3. the best cell's box: its centre taken, its size blended with the last by ``lr · penalty · p``, clipped
   to the frame.

It keeps one hypothesis, has no motion model, always reports the object and never searches again: what
vistrack's ``siam`` model adds (:mod:`vistrack.models.siam`).
"""

from __future__ import annotations

import time

import numpy as np

from ..models.siam.network import CONTEXT, EXEMPLAR, INSTANCE, SiamNetwork, cell_points, context_side, crop

__all__ = ["NanoTrackV3", "SETTINGS", "track_nanotrack_v3"]

#: the authors' settings (NanoTrack/models/config/configv3.yaml)
SETTINGS = {"window_influence": 0.455, "penalty_k": 0.138, "lr": 0.348}


class NanoTrackV3:
    """NanoTrack v3 with its authors' tracker logic (module docstring), OpenCV's ``init`` / ``update`` shape.

    Parameters
    ----------
    network : SiamNetwork or None
        The network (a new one on the package's weights by default).
    window_influence, penalty_k, lr : float
        The authors' settings (:data:`SETTINGS`).
    """

    def __init__(self, network=None, *, window_influence=SETTINGS["window_influence"],
                 penalty_k=SETTINGS["penalty_k"], lr=SETTINGS["lr"]):
        self.net = network or SiamNetwork()
        self.window_influence, self.penalty_k, self.lr = float(window_influence), float(penalty_k), float(lr)
        size = 15
        hann = np.hanning(size)
        self.window = np.outer(hann, hann).ravel()
        self.points = cell_points(size)
        self.centre = self.size = self.fill = None
        self.score = None

    def init(self, frame, box):
        """Start from ``box`` ``(x, y, w, h)`` in ``frame`` (BGR ``(H, W, 3)`` uint8)."""
        x, y, w, h = (float(v) for v in box)
        self.centre = np.array([x + (w - 1) / 2, y + (h - 1) / 2])
        self.size = np.array([w, h])
        self.fill = np.asarray(frame, float).reshape(-1, frame.shape[-1]).mean(axis=0)
        self.net.set_exemplar(crop(frame, self.centre, round(float(context_side(w, h, CONTEXT))), EXEMPLAR,
                                   self.fill), fixed=False)  # the head as the authors run it: both inputs each frame
        self.score = 1.0

    def update(self, frame):
        """One frame: ``(True, (x, y, w, h))`` (the authors' tracker always reports the object)."""
        s_z = float(context_side(*self.size, CONTEXT))
        scale = EXEMPLAR / s_z
        s_x = s_z * INSTANCE / EXEMPLAR
        logit, ltrb = self.net.search(crop(frame, self.centre, round(s_x), INSTANCE, self.fill))
        score = 1.0 / (1.0 + np.exp(-logit[0].ravel().astype(float)))  # softmax of the two logits
        d = ltrb[0].reshape(4, -1).astype(float)
        x1, y1 = self.points[:, 0] - d[0], self.points[:, 1] - d[1]
        x2, y2 = self.points[:, 0] + d[2], self.points[:, 1] + d[3]
        cx, cy, bw, bh = (x1 + x2) / 2, (y1 + y2) / 2, x2 - x1, y2 - y1
        s_c = _change(context_side(bw, bh) / context_side(*(self.size * scale)))
        r_c = _change((self.size[0] / self.size[1]) / (bw / bh))
        penalty = np.exp(-(r_c * s_c - 1) * self.penalty_k)
        pscore = (penalty * score) * (1 - self.window_influence) + self.window * self.window_influence
        k = int(np.argmax(pscore))
        lr = penalty[k] * score[k] * self.lr
        c = self.centre + np.array([cx[k], cy[k]]) / scale
        wh = self.size * (1 - lr) + np.array([bw[k], bh[k]]) / scale * lr
        hgt, wid = frame.shape[:2]
        self.centre = np.array([min(max(c[0], 0.0), wid), min(max(c[1], 0.0), hgt)])
        self.size = np.array([min(max(wh[0], 10.0), wid), min(max(wh[1], 10.0), hgt)])
        self.score = float(score[k])
        return True, (self.centre[0] - self.size[0] / 2, self.centre[1] - self.size[1] / 2, *self.size)


def _change(r):
    return np.maximum(r, 1.0 / r)


def track_nanotrack_v3(box, frames):
    """One run of :class:`NanoTrackV3` from ``box`` ``(x, y, w, h)`` on the first of ``frames`` (``(index, BGR or
    grey frame)`` pairs): ``(boxes (F, 4), ms (F,), index (F,))``, ``x, y, w, h`` per frame, the milliseconds of each
    call, the frames' indices (the shape of :func:`~vistrack.baselines.opencv.track_opencv`)."""
    import cv2

    tracker = NanoTrackV3()
    boxes, ms, index = [], [], []
    for k, (i, frame) in enumerate(frames):
        f = np.asarray(frame)
        f = cv2.cvtColor(f, cv2.COLOR_GRAY2BGR) if f.ndim == 2 else f
        index.append(i)
        t0 = time.perf_counter()
        if k == 0:
            tracker.init(f, box)
            b = tuple(float(v) for v in box)
        else:
            b = tracker.update(f)[1]
        ms.append((time.perf_counter() - t0) * 1e3)
        boxes.append(b)
    return np.array(boxes, float), np.array(ms), np.array(index, int)
