"""Fault-injection soak: ~280 scenarios of bad input, broken files and interruptions, each run as a
user would (``python -m vistrack.cli ...`` in a fresh folder), its outcome classified automatically.

Not part of CI (about 25 minutes on 2 cores). The fast cases that guard each fix live in
``tests/test_faults*.py``; this sweep looks for new ones. Issue 47's cases are in ``soak_sweep3.py``
(a full disk on a small tmpfs where one can be mounted, else ``skipped``); a case whose fix is another
issue's is counted apart (``..., awaits issue 46``), not as a failure.

    python benchmarks/soak.py [--only SUBSTRING] [--keep DIR] [--timeout 180]

Outcomes, in this order of precedence:

* ``hang``: no exit within the timeout;
* ``traceback``: a Python traceback on stdout/stderr, or the process died by a signal;
* ``data loss``: a scenario check found a file lost or damaged that should have survived
  (the old clip of an interrupted synth, the partial track of an interrupted run, task files);
* ``silent wrong``: exit 0 on input that must be refused, or an output that does not parse,
  holds NaN/inf (no output column is documented to hold them), or fails the scenario's check
  (a resume that mixes seeds, ground truth of another length without a warning, ...);
* ``misleading error``: a non-zero exit without exactly one ``Error:`` line, an error that does
  not name what is wrong (the scenario's keyword), or valid input refused;
* ``clear error``: a non-zero exit with one ``Error:`` line and no traceback;
* ``correct``: exit 0 (or 130 / 143 where the scenario interrupts) and outputs that parse;
* ``skipped``: the scenario cannot run here (no tmpfs can be mounted, no vot-trax), with the reason.

Prints a markdown table (scenario, command, exit code, outcome, note) and the totals.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")  # this script reads damaged files too

import cv2
import numpy as np

OUTCOMES = ["clear error", "correct", "misleading error", "traceback", "silent wrong", "data loss", "hang", "skipped"]
W, H, FRAMES = 160, 120, 40
INIT = "48,51,24,18"
FX = None  # the fixtures folder (set by main)
#: the outcomes that are failures (a scenario that awaits another issue's fix is counted apart)
BAD = ("traceback", "hang", "silent wrong", "data loss")
NAN = re.compile(r"(?<![A-Za-z_])(nan|-?inf|infinity)(?![A-Za-z_])", re.I)


@dataclass
class Result:
    code: int | None
    out: str
    err: str
    seconds: float
    timeout: bool = False
    note: str = ""
    skip: str = ""  # why the scenario could not run here (no tmpfs, no vot-trax)


@dataclass
class Scenario:
    name: str
    argv: list
    expect: str = "error"  # "error": must be refused; "ok": must work; "either": a clear error or a correct result
    mention: str = ""  # the error line must contain this (else: misleading)
    check: object = None  # check(w, res) -> None or (outcome, note)
    prepare: object = None  # prepare(w) before the run
    driver: object = None  # driver(w, argv, timeout) -> Result, instead of one plain run
    codes: tuple = (0,)
    extra: list = field(default_factory=list)
    awaits: str = ""  # another issue's fix: a failure here is counted apart ("awaits issue 46"), not as one


# ---------------------------------------------------------------- fixtures


def _frames(n, w=W, h=H, seed=0):
    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.normal(110, 40, (h, w, 3)).astype(np.float32), (0, 0), 2).clip(0, 255).astype(np.uint8)
    for t in range(n):
        f = bg.copy()
        cx, cy = int(w * 0.375 + 20 * np.sin(0.1 * t)), int(h * 0.5 + 10 * np.cos(0.1 * t))
        s = max(1, w // 13)
        cv2.rectangle(f, (cx - s, cy - s * 3 // 4), (cx + s, cy + s * 3 // 4), (30, 60, 220), -1)
        yield f


def _avi(path, n, w=W, h=H, color=True):
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (w, h), color)
    for f in _frames(n, w, h):
        wr.write(f if color else cv2.cvtColor(f, cv2.COLOR_BGR2GRAY))
    wr.release()


def _mp4(path, n, faststart, w=W, h=H):
    """MPEG-4 Part 2 through PyAV, the moov atom at the front (``faststart``) or at the end."""
    import av

    c = av.open(str(path), "w", options={"movflags": "faststart"} if faststart else {})
    s = c.add_stream("mpeg4", rate=25)
    s.width, s.height, s.pix_fmt = w, h, "yuv420p"
    for f in _frames(n, w, h):
        for p in s.encode(av.VideoFrame.from_ndarray(f, format="bgr24")):
            c.mux(p)
    for p in s.encode():
        c.mux(p)
    c.close()
    data = Path(path).read_bytes()
    assert (data.find(b"moov") < data.find(b"mdat")) == faststart, path


def _images(folder, n, mode="bgr", ext="png"):
    (folder / "img").mkdir(parents=True)
    for i, f in enumerate(_frames(n)):
        img = {"bgr": f, "grey": cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), "bgra": cv2.cvtColor(f, cv2.COLOR_BGR2BGRA),
               "u16": f.astype(np.uint16) * 257}[mode]
        cv2.imwrite(str(folder / "img" / f"{i + 1:04d}.{ext}"), img)
    return folder


def _otb_rows(n):
    """OTB ground truth (1-based x,y,w,h) of the moving box that :func:`_frames` draws."""
    s = W // 13
    return [f"{int(W * 0.375 + 20 * np.sin(0.1 * t)) - s + 1},{int(H * 0.5 + 10 * np.cos(0.1 * t)) - s * 3 // 4 + 1},"
            f"{2 * s + 1},{2 * (s * 3 // 4) + 1}" for t in range(n)]


def _otb(folder, rows, n=12, mode="bgr"):
    _images(folder, n, mode)
    (folder / "groundtruth_rect.txt").write_text("\n".join(rows) + "\n")
    return folder


def build_fixtures(fx):
    from vistrack.data_synth.contour_clip import make_contour_clip
    from vistrack.data_synth.landmark_clip import make_landmark_clip
    from vistrack.data_synth.plate_clip import make_plate_clip

    fx.mkdir(parents=True)
    kw = dict(size=(128, 96), clutter="low", distractor=False)
    make_contour_clip(fx / "clip", frames=20, seed=1, **kw)
    for s in (1, 2):
        make_contour_clip(fx / "suite" / f"c{s}", frames=10, seed=s, **kw)
    make_plate_clip(fx / "plate", frames=10, size=(160, 120), seed=1, cars=1)
    make_landmark_clip(fx / "lm", frames=10, size=(128, 96), seed=1)
    _avi(fx / "v.avi", FRAMES)
    _avi(fx / "grey.avi", FRAMES, color=False)
    _avi(fx / "tiny.avi", 10, 8, 8)
    _mp4(fx / "moov_end.mp4", FRAMES, False)
    _mp4(fx / "moov_front.mp4", FRAMES, True)
    _mp4(fx / "one.mp4", 1, True)
    _mp4(fx / "uhd.mp4", 3, True, 3840, 2160)
    rng = np.random.default_rng(7)
    for src, dst in [("moov_end.mp4", "trunc_end.mp4"), ("moov_front.mp4", "trunc_front.mp4"), ("v.avi", "trunc.avi")]:
        data = (fx / src).read_bytes()
        (fx / dst).write_bytes(data[: int(0.6 * len(data))])
    for src, dst in [("moov_front.mp4", "corrupt.mp4"), ("v.avi", "corrupt.avi")]:
        data = bytearray((fx / src).read_bytes())
        k = len(data) // 2
        data[k:k + 1500] = rng.integers(0, 256, 1500, dtype=np.uint8).tobytes()
        (fx / dst).write_bytes(bytes(data))
    (fx / "empty.mp4").write_bytes(b"")
    (fx / "notes.txt").write_text("not a video\n")
    for mode in ("grey", "bgra", "u16"):
        _images(fx / mode, 8, mode)
    _images(fx / "badimg", 8, ext="jpg")
    (fx / "badimg" / "img" / "0004.jpg").write_bytes(b"\xff\xd8 not a jpeg")
    (fx / "allbad" / "img").mkdir(parents=True)
    for i in range(3):
        (fx / "allbad" / "img" / f"{i + 1:04d}.jpg").write_bytes(b"garbage")
    (fx / "emptydir").mkdir()
    rows = _otb_rows(12)
    _otb(fx / "otb", rows)
    _otb(fx / "otb_nan", rows[:4] + ["NaN,NaN,NaN,NaN"] * 3 + rows[7:])
    _otb(fx / "otb_zero", rows[:4] + ["0,0,0,0"] * 3 + rows[7:])
    _otb(fx / "otb_short", rows[:8])
    _otb(fx / "otb_long", rows + rows[:4])
    _otb(fx / "otb_bad", rows[:5] + ["12,13,fourteen,15"] + rows[6:])
    _otb(fx / "otb_absent", ["0,0,0,0"] * 12)
    _otb(fx / "otb_empty", [])
    _otb(fx / "otb_negative", rows[:6] + ["30,30,-10,12"] * 2 + rows[8:])
    _otb(fx / "otb_grey", rows, mode="grey")
    badimg_gt = fx / "otb_badimg"
    _otb(badimg_gt, _otb_rows(8), n=8)
    (badimg_gt / "img" / "0004.png").write_bytes(b"not a png")
    (fx / "template_nan.txt").write_text("10 10\nnan 12\n14 14\n")
    build_sweep2_fixtures(fx, rows)
    (fx / "garbage.txt").write_text("x y z\n")
    (fx / "file").write_text("a file\n")
    res = fx / "results"
    res.mkdir()
    (res / "c1.txt").write_text("\n".join(["40,40,20,20"] * 5 + ["NaN,NaN,NaN,NaN"] * 5) + "\n")
    bad = fx / "badresults"
    bad.mkdir()
    (bad / "c1.txt").write_text("hello\n")


def build_sweep2_fixtures(fx, rows):
    """The inputs of issue 38's cases (the second sweep)."""
    # an image folder whose 4th frame has another size
    _images(fx / "sizes", 8)
    cv2.imwrite(str(fx / "sizes" / "img" / "0004.png"), np.zeros((2 * H, 2 * W, 3), np.uint8))
    # meta.json that is JSON but not an object
    for name, text in (("meta_list", "[1, 2, 3]"), ("meta_str", '"hello"')):
        _otb(fx / name, rows)
        (fx / name / "meta.json").write_text(text)
    # result folders: two of one name, files of different lengths; one named like an algorithm; a short one
    for d, n in (("rd_a/mt", 10), ("rd_b/mt", 6), ("rd_lis/lis", 10), ("rd_short/mt", 6)):
        (fx / d).mkdir(parents=True)
        (fx / d / "c1.txt").write_text("40,40,20,20\n" * n)
    # 40 frames, 12 of them undecodable
    _otb(fx / "bad12", _otb_rows(40), n=40)
    for k in range(3, 40, 3)[:12]:
        (fx / "bad12" / "img" / f"{k + 1:04d}.png").write_bytes(b"not a png")
    # ground truth absent (NaN) in the first 4 frames
    _otb(fx / "otb_late", ["NaN,NaN,NaN,NaN"] * 4 + rows[4:])
    # frames named frame1 .. frame12 (lexicographic order: 1, 10, 11, 12, 2, ...), each brighter than the last
    (fx / "natural" / "img").mkdir(parents=True)
    for i in range(12):
        f = np.full((H, W, 3), 10 + 20 * i, np.uint8)
        cv2.rectangle(f, (60, 50), (80, 66), (30, 60, 220), -1)
        cv2.imwrite(str(fx / "natural" / "img" / f"frame{i + 1}.png"), f)
    (fx / "template_nan4.txt").write_text("10 10\nnan 12\n14 14\n20 20\n")
    _avi(fx / "long.avi", 400)
    _otb(fx / "one_frame", rows[:1], n=1)
    _otb(fx / "otb_huge", rows[:1] + ["1e300,5,6,7"] + rows[2:])
    _otb(fx / "otb_binary", rows)
    (fx / "otb_binary" / "groundtruth_rect.txt").write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe" + bytes(range(256)))
    _otb(fx / "otb_bom", rows)
    (fx / "otb_bom" / "groundtruth_rect.txt").write_bytes(b"\xef\xbb\xbf" + "\n".join(rows).encode() + b"\n")


