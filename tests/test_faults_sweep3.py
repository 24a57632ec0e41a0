"""Issue 47, the third sweep: outputs replaced only by complete files (1), sizes checked before
work starts (2), the Python API as careful as the CLI (3), TraX and start-up (4), run's summary
scored as eval scores (6), the minor and wording cases (7). Each ends in one clear line or a
correct output; never a traceback, never an earlier output lost."""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import cv2
import numpy as np
import pytest
from test_faults_sweep2 import one_error

from cli_helpers import run

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from full_disk import Unavailable, on_tmpfs  # noqa: E402
from soak_sweep3 import INTERRUPT_AT, trax_session  # noqa: E402

H, W = 120, 160
INIT = "48,51,24,18"


def box_frame(i, w=W, h=H):
    img = np.full((h, w, 3), 100, np.uint8)
    img[::7] = 60  # texture: the encoder has something to write
    cv2.rectangle(img, (40 + i % 40, 50), (64 + i % 40, 68), (30, 60, 220), -1)
    return img


def avi(path, n, w=W, h=H):
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (w, h))
    for i in range(n):
        wr.write(box_frame(i, w, h))
    wr.release()
    return path


# ------------------------------------------------------------------ 1: outputs replaced only by complete files


def _tmpfs(steps, **kw):
    try:
        return on_tmpfs(steps, **kw)
    except Unavailable as e:
        pytest.skip(str(e))


def test_a_full_disk_keeps_the_earlier_video_and_leaves_no_unplayable_one(tmp_path):
    """df_old: ``run --out T/old.mp4`` over an earlier valid video on a 16 kB tmpfs that fills up: one
    line naming T/old.mp4 and the cause; the earlier video byte for byte. df_out: with no earlier file
    nothing is left under the final name, and the error names it (not the temporary file)."""
    short, long = avi(tmp_path / "short.avi", 3), avi(tmp_path / "long.avi", 120)
    run_ = ["run", "--init", INIT, "-n", "20", "-q"]
    first, over, new = _tmpfs([[*run_, "--out", "{T}/old.mp4", str(v)] for v in (short, long)]
                              + [[*run_, "--out", "{T}/a.mp4", str(long)]], size="16k")
    assert first["code"] == 0 and first["files"]["old.mp4"]["frames"] == 3, first
    one_error(over["code"], over["err"], "{T}/old.mp4", "No space left on device", "the earlier old.mp4 is kept")
    assert over["files"] == first["files"]
    one_error(new["code"], new["err"], "{T}/a.mp4", "No space left on device", "no a.mp4 was written")
    assert new["files"] == first["files"] and ".part" not in new["err"]


def test_a_full_disk_under_the_track_keeps_the_earlier_track_else_its_whole_rows(tmp_path):
    short, long = avi(tmp_path / "short.avi", 3), avi(tmp_path / "long.avi", 120)
    base = ["-n", "20", "-q", "--init", INIT, "--track", "{T}/t.csv", "--results", "{T}/r.txt"]
    first, second, alone = _tmpfs([["run", str(short), *base], ["run", str(long), *base, "--out", "/dev/null"],
                                   ["run", str(long), "--init", INIT, "-n", "20", "-q", "--track", "{T}/new.csv"]],
                                  size="16k")  # 4 pages: two files and their locks (a lock holds its pid)
    assert first["code"] == 0 and sorted(first["files"]) == ["r.txt", "t.csv"]
    one_error(second["code"], second["err"], "{T}/", "No space left on device", "is kept")
    assert second["files"] == first["files"]
    one_error(alone["code"], alone["err"], "{T}/new.csv", "No space left on device", "rows written before are kept")
    assert sorted(alone["files"]) == ["new.csv", "r.txt", "t.csv"] and 0 < alone["files"]["new.csv"]["size"] <= 4096


def _failing_flush(monkeypatch):
    """PyAV's flush fails as on a full disk (the container's last write)."""
    import av

    real = av.open

    def open_(*a, **kw):
        c = real(*a, **kw)
        if kw.get("format") == "mp4" or (len(a) > 1 and a[1] == "w"):
            return _Failing(c)
        return c

    monkeypatch.setattr(av, "open", open_)


