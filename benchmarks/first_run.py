"""How long the first run after an install takes to compile the kernels, per model: ``vistrack run`` on a
small synthetic clip of each model with its default algorithm, once with an empty kernel cache
(``NUMBA_CACHE_DIR``: as after a fresh install) and once with the cache it left; the difference in
CPU seconds (the compile is one thread: on an idle machine the wall time is about the same) is the
compile time, the figure of the model's registry entry (``ModelSpec.compile_seconds``) in the message. A first
run says "compiling kernels" where the model has compiled kernels; a second run never does.

    python benchmarks/first_run.py [--models box,contour,plate,landmarks] [--repeat 1]
"""

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: a clip of each model and how to run it (from its ground truth where it has one)
CLIPS = {
    "box": (["synth", "contour", "--size", "160x120", "--frames", "10"], ["--model", "box", "--init-gt"]),
    "contour": (["synth", "contour", "--size", "160x120", "--frames", "10"], ["--init-gt"]),
    "plate": (["synth", "plate", "--frames", "10"], []),
    "landmarks": (["synth", "landmarks", "--frames", "10"], []),
}


def vistrack(args, env):
    """``(cpu seconds, wall seconds, stderr)`` of ``vistrack *args`` in a child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-c", "from vistrack.cli import main; main()", *args], env=env,
                         capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if res.returncode:
        sys.exit(res.stderr)
    return after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime, wall, res.stderr


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default=",".join(CLIPS))
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        for name in args.models.split(","):
            synth, opts = CLIPS[name]
            clip = Path(d) / name
            vistrack([*synth, "--out", str(clip), "-q"], dict(os.environ))
            for k in range(args.repeat):
                env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(d) / f"cache-{name}-{k}")}
                first = vistrack(["run", str(clip), *opts], env)
                later = vistrack(["run", str(clip), *opts], env)
                assert "compiling kernels" not in later[2], later[2]
                if "compiling kernels (first run only" not in first[2]:
                    print(f"{name:10s} no compiled kernels (nothing said); a run takes {first[1]:4.1f} s wall")
                    continue
                print(f"{name:10s} compile {first[0] - later[0]:5.1f} s CPU ({first[1] - later[1]:5.1f} s wall); "
                      f"first run {first[1]:5.1f} s, later {later[1]:4.1f} s wall")


if __name__ == "__main__":
    main()
