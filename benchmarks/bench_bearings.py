"""LIS vs bootstrap and AVPF at the thesis's equal-error particle counts (Table 4.3).

Runs every configuration on the same sequences, interleaved, and reports ms
per 10-step run, the ratio to LIS, and the final/mean errors; then the split of
a LIS step's time (predict, local proposal, likelihood, transition densities,
resampling).

    python benchmarks/bench_bearings.py [--runs 10] [--ships 1]
"""

import argparse
import time

import numpy as np

from vistrack.core.particles import ParticleSet
from vistrack.data_synth.bearings_sequence import simulate
from vistrack.filters import filter_steps
from vistrack.models import Bearings
from vistrack.registry import make_filter
from vistrack.system.resources import keep_freed_memory


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--ships", type=int, default=1)
    args = ap.parse_args()
    model = Bearings(args.ships)
    configs = ([("lis", 100), ("bootstrap", 3000), ("avpf", 500), ("bootstrap", 100), ("lls", 100)]
               if args.ships == 1 else [("lis", 10), ("bootstrap", 100), ("avpf", 50), ("bootstrap", 1000)])
    seqs = [simulate(model, 10, np.random.default_rng(100 + s)) for s in range(10)]
    filters = {c: make_filter(c[0], model) for c in configs}
    t = {c: 0.0 for c in configs}
    err = {c: [] for c in configs}
    for s, (xs, ys) in enumerate(seqs):
        for r in range(args.runs):
            for c in configs:  # interleaved: machine noise hits every config alike
                rng = np.random.default_rng([s, r])
                t0 = time.perf_counter()
                means = np.array([p.mean() for p in filter_steps(filters[c], ys, c[1], rng)])
                t[c] += time.perf_counter() - t0
                err[c].append(model.position_error(means, xs))
    n_runs = len(seqs) * args.runs
    ref = t[configs[0]]
    print(f"bearings-only, {args.ships} ship(s), {n_runs} runs of 10 steps each")
    print(f"{'algo':<10} {'N':>6} {'ms/run':>8} {'x LIS':>6} {'final err':>10} {'mean err':>9}")
    for c in configs:
        e = np.array(err[c])
        print(f"{c[0]:<10} {c[1]:>6} {1e3 * t[c] / n_runs:>8.2f} {t[c] / ref:>6.2f} "
              f"{e[:, -1].mean():>10.5f} {e.mean():>9.5f}")

    # time split of one LIS step
    lis = filters[configs[0]]
    n = configs[0][1]
    rng = np.random.default_rng(0)
    xs, ys = seqs[0]
    p = lis.first_step(ys[0], n, rng)
    parts = dict.fromkeys(["1st stage+resample", "predict", "local proposal", "likelihood", "transition", "weights"],
                          0.0)
    reps = 300
    for _ in range(reps):
        t0 = time.perf_counter()
        idx, lw = lis._ancestors(p, ys[1], rng, lis.kernel)
        prev = p.states[idx]
        t1 = time.perf_counter()
        x = model.predict(prev, rng)
        t2 = time.perf_counter()
        z, la, lq = lis.proposal.sample(x, ys[1], rng, prev)
        t3 = time.perf_counter()
        ll = model.loglik(ys[1], z)
        t4 = time.perf_counter()
        k = model.transition_logpdf(z, prev) - model.transition_logpdf(x, prev)
        t5 = time.perf_counter()
        ParticleSet(z, lw + la + ll - lq + k)
        t6 = time.perf_counter()
        for key, dt in zip(parts, [t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5]):
            parts[key] += dt
    total = sum(parts.values())
    print(f"\nLIS step split at N={n} ({1e6 * total / reps:.0f} us/step):")
    for key, v in parts.items():
        print(f"  {key:<18} {1e6 * v / reps:7.1f} us  {100 * v / total:5.1f} %")


if __name__ == "__main__":
    keep_freed_memory()  # as the CLI does
    main()
