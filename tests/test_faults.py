"""Fault injection: interrupts, bad numbers, broken files. Each case ends in one clear error line
or a correct partial result: never a traceback, never exit 0 with NaN in an output."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys

import cv2
import numpy as np
import pytest

from cli_helpers import run
from process_helpers import PATIENCE, TaskGate, gated_cli, wait_until

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
    write_video(video, 40)
    track, out = tmp_path / "t.csv", tmp_path / "a.mp4"
    args = ["run", str(video), "--init", "48,51,24,18", "-n", "300", "--algo", "bootstrap", "--track", str(track),
            "--out", str(out), "-q"]
    # the decoder waits before frame 8 until the signal is sent: the run cannot end before it
    proc = gated_cli(args, 8, tmp_path)
    part = tmp_path / "t.csv.part"
    wait_until(lambda: part.is_file() and part.read_text().count("\n") >= 4, "4 rows of the track", proc=proc)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=PATIENCE)  # closes its stdin: the decoder goes on
    assert proc.returncode == code, stderr
    assert "Traceback" not in stderr and "after" in stderr and str(track) in stderr
    rows = read_rows(track)
    assert 3 <= len(rows) < 40 and not part.exists()
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
    from vistrack.registry import check_particle_memory

    assert check_particle_memory(1000, 32_000, "lis", available=2**30) == 32_000_000
    with pytest.raises(ValueError, match="use at most 2097"):  # half of 1 GiB / (32 KB x 8 for LLS)
        check_particle_memory(3000, 32_000, "lls", available=2**30)


def test_track_csv_is_whole_after_a_write_error(tmp_path):
    """A write error mid-run (disk full) leaves the rows written so far, renamed into place."""
    from vistrack.session.recording import TrackCSV

    t = TrackCSV(tmp_path / "t.csv")
    t.write({"frame": 0, "cx": 1.0})
    t.write({"frame": 1, "cx": 2.0})
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
    from vistrack.batch.tasks import OutLocked, lock_out

    holder = subprocess.Popen([sys.executable, "-c", "import signal; signal.pause()"])  # alive until killed
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
    from vistrack.batch.tasks import write_atomic

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

    from vistrack.io.video import open_video, prefetch

    video = tmp_path / "v.avi"
    write_video(video, 30)
    src = open_video(video)
    direct = [(i, f.copy()) for i, f in src]
    ahead = list(prefetch(src, size=3))
    assert [i for i, _ in ahead] == [i for i, _ in direct]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(ahead, direct))
    before = set(threading.enumerate())
    gen = prefetch(src, size=2)
    next(gen)
    (decoder,) = [t for t in threading.enumerate() if t.name == "vistrack-decode" and t not in before]
    gen.close()  # stopping early ends the decoder thread: close() returns once it has ended
    assert not decoder.is_alive()

    def broken():
        yield 0, direct[0][1]
        raise VideoError_("disk gone")

    class VideoError_(RuntimeError):
        pass

    with pytest.raises(VideoError_, match="disk gone"):
        list(prefetch(broken()))


def test_an_undecodable_image_is_skipped_and_counted(tmp_path, capsys):
    """One bad image in an image folder: tracking goes on at the next frame, the bad frame has a row
    with visible=0, lost_reason "decode" (issue 38: every input frame accounted for; indices stay
    the stream's), and the warning says how many failed."""
    import warnings

    from vistrack.io.video import VideoDecodeWarning, open_video

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
    rows = read_rows(tmp_path / "t.csv")
    assert [int(r["frame"]) for r in rows] == list(range(8))
    assert (rows[3]["visible"], rows[3]["lost_reason"]) == ("0", "decode")
    assert "1 frame(s) failed to decode: 3 (their rows have visible=0" in err


def _moving_box_frames(folder, n=8):
    """``n`` OTB image frames of a red box moving 2 px per frame into ``folder``; returns their
    ground-truth lines (1-based ``x,y,w,h``)."""
    folder.mkdir(parents=True)
    rows = []
    for i in range(n):
        img = np.full((H, W, 3), 100, np.uint8)
        cv2.rectangle(img, (40 + 2 * i, 50), (64 + 2 * i, 68), (30, 60, 220), -1)
        cv2.imwrite(str(folder / f"{i + 1:04d}.png"), img)
        rows.append(f"{41 + 2 * i},51,25,19")  # OTB: 1-based
    return rows


def test_eval_keeps_frames_aligned_with_the_truth_past_a_bad_frame(tmp_path, capsys):
    """The bad frame counts as lost (no estimate) and the frames after it are scored against their own
    ground truth, not shifted by one."""
    import json

    rows = _moving_box_frames(tmp_path / "clip" / "img")
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

    from eval_helpers import strip_timing
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "clips" / "c1", frames=12, size=(128, 96), seed=1, clutter="low", distractor=False)
    grid = ["eval", str(tmp_path / "clips"), "--algos", "lis,bootstrap", "--particles", "60", "--runs", "3",
            "--seed", "4", "-q"]
    with TaskGate(tmp_path / "gate") as gate:  # the tasks wait at their start until the gate opens
        proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", *grid, "--workers", "2", "--out", "killed"],
                                cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=gate.env)
        try:
            wait_until(lambda: gate.started() >= 2, "both workers holding a task", proc=proc)
            holder = int(next(p for p in gate.folder.iterdir() if p.name.startswith("started-")).name.rsplit("-", 1)[1])
            victim = next(w for w in _workers(proc.pid) if w.pid == holder)
            victim.kill()
            gate.open()
            code, _, err = run([*grid, "--in-process", "--workers", "1", "--out", str(tmp_path / "whole")], capsys)
            assert code == 0, err
            _, err = proc.communicate(timeout=PATIENCE)
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

    from vistrack.batch.cluster import run_grid
    from vistrack.cli.progress import progress

    with pytest.raises(click.ClickException) as e, progress("tasks", quiet=True) as hooks:
        run_grid([{"name": "t1"}], tmp_path, workers=1, in_process=True, runner=runner, **hooks)
    assert message in e.value.message and "--resume runs the rest" in e.value.message
    assert not (tmp_path / ".vistrack.lock").exists()


