"""One tracking run over a video, as ``vistrack run`` does it: the track CSV and the annotated
video written frame by frame, nothing lost on an interrupt, and the summary against ground truth.

Writing whole or not at all: the track CSV goes to a temporary name of its own beside ``PATH``
(``PATH.part``, or ``PATH.<pid>-<k>.part`` when that is taken; :mod:`vistrack.io.outputs`), one
flushed row per frame, under a lock that a second run given the same ``PATH`` refuses,
and is renamed to ``PATH`` when the run ends for any reason (done, Ctrl-C, SIGTERM, an
error), so ``PATH`` is always a whole CSV of the frames tracked; a killed process leaves only
the ``.part`` file (whole rows up to the last frame). The annotated video is closed on every
exit path, so the frames so far play.

Every frame of the input is accounted for: a frame that failed to decode (an index missing
from the frames) gets a row with ``visible=0`` and ``lost_reason`` ``"decode"`` (the
filter's state carried over, ``ms`` 0), a ``0,0,0,0`` results line and a blank annotated
frame saying so. A signal (Ctrl-C, SIGTERM; :func:`deferred_signals`) stops the run after
the frame in hand, so that the track, the results and the video hold the same frames.
"""

from __future__ import annotations

import itertools
import time
import warnings
from contextlib import nullcontext
from dataclasses import dataclass, field

import numpy as np

from ..core.hooks import Confidence, Redetects, offers
from ..core.particles import DegenerateWeightsWarning
from ..io.render import annotate, annotate_targets
from ..io.results_format import result_paths
from ..io.track_files import TrackCSV, check_lost_reason
from ..io.video_writer import VideoWriter
from ..loop.profiling import STAGES, Timer, instrument
from ..loop.stepper import Stepper, top_particles, warm_up
from ..system.signals import deferred_signals, stop_reason

__all__ = ["SessionLog", "record_video", "track_row", "target_rows"]


