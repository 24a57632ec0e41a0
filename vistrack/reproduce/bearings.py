"""The bearings-only experiments of thesis 001, §4.5.5 (Figs. 4.18, 4.21, 4.22; Tables 4.3, 4.4).

10 fixed state/observation sequences, ``R`` runs of every (algorithm, N) on
each; the error is the Euclidean distance of the weighted-mean position to the
truth (averaged over ships: the joint error; each ship's is kept too). With
``entries`` the (algorithm, N) pairs are given instead of the grid, e.g. the
equal-time counts of :meth:`BearingsConfig.equal_time`. Randomness: ``SeedSequence(seed)`` spawns one
stream for the sequences and one per (sequence, run); a run's stream is the
same for every algorithm and N (common random numbers), so results do not
depend on the order the grid is evaluated in.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import asdict, dataclass, field

import numpy as np

from ..batch.tasks import load_task_results, save_result
from ..core.particles import DegenerateWeightsWarning
from ..filters import filter_steps
from ..models.bearings.model import LIS_PROPOSALS, Bearings, simulate
from ..registry import FILTERS, derived_algos, make_filter
from ..registry.comparisons import BEARINGS
from ..scoring.metrics import best_ms, equal_time
from ..system.resources import check_memory, prepare_worker

__all__ = ["BearingsConfig", "run_bearings", "run_bearing_task", "sequence", "DEFAULT_ALGOS", "format_ship_table"]

#: Tables 4.3 and 4.4's algorithms
DEFAULT_ALGOS = BEARINGS


@dataclass
class BearingsConfig:
    """Parameters of one reproduction (the ``config`` block of the JSON)."""

    ships: int = 1
    sequences: int = 10
    runs: int = 100
    steps: int = 10
    algos: list = field(default_factory=lambda: list(DEFAULT_ALGOS))
    particles: list = field(default_factory=lambda: [100, 500, 3000])
    #: LIS's local proposal (:data:`~vistrack.models.bearings.model.LIS_PROPOSALS`)
    proposal: str = "xi"
    seed: int = 0
    resample: str = "systematic"
    ess_threshold: float | None = None
    #: ``[[algo, N], ...]`` run instead of ``algos`` x ``particles`` (``None``: the grid)
    entries: list | None = None

    table = "bearings"
    #: the folder of its task files when ``--out`` is not given
    results_dir = "bearings-results"

    def pairs(self):
        """The ``(algo, N)`` pairs to run: :attr:`entries`, else every algorithm at every N."""
        if self.entries is not None:
            return [(a, int(n)) for a, n in self.entries]
        return [(a, int(n)) for a in self.algos for n in self.particles]

    def validate(self):
        """Raise ``ValueError`` with one clear sentence for bad values."""
        if self.ships < 1:
            raise ValueError(f"--ships must be at least 1, got {self.ships}")
        for name in ("sequences", "runs", "steps"):
            v = getattr(self, name)
            if v < 1:
                raise ValueError(f"--{name} must be a positive integer, got {v}")
        if self.proposal not in LIS_PROPOSALS:
            raise ValueError(f"--lis-proposal must be one of {', '.join(LIS_PROPOSALS)}, got {self.proposal!r}")
        if not self.particles:
            raise ValueError("--particles needs at least one particle count")
        bad = [n for n in self.particles if n < 1]
        if bad:
            raise ValueError(f"--particles must be positive integers, got {bad[0]}")
        if not self.algos:
            raise ValueError("--algos needs at least one algorithm")
        self.check_size()
        model = Bearings(self.ships, proposal=self.proposal)
        for a in dict.fromkeys(a for a, _ in self.pairs()):
            if a not in FILTERS:
                runs = ", ".join(derived_algos(Bearings))
                raise ValueError(f"unknown algorithm {a!r} for bearings; choose from {runs}")
            make_filter(a, model)  # a filter whose model parts bearings lacks: its one-line ValueError

    def tasks(self):
        """One engine task per fixed sequence (all its runs, algorithms and N inside)."""
        self.validate()
        tag = f"M{self.ships}_T{self.steps}_R{self.runs}_S{self.sequences}_s{self.seed}"
        return [{"name": f"bearings_{tag}_seq{s:03d}", "sequence": s, "config": asdict(self)}
                for s in range(self.sequences)]

    @property
    def runner(self):
        """:func:`run_bearing_task`."""
        return run_bearing_task

    def results(self, tasks, out_dir):
        """``{"config", "results", "curves"}`` from the task files of :meth:`tasks`."""
        per = {}
        for data in load_task_results(tasks, out_dir):
            for e in data["entries"]:
                per.setdefault((e["algo"], e["particles"]), []).append((np.array(e["ship_errors"]), e["seconds"],
                                                                        e["degenerate"]))
        return _summarize(self, per)

    def equal_time(self, runs=3, repeats=3, steps=4):
        """``(algo, N)`` pairs at equal time per run (as ``eval --equal-time``): for every N of
        :attr:`particles`, the first algorithm at N and every other at the N whose time per run is
        closest to it (:func:`~vistrack.scoring.metrics.equal_time` with the secant search, ``steps``
        steps). Times are the best of ``repeats`` timings (:func:`~vistrack.scoring.metrics.best_ms`), in
        CPU time of this thread, of ``runs`` runs on the first sequence. Returns ``(pairs, {"algo:N": ms
        per run})``, the times at the answers."""
        model = Bearings(self.ships, proposal=self.proposal)
        _, obs, seeds = sequence(self, model, 0)
        seeds = seeds[:runs]

        def ms(algo, n):
            filt = make_filter(algo, model, resample=self.resample, ess_threshold=self.ess_threshold)
            return best_ms(lambda: [_timed_run(filt, obs, n, ss) for ss in seeds], repeats, time.thread_time) \
                / len(seeds)

        pairs, times = [], {}
        for n in self.particles:
            found, t = equal_time(ms, [(a, int(n)) for a in self.algos], search_steps=steps)
            pairs += found
            times.update(t)
        return pairs, times

    def check_size(self, available=None):
        """Raise :class:`~vistrack.system.resources.TooLarge` (one line) when the errors gathered
        (:data:`VALUE_BYTES` per ship, step, run, sequence and pair), the runs' seed streams that
        every task makes and one step's particles in every worker at once (a worker per core, at most
        one per sequence) would not fit in memory."""
        import os

        pairs = self.pairs()
        per_step = VALUE_BYTES * self.sequences * len(pairs) * self.runs * self.ships
        at_once = min(self.sequences, os.cpu_count() or 1)
        rest = 600 * self.sequences * self.runs + at_once * max(n for _, n in pairs) * 4 * self.ships * 8 * 32

        def most(room):
            steps = int((room - rest) // per_step)
            return f"give at most {steps} --steps" if steps >= 1 else \
                "give fewer --ships, --particles, --runs or --sequences"

        check_memory(per_step * self.steps + rest, f"{self.ships} ship(s), {self.sequences} sequences x {self.runs} "
                     f"runs x {self.steps} steps x {len(pairs)} algorithm and N pair(s) need", most,
                     available=available)


#: bytes of one number gathered from the tasks: its JSON text, the parsed float, the array's copy
VALUE_BYTES = 64


def _sequence_runs(cfg, model, s):
    """Sequence ``s``: its ``runs`` filter runs for every (algorithm, N).

    Returns ``{(algo, N): (errors (runs, steps, M), seconds, degenerate steps)}``: every ship's
    position error. Run ``r`` draws from ``SeedSequence(seed).spawn(2)[1].spawn(sequences *
    runs)[s * runs + r]`` for every algorithm and N (common random numbers).
    """
    truth, obs, run_seeds = sequence(cfg, model, s)
    out = {}
    for algo, n in cfg.pairs():
        filt = make_filter(algo, model, resample=cfg.resample, ess_threshold=cfg.ess_threshold)
        errors = np.empty((cfg.runs, cfg.steps, cfg.ships))
        elapsed = 0.0
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", DegenerateWeightsWarning)
            for r, ss in enumerate(run_seeds):
                means, sec = _timed_run(filt, obs, n, ss)
                elapsed += sec
                errors[r] = np.linalg.norm(model.positions(means) - model.positions(truth), axis=-1)
        degenerate = sum(issubclass(w.category, DegenerateWeightsWarning) for w in caught)
        out[(algo, n)] = (errors, elapsed, degenerate)
    return out


def sequence(cfg, model, s):
    """Sequence ``s``'s ``(truth (steps, d), obs (steps, M), run seeds (runs,))``."""
    seq_ss, run_ss = np.random.SeedSequence(cfg.seed).spawn(2)
    truth, obs = simulate(model, cfg.steps, np.random.default_rng(seq_ss.spawn(cfg.sequences)[s]))
    return truth, obs, run_ss.spawn(cfg.sequences * cfg.runs)[s * cfg.runs:(s + 1) * cfg.runs]