class _Failing:
    def __init__(self, c):
        self._c = c

    def __getattr__(self, name):
        return getattr(self._c, name)

    def close(self):
        self._c.close()
        raise OSError(28, "No space left on device", "/somewhere/.a.part.mp4")


def test_the_video_writer_renames_only_after_a_successful_flush(tmp_path, monkeypatch):
    from vistrack.io.outputs import OutputError
    from vistrack.io.video_writer import VideoWriter

    out = tmp_path / "a.mp4"
    with VideoWriter(out, 25, (W, H), codec="h264", atomic=True) as w:
        w.write(box_frame(0))
    earlier = out.read_bytes()
    _failing_flush(monkeypatch)
    w = VideoWriter(out, 25, (W, H), codec="h264", atomic=True)
    for i in range(5):
        w.write(box_frame(i))
    with pytest.raises(OutputError) as e:
        w.close()
    assert str(e.value) == f"cannot write the annotated video {out}: No space left on device; the earlier a.mp4 is kept"
    assert e.value.filename == str(out) and e.value.errno == 28
    assert out.read_bytes() == earlier and sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4"]
    w = VideoWriter(tmp_path / "b.mp4", 25, (W, H), codec="h264", atomic=True)
    w.write(box_frame(0))
    with pytest.raises(OutputError, match="no b.mp4 was written"):
        w.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4"]


def test_opencvs_silent_writer_is_checked(tmp_path, monkeypatch):
    """OpenCV's writer says nothing when a write fails: a file that does not play back its frames
    is an error, not an output."""
    import vistrack.io.video_writer as vw
    from vistrack.io.outputs import OutputError

    out = tmp_path / "a.avi"
    with vw.VideoWriter(out, 25, (W, H), codec="auto", atomic=True) as w:
        for i in range(3):
            w.write(box_frame(i))
    earlier = out.read_bytes()
    real = cv2.VideoWriter

    class Lossy:  # drops every frame after the first, as on a full disk
        def __init__(self, *a):
            self._w, self._n = real(*a), 0

        def isOpened(self):
            return self._w.isOpened()

        def write(self, f):
            self._n += 1
            if self._n == 1:
                self._w.write(f)

        def release(self):
            self._w.release()

    monkeypatch.setattr(vw.cv2, "VideoWriter", Lossy)
    w = vw.VideoWriter(out, 25, (W, H), codec="auto", atomic=True)
    for i in range(6):
        w.write(box_frame(i))
    with pytest.raises(OutputError, match=f"cannot write the annotated video {out}: .*; the earlier a.avi is kept"):
        w.close()
    assert out.read_bytes() == earlier and sorted(p.name for p in tmp_path.iterdir()) == ["a.avi"]


def test_every_writer_keeps_the_earlier_file_on_a_failure(tmp_path, monkeypatch):
    """write_atomic (results.json, report.md, task files), the plots and the track CSV: a failed
    write removes the temporary file, keeps the earlier output and names it."""
    import vistrack.reports.plots as plots
    from vistrack.batch.tasks import write_atomic
    from vistrack.io.outputs import OutputError
    from vistrack.io.track_files import TrackCSV

    (tmp_path / "results.json").write_text("{}")
    real = Path.write_text

    def full(self, *a, **kw):
        real(self, "half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(OutputError, match=r"cannot write the file .*results.json: No space left on device; the "
                                          r"earlier results.json is kept"):
        write_atomic(tmp_path / "results.json", '{"a": 1}')
    monkeypatch.undo()
    assert (tmp_path / "results.json").read_text() == "{}"

    png = plots.plot_per_frame({"lis": [1.0, 2.0]}, tmp_path / "p.png", ylabel="e", title="t")
    earlier = png.read_bytes()
    monkeypatch.setattr("matplotlib.figure.Figure.savefig",
                        lambda self, f, **kw: (Path(f).write_bytes(b"x"), (_ for _ in ()).throw(OSError(28, "full"))))
    with pytest.raises(OutputError, match="cannot write the plot .*p.png: full; the earlier p.png is kept"):
        plots.plot_per_frame({"lis": [1.0, 3.0]}, png, ylabel="e", title="t")
    assert png.read_bytes() == earlier

    (tmp_path / "t.csv").write_text("frame,cx\n0,1.000\n")
    t = TrackCSV(tmp_path / "t.csv")
    t.write({"frame": 0, "cx": 5.0})
    t._f.flush = lambda: (_ for _ in ()).throw(OSError(28, "No space left on device"))
    with pytest.raises(OutputError, match="cannot write the track file .*t.csv: No space left on device; the "
                                          "earlier t.csv is kept"):
        t.write({"frame": 1, "cx": 6.0})
    t.close()
    assert (tmp_path / "t.csv").read_text() == "frame,cx\n0,1.000\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.png", "results.json", "t.csv"]


