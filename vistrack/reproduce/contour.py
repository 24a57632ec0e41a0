"""Contour tracking experiment (thesis 001, §4.3.2, Table 4.1) on synthetic clips.

Runs through the evaluation engine (:mod:`vistrack.engine.evaluation`): every
(clip, algorithm, N, run) is one task that writes its own file, so the
experiment resumes after an interruption and runs on any Dask cluster. Run
``r`` on clip ``c`` uses ``SeedSequence(seed).spawn(clips)[c].spawn(runs)[r]``
for every algorithm (common random numbers).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..engine.evaluation import entry_tasks, load_task_results, pooled_summary

__all__ = ["ContourConfig", "contour_tasks", "contour_results"]


@dataclass
class ContourConfig:
    """The contour experiment (Table 4.1): ``runs`` per clip and ``(algo, N)`` entry, root ``seed``.

    Attributes
    ----------
    clips : list
        Clip folders.
    entries : list of (str, int)
        ``(algorithm, N)`` pairs.
    runs : int
    seed : int
    """

    clips: list
    entries: list = field(default_factory=lambda: [("ls-n-ips", 30), ("bootstrap", 2000)])
    runs: int = 10
    seed: int = 0


def contour_tasks(cfg):
    """The experiment's tasks (see :func:`vistrack.engine.evaluation.task_list`)."""
    return entry_tasks(cfg, "contour")


def contour_results(tasks, out_dir):
    """Pooled summaries per (algo, N) over clips and runs, in the order of the entries."""
    return pooled_summary(load_task_results(tasks, out_dir))

