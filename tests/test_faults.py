"""Fault injection: interrupts, bad numbers, broken files. Each case ends in one clear error line
or a correct partial result: never a traceback, never exit 0 with NaN in an output."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time

import cv2
import numpy as np
import pytest

from cli_helpers import run

H, W = 120, 160


def write_video(path, n, seed=0):
    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.normal(110, 40, (H, W, 3)).astype(np.float32), (0, 0), 2).clip(0, 255).astype(np.uint8)
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (W, H))
    for t in range(n):
        f = bg.copy()
        cx, cy = int(60 + 20 * np.sin(0.1 * t)), int(60 + 10 * np.cos(0.1 * t))
        cv2.rectangle(f, (cx - 12, cy - 9), (cx + 12, cy + 9), (30, 60, 220), -1)
        wr.write(f)
    wr.release()


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"])
def test_signal_mid_run_keeps_the_track_so_far(tmp_path, sig, code):
    """``run`` stopped by Ctrl-C or SIGTERM: exit 130 / 143, the track CSV holds every frame done as
    whole rows (no ``.part`` left), the annotated video plays those frames, one line says so."""
    video = tmp_path / "v.avi"
    write_video(video, 300)
    track, out = tmp_path / "t.csv", tmp_path / "a.mp4"
    cmd = [sys.executable, "-m", "vistrack.cli", "run", str(video), "--init", "48,51,24,18", "-n", "3000",
           "--algo", "bootstrap", "--track", str(track), "--out", str(out), "-q"]
    # from tmp_path: run from the repository root, ``-m`` would import the source tree's ``vistrack/``
    # (which has no ``cli``: it is mapped from ``cli/`` at install) instead of the installed package
    # a shell's background job starts with SIGINT ignored, which Python keeps: give the child the default
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    part = tmp_path / "t.csv.part"
    deadline = time.time() + 60
    while time.time() < deadline and proc.poll() is None:
        if part.is_file() and part.read_text().count("\n") >= 4:
            break
        time.sleep(0.05)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == code, stderr
    assert "Traceback" not in stderr and "after" in stderr and str(track) in stderr
    rows = read_rows(track)
    assert 3 <= len(rows) < 300 and not part.exists()
    assert [int(r["frame"]) for r in rows] == list(range(len(rows)))
    assert all(np.isfinite(float(r["cx"])) for r in rows)
    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) >= len(rows) - 1


@pytest.mark.parametrize("args, message", [
    (["--init", "nan,1,2,3"], "expected four finite numbers"),
    (["--init", "10,10,inf,20"], "expected four finite numbers"),
    (["--init", "10,10,20,20", "-n", "100000000"], "particles need about"),
    (["--init", "10,10,20,20", "--ess-threshold", "nan"], "expected a number in [0, 1], got nan"),
    (["--init", "10,10,20,20", "--seed", "-1"], "-1 is not in the range"),
], ids=["init-nan", "init-inf", "n-huge", "ess-nan", "seed-negative"])
def test_bad_numbers_are_one_error_line(tmp_path, capsys, args, message):
    video = tmp_path / "v.avi"
    write_video(video, 3)
    with _no_warnings():
        code, out, err = run(["run", str(video), *args, "--track", str(tmp_path / "t.csv")], capsys)
    assert code != 0 and message in err and "Traceback" not in err
    assert err.count("Error:") == 1
    assert not (tmp_path / "t.csv").exists()


class _no_warnings:
    """No Python warning (numpy's RuntimeWarning on inf, ...) reaches the user."""

    def __enter__(self):
        import warnings

        self._cm = warnings.catch_warnings(record=True)
        self.caught = self._cm.__enter__()
        warnings.simplefilter("always")
        return self

    def __exit__(self, *exc):
        self._cm.__exit__(*exc)
        assert not self.caught, [str(w.message) for w in self.caught]


def test_particle_memory_check_known_answer():
    from vistrack.runtime import check_particle_memory

    assert check_particle_memory(1000, 32_000, "lis", available=2**30) == 32_000_000
    with pytest.raises(ValueError, match="use at most 2097"):  # half of 1 GiB / (32 KB x 8 for LLS)
        check_particle_memory(3000, 32_000, "lls", available=2**30)


def test_track_csv_is_whole_after_a_write_error(tmp_path):
    """A write error mid-run (disk full) leaves the rows written so far, renamed into place."""
    from vistrack.session import TrackCSV

    t = TrackCSV(tmp_path / "t.csv")
    t.write({"frame": 0, "cx": 1.0})
    t.write({"frame": 1, "cx": float("nan")})
    t._f.close()  # the disk goes away
    with pytest.raises(ValueError):
        t.write({"frame": 2, "cx": 3.0})
    t.close()
    rows = read_rows(tmp_path / "t.csv")
    assert [r["frame"] for r in rows] == ["0", "1"] and not (tmp_path / "t.csv.part").exists()


def test_truncated_and_empty_videos_are_clear_errors(tmp_path, capsys):
    video = tmp_path / "v.avi"
    write_video(video, 20)
    data = video.read_bytes()
    (tmp_path / "empty.avi").write_bytes(b"")
    (tmp_path / "head.avi").write_bytes(data[:200])
    for name in ("empty.avi", "head.avi"):
        code, _, err = run(["run", str(tmp_path / name), "--init", "48,51,24,18", "-q"], capsys)
        assert code != 0 and err.startswith("Error:") and "Traceback" not in err, (name, err)


def test_one_experiment_per_out_folder(tmp_path):
    """A second eval into a folder that a live process holds refuses with one line; a lock left by
    a dead process is taken over; the lock is gone after."""
    from vistrack.evaluation import OutLocked, lock_out

    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        import socket

        (tmp_path / ".vistrack.lock").write_text(f"{holder.pid}@{socket.gethostname()}")
        with pytest.raises(OutLocked, match=f"in use by another vistrack process .{holder.pid}@"):
            with lock_out(tmp_path):
                pass
    finally:
        holder.kill()
        holder.wait()
    with lock_out(tmp_path):  # the holder is dead: taken over
        with lock_out(tmp_path):  # re-entrant
            assert (tmp_path / ".vistrack.lock").read_text().startswith(f"{os.getpid()}@")
    assert not (tmp_path / ".vistrack.lock").exists()


def test_write_atomic_leaves_the_old_file_on_failure(tmp_path):
    from vistrack.evaluation import write_atomic

    p = tmp_path / "results.json"
    write_atomic(p, "old")

    class Boom:
        def __str__(self):
            raise RuntimeError

    with pytest.raises(TypeError):
        write_atomic(p, Boom())
    assert p.read_text() == "old" and [q.name for q in tmp_path.iterdir()] == ["results.json"]


def test_prefetch_gives_the_same_frames_and_stops_cleanly(tmp_path):
    import threading

    from vistrack.video import open_video, prefetch

    video = tmp_path / "v.avi"
    write_video(video, 30)
    src = open_video(video)
    direct = [(i, f.copy()) for i, f in src]
    ahead = list(prefetch(src, size=3))
    assert [i for i, _ in ahead] == [i for i, _ in direct]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(ahead, direct))
    gen = prefetch(src, size=2)
    next(gen)
    gen.close()  # stopping early ends the decoder thread
    time.sleep(0.3)
    assert not any(t.name == "vistrack-decode" for t in threading.enumerate())

    def broken():
        yield 0, direct[0][1]
        raise VideoError_("disk gone")

    class VideoError_(RuntimeError):
        pass

    with pytest.raises(VideoError_, match="disk gone"):
        list(prefetch(broken()))