# ------------------------------------------------------------------ 2: every size checked before work starts


def test_the_task_grid_is_checked_against_memory_known_answers():
    from vistrack.evaluation.experiment import TASK_BYTES, TASK_FRAME_BYTES, check_grid_size
    from vistrack.system.resources import TooLarge

    each = TASK_BYTES + TASK_FRAME_BYTES * 100
    room = 2 * each * 1000  # half of it holds 1000 tasks
    assert check_grid_size(2, [("lis", 10), ("bootstrap", 10)], 250, 100, available=room) == 1000
    with pytest.raises(TooLarge, match=r"a grid of 1004 tasks \(2 clip\(s\) x 2 algorithm and N pair\(s\) x 251 "
                                       r"run\(s\)\) needs about .* give at most 250 runs"):
        check_grid_size(2, [("lis", 10), ("bootstrap", 10)], 251, 100, available=room)
    # a deterministic OpenCV tracker runs once, whatever --runs; MIL (randomised inside OpenCV) runs --runs times
    assert check_grid_size(2, [("lis", 10), ("opencv-kcf", 1)], 499, 100, available=room) == 1000
    assert check_grid_size(2, [("lis", 10), ("opencv-mil", 1)], 250, 100, available=room) == 1000


@pytest.mark.parametrize("argv, words", [
    (["eval", "{clip}", "--algos", "lis", "--particles", "20", "--runs", "100000000", "--workers", "1", "--out",
      "{d}/E"], ["a grid of 100000000 tasks", "give at most"]),
    (["synth-suite", "--kind", "contour", "--clips", "1000000000000", "--frames", "1", "--size", "64x48", "--out",
      "{d}/S"], ["1000000000000 clips of 1 frames at 64x48 need about", "free on", "give at most"]),
    (["run", "{noise}", "--targets", "100000", "--track", "{d}/t.csv"], ["of 100000 targets need about"]),
    (["run", "{noise}", "--targets", "1000", "--track", "{d}/t.csv"],
     ["--targets 1000: a 160x120 frame holds at most 96 plates"]),
    (["reproduce", "bearings", "--steps", "1000000000", "--runs", "2", "--sequences", "2", "--particles", "50",
      "--in-process", "--out", "{d}/B"], ["1000000000 steps", "give at most"]),
    (["reproduce", "landmarks", "--steps", "1000000000", "--runs", "2", "--in-process", "--out", "{d}/L"],
     ["1000000000 steps", "give at most"]),
    (["reproduce", "contour", "--runs", "100000000", "--clips", "{d}/made", "--make", "2", "--frames", "3", "--size",
      "96x72", "--in-process", "--out", "{d}/C"], ["a grid of 400000000 tasks"]),
], ids=["eval-runs", "synth-suite-clips", "run-targets-memory", "run-targets-sense", "bearings-steps",
        "landmarks-steps", "reproduce-runs"])
