"""The files an evaluation writes: ``results.json``, ``results.csv``, plots and ``report.md``."""

from __future__ import annotations

import csv
import html
import io
import json
import re
import warnings
from pathlib import Path

import numpy as np

from ..batch.tasks import write_atomic
from ..registry import BASELINES, get_model_spec, is_baseline
from ..scoring.aggregate import summarize

__all__ = ["CSV_COLUMNS", "task_row", "write_eval_outputs", "averages"]

CSV_COLUMNS = ["clip", "algo", "particles", "run", "frames", "mean_error", "mean_error_all", "p_lost", "success_auc",
               "precision_20px", "frames_per_s", "mean_ess", "reported_lost", "success_auc_lost_empty", "lt_precision",
               "lt_recall", "lt_f"]


def averages(out):
    """The table of averages over clips of the report in folder ``out`` (``report.md``, as
    :func:`write_eval_outputs` and :func:`~vistrack.reports.mot_report.write_mot_outputs` write it): what
    ``eval`` and ``demo`` print."""
    return (Path(out) / "report.md").read_text().split("\n\n## Per clip")[0].split("## Averages over clips\n\n")[-1]


def task_row(r):
    """One ``results.csv`` row of a task result: the numbers ``results.json`` gives this one run
    (:func:`~vistrack.evaluation.experiment.summarize`), so the two files agree — frames where the ground
    truth has no object (OTB/VOT absent frames) count in neither. ``mean_error`` is over the
    frames not lost, ``mean_error_all`` over every frame with the object in view and an estimate;
    empty where there is none."""
    s = summarize([r], not_filters=BASELINES)[0]
    row = {"clip": r["clip"], "algo": r["algo"], "particles": r["particles"], "run": r["run"], "frames": r["frames"]}
    row.update({k: "" if s[k] is None else s[k] for k in CSV_COLUMNS[5:]})
    return row


def _normalised(curves, points=101):
    """Per-frame curves of clips of different lengths on one time axis ``t / (T - 1)`` in 0..1."""
    x = np.linspace(0.0, 1.0, points)
    return {k: (x, np.interp(x, np.linspace(0.0, 1.0, len(y)), np.asarray(y, float))) for k, y in curves.items()}


def _eval_plots(out, summaries, labels):
    """The evaluation's PNGs in ``out``, curves averaged over the summaries of each label; their paths."""
    from .plots import plot_per_frame, plot_precision, plot_success, plot_vs_n

    same_length = len({len(s["p_lost_per_frame"]) for s in summaries}) == 1

    def avg(key):
        out_ = {}
        for k, ss in labels.items():
            rows = [np.array([np.nan if v is None else v for v in s[key]], float) for s in ss]
            if not same_length:  # each clip on the normalised time axis first
                rows = [_normalised({0: r})[0][1] for r in rows]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                out_[k] = np.nanmean(np.array(rows), axis=0)
        return out_ if same_length else {k: (np.linspace(0, 1, len(v)), v) for k, v in out_.items()}

    xlabel = "frame" if same_length else "time (fraction of each clip: the clips differ in length)"
    plots = [plot_per_frame(avg("error_per_frame"), out / "error_vs_frame.png", xlabel=xlabel,
                            ylabel="mean centre error (px), runs not lost in that frame",
                            title="Tracking error per frame (lost runs left out)"),
             plot_per_frame(avg("p_lost_per_frame"), out / "p_lost_vs_frame.png", xlabel=xlabel, ylabel="P(lost)",
                            title="Probability of losing the object per frame")]
    plots.append(plot_vs_n(summaries, out / "error_vs_n.png", key="mean_error_all",
                           ylabel="mean centre error (px), all frames",
                           title="Mean centre error over all frames (lost ones included) vs N"))
    timed = [s for s in summaries if s["frames_per_s"] is not None]  # result files carry no timing
    if timed:
        plots.append(plot_vs_n(timed, out / "fps_vs_n.png", key="frames_per_s", ylabel="frames/s (filter)"))
    plots.append(plot_success({k: np.mean([s["success_curve"] for s in ss], axis=0) for k, ss in labels.items()},
                              out / "success.png", title="Success plot (IoU), all frames"))
    plots.append(plot_precision({k: np.mean([s["precision_curve"] for s in ss], axis=0) for k, ss in labels.items()},
                                out / "precision.png", title="Precision plot (centre error), all frames"))
    return plots


