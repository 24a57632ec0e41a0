"""How long the first run after an install takes to compile the kernels, per model: ``vistrack run`` on a
small synthetic clip of each model with its default algorithm (and ``default-real``, ``box-real``: the real clip
of issue 54, ``girl_otb.mp4 --init 57,21,31,45``, with the default model and the box model, where
``../shared/data/real`` is there), once with an empty kernel
cache (``NUMBA_CACHE_DIR``: as after a fresh install) and once with the cache it left; the difference in
CPU seconds (the compile is one thread: on an idle machine the wall time is about the same) is the
compile time. A first run counts the kernels it compiles ("compiling kernels (first run only): k/n",
its n printed here); a second run says nothing. The load average is printed beside each line: on a busy
machine the wall time is longer, and the CPU seconds a little.

    python benchmarks/first_run.py [--models default-real,box-real,box,contour,plate,landmarks] [--repeat 1]
"""

import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: the kernels' count on the first run's bar
COUNT = re.compile(r"compiling kernels \(first run only\):.*?(\d+)/(\d+) \[")
#: the real clip of issue 54's first run, and the box a user types for it
REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real" / "girl_otb" / "girl_otb.mp4"
#: a clip of each model and how to run it (from its ground truth where it has one; a real clip: None)
CLIPS = {
    "default-real": (None, ["--init", "57,21,31,45"]),  # issue 54: the default model (siam)
    "box-real": (None, ["--model", "box", "--init", "57,21,31,45"]),
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
            clip = Path(d) / name if synth else REAL
            if synth:
                vistrack([*synth, "--out", str(clip), "-q"], dict(os.environ))
            elif not clip.is_file():
                print(f"{name:10s} skipped: {clip} is not there")
                continue
            for k in range(args.repeat):
                env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(d) / f"cache-{name}-{k}")}
                first = vistrack(["run", str(clip), *opts], env)
                later = vistrack(["run", str(clip), *opts], env)
                assert "compiling kernels" not in later[2], later[2]
                if "compiling kernels (first run only" not in first[2]:
                    print(f"{name:10s} no compiled kernels (nothing said); a run takes {first[1]:4.1f} s wall")
                    continue
                counts = re.findall(COUNT, first[2].replace("\r", "\n"))
                n = counts[-1][1] if counts else "?"
                load = " ".join(f"{v:.1f}" for v in os.getloadavg())
                print(f"{name:10s} compile {first[0] - later[0]:5.1f} s CPU ({first[1] - later[1]:5.1f} s wall), {n} "
                      f"kernels; first run {first[1]:5.1f} s, later {later[1]:4.1f} s wall; load average {load}")


if __name__ == "__main__":
    main()
