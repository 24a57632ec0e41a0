"""Shared fixtures, the ``slow`` marker's rule, and the kernels compiled once before the suite.

``slow`` (registered in pyproject.toml) marks a test that runs a command end to end (a subprocess, a grid on
Dask, the demo, the docs build), tracks a clip over many frames or checks a proposal against a brute-force
posterior: each took over 2 s on the busy 2-core development machine. ``pytest -m "not slow"`` is the quick
check (under a minute there); the fault tests (``tests/<package>/test_faults_*.py``, filed by what a fault
breaks, every test a command under a fault) are slow as a whole.
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from kernel_helpers import compile_kernels

HERE = Path(__file__).resolve().parent


def pytest_sessionstart(session):
    """Compile the kernels once before the tests, in the process that starts pytest-xdist's workers (before
    it starts them: this hook runs before xdist's own): numba's disk cache then holds them, and every worker
    loads them instead of compiling them inside whichever test touches one first. Nothing without workers
    (``-n 0``, a test or two): a test that needs a kernel compiles it as before."""
    config = session.config
    if not hasattr(config, "workerinput") and config.getoption("numprocesses", None):
        parts = min(2, os.cpu_count() or 1)  # in as many processes at once as the machine has cores (up to 2)
        if parts == 1:
            compile_kernels()
            return
        code = f"import sys; sys.path.insert(0, {str(HERE)!r}); from kernel_helpers import compile_kernels; " \
               "compile_kernels(int(sys.argv[1]), int(sys.argv[2]))"
        procs = [subprocess.Popen([sys.executable, "-c", code, str(k), str(parts)]) for k in range(parts)]
        if any(p.wait() for p in procs):
            pytest.exit("compiling the kernels before the suite failed (its error is above)", returncode=3)


def pytest_collection_modifyitems(items):
    """The fault tests are slow (module docstring)."""
    for item in items:
        if item.path.name.startswith("test_faults"):
            item.add_marker(pytest.mark.slow)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def synth_clip(tmp_path_factory):
    """``synth_clip(kind, **options)``: the folder of a clip rendered by ``vistrack.data_synth`` (``kind``
    ``"contour"``: :func:`~vistrack.data_synth.contour_clip.make_contour_clip`; ``"plate"``:
    :func:`~vistrack.data_synth.plate_clip.make_plate_clip`), made once per session for each set of options."""
    made = {}

    def make(kind, **options):
        key = (kind, tuple(sorted(options.items())))
        if key not in made:
            if kind == "contour":
                from vistrack.data_synth.contour_clip import make_contour_clip as render
            else:
                from vistrack.data_synth.plate_clip import make_plate_clip as render
            out = tmp_path_factory.mktemp(kind) / "clip"
            render(out, **options)
            made[key] = out
        return made[key]

    return make


@pytest.fixture
def ctrl_c_reaches_python():
    """SIGINT raises ``KeyboardInterrupt`` in this process for the test, as in a terminal: a test run
    started as a background job (as CI runners may start it) inherits SIGINT ignored, which the
    code under test rightly keeps (it leaves an ignored SIGINT ignored)."""
    import signal

    saved = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, saved)


@pytest.fixture
def serve():
    """``serve(folder, handler)``: the URL of ``folder`` served on 127.0.0.1 by ``handler``
    (:mod:`server_helpers`: ``QuietHandler`` without range requests by default, ``RangeHandler`` with them)."""
    from server_helpers import serve_folder

    servers = []

    def start(folder, handler=None):
        url, server = serve_folder(folder, handler)
        servers.append(server)
        return url

    yield start
    for s in servers:
        s.shutdown()
        s.server_close()
