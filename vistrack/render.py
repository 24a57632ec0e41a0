"""Draw estimates and particles on frames (annotated output videos)."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["draw_polylines", "draw_label", "annotate"]

ESTIMATE = (0, 255, 255)  # yellow
PARTICLE = (255, 160, 0)  # blue-ish
TRUTH = (0, 200, 0)


def draw_polylines(img, curves, color, thickness=1, closed=True):
    """Draw ``curves (K, M, 2)`` (float px) in place, anti-aliased with sub-pixel precision."""
    if len(curves) == 0:
        return img
    pts = [np.round(np.asarray(c) * 16).astype(np.int32) for c in curves]
    cv2.polylines(img, pts, closed, color, thickness, cv2.LINE_AA, shift=4)
    return img


def draw_label(img, text, org=(6, 16)):
    """White text on a dark box at the top left."""
    scale = max(0.4, img.shape[1] / 800)
    (tw, th), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
    cv2.rectangle(img, (org[0] - 3, org[1] - th - 3), (org[0] + tw + 3, org[1] + base), (0, 0, 0), -1)
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), 1, cv2.LINE_AA)
    return img


def annotate(frame, estimate_curves, particle_curves, text, truth_curves=None):
    """A copy of ``frame`` with particles (thin), the estimate (thick) and a label."""
    img = frame.copy()
    if truth_curves is not None:
        draw_polylines(img, truth_curves, TRUTH, 1)
    draw_polylines(img, particle_curves, PARTICLE, 1)
    draw_polylines(img, estimate_curves, ESTIMATE, 2)
    draw_label(img, text)
    return img