class _FakeClient:
    """``client.run`` on two workers, the second of which cannot see the paths ``hidden(path)`` says
    (a filesystem it does not share)."""

    def __init__(self, hidden):
        self.hidden = hidden

    def run(self, fn, clips):
        missing = fn(clips)
        return {"tcp://a:1": missing, "tcp://b:1": missing + [p for p in clips if self.hidden(p)]}


def test_workers_must_see_the_clips(tmp_path):
    """With a scheduler elsewhere, workers read the clips at the tasks' paths: checked before the grid,
    one line naming what a worker cannot see (they need no --out: the results come back through Dask)."""
    from vistrack.batch.tasks import TaskFailed, check_shared

    clip = tmp_path / "clip"
    clip.mkdir()
    tasks = [{"name": "t", "clip": str(clip)}]
    check_shared(_FakeClient(lambda p: False), tasks)
    with pytest.raises(TaskFailed, match=f"1 worker.s. of the scheduler .e.g. tcp://b:1. cannot see clip {clip}: "):
        check_shared(_FakeClient(lambda p: p == str(clip)), tasks)
    assert [p.name for p in tmp_path.iterdir()] == ["clip"]


def test_eval_through_an_external_scheduler(tmp_path, capsys):
    """--scheduler: the workers (here threads of a cluster started by the test) see --out and the
    clips, the check passes and the results are those of the built-in cluster."""
    import json

    from distributed import LocalCluster

    from eval_helpers import strip_timing
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=6, size=(96, 72), seed=1, clutter="low", distractor=False)
    grid = ["eval", str(tmp_path / "c1"), "--algos", "bootstrap", "--particles", "20", "--runs", "2", "-q"]
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as cluster:
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
    import vistrack.data_synth.contour_clip as contour
    from vistrack.io.clips import find_clips

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
    from vistrack.io.clips import find_clips

    clip = tmp_path / "c1"
    synth = ["synth", "contour", "--size", "96x72", "--clutter", "low", "--no-distractor", "-q"]
    code, _, err = run([*synth, "--frames", "3", "--out", str(clip)], capsys)
    assert code == 0, err
    old = _clip_bytes(clip)
    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", *synth, "--frames", "100000", "--seed", "2",
                             "--out", "c1"], cwd=tmp_path, stderr=subprocess.PIPE, text=True)
    partial = tmp_path / f".c1.partial-{proc.pid}" / "video.mp4"
    wait_until(lambda: partial.is_file() and partial.stat().st_size, "a partial render", proc=proc)
    proc.kill()
    proc.communicate()
    assert partial.is_file() and _clip_bytes(clip) == old
    assert find_clips([tmp_path]) == [clip]
    code, _, err = run([*synth, "--frames", "3", "--seed", "3", "--out", str(clip)], capsys)
    assert code == 0 and "overwriting the clip" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c1"]


