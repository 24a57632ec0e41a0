"""Shared by the ``vistrack reproduce`` commands: their options, the progress bar of making clips and
what they print (kept apart from the command group so that each command's module imports it without
importing the group: no import circle)."""

from __future__ import annotations

from contextlib import contextmanager

import click
from tqdm import tqdm

from vistrack.batch.cluster import run_grid
from vistrack.registry.filter_specs import get_filter_spec
from vistrack.reproduce.clip_suites import SUITES
from vistrack.reproduce.tables import format_table

from .options import SEED, Output, Size, check_outputs, default_of, option, size_text

__all__ = ["Entries", "engine_options", "suite_options", "output_options", "making_clips", "equal_time_line",
           "results_lines", "default_entries", "entries_text", "check_suite_outputs"]


def _stacked(opts):
    """A decorator applying the click options ``opts`` in their order (as ``--help`` lists them)."""
    def deco(f):
        for opt in reversed(opts):
            f = opt(f)
        return f

    return deco


def engine_options(config):
    """The evaluation engine's options, shared by every ``reproduce`` command (``--out``: the ``config``
    class's ``results_dir``)."""
    opts = [
        option("--workers", source=run_grid, type=click.IntRange(min=0),
               help="LocalCluster worker processes (0: one per core)."),
        click.option("--scheduler", help="Address of a running Dask scheduler [default: a LocalCluster]."),
        click.option("--in-process", is_flag=True, help="LocalCluster workers as threads of this process."),
        option("--out", "out_dir", source=config, key="results_dir", type=Output(file_okay=False),
               help="Folder for the per-task result files (OUT/tasks)."),
        click.option("--resume", is_flag=True, help="Keep finished tasks in --out and run only the rest."),
    ]
    return _stacked(opts)


def suite_options(config, clips_help, algos_help):
    """A clip suite's options (``--clips --make --frames --size --algos --runs --seed``), shared by
    the ``reproduce`` commands that track synthetic clips: their defaults those of the experiment's ``config``
    class and of its clip suite (:data:`~vistrack.reproduce.clip_suites.SUITES`)."""
    suite = SUITES[config.table]
    opts = [
        click.option("--clips", "clips_dir", type=click.Path(file_okay=False), help=clips_help),
        option("--make", "make", source=suite, type=click.IntRange(min=1),
               help="Clips to generate (seeds 1..MAKE) when --clips has none."),
        option("--frames", source=suite, type=click.IntRange(min=2), help="Frames per made clip."),
        option("--size", source=suite, shown=size_text, type=Size(), help="Frame size of made clips."),
        option("--algos", "entries", source=config, key="entries", shown=entries_text, type=Entries(),
               help=algos_help),
        option("--runs", source=config, type=click.IntRange(min=1), help="Runs per clip."),
        option("--seed", source=config, type=SEED,
               help="Random seed: the same seed gives the same output, bit for bit."),
    ]
    return _stacked(opts)


def output_options(plots_help):
    """``--json``, ``--plots`` (with ``plots_help``) and ``--quiet``, shared by the ``reproduce`` commands."""
    opts = [
        click.option("--json", "json_path", type=Output(dir_okay=False), help="Write results as JSON here."),
        click.option("--plots", "plots_dir", type=Output(file_okay=False), help=plots_help),
        click.option("--quiet", "-q", is_flag=True, help="No progress bar."),
    ]
    return _stacked(opts)


class Entries(click.ParamType):
    """``algo:N`` pairs, comma-separated, e.g. ``ls-n-ips:30,bootstrap:2000``: registered algorithms
    (:func:`vistrack.registry.filter_specs.get_filter_spec`), positive counts."""

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
            try:
                get_filter_spec(algo)
            except ValueError as e:
                self.fail(str(e), param, ctx)
            out.append((algo, n))
        return out


def entries_text(entries):
    """``(algo, N)`` entries as ``--algos`` takes them: ``ls-n-ips:30,bootstrap:2000``."""
    return ",".join(f"{a}:{n}" for a, n in entries)


def default_entries(config):
    """A config's default ``(algo, N)`` entries as ``--algos`` takes them (:func:`entries_text`)."""
    return entries_text(default_of(config, "entries"))


@contextmanager
def making_clips(make, frames, quiet):
    """A progress bar over the frames of ``make`` clips of ``frames`` frames being made (unless ``quiet``):
    yields its ``update``."""
    with tqdm(total=make * frames, unit="frame", desc="making clips", disable=quiet, leave=False) as bar:
        yield bar.update


def equal_time_line(unit):
    """``on_equal_time(entries, times)``: the entries of equal time and their times on one line."""
    return lambda entries, times: click.echo(
        "equal time: " + ", ".join(f"{a}:{n}" for a, n in entries) + " ("
        + ", ".join(f"{k} {v:.1f} ms/{unit}" for k, v in times.items()) + ")")


def results_lines(experiment, done):
    """What a reproduction prints: its table, the JSON file and the plots written
    (:class:`~vistrack.reproduce.reproduction.Reproduction`)."""
    lines = [format_table(experiment, done.out["results"])]
    if done.json_path:
        lines.append(f"results written to {done.json_path}")
    if done.plots:
        lines.append(f"plot{'s' if len(done.plots) > 1 else ''} written to {' and '.join(done.plots)}")
    return "\n".join(lines)


def check_suite_outputs(experiment, clips_dir, json_path):
    """Before any clip is made or tracked: ``--json`` must not be a file of the clips it reads (the
    experiment's ``--clips``, or its default folder; :func:`~vistrack.cli.options.check_outputs`)."""
    check_outputs({"--json": json_path}, clips_dir or SUITES[experiment].folder)