# ---------------------------------------------------------------- running and judging


def vistrack(argv, cwd, timeout, **kw):
    t0 = time.time()
    try:
        p = subprocess.run([sys.executable, "-m", "vistrack.cli", *argv], cwd=cwd, capture_output=True, text=True,
                           timeout=timeout, **kw)
        return Result(p.returncode, p.stdout, p.stderr, time.time() - t0)
    except subprocess.TimeoutExpired as e:
        return Result(None, str(e.stdout or ""), str(e.stderr or ""), time.time() - t0, timeout=True)


def outputs(w, since):
    """Output files (CSV, JSON, text results) written under ``w`` since ``since``."""
    return [p for p in w.rglob("*") if p.is_file() and p.stat().st_mtime >= since
            and p.suffix in (".csv", ".json", ".txt", ".part") and "fixtures" not in p.parts]


def bad_output(w, since):
    """The first output that does not parse or holds NaN / inf, as a note."""
    import csv

    for p in outputs(w, since):
        text = p.read_text(errors="replace")
        if p.name in ("groundtruth.csv", "objects.csv"):  # documented: a plate clip's nan where no plate is in view
            text = "\n".join(ln for ln in text.splitlines() if not re.match(r"\d+,0,", ln))
        m = NAN.search(text)
        if m:
            return f"{p.relative_to(w)} holds {m.group(0)!r}"
        try:
            if p.suffix == ".json":
                json.loads(text)
            elif p.suffix in (".csv", ".part") and text:
                widths = {len(r) for r in csv.reader(text.splitlines())}
                if len(widths) > 1:
                    return f"{p.relative_to(w)}: rows of different widths {sorted(widths)}"
        except ValueError as e:
            return f"{p.relative_to(w)} does not parse ({e})"
    return None


def classify(sc, w, res, since):
    text = res.out + res.err
    if res.skip:
        return "skipped", res.skip
    if res.timeout:
        return "hang", f"no exit in {res.seconds:.0f} s"
    if "Traceback (most recent call last)" in text:
        last = [ln for ln in res.err.splitlines() if ln and not ln.startswith(" ")][-1:] or ["?"]
        return "traceback", last[0][:100]
    if res.code is not None and res.code < 0 and res.code not in sc.codes:
        last = [ln for ln in res.err.splitlines() if ln.strip()][-1:] or [""]
        return "traceback", f"died by signal {-res.code} {last[0][:80]!r}"
    parts = [p.name for p in w.rglob("*.part")]
    if parts and (res.code is None or res.code >= 0):
        return "data loss", f"{', '.join(parts)} left behind (not renamed into place)"
    litter = [p.name for p in w.rglob(".*") if p.name.endswith(".lock") and p.name != ".vistrack.lock"
              or ".part." in p.name]
    if litter and (res.code is None or res.code >= 0) and "fixtures" not in str(w):
        return "silent wrong", f"{', '.join(litter[:3])} left behind (a lock or temporary file)"
    if sc.check:
        verdict = sc.check(w, res)
        if verdict:
            return verdict
    ok = res.code in sc.codes
    if ok:
        bad = bad_output(w, since)
        if bad:
            return "silent wrong", bad
        if sc.expect == "error":
            return "silent wrong", "accepted (exit 0)"
        return "correct", res.note
    errors = [ln for ln in res.err.splitlines() if ln.startswith("Error:")]
    if len(errors) != 1:
        return "misleading error", f"exit {res.code}, {len(errors)} Error: lines: {res.err.strip()[-100:]!r}"
    if sc.expect == "ok":
        return "misleading error", f"valid input refused: {errors[0][:100]}"
    if sc.mention and sc.mention.lower() not in errors[0].lower():
        return "misleading error", f"does not name {sc.mention!r}: {errors[0][:100]}"
    return "clear error", errors[0][7:107]


def run_scenario(sc, base, fx, timeout):
    w = base / re.sub(r"[^A-Za-z0-9_.-]", "_", sc.name)
    w.mkdir()
    if sc.prepare:
        sc.prepare(w)
    argv = [a.format(fx=fx, w=w) for a in sc.argv]
    since = time.time() - 0.01
    res = sc.driver(w, argv, timeout) if sc.driver else vistrack(argv, w, timeout)
    outcome, note = classify(sc, w, res, since)
    return argv, res, outcome, note


# ---------------------------------------------------------------- drivers: interrupts and concurrent runs