def _timed_run(filt, obs, n, seed):
    """One run of ``filt`` with ``n`` particles from ``seed``: ``(means (steps, d), seconds)``,
    the seconds of CPU time of this thread (on a shared machine, wall time depends on the load)."""
    rng = np.random.default_rng(seed)
    t0 = time.thread_time()
    means = np.array([p.mean() for p in filter_steps(filt, obs, n, rng)])
    return means, time.thread_time() - t0


def run_bearing_task(task, out_dir):
    """Engine runner: sequence ``task["sequence"]``, its result written under ``out_dir``
    (:func:`~vistrack.batch.tasks.save_result`)."""
    prepare_worker()
    cfg = BearingsConfig(**task["config"])
    res = _sequence_runs(cfg, Bearings(cfg.ships, proposal=cfg.proposal), task["sequence"])
    result = {"sequence": task["sequence"],
              "entries": [{"algo": a, "particles": n, "ship_errors": e.tolist(), "seconds": sec, "degenerate": deg}
                          for (a, n), (e, sec, deg) in res.items()]}
    return save_result(out_dir, task, result)


def _summarize(cfg, per):
    results, curves = [], {}
    for (algo, n), parts in per.items():
        ships = np.concatenate([p[0] for p in parts])  # (runs, steps, M)
        errors = ships.mean(axis=2)
        final = errors[:, -1]
        results.append(
            {
                "algo": algo,
                "particles": int(n),
                "ships": cfg.ships,
                "mean_error_final": float(final.mean()),
                "std_error_final": float(final.std(ddof=1)) if len(final) > 1 else 0.0,
                "mean_error": float(errors.mean()),
                "ship_error_final": ships[:, -1].mean(axis=0).tolist(),
                "ship_error_mean": ships.mean(axis=(0, 1)).tolist(),
                "ms_per_run": 1e3 * sum(p[1] for p in parts) / len(errors),
                "degenerate_steps": int(sum(p[2] for p in parts)),
            }
        )
        curves[(algo, int(n))] = errors.mean(axis=0)
    return {"config": asdict(cfg), "results": results, "curves": curves}


