"""Contour tracking speed, side by side in one process (thesis Table 4.1).

Makes one 320x240 synthetic clip, decodes it once, then alternates the
algorithms frame-block by frame-block so that machine noise hits all of them
alike; prints ms per frame (features + filter step) and the ratio to the first.

    python benchmarks/bench_contour.py [--entries ls-n-ips:30,bootstrap:2000,lis:30,lls:30] [--rounds 3]
"""

import argparse
import tempfile
import time

import numpy as np

from vistrack.builders import build_model
from vistrack.clips import load_clip
from vistrack.data_synth.contour import make_contour_clip
from vistrack.filters import make_filter
from vistrack.tracking import track
from vistrack.runtime import keep_freed_memory


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--entries", default="ls-n-ips:30,bootstrap:2000,lis:30,lls:30,bootstrap:100")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--frames", type=int, default=100)
    args = ap.parse_args()
    entries = [(e.split(":")[0], int(e.split(":")[1])) for e in args.entries.split(",")]
    with tempfile.TemporaryDirectory() as d:
        make_contour_clip(d, frames=args.frames, size=(320, 240), seed=1)
        clip = load_clip(d)
        frames = list(clip.source)
        model = build_model("contour", clip, init_gt="")
    times = {e: [] for e in entries}
    for r in range(args.rounds):
        for algo, n in entries:
            filt = make_filter(algo, model)
            t0 = time.perf_counter()
            for _ in track(frames, filt, n, np.random.default_rng(r)):
                pass
            times[(algo, n)].append((time.perf_counter() - t0) * 1e3 / len(frames))
    base = np.median(times[entries[0]])
    print(f"{'algo':<10} {'N':>6} {'ms/frame':>9} {'frames/s':>9} {'x first':>8}")
    for (algo, n), t in times.items():
        m = float(np.median(t))
        print(f"{algo:<10} {n:>6} {m:>9.2f} {1e3 / m:>9.0f} {m / base:>8.2f}")


if __name__ == "__main__":
    keep_freed_memory()  # as the CLI does
    main()