def test_sizes_are_checked_before_work_starts(tmp_path, argv, words):
    """Issue 47's unbounded-memory cases: one line naming the size and what fits, at once; nothing
    made (no results folder, no clip)."""
    from vistrack.data_synth.contour_clip import make_contour_clip

    clip = tmp_path / "clip"
    make_contour_clip(clip, frames=3, size=(96, 72), seed=1, clutter="low", distractor=False)
    noise = tmp_path / "noise" / "img"
    noise.mkdir(parents=True)
    rng = np.random.default_rng(0)
    for i in range(3):
        cv2.imwrite(str(noise / f"{i + 1:04d}.png"), rng.integers(0, 255, (H, W, 3), dtype=np.uint8))
    before = sorted(p.name for p in tmp_path.iterdir())
    code, _, err = run([a.format(d=tmp_path, clip=clip, noise=noise.parent) for a in argv])
    one_error(code, err, *words)
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_large_suite_is_named_lazily(tmp_path):
    """A suite's names are a range, not a list: a billion of them cost nothing, and an earlier
    suite's other clips are found by them all the same."""
    from vistrack.data_synth.scene import SuiteNames, prepare_suite

    names = SuiteNames("contour", 5, 10**9)
    assert len(names) == 10**9 and "contour-05" in names and "contour-1000000004" in names
    assert "contour-04" not in names and "contour-1000000005" not in names and "contour-5" not in names
    assert "plate-07" not in names and list(SuiteNames("plate", 9, 3)) == ["plate-09", "plate-10", "plate-11"]
    out = tmp_path / "s"
    from vistrack.data_synth.contour_clip import make_contour_clip

    for s in (1, 2, 7):
        make_contour_clip(out / f"contour-{s:02d}", frames=2, size=(96, 72), seed=s, clutter="low", distractor=False)
    assert prepare_suite(out, SuiteNames("contour", 2, 10**9)) == ["contour-01"]
    assert sorted(p.name for p in out.iterdir()) == ["contour-02", "contour-07"]


# ------------------------------------------------------------------ 3: the Python API as careful as the CLI


@pytest.mark.parametrize("kw, words", [
    (dict(seed=-1), "seed must be an integer >= 0"),
    (dict(seed=1.5), "seed must be an integer >= 0"),
    (dict(particles=2.5), "particles must be an integer >= 1, got 2.5"),
    (dict(particles=0), "particles must be an integer >= 1, got 0"),
    (dict(ess_threshold=float("nan")), "ess_threshold must be a number in [0, 1]"),
    (dict(ess_threshold=-1), "ess_threshold must be a number in [0, 1]"),
    (dict(ess_threshold=5), "ess_threshold must be a number in [0, 1]"),
    (dict(resample="best"), "unknown resampling scheme 'best'; choose from"),
    (dict(frobnicate=3), "unknown option 'frobnicate' for the box model; its options include"),
    (dict(model="plate", frobnicate=3), "unknown option 'frobnicate' for the plate model; its options include"),
], ids=lambda v: str(v)[:30])
def test_the_tracker_checks_every_argument_when_it_is_made(kw, words):
    import vistrack

    with pytest.raises(ValueError) as e:
        vistrack.Tracker(**kw)
    assert words in str(e.value) and "\n" not in str(e.value)


def test_the_tracker_names_the_options_it_takes():
    import vistrack

    with pytest.raises(ValueError, match="lambda_dcf, lambda_scale, lean_when_lost, lost_confidence, map_stride"):
        vistrack.Tracker(frobnicate=3)
    vistrack.Tracker(lambda_dcf=30.0, lambda_template=2.0)  # the model's own and its appearance's


def _api_frames(n=5):
    out = []
    for k in range(n):
        f = np.full((90, 120, 3), 50, np.uint8)
        f[::6] = 80
        cv2.rectangle(f, (30 + 2 * k, 30), (54 + 2 * k, 54), (40, 60, 230), -1)
        out.append(f)
    return out


def _api_track(frames, box=(30, 30, 25, 25)):
    import vistrack

    t = vistrack.Tracker(seed=3, particles=50)
    t.init(frames[0], box)
    return [t.box_estimate] + [t.update(f) and t.box_estimate for f in frames[1:]]


@pytest.mark.parametrize("convert", [
    lambda f: f.astype(np.float64) / 255, lambda f: f.astype(np.float32), lambda f: f.astype(np.uint16) * 257,
    lambda f: f.astype(np.int64), lambda f: f.tolist(), lambda f: cv2.cvtColor(f, cv2.COLOR_BGR2BGRA),
], ids=["float 0..1", "float 0..255", "uint16", "int64", "nested lists", "BGRA"])
def test_the_tracker_takes_any_reasonable_frame(convert):
    """Frames a user may pass are converted once into the uint8 BGR frame run decodes: the same track."""
    frames = _api_frames()
    assert _api_track([convert(f) for f in frames]) == _api_track(frames)


