"""License-plate tracking experiment (thesis 001, §4.5.3, Figs. 4.15–4.16) on synthetic road clips.

Every (clip, algorithm, N, run) is one task of the evaluation engine
(:mod:`vistrack.evaluation.experiment`): the tracker starts with no box — plates are
acquired through the entering-car component — and the task records per
frame whether a plate is reported (``Plate.visible``), the reported
vertices and the time spent. Run ``r`` on clip ``c`` uses
``SeedSequence(seed).spawn(clips)[c].spawn(runs)[r]`` for every algorithm.

Measures (docs/architecture.md): on frames with a plate, the vertex error is the sum of
the distances of the four vertices; the tracker is lost when it reports no
plate or the vertex error exceeds one third of the true plate height.
P(lost) per frame is the fraction of runs lost; the mean vertex error is over
plate frames not lost. A false report is a frame without a plate in which a
plate is reported. Acquisition delay: frames from a plate's first fully
visible frame to the first frame the tracker is not lost on it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from ..batch.tasks import load_task_results, save_result
from ..core.particles import DegenerateWeightsWarning
from ..evaluation.experiment import entries_config
from ..io.clips import load_clip
from ..loop.stepper import Stepper
from ..registry import build_model, make_filter
from ..registry.comparisons import PLATE
from ..scoring.metrics import plate_frame_measures
from ..system.resources import prepare_worker
from .contour import ContourConfig

__all__ = ["PlateConfig", "run_plate_task", "plate_results"]


@dataclass
class PlateConfig(ContourConfig):
    """The plate experiment (§4.5.3): ``runs`` per clip and ``(algo, N)`` entry, root ``seed``
    (:class:`~vistrack.reproduce.contour.ContourConfig`), and ``acquire_within``: a plate counts
    as acquired in time when the tracker is on it within this many frames."""

    entries: list = field(default_factory=lambda: list(PLATE))
    runs: int = 20
    acquire_within: int = 10

    table = "plate"
    #: the folder of its task files when ``--out`` is not given
    results_dir = "plate-results"
    model = "plate"

    @property
    def runner(self):
        """:func:`run_plate_task`."""
        return run_plate_task

    def results(self, tasks, out_dir):
        """``{"config", "results"}``: :func:`plate_results`."""
        return {"config": entries_config(self), "results": plate_results(self, tasks, out_dir)}


def run_plate_task(task, out_dir):
    """Engine runner: track one plate clip once (no initial box); write the per-frame record."""
    prepare_worker()
    clip = load_clip(task["clip"])
    model = build_model(task["model"], clip)
    filt = make_filter(task["algo"], model)
    rng = np.random.default_rng(task["seed_seq"])
    reported, verts, ms, ess, ll = [], [], [], [], []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DegenerateWeightsWarning)
        for res in Stepper(filt, task["particles"], rng).steps(clip.source):
            reported.append(int(res.visible))
            ll.append(round(float(model.loglik(res.obs, res.estimate[None])[0]), 3))
            verts.append(np.round(model.vertices(res.estimate)[0].ravel(), 3).tolist())
            ms.append(round(res.ms, 4))
            ess.append(round(res.ess, 3))
    result = {"clip": task["clip"], "algo": task["algo"], "particles": task["particles"], "run": task["run"],
              "reported": reported, "vertices": verts, "loglik": ll, "ms": ms, "ess": ess}
    return save_result(out_dir, task, result)


def _acquisition_delays(has, lost, ids):
    """Delay (frames) from each plate appearance's first full frame to the first frame not lost;
    ``None`` when never acquired during the appearance."""
    out, t, m = [], 0, len(has)
    while t < m:
        if not has[t]:
            t += 1
            continue
        start, cid = t, ids[t]
        while t < m and has[t] and ids[t] == cid:
            t += 1
        ok = np.flatnonzero(~lost[start:t])
        out.append(int(ok[0]) if len(ok) else None)
    return out


def plate_results(cfg, tasks, out_dir):
    """Pooled results per (algo, N), in the order of the entries, plus per-frame curves."""
    truths, aspects = {}, {}
    by_entry = {}
    for t, r in zip(tasks, load_task_results(tasks, out_dir)):
        if t["clip"] not in truths:
            clip = load_clip(t["clip"])
            truths[t["clip"]] = clip.truth
            aspects[t["clip"]] = float((clip.meta or {}).get("aspect", 2.0))
        by_entry.setdefault((t["algo"], t["particles"]), []).append((t["clip"], r))
    results = []
    for (algo, n), rows in by_entry.items():
        lost_frames, errs, false_reports, delays, ms, ess, n_runs = [], [], 0, [], [], [], 0
        lost_curve = {}
        for clip, r in rows:
            truth = truths[clip]
            has, err, lost, false = plate_frame_measures(r, truth, aspects[clip])
            lost_frames.append(lost[has])
            errs.append(err[has & ~lost])
            false_reports += int(false.sum())
            delays += _acquisition_delays(has, lost, np.asarray(truth["id"][:len(has)]))
            ms.append(np.mean(r["ms"]))
            ess += r["ess"]
            lost_curve.setdefault(clip, []).append(np.where(has, lost, np.nan))
            n_runs += 1
        lost_all = np.concatenate(lost_frames)
        err_all = np.concatenate(errs)
        acquired = [d for d in delays if d is not None]
        curve = None
        if len({len(v[0]) for v in lost_curve.values()}) == 1:  # clips of one length: P(lost) per frame
            a = np.concatenate([np.array(v) for v in lost_curve.values()])
            has_plate = np.sum(~np.isnan(a), axis=0)
            curve = np.where(has_plate > 0, np.nansum(a, axis=0) / np.maximum(has_plate, 1), np.nan)
        results.append({
            "algo": algo, "particles": int(n), "runs": n_runs, "clips": len(lost_curve),
            "p_lost": float(lost_all.mean()) if len(lost_all) else 0.0,
            "mean_vertex_error": float(err_all.mean()) if len(err_all) else None,
            "false_reports": false_reports,
            "false_reports_per_run": false_reports / max(n_runs, 1),
            "appearances": len(delays),
            "acquired_within": float(np.mean([d is not None and d <= cfg.acquire_within for d in delays]))
            if delays else None,
            "never_acquired": sum(d is None for d in delays),
            "mean_acquisition_delay": float(np.mean(acquired)) if acquired else None,
            "max_acquisition_delay": int(max(acquired)) if acquired else None,
            "ms_per_frame": float(np.mean(ms)), "frames_per_s": float(1e3 / np.mean(ms)),
            "mean_ess": float(np.mean(ess)),
            "p_lost_per_frame": None if curve is None else [None if np.isnan(v) else float(v) for v in curve],
        })
    return results

