"""The landmark shape tracking experiments of seed 000, §4 (Figs. 2a, 2b).

``--k 5``: a deforming pentagon, N = 50, PF-EIS vs PF-Doucet vs PF-Gordon.
``--k 8``: N = 20, mode tracking on the last 10 entries of ``c``; PF-EIS-MT vs
PF-EIS vs PF-Gordon. Every Monte-Carlo run simulates its own sequence from the
known ``X_0`` (the regular K-gon, ``s = θ = 0``, ``c = 0``) and runs every
algorithm on it (common random numbers). The error of a step is the squared
error of the estimated configuration, ``Σ_k |ĥ_k - h_k|²`` with
``ĥ = Σ_i w_i h(X^i)``; ``mse_per_step`` averages it over runs.

Randomness: ``SeedSequence(seed).spawn(runs)``; run ``r`` spawns one stream for
its sequence and one per algorithm, so results do not depend on the order
runs are evaluated in or on which algorithms are chosen.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import asdict, dataclass, field

import numpy as np

from ..batch.tasks import load_task_results, save_result
from ..core.particles import DegenerateWeightsWarning, ParticleSet
from ..models.landmarks.model import Landmarks, simulate
from ..registry import make_filter
from ..registry.comparisons import LANDMARKS, SEED_000_ORDER
from ..registry.filter_specs import get_filter_spec
from ..system.resources import check_memory, prepare_worker
from .bearings import VALUE_BYTES

__all__ = ["LandmarksConfig", "PAPER", "STREAMS", "run_landmarks", "landmarks_run", "run_landmark_task"]

#: the filters of §4, each with its random stream within a run in the order the paper introduces them
#: (:data:`~vistrack.registry.comparisons.SEED_000_ORDER`): fixed, so that a run's draws do not depend on
#: which filters are chosen
STREAMS = SEED_000_ORDER

#: the two experiments of §4: model parameters, N, algorithms
PAPER = {
    5: {"model": dict(sigma_c=0.0025, sigma2_s=1e-4, sigma2_theta=0.25, a_c=0.6, alpha_s=0.9, alpha_theta=0.9,
                      sigma2_o=0.04, p=0.2),
        "particles": 50, "algos": list(LANDMARKS[5]), "mt_dims": None},
    8: {"model": dict(sigma_c=[0.0004] * 2 + [0.000025] * 10, sigma2_s=1e-4, sigma2_theta=0.16, a_c=0.6,
                      alpha_s=0.9, alpha_theta=0.9, sigma2_o=0.01, p=0.2),
        "particles": 20, "algos": list(LANDMARKS[8]), "mt_dims": 10},
}


@dataclass
class LandmarksConfig:
    """One reproduction (the ``config`` block of the JSON)."""

    k: int = 5
    runs: int = 80
    steps: int = 50
    seed: int = 0
    particles: int | None = None
    algos: list = field(default_factory=list)
    mt_dims: int | None = None
    resample: str = "systematic"

    table = "landmarks"
    #: the folder of its task files when ``--out`` is not given
    results_dir = "landmarks-results"

    def __post_init__(self):
        paper = PAPER.get(self.k)
        if paper is None:
            raise ValueError(f"--k must be 5 or 8 (the experiments of §4), got {self.k}")
        if self.particles is None:
            self.particles = paper["particles"]
        if not self.algos:
            self.algos = list(paper["algos"])
        if self.mt_dims is None:
            self.mt_dims = paper["mt_dims"] if paper["mt_dims"] is not None else 2 * self.k - 6

    def validate(self):
        """Raise ``ValueError`` with one clear sentence for bad values."""
        for name in ("runs", "steps", "particles"):
            v = getattr(self, name)
            if v < 1:
                raise ValueError(f"--{name} must be a positive integer, got {v}")
        for a in self.algos:
            if a not in STREAMS:
                raise ValueError(f"unknown algorithm {a!r} for landmarks; choose from {', '.join(STREAMS)}")
        self.check_size()

    def check_size(self, available=None):
        """Raise :class:`~vistrack.system.resources.TooLarge` (one line) when the errors gathered
        (:data:`~vistrack.reproduce.bearings.VALUE_BYTES` per step, run and algorithm), the tasks
        and one step's particles (PF-EIS's ``dim x dim`` matrices each) would not fit in memory."""
        per_step = VALUE_BYTES * self.runs * len(self.algos)
        dim = self.model().dim
        rest = 20_000 * self.runs + int(self.particles) * dim * dim * 8 * 4

        def most(room):
            steps = int((room - rest) // per_step)
            return f"give at most {steps} --steps" if steps >= 1 else "give fewer --runs or particles"

        check_memory(per_step * self.steps + rest, f"{self.runs} runs x {self.steps} steps x {len(self.algos)} "
                     f"algorithm(s) of {self.particles} particles need", most, available=available)

    def model(self):
        """The :class:`~vistrack.models.landmarks.Landmarks` model of the paper's experiment for ``k`` (seed 000 §4)."""
        return Landmarks(self.k, **PAPER[self.k]["model"])

    def tasks(self):
        """One engine task per Monte-Carlo run (every algorithm inside, common random numbers)."""
        self.validate()
        seeds = np.random.SeedSequence(self.seed).spawn(self.runs)
        tag = f"k{self.k}_N{self.particles}_T{self.steps}_s{self.seed}_mt{self.mt_dims}"
        return [{"name": f"landmarks_{tag}_r{r:03d}", "run": r, "seed_seq": seeds[r], "config": asdict(self)}
                for r in range(self.runs)]

    @property
    def runner(self):
        """:func:`run_landmark_task`."""
        return run_landmark_task

    def results(self, tasks, out_dir):
        """``{"config", "results", "curves"}`` from the task files of :meth:`tasks`."""
        runs = load_task_results(tasks, out_dir)
        per = {a: [(np.array(r["algos"][a]["sq_error"]), r["algos"][a]["seconds"], r["algos"][a]["degenerate"])
                   for r in runs] for a in self.algos}
        return _summarize(self, per)


