"""The soak's machinery (:mod:`soak`): a :class:`Scenario` (a command, what it must give, its checks), the
fixtures it runs on, running one as a user would (``python -m vistrack.cli ...`` in a fresh folder) and
judging its outcome, the drivers (interrupts, two runs at once, a killed worker, a small tmpfs, a served
folder, a fresh interpreter) and the checks the scenario modules share (``soak_outputs``, ``soak_sizes``,
``soak_trax``, ``soak_api``, ``soak_data``, ``soak_options``, ``soak_tasks``). :data:`FX`, the fixtures'
folder, is set by :func:`soak.main` before any scenario runs.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
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
        m = NAN.search(text)  # every CSV cell is a number or empty (a plate clip's frames without a plate too)
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


def track_part_rows(n):
    return lambda w: _lines(w / "t.csv.part") > n


def has_task(w):
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
    if _wait_for(p, lambda: has_task(w), timeout):
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


def decoded_frames(path):
    """How many frames OpenCV decodes from ``path`` before its first failure."""
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
    v = decoded_frames(w / "a.mp4") if (w / "a.mp4").is_file() else 0
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


def results_follow_track(n):
    """``w/r.txt`` has ``n`` lines, one per input frame of the track ``w/t.csv``, and a line is ``0,0,0,0``
    exactly where the track does not report the object (``visible=0``: a frame that failed to decode, or
    one reported lost)."""

    def check(w, res):
        if res.code != 0:
            return None
        lines = (w / "r.txt").read_text().splitlines() if (w / "r.txt").is_file() else []
        rows = _rows(w / "t.csv") if (w / "t.csv").is_file() else []
        zeros = [set(ln.replace(",", "").replace(".", "")) <= {"0"} for ln in lines]
        if len(lines) != n or len(rows) != n:
            return "silent wrong", f"results have {len(lines)} lines, the track {len(rows)} rows, for {n} frames"
        wrong = [k for k, (z, r) in enumerate(zip(zeros, rows)) if z != (r["visible"] == "0")]
        if wrong:
            return "silent wrong", f"results lines {wrong[:5]} disagree with the track's visible column"
        res.note = f"{n} lines, {sum(zeros)} 0,0,0,0 (the frames not reported)"
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


def damage(text):
    def then(w):
        p = sorted((w / "R" / "tasks").glob("*.json"))[0]
        p.write_bytes(text if isinstance(text, bytes) else text.encode())

    return then


def resynth(w):
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(w / "suite" / "c1", frames=10, size=(128, 96), seed=9, clutter="low", distractor=False)


# ---------------------------------------------------------------- drivers: a small tmpfs, stdin, steps


def tmpfs(steps, size="48k"):
    """A driver: the steps (vistrack argument lists; ``{T}`` the tmpfs) on a tmpfs; the result is
    the last step's, with the record of every step (``res.steps``)."""

    def driver(w, argv, timeout):
        from full_disk import Unavailable, on_tmpfs

        t0 = time.time()
        runs = [[a.format(w=w, fx=FX, T="{T}") for a in step] for step in steps]
        try:
            record = on_tmpfs(runs, size=size, cwd=w, timeout=timeout)
        except Unavailable as e:
            return Result(None, "", "", time.time() - t0, skip=str(e))
        except subprocess.TimeoutExpired:
            return Result(None, "", "", time.time() - t0, timeout=True)
        last = record[-1]
        res = Result(last["code"], "", last["err"], time.time() - t0)
        res.steps = record
        return res

    return driver

def earlier_kept(name):
    """The first step wrote ``name``; after the failing last step it is there byte for byte, nothing
    else is left on the tmpfs, and the error names ``{T}/name``."""

    def check(w, res):
        first, last = res.steps[0], res.steps[-1]
        if first["code"] != 0 or name not in first["files"]:
            return "harness error", f"the earlier {name} was not written: {first['err'][-80:]}"
        if last["files"] != first["files"]:
            return "data loss", f"the tmpfs holds {sorted(last['files'])}, changed from {sorted(first['files'])}"
        if f"{{T}}/{name}" not in last["err"]:
            return "misleading error", f"the error does not name {name}: {last['err'][-100:]!r}"
        res.note = f"earlier {name} kept"
        return None

    return check

def nothing_left(names):
    """No earlier file: after the failing step the tmpfs holds only ``names`` (whole files)."""

    def check(w, res):
        files = res.steps[-1]["files"]
        if sorted(files) != sorted(names):
            return "silent wrong", f"the tmpfs holds {sorted(files)} (expected {sorted(names)})"
        broken = [n for n, f in files.items() if f["frames"] is not None and f["frames"] <= 0]
        if broken:
            return "silent wrong", f"{broken[0]} does not play"
        return None

    return check

def shown(steps):
    """The last step as the table shows it (the tmpfs as ``T``)."""
    return [a.replace("{T}", "T") for a in steps[-1]]

def clip_kept(w, res):
    first, last = res.steps
    if first["code"] != 0:
        return "harness error", f"the earlier clip was not written: {first['err'][-80:]}"
    if last["files"] != first["files"]:
        return "data loss", f"the tmpfs holds {sorted(last['files'])}, changed from {sorted(first['files'])}"
    return None

def stdin(text, env=None):
    """A driver: the command with ``text`` on its standard input (and ``env`` added to its environment)."""

    def driver(w, argv, timeout):
        t0 = time.time()
        try:
            p = subprocess.run([sys.executable, "-m", "vistrack.cli", *argv], cwd=w, input=text.format(w=w),
                               capture_output=True, text=True, timeout=timeout,
                               env={**os.environ, **(env or {})})
        except subprocess.TimeoutExpired as e:
            return Result(None, str(e.stdout or ""), str(e.stderr or ""), time.time() - t0, timeout=True)
        return Result(p.returncode, p.stdout, p.stderr, time.time() - t0)

    return driver

def two_steps(first, then_argv):
    def driver(w, argv, timeout):
        a = vistrack([x.format(w=w, fx=FX) for x in first], w, timeout)
        b = vistrack([x.format(w=w, fx=FX) for x in then_argv], w, timeout)
        b.steps = [a, b]
        if a.code != 0:
            b.code, b.err = a.code, a.err
        return b

    return driver

def damage_copy(copy, how):
    """Damage the file ``copy`` as a disk error or another program may: ``cut`` to 3000 bytes, 64 bytes
    ``changed`` in its middle, or replaced by ``a folder``."""
    data = copy.read_bytes()
    if how == "cut":
        copy.write_bytes(data[:3000])
    elif how == "changed":
        k = len(data) // 2
        copy.write_bytes(data[:k] + bytes(255 - b for b in data[k:k + 64]) + data[k + 64:])
    else:
        copy.unlink()
        copy.mkdir()


@contextmanager
def looping_server():
    """The URL of an HTTP server on 127.0.0.1 that redirects every path to itself, for the block."""
    import http.server
    import threading

    class Loop(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            self.send_response(302)
            self.send_header("Location", self.path)
            self.end_headers()

        def log_message(self, *a):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Loop)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


def after(seconds):
    t = []

    def ready(w):
        t.append(time.time())
        return t[-1] - t[0] >= seconds

    return ready
