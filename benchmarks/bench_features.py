"""Time the per-frame feature maps at 640x480 (decode excluded), side by side.

    python benchmarks/bench_features.py [--repeats 200]
"""

import argparse
import time

import numpy as np

from vistrack.appearance.features import FeatureMaps
from vistrack.system.resources import keep_freed_memory


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=200)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 255, (480, 640, 3)).astype(np.uint8) for _ in range(4)]
    steps = {
        "gray": lambda f: f.gray,
        "sobel gx+gy": lambda f: (f.gx, f.gy),
        "magnitude": lambda f: f.mag,
        "DoG small+large": lambda f: (f.dog_small, f.dog_large),
        "integral |gx|": lambda f: f.integral("abs_gx"),
    }
    acc = dict.fromkeys(steps, 0.0)
    for k in range(args.repeats):
        fm = FeatureMaps(frames[k % 4])
        for name, fn in steps.items():
            t0 = time.perf_counter()
            fn(fm)
            acc[name] += time.perf_counter() - t0
    total = sum(acc.values())
    print(f"feature maps, 640x480, mean of {args.repeats} frames")
    for name, v in acc.items():
        print(f"  {name:<16} {1e3 * v / args.repeats:6.3f} ms  {100 * v / total:5.1f} %")
    print(f"  {'total':<16} {1e3 * total / args.repeats:6.3f} ms")


if __name__ == "__main__":
    keep_freed_memory()  # as the CLI does
    main()
