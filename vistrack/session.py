"""One tracking run over a video, as ``vistrack run`` does it: the track CSV and the annotated
video written frame by frame, nothing lost on an interrupt, and the summary against ground truth.

Writing whole or not at all: the track CSV goes to ``PATH.part``, one flushed row per frame,
and is renamed to ``PATH`` when the run ends for any reason (done, Ctrl-C, SIGTERM, an
error), so ``PATH`` is always a whole CSV of the frames tracked; a killed process leaves only
the ``.part`` file (whole rows up to the last frame). The annotated video is closed on every
exit path, so the frames so far play.
"""

from __future__ import annotations

import csv
import itertools
import os
import signal
import time
import warnings
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .clips import format_value
from .metrics import center_error, iou, landmark_error, lost_frames, plate_frame_measures, success_auc
from .particles import DegenerateWeightsWarning
from .profiling import STAGES, Timer, profile_stages
from .render import annotate, annotate_targets
from .tracking import top_particles, track, warm_up
from .video import VideoWriter

__all__ = ["TrackCSV", "VideoRun", "track_row", "target_rows", "track_video", "summary_lines", "Terminated", "stop_on_signals"]


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the run is, so that it ends as cleanly as on Ctrl-C."""


@contextmanager
def stop_on_signals():
    """Within the block SIGTERM raises :class:`Terminated` (SIGINT already raises
    ``KeyboardInterrupt``); the previous handler is restored after."""
    def handler(signum, frame):
        raise Terminated()

    try:
        old = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


class TrackCSV:
    """Track rows (dicts) written as they come: header from the first row, one flushed row per
    :meth:`write` to ``path.part``; :meth:`close` renames it to ``path`` (module docstring); a
    device or pipe (``/dev/stdout``) is written directly.
    ``boxes=True``: the OTB / GOT-10k result format instead — ``x,y,w,h`` per frame, no header,
    0-based pixels, ``0,0,0,0`` where the object is not reported (``visible=0``)."""

    def __init__(self, path, boxes=False):
        self.path = Path(path)
        # a device or pipe (/dev/stdout) is written directly: a part file renamed over it would replace it
        self.direct = self.path.exists() and not self.path.is_file()
        self.part = self.path if self.direct else self.path.with_name(self.path.name + ".part")
        self._f = open(self.part, "w", newline="")
        self._w = csv.writer(self._f)
        self.boxes = bool(boxes)
        self.columns = None
        self.rows = 0
        self._done = False

    def write(self, row):
        """Write one track ``row`` (a dict: column -> value; ``visible``, ``cx``, ``cy``, ``w``, ``h`` for the box
        format) and flush it."""
        if self.boxes:
            box = (row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"]) if row["visible"] \
                else (0, 0, 0, 0)
            self._w.writerow([f"{float(v):.2f}" for v in box])
        else:
            if self.columns is None:
                self.columns = list(row)
                self._w.writerow(self.columns)
            self._w.writerow([format_value(row.get(c, "")) for c in self.columns])
        self._f.flush()
        self.rows += 1

    def close(self):
        """Close and rename to :attr:`path` (a run without frames removes the part file); after a
        write error (disk full) the rows written whole so far are kept."""
        if self._done:
            return
        self._done = True
        try:
            self._f.close()
        except OSError:
            pass
        if self.direct:
            return
        if self.rows:
            os.replace(self.part, self.path)
        else:
            self.part.unlink(missing_ok=True)


@dataclass
class VideoRun:
    """What a :func:`track_video` run did."""

    rows: list = field(default_factory=list)
    wall: float = 0.0
    ess_sum: float = 0.0
    degenerate: int = 0
    #: ``None``, or how the run was cut short: ``"interrupt"`` (Ctrl-C) or ``"terminate"`` (SIGTERM)
    stopped: str | None = None
    #: per-stage seconds (:class:`~vistrack.profiling.Timer`) or ``None``
    timer: object = None
    #: why the annotated video is not H.264, or ``None``
    video_note: str | None = None
    #: ``(index, reason, detail)`` of the first frame of every stretch where the object is lost
    losses: list = field(default_factory=list)
    #: a model of several targets: the track rows of every frame and target (:func:`target_rows`)
    target_rows: list = field(default_factory=list)
    _was_lost: bool = False

    def note_lost(self, res, notify=None):
        """Record the frame result ``res`` where a stretch of lost frames starts (and tell ``notify``)."""
        if res.lost_reason and not self._was_lost:
            self.losses.append((res.index, res.lost_reason, res.lost_detail))
            if notify:
                notify(res.index, res.lost_reason, res.lost_detail)
        self._was_lost = bool(res.lost_reason)

    def stage_split(self):
        """``{stage: ms per frame}`` over :data:`~vistrack.profiling.STAGES`, plus ``other`` (the
        rest of the filter step) and ``total`` (wall time per frame); ``None`` without a timer."""
        if self.timer is None or not self.rows:
            return None
        n = len(self.rows)
        out = {s: 1e3 * self.timer.t[s] / n for s in STAGES}
        out["total"] = 1e3 * self.wall / n
        out["other"] = max(0.0, out["total"] - sum(out[s] for s in STAGES))
        return out

    @property
    def exit_code(self):
        """0, or the shell's code for the signal that stopped the run (130 SIGINT, 143 SIGTERM)."""
        return {None: 0, "interrupt": 130, "terminate": 143}[self.stopped]


