"""Several plates at once (thesis 001 §4.5.3 with App. C's partitioned sampling) on synthetic road
clips with up to three plates in view (``make_plate_clip(overlap=True)``).

Every (clip, algorithm, N, run) is one task of the evaluation engine, ``eval --targets``'s
(:mod:`vistrack.evaluation.multi_target`: the reported plates with their ids per frame, scored against
the clip's ``objects.csv``). Run ``r`` on clip ``c`` uses ``SeedSequence(seed).spawn(clips)[c].spawn(runs)[r]``
for every algorithm. The results pool the scores of every run per algorithm and N.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..evaluation.experiment import entries_config
from ..evaluation.multi_target import plates_equal_time, run_plates_task, score_plates_tasks
from ..registry.comparisons import PLATES
from ..scoring.mot import pool_scores, require_motmetrics
from .contour import ContourConfig
from .plate import PlateConfig

__all__ = ["PlatesConfig", "plates_results", "plate_experiment"]


@dataclass
class PlatesConfig(ContourConfig):
    """The several-plates experiment: ``runs`` per clip and ``(algo, N)`` entry, root ``seed``
    (:class:`~vistrack.reproduce.contour.ContourConfig`) and the number of plate slots ``targets``."""

    entries: list = field(default_factory=lambda: list(PLATES))
    runs: int = 10
    targets: int = 3

    table = "plates"
    #: the folder of its task files when ``--out`` is not given
    results_dir = "plate-overlap-results"
    model = "plate"
    several = True

    def validate(self):
        """As the contour experiment's, and the MOT scorer installed (one ``ValueError`` line before any
        tracking, :func:`~vistrack.scoring.mot.require_motmetrics`)."""
        super().validate()
        try:
            require_motmetrics()
        except ImportError as e:
            raise ValueError(str(e)) from None

    def tasks(self):
        """The experiment's tasks, each with ``targets``."""
        tasks = super().tasks()
        for t in tasks:
            t["targets"] = int(self.targets)
        return tasks

    @property
    def runner(self):
        """:func:`~vistrack.evaluation.multi_target.run_plates_task`."""
        return run_plates_task

    def results(self, tasks, out_dir):
        """``{"config", "results"}``: :func:`plates_results`."""
        return {"config": entries_config(self), "results": plates_results(self, tasks, out_dir)}

    def equal_time(self, frames=60):
        """:func:`~vistrack.evaluation.multi_target.plates_equal_time` on the first clip."""
        return plates_equal_time(self.clips[0], self.entries, self.targets, frames)


def plates_results(cfg, tasks, out_dir):
    """Per (algo, N), in the order of the entries: :func:`~vistrack.scoring.mot.pool_scores` over every clip
    and run, the number of clips, and per clip the mean MOTA and IDF1."""
    by_entry = {}
    for r in score_plates_tasks(tasks, out_dir):
        by_entry.setdefault((r["algo"], r["particles"]), []).append(r)
    out = []
    for (algo, n), rows in by_entry.items():
        per_clip = {}
        for r in rows:
            per_clip.setdefault(Path(r["clip"]).name, []).append(r)
        out.append({"algo": algo, "particles": n, "clips": len(per_clip), **pool_scores(rows),
                    "per_clip": {c: [pool_scores(v)["mota"], pool_scores(v)["idf1"]] for c, v in per_clip.items()}})
    return out


def plate_experiment(clips, *, runs, seed, overlap=False, targets=PlatesConfig.targets, entries=None, out=None):
    """``(config, out)`` of ``vistrack reproduce plate``: a :class:`~vistrack.reproduce.plate.PlateConfig` of one
    plate, or with ``overlap`` a :class:`PlatesConfig` of ``targets`` slots; ``entries`` ``None``: the
    experiment's own; ``out`` ``None``: its folder (the config's ``results_dir``)."""
    chosen = {} if entries is None else {"entries": entries}
    cfg = PlatesConfig(clips, runs=runs, seed=seed, targets=targets, **chosen) if overlap else \
        PlateConfig(clips, runs=runs, seed=seed, **chosen)
    return cfg, cfg.results_dir if out is None else out