def _popen(argv, w, group=False):
    # a background job starts with SIGINT ignored, which Python keeps: give the child the default
    return subprocess.Popen([sys.executable, "-m", "vistrack.cli", *argv], cwd=w, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=group,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _finish(p, t0, timeout, note=""):
    try:
        out, err = p.communicate(timeout=timeout)
        return Result(p.returncode, out, err, time.time() - t0, note=note)
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate()
        return Result(None, out, err, time.time() - t0, timeout=True)


def _wait_for(p, ready, timeout):
    deadline = time.time() + timeout
    while time.time() < deadline and p.poll() is None:
        if ready():
            return True
        time.sleep(0.02)
    return False


def interrupt(sig, ready, group=False, then=None):
    """A driver: start the command, send ``sig`` once ``ready(w)`` (to the process group with
    ``group``: Ctrl-C in a terminal), then collect; ``then(w, res)`` may run a follow-up."""
    return signals([sig], ready, group, then)


def _lines(path):
    return path.read_text().count("\n") if path.is_file() else 0


def _track_part_rows(n):
    return lambda w: _lines(w / "t.csv.part") > n


def _has_task(w):
    return (w / "R" / "tasks").is_dir() and any(p.suffix == ".json" for p in (w / "R" / "tasks").iterdir())


def _clip_state(folder):
    return {p.name: p.read_bytes() for p in sorted(Path(folder).iterdir())} if Path(folder).is_dir() else None


def two_evals(argv_a, argv_b):
    """A driver: eval A runs; eval B starts into the same --out while A holds it. B's result is
    the scenario's; A's results.json must be A's own (else: data loss)."""

    def driver(w, argv, timeout):
        t0 = time.time()
        a = _popen([x.format(w=w, fx=FX) for x in argv_a], w)
        _wait_for(a, lambda: (w / "R" / ".vistrack.lock").exists(), timeout)
        res = vistrack(argv, w, timeout)
        ra = _finish(a, t0, timeout)
        try:
            seed = json.loads((w / "R" / "results.json").read_text())["config"]["seed"]
        except (OSError, ValueError, KeyError):
            seed = None
        if ra.code != 0 or seed != 1:
            res.note = f"first eval: exit {ra.code}, results.json seed {seed} (expected 1)"
            res.lost = True
        return res

    return driver


def kill_worker(w, argv, timeout):
    """A driver: kill -9 one Dask worker process of the eval once the first task file is there;
    the scenario's check compares the results with a fresh run's."""
    import psutil

    t0 = time.time()
    p = _popen(argv, w)
    if _wait_for(p, lambda: _has_task(w), timeout):
        for c in psutil.Process(p.pid).children():
            try:
                if "spawn_main" in " ".join(c.cmdline()):
                    c.kill()
                    break
            except psutil.Error:
                pass
    return _finish(p, t0, timeout)


def signals(sigs, ready, group=False, then=None):
    """A driver: start the command, send the signals ``sigs`` one after the other once ``ready(w)``
    (to the process group with ``group``), then collect; ``then(w, res, timeout)`` may run a follow-up."""

    def driver(w, argv, timeout):
        t0 = time.time()
        p = _popen(argv, w, group)
        if not _wait_for(p, lambda: ready(w), timeout):
            res = _finish(p, t0, timeout)
            res.note = "finished before the signal" if not res.timeout else ""
            return res
        for sig in sigs:
            os.killpg(p.pid, sig) if group else p.send_signal(sig)
        res = _finish(p, t0, timeout)
        if then and not res.timeout:
            res = then(w, res, timeout)
        return res

    return driver


def two_runs(argv_a):
    """A driver: run A writes ``w/t.csv``; run B (the scenario's) starts with the same ``--track``
    while A writes it. B's result is the scenario's; A's track must be A's own, whole (else: data
    loss)."""

    def driver(w, argv, timeout):
        t0 = time.time()
        a = _popen([x.format(w=w, fx=FX) for x in argv_a], w)
        _wait_for(a, lambda: _lines(w / "t.csv.part") > 2, timeout)
        res = vistrack(argv, w, timeout)
        ra = _finish(a, t0, timeout)
        rows = _rows(w / "t.csv") if (w / "t.csv").is_file() else []
        frames = [r.get("frame") for r in rows]
        if ra.code != 0 or frames != [str(k) for k in range(400)] or any(None in r.values() for r in rows):
            res.note = f"first run: exit {ra.code}, its track holds {len(rows)} rows, frames {frames[:3]}..."
            res.lost = True
        return res

    return driver


def _decoded(path):
    cap = cv2.VideoCapture(str(path))
    n = 0
    while cap.read()[0]:
        n += 1
    cap.release()
    return n


def same_frames(w, res):
    """After an interrupt: the track, the results and the video hold the same frames 0..k-1."""
    if res.note:
        return None
    t = _rows(w / "t.csv") if (w / "t.csv").is_file() else []
    r = _lines(w / "r.txt")
    v = _decoded(w / "a.mp4") if (w / "a.mp4").is_file() else 0
    if len(t) < 2 or [int(x["frame"]) for x in t] != list(range(len(t))):
        return "data loss", f"track CSV has {len(t)} rows"
    if not len(t) == r == v:
        return "data loss", f"track {len(t)} rows, results {r} lines, video {v} frames"
    res.note = f"{len(t)} frames in each"
    return None


def results_lines(n, zero=None, first_zero=0):
    """``w/r.txt`` has ``n`` lines (one per input frame), ``zero`` of them (or the first
    ``first_zero``) ``0,0,0,0``."""

    def check(w, res):
        if res.code != 0:
            return None
        lines = (w / "r.txt").read_text().splitlines() if (w / "r.txt").is_file() else []
        zeros = [k for k, ln in enumerate(lines) if set(ln.replace(",", "").replace(".", "")) <= {"0"}]
        if len(lines) != n:
            return "silent wrong", f"results have {len(lines)} lines for {n} frames"
        if zero is not None and len(zeros) != zero:
            return "silent wrong", f"{len(zeros)} lines 0,0,0,0 (expected {zero})"
        if first_zero and zeros[:first_zero] != list(range(first_zero)):
            return "silent wrong", f"the first {first_zero} lines are not 0,0,0,0"
        res.note = f"{n} lines, {len(zeros)} 0,0,0,0"
        return None

    return check


def all_of(*checks):
    def check(w, res):
        for c in checks:
            v = c(w, res)
            if v:
                return v
        return None

    return check


def natural_order(w, res):
    """Frames frame1..frame12 (each brighter than the one before) read in natural order: the
    annotated video's frames grow brighter."""
    if res.code != 0:
        return None
    cap = cv2.VideoCapture(str(w / "a.mp4"))
    means = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        means.append(float(f.mean()))
    if len(means) != 12 or np.any(np.diff(means) <= 0):
        return "silent wrong", f"frame brightness {np.round(means).astype(int).tolist()}: not frame1, frame2, .."
    return None


def suite_holds(names):
    def check(w, res):
        if res.code != 0:
            return None
        got = sorted(p.name for p in (w / "s").iterdir() if not p.name.startswith("."))
        if got != sorted(names):
            return "silent wrong", f"the suite folder holds {got}"
        return None

    return check


def short_error(most=300):
    def check(w, res):
        long = [ln for ln in res.err.splitlines() if ln.startswith("Error:") and len(ln) > most]
        return ("misleading error", f"a {len(long[0])}-character error line") if long else None

    return check


def fast(seconds):
    def check(w, res):
        return ("misleading error", f"failed after {res.seconds:.0f} s (ran the grid first)") \
            if res.code and res.seconds > seconds else None

    return check


def says(word):
    def check(w, res):
        return None if word.lower() in (res.out + res.err).lower() else ("silent wrong", f"does not say {word!r}")

    return check


def lost_if_flagged(w, res):
    return ("data loss", res.note) if getattr(res, "lost", False) else None


# ---------------------------------------------------------------- checks


def _rows(path):
    import csv

    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def track_has(min_rows, max_rows=10**9):
    """The track CSV ``w/t.csv`` holds between ``min_rows`` and ``max_rows`` rows (a run that stops
    early on frames OpenCV still decodes is a silent wrong result)."""

    def check(w, res):
        if res.code != 0:
            return None
        n = len(_rows(w / "t.csv")) if (w / "t.csv").is_file() else 0
        if not min_rows <= n <= max_rows:
            return "silent wrong", f"track has {n} rows (expected {min_rows}..{max_rows})"
        res.note = res.note or f"{n} rows"
        return None

    return check


def decodable(video):
    """How many frames of ``video`` OpenCV decodes, reading on past failures (what the track may hold)."""
    cap = cv2.VideoCapture(str(video))
    n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    ok = sum(cap.read()[0] for _ in range(n + 2))
    cap.release()
    return ok


def track_decodable(name):
    """The track has a row per frame, 0, 1, .. (issue 38: a frame that fails to decode has one
    with lost_reason "decode"), and as many tracked rows as OpenCV decodes frames (a run that stops
    at a damaged frame although later ones decode is a silent wrong result)."""

    def check(w, res):
        if res.code != 0:
            return None
        rows = _rows(w / "t.csv") if (w / "t.csv").is_file() else []
        frames = [int(r["frame"]) for r in rows]
        tracked = sum(r["lost_reason"] != "decode" for r in rows)
        if frames != list(range(len(frames))):
            return "silent wrong", f"track frames are not 0..{len(frames) - 1}"
        if tracked != decodable(FX / name):
            return "silent wrong", f"{tracked} tracked rows, {decodable(FX / name)} decodable frames"
        res.note = res.note or f"{len(rows)} rows, {len(rows) - tracked} 'decode'"
        return None

    return check


def track_accounts(n, bad):
    """Every one of ``n`` frames has a row (0..n-1), ``bad`` of them with lost_reason "decode"."""

    def check(w, res):
        if res.code != 0:
            return None
        rows = _rows(w / "t.csv") if (w / "t.csv").is_file() else []
        got = sum(r["lost_reason"] == "decode" for r in rows)
        if [int(r["frame"]) for r in rows] != list(range(n)) or got != bad:
            return "silent wrong", f"{len(rows)} rows ({got} 'decode'); expected {n} ({bad})"
        res.note = f"{n} rows, {bad} 'decode'"
        return None

    return check


def partial_track(w, res):
    """An interrupted run: the track so far is ``t.csv``, whole rows, no ``.part`` left."""
    if res.note:
        return None
    t = w / "t.csv"
    if not t.is_file() or (w / "t.csv.part").exists():
        return "data loss", "no track CSV after the interrupt" if not t.is_file() else "a .part file is left"
    rows = _rows(t)
    if len(rows) < 3 or [int(r["frame"]) for r in rows] != list(range(len(rows))):
        return "data loss", f"track CSV has {len(rows)} rows"
    res.note = f"{len(rows)} rows kept"
    return None


def killed_track(w, res):
    """kill -9 of run: the part file holds whole rows up to the last frame."""
    if res.note:
        return None
    part = w / "t.csv.part"
    if not part.is_file() or _lines(part) < 3:
        return "data loss", "no rows left after kill -9"
    if not part.read_text().endswith("\n"):
        return "data loss", "the last row is cut"
    res.note = f"{_lines(part) - 1} whole rows in t.csv.part"
    return None


def warns(word):
    def check(w, res):
        if res.code == 0 and word.lower() not in res.err.lower():
            return "silent wrong", f"no warning mentioning {word!r}"
        return None

    return check


def consistent_absent(w, res):
    """OTB absent frames: results.csv's per-task numbers equal results.json's (one run, one entry)."""
    if res.code != 0:
        return None
    s = json.loads((w / "R" / "results.json").read_text())["results"][0]
    (row,) = _rows(w / "R" / "results.csv")
    for k in ("p_lost", "success_auc", "precision_20px", "mean_error"):
        a, b = s[k], row[k]
        if (a is None) != (b == "") or (a is not None and abs(a - float(b)) > 1e-3):
            return "silent wrong", f"{k}: results.json {a} vs results.csv {b}"
    return None


def _strip(path):
    d = json.loads(Path(path).read_text())
    return [{k: v for k, v in r.items() if k != "frames_per_s"} for r in d["results"]]


def equals_fresh(fresh_argv):
    """The results equal a fresh run's (``fresh_argv`` into ``w/F``): resume mixes nothing."""

    def check(w, res):
        if res.code != 0:
            return None
        f = vistrack([a.format(w=w) for a in fresh_argv], w, 300)
        if f.code != 0:
            return "silent wrong", f"the fresh run failed: {f.err[-100:]}"
        if _strip(w / "R" / "results.json") != _strip(w / "F" / "results.json"):
            return "silent wrong", "results differ from a fresh run's"
        return None

    return check


def tasks_kept(n):
    def check(w, res):
        files = list((w / "R" / "tasks").glob("*.json"))
        ok = [p for p in files if json.loads(p.read_text()).get("fingerprint")]
        if len(ok) < n:
            return "data loss", f"{len(ok)} of {n} task files left"
        return None

    return check


def clip_intact(w, res):
    """An interrupted synth over ``w/c1``: the old clip byte for byte, nothing eval would take."""
    from vistrack.io.clips import find_clips

    if _clip_state(w / "c1") != _saved_state(w):
        return "data loss", "the old clip changed"
    try:
        clips = find_clips([w])
    except Exception as e:  # noqa: BLE001
        return "data loss", f"eval cannot read the folder: {e}"
    if clips != [w / "c1"]:
        return "data loss", f"eval would take {[c.name for c in clips]}"
    res.note = res.note or "old clip intact"
    return None


def _saved_state(w):
    return {k: bytes.fromhex(v) for k, v in json.loads((w / "state.json").read_text()).items()}


def input_intact(name):
    def check(w, res):
        if (w / name).read_bytes() != (FX / name).read_bytes():
            return "data loss", f"the input {name} was overwritten"
        return None

    return check


# ---------------------------------------------------------------- scenarios


def R(video, *opts, init=True):
    """``run VIDEO`` with a box, 50 bootstrap particles and the track CSV at ``w/t.csv``."""
    return ["run", video, *(["--init", INIT] if init else []), "-n", "50", "--algo", "bootstrap",
            "--track", "{w}/t.csv", "-q", *opts]


def EV(clips, *opts, model=None):
    """``eval CLIPS`` with one bootstrap-20 run per clip, in-process, into ``w/R``."""
    return ["eval", clips, "--algos", "bootstrap", "--particles", "20", "--runs", "1", "--in-process",
            "--out", "{w}/R", "-q", *(["--model", model] if model else []), *opts]


SY = ["synth", "contour", "--out", "{w}/c", "--frames", "3", "--size", "96x72", "--clutter", "low", "-q"]
BE = ["reproduce", "bearings", "--runs", "2", "--sequences", "2", "--steps", "5", "--particles", "50",
      "--algos", "bootstrap,lis", "--in-process", "--out", "{w}/B", "-q"]


def sub(argv, opt, value):
    """``argv`` with option ``opt`` set to ``value`` (replaced, or appended)."""
    a = list(argv)
    if opt in a:
        a[a.index(opt) + 1] = value
    else:
        a += [opt, value]
    return a


def copy(*names):
    def prepare(w):
        for n in names:
            (shutil.copytree if (FX / n).is_dir() else shutil.copy)(FX / n, w / n)

    return prepare


def link(name, target="/dev/full"):
    """``w/name`` a symlink to ``target``: a full disk that is safe to replace (a rename over the
    link replaces the link, never the device)."""
    return lambda w: (w / name).symlink_to(target)


def evald(clips, *opts, model=None, then=None):
    """Prepare ``w/R`` with an eval of ``clips`` (copied into ``w``), then ``then(w)``."""

    def prepare(w):
        for c in clips:
            shutil.copytree(FX / c, w / c)
        r = vistrack([a.format(w=w) for a in EV(*[str(w / c) for c in clips], *opts, model=model)], w, 300)
        assert r.code == 0, r.err
        if then:
            then(w)

    return prepare


def old_clip(w):
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(w / "c1", frames=3, size=(96, 72), seed=1, clutter="low", distractor=False)
    (w / "state.json").write_text(json.dumps({k: v.hex() for k, v in _clip_state(w / "c1").items()}))


def _damage(text):
    def then(w):
        p = sorted((w / "R" / "tasks").glob("*.json"))[0]
        p.write_bytes(text if isinstance(text, bytes) else text.encode())

    return then


def _resynth(w):
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(w / "suite" / "c1", frames=10, size=(128, 96), seed=9, clutter="low", distractor=False)


def video_scenarios():
    E = "either"
    return [
        Scenario("run avi", R("{fx}/v.avi"), "ok", check=track_has(FRAMES, FRAMES)),
        Scenario("run mp4, moov at the end", R("{fx}/moov_end.mp4"), "ok", check=track_has(FRAMES, FRAMES)),
        Scenario("run mp4, moov at the front", R("{fx}/moov_front.mp4"), "ok", check=track_has(FRAMES, FRAMES)),
        Scenario("run mp4 cut at 60 %, moov at the end", R("{fx}/trunc_end.mp4"), E),
        Scenario("run mp4 cut at 60 %, moov at the front", R("{fx}/trunc_front.mp4"), E,
                 check=track_decodable("trunc_front.mp4")),
        Scenario("run avi cut at 60 %", R("{fx}/trunc.avi"), E, check=track_decodable("trunc.avi")),
        Scenario("run mp4, 1500 bytes overwritten mid-stream", R("{fx}/corrupt.mp4"), "ok",
                 check=track_decodable("corrupt.mp4")),
        Scenario("run avi, 1500 bytes overwritten mid-stream", R("{fx}/corrupt.avi"), "ok",
                 check=track_decodable("corrupt.avi")),
        Scenario("run zero-byte video", R("{fx}/empty.mp4"), mention="empty.mp4"),
        Scenario("run 1-frame video", R("{fx}/one.mp4"), "ok", check=track_has(1, 1)),
        Scenario("run 8x8 frames, box inside", R("{fx}/tiny.avi", init=False) + ["--init", "1,1,5,5"], E),
        Scenario("run 8x8 frames, plates (no box)", R("{fx}/tiny.avi", init=False), E),
        Scenario("run 3840x2160 frames", R("{fx}/uhd.mp4", init=False) + ["--init", "1400,1000,300,200"], "ok",
                 check=track_has(3, 3)),
        Scenario("run grey video", R("{fx}/grey.avi"), "ok", check=track_has(FRAMES, FRAMES)),
        Scenario("run grey image folder", R("{fx}/grey"), "ok", check=track_has(8, 8)),
        Scenario("run 4-channel image folder", R("{fx}/bgra"), "ok", check=track_has(8, 8)),
        Scenario("run 16-bit image folder", R("{fx}/u16"), "ok", check=track_has(8, 8)),
        Scenario("run image folder with one bad image", R("{fx}/badimg"), "ok", check=track_accounts(8, 1)),
        Scenario("run image folder of bad images only", R("{fx}/allbad"), mention="allbad"),
        Scenario("run empty folder", R("{fx}/emptydir"), mention="emptydir"),
        Scenario("run a text file", R("{fx}/notes.txt"), mention="notes.txt"),
        Scenario("run a missing path", R("{fx}/nothere.mp4"), mention="nothere"),
        Scenario("run synthetic clip --init-gt", R("{fx}/clip", "--init-gt", init=False), "ok",
                 check=track_has(20, 20)),
        Scenario("run clip, contour LS-N-IPS", R("{fx}/clip", "--init-gt", "--model", "contour", "--algo", "ls-n-ips",
                                                  init=False), "ok"),
        Scenario("run plate clip, no box", R("{fx}/plate", init=False), "ok", check=track_has(10, 10)),
        Scenario("run landmark clip", ["run", "{fx}/lm", "-n", "50", "--track", "{w}/t.csv", "-q"], "ok",
                 check=track_has(10, 10)),
        Scenario("run OTB folder --init-gt", R("{fx}/otb", "--init-gt", init=False), "ok", check=track_has(12, 12)),
        Scenario("run OTB folder whose ground truth is all absent, --init-gt", R("{fx}/otb_absent", "--init-gt",
                                                                                 init=False), mention="ground"),
        Scenario("run --max-frames 5", R("{fx}/v.avi", "--max-frames", "5"), "ok", check=track_has(5, 5)),
        Scenario("run --out annotated video", R("{fx}/v.avi", "--out", "{w}/a.mp4"), "ok"),
        Scenario("run --results OTB format", R("{fx}/v.avi", "--results", "{w}/r.txt"), "ok"),
    ]


def number_scenarios():
    base = R("{fx}/v.avi", init=False)
    init = [("nan,1,2,3", "--init"), ("10,10,inf,20", "--init"), ("10,10,-5,20", "--init"), ("10,10,0,0", "--init"),
            ("1e300,1,2,3", "--init"), ("1,2,3", "--init"), ("a,b,c,d", "--init"), ("500,500,20,20", "--init")]
    out = [Scenario(f"run --init {v}", base + ["--init", v], mention=m) for v, m in init]
    opts = [("-n", "0"), ("-n", "-5"), ("-n", "100000000"), ("-n", "nan"), ("--ess-threshold", "nan"),
            ("--ess-threshold", "-0.5"), ("--ess-threshold", "2"), ("--ess-threshold", "inf"), ("--seed", "-1"),
            ("--seed", "nan"), ("--max-frames", "0"), ("--max-frames", "-3"),
            ("--show-particles", "-1")]
    out += [Scenario(f"run {o} {v}", sub(base + ["--init", INIT], o, v), mention=o.lstrip("-")[:4] if o != "-n"
                     else "partic") for o, v in opts]
    out += [Scenario("run --seed 2**64 (any non-negative integer seeds numpy)",
                     sub(base + ["--init", INIT], "--seed", str(2**64)), "either")]
    out += [
        Scenario("run --show-particles 1000000 (more than N)", R("{fx}/v.avi", "--show-particles", "1000000",
                                                                  "--out", "{w}/a.mp4"), "either"),
        Scenario("run --template with NaN", R("{fx}/v.avi", "--model", "contour", "--template",
                                              "{fx}/template_nan.txt"), mention="template"),
        Scenario("run --template garbage", R("{fx}/v.avi", "--model", "contour", "--template", "{fx}/garbage.txt"),
                 mention="garbage.txt"),
        Scenario("run --template missing", R("{fx}/v.avi", "--model", "contour", "--template", "{fx}/none.txt"),
                 mention="none.txt"),
        Scenario("run --init-gt missing file", R("{fx}/v.avi", "--init-gt", "{fx}/none.txt", init=False),
                 mention="none.txt"),
        Scenario("run --init-gt garbage file", R("{fx}/v.avi", "--init-gt", "{fx}/garbage.txt", init=False),
                 mention="garbage.txt"),
        Scenario("run --init-gt on a bare video", R("{fx}/v.avi", "--init-gt", init=False), mention="ground"),
        Scenario("run --model landmarks on a plain video", R("{fx}/v.avi", "--model", "landmarks", init=False),
                 mention="landmark"),
        Scenario("run --algo pf-eis with the box model", R("{fx}/v.avi", "--algo", "pf-eis"), mention="pf-eis"),
        Scenario("run --init and --init-gt together", R("{fx}/clip", "--init-gt"), "either"),
        Scenario("run --model box without a box", R("{fx}/v.avi", "--model", "box", init=False), mention="init"),
    ]
    return out


def output_scenarios():
    v = "{fx}/v.avi"
    return [
        Scenario("run --out annotated.txt", R(v, "--out", "{w}/annotated.txt"), "either"),
        Scenario("run --out annotated (no extension)", R(v, "--out", "{w}/annotated"), "either"),
        Scenario("run --out on a full disk", R(v, "--out", "{w}/full.mp4"), prepare=link("full.mp4")),
        Scenario("run --track on a full disk", R(v, "--track", "{w}/full.csv"), prepare=link("full.csv")),
        Scenario("run --results on a full disk", R(v, "--results", "{w}/full.txt"), prepare=link("full.txt")),
        Scenario("run --track to /dev/null", R(v, "--track", "/dev/null"), "ok"),
        Scenario("run --track to /dev/stdout", R(v, "--track", "/dev/stdout"), "ok",
                 check=lambda w, res: (None if res.out.startswith("frame,visible,")
                                       else ("silent wrong", "no CSV on stdout"))),
        Scenario("run --track into a missing folder", R(v, "--track", "{w}/no/t.csv"), mention="no"),
        Scenario("run --track is a folder", R(v, "--track", "{w}"), mention="director"),
        Scenario("run --out under a file", R(v, "--out", "{fx}/notes.txt/a.mp4"), mention="notes.txt"),
        Scenario("run --out is the input video", R("{w}/v.avi", "--out", "{w}/v.avi"), "either", prepare=copy("v.avi"),
                 check=input_intact("v.avi")),
        Scenario("run --track is the input video", R("{w}/v.avi", "--track", "{w}/v.avi"), "either",
                 prepare=copy("v.avi"), check=input_intact("v.avi")),
    ]


def interrupt_scenarios():
    slow = R("{fx}/v.avi", "--out", "{w}/a.mp4", init=False) + ["--init", INIT, "-n", "3000"]
    grid = sub(sub(EV("{w}/suite"), "--particles", "400"), "--runs", "3")
    grid.remove("--in-process")  # worker processes, which get the Ctrl-C too
    synth_over = ["synth", "contour", "--out", "c1", "--frames", "100000", "--size", "96x72", "-q", "--seed", "2"]

    def resumed(w, res, timeout):
        r = vistrack([a.format(w=w) for a in grid + ["--resume"]], w, timeout)
        if r.code != 0:
            res.note, res.lost = f"--resume after Ctrl-C failed: {r.err[-80:]}", True
        return res

    return [
        Scenario("run SIGINT mid-run", slow, "ok", codes=(130,), check=partial_track,
                 driver=interrupt(signal.SIGINT, _track_part_rows(4))),
        Scenario("run SIGTERM mid-run", slow, "ok", codes=(143,), check=partial_track,
                 driver=interrupt(signal.SIGTERM, _track_part_rows(4))),
        Scenario("run Ctrl-C on the process group", slow, "ok", codes=(130,), check=partial_track,
                 driver=interrupt(signal.SIGINT, _track_part_rows(4), group=True)),
        Scenario("run kill -9 mid-run", slow, "ok", codes=(-9,), check=killed_track,
                 driver=interrupt(signal.SIGKILL, _track_part_rows(4))),
        Scenario("eval Ctrl-C on the process group, then --resume", grid, "ok", codes=(130,), prepare=copy("suite"),
                 check=lost_if_flagged, driver=interrupt(signal.SIGINT, _has_task, group=True, then=resumed)),
        Scenario("eval SIGTERM mid-grid", grid, "either", codes=(143, 0), prepare=copy("suite"),
                 driver=interrupt(signal.SIGTERM, _has_task)),
        Scenario("eval kill -9 of a worker mid-grid", grid, "ok", prepare=copy("suite"), driver=kill_worker,
                 check=equals_fresh(sub(sub(sub(EV("{w}/suite"), "--particles", "400"), "--runs", "3"),
                                        "--out", "{w}/F"))),
        Scenario("synth SIGINT while overwriting a clip", synth_over, "ok", codes=(130,), prepare=old_clip,
                 check=clip_intact, driver=interrupt(signal.SIGINT, lambda w: any(w.glob(".c1.partial-*/video.mp4")))),
        Scenario("synth kill -9 while overwriting a clip", synth_over, "ok", codes=(-9,), prepare=old_clip,
                 check=clip_intact, driver=interrupt(signal.SIGKILL, lambda w: any(w.glob(".c1.partial-*/video.mp4")))),
        Scenario("reproduce bearings Ctrl-C on the process group", sub(sub(BE, "--runs", "200"), "--particles", "3000"),
                 "ok", codes=(130,),
                 driver=interrupt(signal.SIGINT, lambda w: (w / "B" / "tasks").is_dir(), group=True)),
    ]


def eval_scenarios():
    suite = "{fx}/suite"
    seed1 = EV("{w}/suite", "--seed", "1")
    return [
        Scenario("eval suite", EV(suite), "ok"),
        Scenario("eval suite, 2 worker processes", [a for a in EV(suite) if a != "--in-process"] + ["--workers", "2"],
                 "ok"),
        *[Scenario(f"eval {o} {v}", sub(EV(suite), o, v), mention=m) for o, v, m in [
            ("--particles", "0", "particles"), ("--particles", "-5", "particles"), ("--particles", "nan", "particles"),
            ("--runs", "0", "runs"), ("--runs", "-1", "runs"), ("--seed", "-1", "seed"), ("--workers", "-1", "workers"),
            ("--timeout", "0", "timeout"), ("--algos", "nope", "nope"), ("--model", "nope", "nope")]],
        Scenario("eval --particles 100000000", sub(EV(suite), "--particles", "100000000"), mention="partic"),
        Scenario("eval --algos '' without --results-dir", sub(EV(suite), "--algos", ""), mention="algos"),
        Scenario("eval --out is a file", sub(EV(suite), "--out", "{fx}/notes.txt"), mention="notes.txt"),
        Scenario("eval --out under a file", sub(EV(suite), "--out", "{fx}/notes.txt/R"), mention="notes.txt"),
        Scenario("eval --out on a full disk", EV(suite), prepare=lambda w: [(w / "R").mkdir(),
                                                                          (w / "R" / "results.json").symlink_to(
                                                                              "/dev/full")]),
        Scenario("eval --scheduler notaurl", EV(suite, "--scheduler", "notaurl"), mention="notaurl"),
        Scenario("eval unreachable scheduler keeps the old task files",
                 EV("{w}/suite", "--scheduler", "tcp://127.0.0.1:9", "--timeout", "2"), prepare=evald(["suite"]),
                 mention="scheduler", check=tasks_kept(2)),
        Scenario("eval two evals into one --out", EV(suite, "--seed", "2"), mention="in use", check=lost_if_flagged,
                 driver=two_evals(sub(sub(EV(suite, "--seed", "1"), "--particles", "300"), "--runs", "4"),
                                  EV(suite, "--seed", "2"))),
        Scenario("eval --resume after a seed change", sub(EV("{w}/suite", "--resume"), "--seed", "2"), "ok",
                 prepare=evald(["suite"], "--seed", "1"), check=equals_fresh(sub(sub(seed1, "--seed", "2"),
                                                                                  "--out", "{w}/F"))),
        Scenario("eval --resume with a {} task file", EV("{w}/suite", "--resume"), "ok", prepare=evald(
            ["suite"], then=_damage("{}")), check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval --resume with a cut task file", EV("{w}/suite", "--resume"), "ok", prepare=evald(
            ["suite"], then=_damage('{"clip": "c')), check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval --resume with a binary task file", EV("{w}/suite", "--resume"), "ok", prepare=evald(
            ["suite"], then=_damage(b"\\xff\\xfe\\x00")), check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval --resume after the clip changed", EV("{w}/suite", "--resume"), "ok", prepare=evald(
            ["suite"], then=_resynth), check=equals_fresh(sub(EV("{w}/suite"), "--out", "{w}/F"))),
        Scenario("eval a clip without ground truth", EV("{fx}/v.avi"), mention="ground truth"),
        Scenario("eval a missing path", EV("{fx}/nothere"), mention="nothere"),
        Scenario("eval an empty folder", EV("{fx}/emptydir"), mention="emptydir"),
        Scenario("eval OTB clip", EV("{fx}/otb", model="box"), "ok", check=consistent_absent),
        Scenario("eval OTB clip, grey images", EV("{fx}/otb_grey", model="box"), "ok"),
        Scenario("eval OTB absent frames as NaN", EV("{fx}/otb_nan", model="box"), "ok", check=consistent_absent),
        Scenario("eval OTB absent frames as 0,0,0,0", EV("{fx}/otb_zero", model="box"), "ok", check=consistent_absent),
        Scenario("eval ground truth shorter than the video", EV("{fx}/otb_short", model="box"), "ok",
                 check=warns("ground truth")),
        Scenario("eval ground truth longer than the video", EV("{fx}/otb_long", model="box"), "ok",
                 check=warns("ground truth")),
        Scenario("eval ground truth with negative sizes (absent)", EV("{fx}/otb_negative", model="box"), "ok",
                 check=consistent_absent),
        Scenario("eval malformed ground-truth line", EV("{fx}/otb_bad", model="box"), mention="line 6"),
        Scenario("eval ground truth all absent", EV("{fx}/otb_absent", model="box"), mention="ground truth"),
        Scenario("eval empty ground-truth file", EV("{fx}/otb_empty", model="box"), mention="ground truth"),
        Scenario("eval one undecodable image", EV("{fx}/otb_badimg", model="box"), "ok"),
        Scenario("eval --results-dir", EV("{w}/suite/c1", "--results-dir", "{w}/results"), "ok",
                 prepare=copy("suite", "results")),
        Scenario("eval --results-dir without a clip's file", EV("{fx}/suite", "--results-dir", "{fx}/results"),
                 mention="c2.txt"),
        Scenario("eval --results-dir with a garbage file", EV("{w}/suite/c1", "--results-dir", "{w}/badresults"),
                 mention="c1.txt", prepare=copy("suite", "badresults")),
        Scenario("eval --model plate on contour clips", EV(suite, model="plate"), "either"),
        Scenario("eval --model landmarks on contour clips", EV(suite, model="landmarks"), "either"),
        Scenario("eval --algos opencv-mil", sub(EV(suite), "--algos", "opencv-mil"), "ok"),
        Scenario("eval --equal-time", EV(suite, "--equal-time") + ["--algos", "bootstrap,lis"], "ok"),
    ]


