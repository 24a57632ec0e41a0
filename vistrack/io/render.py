"""Draw estimates and particles on frames (annotated output videos)."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["draw_polylines", "draw_label", "annotate", "annotate_targets", "id_colour"]

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


#: BGR colours of target ids, in turn (id k: ``ID_COLOURS[k % 8]``)
ID_COLOURS = ((0, 255, 255), (255, 0, 255), (0, 255, 0), (255, 128, 0), (0, 128, 255), (255, 255, 0),
              (128, 0, 255), (0, 0, 255))


def id_colour(i):
    """The BGR colour of target id ``i`` (:data:`ID_COLOURS`)."""
    return ID_COLOURS[int(i) % len(ID_COLOURS)]


def annotate_targets(frame, ids, outlines, particle_curves, text):
    """A copy of ``frame`` with particles (thin) and each target's outline (thick) in its id's
    colour with the id written above it, and a label."""
    img = frame.copy()
    draw_polylines(img, particle_curves, PARTICLE, 1)
    scale = max(0.4, img.shape[1] / 1000)
    for i, curve in zip(ids, outlines):
        col = id_colour(i)
        draw_polylines(img, [curve], col, 2)
        x, y = np.min(curve, axis=0)
        cv2.putText(img, str(int(i)), (int(x), int(y) - 4), cv2.FONT_HERSHEY_SIMPLEX, scale, col, 1, cv2.LINE_AA)
    draw_label(img, text)
    return img