@pytest.mark.parametrize("outputs, message", [
    (["--out", "{v}"], "--out {v} would overwrite the input it reads (v.avi)"),
    (["--track", "{v}"], "--track {v} would overwrite the input it reads (v.avi)"),
    (["--track", "{d}/t.csv", "--results", "{d}/t.csv"], "--track and --results name the same file"),
], ids=["out-is-input", "track-is-input", "same-file"])
def test_run_outputs_never_overwrite_the_input(tmp_path, capsys, outputs, message):
    video = tmp_path / "v.avi"
    write_video(video, 3)
    before = video.read_bytes()
    args = [a.format(v=video, d=tmp_path) for a in outputs]
    code, _, err = run(["run", str(video), "--init", "48,51,24,18", *args], capsys)
    assert code != 0 and message.format(v=video) in err and err.count("Error:") == 1
    assert video.read_bytes() == before


def test_clip_files_are_inputs_too(tmp_path, capsys):
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c", frames=2, size=(96, 72), seed=1, clutter="low", distractor=False)
    gt = (tmp_path / "c" / "groundtruth.csv").read_bytes()
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "--track", str(tmp_path / "c" / "groundtruth.csv")],
                       capsys)
    assert code != 0 and "would overwrite the input it reads (groundtruth.csv)" in err
    assert (tmp_path / "c" / "groundtruth.csv").read_bytes() == gt
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "-q", "--track", str(tmp_path / "c" / "t.csv")],
                       capsys)
    assert code == 0, err  # another file in the clip folder is fine


