"""Shared by the ``vistrack reproduce`` commands: their options, the clip suites, the engine call
and the reports (kept apart from the command group so that each command's module imports it
without importing the group: no import circle)."""

from __future__ import annotations

import json
import os

import click
from tqdm import tqdm

from vistrack.engine.evaluation import write_atomic
from vistrack.reproduce.tables import format_table, write_plots

from .options import SEED, check_writable

__all__ = ["Entries", "engine_options", "suite_options", "output_options"]


def _stacked(opts):
    """A decorator applying the click options ``opts`` in their order (as ``--help`` lists them)."""
    def deco(f):
        for opt in reversed(opts):
            f = opt(f)
        return f

    return deco


def engine_options(default_out):
    """The evaluation engine's options, shared by every ``reproduce`` command."""
    opts = [
        click.option("--workers", default=0, show_default=True, type=click.IntRange(min=0),
                     help="LocalCluster worker processes (0: one per core)."),
        click.option("--scheduler", help="Address of a running Dask scheduler [default: a LocalCluster]."),
        click.option("--in-process", is_flag=True, help="LocalCluster workers as threads of this process."),
        click.option("--out", "out_dir", default=default_out, show_default=True, type=click.Path(file_okay=False),
                     help="Folder for the per-task result files (OUT/tasks)."),
        click.option("--resume", is_flag=True, help="Keep finished tasks in --out and run only the rest."),
    ]
    return _stacked(opts)


def suite_options(clips_help, size, algos, algos_help, runs, frames=300):
    """A clip suite's options (``--clips --make --frames --size --algos --runs --seed``), shared by
    the ``reproduce`` commands that track synthetic clips."""
    opts = [
        click.option("--clips", "clips_dir", type=click.Path(file_okay=False), help=clips_help),
        click.option("--make", "make", default=10, show_default=True, type=click.IntRange(min=1),
                     help="Clips to generate (seeds 1..MAKE) when --clips has none."),
        click.option("--frames", default=frames, show_default=True, type=click.IntRange(min=2),
                     help="Frames per made clip."),
        click.option("--size", default=size, show_default=True, help="Frame size of made clips."),
        click.option("--algos", "entries", default=algos, show_default=True, type=Entries(), help=algos_help),
        click.option("--runs", default=runs, show_default=True, type=click.IntRange(min=1), help="Runs per clip."),
        click.option("--seed", default=0, show_default=True, type=SEED,
                      help="Random seed: the same seed gives the same output, bit for bit."),
    ]
    return _stacked(opts)


def output_options(plots_help):
    """``--json``, ``--plots`` (with ``plots_help``) and ``--quiet``, shared by the ``reproduce`` commands."""
    opts = [
        click.option("--json", "json_path", type=click.Path(dir_okay=False), help="Write results as JSON here."),
        click.option("--plots", "plots_dir", type=click.Path(file_okay=False), help=plots_help),
        click.option("--quiet", "-q", is_flag=True, help="No progress bar."),
    ]
    return _stacked(opts)


class Entries(click.ParamType):
    """``algo:N`` pairs, comma-separated, e.g. ``ls-n-ips:30,bootstrap:2000``."""

    name = "ALGO:N,..."

    def convert(self, value, param, ctx):
        """Parse ``value`` into a list of ``(algo, N)`` pairs; a bad pair fails with click's one-line usage error."""
        if isinstance(value, list):
            return value
        out = []
        for item in str(value).split(","):
            algo, _, n = item.strip().partition(":")
            try:
                n = int(n)
            except ValueError:
                self.fail(f"expected ALGO:N pairs such as ls-n-ips:30, got {item!r}", param, ctx)
            if n < 1:
                self.fail(f"number of particles must be positive in {item!r}", param, ctx)
            out.append((algo, n))
        return out


def _report(experiment, out, config, json_path, plots_dir, title=""):
    """Print the experiment's table; write ``--json`` and ``--plots``."""
    click.echo(format_table(experiment, out["results"]))
    if json_path:
        write_atomic(json_path, json.dumps({"config": config, "results": out["results"]}, indent=2))
        click.echo(f"results written to {json_path}")
    if plots_dir:
        paths = write_plots(experiment, out, plots_dir, title=title)
        click.echo(f"plot{'s' if len(paths) > 1 else ''} written to {' and '.join(paths)}")


def _plots_dir(plots_dir, first_png):
    """Create ``--plots`` and check it is writable before any work."""
    if plots_dir:
        try:
            os.makedirs(plots_dir, exist_ok=True)
        except OSError as e:
            raise click.ClickException(f"cannot create --plots folder {plots_dir}: {e.strerror}") from None
        check_writable(os.path.join(plots_dir, first_png), "plot")


def _check_entries(entries):
    from vistrack.filters import ALGORITHMS

    for algo, _ in entries:
        if algo not in ALGORITHMS:
            raise click.ClickException(f"unknown algorithm {algo!r}; choose from {', '.join(sorted(ALGORITHMS))}")


def _clip_suite(clips_dir, default, make, frames, size, maker, prefix, quiet, grid=None, **kw):
    """:func:`vistrack.reproduce.suite.clip_suite` in ``clips_dir`` (or ``default``), with a progress bar;
    ``grid``: ``(entries, runs)``, the task grid checked against memory first (as made clips)."""
    from vistrack.engine.evaluation import check_grid_size
    from vistrack.reproduce.suite import clip_suite

    from .options import Size

    if grid is not None:
        check_grid_size(make, *grid, frames)
    with tqdm(total=make * frames, unit="frame", desc="making clips", disable=quiet, leave=False) as bar:
        return clip_suite(clips_dir or default, make, frames, Size().convert(size, None, None), maker, prefix,
                          progress=bar.update, **kw)


def _run(tasks, out_dir, desc, runner=None, **engine):
    """Run ``tasks`` on the evaluation engine into ``out_dir`` (created; see
    :func:`vistrack.cli.eval.run_tasks`: nothing in it is removed, each task file is replaced
    whole when its task finishes, and ``--resume`` keeps only files of the very same task);
    returns the folder."""
    from pathlib import Path

    from .grid import run_tasks

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise click.ClickException(f"cannot create --out folder {out_dir}: {e.strerror}") from None
    run_tasks(tasks, out, desc=desc, runner=runner, **engine)
    return out