def format_ship_table(results):
    """Each ship's mean final-step error (rows of :func:`run_bearings`'s ``results``) as a text
    table: ``algo``, ``N``, then one column per ship and the joint error (their mean)."""
    m = len(results[0]["ship_error_final"])
    head = f"{'algo':<24} {'N':>6} " + " ".join(f"{'ship ' + str(k + 1):>8}" for k in range(m)) + f" {'joint':>8}"
    lines = ["final-step error per ship", head, "-" * len(head)]
    for r in results:
        lines.append(f"{r['algo']:<24} {r['particles']:>6d} " + " ".join(f"{v:>8.5f}" for v in r["ship_error_final"])
                     + f" {r['mean_error_final']:>8.5f}")
    return "\n".join(lines)


def run_bearings(cfg, progress=None):
    """Run the grid in this process; return ``{"config", "results", "curves"}`` (the same numbers
    as the engine path, :meth:`BearingsConfig.tasks`).

    ``results`` rows carry ``algo, particles, ships, mean_error_final,
    std_error_final, mean_error, ms_per_run`` (plus ``degenerate_steps``);
    ``curves`` maps ``(algo, N)`` to the mean error per time step.
    ``progress(k)`` is called after every ``k`` finished runs.
    """
    cfg.validate()
    model = Bearings(cfg.ships, proposal=cfg.proposal)
    per = {}
    for s in range(cfg.sequences):
        for key, v in _sequence_runs(cfg, model, s).items():
            per.setdefault(key, []).append(v)
        if progress:
            progress(cfg.runs * len(cfg.pairs()))
    return _summarize(cfg, per)
