"""Several targets at once: the per-object files and the CLEAR-MOT and identity scores.

The multi-target files (a plate clip's ``objects.csv`` and the track CSV of ``vistrack run
--targets K``) have one row per frame and object, with the columns ``frame, visible, id`` and
the object's geometry (the plate's vertices ``x0, y0, ..., x3, y3`` and ``scale``, its width in
px); a frame without any object has one row with ``visible = 0`` and ``id = -1``.
:func:`objects_by_frame` reads them into per-frame arrays.

Scores (:func:`clear_mot`), by the ``motmetrics`` library: a reported plate and a true one can
be matched in a frame when their summed vertex error is at most a third of the true plate's
height — the single-plate experiment's rule for "on the plate" (:mod:`vistrack.scoring.metrics`).

* MOTA = 1 - (misses + false positives + identity switches) / true objects (Bernardin &
  Stiefelhagen 2008, CLEAR MOT);
* IDF1 = 2 IDTP / (2 IDTP + IDFP + IDFN), the F-score of the detections matched under the best
  one-to-one assignment of whole tracks to whole true trajectories (Ristani et al. 2016);
* MOTP here is the mean summed vertex error (px) of the matches;
* ``empty_frame_reports``: the plates reported in frames without any plate in view.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["MultiTarget", "Identities", "FrameObjects", "objects_by_frame", "plate_distances", "clear_mot",
           "require_motmetrics", "pool_scores",
           "MOT_KEYS"]


@runtime_checkable
class MultiTarget(Protocol):
    """A video model that reports several targets per frame (the plate slots of
    :class:`~vistrack.models.plate.plates.Plates`): each frame's targets are single-target states
    ``(M, d1)`` with their boxes, outlines and track-file columns."""

    def targets(self, obs, estimate):
        """The states ``(M, d1)`` of the targets reported at the joint ``estimate`` in the frame observed as ``obs``."""

    def target_box(self, states):
        """Boxes ``(M, 4)`` ``(x, y, w, h)`` of target states ``(M, d1)``."""

    def target_outline(self, states):
        """Points ``(M, P, 2)`` to draw per target state."""

    def describe_target(self, state):
        """The track-file columns of one target state ``(d1,)``."""


class Identities:
    """Track ids for the targets reported frame by frame: a target takes the id of the track whose
    predicted box centre (last centre plus its velocity times the frames since) is nearest, within
    half the track's box width, among the tracks seen in the last ``memory`` frames; the others get
    new ids 0, 1, 2, ... (one-to-one, nearest pairs first). A track's velocity is the exponential
    average (weight ``smooth`` on the newest) of its displacements per frame.

    Parameters
    ----------
    memory : int
        Frames a track unseen keeps its id (a plate reported again within them keeps its id). A car
        passing in front hides a plate for about 20 frames: on the training clips (seeds 201-203,
        partitioned LIS-100) memories of 10 / 30 / 60 frames gave IDF1 0.904 / 0.925 / 0.925 and
        1.7 / 0.3 / 0.3 identity switches per run.
    smooth : float
        Weight of the newest displacement in the velocity.
    """

    def __init__(self, memory=30, smooth=0.5):
        self.memory = int(memory)
        self.smooth = float(smooth)
        self.next_id = 0
        self._tracks = {}  # id -> (last frame, centre (2,), velocity (2,), width)

    def assign(self, frame, boxes):
        """Ids ``(M,)`` of the targets with ``boxes (M, 4)`` ``(x, y, w, h)`` in ``frame``."""
        boxes = np.asarray(boxes, float).reshape(-1, 4)
        centres = boxes[:, :2] + boxes[:, 2:] / 2
        live = {i: tr for i, tr in self._tracks.items() if frame - tr[0] <= self.memory}
        pairs = []
        for i, (f0, c0, v0, w0) in live.items():
            d = np.hypot(*(centres - (c0 + v0 * (frame - f0))).T)
            pairs += [(d[m], i, m) for m in np.flatnonzero(d <= 0.5 * w0)]
        ids = np.full(len(boxes), -1)
        used = set()
        for _, i, m in sorted(pairs):
            if ids[m] < 0 and i not in used:
                ids[m] = i
                used.add(i)
        for m in np.flatnonzero(ids < 0):
            ids[m] = self.next_id
            self.next_id += 1
        for m, i in enumerate(ids):
            f0, c0, v0, _ = self._tracks.get(i, (frame, centres[m], np.zeros(2), None))
            v = v0 if frame == f0 else (1 - self.smooth) * v0 + self.smooth * (centres[m] - c0) / (frame - f0)
            self._tracks[i] = (frame, centres[m], v, boxes[m, 2])
        self._tracks = {i: tr for i, tr in self._tracks.items() if frame - tr[0] <= self.memory}
        return ids

#: the scores of :func:`clear_mot`, in the order tables list them
MOT_KEYS = ("mota", "idf1", "motp", "switches", "false_positives", "misses", "objects", "empty_frame_reports",
            "frames_without")


@dataclass
class FrameObjects:
    """The objects of one frame: ``ids (M,)``, plate ``vertices (M, 4, 2)`` and ``scale (M,)``."""

    ids: np.ndarray
    vertices: np.ndarray
    scale: np.ndarray


def objects_by_frame(columns, frames=None):
    """Per-frame objects of a multi-target file read by
    :func:`~vistrack.io.clips.read_groundtruth_csv` (``columns``: name -> array, one entry per row):
    a list with one :class:`FrameObjects` per frame ``0 .. frames - 1`` (default: up to the
    largest frame in the file), empty where the file has no visible row."""
    frame = np.asarray(columns["frame"], int)
    n = int(frame.max()) + 1 if frames is None and len(frame) else int(frames or 0)
    vis = (np.asarray(columns["visible"]) > 0) & (frame < n)
    verts = np.stack([np.column_stack([columns[f"x{i}"], columns[f"y{i}"]]) for i in range(4)], axis=1)
    ids = np.asarray(columns["id"], int)
    scale = np.asarray(columns["scale"], float)
    out = [FrameObjects(np.zeros(0, int), np.zeros((0, 4, 2)), np.zeros(0)) for _ in range(n)]
    for t in np.unique(frame[vis]):
        sel = vis & (frame == t)
        out[t] = FrameObjects(ids[sel], verts[sel], scale[sel])
    return out


def plate_distances(truth, hyp, aspect):
    """Summed vertex errors ``(M_truth, M_hyp)`` (px) between the plates of one frame, NaN where
    above a third of the true plate's height (no match possible)."""
    d = np.linalg.norm(truth.vertices[:, None] - hyp.vertices[None], axis=3).sum(axis=2)
    height = truth.scale[:, None] / aspect
    with np.errstate(invalid="ignore"):
        return np.where(d <= height / 3, d, np.nan)


