"""The batch engine on a real Dask cluster with no filesystem in common (issue 36, item 1): a
`dask scheduler` and two `dask worker` processes on 127.0.0.1, each in its own empty working folder
and clip cache, run an eval whose clip is served over HTTP on 127.0.0.1, started in a folder of the
client's that no worker runs in, with --out relative to it: a worker that wrote --out would write it
into its own folder. The results equal the local run's, and killing a worker mid-run changes nothing."""

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from clip_helpers import square_clip
from process_helpers import PATIENCE, TaskGate, listening, wait_until

DASK = shutil.which("dask") or str(Path(sys.executable).with_name("dask"))
pytestmark = [pytest.mark.skipif(not Path(DASK).exists(), reason="the dask command is not installed"),
              pytest.mark.slow]  # every test here is slow (the rule: tests/conftest.py)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def strip(results):
    return [{k: v for k, v in r.items() if k not in ("frames_per_s", "clip")} for r in results]


def eval_args(clip, out, *extra):
    return [sys.executable, "-c", "from vistrack.cli import main; main()", "eval", str(clip),
            "--algos", "bootstrap,lis", "--particles", "1500", "--runs", "6", "--seed", "7", "--out", str(out), "-q",
            *extra]


def test_eval_on_a_cluster_without_a_shared_filesystem_equals_the_local_run(tmp_path):
    served = tmp_path / "served"
    square_clip(served / "sq", 20)
    procs = []
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    gate = TaskGate(tmp_path / "gate")  # the workers' tasks wait at their start until it opens
    try:
        http_port, sched_port = free_port(), free_port()
        procs.append(subprocess.Popen([sys.executable, "-m", "http.server", str(http_port), "--bind", "127.0.0.1"],
                                      cwd=served, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        procs.append(subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", str(sched_port),
                                       "--dashboard-address", ":0"], cwd=tmp_path, env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        workers = []
        for k in range(2):
            wd = tmp_path / f"worker{k}"
            wd.mkdir()
            workers.append(subprocess.Popen(
                [DASK, "worker", f"tcp://127.0.0.1:{sched_port}", "--nthreads", "1", "--no-nanny",
                 "--no-dashboard", "--host", "127.0.0.1"], cwd=wd,
                env={**gate.env, **env, "PYTHONPATH": gate.env["PYTHONPATH"], "VISTRACK_CACHE": str(wd / "cache")},
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        procs += workers
        wait_until(lambda: listening(http_port), "the HTTP server listening", proc=procs[0])
        url = f"http://127.0.0.1:{http_port}/sq/"
        client_env = {**env, "VISTRACK_CACHE": str(tmp_path / "client-cache")}
        client = tmp_path / "client-only"  # the client's working folder, no worker's
        client.mkdir()
        out = client / "out"
        run = subprocess.Popen(eval_args(url, "out", "--scheduler", f"tcp://127.0.0.1:{sched_port}", "--timeout",
                                         str(PATIENCE)),
                               cwd=client, env=client_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        # a worker killed mid-run, holding a task: the task runs again elsewhere from its own seed stream
        wait_until(lambda: gate.started() >= 2, "both workers holding a task", proc=run)
        workers[0].send_signal(signal.SIGKILL)
        gate.open()
        _, err = run.communicate(timeout=PATIENCE)
        assert run.returncode == 0, err
        for k in range(2):  # the workers wrote nothing where they ran (no "out"); one fetched the clip into its cache
            assert sorted(p.name for p in (tmp_path / f"worker{k}").iterdir()) in ([], ["cache"])
        assert (tmp_path / "worker1" / "cache").is_dir()
        local = tmp_path / "local"
        done = subprocess.run(eval_args(served / "sq", local, "--in-process", "--workers", "1"), cwd=tmp_path,
                              env=client_env, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        got = json.loads((out / "results.json").read_text())["results"]
        want = json.loads((local / "results.json").read_text())["results"]
        assert len(got) == 2 and strip(got) == strip(want)
    finally:
        gate.open()
        for p in procs:
            if p.poll() is None:
                p.kill()
            p.wait(timeout=PATIENCE)
