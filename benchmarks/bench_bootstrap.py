"""Time one bootstrap step (predict + likelihood + systematic resampling) vs N.

Bearings-only model, one ship. Reports the median time per step, µs per
particle and the ratio to N = 100, measured side by side in one run.

    python benchmarks/bench_bootstrap.py [--repeats 30]
"""

import argparse
import time

import numpy as np

from vistrack.data_synth.bearings_sequence import simulate
from vistrack.filters import Bootstrap
from vistrack.models import Bearings
from vistrack.system.resources import keep_freed_memory


def time_step(filt, particles, obs, rng, repeats):
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        filt.step(particles, obs, rng)
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--ships", type=int, default=1)
    args = ap.parse_args()
    model = Bearings(args.ships)
    rng = np.random.default_rng(0)
    _, ys = simulate(model, 3, rng)
    filt = Bootstrap(model)
    rows = []
    for n in [100, 300, 1000, 3000, 10_000, 30_000, 100_000]:
        p = filt.first_step(ys[0], n, rng)
        rows.append((n, time_step(filt, p, ys[1], rng, args.repeats)))
    base = rows[0][1]
    print(f"bootstrap step, bearings-only ({args.ships} ship(s)), median of {args.repeats}")
    print(f"{'N':>8} {'ms/step':>9} {'us/particle':>12} {'x N=100':>8}")
    for n, t in rows:
        print(f"{n:>8} {1e3 * t:>9.3f} {1e6 * t / n:>12.3f} {t / base:>8.1f}")


if __name__ == "__main__":
    keep_freed_memory()  # as the CLI does
    main()
