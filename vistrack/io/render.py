"""Draw estimates and particles on frames (annotated output videos)."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["draw_polylines", "draw_dashed", "draw_box", "draw_tag", "draw_label", "annotate", "annotate_targets",
           "id_colour", "tracker_colour"]

ESTIMATE = (0, 255, 255)  # yellow
PARTICLE = (255, 160, 0)  # blue-ish
TRUTH = (0, 200, 0)
#: the last box reported, drawn dashed on a frame where the object is reported lost
LOST = (200, 200, 200)  # light grey
#: the tags on the box: ``lost: <reason>`` (red) and ``re-detected`` (green)
LOST_TAG = (0, 0, 210)
FOUND_TAG = (0, 170, 0)


def draw_polylines(img, curves, color, thickness=1, closed=True):
    """Draw ``curves (K, M, 2)`` (float px) in place, anti-aliased with sub-pixel precision."""
    if len(curves) == 0:
        return img
    pts = [np.round(np.asarray(c) * 16).astype(np.int32) for c in curves]
    cv2.polylines(img, pts, closed, color, thickness, cv2.LINE_AA, shift=4)
    return img


def draw_dashed(img, curves, color, thickness=1, dash=6.0):
    """Draw the closed ``curves (K, M, 2)`` (float px) dashed in place: dashes and gaps ``dash`` px long."""
    for c in curves:
        pts = np.asarray(c, float)
        pts = np.vstack([pts, pts[:1]])
        seg = np.diff(pts, axis=0)
        length = np.hypot(seg[:, 0], seg[:, 1])
        at = np.concatenate([[0.0], np.cumsum(length)])
        if at[-1] <= 0:
            continue
        starts = np.arange(0.0, at[-1], 2 * dash)
        ends = np.minimum(starts + dash, at[-1])
        xs = [np.interp(np.r_[a, at[(at > a) & (at < b)], b], at, pts[:, 0]) for a, b in zip(starts, ends)]
        ys = [np.interp(np.r_[a, at[(at > a) & (at < b)], b], at, pts[:, 1]) for a, b in zip(starts, ends)]
        draw_polylines(img, [np.column_stack([x, y]) for x, y in zip(xs, ys)], color, thickness, closed=False)
    return img


def draw_box(img, box, color, thickness=1, dashed=False):
    """Draw the box ``(x, y, w, h)`` (px) in place where it is finite and of positive size (``dashed``:
    :func:`draw_dashed`)."""
    x, y, w, h = (float(v) for v in box)
    if not (np.all(np.isfinite([x, y, w, h])) and w > 0 and h > 0):
        return img
    corners = np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h]])
    if dashed:
        return draw_dashed(img, [corners], color, thickness)
    x0, y0, x1, y1 = (int(round(v)) for v in (x, y, x + w, y + h))
    cv2.rectangle(img, (x0, y0), (x1, y1), color, thickness)
    return img


def draw_tag(img, text, bounds, color):
    """White ``text`` on a filled ``color`` tag above the box ``bounds`` ``(x0, y0, x1, y1)`` (px), or below it
    where the frame's label (:func:`draw_label`) holds the space above; kept inside the image."""
    scale = max(0.4, img.shape[1] / 900)
    (tw, th), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
    x0, y0, _, y1 = np.nan_to_num(np.asarray(bounds, float))
    label = 16 + 2 * base + th + 8  # the lowest a tag's bottom may be without covering the frame's label
    y = y0 - 3 if y0 - 3 >= label else y1 + th + base + 7
    x = int(np.clip(x0, 0, max(0, img.shape[1] - tw - 6)))
    y = int(np.clip(y, th + base + 4, img.shape[0] - 1))
    cv2.rectangle(img, (x, y - th - base - 4), (x + tw + 6, y), color, -1)
    cv2.putText(img, text, (x + 3, y - base - 2), cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), 1, cv2.LINE_AA)
    return img


def draw_label(img, text, org=(6, 16)):
    """White text on a dark box at the top left."""
    scale = max(0.4, img.shape[1] / 800)
    (tw, th), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
    cv2.rectangle(img, (org[0] - 3, org[1] - th - 3), (org[0] + tw + 3, org[1] + base), (0, 0, 0), -1)
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), 1, cv2.LINE_AA)
    return img


def annotate(frame, estimate_curves, particle_curves, text, truth_curves=None, lost=None, redetected=False):
    """A copy of ``frame`` with particles (thin), the estimate (thick) and a label. ``lost``: the frame is
    reported lost, ``(reason, curves)``: the last curves reported drawn dashed in grey (none before the first
    report) and tagged ``lost: <reason>``, the estimate not drawn; ``redetected``: the estimate tagged
    ``re-detected`` (the object found again)."""
    img = frame.copy()
    if truth_curves is not None:
        draw_polylines(img, truth_curves, TRUTH, 1)
    draw_polylines(img, particle_curves, PARTICLE, 1)
    if lost is not None:
        reason, last = lost
        draw_dashed(img, last, LOST, 2)
        draw_tag(img, f"lost: {reason}", _bounds(last), LOST_TAG)
    else:
        draw_polylines(img, estimate_curves, ESTIMATE, 2)
        if redetected and len(estimate_curves):
            draw_tag(img, "re-detected", _bounds(estimate_curves), FOUND_TAG)
    draw_label(img, text)
    return img


def _bounds(curves):
    """``(x0, y0, x1, y1)`` of ``curves (K, M, 2)``; the top left under the frame's label without any."""
    if not len(curves):
        return (6, 0, 6, 24)
    pts = np.concatenate([np.asarray(c, float).reshape(-1, 2) for c in curves])
    return (*pts.min(axis=0), *pts.max(axis=0))


#: BGR colours of target ids, in turn (id k: ``ID_COLOURS[k % 8]``)
ID_COLOURS = ((0, 255, 255), (255, 0, 255), (0, 255, 0), (255, 128, 0), (0, 128, 255), (255, 255, 0),
              (128, 0, 255), (0, 0, 255))


#: BGR colours of the trackers compared in a report's videos, in turn (the truth is :data:`TRUTH`)
TRACKER_COLOURS = ((0, 0, 255), (255, 128, 0), (255, 0, 255), (0, 200, 255), (255, 255, 0), (128, 0, 255),
                   (0, 128, 255), (200, 200, 200))


def tracker_colour(k):
    """The BGR colour of the ``k``-th tracker of a comparison (:data:`TRACKER_COLOURS`)."""
    return TRACKER_COLOURS[int(k) % len(TRACKER_COLOURS)]


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
