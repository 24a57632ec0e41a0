"""Partitioned sampling on M-ship bearings (thesis App. C): each ship's final-step error and how
many distinct values of each ship the final particle set holds, at equal N.

The sequences are those of ``vistrack reproduce bearings --ships M --seed S`` (the same
``SeedSequence``). "Distinct ESS" of ship k is ``1 / Σ_v W_v²`` over the distinct values ``v``
of the ship's state in the final set, ``W_v`` the total weight of the particles holding it: 1
when every particle holds the same ship k, N for N distinct equally weighted values; it
measures App. C's impoverishment of the partitions sampled first. The reference is the
exact posterior's error to the eye: the posterior factorises over the independent ships, so
each ship is filtered alone by bootstrap with ``--reference`` particles.

    python benchmarks/bench_partitions.py --ships 10 -n 1000 --runs 10

``--speed`` instead times partitioned and branched partitioned sampling at N = 100, 1000, 3000
(CPU ms per run, best of 6 interleaved repeats of 3 runs), branched both with every group at
once (bearings' stacked partitions) and group by group (the path of models without them).

``--group-shares`` instead reports how the branched filter's groups share the joined weight
after each step (their total weights are their own estimates of ``p(Y_t|Y_{1:t-1})``).

An entry ``ALGO:N`` of ``--algos`` runs ``ALGO`` with ``N`` particles instead of ``-n`` (e.g. the
equal-time counts of ``reproduce bearings --equal-time``). ``partitioned-reversed`` in ``--algos`` is
partitioned sampling drawing the ships in the
reversed order (ship M first, ship 1 last), from the same seeds: does a ship's error depend
on its place in the order? ``--paired`` prints, for every algorithm after the first, the
paired differences (this algorithm − the first) of ship 1's, ship M's and the joint
final-step error over the (sequence, run) pairs, mean ± standard error, and the difference of
the first half of the ships' mean difference and the second half's (partitioned draws the
first half early, the reversed order late: negative where a ship gains from coming later).

    python benchmarks/bench_partitions.py --ships 10 -n 1000 --runs 20 --reference 0 \
        --algos partitioned,partitioned-reversed,branched-partitioned --paired
"""

import argparse
import time

import numpy as np

from vistrack.core.particles import logsumexp
from vistrack.filters import BranchedPartitioned, filter_steps
from vistrack.filters.partition_step import PartitionedBase
from vistrack.models import Bearings
from vistrack.registry import make_filter
from vistrack.reproduce.bearings import BearingsConfig, sequence


class GroupShares(BranchedPartitioned):
    """Branched partitioning that records each step's group weights, heaviest first."""

    shares = []

    def assign(self, n, rng):
        self._labels = super().assign(n, rng)
        return self._labels

    def _partitions(self, prev, log_w, obs, rng, kernel):
        x, lw, lam = super()._partitions(prev, log_w, obs, rng, kernel)
        labels = np.sort(self._labels)  # bearings stacks its partitions: the rows come back sorted by group
        tot = np.array([logsumexp(lw[labels == g]) for g in range(len(self.orderings))])
        self.shares.append(np.sort(np.exp(tot - logsumexp(tot)))[::-1])
        return x, lw, lam


class GroupByGroup(BranchedPartitioned):
    """Branched partitioning one group after the other, as for models without stacked partitions."""

    def _partitions(self, prev, log_w, obs, rng, kernel):
        return PartitionedBase._partitions(self, prev, log_w, obs, rng, kernel)


def speed(cfg, model):
    """Print a table row per N: CPU ms per run of each filter and the ratios to partitioned."""
    _, obs, _ = sequence(cfg, model, 0)
    for n in (100, 1000, 3000):
        filters = {"partitioned": make_filter("partitioned", model),
                   "branched": make_filter("branched-partitioned", model), "group by group": GroupByGroup(model)}
        best = dict.fromkeys(filters, np.inf)
        for _ in range(6):
            for name, filt in filters.items():
                t0 = time.thread_time()
                for s in range(3):
                    list(filter_steps(filt, obs, n, np.random.default_rng(s)))
                best[name] = min(best[name], (time.thread_time() - t0) / 3)
        p = best["partitioned"]
        print(f"| {model.ships} | {n} | " + " | ".join(f"{1e3 * v:.1f}" for v in best.values())
              + f" | {best['branched'] / p:.2f} | {best['group by group'] / p:.2f} |", flush=True)


def group_shares(cfg, model, n):
    """Print the heaviest group's mean share and the effective number of groups."""
    for s in range(cfg.sequences):
        _, obs, seeds = sequence(cfg, model, s)
        for ss in seeds:
            list(filter_steps(GroupShares(model), obs, n, np.random.default_rng(ss)))
    sh = np.array(GroupShares.shares)
    print(f"M = {model.ships}, N = {n}: heaviest group's share {sh[:, 0].mean():.2f}, two heaviest "
          f"{sh[:, :2].sum(axis=1).mean():.2f}, effective number of groups {np.mean(1 / np.sum(sh**2, axis=1)):.2f}")