def synth_scenarios():
    return [
        Scenario("synth contour", SY, "ok"),
        Scenario("synth contour over an existing clip", SY, "ok",
                 prepare=lambda w: shutil.copytree(FX / "clip", w / "c")),
        *[Scenario(f"synth {o} {v}", sub(SY, o, v), mention=m) for o, v, m in [
            ("--frames", "0", "frames"), ("--frames", "-1", "frames"), ("--size", "8x8", "8x8"),
            ("--size", "100000x100000", "100000"), ("--size", "nanxnan", "size"), ("--seed", "-1", "seed")]],
        Scenario("synth --size 3840x2160", sub(sub(SY, "--size", "3840x2160"), "--frames", "2"), "ok"),
        Scenario("synth --out is a file", sub(SY, "--out", "{fx}/notes.txt"), mention="notes.txt"),
        Scenario("synth --out under a file", sub(SY, "--out", "{fx}/notes.txt/c"), mention="notes.txt"),
        Scenario("synth --out under a device", sub(SY, "--out", "/dev/full/c"), mention="/dev/full"),
        Scenario("synth --out the current folder", sub(SY, "--out", "."), "either"),
        Scenario("synth plate --cars 0", ["synth", "plate", "--out", "{w}/p", "--frames", "3", "--cars", "0"],
                 mention="cars"),
        Scenario("synth plate --size 100x80", ["synth", "plate", "--out", "{w}/p", "--frames", "3", "--size", "100x80"],
                 mention="100x80"),
        Scenario("synth plate small", ["synth", "plate", "--out", "{w}/p", "--frames", "3", "--size", "160x120", "-q"],
                 "ok"),
        Scenario("synth landmarks --k 2", ["synth", "landmarks", "--out", "{w}/l", "--frames", "3", "--k", "2"],
                 mention="k"),
        *[Scenario(f"synth landmarks --occlusion {v}", ["synth", "landmarks", "--out", "{w}/l", "--frames", "3",
                                                        "--size", "128x96", "--occlusion", v], mention="occlusion")
          for v in ("nan", "2", "-1")],
        Scenario("synth landmarks --clutter-blobs -1", ["synth", "landmarks", "--out", "{w}/l", "--frames", "3",
                                                        "--clutter-blobs", "-1"], mention="clutter"),
        Scenario("synth-suite --clips 0", ["synth-suite", "--kind", "contour", "--clips", "0", "--out", "{w}/s"],
                 mention="clips"),
        Scenario("synth-suite plate 64x48", ["synth-suite", "--kind", "plate", "--clips", "1", "--frames", "2",
                                             "--size", "64x48", "--out", "{w}/s"], mention="64x48"),
        Scenario("synth-suite contour", ["synth-suite", "--kind", "contour", "--clips", "2", "--frames", "2",
                                         "--size", "96x72", "--out", "{w}/s", "-q"], "ok"),
    ]


