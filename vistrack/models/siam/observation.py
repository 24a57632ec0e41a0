"""A frame as the siam model observes it: the Siamese network's response over one search crop, in frame
coordinates (thesis 001 §4.5: the learned response as ``log r`` and as LIS's local proposal).

The network (:mod:`~vistrack.models.siam.network`) gives, over a ``15 × 15`` grid of cells of the search
crop, the object's logit (object less background) and a box per cell. :class:`SiamFrame` holds them with the
crop's geometry: cell ``(i, j)`` sits at ``c + a (j - 7, i - 7)`` frame px (``c`` the crop's centre, ``a``
the cell's side in frame px, 16 search-crop px), and its box is ``(cx, cy, log w/w_0, log h/h_0)``, the
state's coordinates (:mod:`~vistrack.models.siam.model`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .network import STRIDE, cell_points

__all__ = ["SiamFrame", "cell_boxes", "colour_histogram"]

#: colour bins per channel of :func:`colour_histogram` (BGR, 4 x 4 x 4)
COLOUR_BINS = 4


def colour_histogram(image, box):
    """The normalised BGR histogram ``(64,)`` (4 bins a channel) of the pixels of ``image (3, S, S)`` (float,
    0..255) inside ``box`` ``(x0, y0, x1, y1)`` (pixels of the image, clipped to it); uniform where it is empty."""
    s = image.shape[1]
    x0, y0 = max(0, int(box[0])), max(0, int(box[1]))
    x1, y1 = min(s, int(np.ceil(box[2]))), min(s, int(np.ceil(box[3])))
    n = COLOUR_BINS ** 3
    if x1 <= x0 or y1 <= y0:
        return np.full(n, 1.0 / n)
    q = (image[:, y0:y1, x0:x1] * (COLOUR_BINS / 256.0)).astype(np.intp)
    idx = (q[0] * COLOUR_BINS + q[1]) * COLOUR_BINS + q[2]
    h = np.bincount(idx.ravel(), minlength=n).astype(float)
    return h / h.sum()

_POINTS = cell_points(15)


def cell_boxes(ltrb, centre, scale, size0, points=_POINTS):
    """The head's box of every cell in the state's coordinates: ``(C, 4)`` ``(cx, cy, log w/w_0, log h/h_0)``.

    ``ltrb (4, M, M)`` distances (search-crop px) of the box's sides from each cell's point, ``centre (2,)`` the
    crop's centre (frame px), ``scale`` search-crop px per frame px, ``size0 (2,)`` the first box's size."""
    d = np.asarray(ltrb, float).reshape(4, -1)
    cx = centre[0] + (points[:, 0] + (d[2] - d[0]) / 2) / scale
    cy = centre[1] + (points[:, 1] + (d[3] - d[1]) / 2) / scale
    w = np.maximum(d[0] + d[2], 1e-3) / scale
    h = np.maximum(d[1] + d[3], 1e-3) / scale
    return np.stack([cx, cy, np.log(w / size0[0]), np.log(h / size0[1])], axis=1)


@dataclass
class SiamFrame:
    """One frame's response over its search crop.

    Attributes
    ----------
    frame : ndarray (H, W, 3) uint8
        The frame (BGR).
    centre : ndarray (2,)
        The search crop's centre (frame px).
    scale : float
        Search-crop px per frame px (``255 / side``).
    logit : ndarray (M, M)
        The object's logit less the background's per cell (float64).
    boxes : ndarray (M * M, 4)
        The head's box per cell, row by row, in the state's coordinates (:func:`cell_boxes`).
    size0 : ndarray (2,)
        The first box's size ``(w_0, h_0)`` (the state's log-sizes are relative to it).
    crop : ndarray (3, S, S) float32 or None
        The search crop the network saw (BGR; :func:`~vistrack.models.siam.network.crop`).
    redetected : bool
        Whether this frame's crop is a lost object's re-detection (:mod:`~vistrack.models.siam.lost`).
    found : ndarray (4,) or None
        Where a re-detection found the object (the particles are re-seeded there).
    """

    frame: np.ndarray
    centre: np.ndarray
    scale: float
    logit: np.ndarray
    boxes: np.ndarray
    size0: np.ndarray
    crop: np.ndarray | None = None
    redetected: bool = False
    found: np.ndarray | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def size(self):
        """``M``: the map's side in cells."""
        return self.logit.shape[0]

    @property
    def cell(self):
        """A cell's side in frame px."""
        return STRIDE / self.scale

    #: a cell's side in search-crop px
    cell_px = STRIDE

    def cell_coords(self, xy):
        """Map coordinates ``(N, 2)`` ``(u, v)`` (column, row; cell centres at whole numbers) of frame points
        ``xy (N, 2)``."""
        half = self.size // 2
        return (np.asarray(xy, float) - self.centre) * (self.scale / STRIDE) + half

    def logit_at(self, xy, floor):
        """The logit bilinearly interpolated at frame points ``xy (N, 2)`` -> ``(N,)``; ``floor`` outside the map
        (more than half a cell beyond its outer cells)."""
        uv = self.cell_coords(xy)
        m = self.size
        inside = np.all((uv > -0.5) & (uv < m - 0.5), axis=1)
        uv = np.clip(uv, 0.0, m - 1.0)
        i0 = np.minimum(np.floor(uv).astype(np.intp), m - 2)
        f = uv - i0
        L = self.logit
        u0, v0 = i0[:, 0], i0[:, 1]
        top = L[v0, u0] * (1 - f[:, 0]) + L[v0, u0 + 1] * f[:, 0]
        bottom = L[v0 + 1, u0] * (1 - f[:, 0]) + L[v0 + 1, u0 + 1] * f[:, 0]
        return np.where(inside, top * (1 - f[:, 1]) + bottom * f[:, 1], floor)

    def nearest_cell(self, xy):
        """The index ``(N,)`` (row by row) of the cell nearest each frame point ``xy (N, 2)`` (clipped to the map)."""
        uv = np.clip(np.rint(self.cell_coords(xy)), 0, self.size - 1).astype(np.intp)
        return uv[:, 1] * self.size + uv[:, 0]