def track_row(model, res):
    """The track-CSV row of a :class:`~vistrack.tracking.FrameResult`: ``frame, visible``, the
    model's :meth:`describe` columns, ``redetected`` (a model that re-detects a lost object, the box
    model's: 1 on the frame it is re-found), ``ess, ms, lost_reason``."""
    row = {"frame": res.index, "visible": int(res.visible)}
    row.update(model.describe(res.estimate))
    if getattr(model, "redetect", None) is not None:
        row["redetected"] = int(res.redetected)
    row["ess"], row["ms"], row["lost_reason"] = res.ess, res.ms, res.lost_reason
    return row


def target_rows(model, res):
    """The track-CSV rows of a frame of a model of several targets (:class:`~vistrack.mot.MultiTarget`):
    one per reported target, ``frame, visible = 1, id``, the target's :meth:`describe_target`
    columns, ``ess, ms, lost_reason``; one row with ``visible = 0, id = -1``, NaN geometry and the
    frame's ``lost_reason`` when none is reported."""
    ids, states = res.targets
    tail = {"ess": res.ess, "ms": res.ms}
    if not len(ids):
        row = {"frame": res.index, "visible": 0, "id": -1}
        row.update({k: np.nan for k in model.describe_target(np.zeros(states.shape[1]))})
        return [{**row, **tail, "lost_reason": res.lost_reason}]
    return [{"frame": res.index, "visible": 1, "id": int(i), **model.describe_target(x), **tail, "lost_reason": ""}
            for i, x in zip(ids, states)]


def track_video(frames, model, filt, particles, rng, *, track_path=None, out_path=None, results_path=None,
                video_info=None, show_particles=10, label="", progress=None, notify=None, profile=True):
    """Track ``frames`` (iterable of ``(index, frame)``), writing the track CSV and annotated video as
    it goes; stops cleanly on Ctrl-C / SIGTERM (:func:`stop_on_signals`). Returns a :class:`VideoRun`.

    Parameters
    ----------
    frames : iterable of (int, ndarray)
    model, filt : the model and its filter
    particles : int
    rng : numpy.random.Generator
    track_path, out_path, results_path : path or None
        Track CSV (:class:`TrackCSV`), annotated mp4 and OTB/GOT-10k result file (``x,y,w,h``).
    video_info : tuple or None
        ``(fps, (width, height))`` for the annotated video.
    show_particles : int
        Draw this many highest-weight particles.
    label : str
        Text drawn on every annotated frame after the frame number.
    progress : callable or None
        ``progress(ess)`` after every frame (a progress bar).
    notify : callable or None
        ``notify(index, reason, detail)`` on the first frame of every stretch where the
        object is lost (``visible=0``; :mod:`vistrack.models.collapse`).
    profile : bool
        Time the stages (:mod:`vistrack.profiling`) into ``VideoRun.timer``; the tracks are
        the same either way.
    """
    run = VideoRun()
    run.timer = Timer() if profile else None
    frames = _warmed(frames, filt, particles)
    if profile:
        frames = run.timer.timed_iter(frames, "decode")
    writer = VideoWriter(out_path, *video_info, codec="auto") if out_path else None
    run.video_note = writer.note if writer else None
    outs = [TrackCSV(track_path)] if track_path else []
    if results_path:
        outs.append(TrackCSV(results_path, boxes=True))
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings(), (profile_stages(model, filt, run.timer) if profile else nullcontext()):
            warnings.simplefilter("ignore", DegenerateWeightsWarning)
            for res in track(frames, filt, particles, rng):
                _record(run, res, model, outs, writer, show_particles, label, notify)
                if progress:
                    progress(run.rows[-1]["ess"])
    except (KeyboardInterrupt, SystemError) as e:  # Terminated is a KeyboardInterrupt
        run.stopped = _stop_reason(e)
    finally:
        run.wall = time.perf_counter() - t0
        _close_all(outs, writer)
    return run