@dataclass
class SessionLog:
    """What a :func:`record_video` run did."""

    rows: list = field(default_factory=list)
    wall: float = 0.0
    ess_sum: float = 0.0
    degenerate: int = 0
    #: ``None``, or how the run was cut short: ``"interrupt"`` (Ctrl-C) or ``"terminate"`` (SIGTERM)
    stopped: str | None = None
    #: per-stage seconds (:class:`~vistrack.loop.profiling.Timer`) or ``None``
    timer: object = None
    #: why the annotated video is not H.264, or ``None``
    video_note: str | None = None
    #: ``(index, reason, detail)`` of the first frame of every stretch where the object is lost
    losses: list = field(default_factory=list)
    #: a model of several targets: the track rows of every frame and target (:func:`target_rows`)
    target_rows: list = field(default_factory=list)
    #: the outline last reported (drawn dashed, tagged "lost", on the frames reported lost after it)
    shown: object = None
    _was_lost: bool = False

    def note_lost(self, res, notify=None):
        """Record the frame result ``res`` where a stretch of lost frames starts (and tell ``notify``)."""
        if res.lost_reason and not self._was_lost:
            self.losses.append((res.index, res.lost_reason, res.lost_detail))
            if notify:
                notify(res.index, res.lost_reason, res.lost_detail)
        self._was_lost = bool(res.lost_reason)

    def stage_split(self):
        """``{stage: ms per frame}`` over :data:`~vistrack.loop.profiling.STAGES`, plus ``other`` (the
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
    """The track-CSV row of a :class:`~vistrack.loop.stepper.FrameResult`: ``frame, visible``, the
    model's :meth:`describe` columns, ``redetected`` (a model that re-detects a lost object, the box
    model's: 1 on the frame it is re-found), ``ess, ms, lost_reason`` and, for a model with a
    calibrated confidence (:class:`~vistrack.core.hooks.Confidence`, the box model's),
    ``confidence`` in ``[0, 1]`` (empty on a frame it gives none)."""
    return _row(model, res.index, res.visible, res.estimate, int(res.redetected), res.ess, res.ms, res.lost_reason,
                res.confidence)


def _row(model, index, visible, estimate, redetected, ess, ms, lost_reason, confidence=None):
    """A track-CSV row, its columns in :func:`track_row`'s order whether the frame was tracked or not."""
    row = {"frame": index, "visible": int(visible), **model.describe(estimate)}
    if offers(model, Redetects):
        row["redetected"] = redetected
    row["ess"], row["ms"], row["lost_reason"] = ess, ms, check_lost_reason(lost_reason)
    if offers(model, Confidence):
        row["confidence"] = "" if confidence is None else float(confidence)
    return row


def target_rows(model, res):
    """The track-CSV rows of a frame of a model of several targets (:class:`~vistrack.scoring.mot.MultiTarget`):
    one per reported target, ``frame, visible = 1, id``, the target's :meth:`describe_target`
    columns, ``ess, ms, lost_reason``; one row with ``visible = 0, id = -1``, NaN geometry (empty cells in
    the CSV) and the frame's ``lost_reason`` when none is reported."""
    ids, states = res.targets
    tail = {"ess": res.ess, "ms": res.ms}
    if not len(ids):
        row = {"frame": res.index, "visible": 0, "id": -1}
        row.update({k: np.nan for k in model.describe_target(np.zeros(states.shape[1]))})
        return [{**row, **tail, "lost_reason": check_lost_reason(res.lost_reason)}]
    return [{"frame": res.index, "visible": 1, "id": int(i), **model.describe_target(x), **tail, "lost_reason": ""}
            for i, x in zip(ids, states)]


def record_video(frames, model, filt, particles, rng, *, track_path=None, out_path=None, results_path=None,
                video_info=None, show_particles=10, label="", progress=None, notify=None, profile=True,
                frame_count=None, start=0, lead=(), results_format="otb", sequence="sequence", ready=None):
    """Track ``frames`` (iterable of ``(index, frame)``), writing the track CSV and annotated video as
    it goes; every frame of the input accounted for and a signal honoured after the frame in hand
    (module docstring). Returns a :class:`SessionLog`.

    Parameters
    ----------
    frames : iterable of (int, ndarray)
    model, filt : the model and its filter
    particles, rng : int, numpy.random.Generator
    track_path, out_path, results_path : path or None
        Track CSV (:class:`TrackCSV`), annotated mp4 and result file (``x,y,w,h``; for GOT-10k and
        VOT the results folder, :func:`~vistrack.io.results_format.result_paths`).
    results_format, sequence : str
        The result file's format, ``otb`` (1-based), ``got10k`` or ``vot``
        (:mod:`vistrack.io.results_format`), and the sequence's name in the GOT-10k and VOT layouts.
    video_info, show_particles, label : tuple or None, int, str
        ``(fps, (width, height))`` for the annotated video; draw this many highest-weight particles,
        and ``label`` after the frame number.
    progress, notify, ready : callable or None
        ``progress(ess)`` after every frame (a progress bar); ``notify(index, reason, detail)`` on the
        first frame of every stretch where the object is lost (:mod:`vistrack.models.collapse`);
        ``ready()`` once the kernels are loaded, before the first frame (a progress bar's clock starts).
    profile : bool
        Time the stages (:mod:`vistrack.loop.profiling`) into ``SessionLog.timer`` (the same tracks).
    lead : sequence of (int, ndarray)
        Frames before ``frames`` searched without finding the object
        (:class:`~vistrack.models.plate.detect.PlateSearch`): rows with ``visible=0``, "not found".
    frame_count, start : int or None, int
        The input's exact frame count (an image folder: frames after the last one decoded get rows
        too), and the frame tracking starts from (:func:`~vistrack.io.starts.start_frame`; earlier
        frames get rows with ``lost_reason`` "not started").
    """
    run = SessionLog(timer=Timer() if profile else None)
    frames = _warmed(frames, filt, particles, ready)
    frames = run.timer.timed_iter(frames, "decode") if profile else frames
    with deferred_signals() as stop:  # from opening the outputs to closing them: a signal waits for the frame
        outs, writer = _open_outputs(track_path, results_path, results_format, sequence, out_path, video_info)
        run.video_note = writer.note if writer else None
        _record_lead(run, lead, model, outs, writer, label)
        t0, failed = time.perf_counter(), False
        try:
            with warnings.catch_warnings(), (instrument(model, filt, run.timer) if profile else nullcontext()):
                warnings.simplefilter("ignore", DegenerateWeightsWarning)
                _track_loop(run, Stepper(filt, particles, rng).steps(frames), model, outs, writer, stop,
                            first=lead[-1][0] + 1 if len(lead) else 0, start=start, frame_count=frame_count,
                            show_particles=show_particles, label=label, notify=notify, progress=progress)
        except (KeyboardInterrupt, SystemError) as e:  # Terminated is a KeyboardInterrupt
            run.stopped = stop_reason(e)
        except BaseException:
            failed = True
            raise
        finally:
            run.wall = time.perf_counter() - t0
            _close_all(outs, writer, complete=not failed)
        if stop.reason:  # a signal while the outputs were closed counts too
            run.stopped = stop.reason
    return run


def _track_loop(run, results, model, outs, writer, stop, *, first, start, frame_count, show_particles, label, notify,
                progress):
    """Record every frame result of ``results`` into ``run`` and the outputs, with a row for every
    frame between them (before ``start``: "not started"; else failed to decode) and after the last
    one up to an exact ``frame_count``; stops after the frame in hand once ``stop.reason`` is set."""
    expected, last = first, None
    for res in results:
        for i in range(expected, res.index):  # frames before the start, or that failed to decode
            _record_decode(run, i, res, model, outs, writer, label, notify, progress, i < start)
        _record(run, res, model, outs, writer, show_particles, label, notify)
        if progress:
            progress(run.rows[-1]["ess"])
        expected, last = res.index + 1, res
        if stop.reason:
            return
    if last is not None and frame_count:
        for i in range(expected, int(frame_count)):
            _record_decode(run, i, last, model, outs, writer, label, notify, progress)


def _open_outputs(track_path, results_path, results_format, sequence, out_path, video_info):
    """``(outs, writer)``: the track CSV and result files (:class:`TrackCSV`) and the annotated video
    of a run; an output another run holds (``OutputBusy``) or that cannot be written leaves none of
    them behind."""
    outs, writer = [], None
    try:
        if track_path:
            outs.append(TrackCSV(track_path))
        if results_path:
            box_path, time_path = result_paths(results_path, results_format, sequence)
            box_path.parent.mkdir(parents=True, exist_ok=True)
            outs.append(TrackCSV(box_path, boxes=results_format))
            if time_path is not None:
                outs.append(TrackCSV(time_path, boxes="time"))
        writer = VideoWriter(out_path, *video_info, codec="auto", atomic=True) if out_path else None
    except BaseException:
        _close_all(outs, writer, complete=False)
        raise
    return outs, writer


def _record_lead(run, lead, model, outs, writer, label):
    """Rows (``visible=0``, "not found") and unmarked video frames for the frames searched without
    finding the object (:class:`~vistrack.models.plate.detect.PlateSearch`)."""
    for index, frame in lead:
        row = _row(model, index, 0, np.full(model.dim, np.nan), 0, 0.0, 0.0, "not found")
        run.rows.append(row)
        for o in outs:
            o.write(row)
        if writer:
            writer.write(annotate(frame, [], [], f"#{index}  {label}  searching"))


def _close_all(outs, writer, complete=True):
    """Close the track files, then the annotated video: a video that fails to close (a full disk
    shows when its last packets are written) must not cost the track. ``complete=False`` (the run
    failed): none of them replaces an earlier file, and the run's own error is the one raised. Every
    one is closed; the first error is raised."""
    error = None
    for o in [*outs, *([writer] if writer else [])]:
        try:
            if not complete:
                o.abandon()
            o.close()
        except Exception as e:  # noqa: BLE001 - the others are closed all the same
            error = error or e
    if error is not None and complete:
        raise error


def _warmed(frames, filt, particles, ready=None):
    """``frames`` with the filter's kernels loaded on a blank frame shaped like the first
    (:func:`~vistrack.loop.stepper.warm_up`) before they are taken: start-up, not tracking time; then
    ``ready()``."""
    frames = iter(frames)
    first = next(frames, None)
    if first is not None:
        warm_up(filt, particles, first[1])
        frames = itertools.chain([first], frames)
    if ready:
        ready()
    return frames


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
            if vis:
                run.shown = model.outline(res.estimate)
            lost = None if vis else (res.lost_reason, [] if run.shown is None else run.shown)
            img = annotate(res.frame, run.shown if vis else [], particles, text, lost=lost,
                           redetected=bool(res.redetected))
        else:
            ids, states = res.targets
            img = annotate_targets(res.frame, ids, model.target_outline(states), particles, text)
        writer.write(img)


class _Untracked:
    """The :class:`~vistrack.loop.stepper.FrameResult` fields of a frame that was not tracked."""

    visible = False

    def __init__(self, index, reason, detail):
        self.index, self.lost_reason, self.lost_detail = index, reason, detail


def _record_decode(run, index, near, model, outs, writer, label, notify=None, progress=None, before=False):
    """The row of frame ``index``, which failed to decode (or comes ``before`` the start frame):
    ``visible=0``, ``lost_reason`` "decode" ("not started"), the geometry and ESS of the
    neighbouring frame's result ``near`` (the filter's state, which the frame did not change),
    ``ms`` 0; a blank annotated frame saying so."""
    reason, detail = ("not started", "before the first ground-truth box") if before else \
        ("decode", "the frame failed to decode")
    row = _row(model, index, 0, near.estimate, 0, near.ess, 0.0, reason)
    rows = [row]
    if near.targets is not None:
        rows = [{"frame": index, "visible": 0, "id": -1,
                 **{k: np.nan for k in model.describe_target(np.zeros(near.targets[1].shape[1]))},
                 "ess": near.ess, "ms": 0.0, "lost_reason": reason}]
        run.target_rows += rows
    if not before:
        run.note_lost(_Untracked(index, reason, detail), notify)
    run.rows.append(row)
    for o in outs:
        for r in rows:
            o.write(r)
    run.ess_sum += row["ess"]
    if writer:
        blank = np.zeros((writer.size[1], writer.size[0], 3), np.uint8)
        writer.write(annotate(blank, [], [], f"#{index}  {label}  {detail}"))
    if progress:
        progress(row["ess"])


