"""Several targets at once: one task tracks a clip with ``targets`` plate slots (the multi-plate model,
:class:`~vistrack.models.plate.plates.Plates`, thesis 001 App. C with §4.5.3), with no initial box —
plates are acquired by the slots' births — and records per frame the reported plates with their ids
(:class:`~vistrack.scoring.mot.Identities`), the time spent and the ESS; its scores per run against the
clip's ``objects.csv`` (:func:`vistrack.scoring.mot.clear_mot`): MOTA, IDF1, identity switches, false
positives, misses, and the plates reported in frames without any plate in view.

``eval --targets`` and ``reproduce plate --overlap`` (:mod:`vistrack.reproduce.multi_plate`) run these tasks.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..batch.tasks import load_task_results, save_result
from ..core.particles import DegenerateWeightsWarning
from ..io.clips import load_clip
from ..loop.stepper import Stepper
from ..registry import build_model, make_filter, targets_model
from ..scoring.metrics import best_ms, equal_time
from ..scoring.mot import FrameObjects, clear_mot, objects_by_frame
from ..system.resources import prepare_worker

__all__ = ["track_plates", "run_plates_task", "record_objects", "score_plates_tasks", "plates_equal_time"]


def track_plates(clip, algo, n, targets, rng, frames=None):
    """Track ``clip`` with ``targets`` plate slots by ``algo`` with ``n`` particles; yields per frame
    ``(FrameResult, ids (M,), vertices (M, 4, 2), scale (M,))`` of the reported plates."""
    model = build_model(targets_model(), clip, targets=targets)
    filt = make_filter(algo, model)
    source = clip.source if frames is None else frames
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DegenerateWeightsWarning)
        for res in Stepper(filt, n, rng).steps(source):
            ids, states = res.targets
            yield res, ids, model.target_outline(states), states[:, 3]


def run_plates_task(task, out_dir):
    """Engine runner: track one clip once with the task's ``targets`` slots; write the per-frame record
    (the reported plates' ids, vertices and scales, ms and ESS)."""
    prepare_worker()
    clip = load_clip(task["clip"])
    rng = np.random.default_rng(task["seed_seq"])
    ids, verts, scale, ms, ess = [], [], [], [], []
    for res, i, v, s in track_plates(clip, task["algo"], task["particles"], task["targets"], rng):
        ids.append(i.tolist())
        verts.append(np.round(v, 3).tolist())
        scale.append(np.round(s, 3).tolist())
        ms.append(round(res.ms, 4))
        ess.append(round(res.ess, 3))
    result = {"clip": task["clip"], "algo": task["algo"], "particles": task["particles"], "run": task["run"],
              "targets": task["targets"], "ids": ids, "vertices": verts, "scale": scale, "ms": ms, "ess": ess}
    return save_result(out_dir, task, result)


def record_objects(result):
    """The reported plates of a task record as :class:`~vistrack.scoring.mot.FrameObjects`, one per frame."""
    return [FrameObjects(np.asarray(i, int), np.asarray(v, float).reshape(-1, 4, 2), np.asarray(s, float))
            for i, v, s in zip(result["ids"], result["vertices"], result["scale"])]


def score_plates_tasks(tasks, out_dir):
    """One row per task: ``clip, algo, particles, run``, the scores of :func:`~vistrack.scoring.mot.clear_mot`
    against the clip's ``objects.csv``, its ``ms`` per frame and mean ``ess``. A clip without
    ``objects.csv`` is a ``ValueError``."""
    truths, aspects, rows = {}, {}, []
    for t, r in zip(tasks, load_task_results(tasks, out_dir)):
        if t["clip"] not in truths:
            clip = load_clip(t["clip"])
            if clip.objects is None:
                raise ValueError(f"{t['clip']} has no objects.csv (the per-plate ground truth of synth plate)")
            truths[t["clip"]] = objects_by_frame(clip.objects, len(r["ids"]))
            aspects[t["clip"]] = float((clip.meta or {}).get("aspect", 2.0))
        s = clear_mot(truths[t["clip"]], record_objects(r), aspects[t["clip"]])
        rows.append({"clip": t["clip"], "algo": t["algo"], "particles": int(t["particles"]), "run": t["run"], **s,
                     "ms": float(np.mean(r["ms"])), "ess": float(np.mean(r["ess"]))})
    return rows


def plates_equal_time(clip_path, entries, targets, frames=60):
    """``entries`` with every N after the first set so that its time per frame matches the first
    entry's (:func:`~vistrack.scoring.metrics.equal_time`, a line through N and 2N), timed on ``frames``
    frames of ``clip_path`` from a quarter of the way in, where plates are in view (the first frames
    have none, and a partitioned LIS step costs more with plates to track: timed on the first 60
    frames of the first clip, bootstrap's N came out at 1.8× the time per frame over the whole runs).
    Returns ``(entries, {"algo:N": ms per frame})`` with the times at N and 2N."""
    clip = load_clip(clip_path)
    start = (clip.source.frame_count or 0) // 4
    fr = [(i, f) for i, f in clip.source if start <= i < start + frames]

    def ms(algo, n):
        def run():
            for _ in track_plates(clip, algo, n, targets, np.random.default_rng(0), fr):
                pass

        return best_ms(run) / len(fr)

    return equal_time(ms, entries, doubled=True)
