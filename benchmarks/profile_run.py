"""Where the milliseconds of ``vistrack run VIDEO --init X,Y,W,H --track FILE`` go, decode to CSV (issue 53).

    python benchmarks/profile_run.py                          # ball1 at 1280x720 and at 640x480
    python benchmarks/profile_run.py --clip gull1_dtb70 --sizes 1280x720,640x480 --top 25

For each size (the clip re-encoded once at that size, mp4v, into ``~/.cache/vistrack/profile_run``), in this one
process, single-threaded (OpenCV's threads off; the decoding thread of ``run`` is its own):

- ``decode``: the frames read by vistrack's reader alone (:func:`vistrack.io.video.open_video`);
- ``track``: ``vistrack.Tracker`` (what ``run`` runs: the box model, LIS, 100 particles) over the frames held in
  memory;
- ``run``: ``vistrack run VIDEO --init X,Y,W,H --track FILE --seed 1`` in this process (the library calls behind
  it: its reader and decoding thread, the frame loop, the stage timers, the track CSV), wall clock and CPU time
  (all threads: decoding overlaps tracking on a second core), and its stages on the CPU clock (those of
  ``run``'s summary, :mod:`vistrack.loop.profiling`: features, likelihood, proposal, resampling, adapt; the rest
  of the main thread, and the decoding thread);

each the fastest of ``--reps``, in ms a frame; the box model's parts on the CPU clock (:func:`box_parts`); then a
profile of one ``run`` (cProfile on the CPU clock, the main thread), its ``--top`` functions by own time.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
from real_corpus import DATA, find_clips

import vistrack
from vistrack.io.video import open_video

CACHE = Path.home() / ".cache" / "vistrack" / "profile_run"


def resized(clip, size, cache=CACHE):
    """The clip's video re-encoded at ``size`` ``(W, H)`` (the original when it has that size), and the user's
    box scaled to it."""
    src = open_video(clip.video)
    w0, h0 = src.size
    sx, sy = size[0] / w0, size[1] / h0
    x, y, w, h = clip.user_box
    box = (int(round(x * sx)), int(round(y * sy)), int(round(w * sx)), int(round(h * sy)))
    if (w0, h0) == tuple(size):
        return clip.video, box
    out = Path(cache) / f"{clip.name}-{size[0]}x{size[1]}.mp4"
    if not out.is_file():
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_suffix(".tmp.mp4")
        wr = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*"mp4v"), src.fps or 25.0, tuple(size))
        for _, f in src:
            wr.write(cv2.resize(f, tuple(size), interpolation=cv2.INTER_AREA))
        wr.release()
        tmp.replace(out)
    return out, box


def _clocks(fn):
    """``(wall, cpu)`` seconds of ``fn()``."""
    t0, c0 = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - t0, time.process_time() - c0


def decode_all(video):
    return [f for _, f in open_video(video)]


def track_all(frames, box):
    t = vistrack.Tracker(seed=1)
    t.init(frames[0], box)
    for f in frames[1:]:
        t.update(f)


def box_parts(frames, box):
    """The box model's parts on the CPU clock, ms a frame, over ``frames`` tracked by ``vistrack.Tracker``: its
    observation (the correlation filter's response, the scale filter's, the rest: the region, a whole-frame
    search while lost), the filter's step (the likelihood, with the appearance maps it makes, and the rest: the
    proposal's draws, the weights, resampling), the confidence, the lost test and the adaptation."""
    from collections import defaultdict

    acc = defaultdict(float)

    def timed(owner, name, label):
        fn = getattr(owner, name)

        def wrapper(*a, **k):
            t0 = time.process_time()
            try:
                return fn(*a, **k)
            finally:
                acc[label] += time.process_time() - t0

        setattr(owner, name, wrapper)

    t = vistrack.Tracker(seed=1)
    t.init(frames[0], box)
    m = t.model
    for owner, name, label in ((m, "observe", "observe"), (m.cf, "detect", "  correlation filter"),
                               (m.sf, "detect", "  scale filter"), (t._stepper.filt, "step", "step"),
                               (m, "loglik", "  likelihood"), (m, "confidence", "confidence"),
                               (m, "check_lost", "lost test"), (m, "adapt", "adapt")):
        timed(owner, name, label)
    c0 = time.process_time()
    for f in frames[1:]:
        t.update(f)
    total = time.process_time() - c0
    out = {k: 1e3 * v / (len(frames) - 1) for k, v in acc.items()}
    out["total"] = 1e3 * total / (len(frames) - 1)
    return out