def reproduce_scenarios():
    out = [Scenario("reproduce bearings", BE + ["--json", "{w}/b.json"], "ok")]
    out += [Scenario(f"reproduce bearings {o} {v}", sub(BE, o, v), mention=m) for o, v, m in [
        ("--runs", "0", "runs"), ("--runs", "-1", "runs"), ("--particles", "0", "particles"), ("--ships", "0", "ships"),
        ("--ships", "-1", "ships"), ("--steps", "0", "steps"), ("--sequences", "-1", "sequences"),
        ("--ess-threshold", "nan", "ess"), ("--algos", "nope", "nope"), ("--seed", "-1", "seed")]]
    out += [
        Scenario("reproduce bearings --json on a full disk", BE + ["--json", "{w}/full.json"],
                 prepare=link("full.json")),
        Scenario("reproduce bearings --json into a missing folder", BE + ["--json", "{w}/no/b.json"], mention="no"),
        Scenario("reproduce bearings --plots is a file", BE + ["--plots", "{fx}/notes.txt"], mention="notes.txt"),
        Scenario("reproduce contour --clips missing: made there",
                 ["reproduce", "contour", "--clips", "{w}/made", "--make", "1", "--frames", "3", "--size", "96x72",
                  "--algos", "lis:10", "--runs", "1", "--in-process", "--out", "{w}/C", "-q"], "ok"),
        Scenario("reproduce contour on two small clips", ["reproduce", "contour", "--clips", "{fx}/suite", "--algos",
                                                          "lis:20,bootstrap:40", "--runs", "1", "--in-process", "--out",
                                                          "{w}/C", "--json", "{w}/c.json", "-q"], "ok"),
        Scenario("reproduce contour --algos lis:0",
                 ["reproduce", "contour", "--clips", "{fx}/suite", "--algos", "lis:0", "--runs", "1", "--in-process",
                  "--out", "{w}/C", "-q"],
                 mention="lis:0"),
        Scenario("reproduce contour --frames 1", ["reproduce", "contour", "--clips", "{w}/none", "--frames", "1",
                                                  "--in-process", "--out", "{w}/C", "-q"], mention="frames"),
        Scenario("fit-plate a missing folder", ["fit-plate", "{fx}/nothere"], mention="nothere"),
        Scenario("fit-plate contour clips", ["fit-plate", "{fx}/suite"], mention="plate"),
        Scenario("unknown command", ["frobnicate"], mention="frobnicate"),
    ]
    return out