def test_an_undecodable_image_is_skipped_and_counted(tmp_path, capsys):
    """One bad image in an image folder: tracking goes on at the next frame, the track has no row for
    the bad frame (indices stay the stream's), and the warning says how many were skipped."""
    import warnings

    from vistrack.video import VideoDecodeWarning, open_video

    (tmp_path / "img").mkdir()
    for i in range(8):
        img = np.full((H, W, 3), 100, np.uint8)
        cv2.rectangle(img, (40 + 2 * i, 50), (64 + 2 * i, 68), (30, 60, 220), -1)
        cv2.imwrite(str(tmp_path / "img" / f"{i + 1:04d}.jpg"), img)
    (tmp_path / "img" / "0004.jpg").write_bytes(b"\xff\xd8 not a jpeg")
    src = open_video(tmp_path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        idx = [i for i, _ in src]
    assert idx == [0, 1, 2, 4, 5, 6, 7] and src.skipped == [3]
    assert any(issubclass(w.category, VideoDecodeWarning) and "1 frame(s) of 8" in str(w.message) for w in caught)
    code, out, err = run(["run", str(tmp_path), "--init", "40,50,25,19", "--track", str(tmp_path / "t.csv")], capsys)
    assert code == 0, err
    assert [int(r["frame"]) for r in read_rows(tmp_path / "t.csv")] == [0, 1, 2, 4, 5, 6, 7]
    assert "failed to decode and were skipped" in err


def test_eval_keeps_frames_aligned_with_the_truth_past_a_bad_frame(tmp_path, capsys):
    """The bad frame counts as lost (no estimate) and the frames after it are scored against their own
    ground truth, not shifted by one."""
    import json

    (tmp_path / "clip" / "img").mkdir(parents=True)
    rows = []
    for i in range(8):
        img = np.full((H, W, 3), 100, np.uint8)
        cv2.rectangle(img, (40 + 2 * i, 50), (64 + 2 * i, 68), (30, 60, 220), -1)
        cv2.imwrite(str(tmp_path / "clip" / "img" / f"{i + 1:04d}.png"), img)
        rows.append(f"{41 + 2 * i},51,25,19")  # OTB: 1-based
    (tmp_path / "clip" / "img" / "0004.png").write_bytes(b"not a png")
    (tmp_path / "clip" / "groundtruth_rect.txt").write_text("\n".join(rows) + "\n")
    code, _, err = run(["eval", str(tmp_path / "clip"), "--model", "box", "--algos", "lis", "--particles", "50",
                        "--runs", "1", "--in-process", "--out", str(tmp_path / "ev"), "-q"], capsys)
    assert code == 0, err
    (task,) = [json.loads(p.read_text()) for p in (tmp_path / "ev" / "tasks").glob("*.json")]
    assert task["error"][3] is None and task["lost"][3] == 1
    assert all(e is not None and e < 3 for k, e in enumerate(task["error"]) if k != 3)


def _workers(pid):
    """The Dask worker processes a LocalCluster of process ``pid`` spawned."""
    import psutil

    procs = []
    for c in psutil.Process(pid).children():
        try:
            if "spawn_main" in " ".join(c.cmdline()):
                procs.append(c)
        except psutil.Error:
            pass
    return procs


def test_eval_worker_killed_mid_grid_gives_the_uninterrupted_results(tmp_path, capsys):
    """kill -9 of a worker process while the grid runs: the nanny replaces it, its task runs again from
    its own seed stream, and results.json equals an uninterrupted run's (but for the frame rates)."""
    import json

    from test_eval import strip_timing
    from vistrack.data_synth.contour import make_contour_clip

    make_contour_clip(tmp_path / "clips" / "c1", frames=12, size=(128, 96), seed=1, clutter="low", distractor=False)
    grid = ["eval", str(tmp_path / "clips"), "--algos", "lis,bootstrap", "--particles", "60", "--runs", "3",
            "--seed", "4", "-q"]
    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", *grid, "--workers", "2", "--out", "killed"],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        tasks, victim = tmp_path / "killed" / "tasks", None
        deadline = time.time() + 120
        while victim is None and proc.poll() is None and time.time() < deadline:
            if tasks.is_dir() and any(tasks.iterdir()):  # both workers are busy now: one finished, 5 tasks left
                victim = _workers(proc.pid)[0]
                victim.kill()
            time.sleep(0.02)
        assert victim is not None and len(list(tasks.iterdir())) < 6
        code, _, err = run([*grid, "--in-process", "--workers", "1", "--out", str(tmp_path / "whole")], capsys)
        assert code == 0, err
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 0 and "Traceback" not in err, err
    assert "note: 1 worker process(es) died and were replaced" in err
    whole = json.loads((tmp_path / "whole" / "results.json").read_text())
    assert strip_timing(json.loads((tmp_path / "killed" / "results.json").read_text())) == strip_timing(whole)


def _dies_every_time(task, out_dir):
    from types import SimpleNamespace

    from distributed import KilledWorker

    raise KilledWorker(f"vistrack-{task['name']}", SimpleNamespace(address="tcp://w:1"), 3)


def _disk_gone(task, out_dir):
    raise OSError(28, "No space left on device")


@pytest.mark.parametrize("runner, message", [
    (_dies_every_time, "task t1 ended the process of every worker that ran it (4; out of memory?)"),
    (_disk_gone, "task t1 failed: [Errno 28] No space left on device"),
], ids=["killed-worker", "oserror"])
def test_a_task_that_cannot_finish_is_one_error_line(tmp_path, runner, message):
    """Workers that keep dying on a task (dask's KilledWorker) or a task meeting a broken file: one
    line naming the task, the finished task files kept for --resume."""
    import click

    from vistrack.cli.eval import run_tasks

    with pytest.raises(click.ClickException) as e:
        run_tasks([{"name": "t1"}], tmp_path, workers=1, in_process=True, quiet=True, runner=runner)
    assert message in e.value.message and "--resume runs the rest" in e.value.message
    assert not (tmp_path / ".vistrack.lock").exists()


class _FakeClient:
    """``client.run`` on two workers, the second of which cannot see the paths ``hidden(path)`` says
    (a filesystem it does not share)."""

    def __init__(self, hidden):
        self.hidden = hidden

    def run(self, fn, probe, clips):
        missing = fn(probe, clips)
        return {"tcp://a:1": missing, "tcp://b:1": missing + [p for p in [probe, *clips] if self.hidden(p)]}


def test_workers_must_see_out_and_the_clips(tmp_path):
    """With a scheduler elsewhere, workers write into --out and read the clips at the tasks' paths:
    checked before the grid, one line naming what a worker cannot see; the probe file is removed."""
    from vistrack.tasks import TaskFailed, check_shared

    clip = tmp_path / "clip"
    clip.mkdir()
    tasks = [{"name": "t", "clip": str(clip)}]
    check_shared(_FakeClient(lambda p: False), tasks, tmp_path)
    with pytest.raises(TaskFailed, match=f"1 worker.s. of the scheduler .e.g. tcp://b:1. cannot see clip {clip}: "):
        check_shared(_FakeClient(lambda p: p == str(clip)), tasks, tmp_path)
    with pytest.raises(TaskFailed, match=f"cannot see --out {tmp_path}: --out and the clips must be on a filesystem"):
        check_shared(_FakeClient(lambda p: True), tasks, tmp_path)
    assert [p.name for p in tmp_path.iterdir()] == ["clip"]


def test_eval_through_an_external_scheduler(tmp_path, capsys):
    """--scheduler: the workers (here threads of a cluster started by the test) see --out and the
    clips, the check passes and the results are those of the built-in cluster."""
    import json

    from distributed import LocalCluster

    from test_eval import strip_timing
    from vistrack.data_synth.contour import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=6, size=(96, 72), seed=1, clutter="low", distractor=False)
    grid = ["eval", str(tmp_path / "c1"), "--algos", "bootstrap", "--particles", "20", "--runs", "2", "-q"]
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        code, _, err = run([*grid, "--scheduler", cluster.scheduler_address, "--out", str(tmp_path / "ext")], capsys)
    assert code == 0, err
    code, _, err = run([*grid, "--in-process", "--out", str(tmp_path / "own")], capsys)
    assert code == 0, err
    ext, own = (json.loads((tmp_path / d / "results.json").read_text()) for d in ("ext", "own"))
    assert strip_timing(ext) == strip_timing(own)
    assert not list(tmp_path.glob("ext/.vistrack-probe*"))


