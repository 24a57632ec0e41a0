"""The plate model's observation of a frame (:meth:`~vistrack.models.plate.model.Plate.observe`): the
feature maps, the likelihood's 4-channel map and the learned appearance's maps over the region the
tracked particles can reach, with frames of their own for boxes elsewhere (births)."""

from __future__ import annotations

import numpy as np

__all__ = ["PlateObservation"]


class PlateObservation:
    """One frame as the plate model observes it (:meth:`~vistrack.models.plate.model.Plate.observe`).

    Attributes
    ----------
    maps : FeatureMaps
        The frame's feature maps.
    plate : ndarray of shape (H, W, 4) float32
        :func:`~vistrack.models.plate.likelihood.plate_map` of the frame.
    appearance : AppearanceFrame or None
        The learned appearance's maps over the region the tracked particles can reach
        (:meth:`~vistrack.models.plate.model.Plate.learn_appearance`).
    build : callable or None
        ``build(roi) -> AppearanceFrame`` of this frame over ``roi (x0, y0, x1, y1)``: the frames of
        boxes outside :attr:`appearance`'s region (:meth:`appearance_frames`).
    dcf : DCFResponse or None
        The correlation filter's response about the tracked particles' prediction
        (:attr:`Plate.cf <vistrack.models.plate.Plate.cf>`; none on the first frame or without a filter).
    """

    dcf = None

    def __init__(self, maps, plate, appearance=None, build=None):
        self.maps, self.plate, self.appearance = maps, plate, appearance
        self.build = build
        self._extra = []  # frames built for boxes outside ``appearance``'s region, shared by their neighbours

    @property
    def shape(self):
        """``(H, W)`` of the frame observed."""
        return self.maps.shape

    def _covers(self, frame, boxes, grow):
        """Which ``boxes (N, 4)`` (cx, cy, w, h), grown by ``grow (N,)`` px and two working pixels, lie in
        ``frame``'s region (a side at the frame's border covers everything beyond it)."""
        x0, y0, x1, y1 = frame.roi
        h, w = self.shape
        pad = 2 + 2 / frame.f  # two working pixels off the region's border (its Sobel reflects there)
        half_w, half_h = boxes[:, 2] / 2 + grow + pad, boxes[:, 3] / 2 + grow + pad
        return (((x0 <= 0) | (boxes[:, 0] - half_w >= x0)) & ((x1 >= w) | (boxes[:, 0] + half_w <= x1))
                & ((y0 <= 0) | (boxes[:, 1] - half_h >= y0)) & ((y1 >= h) | (boxes[:, 1] + half_h <= y1)))

    def appearance_frames(self, boxes, grow, margin):
        """``[(AppearanceFrame, indices)]`` that cover ``boxes (N, 4)`` (cx, cy, w, h) with ``grow (N,)``
        px around each (the colour term's ring): :attr:`appearance` for those in its region, and for
        the others (births elsewhere in the frame) frames over each box grown by ``margin`` px, built
        on first need and shared by the boxes they cover."""
        left = np.ones(len(boxes), bool)
        out = []
        for frame in [self.appearance] + self._extra:
            sel = left & self._covers(frame, boxes, grow)
            if sel.any():
                out.append((frame, np.flatnonzero(sel)))
                left &= ~sel
        while left.any():
            i = int(np.argmax(left))
            b = boxes[i]
            g = grow[i] + margin + 2 + 2 / self.appearance.f
            roi = tuple(int(v) for v in (np.floor(b[0] - b[2] / 2 - g), np.floor(b[1] - b[3] / 2 - g),
                                         np.ceil(b[0] + b[2] / 2 + g), np.ceil(b[1] + b[3] / 2 + g)))
            frame = self.build(roi)
            self._extra.append(frame)
            sel = left & self._covers(frame, boxes, grow)
            sel[i] = True
            out.append((frame, np.flatnonzero(sel)))
            left &= ~sel
        return out