def test_the_tracker_takes_grey_frames_of_one_channel():
    grey = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in _api_frames()]
    assert _api_track([g[:, :, None] for g in grey]) == _api_track(grey)


@pytest.mark.parametrize("frame, words", [
    (np.ones((90, 120), bool), "dtype bool"),
    (np.ones((90, 120), complex), "dtype complex128"),
    (np.full((90, 120), np.nan), "NaN"),
    (np.full((90, 120), 300, np.int64), "values in 0..255"),
    (np.full((90, 120), -1.0), "values in 0..1 or 0..255"),
    (np.zeros((90, 120, 2), np.uint8), "shape (90, 120, 2)"),
    (np.zeros((2, 90, 120, 3), np.uint8), "shape (2, 90, 120, 3)"),
    (np.zeros((0, 120, 3), np.uint8), "shape (0, 120, 3)"),
    ([[1, 2], [3]], "ragged"),
    ("frame.png", "dtype <U9"),
], ids=["bool", "complex", "nan", "int over 255", "negative", "2 channels", "4-d", "empty", "ragged", "text"])
def test_the_tracker_refuses_a_frame_it_cannot_read_with_one_line(frame, words):
    import vistrack

    with pytest.raises(ValueError) as e:
        vistrack.Tracker().init(frame, (30, 30, 25, 25))
    assert words in str(e.value) and "\n" not in str(e.value)


def test_a_frame_size_or_kind_change_after_init_is_an_error_as_in_run():
    import vistrack

    frames = _api_frames()
    t = vistrack.Tracker()
    t.init(frames[0], (30, 30, 25, 25))
    with pytest.raises(ValueError, match="this frame is 120x80 colour, but the tracker started on 120x90 colour"):
        t.update(frames[1][:80])
    with pytest.raises(ValueError, match="this frame is 120x90 grey, but the tracker started on 120x90 colour"):
        t.update(cv2.cvtColor(frames[1], cv2.COLOR_BGR2GRAY))
    ok, box = t.update(frames[1])  # the tracker goes on
    assert t.result.index == 1
    with pytest.raises(ValueError, match=r"box must be four numbers \(x, y, w, h\), got 3"):
        vistrack.Tracker().init(frames[0], (1, 2, 3))
    with pytest.raises(ValueError, match="box must be four numbers"):
        vistrack.Tracker().init(frames[0], "30,30,25,25")


# ------------------------------------------------------------------ 4: TraX and start-up


def _vistrack(argv, stdin=subprocess.DEVNULL, **kw):
    return subprocess.run([sys.executable, "-m", "vistrack.cli", *argv], stdin=stdin, capture_output=True, text=True,
                          timeout=120, **kw)


def test_trax_checks_its_options_before_the_hello():
    p = _vistrack(["trax", "--model", "nonsense"])
    assert p.stdout == "" and p.stderr.startswith("Error: unknown model 'nonsense'") and p.stderr.count("\n") == 1
    p = _vistrack(["trax", "--algo", "pf-eis"])
    assert p.stdout == "" and "does not run on the box model" in p.stderr and p.stderr.count("\n") == 1


@pytest.mark.parametrize("stdin", ["", "garbage\n", "@@TRAX:frame\n"], ids=["nothing", "garbage", "out of order"])
def test_trax_answers_an_absent_or_broken_client_with_one_line(stdin):
    pytest.importorskip("trax", reason="vot-trax is not installed")
    p = _vistrack(["trax"], stdin=None, input=stdin)
    assert p.returncode == 1 and p.stdout.startswith("@@TRAX:hello")
    assert p.stderr.startswith("Error: no TraX client") and p.stderr.count("\n") == 1, p.stderr


@pytest.mark.parametrize("case, words", [
    ("outside", "start box 500,500,10,10 lies outside the 120x90 frame"),
    ("missing", "cannot read the frame {d}/nothere.png: no such file"),
    ("size", "this frame is 120x80 colour, but the tracker started on 120x90 colour frames"),
])
def test_trax_session_errors_reach_the_client_and_no_traceback(tmp_path, case, words):
    pytest.importorskip("trax", reason="vot-trax is not installed")
    f = _api_frames(1)[0]
    cv2.imwrite(str(tmp_path / "f0.png"), f)
    cv2.imwrite(str(tmp_path / "f1.png"), f[:80])
    box = (500, 500, 10, 10) if case == "outside" else (30, 30, 25, 25)
    second = {"outside": None, "missing": tmp_path / "nothere.png", "size": tmp_path / "f1.png"}[case]
    code, err, heard = trax_session(tmp_path / "f0.png", box, second)
    words = words.format(d=tmp_path)
    assert isinstance(heard, str) and words in heard  # the client was told why
    assert code == 1 and err.startswith(f"Error: {words}") and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize("where", ["start-up", "shut-down"])
