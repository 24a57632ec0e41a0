"""A reproduction as one call (:func:`reproduce`): its configuration checked, the particle counts of
equal time where asked, its tasks on the engine (:func:`vistrack.batch.cluster.run_experiment`), and its
results written as JSON and as the figures of the seeds (:mod:`vistrack.reproduce.tables`).

Each experiment's config is an :class:`~vistrack.batch.cluster.Experiment` with a ``table`` (its name in
:data:`~vistrack.reproduce.tables.TABLES`), a ``validate()`` and, where its counts can be set for equal
time, an ``equal_time()`` returning ``(entries, times)``.
"""

from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass

from ..batch.cluster import run_experiment
from ..batch.tasks import write_atomic
from ..io.outputs import check_writable
from .tables import FIRST_PLOT, write_plots

__all__ = ["Reproduction", "reproduce", "plots_folder"]


@dataclass
class Reproduction:
    """What :func:`reproduce` did: ``out`` (``{"config", "results"}``, with ``"curves"`` where the
    experiment plots them), the JSON file written (or ``None``) and the plots written."""

    out: dict
    json_path: str | None = None
    plots: list = dataclasses.field(default_factory=list)


def plots_folder(plots_dir, experiment):
    """Make the ``--plots`` folder and check that ``experiment``'s first figure can be written there, before
    any work; a one-line ``ValueError`` otherwise."""
    if not plots_dir:
        return
    try:
        os.makedirs(plots_dir, exist_ok=True)
    except OSError as e:
        raise ValueError(f"cannot create --plots folder {plots_dir}: {e.strerror}") from None
    check_writable(os.path.join(plots_dir, FIRST_PLOT[experiment]), "plot")


def reproduce(cfg, out, *, json_path=None, plots_dir=None, title="", equal_time=False, on_equal_time=None,
              **engine):
    """Run the reproduction ``cfg`` into the folder ``out`` (its task files) and write its results.

    ``cfg.validate()`` first; with ``equal_time`` the entries of ``cfg.equal_time()``
    (``on_equal_time(entries, times)`` hears them before the grid runs); then
    :func:`~vistrack.batch.cluster.run_experiment` with the ``engine`` options; then ``{"config",
    "results"}`` as JSON to ``json_path`` and the figures into ``plots_dir``
    (:func:`~vistrack.reproduce.tables.write_plots`, titled ``title``). Returns a :class:`Reproduction`.
    """
    cfg.validate()
    plots_folder(plots_dir, cfg.table)  # first: the JSON may go into the folder it makes
    check_writable(json_path, "--json file")
    if equal_time:
        entries, times = cfg.equal_time()
        if on_equal_time:
            on_equal_time(entries, times)
        cfg = dataclasses.replace(cfg, entries=entries)
    out = run_experiment(cfg, out, **engine)
    done = Reproduction(out)
    if json_path:
        write_atomic(json_path, json.dumps({"config": out["config"], "results": out["results"]}, indent=2))
        done.json_path = json_path
    if plots_dir:
        done.plots = write_plots(cfg.table, out, plots_dir, title=title)
    return done