def _label(s):
    """A tracker's name in tables and plots: ``algo, N=n``, or the name alone without particles."""
    return f"{s['algo']}, N={s['particles']}" if s.get("particle_filter", True) else s["algo"]


def _runs_line(labels):
    """``lis, N=100: 20 runs; opencv-mil: 20 runs (randomised inside OpenCV, not seeded); opencv-kcf: 1 run
    (deterministic)``: the true run count per tracker."""
    parts = []
    for k, ss in labels.items():
        n = sorted({s["runs"] for s in ss})
        runs = "/".join(str(v) for v in n)
        algo = ss[0]["algo"]
        note = (f" ({BASELINES[algo].runs_note})" if is_baseline(algo)
                else " (a result file)" if not ss[0].get("particle_filter", True) else "")
        parts.append(f"{k}: {runs} run{'s' if n != [1] else ''}{note}")
    return "; ".join(parts)


def write_eval_outputs(out, cfg, summaries, results, chosen=None):
    """Write ``results.json``, ``results.csv``, the plots, ``report.md`` and ``report.html`` (with an
    annotated video of one run per tracker in ``videos/``) of an evaluation into ``out`` (each file whole);
    returns the plot paths and the videos' paths."""
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
        labels.setdefault(_label(s), []).append(s)
    plots = _eval_plots(out, summaries, labels)
    head = (f"{len(cfg.clips)} clip(s), model {cfg.model}, seed {cfg.seed}. Runs per clip: {_runs_line(labels)}. "
            "Scores are mean ± standard deviation over runs (per clip; averaged over clips below).")
    lines = ["# vistrack eval report", "", head, ""]
    if chosen:
        lines += ["Equal time per frame: N chosen per algorithm: "
                  + ", ".join(f"{a} N={n}" for a, n in chosen.items()), ""]
    lines += ["## Averages over clips", "", _table(labels, first="algo | N"), "", "## Per clip", ""]
    by_clip = {}
    for s in summaries:
        by_clip.setdefault(s["clip"], {})[_label(s)] = [s]
    for clip, lab in by_clip.items():
        lines += [f"### {Path(clip).name}", "", _table(lab, first="algo | N"), ""]
    lines += [_lost_note(cfg)]
    sources = _sources_note(results)
    if sources:
        lines += ["", sources]
    lines += ["", "Plots:", ""] + [f"![{Path(p).stem}]({Path(p).name})" for p in plots]
    videos = _annotated_videos(out, results)
    lines += ["", "Per-task rows: `results.csv`; everything: `results.json`; the table, plots and "
              + (f"annotated videos ({len(videos)}, one run per tracker on {Path(videos[0][2]).name}) "
                 if videos else "") + "in a browser: `report.html`."]
    write_atomic(out / "report.md", "\n".join(lines) + "\n")
    write_atomic(out / "report.html", _html(head, labels, by_clip, plots, videos,
                                            " ".join(t for t in (_lost_note(cfg), sources) if t)))
    return plots, [path for _, path, _ in videos]


def _sources_note(results):
    """What the report says of the clips given as URLs: for each, the server's version its tasks read
    and how many of them used a cached copy (checked against the server) or downloaded it; ``""``
    without such clips."""
    from ..io.remote import describe_version

    by_url = {}
    for r in results:
        if r.get("source"):
            by_url.setdefault(r["source"]["url"], []).append(r["source"])
    parts = []
    for url, seen in by_url.items():
        cached = sum(bool(s["cached"]) for s in seen)
        parts.append(f"{url} ({describe_version(seen[0]['version'])}): {cached} of {len(seen)} task(s) used a cached "
                     f"copy checked against the server, {len(seen) - cached} downloaded it")
    return ("Clips given as URLs, read as the server had them: " + "; ".join(parts) + ".") if parts else ""


