"""What ``vistrack run`` prints after a run: losses, time per stage, and the scores against
ground truth (success AUC, precision, centre error; MOTA and IDF1 for several targets)."""

from __future__ import annotations

import numpy as np

from ..core.metrics import (
    center_error,
    iou,
    landmark_error,
    lost_frames,
    lt_scores,
    plate_frame_measures,
    precision,
    success_auc,
)
from .profiling import STAGES

__all__ = ["summary_lines"]


def summary_lines(run, particles, *, model_name, model, truth, frame_width, objects=None):
    """The summary ``vistrack run`` prints: speed and ESS, then the comparison with ground
    truth when there is one (landmark error; plate lost/vertex error/false reports; success
    AUC, precision at 20 px and centre error for box-level truth; for several targets, MOTA and
    IDF1 against ``objects``, the columns of the clip's ``objects.csv``)."""
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
    if model_name == "landmarks" and "lx0" in truth:
        err = landmark_error(rows, truth, model.k)
        lines.append(f"vs ground truth: mean landmark error {err.mean():.2f} px (per frame: median "
                     f"{np.median(err):.2f}, max {err.max():.2f})")
    elif model_name == "plate" and "x0" in truth:
        rec = {"reported": [r["visible"] for r in rows],
               "vertices": [[r[f"{c}{i}"] for i in range(4) for c in "xy"] for r in rows]}
        has, err, lost, false = plate_frame_measures(rec, truth, model.layout.aspect)
        ok = has & ~lost
        mean = f"{np.nanmean(err[ok]):.2f} px" if ok.any() else "n/a (never tracked)"
        lines.append(f"vs ground truth: plate lost in {int(lost.sum())} of {int(has.sum())} plate frames; mean vertex "
                     f"error {mean} when tracked; {int(false.sum())} frames reported a plate where there was none")
    elif "w" in truth and "cx" in truth:
        lines.append(_box_summary(rows, truth, frame_width))
    return lines


def _mot_line(run, objects, model):
    """One line: the CLEAR-MOT and identity scores of the run's target rows against ``objects``."""
    from ..core.mot import clear_mot, objects_by_frame

    cols = {k: np.array([r[k] for r in run.target_rows], float) for k in ("frame", "visible", "id", "scale")
            + tuple(f"{c}{i}" for i in range(4) for c in "xy")}
    frames = int(max(r["frame"] for r in run.rows)) + 1
    truth = objects_by_frame(objects)[:frames]
    s = clear_mot(truth, objects_by_frame(cols, len(truth)), model.layout.aspect)
    fmt = lambda v: "n/a" if v is None else f"{v:.3f}"  # noqa: E731
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


def _box_summary(rows, t, frame_width):
    """The line against box ground truth: the scores, the centre error over the frames the tracker reported
    (``visible=1``), and the frames it reported lost beside those the ground truth says it lost."""
    k = np.array([r["frame"] for r in rows], int)
    m = int(np.sum(k < len(t["cx"])))
    k = k[:m]
    est = np.array([[rows[i]["cx"], rows[i]["cy"], rows[i]["w"], rows[i]["h"]] for i in range(m)], float)
    reported = np.array([bool(rows[i]["visible"]) for i in range(m)])
    conf = np.array([np.nan if rows[i].get("confidence", "") == "" else rows[i]["confidence"] for i in range(m)],
                    float)
    err = center_error(est[:, 0], est[:, 1], t["cx"][k], t["cy"][k])
    boxes = np.column_stack([est[:, :2] - est[:, 2:] / 2, est[:, 2:]])
    truth = np.column_stack([t["cx"][k] - t["w"][k] / 2, t["cy"][k] - t["h"][k] / 2, t["w"][k], t["h"][k]])
    ious = iou(boxes, truth)
    vis = (t["w"][k] > 0) & (t["h"][k] > 0)
    if "visible" in t:
        vis &= np.asarray(t["visible"][k]) > 0
    searched = np.isnan(err)  # frames searched before the object was found: no estimate, lost
    lost = (lost_frames("size", np.nan_to_num(err), frame_width, truth={"w": t["w"][k], "h": t["h"][k]})
            | searched) & vis
    tracked = f"{err[vis & reported].mean():.2f} px" if (vis & reported).any() else "none"
    n = int(vis.sum())
    mean = f"{err[vis & ~searched].mean():.2f} px" if (vis & ~searched).any() else "n/a"
    lt = lt_scores(boxes, np.where(vis[:, None], truth, 0.0), reported,
                   conf if np.isfinite(conf[1:]).all() and m > 1 else None)
    absent = int((~vis).sum())
    return (f"vs ground truth ({n} frames with the object): success AUC {success_auc(ious[vis]):.3f} "
            f"({success_auc(np.where(reported, ious, 0.0)[vis]):.3f} with the frames reported lost as empty), "
            f"precision@20px {precision(err[vis]):.3f}, long-term F-score {lt['f_score']:.3f} (precision "
            f"{lt['precision']:.3f}, recall {lt['recall']:.3f}), mean centre error {mean} over all of them"
            + (f" but the {int((vis & searched).sum())} searched before it was found" if (vis & searched).any() else "")
            + f" ({tracked} over the frames reported tracked); reported lost (visible=0) in "
            f"{int((vis & ~reported).sum())} of them, lost by the ground truth (centre error > half the object's "
            f"larger side) in {int(lost.sum())} (both in {int((lost & ~reported).sum())})"
            + (f"; the object absent in {absent} frames, reported absent in {int((~vis & ~reported).sum())}"
               if absent else ""))