def sweep2_scenarios():
    """Issue 38: the second sweep's cases, numbered as in the issue."""
    v = "{fx}/v.avi"
    slow = ["run", "{fx}/v.avi", "--init", INIT, "-n", "3000", "--algo", "bootstrap", "--track", "{w}/t.csv",
            "--results", "{w}/r.txt", "--out", "{w}/a.mp4", "-q"]
    ready = _track_part_rows(4)

    def hard(name, target):
        return lambda w: (shutil.copy(FX / "v.avi", w / "in.avi"), os.link(w / "in.avi", w / name))

    def fifo(w):
        os.mkfifo(w / "fifo")

    def old_suite(w):
        r = vistrack(["synth-suite", "--kind", "contour", "--clips", "3", "--frames", "2", "--size", "96x72",
                      "--out", str(w / "s"), "-q"], w, 300)
        assert r.code == 0, r.err

    def intact(name):
        def check(w, res):
            return None if (w / name).read_bytes() == (FX / "v.avi").read_bytes() else \
                ("data loss", f"the input {name} was overwritten")

        return check

    out = [
        # 1, 2: data loss
        *[Scenario(f"#1 run {o} a hard link of the input", ["run", "{w}/in.avi", "--init", INIT, "-n", "50", o,
                                                            "{w}/h" + ext, "-q"], prepare=hard("h" + ext, "in.avi"),
                   mention="overwrite", check=intact("in.avi")) for o, ext in
          (("--out", ".avi"), ("--track", ".avi"), ("--results", ".avi"))],
        Scenario("#1 run --out a symbolic link of the input", ["run", "{w}/in.avi", "--init", INIT, "--out",
                                                               "{w}/s.avi", "-q"], mention="overwrite",
                 prepare=lambda w: (shutil.copy(FX / "v.avi", w / "in.avi"), (w / "s.avi").symlink_to(w / "in.avi")),
                 check=intact("in.avi")),
        Scenario("#2 two runs, one --track at once", R("{fx}/otb", "--init-gt", init=False), mention="another vistrack",
                 check=lost_if_flagged, driver=two_runs(["run", "{fx}/long.avi", "--init", INIT, "-n", "20000",
                                                         "--algo", "bootstrap", "--track", "{w}/t.csv", "-q"])),
        # 3-5: tracebacks
        Scenario("#3 run image folder whose frames change size, --out", R("{fx}/sizes", "--out", "{w}/a.mp4"),
                 mention="0004.png"),
        Scenario("#3 run image folder whose frames change size", R("{fx}/sizes"), mention="0004.png"),
        Scenario("#4 run --init 0,0,1e12,1e12 (box)", R(v, init=False) + ["--init", "0,0,1e12,1e12"], mention="larger"),
        Scenario("#4 run --init 0,0,1e12,1e12 (contour)", R(v, "--model", "contour", init=False)
                 + ["--init", "0,0,1e12,1e12"], mention="larger"),
        Scenario("#5 run meta.json [1,2,3]", R("{fx}/meta_list"), mention="meta.json"),
        Scenario("#5 run meta.json \"hello\"", R("{fx}/meta_str"), mention="meta.json"),
        Scenario("#5 eval meta.json [1,2,3]", EV("{fx}/meta_list", model="box"), mention="meta.json"),
        Scenario("#5 eval --results-dir a/mt --results-dir b/mt", EV("{fx}/suite/c1", "--results-dir", "{fx}/rd_a/mt",
                                                                     "--results-dir", "{fx}/rd_b/mt"),
                 mention="same name"),
        # 6-13: silent wrong output
        Scenario("#6 run 12 undecodable frames of 40, --results", R("{fx}/bad12", "--results", "{w}/r.txt"), "ok",
                 check=all_of(track_accounts(40, 12), results_lines(40, 12))),
        Scenario("#7 eval --results-dir shorter than the ground truth", EV("{fx}/suite/c1", "--results-dir",
                                                                           "{fx}/rd_short/mt"), "ok",
                 check=warns("6 lines for the 10")),
        Scenario("#8 run SIGINT once: track, video, results", slow, "ok", codes=(130,), check=same_frames,
                 driver=signals([signal.SIGINT], ready)),
        Scenario("#8 run SIGINT twice: track, video, results", slow, "ok", codes=(130,), check=same_frames,
                 driver=signals([signal.SIGINT, signal.SIGINT], ready)),
        Scenario("#8 run Ctrl-C twice on the process group", slow, "ok", codes=(130,), check=same_frames,
                 driver=signals([signal.SIGINT, signal.SIGINT], ready, group=True)),
        Scenario("#8 run SIGTERM: track, video, results", slow, "ok", codes=(143,), check=same_frames,
                 driver=signals([signal.SIGTERM], ready)),
        Scenario("#8 run SIGTERM early: track, video, results", slow, "ok", codes=(143,), check=same_frames,
                 driver=signals([signal.SIGTERM], _track_part_rows(2))),
        Scenario("#8 run SIGTERM then SIGINT", slow, "ok", codes=(143,), check=same_frames,
                 driver=signals([signal.SIGTERM, signal.SIGINT], ready)),
        Scenario("#9 run --init-gt, ground truth absent in frames 0-3", R("{fx}/otb_late", "--init-gt", "--results",
                                                                          "{w}/r.txt", init=False), "ok",
                 check=all_of(says("tracking starts there"), results_lines(12, first_zero=4))),
        Scenario("#10 run frames frame1..frame12", R("{fx}/natural", "--out", "{w}/a.mp4", "--show-particles", "0",
                                                     init=False) + ["--init", "60,50,21,17"], "ok",
                 check=natural_order),
        Scenario("#11 synth-suite over an earlier, larger suite", ["synth-suite", "--kind", "contour", "--clips", "2",
                                                                   "--frames", "2", "--size", "96x72", "--seed", "5",
                                                                   "--out", "{w}/s", "-q"], "ok", prepare=old_suite,
                 check=suite_holds(["contour-05", "contour-06"])),
        Scenario("#11 synth --out a folder holding an OTB clip", sub(SY, "--out", "{w}/otb"), mention="not a clip",
                 prepare=copy("otb")),
        Scenario("#12 run avi cut at 60 % says it ended early", R("{fx}/trunc.avi"), "ok", check=warns("ended early")),
        Scenario("#13 eval --results-dir named lis", EV("{fx}/suite/c1", "--results-dir", "{fx}/rd_lis/lis"),
                 mention="named like"),
        Scenario("#13 eval --equal-time on a 1-frame clip", EV("{fx}/one_frame", "--equal-time", model="box")
                 + ["--algos", "lis,bootstrap"], mention="at least 3"),
        Scenario("#13 eval --particles 100,100", sub(EV("{fx}/suite"), "--particles", "100,100"), mention="twice"),
        Scenario("#13 eval --algos lis,lis", sub(EV("{fx}/suite"), "--algos", "lis,lis"), mention="twice"),
        Scenario("#13 synth --size 321x241", sub(SY, "--size", "321x241"), mention="even"),
        Scenario("#13 run ground-truth box 1e300", R("{fx}/otb_huge", "--init-gt", init=False), mention="line 2",
                 check=short_error()),
        Scenario("#13 synth plate --frames 3 --size 160x120", ["synth", "plate", "--out", "{w}/p", "--frames", "3",
                                                               "--size", "160x120", "-q"], "ok",
                 check=warns("no plate")),
        Scenario("#13 demo --real-frames 60 on a 12-frame clip", ["demo", "--out", "{w}/d", "--frames", "10", "--runs",
                                                                  "1", "--real-clip", "{fx}/otb", "--real-frames",
                                                                  "60"], "ok", check=says("all 12 frames")),
        # 14: wording
        Scenario("#14 run /dev/zero", R("/dev/zero"), mention="not a regular file"),
        Scenario("#14 run a FIFO", R("{w}/fifo"), mention="not a regular file", prepare=fifo),
        Scenario("#14 run --init with 1 px inside the frame", R(v, init=False) + ["--init", "159,119,30,30"],
                 mention="outside"),
        Scenario("#14 run binary ground truth", R("{fx}/otb_binary", "--init-gt", init=False),
                 mention="groundtruth_rect.txt"),
        Scenario("#14 run --template of 4 points, one NaN", R(v, "--model", "contour", "--template",
                                                              "{fx}/template_nan4.txt"),
                 mention="finite"),
        Scenario("#14 run ground truth with a UTF-8 BOM", R("{fx}/otb_bom", "--init-gt", init=False), "ok",
                 check=track_has(12, 12)),
        Scenario("#14 synth --size 8192x2048", sub(SY, "--size", "8192x2048"), mention="8190"),
        Scenario("#14 eval --out E where E/tasks is a file", sub(EV("{fx}/suite"), "--out", "{w}/E"), mention="tasks",
                 check=fast(20), prepare=lambda w: ((w / "E").mkdir(), (w / "E" / "tasks").write_text("x"))),
    ]
    return out


