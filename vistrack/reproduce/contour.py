"""Contour tracking experiment (thesis 001, §4.3.2, Table 4.1) on synthetic clips.

Every (clip, algorithm, N, run) is one task: track the whole clip from the
first frame's ground truth, record the centre error per frame and the time
spent per frame. Runs get independent streams ``SeedSequence(seed).spawn``
per (clip, run), shared by all algorithms (common random numbers), so results
do not depend on the order or the number of worker processes.
"""

from __future__ import annotations

import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field

import numpy as np

from ..builders import build_model
from ..clips import load_clip
from ..filters import make_filter
from ..metrics import center_error, contour_lost_threshold, summarize_runs
from ..tracking import track

__all__ = ["ContourConfig", "run_contour_task", "run_contour"]


@dataclass
class ContourConfig:
    clips: list
    entries: list = field(default_factory=lambda: [("ls-n-ips", 30), ("bootstrap", 2000)])
    runs: int = 10
    seed: int = 0
    workers: int = 0  # 0: one per core


_FRAMES = {}


def _frames(path):
    if path not in _FRAMES:
        _FRAMES.clear()
        clip = load_clip(path)
        _FRAMES[path] = (clip, list(clip.source))
    return _FRAMES[path]


def run_contour_task(path, algo, n, seed_seq):
    """Track clip ``path`` once; returns ``(errors (T,), ms (T,), ess (T,))``."""
    clip, frames = _frames(path)
    model = build_model("contour", clip, init_gt="")
    filt = make_filter(algo, model)
    rng = np.random.default_rng(seed_seq)
    t = clip.truth
    err, ms, ess = [], [], []
    for res in track(frames, filt, n, rng):
        k = res.index
        err.append(float(center_error(res.estimate[0], res.estimate[1], t["cx"][k], t["cy"][k])))
        ms.append(res.ms)
        ess.append(res.ess)
    return np.array(err), np.array(ms), np.array(ess)


def _task(args):
    ci, path, algo, n, r, ss = args
    t0 = time.perf_counter()
    err, ms, ess = run_contour_task(path, algo, n, ss)
    return ci, algo, n, r, err, ms, ess, time.perf_counter() - t0


def run_contour(cfg, progress=None):
    """Run the grid; returns a list of result dicts (one per clip set × entry) and per-clip details."""
    clips = [str(c) for c in cfg.clips]
    streams = np.random.SeedSequence(cfg.seed).spawn(len(clips))
    tasks = []
    for ci, path in enumerate(clips):
        run_seqs = streams[ci].spawn(cfg.runs)
        for algo, n in cfg.entries:
            for r in range(cfg.runs):
                tasks.append((ci, path, algo, n, r, run_seqs[r]))
    widths = {ci: load_clip(p).source.size[0] for ci, p in enumerate(clips)}
    out = {}
    workers = cfg.workers or os.cpu_count() or 1
    if workers == 1:
        results = map(_task, tasks)
        for res in results:
            _collect(out, res)
            if progress:
                progress(1)
    else:
        with ProcessPoolExecutor(workers) as ex:
            futs = [ex.submit(_task, t) for t in tasks]
            for f in as_completed(futs):
                _collect(out, f.result())
                if progress:
                    progress(1)
    summary = []
    for algo, n in cfg.entries:
        errs, losts, ms, ess = [], [], [], []
        for ci in range(len(clips)):
            for r in range(cfg.runs):
                e, m, s = out[(ci, algo, n, r)]
                errs.append(e)
                losts.append(e > contour_lost_threshold(widths[ci]))
                ms.append(m)
                ess.append(s)
        s = summarize_runs(np.array(errs), np.array(losts))
        mean_ms = float(np.mean([m.mean() for m in ms]))
        summary.append({
            "algo": algo, "particles": n, "clips": len(clips), "runs": cfg.runs,
            "p_lost_final": s["p_lost_final"], "p_lost_mean": s["p_lost_mean"], "mean_error": s["mean_error"],
            "ms_per_frame": mean_ms, "frames_per_s": 1e3 / mean_ms, "mean_ess": float(np.mean([x.mean() for x in ess])),
            "p_lost_per_frame": s["p_lost_per_frame"].tolist(), "error_per_frame": s["error_per_frame"].tolist(),
        })
    return summary


def _collect(out, res):
    ci, algo, n, r, err, ms, ess, _ = res
    out[(ci, algo, n, r)] = (err, ms, ess)


def config_dict(cfg):
    d = asdict(cfg)
    d["clips"] = [str(c) for c in cfg.clips]
    return d