def test_ctrl_c_at_start_up_and_shut_down_is_aborted_and_130(where):
    p = subprocess.run([sys.executable, "-c", INTERRUPT_AT, where, "--version"], capture_output=True, text=True,
                       timeout=120)
    assert (p.returncode, p.stderr) == (130, "Aborted.\n")


def test_ctrl_c_while_trax_waits_for_its_client_is_aborted_and_130():
    pytest.importorskip("trax", reason="vot-trax is not installed")
    import signal

    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", "trax"], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.stdout.readline().startswith("@@TRAX:hello")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and err.strip() == "Aborted."


# ------------------------------------------------------------------ 6: run's summary scored as eval scores


def _otb_folder(folder, n, bad=()):
    (folder / "img").mkdir(parents=True)
    for i in range(n):
        img = box_frame(2 * i)
        cv2.imwrite(str(folder / "img" / f"{i + 1:04d}.png"), img)
    for i in bad:
        (folder / "img" / f"{i + 1:04d}.png").write_bytes(b"not a png")
    (folder / "groundtruth_rect.txt").write_text("".join(f"{41 + 2 * i},51,25,19\n" for i in range(n)))
    return folder


def test_run_summary_scores_an_undecodable_frame_as_eval_does(tmp_path):
    """run_summary_decode: one frame of 12 fails to decode; run's summary and eval --results-dir over
    the same results give the same success AUC, precision, lost frames and mean error."""
    import json
    import re

    seq = _otb_folder(tmp_path / "seq", 12, bad=[4])
    (tmp_path / "mt").mkdir()
    code, out, err = run(["run", seq, "--init-gt", "-n", "50", "--results", tmp_path / "mt" / "seq.txt"])
    assert code == 0, err
    line = next(ln for ln in out.splitlines() if ln.startswith("vs ground truth"))
    code, _, err = run(["eval", seq, "--algos", "", "--results-dir", tmp_path / "mt", "--out", tmp_path / "ev", "-q"])
    assert code == 0, err
    (r,) = json.loads((tmp_path / "ev" / "results.json").read_text())["results"]
    got = {k: float(re.search(pat, line).group(1)) for k, pat in (
        ("success_auc", r"success AUC ([0-9.]+)"), ("precision_20px", r"precision@20px ([0-9.]+)"),
        ("mean_error_all", r"mean centre error ([0-9.]+) px over all"),
        ("lost", r"lost by the ground truth \([^)]*\) in (\d+)"))}
    assert got["precision_20px"] == pytest.approx(r["precision_20px"], abs=1e-3) == 11 / 12
    assert got["lost"] / 12 == pytest.approx(r["p_lost"]) == 1 / 12
    assert got["success_auc"] == pytest.approx(r["success_auc"], abs=1e-3)
    assert got["mean_error_all"] == pytest.approx(r["mean_error_all"], abs=0.01)
    assert "but the 1 without an estimate" in line


def test_eval_scores_a_plate_clip_from_its_first_box_frame(tmp_path):
    """eval on a plate clip whose first 7 frames have no plate: the plate rule compares each frame's
    report with that frame's truth (the reports were 7 frames off: every frame lost, no mean error)."""
    import json

    from vistrack.data_synth.plate_clip import make_plate_clip

    make_plate_clip(tmp_path / "p", frames=40, size=(320, 240), seed=1, cars=1)
    code, _, err = run(["eval", tmp_path / "p", "--model", "plate", "--algos", "lis", "--particles", "50", "--runs",
                        "1", "--in-process", "--out", tmp_path / "ev", "-q"])
    assert code == 0, err
    (r,) = json.loads((tmp_path / "ev" / "results.json").read_text())["results"]
    assert r["p_lost"] < 0.6 and r["mean_error"] < 2.0, r["p_lost"]