def scenarios():
    import soak_sweep3

    return (video_scenarios() + number_scenarios() + output_scenarios() + interrupt_scenarios() + eval_scenarios()
            + synth_scenarios() + reproduce_scenarios() + sweep2_scenarios()
            + soak_sweep3.scenarios(sys.modules[__name__]))


# ---------------------------------------------------------------- main


def main():
    global FX
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", default="", help="Run the scenarios whose name contains this.")
    ap.add_argument("--keep", help="Work in this folder and keep it (default: a temporary folder, removed).")
    ap.add_argument("--timeout", type=float, default=180, help="Seconds before a scenario counts as a hang.")
    args = ap.parse_args()
    base = Path(args.keep or tempfile.mkdtemp(prefix="vistrack-soak-")).resolve()
    base.mkdir(parents=True, exist_ok=True)
    FX = base / "fixtures"
    if not FX.is_dir():
        build_fixtures(FX)
    chosen = [s for s in scenarios() if args.only.lower() in s.name.lower()]
    totals = dict.fromkeys(OUTCOMES, 0)
    print("| # | scenario | command | exit | outcome | note |\n|---|---|---|---|---|---|", flush=True)
    t0 = time.time()
    try:
        for k, sc in enumerate(chosen, 1):
            work = base / "work"
            shutil.rmtree(work / re.sub(r"[^A-Za-z0-9_.-]", "_", sc.name), ignore_errors=True)
            work.mkdir(exist_ok=True)
            try:
                argv, res, outcome, note = run_scenario(sc, work, FX, args.timeout)
            except Exception as e:  # noqa: BLE001  (a bug of this script: say so, go on)
                argv, res, outcome, note = sc.argv, Result(None, "", "", 0.0), "harness error", repr(e)[:100]
            if sc.awaits and outcome in BAD + ("misleading error",):
                outcome = f"{outcome}, awaits {sc.awaits}"
            totals[outcome] = totals.get(outcome, 0) + 1
            wdir = str(work / re.sub(r"[^A-Za-z0-9_.-]", "_", sc.name))
            cmd = " ".join(a.replace(wdir, "W").replace(str(FX), "FX") for a in argv)
            cell = (note or "").replace("|", "/").replace("\n", " ")
            print(f"| {k} | {sc.name} | `{cmd}` | {res.code} | {outcome} | {cell} |", flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(base, ignore_errors=True)
    print(f"\n{len(chosen)} scenarios in {time.time() - t0:.0f} s: "
          + ", ".join(f"{n} {o}" for o, n in totals.items() if n or o in OUTCOMES))
    bad = BAD
    print("failures: " + ", ".join(f"{totals.get(o, 0)} {o}" for o in bad)
          + f" ({sum(totals.get(o, 0) for o in bad)} of {len(chosen)} scenarios)")


if __name__ == "__main__":
    main()
