"""A small learned plate/non-plate test for the detector's rectangle candidates.

Candidates
    :func:`rectangle_candidates`: the closed outlines of the grey frame's Canny edges whose
    bounding box is plate-shaped (aspect 1.2–8, at least 8 px high) and which fill at least 60 %
    of their smallest rotated rectangle — a plate's border, whatever its characters (the
    Japanese layout's bold digits touch after binarisation, so the character-row test of
    :class:`~vistrack.models.plate.detect.PlateDetector` misses them).
Features
    :func:`window_features`: the candidate box grown by :data:`GROW` of its size on each side,
    resized to a 64×32 window, its HOG (Dalal and Triggs 2005, scikit-image's; 8×8 cells, 16×16
    blocks, 9 orientations: 756 values), and the box's log aspect ratio.
Classifier
    A logistic regression over the standardised features, ``score = b + Σ_f c_f (x_f - μ_f) / σ_f``
    (log-odds of a plate); its coefficients are in ``plate_classifier.npz`` beside this module,
    made by ``benchmarks/train_plate_classifier.py`` (scikit-learn, used only there) from
    rendered plates (:func:`~vistrack.data_synth.plate_clip.detection_frames`, both layouts) over
    synthetic road scenes and over frames of the plate-free real clips, and the candidates of
    plate-free frames — seeds and frames disjoint from the tests' and from the search's first
    30 frames.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

__all__ = ["PlateClassifier", "rectangle_candidates", "window_features", "WINDOW", "GROW"]

#: the HOG window (width, height) px
WINDOW = (64, 32)
#: each side of a candidate box grows by this share of its width (x) and height (y) before resizing
GROW = (0.08, 0.15)
_WEIGHTS = Path(__file__).with_name("plate_classifier.npz")


def _hog(patch):
    """HOG of a :data:`WINDOW` patch (scikit-image's; OpenCV's ``HOGDescriptor`` is not in every
    OpenCV build): 8×8 cells, 2×2-cell blocks normalised by L2-Hys, 9 orientations — 756 values."""
    from skimage.feature import hog

    return hog(patch, orientations=9, pixels_per_cell=(8, 8), cells_per_block=(2, 2), block_norm="L2-Hys",
               feature_vector=True)


def rectangle_candidates(gray, low=40, high=120, min_h=8, max_w_frac=0.5):
    """Plate-shaped closed outlines in ``gray (H, W) uint8``: boxes ``(M, 4)`` ``(x, y, w, h)`` px
    (module docstring)."""
    e = cv2.Canny(gray, low, high)
    e = cv2.dilate(e, np.ones((2, 2), np.uint8))
    contours, _ = cv2.findContours(e, cv2.RETR_LIST, cv2.CHAIN_APPROX_SIMPLE)
    out = []
    for c in contours:
        x, y, w, h = cv2.boundingRect(c)
        if h < min_h or w < 20 or w > 8 * h or w < 1.2 * h or w > max_w_frac * gray.shape[1]:
            continue
        _, (rw, rh), _ = cv2.minAreaRect(c)
        if cv2.contourArea(c) < 0.6 * rw * rh:
            continue
        out.append((x, y, w, h))
    return np.array(out, float).reshape(-1, 4)


def window_features(gray, boxes):
    """Features ``(M, 757)`` float32 of ``boxes (M, 4)`` ``(x, y, w, h)`` in ``gray (H, W) uint8``: the
    HOG of each grown box resized to :data:`WINDOW` (756) and ``log(w / h)``."""
    H, W = gray.shape
    out = np.empty((len(boxes), 757), np.float32)
    for i, (x, y, w, h) in enumerate(np.asarray(boxes, float)):
        gx, gy = GROW[0] * w, GROW[1] * h
        x0, y0 = int(max(0, np.floor(x - gx))), int(max(0, np.floor(y - gy)))
        x1, y1 = int(min(W, np.ceil(x + w + gx))), int(min(H, np.ceil(y + h + gy)))
        crop = gray[y0:max(y1, y0 + 1), x0:max(x1, x0 + 1)]
        interp = cv2.INTER_AREA if crop.shape[1] > WINDOW[0] else cv2.INTER_LINEAR
        patch = cv2.resize(crop, WINDOW, interpolation=interp)
        out[i, :756] = _hog(patch)
        out[i, 756] = np.log(w / h)
    return out


class PlateClassifier:
    """The learned plate test (module docstring).

    Parameters
    ----------
    path : str or Path or None
        The ``.npz`` with ``coef (F,)``, ``bias ()``, ``mean (F,)``, ``scale (F,)`` and ``threshold ()``
        (the log-odds a plate needs); ``None``: the one shipped beside this module.
    """

    def __init__(self, path=None):
        with np.load(path or _WEIGHTS) as d:
            self.coef, self.bias = d["coef"].astype(float), float(d["bias"])
            self.mean, self.scale = d["mean"].astype(float), d["scale"].astype(float)
            #: log-odds a candidate needs to be a plate
            self.threshold = float(d["threshold"])

    def decision(self, features):
        """Log-odds of a plate ``(M,)`` of ``features (M, F)``."""
        return ((np.asarray(features, float) - self.mean) / self.scale) @ self.coef + self.bias

    def score(self, gray, boxes):
        """Log-odds of a plate ``(M,)`` of ``boxes (M, 4)`` in ``gray``."""
        if len(boxes) == 0:
            return np.zeros(0)
        return self.decision(window_features(gray, boxes))
