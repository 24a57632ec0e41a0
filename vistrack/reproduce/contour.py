"""Contour tracking experiment (thesis 001, §4.3.2, Table 4.1) on synthetic clips.

Runs through the evaluation engine (:mod:`vistrack.evaluation.experiment`): every
(clip, algorithm, N, run) is one task that writes its own file, so the
experiment resumes after an interruption and runs on any Dask cluster. Run
``r`` on clip ``c`` uses ``SeedSequence(seed).spawn(clips)[c].spawn(runs)[r]``
for every algorithm (common random numbers).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..batch.tasks import load_task_results
from ..evaluation.experiment import entries_config, entry_tasks, run_task
from ..registry import check_algo, get_filter_spec
from ..registry.comparisons import CONTOUR
from ..scoring.aggregate import pooled_summary

__all__ = ["ContourConfig"]


@dataclass
class ContourConfig:
    """The contour experiment (Table 4.1): ``runs`` per clip and ``(algo, N)`` entry, root ``seed``.
    An :class:`~vistrack.batch.cluster.Experiment` (:meth:`tasks`, :attr:`runner`, :meth:`results`).

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
    entries: list = field(default_factory=lambda: list(CONTOUR))
    runs: int = 10
    seed: int = 0

    #: the experiment's table and figures (:mod:`vistrack.reproduce.tables`)
    table = "contour"
    #: the folder of its task files when ``--out`` is not given
    results_dir = "contour-results"
    #: the registered model its tasks build (:mod:`vistrack.registry`)
    model = "contour"
    #: whether it tracks several targets (the model's several-target form)
    several = False

    def validate(self):
        """A one-line ``ValueError`` for an unknown algorithm or one that does not run on the model."""
        for algo, _ in self.entries:
            get_filter_spec(algo)
            check_algo(self.model, algo, self.several)

    def tasks(self):
        """The experiment's tasks (:func:`~vistrack.evaluation.experiment.entry_tasks`)."""
        return entry_tasks(self, self.model)

    @property
    def runner(self):
        """:func:`~vistrack.evaluation.experiment.run_task`: a task of ``eval`` with the thesis's lost rule."""
        return run_task

    def results(self, tasks, out_dir):
        """``{"config", "results"}``: pooled summaries per (algo, N) over clips and runs, in the order of the
        entries (:func:`~vistrack.scoring.aggregate.pooled_summary`)."""
        return {"config": entries_config(self), "results": pooled_summary(load_task_results(tasks, out_dir))}

