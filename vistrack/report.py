"""The files an evaluation writes: ``results.json``, ``results.csv``, plots and ``report.md``."""

from __future__ import annotations

import csv
import io
import json
import warnings
from pathlib import Path

import numpy as np

from .evaluation import write_atomic

__all__ = ["CSV_COLUMNS", "task_row", "write_eval_outputs"]

CSV_COLUMNS = ["clip", "algo", "particles", "run", "frames", "mean_error", "mean_error_all", "p_lost", "success_auc",
               "precision_20px", "frames_per_s", "mean_ess"]


def task_row(r):
    """One ``results.csv`` row of a task result: the numbers ``results.json`` gives this one run
    (:func:`~vistrack.evaluation.summarize`), so the two files agree — frames where the ground
    truth has no object (OTB/VOT absent frames) count in neither. ``mean_error`` is over the
    frames not lost, ``mean_error_all`` over every frame with the object in view and an estimate;
    empty where there is none."""
    from .evaluation import summarize

    s = summarize([r])[0]
    row = {"clip": r["clip"], "algo": r["algo"], "particles": r["particles"], "run": r["run"], "frames": r["frames"]}
    row.update({k: "" if s[k] is None else s[k] for k in CSV_COLUMNS[5:]})
    return row


def _eval_plots(out, summaries, labels):
    """The evaluation's PNGs in ``out``, curves averaged over the summaries of each label; their paths."""
    from .plots import plot_per_frame, plot_precision, plot_success, plot_vs_n

    def avg(key):
        out_ = {}
        for k, ss in labels.items():
            arr = np.array([[np.nan if v is None else v for v in s[key]] for s in ss], float)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                out_[k] = np.nanmean(arr, axis=0)
        return out_

    plots = []
    if len({len(s["p_lost_per_frame"]) for s in summaries}) == 1:  # per-frame curves need equal lengths
        plots.append(plot_per_frame(avg("error_per_frame"), out / "error_vs_frame.png",
                                    ylabel="mean centre error (px), runs not lost", title="Tracking error per frame"))
        plots.append(plot_per_frame(avg("p_lost_per_frame"), out / "p_lost_vs_frame.png", ylabel="P(lost)",
                                    title="Probability of losing the object per frame"))
    plots.append(plot_vs_n(summaries, out / "error_vs_n.png", key="mean_error", ylabel="mean centre error (px)"))
    timed = [s for s in summaries if s["frames_per_s"] is not None]  # result files carry no timing
    if timed:
        plots.append(plot_vs_n(timed, out / "fps_vs_n.png", key="frames_per_s", ylabel="frames/s (filter)"))
    plots.append(plot_success({k: np.mean([s["success_curve"] for s in ss], axis=0) for k, ss in labels.items()},
                              out / "success.png"))
    plots.append(plot_precision({k: np.mean([s["precision_curve"] for s in ss], axis=0) for k, ss in labels.items()},
                                out / "precision.png"))
    return plots


def write_eval_outputs(out, cfg, summaries, results, chosen=None):
    """Write ``results.json``, ``results.csv``, the plots and ``report.md`` of an evaluation into
    ``out`` (each file whole); returns the plot paths."""
    rows = [task_row(r) for r in results]
    write_atomic(out / "results.json", json.dumps(
        {"config": {"clips": [str(c) for c in cfg.clips], "algos": cfg.algos, "particles": cfg.particles,
                    "runs": cfg.runs, "seed": cfg.seed, "model": cfg.model, "equal_time": chosen},
         "results": summaries}, indent=1))
    buf = io.StringIO(newline="")
    w = csv.DictWriter(buf, CSV_COLUMNS)
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in r.items()})
    write_atomic(out / "results.csv", buf.getvalue())
    labels = {}
    for s in summaries:
        labels.setdefault(f"{s['algo']}, N={s['particles']}", []).append(s)
    plots = _eval_plots(out, summaries, labels)
    lines = ["# vistrack eval report", "",
             f"{len(cfg.clips)} clip(s) × algorithms {', '.join(cfg.algos)} × N {cfg.particles} × {cfg.runs} run(s), "
             f"seed {cfg.seed}, model {cfg.model}.", ""]
    if chosen:
        lines += ["Equal time per frame: N chosen per algorithm: "
                  + ", ".join(f"{a} N={n}" for a, n in chosen.items()), ""]
    lines += ["## Averages over clips", "", _table(labels, first="algo | N"), "", "## Per clip", ""]
    by_clip = {}
    for s in summaries:
        by_clip.setdefault(s["clip"], {})[f"{s['algo']}, N={s['particles']}"] = [s]
    for clip, lab in by_clip.items():
        lines += [f"### {Path(clip).name}", "", _table(lab, first="algo | N"), ""]
    lines += [_lost_note(cfg)]
    lines += ["", "Plots:", ""] + [f"![{Path(p).stem}]({Path(p).name})" for p in plots]
    lines += ["", "Per-task rows: `results.csv`; everything: `results.json`."]
    write_atomic(out / "report.md", "\n".join(lines) + "\n")
    return plots


def _mean(ss, key, fmt=".2f"):
    v = [s[key] for s in ss if s.get(key) is not None]
    return f"{np.mean(v):{fmt}}" if v else "–"


def _table(labels, first):
    """A markdown table: one row per ``label -> [summaries]``, their averages."""
    out = [f"| {first} | mean error, all frames (px) | mean error, not lost (px) | P(lost) | P(lost) last frame | "
           "success AUC | precision@20px | frames/s |", "|---|---|---|---|---|---|---|---|---|"]
    for ss in labels.values():
        out.append(f"| {ss[0]['algo']} | {ss[0]['particles']} | {_mean(ss, 'mean_error_all')} | "
                   f"{_mean(ss, 'mean_error')} | "
                   f"{np.mean([s['p_lost'] for s in ss]):.3f} | {np.mean([s['p_lost_final'] for s in ss]):.3f} | "
                   f"{np.mean([s['success_auc'] for s in ss]):.3f} | "
                   f"{np.mean([s['precision_20px'] for s in ss]):.3f} | "
                   f"{_mean(ss, 'frames_per_s', '.0f')} |")
    return "\n".join(out)


def _lost_note(cfg):
    rule = ("plate: no plate reported, or the vertex error above a third of the plate height" if cfg.model == "plate"
            else "centre error above half the larger side of the true box")
    return f"Lost: {rule} (thesis reproductions use the thesis's rules: `vistrack reproduce`)."