def _filter(cfg, algo, model):
    """``algo`` on ``model`` with the config's resampling and, for a filter that takes it
    (:attr:`~vistrack.registry.filter_specs.FilterSpec.options`), its ``mt_dims``."""
    kw = {"mt_dims": cfg.mt_dims} if any(o.name == "mt_dims" for o in get_filter_spec(algo).options) else {}
    return make_filter(algo, model, resample=cfg.resample, **kw)


def landmarks_run(model, filt, obs, n, rng):
    """Estimated configurations ``(T, K)`` of one run from ``n`` copies of ``X_0``."""
    particles = ParticleSet(model.sample_prior(n, rng))
    est = np.empty(obs.shape, complex)
    for t, y in enumerate(obs):
        particles = filt.step(particles, y, rng)
        est[t] = particles.weights @ model.configuration(particles.states)
    return est


def _one_run(cfg, model, r, seed_seq):
    """Run ``r``: simulate its sequence, track it with every algorithm.

    Returns ``{algo: (squared error per step, seconds, degenerate steps)}``.
    """
    seq_ss, *algo_ss = seed_seq.spawn(1 + len(STREAMS))
    states, obs = simulate(model, cfg.steps, np.random.default_rng(seq_ss))
    truth = model.configuration(states[1:])
    out = {}
    for a in cfg.algos:
        rng = np.random.default_rng(algo_ss[STREAMS.index(a)])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", DegenerateWeightsWarning)
            t0 = time.perf_counter()
            est = landmarks_run(model, _filter(cfg, a, model), obs, cfg.particles, rng)
            sec = time.perf_counter() - t0
        deg = sum(issubclass(w.category, DegenerateWeightsWarning) for w in caught)
        out[a] = (np.sum(np.abs(est - truth) ** 2, axis=1), sec, deg)
    return out


def run_landmark_task(task, out_dir):
    """Engine runner: one run, its result written under ``out_dir`` (:func:`~vistrack.batch.tasks.save_result`)."""
    prepare_worker()
    cfg = LandmarksConfig(**task["config"])
    res = _one_run(cfg, cfg.model(), task["run"], task["seed_seq"])
    result = {"run": task["run"], "algos": {a: {"sq_error": [float(v) for v in sq], "seconds": sec, "degenerate": deg}
                                            for a, (sq, sec, deg) in res.items()}}
    return save_result(out_dir, task, result)


def _summarize(cfg, per):
    results, curves = [], {}
    for a in cfg.algos:
        sq = np.array([p[0] for p in per[a]])
        curve = sq.mean(axis=0)
        results.append({"algo": a, "particles": int(cfg.particles), "k": cfg.k,
                        "mse_per_step": [float(v) for v in curve], "mean_mse": float(curve.mean()),
                        "final_mse": float(curve[-1]), "median_run_mse": float(np.median(sq.mean(axis=1))),
                        "ms_per_run": 1e3 * sum(p[1] for p in per[a]) / len(sq),
                        "degenerate_steps": int(sum(p[2] for p in per[a]))})
        curves[(a, int(cfg.particles))] = curve
    return {"config": asdict(cfg), "results": results, "curves": curves}


def run_landmarks(cfg, progress=None):
    """Run the grid in this process; return ``{"config", "results", "curves"}``.

    ``results`` rows: ``algo, particles, k, mse_per_step, mean_mse, ms_per_run``
    (plus ``final_mse``, ``median_run_mse``, ``degenerate_steps``);
    ``curves[(algo, N)]`` is the MSE per step. ``progress(1)`` is called after
    every run. The same numbers as the engine path (:meth:`LandmarksConfig.tasks`).
    """
    cfg.validate()
    model = cfg.model()
    per = {a: [] for a in cfg.algos}
    for task in cfg.tasks():
        for a, v in _one_run(cfg, model, task["run"], task["seed_seq"]).items():
            per[a].append(v)
        if progress:
            progress(1)
    return _summarize(cfg, per)