def _clip_bytes(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_a_failed_synth_leaves_the_old_clip_whole(tmp_path, monkeypatch):
    """The writer fails mid-clip (disk full) while a clip is overwritten: the old clip is intact,
    no partial folder is left, the user's own files in the folder survive a successful overwrite."""
    import vistrack.data_synth.contour as contour
    from vistrack.evaluation import find_clips

    clip = tmp_path / "suite" / "c1"
    kw = dict(frames=4, size=(96, 72), clutter="low", distractor=False)
    contour.make_contour_clip(clip, seed=1, **kw)
    (clip / "notes.txt").write_text("mine")
    old = _clip_bytes(clip)

    class Full(contour.VideoWriter):
        def write(self, frame):
            if self.frames == 2:
                raise OSError(28, "No space left on device")
            super().write(frame)

    monkeypatch.setattr(contour, "VideoWriter", Full)
    with pytest.raises(OSError, match="No space left"):
        contour.make_contour_clip(clip, seed=2, **kw)
    assert _clip_bytes(clip) == old
    assert [p.name for p in (tmp_path / "suite").iterdir()] == ["c1"] and find_clips([tmp_path / "suite"]) == [clip]
    monkeypatch.undo()
    contour.make_contour_clip(clip, seed=2, **kw)
    new = _clip_bytes(clip)
    assert new["notes.txt"] == b"mine" and new["groundtruth.csv"] != old["groundtruth.csv"]
    assert [p.name for p in (tmp_path / "suite").iterdir()] == ["c1"]
    with pytest.raises(ValueError, match="holds the current folder"):
        monkeypatch.chdir(clip)
        contour.make_contour_clip(".", seed=2, **kw)


def test_synth_killed_mid_clip_leaves_the_old_clip_and_no_clip_eval_takes(tmp_path, capsys):
    """kill -9 of ``vistrack synth`` overwriting a clip: the old video and ground truth are there, as
    they were; the partial render is a hidden folder that eval does not take for a clip, and the next
    synth into that folder removes it."""
    from vistrack.evaluation import find_clips

    clip = tmp_path / "c1"
    synth = ["synth", "contour", "--size", "96x72", "--clutter", "low", "--no-distractor", "-q"]
    code, _, err = run([*synth, "--frames", "3", "--out", str(clip)], capsys)
    assert code == 0, err
    old = _clip_bytes(clip)
    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", *synth, "--frames", "100000", "--seed", "2",
                             "--out", "c1"], cwd=tmp_path, stderr=subprocess.PIPE, text=True)
    partial = tmp_path / f".c1.partial-{proc.pid}" / "video.mp4"
    deadline = time.time() + 60
    while proc.poll() is None and time.time() < deadline and not (partial.is_file() and partial.stat().st_size):
        time.sleep(0.02)
    proc.kill()
    proc.communicate()
    assert partial.is_file() and _clip_bytes(clip) == old
    assert find_clips([tmp_path]) == [clip]
    code, _, err = run([*synth, "--frames", "3", "--seed", "3", "--out", str(clip)], capsys)
    assert code == 0 and "overwriting the clip" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c1"]
