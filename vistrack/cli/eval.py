"""``vistrack eval``: algorithms × particle counts × runs over clips, on Dask."""

from __future__ import annotations

import click

from vistrack.batch.cluster import run_grid
from vistrack.evaluation.experiment import EvalConfig
from vistrack.evaluation.pipeline import eval_config, evaluate
from vistrack.io.results_format import FORMATS
from vistrack.registry import BASELINES, DEFAULT_MODEL, MODELS, algos_for, all_algos, targets_model
from vistrack.reports.eval_report import averages

from .errors import one_line
from .options import SEED, IntList, Output, StrList, check_outputs, joined, option
from .progress import Bars, progress

__all__ = ["eval_cmd"]


def _chosen(bars):
    """``on_equal_time``: the particle counts of equal time on one line (nothing with ``quiet``), after the bar
    shown is closed."""
    if bars.quiet:
        return None
    return lambda chosen: bars.echo("equal time per frame: " + ", ".join(f"{a} N={n}" for a, n in chosen.items()))


#: ``eval --help``
EVAL_HELP = """Evaluate algorithms over CLIPS with ground truth: clip folders, videos or image folders (OTB, VOT,
GOT-10k, LaSOT or vistrack's layout), folders of them, dataset roots (a LaSOT root, a GOT-10k split,
a VOT workspace) or URLs of clip folders.

\b
Examples:
  vistrack eval suite --algos ls-n-ips,lis,bootstrap,opencv-mil --particles 30,100 --runs 20 --out results
  vistrack eval LaSOT/ --algos lis,opencv-csrt --runs 3 --out ev      # a dataset root
  vistrack eval suite --algos lis,bootstrap --particles 100 --equal-time --out eq
  vistrack eval suite --resume --out results ...                      # continue an interrupted run
  vistrack eval clips/ --algos lis --results-dir other/ --out results # score another tracker's files too

Every clip × algorithm × N × run is one Dask task writing its own file
under OUT/tasks, so --resume continues an interrupted evaluation. Each
run starts from the first ground-truth box. Writes OUT/report.md (tables
and plots), OUT/report.html (the same with an annotated video per tracker,
opened from the folder alone), OUT/results.json, OUT/results.csv (one row
per task) and PNG plots.
"""


@click.command("eval", help=EVAL_HELP)
@click.argument("clips", nargs=-1, required=True, type=click.Path())
@option("--algos", source=EvalConfig, shown=joined, type=StrList(),
        help="Algorithms, any that run takes on the model (" + ", ".join(all_algos()) + ") and comparison "
             "trackers (" + ", ".join(b.help for b in BASELINES.values()) + ").")
@option("--particles", source=EvalConfig, shown=joined, type=IntList(), help="Particle counts N.")
@option("--runs", source=EvalConfig, type=click.IntRange(min=1), help="Runs per clip × algo × N.")
@option("--seed", source=EvalConfig, type=SEED,
        help="Random seed: the same seed gives the same output, bit for bit. Run r of every clip tracks it as "
             "`vistrack run CLIP --init-gt --seed S --run r` does (run 0: as run --seed S), whatever the workers: "
             "eval --runs 1 --seed S gives run --seed S's track.")
@click.option("--model", default=None, metavar="[" + "|".join(MODELS) + "]",
              help="Tracking model, any registered one, started from the first ground-truth box [default: as run: "
                   "the model the clips' meta.json names (synthetic clips), else " + DEFAULT_MODEL + ", any object, "
                   "appearance learned from the first frame]. plate: layout from the box's aspect.")
@click.option("--equal-time", is_flag=True, help="Pick N per algorithm for equal CPU time per frame.")
@click.option("--targets", type=click.IntRange(min=1), default=None,
              help="Plate model: track up to K plates at once (no start box; "
                   + ", ".join(algos_for(targets_model(), targets=True)) + ") and score MOTA and IDF1 against each "
                   "clip's objects.csv (synth plate).")
@click.option("--scheduler", help="Address of a running Dask scheduler (tcp://host:8786) [default: a LocalCluster].")
@option("--workers", source=run_grid, type=click.IntRange(min=0),
        help="LocalCluster worker processes (0: one per core).")
@option("--timeout", source=run_grid, type=click.IntRange(min=1), help="Seconds to wait for --scheduler.")
@click.option("--in-process", is_flag=True, help="LocalCluster workers as threads of this process (debugging, tests).")
@click.option("--resume", is_flag=True, help="Keep finished task files in --out and run only the rest.")
@click.option("--results-dir", "results_dirs", multiple=True, type=click.Path(exists=True, file_okay=False),
              help="Score another tracker's result files beside vistrack's: DIR/<clip name>.txt per clip (OTB) or "
                   "DIR/<clip>/<clip>_001.txt (GOT-10k, VOT), x,y,w,h per frame (0,0,0,0 for none; what run "
                   "--results writes); named after DIR. Repeat for several trackers; --algos '' scores only these.")
@option("--results-format", "results_format", source=evaluate, type=click.Choice(FORMATS),
        help="Format of the --results-dir files: otb (1-based pixels, as the OTB toolkit and pytracking write "
             "them), got10k or vot (0-based).")
@click.option("--out", "out_dir", required=True, type=Output(file_okay=False), help="Results folder.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar; print only errors.")
def eval_cmd(clips, algos, particles, runs, seed, model, equal_time, targets, scheduler, workers, timeout, in_process,
             resume, results_dirs, results_format, out_dir, quiet):
    """``vistrack eval``: :data:`EVAL_HELP`."""
    check_outputs({"--out": out_dir}, None, [*clips, *results_dirs])
    with one_line():
        cfg = eval_config(clips, algos=algos, particles=particles, runs=runs, seed=seed, model=model, targets=targets,
                          results_dirs=results_dirs)
    engine = dict(scheduler=scheduler, workers=workers, timeout=timeout, in_process=in_process, resume=resume)
    bars = Bars(quiet)
    with progress("eval", quiet, bars) as hooks:
        done = evaluate(cfg, out_dir, results_dirs=results_dirs, results_format=results_format, equal_time=equal_time,
                        on_equal_time=_chosen(bars), compiling_progress=bars.compiling, **engine, **hooks)
    if not quiet:
        click.echo(averages(out_dir))
        click.echo(done.wrote())
