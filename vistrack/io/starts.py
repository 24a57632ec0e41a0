"""Where a run starts: the start box and frame from the user's ``--init`` / ``--init-gt`` and the clip.

Shared by :mod:`vistrack.registry.builders` and the model packages' builders (``vistrack.models.*.builder``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .clips import read_groundtruth_csv
from .video import VideoError, find_groundtruth, groundtruth_origin, read_rects

__all__ = ["MAX_BOX_FACTOR", "initial_truth", "start_frame", "check_start_box", "start_box_problem", "first_frame",
           "start_box", "one_based_init_note"]


def initial_truth(clip, init_gt):
    """The first visible ground-truth row as a dict, from the clip or from ``init_gt``.

    ``init_gt`` is ``""``/``True`` for the clip's own ground truth, or a path to a
    ``groundtruth.csv`` or an OTB ``x,y,w,h`` file.
    """
    if init_gt in ("", True, None):
        truth = clip.truth
        if truth is None:
            raise VideoError(f"--init-gt: {clip.folder} has no groundtruth.csv or groundtruth_rect.txt; "
                             "give a file (--init-gt FILE) or a box (--init x,y,w,h)")
    else:
        if "://" in str(init_gt):
            raise VideoError(f"--init-gt {init_gt}: a URL; give a local ground-truth file, or --init-gt alone for "
                             "the clip's own (a clip given as a URL brings its ground truth)")
        p = Path(init_gt)
        if p.is_dir():
            raise VideoError(f"--init-gt: {p} is a folder; give a ground-truth file (groundtruth.csv, or x,y,w,h "
                             "per line), or --init-gt alone for the clip's own")
        if not p.is_file():
            raise VideoError(f"--init-gt: {p} does not exist" if not p.exists() else
                             f"--init-gt: {p} is not a regular file")
        if p.suffix == ".csv":
            truth = read_groundtruth_csv(p)
        else:
            r = read_rects(p, origin=groundtruth_origin(p))
            truth = {"visible": ((r[:, 2] > 0) & (r[:, 3] > 0)).astype(float), "cx": r[:, 0] + r[:, 2] / 2,
                     "cy": r[:, 1] + r[:, 3] / 2, "w": r[:, 2], "h": r[:, 3]}
    vis = np.flatnonzero(np.asarray(truth["visible"]) > 0)
    if not len(vis):
        raise VideoError("--init-gt: the object is not visible in any ground-truth row")
    row = {k: float(v[vis[0]]) for k, v in truth.items() if np.asarray(v).dtype.kind in "fiub"}
    if "w" in row and "cx" in row:
        check_start_box((row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"]),
                        clip.source.size, f"the first ground-truth box (frame {int(vis[0])})")
    return row


def start_frame(clip, init=None, init_gt=None):
    """The frame a run starts from: the first frame whose ground-truth row has the object
    (``init_gt`` given, no ``init``), else 0. Frames before it are not tracked (``vistrack run``
    gives them rows with ``lost_reason`` "not started"; their ground truth has no box to score)."""
    if init is not None or init_gt is None:
        return 0
    if init_gt in ("", True):
        truth = clip.truth
        if truth is None:
            return 0
    else:
        p = Path(init_gt)
        if p.suffix == ".csv":
            truth = read_groundtruth_csv(p)
        else:
            r = read_rects(p, origin=groundtruth_origin(p))
            truth = {"visible": ((r[:, 2] > 0) & (r[:, 3] > 0)).astype(float)}
    vis = np.flatnonzero(np.asarray(truth["visible"]) > 0)
    return int(vis[0]) if len(vis) else 0


#: a start box may be at most this many times the frame's width and height
MAX_BOX_FACTOR = 2


def check_start_box(box, size, what="--init box"):
    """Raise :class:`VideoError` unless ``box`` ``(x, y, w, h)`` is one to start tracking from in a frame of
    ``size`` ``(width, height)`` (:func:`start_box_problem`)."""
    problem = start_box_problem(box, size, what)
    if problem:
        raise VideoError(problem[1])


def start_box_problem(box, size, what="--init box"):
    """``None`` where ``box`` ``(x, y, w, h)`` is one to start tracking from in a frame of ``size``
    ``(width, height)``: finite numbers and a positive size, at most :data:`MAX_BOX_FACTOR` times the frame's
    width and height, at least 2 px wide and high, its centre in the frame (else the tracker would report
    the object out of frame from the start) and 2 px of it inside each way; else ``(kind, line)``, the first
    check it fails (``"numbers"``, ``"size"`` or ``"outside"``) and the one line that refuses it."""
    fw, fh = size
    x, y, w, h = (float(v) for v in box)
    text, cx, cy = f"{x:.6g},{y:.6g},{w:.6g},{h:.6g}", x + w / 2, y + h / 2
    if not all(np.isfinite([x, y, w, h])) or w <= 0 or h <= 0:
        return "numbers", f"{what} {text} needs finite numbers and a positive size (width and height)"
    if w > MAX_BOX_FACTOR * fw or h > MAX_BOX_FACTOR * fh:
        return "size", (f"{what} {text} is far larger than the {fw}x{fh} frame (at most {MAX_BOX_FACTOR} times its "
                        "width and height): give the object's box")
    if w < 2 or h < 2:
        return "size", (f"{what} {text} is smaller than 2 px ({w:.6g}x{h:.6g}): give a box of at least 2x2 px on "
                        "the object")
    if not (0 <= cx < fw and 0 <= cy < fh):
        return "outside", (f"{what} {text} lies outside the {fw}x{fh} frame (its centre {cx:.6g},{cy:.6g} is not in "
                           "it): give a box on the object")
    if min(x + w, fw) - max(x, 0) < 2 or min(y + h, fh) - max(y, 0) < 2:
        return "outside", (f"{what} {text} lies outside the {fw}x{fh} frame (less than 2 px of it inside): give a "
                           "box on the object")
    return None


def first_frame(clip, index=0):
    """The first decodable frame of ``clip`` at or after ``index`` (the start frame)."""
    for i, frame in clip.source:
        if i >= index:
            return frame
    raise VideoError(f"{clip.source.shown}: no frame could be decoded" + (f" from frame {index} on" if index else ""))


def start_box(clip, init, init_gt):
    """The start box ``(x, y, w, h)``: ``init``, or the first ground-truth row."""
    if init is not None:
        return tuple(float(v) for v in init)
    row = initial_truth(clip, init_gt)
    return (row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"])


def one_based_init_note(clip, init):
    """A note (one line) when the ``--init`` box ``init`` is the first box of the clip's ground-truth
    file as the file writes it, in a convention that counts pixels from 1 (OTB, LaSOT: a first line
    pasted as it is): ``--init`` is 0-based, so the box is off by a pixel each way, and ``--init-gt``
    starts from the true one. ``None`` otherwise."""
    gt = find_groundtruth(clip.folder) if clip.truth is not None else None
    if init is None or gt is None or groundtruth_origin(gt) != 1:
        return None
    raw = read_rects(gt)  # as the file writes them
    seen = np.flatnonzero((raw[:, 2] > 0) & (raw[:, 3] > 0))
    if not len(seen) or not np.allclose(raw[seen[0]], np.asarray(init, float)):
        return None
    x, y, w, h = raw[seen[0]]
    return (f"note: --init {x:g},{y:g},{w:g},{h:g} is the first box of {gt}, which counts pixels from 1 (OTB, "
            f"LaSOT); --init is 0-based (the top-left pixel is 0,0), where that box is {x - 1:g},{y - 1:g},{w:g},"
            f"{h:g}: --init-gt starts from it")