def require_motmetrics():
    """Raise ``ImportError`` saying what to install when ``motmetrics`` (a dependency of vistrack,
    which :func:`clear_mot` scores with) cannot be imported: batch commands check it before they
    track, so that a stale environment does not lose its score after hours of runs."""
    try:
        importlib.import_module("motmetrics")
    except ImportError:
        raise ImportError("the motmetrics library (vistrack's scorer of MOTA and IDF1) is not installed: "
                          "pip install motmetrics, or reinstall vistrack") from None


def clear_mot(truth, hyp, aspect):
    """CLEAR-MOT and identity scores of the tracks ``hyp`` against ``truth`` (lists of
    :class:`FrameObjects`, one per frame; frames beyond the shorter are not scored).

    Returns a dict with :data:`MOT_KEYS`: ``mota``, ``idf1``, ``motp`` (mean summed vertex error of
    the matches, px; ``None`` without any), ``switches``, ``false_positives``, ``misses``,
    ``objects`` (true objects summed over frames), ``empty_frame_reports`` (plates reported in
    frames without a true one) and ``frames_without`` (such frames).
    """
    import motmetrics as mm

    m = min(len(truth), len(hyp))
    acc = mm.MOTAccumulator(auto_id=True)
    empty_reports = frames_without = 0
    for t in range(m):
        a, b = truth[t], hyp[t]
        acc.update(a.ids.tolist(), b.ids.tolist(), plate_distances(a, b, aspect))
        if len(a.ids) == 0:
            frames_without += 1
            empty_reports += len(b.ids)
    s = mm.metrics.create().compute(acc, metrics=["mota", "idf1", "motp", "num_switches", "num_false_positives",
                                                  "num_misses", "num_objects"], name="run").iloc[0]
    n_obj = int(s["num_objects"])
    motp = float(s["motp"])
    return {"mota": float(s["mota"]) if n_obj else None, "idf1": float(s["idf1"]) if n_obj else None,
            "motp": motp if np.isfinite(motp) else None, "switches": int(s["num_switches"]),
            "false_positives": int(s["num_false_positives"]), "misses": int(s["num_misses"]), "objects": n_obj,
            "empty_frame_reports": int(empty_reports), "frames_without": int(frames_without)}


def pool_scores(rows):
    """The scores of task rows (:func:`score_plates_tasks`) of one group: the means over runs of MOTA,
    IDF1, MOTP, switches, false positives and misses per run, the plates reported in frames without
    one (summed), ms per frame and mean ESS."""
    def mean(k):
        v = [r[k] for r in rows if r[k] is not None]
        return float(np.mean(v)) if v else None

    return {"runs": len(rows), "mota": mean("mota"), "idf1": mean("idf1"), "motp": mean("motp"),
            "mota_std": float(np.std([r["mota"] or 0.0 for r in rows])),
            "switches_per_run": mean("switches"), "false_positives_per_run": mean("false_positives"),
            "misses_per_run": mean("misses"), "objects_per_run": mean("objects"),
            "empty_frame_reports": int(sum(r["empty_frame_reports"] for r in rows)),
            "frames_without": int(sum(r["frames_without"] for r in rows)),
            "ms_per_frame": mean("ms"), "mean_ess": mean("ess")}
