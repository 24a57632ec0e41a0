"""The files ``vistrack eval --targets K`` writes: ``results.json``, ``results.csv`` and ``report.md``
with the CLEAR-MOT and identity scores (:mod:`vistrack.scoring.mot`) per clip × algorithm × N and averaged
over clips."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

from ..batch.tasks import write_atomic
from ..scoring.mot import pool_scores

__all__ = ["MOT_CSV_COLUMNS", "write_mot_outputs"]

#: ``results.csv``: one row per task
MOT_CSV_COLUMNS = ["clip", "algo", "particles", "run", "mota", "idf1", "motp", "switches", "false_positives", "misses",
                   "objects", "empty_frame_reports", "frames_without", "ms", "ess"]


def _groups(rows, key):
    out = {}
    for r in rows:
        out.setdefault(key(r), []).append(r)
    return out


def _table(groups):
    """A markdown table: one row per ``(algo, N) -> pooled scores``."""

    def fmt(v, f):
        return "–" if v is None else format(v, f)

    lines = ["| algo | N | runs | MOTA | IDF1 | MOTP (px) | switches / run | false positives / run | misses / run | "
             "plates reported in frames without one | ms/frame |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for (algo, n), s in groups.items():
        lines.append(f"| {algo} | {n} | {s['runs']} | {fmt(s['mota'], '.3f')} | {fmt(s['idf1'], '.3f')} | "
                     f"{fmt(s['motp'], '.2f')} | {fmt(s['switches_per_run'], '.2f')} | "
                     f"{fmt(s['false_positives_per_run'], '.1f')} | {fmt(s['misses_per_run'], '.1f')} | "
                     f"{s['empty_frame_reports']} (in {s['frames_without']} frames) | "
                     f"{fmt(s['ms_per_frame'], '.1f')} |")
    return "\n".join(lines)


def write_mot_outputs(out, cfg, rows, targets, chosen=None):
    """Write ``results.json`` (the pooled scores per algorithm and N, over all clips and per clip),
    ``results.csv`` (``rows``: one per task, :data:`MOT_CSV_COLUMNS`) and ``report.md`` into ``out``."""

    out = Path(out)
    overall = {k: pool_scores(v) for k, v in _groups(rows, lambda r: (r["algo"], r["particles"])).items()}
    per_clip = {c: {k: pool_scores(v) for k, v in _groups(rs, lambda r: (r["algo"], r["particles"])).items()}
                for c, rs in _groups(rows, lambda r: r["clip"]).items()}
    summaries = [{"clip": None, "algo": a, "particles": n, **s} for (a, n), s in overall.items()]
    summaries += [{"clip": c, "algo": a, "particles": n, **s} for c, g in per_clip.items() for (a, n), s in g.items()]
    write_atomic(out / "results.json", json.dumps(
        {"config": {"clips": [str(c) for c in cfg.clips], "algos": cfg.algos, "particles": cfg.particles,
                    "runs": cfg.runs, "seed": cfg.seed, "model": cfg.model, "targets": targets,
                    "equal_time": chosen}, "results": summaries}, indent=1))
    buf = io.StringIO(newline="")
    w = csv.DictWriter(buf, MOT_CSV_COLUMNS, extrasaction="ignore")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if r[k] is None else f"{r[k]:.4f}" if isinstance(r[k], float) else r[k])
                    for k in MOT_CSV_COLUMNS})
    write_atomic(out / "results.csv", buf.getvalue())
    lines = ["# vistrack eval report (several targets)", "",
             f"{len(cfg.clips)} clip(s) × algorithms {', '.join(cfg.algos)} × N {cfg.particles} × {cfg.runs} run(s), "
             f"seed {cfg.seed}, model {cfg.model} with {targets} slots; scored against each clip's objects.csv.", ""]
    if chosen:
        lines += ["Equal time per frame: N chosen per algorithm: " + ", ".join(f"{a} N={n}" for a, n in chosen.items()),
                  ""]
    lines += ["## Averages over clips", "", _table(overall), "", "## Per clip", ""]
    for clip, g in per_clip.items():
        lines += [f"### {Path(clip).name}", "", _table(g), ""]
    lines += ["A reported plate matches a true one when their summed vertex error is at most a third of the true "
              "plate's height. MOTA = 1 - (misses + false positives + switches) / true plates; IDF1: the F-score of "
              "the detections under the best one-to-one assignment of tracks to true plates; means over runs.", "",
              "Per-task rows: `results.csv`; everything: `results.json`."]
    write_atomic(out / "report.md", "\n".join(lines) + "\n")
    return overall
