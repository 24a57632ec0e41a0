"""The bearings-only experiments of thesis 001, §4.5.5 (Figs. 4.18, 4.21, 4.22; Tables 4.3, 4.4).

10 fixed state/observation sequences, ``R`` runs of every (algorithm, N) on
each; the error is the Euclidean distance of the weighted-mean position to the
truth (averaged over ships). Randomness: ``SeedSequence(seed)`` spawns one
stream for the sequences and one per (sequence, run); a run's stream is the
same for every algorithm and N (common random numbers), so results do not
depend on the order the grid is evaluated in.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import asdict, dataclass, field

import numpy as np

from ..data_synth.bearings import simulate
from ..filters import ALGORITHMS, filter_steps, make_filter
from ..models.bearings import Bearings
from ..particles import DegenerateWeightsWarning

__all__ = ["BearingsConfig", "run_bearings", "DEFAULT_ALGOS"]

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


def run_bearings(cfg, progress=None):
    """Run the grid; return ``{"config", "results", "curves"}``.

    ``results`` rows carry ``algo, particles, ships, mean_error_final,
    std_error_final, mean_error, ms_per_run`` (plus ``degenerate_steps``);
    ``curves`` maps ``(algo, N)`` to the mean error per time step.
    ``progress(k)`` is called after every ``k`` finished runs.
    """
    cfg.validate()
    model = Bearings(cfg.ships)
    root = np.random.SeedSequence(cfg.seed)
    seq_ss, run_ss = root.spawn(2)
    sequences = [simulate(model, cfg.steps, np.random.default_rng(s)) for s in seq_ss.spawn(cfg.sequences)]
    run_seeds = run_ss.spawn(cfg.sequences * cfg.runs)

    results, curves = [], {}
    for algo in cfg.algos:
        filt = make_filter(algo, model, resample=cfg.resample, ess_threshold=cfg.ess_threshold)
        for n in cfg.particles:
            errors = np.empty((cfg.sequences * cfg.runs, cfg.steps))
            elapsed, degenerate = 0.0, 0
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", DegenerateWeightsWarning)
                for s, (truth, obs) in enumerate(sequences):
                    for r in range(cfg.runs):
                        k = s * cfg.runs + r
                        rng = np.random.default_rng(run_seeds[k])
                        t0 = time.perf_counter()
                        means = np.array([p.mean() for p in filter_steps(filt, obs, n, rng)])
                        elapsed += time.perf_counter() - t0
                        errors[k] = model.position_error(means, truth)
                    if progress:
                        progress(cfg.runs)
                degenerate = sum(issubclass(w.category, DegenerateWeightsWarning) for w in caught)
            final = errors[:, -1]
            results.append(
                {
                    "algo": algo,
                    "particles": int(n),
                    "ships": cfg.ships,
                    "mean_error_final": float(final.mean()),
                    "std_error_final": float(final.std(ddof=1)) if len(final) > 1 else 0.0,
                    "mean_error": float(errors.mean()),
                    "ms_per_run": 1e3 * elapsed / len(errors),
                    "degenerate_steps": int(degenerate),
                }
            )
            curves[(algo, int(n))] = errors.mean(axis=0)
    return {"config": asdict(cfg), "results": results, "curves": curves}
