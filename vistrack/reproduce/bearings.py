"""The bearings-only experiments of thesis 001, §4.5.5 (Figs. 4.18, 4.21, 4.22; Tables 4.3, 4.4).

10 fixed state/observation sequences, ``R`` runs of every (algorithm, N) on
each; the error is the Euclidean distance of the weighted-mean position to the
truth (averaged over ships). Randomness: ``SeedSequence(seed)`` spawns one
stream for the sequences and one per (sequence, run); a run's stream is the
same for every algorithm and N (common random numbers), so results do not
depend on the order the grid is evaluated in.
"""

from __future__ import annotations

import json
import time
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..models.bearings import simulate
from ..filters import ALGORITHMS, filter_steps, make_filter
from ..models.bearings import LIS_PROPOSALS, Bearings
from ..particles import DegenerateWeightsWarning

__all__ = ["BearingsConfig", "run_bearings", "bearing_tasks", "run_bearing_task", "bearing_results", "DEFAULT_ALGOS"]

DEFAULT_ALGOS = ("bootstrap", "avpf", "lis")


@dataclass
class BearingsConfig:
    """Parameters of one reproduction (the ``config`` block of the JSON)."""

    ships: int = 1
    sequences: int = 10
    runs: int = 100
    steps: int = 10
    algos: list = field(default_factory=lambda: list(DEFAULT_ALGOS))
    particles: list = field(default_factory=lambda: [100, 500, 3000])
    #: LIS's local proposal (:data:`~vistrack.models.bearings.LIS_PROPOSALS`)
    proposal: str = "xi"
    seed: int = 0
    resample: str = "systematic"
    ess_threshold: float | None = None

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
        for a in self.algos:
            if a not in ALGORITHMS or a == "sir":
                choices = ", ".join(sorted(k for k in ALGORITHMS if k != "sir"))
                raise ValueError(f"unknown algorithm {a!r} for bearings; choose from {choices}")


def _sequence_runs(cfg, model, s):
    """Sequence ``s``: its ``runs`` filter runs for every (algorithm, N).

    Returns ``{(algo, N): (errors (runs, steps), seconds, degenerate steps)}``. Run ``r`` draws
    from ``SeedSequence(seed).spawn(2)[1].spawn(sequences * runs)[s * runs + r]`` for every
    algorithm and N (common random numbers).
    """
    seq_ss, run_ss = np.random.SeedSequence(cfg.seed).spawn(2)
    truth, obs = simulate(model, cfg.steps, np.random.default_rng(seq_ss.spawn(cfg.sequences)[s]))
    run_seeds = run_ss.spawn(cfg.sequences * cfg.runs)[s * cfg.runs:(s + 1) * cfg.runs]
    out = {}
    for algo in cfg.algos:
        filt = make_filter(algo, model, resample=cfg.resample, ess_threshold=cfg.ess_threshold)
        for n in cfg.particles:
            errors = np.empty((cfg.runs, cfg.steps))
            elapsed = 0.0
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", DegenerateWeightsWarning)
                for r, ss in enumerate(run_seeds):
                    rng = np.random.default_rng(ss)
                    t0 = time.perf_counter()
                    means = np.array([p.mean() for p in filter_steps(filt, obs, n, rng)])
                    elapsed += time.perf_counter() - t0
                    errors[r] = model.position_error(means, truth)
            degenerate = sum(issubclass(w.category, DegenerateWeightsWarning) for w in caught)
            out[(algo, int(n))] = (errors, elapsed, degenerate)
    return out


def bearing_tasks(cfg):
    """One engine task per fixed sequence (all its runs, algorithms and N inside)."""
    cfg.validate()
    tag = f"M{cfg.ships}_T{cfg.steps}_R{cfg.runs}_S{cfg.sequences}_s{cfg.seed}"
    return [{"name": f"bearings_{tag}_seq{s:03d}", "sequence": s, "config": asdict(cfg)}
            for s in range(cfg.sequences)]


def run_bearing_task(task, out_dir):
    """Engine runner: sequence ``task["sequence"]``, written to ``out_dir/tasks/<name>.json``."""
    from ..evaluation import prepare_worker, write_task_result

    prepare_worker()

    cfg = BearingsConfig(**task["config"])
    res = _sequence_runs(cfg, Bearings(cfg.ships, proposal=cfg.proposal), task["sequence"])
    result = {"sequence": task["sequence"],
              "entries": [{"algo": a, "particles": n, "errors": e.tolist(), "seconds": sec, "degenerate": deg}
                          for (a, n), (e, sec, deg) in res.items()]}
    return write_task_result(Path(out_dir) / "tasks" / f"{task['name']}.json", result, task)


def bearing_results(cfg, tasks, out_dir):
    """``{"config", "results", "curves"}`` from the task files of :func:`bearing_tasks`."""
    per = {}
    for t in tasks:
        data = json.loads((Path(out_dir) / "tasks" / f"{t['name']}.json").read_text())
        for e in data["entries"]:
            per.setdefault((e["algo"], e["particles"]), []).append((np.array(e["errors"]), e["seconds"],
                                                                    e["degenerate"]))
    return _summarize(cfg, per)


def _summarize(cfg, per):
    results, curves = [], {}
    for (algo, n), parts in per.items():
        errors = np.concatenate([p[0] for p in parts])
        final = errors[:, -1]
        results.append(
            {
                "algo": algo,
                "particles": int(n),
                "ships": cfg.ships,
                "mean_error_final": float(final.mean()),
                "std_error_final": float(final.std(ddof=1)) if len(final) > 1 else 0.0,
                "mean_error": float(errors.mean()),
                "ms_per_run": 1e3 * sum(p[1] for p in parts) / len(errors),
                "degenerate_steps": int(sum(p[2] for p in parts)),
            }
        )
        curves[(algo, int(n))] = errors.mean(axis=0)
    return {"config": asdict(cfg), "results": results, "curves": curves}


def run_bearings(cfg, progress=None):
    """Run the grid in this process; return ``{"config", "results", "curves"}`` (the same numbers
    as the engine path, :func:`bearing_tasks`).

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
            progress(cfg.runs * len(cfg.algos) * len(cfg.particles))
    return _summarize(cfg, per)
