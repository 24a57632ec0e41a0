"""Shared by the tests that drive other processes (signals, killed workers, servers): they wait on
events, locks and process exits with generous timeouts, never on a fixed sleep or on one process
outrunning another, so that they pass on a loaded machine.

- :func:`wait_until`: a condition another process makes true (a file, a port), or its exit.
- :func:`gated_cli`: ``vistrack ARGS`` in a child process whose decoder stops before frame ``gate``
  until the parent closes the child's stdin: the run cannot finish before the parent has done what
  it meant to do mid-run (send a signal).
- :class:`TaskGate`: the engine's tasks, in every worker process, wait on a lock the test holds (and
  say that they started): a worker can be killed while it holds a task, whatever the machine's load.
"""

from __future__ import annotations

import fcntl
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

#: seconds a condition may take on a loaded 2-core machine before the test fails
PATIENCE = 300


def wait_until(predicate, what, timeout=PATIENCE, proc=None):
    """Return once ``predicate()`` is true; ``AssertionError`` naming ``what`` after ``timeout``
    seconds, or when ``proc`` (a ``Popen``) exits first (with its output)."""
    deadline = time.monotonic() + timeout
    tick = threading.Event()
    while not predicate():
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"the process exited ({proc.returncode}) before {what}: {proc.communicate()}")
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {timeout} s")
        tick.wait(0.05)  # polling interval only; nothing depends on it


_GATED = """
import sys
import vistrack.io.video as video

GATE = int(sys.argv.pop(1))
iterate = video.VideoSource.__iter__


def gated(self):
    for i, frame in iterate(self):
        if i == GATE:
            sys.stdin.read()  # until the test closes our stdin
        yield i, frame


video.VideoSource.__iter__ = gated
from vistrack.cli import main

main(sys.argv[1:])
"""


def gated_cli(args, gate, cwd, **kw):
    """``Popen`` of ``vistrack *args`` (text mode, stdout and stderr piped) whose video decoding waits
    before yielding frame ``gate`` until the test closes ``proc.stdin``; SIGINT and SIGHUP at their defaults (a
    shell's background job would start with SIGINT ignored, a suite run under ``nohup`` with SIGHUP ignored,
    which the run rightly keeps ignoring). Run it from ``cwd`` outside the repository (``-c`` from the root
    would import the source tree's ``vistrack/``)."""
    return subprocess.Popen([sys.executable, "-c", _GATED, str(gate), *map(str, args)], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd,
                            preexec_fn=_default_signals, **kw)


def _default_signals():
    """In the child before it runs: SIGINT and SIGHUP at their defaults (:func:`gated_cli`)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)


_SITECUSTOMIZE = """
import os

if os.environ.get("VISTRACK_TEST_GATE"):
    import fcntl
    import functools
    from pathlib import Path

    import vistrack.evaluation.experiment as evaluation

    gate = Path(os.environ["VISTRACK_TEST_GATE"])
    run_task = evaluation.run_task

    @functools.wraps(run_task)
    def gated_run_task(task, out_dir):
        (gate / f"started-{task['name']}-{os.getpid()}").touch()
        with open(gate / "lock", "rb") as f:
            fcntl.flock(f, fcntl.LOCK_SH)  # waits while the test holds the lock
            fcntl.flock(f, fcntl.LOCK_UN)
        return run_task(task, out_dir)

    evaluation.run_task = gated_run_task
"""


class TaskGate:
    """Hold the engine's tasks at their start in every process given :attr:`env`: a ``sitecustomize``
    wraps :func:`vistrack.evaluation.experiment.run_task` to mark that it started and then wait on a file
    lock that the gate holds until :meth:`open`. Use as a context manager (opened on exit)."""

    def __init__(self, folder):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        (self.folder / "sitecustomize.py").write_text(_SITECUSTOMIZE)
        self._lock = open(self.folder / "lock", "wb")
        fcntl.flock(self._lock, fcntl.LOCK_EX)
        path = os.pathsep.join(p for p in (str(self.folder), os.environ.get("PYTHONPATH")) if p)
        #: the environment of the processes whose tasks wait
        self.env = {**os.environ, "VISTRACK_TEST_GATE": str(self.folder), "PYTHONPATH": path}

    def started(self):
        """How many tasks have started (and wait, until :meth:`open`)."""
        return sum(1 for p in self.folder.iterdir() if p.name.startswith("started-"))

    def open(self):
        """Let every task run (now and later)."""
        if not self._lock.closed:
            fcntl.flock(self._lock, fcntl.LOCK_UN)
            self._lock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.open()


def listening(port, host="127.0.0.1"):
    """Whether a server accepts connections on ``host:port``."""
    import socket

    try:
        socket.create_connection((host, port), timeout=5).close()
        return True
    except OSError:
        return False