def test_devices_are_written_directly_never_replaced(tmp_path):
    """``--track /dev/stdout`` and the like: the rows go to the device; the part-file-and-rename of a
    regular file would replace the device node (here a link to it stands for it)."""
    from vistrack.batch.tasks import write_atomic
    from vistrack.session.recording import TrackCSV

    for name in ("t.csv", "results.json"):
        (tmp_path / name).symlink_to("/dev/null")
    t = TrackCSV(tmp_path / "t.csv")
    t.write({"frame": 0, "cx": 1.0})
    t.close()
    write_atomic(tmp_path / "results.json", "{}")
    assert all((tmp_path / n).is_symlink() for n in ("t.csv", "results.json"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json", "t.csv"]
    (tmp_path / "full.csv").symlink_to("/dev/full")
    t = TrackCSV(tmp_path / "full.csv")
    with pytest.raises(OSError, match="No space left"):
        t.write({"frame": 0, "cx": 1.0})
    t.close()
    assert (tmp_path / "full.csv").is_symlink()


def test_eval_refuses_particles_beyond_memory_and_reports_unwritable_results(tmp_path, capsys):
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=3, size=(96, 72), seed=1, clutter="low", distractor=False)
    grid = ["eval", str(tmp_path / "c1"), "--algos", "bootstrap", "--runs", "1", "--in-process", "-q"]
    code, _, err = run([*grid, "--particles", "100000000", "--out", str(tmp_path / "big")], capsys)
    assert code != 0 and "100000000 particles need about" in err and err.count("Error:") == 1
    out = tmp_path / "R"
    out.mkdir()
    (out / "results.json").symlink_to("/dev/full")
    code, _, err = run([*grid, "--particles", "10", "--out", str(out)], capsys)
    assert code != 0 and err.startswith(f"Error: cannot write the results into {out}: No space left on device")
    assert "Traceback" not in err and len(list((out / "tasks").glob("*.json"))) == 1


def test_annotated_video_outputs(tmp_path, capsys):
    """--out without .mp4 is one line saying so; a disk that fills up under the annotated video
    (found when it is closed, after every frame) costs the video, never the track CSV; a full disk
    under the track CSV stops the run at once."""
    video = tmp_path / "v.avi"
    write_video(video, 6)
    base = ["run", str(video), "--init", "48,51,24,18", "-n", "20", "-q", "--track", str(tmp_path / "t.csv")]
    for name in ("annotated.txt", "annotated"):
        code, _, err = run([*base, "--out", str(tmp_path / name)], capsys)
        assert code != 0 and "give a file name ending in .mp4" in err and err.count("\n") == 1, err
    (tmp_path / "full.mp4").symlink_to("/dev/full")
    code, _, err = run([*base, "--out", str(tmp_path / "full.mp4")], capsys)
    assert code != 0 and err.startswith("Error: [Errno 28] No space left on device") and "Traceback" not in err
    assert len(read_rows(tmp_path / "t.csv")) == 6 and not (tmp_path / "t.csv.part").exists()
    (tmp_path / "full.csv").symlink_to("/dev/full")
    code, _, err = run([*base[:-1], str(tmp_path / "full.csv")], capsys)
    assert code != 0 and "No space left on device" in err and err.count("\n") == 1


def _mp4(path, n, faststart, size=(W, H)):
    import av

    c = av.open(str(path), "w", options={"movflags": "faststart"} if faststart else {})
    s = c.add_stream("mpeg4", rate=25)
    s.width, s.height, s.pix_fmt = *size, "yuv420p"
    rng = np.random.default_rng(0)
    for _ in range(n):
        frame = rng.integers(0, 255, (size[1], size[0], 3), dtype=np.uint8)
        for p in s.encode(av.VideoFrame.from_ndarray(frame, format="bgr24")):
            c.mux(p)
    for p in s.encode():
        c.mux(p)
    c.close()


def _decodable(video):
    cap = cv2.VideoCapture(str(video))
    n = sum(cap.read()[0] for _ in range(100))
    cap.release()
    return n


def test_damaged_videos_give_the_frames_opencv_decodes(tmp_path, capsys):
    """Cut at 60 % with the moov atom at the front: the frames before the cut; at the end (no index):
    one error line; bytes overwritten mid-stream: every frame OpenCV still decodes, in order."""
    _mp4(tmp_path / "front.mp4", 20, True)
    _mp4(tmp_path / "end.mp4", 20, False)
    write_video(tmp_path / "v.avi", 20)
    for name in ("front.mp4", "end.mp4"):
        data = (tmp_path / name).read_bytes()
        (tmp_path / f"cut_{name}").write_bytes(data[: int(0.6 * len(data))])
    data = bytearray((tmp_path / "v.avi").read_bytes())
    k = len(data) // 2
    data[k:k + 1500] = bytes(range(256)) * 5 + bytes(220)
    (tmp_path / "hit.avi").write_bytes(bytes(data))
    for name in ("cut_front.mp4", "hit.avi"):
        t = tmp_path / f"{name}.csv"
        code, _, err = run(["run", str(tmp_path / name), "--init", "48,51,24,18", "-n", "20", "-q", "--track", str(t)],
                           capsys)
        n = _decodable(tmp_path / name)
        assert code == 0 and "Traceback" not in err and 0 < n < 20 or name == "hit.avi", (name, n, err)
        rows = [int(r["frame"]) for r in read_rows(t)]
        assert len(rows) == n and rows == sorted(rows)
    code, _, err = run(["run", str(tmp_path / "cut_end.mp4"), "--init", "48,51,24,18", "-q"], capsys)
    assert code != 0 and "is not a video OpenCV can decode" in err and err.count("\n") == 1


@pytest.mark.parametrize("kind", ["1-frame", "8x8", "3840x2160", "grey", "4-channel"])
def test_odd_frames_track(tmp_path, capsys, kind):
    """One frame, 8x8 and 3840x2160 frames, grey and 4-channel images: a track with a row per frame."""
    init = "48,51,24,18"
    if kind in ("1-frame", "8x8", "3840x2160"):
        size = {"1-frame": (W, H), "8x8": (8, 8), "3840x2160": (3840, 2160)}[kind]
        n = 1 if kind == "1-frame" else 2
        video = tmp_path / "v.mp4"
        _mp4(video, n, True, size)
        init = {"8x8": "1,1,5,5", "3840x2160": "1400,1000,300,200"}.get(kind, init)
    else:
        video, n = tmp_path / "img", 3
        video.mkdir()
        for i in range(n):
            img = np.full((H, W, 3), 90, np.uint8)
            cv2.rectangle(img, (48 + i, 51), (72 + i, 69), (30, 60, 220), -1)
            img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if kind == "grey" else cv2.cvtColor(img, cv2.COLOR_BGR2BGRA)
            cv2.imwrite(str(video / f"{i + 1:04d}.png"), img)
    t = tmp_path / "t.csv"
    code, _, err = run(["run", str(video), "--init", init, "-n", "20", "-q", "--track", str(t)], capsys)
    assert code == 0, err
    rows = read_rows(t)
    assert len(rows) == n and all(np.isfinite(float(r[c])) for r in rows for c in ("cx", "cy", "w", "h"))


def test_absent_frames_count_alike_in_results_json_and_csv(tmp_path, capsys):
    """OTB frames without the object (NaN, 0,0,0,0) are not visible everywhere: results.csv's row of
    a task has results.json's numbers for that one run."""
    import json

    rows = _moving_box_frames(tmp_path / "clip" / "img")
    rows[3], rows[4] = "NaN,NaN,NaN,NaN", "0,0,0,0"
    (tmp_path / "clip" / "groundtruth_rect.txt").write_text("\n".join(rows) + "\n")
    code, _, err = run(["eval", str(tmp_path / "clip"), "--model", "box", "--algos", "bootstrap", "--particles", "30",
                        "--runs", "1", "--in-process", "--out", str(tmp_path / "ev"), "-q"], capsys)
    assert code == 0, err
    (s,) = json.loads((tmp_path / "ev" / "results.json").read_text())["results"]
    (row,) = read_rows(tmp_path / "ev" / "results.csv")
    for k in ("mean_error", "mean_error_all", "p_lost", "success_auc", "precision_20px"):
        assert float(row[k]) == pytest.approx(s[k], abs=1e-4), k
    assert s["p_lost"] == 0.0 and s["success_auc"] > 0.7


def test_eval_refuses_a_folder_in_use_and_keeps_task_files_when_the_scheduler_is_away(tmp_path, capsys):
    import socket

    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=2, size=(96, 72), seed=1, clutter="low", distractor=False)
    out = tmp_path / "R"
    (out / "tasks").mkdir(parents=True)
    (out / "tasks" / "old.json").write_text('{"fingerprint": "x"}')
    grid = ["eval", str(tmp_path / "c1"), "--algos", "bootstrap", "--particles", "10", "--runs", "1", "--out", str(out)]
    holder = subprocess.Popen([sys.executable, "-c", "import signal; signal.pause()"])  # alive until killed
    try:
        (out / ".vistrack.lock").write_text(f"{holder.pid}@{socket.gethostname()}")
        code, _, err = run(grid, capsys)
        assert code != 0 and f"is in use by another vistrack process ({holder.pid}@" in err and err.count("\n") == 1
    finally:
        holder.kill()
        holder.wait()
    code, _, err = run([*grid, "--scheduler", "tcp://127.0.0.1:9", "--timeout", "1"], capsys)
    assert code != 0 and "cannot reach the Dask scheduler" in err
    assert (out / "tasks" / "old.json").read_text() == '{"fingerprint": "x"}' and not (out / ".vistrack.lock").exists()