def run_once(video, box, csv_path):
    """``vistrack run VIDEO --init X,Y,W,H --track FILE --seed 1``: the library calls behind it
    (:func:`~vistrack.session.plan.prepare`, :func:`~vistrack.session.plan.execute`), its stages timed on the
    main thread's CPU clock (what the machine's other jobs leave out); ``{stage: seconds}`` with ``other`` (the
    rest of the main thread: the frame loop, the track CSV) and ``decoding thread`` (the rest of the process)."""
    from vistrack.core.seeds import run_seed
    from vistrack.loop.profiling import STAGES, Timer
    from vistrack.registry import DEFAULT_PARTICLES
    from vistrack.session import recording
    from vistrack.session.plan import execute, prepare

    plan = prepare(str(video), init=tuple(float(v) for v in box))
    timer = recording.Timer
    recording.Timer = lambda: Timer(clock=time.thread_time)
    try:
        t0, c0 = time.thread_time(), time.process_time()
        log = execute(plan, DEFAULT_PARTICLES, run_seed(1, 0), track_path=csv_path)
        main_thread, process = time.thread_time() - t0, time.process_time() - c0
    finally:
        recording.Timer = timer
    out = {k: log.timer.t[k] for k in STAGES if k != "decode"}
    out["other"] = main_thread - sum(out.values())
    out["decoding thread"] = process - main_thread
    return out


def measure(video, box, reps, top):
    """The module docstring's numbers for one video: ``{part: (wall ms, cpu ms)}`` a frame, the stages of the
    ``run`` of least CPU (:func:`run_once`) in ms a frame, and the profile."""
    frames = decode_all(video)
    n = len(frames)
    track_all(frames[:3], box)  # the kernels loaded before any clock
    with tempfile.TemporaryDirectory() as tmp:
        csv_path = Path(tmp) / "track.csv"
        runs = []
        parts = {"decode": lambda: decode_all(video), "track": lambda: track_all(frames, box),
                 "run": lambda: runs.append(run_once(video, box, csv_path))}
        best = {k: (np.inf, np.inf) for k in parts}
        for _ in range(reps):
            for k, fn in parts.items():
                w, c = _clocks(fn)
                best[k] = (min(best[k][0], w), min(best[k][1], c))
        out = {k: (1e3 * w / n, 1e3 * c / n) for k, (w, c) in best.items()}
        split = {k: 1e3 * v / n for k, v in min(runs, key=lambda d: sum(d.values())).items()}
        parts = min((box_parts(frames, box) for _ in range(reps)), key=lambda d: d["total"])
        prof = cProfile.Profile(time.process_time)
        prof.runcall(run_once, video, box, csv_path)
    text = io.StringIO()
    stats = pstats.Stats(prof, stream=text)
    stats.sort_stats("tottime").print_stats(top)
    return n, out, split, parts, text.getvalue()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--clip", default="ball1_vot2015", help="a clip of the corpus (default ball1_vot2015, 1280x720)")
    ap.add_argument("--sizes", default="1280x720,640x480", help="frame sizes, WxH, comma-separated")
    ap.add_argument("--reps", type=int, default=3, help="runs of each part, the fastest kept")
    ap.add_argument("--top", type=int, default=20, help="functions of the profile printed (by own time)")
    ap.add_argument("--data", default=str(DATA))
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)
    clip = find_clips(args.data, [args.clip])[0]
    for spec in args.sizes.split(","):
        size = tuple(int(v) for v in spec.lower().split("x"))
        video, box = resized(clip, size)
        n, out, split, parts, prof = measure(video, box, args.reps, args.top)
        print(f"\n{clip.name} at {size[0]}x{size[1]}, {n} frames, box {box}: ms a frame (wall / CPU)")
        for k, (w, c) in out.items():
            print(f"  {k:<7} {w:6.2f} / {c:6.2f}")
        print("  run, CPU a frame (the run least busy): " + ", ".join(f"{k} {v:.2f}" for k, v in split.items()))
        print("  the box model's parts, CPU a frame (tracked from memory): "
              + ", ".join(f"{k.strip()} {v:.2f}" for k, v in parts.items()))
        print(f"\nprofile of one run (CPU clock, main thread), by own time:\n{prof}")


if __name__ == "__main__":
    sys.exit(main())