# ------------------------------------------------------------------ 7: the minor and wording cases


def test_init_gt_with_missing_first_boxes_keeps_the_redetected_column(tmp_path):
    import csv

    seq = _otb_folder(tmp_path / "seq", 8)
    rows = (seq / "groundtruth_rect.txt").read_text().splitlines()
    (seq / "groundtruth_rect.txt").write_text("\n".join(["NaN,NaN,NaN,NaN"] * 3 + rows[3:]) + "\n")
    code, _, err = run(["run", seq, "--init-gt", "-n", "30", "-q", "--track", tmp_path / "t.csv"])
    assert code == 0, err
    with open(tmp_path / "t.csv", newline="") as f:
        track = list(csv.DictReader(f))
    assert list(track[0]) == ["frame", "visible", "cx", "cy", "w", "h", "angle_deg", "scale", "redetected", "ess", "ms",
                              "lost_reason", "confidence"]
    assert [r["lost_reason"] for r in track[:3]] == ["not started"] * 3
    assert {r["redetected"] for r in track[:3]} == {"0"}


def _perturb_source(tmp_path):
    return _otb_folder(tmp_path / "src", 10)


def test_perturb_gain_without_light_is_refused(tmp_path):
    from vistrack.data_synth.perturb import Perturbation

    code, _, err = run(["synth", "perturb", _perturb_source(tmp_path), "--out", tmp_path / "o", "--gain", "0.5:1"])
    one_error(code, err, "--gain sets the range of --light")
    assert not (tmp_path / "o").exists()
    assert Perturbation(light="ramp").gain == (0.3, 1.6) and Perturbation(blur=3).gain == (0.3, 1.6)


def test_perturb_marks_an_object_shaken_out_of_view_absent(tmp_path):
    from vistrack.data_synth.perturb import PerturbWarning

    with pytest.warns(PerturbWarning, match="moves the object wholly out of the frame in 10 of the 10 frames"):
        code, _, err = run(["synth", "perturb", _perturb_source(tmp_path), "--out", tmp_path / "o", "--shake", "1000",
                            "-q"])
    assert code == 0, err
    gt = np.loadtxt(tmp_path / "o" / "groundtruth_rect.txt", delimiter=",")
    assert np.all(gt == 0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PerturbWarning)
        code, _, err = run(["synth", "perturb", tmp_path / "src", "--out", tmp_path / "o6", "--shake", "6", "-q"])
    assert code == 0, err
    assert np.all(np.loadtxt(tmp_path / "o6" / "groundtruth_rect.txt", delimiter=",")[:, 2] > 0)


def test_perturb_overwrites_its_own_earlier_output(tmp_path):
    src = _perturb_source(tmp_path)
    for blur in ("3", "5"):
        code, _, err = run(["synth", "perturb", src, "--out", tmp_path / "o", "--blur", blur, "-q"])
        assert code == 0, err
    (tmp_path / "o" / "notes.txt").write_text("mine")
    code, _, err = run(["synth", "perturb", src, "--out", tmp_path / "o", "--blur", "7", "-q"])
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["groundtruth_rect.txt", "notes.txt", "perturb.json",
                                                                  "src.mp4"]
    import json

    assert json.loads((tmp_path / "o" / "perturb.json").read_text())["blur"] == 7


@pytest.mark.parametrize("gt, words", [
    ("1,1,0.5,0.5", "is smaller than 2 px (0.5x0.5)"),
    ("500,500,20,20", "lies outside the 160x120 frame"),
])
def test_a_tiny_ground_truth_box_is_called_tiny_not_outside(tmp_path, gt, words):
    seq = _otb_folder(tmp_path / "seq", 3)
    (seq / "groundtruth_rect.txt").write_text(f"{gt}\n" * 3)
    code, _, err = run(["run", seq, "--init-gt", "-q"])
    one_error(code, err, words)


def test_init_gt_given_a_folder_says_so(tmp_path):
    seq = _otb_folder(tmp_path / "seq", 3)
    code, _, err = run(["run", seq, "--init-gt", seq, "-q"])
    assert "does not exist" not in one_error(code, err, f"--init-gt: {seq} is a folder; give a ground-truth file")