@pytest.mark.parametrize("text", ["{}", "[]", '{"clip": "c', "\xff\xfe", ""])
def test_a_damaged_task_file_is_run_again(tmp_path, text):
    """``--resume`` reuses a task file only when it parses and carries this task's fingerprint."""
    from vistrack.batch.tasks import stale_tasks, task_done

    task = {"name": "t", "algo": "lis", "particles": 10, "run": 0}
    (tmp_path / "tasks").mkdir()
    (tmp_path / "tasks" / "t.json").write_text(text, errors="surrogateescape")
    assert not task_done(task, tmp_path) and stale_tasks([task], tmp_path) == [task]


def test_a_task_file_written_by_other_code_is_run_again(tmp_path, monkeypatch):
    """The fingerprint covers vistrack's source: a result written before a change of the code (a
    report rule, a default; the version string unchanged) is not reused by ``--resume``."""
    from vistrack.batch import tasks

    task = {"name": "t", "algo": "lis", "particles": 10, "run": 0}
    tasks.write_task_result(tmp_path / "tasks" / "t.json", {"error": 1.0}, task)
    assert tasks.task_done(task, tmp_path) and len(tasks.code_signature()) == 16
    monkeypatch.setattr(tasks, "_CODE", "0" * 16)  # another checkout's source
    assert not tasks.task_done(task, tmp_path) and tasks.stale_tasks([task], tmp_path) == [task]


