"""Faults that break a batch of tasks: the --out folder in use, a worker killed or a task that cannot finish,
workers that cannot see the clips, a scheduler away, damaged or stale task files on --resume, Ctrl-C in the
workers."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import pytest

from cli_helpers import run
from process_helpers import PATIENCE, TaskGate, wait_until


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


# ------------------------------------------------------------------ the fourth sweep (issue 55)


@pytest.mark.parametrize("damage", ["a key lost", "a list cut short", "a value changed"])
def test_a_task_file_damaged_under_its_fingerprint_is_run_again(tmp_path, damage):
    """A damaged task file that kept its fingerprint was reused on --resume: without its 'reported' key, the
    run's reported-lost fraction became 0; with lists cut short, numpy's 'inhomogeneous shape' ended
    eval. Every task file holds a digest of what its task wrote."""
    import json

    from vistrack.batch import tasks
    from vistrack.batch.tasks import TaskFailed

    task = {"name": "t", "algo": "lis", "particles": 10, "run": 0}
    p = tmp_path / "tasks" / "t.json"
    tasks.write_task_result(p, {"error": [1.0, 2.0, 3.0], "reported": [1, 1, 0], "frames": 3}, task)
    assert tasks.task_done(task, tmp_path) and tasks.load_task_results([task], tmp_path)[0]["frames"] == 3
    data = json.loads(p.read_text())
    if damage == "a key lost":
        del data["reported"]
    elif damage == "a list cut short":
        data["error"] = data["error"][:2]
    else:
        data["frames"] = 4
    p.write_text(json.dumps(data))
    assert not tasks.task_done(task, tmp_path) and tasks.stale_tasks([task], tmp_path) == [task]
    with pytest.raises(TaskFailed, match=f"task file {p} was changed or damaged after its task wrote it"):
        tasks.load_task_results([task], tmp_path)


def test_the_code_signature_covers_the_whole_package():
    """The signature hashed the modules of vistrack/batch/ alone since the packages moved: a change of a
    model or a score kept old task files on --resume."""
    from pathlib import Path

    import vistrack
    from vistrack.batch import tasks

    root = Path(vistrack.__file__).parent
    assert Path(tasks.__file__).resolve().parents[1] == root.resolve()
    assert len(list(root.rglob("*.py"))) > 100  # what the signature reads: every module, not one folder's