def _annotated_videos(out, results, max_trackers=8, width=480, least=320):
    """Run 0 of each tracker on the first clip drawn over its frames (the true box green, the
    tracker's in its colour) as ``out/videos/<tracker>.mp4`` (H.264, index first), at most ``width``
    pixels wide and at least ``least`` (a small clip enlarged by a whole factor, pixels kept sharp, so
    that a browser's player controls do not cover it); ``[(label, path, clip)]``, empty where the task
    results carry no boxes (written by an older version)."""
    import cv2

    from ..io.clips import load_clip
    from ..io.render import TRUTH, draw_box, draw_label, tracker_colour
    from ..io.video import VideoWriter

    clips = list(dict.fromkeys(r["clip"] for r in results))
    if not clips:
        return []
    first = [r for r in results if r["clip"] == clips[0] and r["run"] == 0 and r.get("boxes")]
    first = list({_label({**r, "particle_filter": not is_baseline(r["algo"]) and not r.get("external")}): r
                  for r in first}.items())[:max_trackers]
    if not first:
        return []
    (out / "videos").mkdir(exist_ok=True)
    clip = load_clip(clips[0])
    truth = np.column_stack([clip.truth["cx"] - clip.truth["w"] / 2, clip.truth["cy"] - clip.truth["h"] / 2,
                             clip.truth["w"], clip.truth["h"]])
    writers = [(label, r, out / "videos" / (re.sub(r"[^A-Za-z0-9_.-]+", "_", label) + ".mp4"), k)
               for k, (label, r) in enumerate(first)]
    opened = {}
    try:
        for i, frame in clip.source:
            if i >= len(truth):
                break
            f = frame if frame.ndim == 3 else cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
            scale = min(1.0, width / f.shape[1]) if f.shape[1] >= least else float(-(-least // f.shape[1]))
            small = f if scale == 1 else cv2.resize(f, None, fx=scale, fy=scale,  # once per frame
                                                     interpolation=cv2.INTER_LINEAR if scale < 1 else cv2.INTER_NEAREST)
            for label, r, path, k in writers:
                img = small.copy()
                draw_box(img, truth[i] * scale, TRUTH)
                b = r["boxes"][i] if i < len(r["boxes"]) else None
                if b is not None:
                    draw_box(img, np.asarray(b, float) * scale, tracker_colour(k))
                draw_label(img, f"{label}  #{i}", org=(4, 14))
                if path not in opened:
                    opened[path] = VideoWriter(path, clip.source.fps or 25.0, (img.shape[1], img.shape[0]),
                                               codec="auto", atomic=True, what="report video")
                opened[path].write(img)
    finally:
        _close_videos(opened.values())
    return [(label, path, clips[0]) for label, _, path, _ in writers if path.exists()]


def _close_videos(writers):
    """Close every writer (each renamed into place when whole); the first error is raised."""
    error = None
    for wr in writers:
        try:
            wr.close()
        except OSError as e:
            error = error or e
    if error is not None:
        raise error


def _html(head, labels, by_clip, plots, videos, lost_note):
    """``report.html``: the tables, the plots and the videos side by side, from this folder alone (no
    server, no network). A small script writes what loaded into ``#media-check`` (images drawn,
    videos' durations)."""
    esc = html.escape

    def table(lab):
        rows = []
        for ss in lab.values():
            cells = _cells(ss)
            rows.append("<tr>" + "".join(f"<td>{esc(c)}</td>" for c in cells) + "</tr>")
        return ("<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in _HEADER) + "</tr>" + "".join(rows)
                + "</table>")

    parts = ["<!doctype html><html><head><meta charset='utf-8'><title>vistrack eval report</title><style>",
             "body{font-family:sans-serif;margin:1.5em;max-width:1400px}table{border-collapse:collapse;margin:.5em 0}"
             "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#f3f3f3}"
             ".grid{display:flex;flex-wrap:wrap;gap:12px}.grid figure{margin:0}video{max-width:480px}"
             "img{max-width:640px}#media-check{color:#888;font-size:80%}</style></head><body>",
             "<h1>vistrack eval report</h1>", f"<p>{esc(head)}</p>", "<h2>Averages over clips</h2>", table(labels)]
    if videos:
        parts.append(f"<h2>One run per tracker on {esc(Path(videos[0][2]).name)}</h2>"
                     "<p>The true box in green, the tracker's in its colour.</p><div class='grid'>")
        for label, path, _ in videos:
            parts.append(f"<figure><video src='videos/{esc(path.name)}' controls muted loop autoplay playsinline "
                         f"preload='auto'></video><figcaption>{esc(label)}</figcaption></figure>")
        parts.append("</div>")
    parts.append("<h2>Plots</h2><div class='grid'>")
    parts += [f"<figure><img src='{esc(Path(p).name)}' alt='{esc(Path(p).stem)}'></figure>" for p in plots]
    parts.append("</div><h2>Per clip</h2>")
    for clip, lab in by_clip.items():
        parts += [f"<h3>{esc(Path(clip).name)}</h3>", table(lab)]
    parts += [f"<p>{esc(lost_note)}</p>", "<pre id='media-check'></pre>", _CHECK_SCRIPT, "</body></html>"]
    return "\n".join(parts) + "\n"


_CHECK_SCRIPT = """<script>
function mediaCheck() {
  const imgs = [...document.images].map(i => i.complete ? i.naturalWidth : 0);
  const vids = [...document.querySelectorAll('video')].map(v => isFinite(v.duration) ? v.duration : 0);
  document.getElementById('media-check').textContent = JSON.stringify({images: imgs, videos: vids});
}
window.addEventListener('load', mediaCheck);
document.querySelectorAll('video').forEach(v => v.addEventListener('loadedmetadata', mediaCheck));
</script>"""

_HEADER = ["algo", "N", "runs", "mean error, all frames (px)", "mean error, not lost (px)", "P(lost)",
           "reported lost", "P(lost) last frame", "success AUC", "AUC, reported lost as empty", "long-term F (Pr / Re)",
           "precision@20px", "frames/s"]


def _mean(ss, key, fmt=".2f"):
    v = [s[key] for s in ss if s.get(key) is not None]
    return f"{np.mean(v):{fmt}}" if v else "–"


def _pm(ss, key, fmt=".3f"):
    """``mean ± sd``: the mean over ``ss`` of ``key`` and of its spread over runs (``key_sd``)."""
    m = np.mean([s[key] for s in ss])
    sd = [s.get(f"{key}_sd") for s in ss]
    if any(v is None for v in sd) or all(s["runs"] < 2 for s in ss):
        return f"{m:{fmt}}"
    return f"{m:{fmt}} ± {np.mean(sd):{fmt}}"


def _cells(ss):
    s0 = ss[0]
    return [s0["algo"], str(s0["particles"]) if s0.get("particle_filter", True) else "–",
            "/".join(str(v) for v in sorted({s["runs"] for s in ss})), _mean(ss, "mean_error_all"),
            _mean(ss, "mean_error"), _pm(ss, "p_lost"), _mean(ss, "reported_lost", ".3f"),
            f"{np.mean([s['p_lost_final'] for s in ss]):.3f}", _pm(ss, "success_auc"),
            _mean(ss, "success_auc_lost_empty", ".3f"), _lt(ss), _pm(ss, "precision_20px"),
            _mean(ss, "frames_per_s", ".0f")]


def _lt(ss):
    """``F (Pr / Re)``: VOT-LT's long-term scores, the mean over the summaries (``–`` where they have none)."""
    if any(s.get("lt_f") is None for s in ss):
        return "–"
    return " ".join([_mean(ss, "lt_f", ".3f"), f"({_mean(ss, 'lt_precision', '.3f')} /",
                     f"{_mean(ss, 'lt_recall', '.3f')})"])


def _table(labels, first):
    """A markdown table: one row per ``label -> [summaries]``, their averages (``±``: over runs)."""
    out = ["| " + first + " | " + " | ".join(_HEADER[2:]) + " |", "|---" * len(_HEADER) + "|"]
    for ss in labels.values():
        out.append("| " + " | ".join(_cells(ss)) + " |")
    return "\n".join(out)


#: what eval counts as lost, by the model's lost rule (:attr:`~vistrack.models.spec.ModelSpec.lost_rule`)
LOST_RULES = {"centre": "centre error above half the larger side of the true box",
              "plate": "plate: no plate reported, or the vertex error above a third of the plate height"}


def _lost_note(cfg):
    rule = LOST_RULES[get_model_spec(cfg.model).lost_rule]
    return (f"Lost: {rule} (thesis reproductions use the thesis's rules: `vistrack reproduce`). Reported lost: the "
            "share of the frames with the object that the tracker reported lost (vistrack's `visible=0`, an OpenCV "
            "tracker's failed `update`). Long-term F: VOT-LT's tracking F-score (precision over the frames the tracker "
            "reports, recall over the frames with the object, at the confidence threshold that maximises F; at the "
            "tracker's own threshold where it gives no confidence).")
