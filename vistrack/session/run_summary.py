"""What ``vistrack run`` prints after a run (:func:`run_report`): how it ended (an interrupt, frames that
failed to decode, a video shorter than its header says), losses, time per stage, the scores against
ground truth (success AUC, precision, centre error; MOTA and IDF1 for several targets) and the files
written."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..loop.profiling import STAGES
from ..registry import get_model_spec
from ..scoring.aggregate import summarize
from ..scoring.metrics import score_frames

__all__ = ["summary_lines", "RunReport", "run_report"]


@dataclass
class RunReport:
    """What a run has to say when it ends (:func:`run_report`).

    Attributes
    ----------
    notes : list of str
        How it ended, for stderr: an interrupt, frames that failed to decode, a video that ended early.
    lines : list of str
        The summary and the files written, for stdout (left out by ``run --quiet``).
    exit_code : int
        0, or the shell's code for the signal that stopped the run (130, 143).
    error : str or None
        The run's one error line where no frame could be decoded.
    """

    notes: list = field(default_factory=list)
    lines: list = field(default_factory=list)
    exit_code: int = 0
    error: str | None = None


def run_report(video, plan, done, particles, outputs):
    """The :class:`RunReport` of ``vistrack run VIDEO`` after :func:`~vistrack.session.plan.execute` of
    ``plan`` with ``particles`` particles returned the :class:`~vistrack.session.recording.SessionLog`
    ``done``; ``outputs`` as given to it (``track_path``, ``out_path``, ``results_path``, ``results_format``,
    ``sequence``)."""
    from ..io.results_format import result_paths

    report, src = RunReport(exit_code=done.exit_code), plan.clip.source
    if not done.rows:
        report.error = None if done.stopped else f"{video}: no frame could be decoded"
        return report
    track, video_out, results = outputs.get("track_path"), outputs.get("out_path"), outputs.get("results_path")
    if results and outputs.get("results_format", "otb") != "otb":
        results = result_paths(results, outputs["results_format"], outputs["sequence"])[0]
    if done.stopped:
        report.notes.append(f"{'Interrupted' if done.stopped == 'interrupt' else 'Terminated'} after {len(done.rows)} "
                            "frames" + (f"; track so far: {track}" if track else "")
                            + (f"; annotated video so far: {video_out}" if video_out else ""))
    if src.skipped:
        report.notes.append(f"{len(src.skipped)} frame(s) failed to decode: " + ", ".join(map(str, src.skipped[:10]))
                            + (", ..." if len(src.skipped) > 10 else "")
                            + " (their rows have visible=0, lost_reason \"decode\"; results 0,0,0,0)")
    if src.ended_at is not None and not done.stopped:
        report.notes.append(f"warning: {video} ended early: decoding stopped at frame {src.ended_at} of the "
                            f"{src.frame_count} its header announces (frames {src.ended_at}-{src.frame_count - 1} "
                            "have no row)")
    report.lines = summary_lines(done, particles, model_name=plan.model_name, model=plan.model, truth=plan.clip.truth,
                                 frame_width=src.size[0], objects=plan.clip.objects)
    report.lines += ([f"track: {track}"] if track else []) + (
        [f"annotated video: {video_out} ({done.video_note or 'H.264'})"] if video_out else []) + (
        [f"results (x,y,w,h): {results}"] if results else [])
    if not (track or video_out or results):
        report.lines.append("nothing written (give --track, --results or --out to keep the track)")
    return report


def summary_lines(run, particles, *, model_name, model, truth, frame_width, objects=None):
    """The summary ``vistrack run`` prints: speed and ESS, then the comparison with ground
    truth when there is one (the model's own, :attr:`~vistrack.models.spec.ModelSpec.summary`: the
    landmark error, the plate's lost frames, vertex error and false reports; else success AUC,
    precision at 20 px and centre error for box-level truth; for several targets, MOTA and IDF1 against
    ``objects``, the columns of the clip's ``objects.csv``)."""
    rows, n = run.rows, len(run.rows)
    ms = np.array([r["ms"] for r in rows if r["ess"] > 0] or [np.nan])  # not the frames searched (lead)
    lines = [f"{n} frames, {n / max(run.wall, 1e-9):.0f} frames/s end to end ({1e3 / ms.mean():.0f} frames/s in "
             f"the filter), mean ESS {run.ess_sum / n:.1f} of {particles}"
             + (f", {run.degenerate} degenerate frames" if run.degenerate else "")]
    split = run.stage_split()
    if split:
        lines.append("ms per frame: " + ", ".join(f"{s} {split[s]:.2f}" for s in (*STAGES, "other"))
                     + f" (total {split['total']:.2f}, drawing and writing included in other)")
    if run.losses:
        lines.append(_lost_line(run))
    if run.target_rows:  # several targets: scored against the clip's objects.csv
        return lines + ([] if objects is None else [_mot_line(run, objects, model)])
    if truth is None:
        return lines
    spec = get_model_spec(model_name)
    own = spec.summary(rows, truth, model) if spec.summary is not None else None
    if own is not None:
        lines.append(own)
    elif "w" in truth and "cx" in truth:
        lines.append(_box_summary(rows, truth, frame_width))
    return lines


def _mot_line(run, objects, model):
    """One line: the CLEAR-MOT and identity scores of the run's target rows against ``objects``."""
    from ..scoring.mot import clear_mot, objects_by_frame

    cols = {k: np.array([r[k] for r in run.target_rows], float) for k in ("frame", "visible", "id", "scale")
            + tuple(f"{c}{i}" for i in range(4) for c in "xy")}
    frames = int(max(r["frame"] for r in run.rows)) + 1
    truth = objects_by_frame(objects)[:frames]
    s = clear_mot(truth, objects_by_frame(cols, len(truth)), model.layout.aspect)

    def fmt(v):
        return "n/a" if v is None else f"{v:.3f}"

    return (f"vs ground truth (objects.csv, {s['objects']} plates over the frames): MOTA {fmt(s['mota'])}, IDF1 "
            f"{fmt(s['idf1'])}, {s['switches']} identity switches, {s['false_positives']} false positives, "
            f"{s['misses']} misses; {s['empty_frame_reports']} plates reported in the {s['frames_without']} frames "
            "without one")


def _lost_line(run):
    """One line: in how many frames the object was not reported, why, and where it was first lost."""
    reasons = {}
    for r in run.rows:
        if r["lost_reason"]:
            reasons[r["lost_reason"]] = reasons.get(r["lost_reason"], 0) + 1
    first, reason, detail = run.losses[0]
    times = f"; lost {len(run.losses)} times" if len(run.losses) > 1 else ""
    return (f"object not reported (visible=0) in {sum(reasons.values())} of {len(run.rows)} frames ("
            + ", ".join(f"{k} {v}" for k, v in reasons.items()) + f"); first lost at frame {first} ({reason}: "
            f"{detail}){times}")


#: a track row's ``lost_reason`` where the filter did not look at the frame: it has no estimate
NO_ESTIMATE = ("decode", "not started", "not found")


def _box_summary(rows, t, frame_width):
    """One line: the track scored as ``eval`` scores a task (:func:`~vistrack.scoring.metrics.score_frames`,
    :func:`~vistrack.scoring.aggregate.summarize`), over the same frames: a frame without an estimate
    (undecodable, searched before the object was found) is a missed frame in both; beside the scores,
    the frames the tracker reported lost (``visible=0``) and those the ground truth says it lost."""
    n_frames = int(max(r["frame"] for r in rows)) + 1
    boxes, shown, conf = np.full((n_frames, 4), np.nan), np.zeros(n_frames, bool), np.full(n_frames, np.nan)
    for r in rows:
        if r["lost_reason"] not in NO_ESTIMATE:
            boxes[r["frame"]] = (r["cx"] - r["w"] / 2, r["cy"] - r["h"] / 2, r["w"], r["h"])
        shown[r["frame"]] = bool(r["visible"])
        if r.get("confidence", "") not in ("", None):
            conf[r["frame"]] = float(r["confidence"])
    scored = score_frames(t, boxes, frame_width, rule="size", shown=shown,
                          confidence=conf if np.isfinite(conf).any() else None)
    s = summarize([{**scored, "clip": "", "algo": "", "particles": 0, "run": 0, "ms": [], "ess": []}])[0]
    vis = np.array(scored["visible"], bool)
    reported = np.array(scored["reported"], bool)
    absent = int((~vis).sum())
    if not vis.size:
        return "vs ground truth: it has no row for the frames tracked, so there is nothing to score"
    if not vis.any():  # no frame to score: a ground truth without rows for these frames, or the object never in view
        return (f"vs ground truth: the object is in none of the {vis.size} frames it covers, so there is no "
                f"success or precision score; reported absent (visible=0) in {int((~reported).sum())} of them")
    missed = int(np.sum(vis & np.array([e is None for e in scored["error"]], bool)))
    lost = vis & np.array(scored["lost"], bool)
    mean_all = "n/a" if s["mean_error_all"] is None else f"{s['mean_error_all']:.2f} px"
    err = np.array([np.inf if e is None else e for e in scored["error"]])
    on = vis & reported & np.isfinite(err)  # tracked: the frames the tracker reported (issue 44), not the truth's rule
    tracked = f"{err[on].mean():.2f} px" if on.any() else "none"
    but = f" but the {missed} without an estimate (undecodable, or searched before it was found)" if missed else ""
    return (f"vs ground truth ({int(vis.sum())} frames with the object): success AUC {s['success_auc']:.3f} "
            f"({s['success_auc_lost_empty']:.3f} with the frames reported lost as empty), precision@20px "
            f"{s['precision_20px']:.3f}, long-term F-score {s['lt_f']:.3f} (precision {s['lt_precision']:.3f}, "
            f"recall {s['lt_recall']:.3f}), mean centre error {mean_all} over all of them{but} ({tracked} over "
            f"the frames reported tracked); reported lost (visible=0) in {int((vis & ~reported).sum())} of them, "
            f"lost by the ground truth (centre error > half the object's larger side, or no estimate) in "
            f"{int(lost.sum())} (both in {int((lost & ~reported).sum())})"
            + (f"; the object absent in {absent} frames, reported absent in {int((~vis & ~reported).sum())}"
               if absent else ""))
