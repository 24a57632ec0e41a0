"""A first run that explains itself (issues 46 and 54, item 1): the kernels compile once per install (numba's
on-disk cache); the first run compiles the model's and algorithm's kernels (kernel_manifest.json) up front
under one bar, "compiling kernels (first run only)" counting k/n to n/n, finished before the tracking bar
appears; nothing compiles after that list (nothing mid-track), and the next run compiles nothing and says
nothing."""

import importlib
import os
import pkgutil
import re
import subprocess
import sys

import pytest

import vistrack

#: ``vistrack run ARGS`` in a child process that records, in order, numba's compile events and the
#: moment the kernels are ready (the progress bar's clock starts), and prints them last
RECORD = """
import sys
from numba.core import event
import vistrack.session.recording as run

seen = []


class Listener(event.Listener):
    def on_start(self, ev):
        seen.append("compile")

    def on_end(self, ev):
        pass


event.register("numba:compile", Listener())
record_video = run.record_video

import vistrack.system.compiling as compiling

listed = compiling.Compiler.compile


def compile_listed(self, *args, **kw):
    listed(self, *args, **kw)
    seen.append("listed")


compiling.Compiler.compile = compile_listed


def recorded(*args, ready=None, **kw):
    def mark():
        seen.append("ready")
        if ready:
            ready()
    return record_video(*args, ready=mark, **kw)


from vistrack.cli import main

sys.modules["vistrack.session.plan"].record_video = recorded  # execute calls it by this name
try:
    main(sys.argv[1:])
finally:
    print("EVENTS", " ".join(seen))
"""


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    from vistrack.data_synth.contour_clip import make_contour_clip

    folder = tmp_path_factory.mktemp("first") / "c"
    make_contour_clip(folder, frames=4, size=(96, 72), seed=1, clutter="low", distractor=False, model="box")
    return folder


@pytest.mark.slow
def test_the_first_run_says_it_compiles_once_and_the_next_compiles_nothing(clip, tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "kernels")}  # empty: as after a fresh install

    def vistrack_run():
        res = subprocess.run([sys.executable, "-c", RECORD, "run", str(clip), "--init-gt", "-n", "30"], env=env,
                             cwd=tmp_path, capture_output=True, text=True)
        assert res.returncode == 0, res.stderr
        events = res.stdout.split("EVENTS", 1)[1].split()
        return res.stderr, events

    err, events = vistrack_run()
    lines = err.replace("\r", "\n").splitlines()
    said = [k for k, line in enumerate(lines) if line.startswith("compiling kernels (first run only): ")]
    counts = [tuple(map(int, re.search(r"\| *(\d+)/(\d+) \[", lines[k]).groups())) for k in said]
    n = counts[-1][1]
    assert n > 5 and counts[-1] == (n, n) and all(t == n for _, t in counts), counts  # one bar, one count
    assert [d for d, _ in counts] == sorted(d for d, _ in counts)
    tracking = [k for k, line in enumerate(lines) if "frame/s" in line]
    assert said[-1] < tracking[0], err  # the count finished before the tracking bar appears
    assert "compile" in events, events
    # every kernel compiled in the list (else: python tools/kernel_manifest.py, after a kernel changed)
    assert events[events.index("listed"):] == ["listed", "ready"], events
    err, events = vistrack_run()
    assert "compiling kernels" not in err and events == ["listed", "ready"], (err, events)


def test_every_kernel_is_kept_in_numba_s_disk_cache():
    """Every compiled kernel of the package is a ``cache=True`` dispatcher (compiled once per install)."""
    from numba.core.caching import NullCache
    from numba.core.registry import CPUDispatcher

    found = []
    for mod in pkgutil.walk_packages(vistrack.__path__, "vistrack."):
        if mod.name.startswith("vistrack.cli"):
            continue
        m = importlib.import_module(mod.name)
        found += [(mod.name, k) for k, v in vars(m).items() if isinstance(v, CPUDispatcher) and
                  v.__module__ == mod.name and isinstance(v._cache, NullCache)]
    assert not found, found