def make(algo, model):
    """The filter ``algo`` (``partitioned-reversed``: partitioned with the ships drawn M..1)."""
    if algo != "partitioned-reversed":
        return make_filter(algo, model)
    filt = make_filter("partitioned", model)
    filt.orderings = [tuple(reversed(range(model.ships)))]
    return filt


def paired(rows):
    """Print each algorithm's paired differences to the first on ship 1, ship M and the joint error."""
    names = list(rows)
    base = np.array(rows[names[0]][0])  # (pairs, M)
    print(f"paired differences to {names[0]} (final step, mean ± SE over {len(base)} (sequence, run) pairs)")
    for algo in names[1:]:
        d = np.array(rows[algo][0]) - base
        half = d.shape[1] // 2  # ships 1..M/2 come later in the reversed order, the others earlier
        cols = {"ship 1": d[:, 0], f"ship {d.shape[1]}": d[:, -1], "joint": d.mean(axis=1),
                "first half − second half": d[:, :half].mean(axis=1) - d[:, -half:].mean(axis=1)}
        print(f"{algo:<22} " + "  ".join(f"{k} {v.mean():+.5f} ± {v.std(ddof=1) / np.sqrt(len(v)):.5f}"
                                         for k, v in cols.items()))


def distinct_ess(particles, cols):
    """``1 / Σ_v W_v²`` over the distinct rows ``v`` of ``states[:, cols]``."""
    _, inv = np.unique(particles.states[:, cols], axis=0, return_inverse=True)
    w = np.bincount(inv.ravel(), weights=particles.weights)
    return 1.0 / np.dot(w, w)


def reference_errors(model, truth, obs, n):
    """Each ship's final-step error of its own bootstrap filter with ``n`` particles, ``(M,)``."""
    out = []
    for j, cols in enumerate(model.partitions):
        ship = model.target_model(j)
        *_, last = filter_steps(make_filter("bootstrap", ship), obs[:, j:j + 1], n, np.random.default_rng(j))
        out.append(np.linalg.norm(ship.positions(last.mean()[None]) - ship.positions(truth[-1:, cols]), axis=-1)[0, 0])
    return np.array(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ships", type=int, default=10)
    ap.add_argument("-n", "--particles", type=int, default=1000)
    ap.add_argument("--sequences", type=int, default=10)
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--algos", default="bootstrap,lis,partitioned,branched-partitioned")
    ap.add_argument("--reference", type=int, default=200_000, help="particles per ship of the reference (0: none)")
    ap.add_argument("--group-shares", action="store_true", help="only the branched filter's group weights")
    ap.add_argument("--speed", action="store_true", help="only the timings of partitioned and branched")
    ap.add_argument("--paired", action="store_true", help="paired differences to the first algorithm")
    a = ap.parse_args()
    cfg = BearingsConfig(ships=a.ships, sequences=a.sequences, runs=a.runs, seed=a.seed)
    model = Bearings(a.ships)
    if a.group_shares:
        return group_shares(cfg, model, a.particles)
    if a.speed:
        return speed(cfg, model)
    rows = {algo: ([], [], 0.0) for algo in a.algos.split(",")}
    ref = []
    for s in range(a.sequences):
        truth, obs, seeds = sequence(cfg, model, s)
        if a.reference:
            ref.append(reference_errors(model, truth, obs, a.reference))
        for algo, (err, div, _) in rows.items():
            name, _, n = algo.partition(":")
            filt, n = make(name, model), int(n or a.particles)
            t0 = time.thread_time()
            for ss in seeds:
                *_, last = filter_steps(filt, obs, n, np.random.default_rng(ss))
                err.append(np.linalg.norm(model.positions(last.mean()[None]) - model.positions(truth[-1:]), axis=-1)[0])
                div.append([distinct_ess(last, cols) for cols in model.partitions])
            rows[algo] = (err, div, rows[algo][2] + time.thread_time() - t0)
    print(f"M = {a.ships}, N = {a.particles}, {a.sequences} sequences x {a.runs} runs; final-step error per ship "
          "(ship 1 is sampled first by partitioned), then distinct ESS per ship")
    if ref:
        print(f"{'reference':<22} {np.mean(ref):.5f}  " + " ".join(f"{v:.4f}" for v in np.mean(ref, axis=0)))
    for algo, (err, div, sec) in rows.items():
        print(f"{algo:<22} {np.mean(err):.5f}  " + " ".join(f"{v:.4f}" for v in np.mean(err, axis=0))
              + f"  ({1e3 * sec / len(err):.0f} ms/run)")
        print(f"{'':<22} {'':7}  " + " ".join(f"{v:6.0f}" for v in np.mean(div, axis=0)))
    if a.paired:
        paired(rows)


if __name__ == "__main__":
    main()