def _close_all(outs, writer):
    """Close the track files, then the annotated video: a video that fails to close (a full disk
    shows when its last packets are written) must not cost the track."""
    try:
        for o in outs:
            o.close()
    finally:
        if writer:
            writer.close()


def _stop_reason(exc):
    """``"terminate"`` (SIGTERM) or ``"interrupt"`` (Ctrl-C) for the exception that stopped a run;
    re-raises any other. A signal that arrives while a compiled kernel is being called surfaces as
    a ``SystemError`` caused by the handler's exception (numba's dispatcher returns with it set)."""
    cause = exc.__cause__ if isinstance(exc, SystemError) else exc
    if not isinstance(cause, KeyboardInterrupt):
        raise exc
    return "terminate" if isinstance(cause, Terminated) else "interrupt"


def _warmed(frames, filt, particles):
    """``frames`` with the filter's kernels loaded on a blank frame shaped like the first
    (:func:`~vistrack.tracking.warm_up`) before they are taken: start-up, not tracking time."""
    frames = iter(frames)
    first = next(frames, None)
    if first is None:
        return frames
    warm_up(filt, particles, first[1])
    return itertools.chain([first], frames)


def _record(run, res, model, outs, writer, show_particles, label, notify=None):
    """One frame's result into ``run``: its track row (to ``outs``), the loss notice (``notify``)
    and the annotated frame (to ``writer``)."""
    vis = res.visible
    row = track_row(model, res)
    run.note_lost(res, notify)
    run.rows.append(row)
    rows = [row] if res.targets is None else target_rows(model, res)
    if res.targets is not None:
        run.target_rows += rows
    for o in outs:
        for r in rows:
            o.write(r)
    run.ess_sum += row["ess"]
    run.degenerate += bool(res.particles.degenerate)
    if writer:
        text = f"#{res.index}  {label}  ESS {row['ess']:.1f}"
        particles = model.outline(top_particles(res.particles, show_particles))
        if res.targets is None:
            img = annotate(res.frame, model.outline(res.estimate) if vis else [], particles, text)
        else:
            ids, states = res.targets
            img = annotate_targets(res.frame, ids, model.target_outline(states), particles, text)
        writer.write(img)


def summary_lines(run, particles, *, model_name, model, truth, frame_width, objects=None):
    """The summary ``vistrack run`` prints: speed and ESS, then the comparison with ground
    truth when there is one (landmark error; plate lost/vertex error/false reports; success
    AUC, precision at 20 px and centre error for box-level truth; for several targets, MOTA and
    IDF1 against ``objects``, the columns of the clip's ``objects.csv``)."""
    rows, n = run.rows, len(run.rows)
    ms = np.array([r["ms"] for r in rows])
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
    from .mot import clear_mot, objects_by_frame

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
    k = np.array([r["frame"] for r in rows], int)
    m = int(np.sum(k < len(t["cx"])))
    k = k[:m]
    est = np.array([[rows[i]["cx"], rows[i]["cy"], rows[i]["w"], rows[i]["h"]] for i in range(m)], float)
    err = center_error(est[:, 0], est[:, 1], t["cx"][k], t["cy"][k])
    ious = iou(np.column_stack([est[:, :2] - est[:, 2:] / 2, est[:, 2:]]),
               np.column_stack([t["cx"][k] - t["w"][k] / 2, t["cy"][k] - t["h"][k] / 2, t["w"][k], t["h"][k]]))
    vis = (t["w"][k] > 0) & (t["h"][k] > 0)
    lost = lost_frames("size", err, frame_width, truth={"w": t["w"][k], "h": t["h"][k]}) & vis
    tracked = f"{err[vis & ~lost].mean():.2f} px" if (vis & ~lost).any() else "none"
    n = int(vis.sum())
    return (f"vs ground truth ({n} frames with the object): success AUC {success_auc(ious[vis]):.3f}, precision@20px "
            f"{np.mean(err[vis] <= 20):.3f}, mean centre error {err[vis].mean():.2f} px over all of them "
            f"({tracked} over tracked frames); lost (centre error > half the object's larger side) in "
            f"{int(lost.sum())} frames")
