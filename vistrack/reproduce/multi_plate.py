"""Several plates at once (thesis 001 §4.5.3 with App. C's partitioned sampling) on synthetic road
clips with up to three plates in view (``make_plate_clip(overlap=True)``).

Every (clip, algorithm, N, run) is one task of the evaluation engine (:mod:`vistrack.engine.evaluation`):
the multi-plate model (:class:`~vistrack.models.plate.plates.Plates`, ``targets`` slots) tracks the clip
with no initial box — plates are acquired by the slots' births — and the task records per frame
the reported plates with their ids (:class:`~vistrack.core.mot.Identities`), the time spent and the
ESS. Run ``r`` on clip ``c`` uses ``SeedSequence(seed).spawn(clips)[c].spawn(runs)[r]`` for every
algorithm. Scores per run against the clip's ``objects.csv`` (:func:`vistrack.core.mot.clear_mot`):
MOTA, IDF1, identity switches, false positives, misses, and the plates reported in frames
without any plate in view.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.metrics import equal_time_n
from ..core.mot import FrameObjects, clear_mot, objects_by_frame, pool_scores
from ..core.particles import DegenerateWeightsWarning
from ..engine.evaluation import entry_tasks, prepare_worker, write_task_result
from ..filters import make_filter
from ..io.clips import load_clip
from ..registry.builders import build_model
from ..track.loop import track
from .contour import ContourConfig

__all__ = ["PlatesConfig", "plates_tasks", "run_plates_task", "score_plates_tasks", "plates_results",
           "plates_equal_time"]


@dataclass
class PlatesConfig(ContourConfig):
    """The several-plates experiment: ``runs`` per clip and ``(algo, N)`` entry, root ``seed``
    (:class:`~vistrack.reproduce.contour.ContourConfig`) and the number of plate slots ``targets``."""

    entries: list = field(default_factory=lambda: [("partitioned-lis", 100), ("bootstrap", 2000)])
    runs: int = 10
    targets: int = 3


def plates_tasks(cfg):
    """The experiment's tasks (:func:`vistrack.engine.evaluation.entry_tasks`, each with ``targets``)."""
    tasks = entry_tasks(cfg, "plate")
    for t in tasks:
        t["targets"] = int(cfg.targets)
    return tasks


def track_plates(clip, algo, n, targets, rng, frames=None):
    """Track ``clip`` with ``targets`` plate slots by ``algo`` with ``n`` particles; yields per frame
    ``(FrameResult, ids (M,), vertices (M, 4, 2), scale (M,))`` of the reported plates."""
    model = build_model("plate", clip, targets=targets)
    filt = make_filter(algo, model)
    source = clip.source if frames is None else frames
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DegenerateWeightsWarning)
        for res in track(source, filt, n, rng):
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
    return write_task_result(Path(out_dir) / "tasks" / f"{task['name']}.json", result, task)


def record_objects(result):
    """The reported plates of a task record as :class:`~vistrack.core.mot.FrameObjects`, one per frame."""
    return [FrameObjects(np.asarray(i, int), np.asarray(v, float).reshape(-1, 4, 2), np.asarray(s, float))
            for i, v, s in zip(result["ids"], result["vertices"], result["scale"])]


def score_plates_tasks(tasks, out_dir):
    """One row per task: ``clip, algo, particles, run``, the scores of :func:`~vistrack.core.mot.clear_mot`
    against the clip's ``objects.csv``, its ``ms`` per frame and mean ``ess``. A clip without
    ``objects.csv`` is a ``ValueError``."""
    truths, aspects, rows = {}, {}, []
    for t in tasks:
        r = json.loads((Path(out_dir) / "tasks" / f"{t['name']}.json").read_text())
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


def plates_results(cfg, tasks, out_dir):
    """Per (algo, N), in the order of the entries: :func:`pool_scores` over every clip and run, the
    number of clips, and per clip the mean MOTA and IDF1."""
    by_entry = {}
    for r in score_plates_tasks(tasks, out_dir):
        by_entry.setdefault((r["algo"], r["particles"]), []).append(r)
    out = []
    for (algo, n), rows in by_entry.items():
        per_clip = {}
        for r in rows:
            per_clip.setdefault(Path(r["clip"]).name, []).append(r)
        out.append({"algo": algo, "particles": n, "clips": len(per_clip), **pool_scores(rows),
                    "per_clip": {c: [pool_scores(v)["mota"], pool_scores(v)["idf1"]] for c, v in per_clip.items()}})
    return out


def plates_equal_time(clip_path, entries, targets, frames=60):
    """``entries`` with every N after the first set so that its time per frame matches the first
    entry's, timed on ``frames`` frames of ``clip_path`` from a quarter of the way in, where plates
    are in view (the first frames have none, and a partitioned LIS step costs more with plates to
    track: timed on the first 60 frames of the first clip, bootstrap's N came out at 1.8× the time
    per frame over the whole runs); linear in N between N and 2N. Returns ``(entries, {"algo:N": ms
    per frame})``."""
    import time

    clip = load_clip(clip_path)
    start = (clip.source.frame_count or 0) // 4
    fr = [(i, f) for i, f in clip.source if start <= i < start + frames]

    def ms(algo, n):
        best = np.inf
        for _ in range(2):
            t0 = time.perf_counter()
            for _ in track_plates(clip, algo, n, targets, np.random.default_rng(0), fr):
                pass
            best = min(best, (time.perf_counter() - t0) * 1e3 / len(fr))
        return best

    ref_algo, ref_n = entries[0]
    budget = ms(ref_algo, ref_n)
    out, times = [(ref_algo, ref_n)], {f"{ref_algo}:{ref_n}": budget}
    for algo, n in entries[1:]:
        m, t1, t2 = equal_time_n(lambda k: ms(algo, k), n, budget)
        out.append((algo, m))
        times[f"{algo}:{n}"], times[f"{algo}:{2 * n}"] = t1, t2
    return out, times