def test_synth_sigterm_stops_cleanly(tmp_path):
    """SIGTERM (as Ctrl-C) stops any command: exit 143 with one line, the partial clip removed, the
    old clip as it was."""
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=2, size=(96, 72), seed=1, clutter="low", distractor=False)
    old = _clip_bytes(tmp_path / "c1")
    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", "synth", "contour", "--out", "c1", "--frames",
                             "100000", "--size", "96x72", "-q"], cwd=tmp_path, stderr=subprocess.PIPE, text=True)
    partial = tmp_path / f".c1.partial-{proc.pid}" / "video.mp4"
    wait_until(partial.is_file, "a partial render", proc=proc)
    proc.terminate()
    _, err = proc.communicate(timeout=PATIENCE)
    assert proc.returncode == 143 and err.strip().endswith("\nTerminated.") and "Traceback" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c1"] and _clip_bytes(tmp_path / "c1") == old


def test_fit_plate_refuses_clips_without_plates(tmp_path, capsys):
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c1", frames=2, size=(96, 72), seed=1, clutter="low", distractor=False)
    code, _, err = run(["fit-plate", str(tmp_path)], capsys)
    assert code != 0 and "c1 is not a plate clip (its groundtruth.csv has no plate vertices x0..y3)" in err


def test_local_workers_leave_ctrl_c_to_the_client():
    """Ctrl-C in a terminal reaches every process of the group: the LocalCluster's workers (their
    preload hook) ignore it, so that the client alone stops the grid, without worker tracebacks
    (the whole path: benchmarks/soak.py, 'eval Ctrl-C on the process group')."""
    import logging

    from vistrack.evaluation.experiment import dask_setup

    saved, level = signal.getsignal(signal.SIGINT), logging.getLogger("distributed").level
    try:
        dask_setup(None)
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert logging.getLogger("distributed").level == logging.ERROR
    finally:
        signal.signal(signal.SIGINT, saved)
        logging.getLogger("distributed").setLevel(level)
