"""``vistrack reproduce ...``: the seeds' experiments."""

from __future__ import annotations

import json
import os

import click
from tqdm import tqdm

from vistrack.reproduce.bearings import (DEFAULT_ALGOS, BearingsConfig, bearing_results, bearing_tasks,
                                         equal_time_pairs, format_ship_table, run_bearing_task)
from vistrack.reproduce.landmarks import (LANDMARK_ALGOS, LandmarksConfig, landmark_results, landmark_tasks,
                                          run_landmark_task)
from vistrack.reproduce.plate import PlateConfig, plate_results, plate_tasks, run_plate_task
from vistrack.evaluation import entries_config, write_atomic
from vistrack.reproduce.contour import ContourConfig, contour_results, contour_tasks
from vistrack.reproduce.report import format_table, write_plots

from .options import SEED, Fraction, IntList, StrList, check_writable

__all__ = ["reproduce"]


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


@click.group()
def reproduce():
    """Reproduce the experiments of the seeds (tables and figures)."""


@reproduce.command()
@click.option("--ships", default=1, show_default=True, type=int, help="Number of ships M (state dimension 4M).")
@click.option("--sequences", default=10, show_default=True, type=int, help="Fixed state/observation sequences.")
@click.option("--runs", default=100, show_default=True, type=int, help="Filter runs per sequence.")
@click.option("--steps", default=10, show_default=True, type=int, help="Time steps per sequence.")
@click.option("--algos", default=",".join(DEFAULT_ALGOS), show_default=True, type=StrList(),
              help="Algorithms, comma-separated (bootstrap, avpf, lis, lls, partitioned, branched-partitioned, ...).")
@click.option("--particles", default="100,500,3000", show_default=True, type=IntList(),
              help="Particle counts N, comma-separated.")
@click.option("--equal-time", is_flag=True, help="Run the first algorithm at each N and every other at the N that "
              "takes as long per run (timed here on the first sequence).")
@click.option("--seed", default=0, show_default=True, type=SEED, help="Seed of sequences and runs.")
@click.option("--resample", default="systematic", show_default=True,
              type=click.Choice(["multinomial", "residual", "stratified", "systematic"]),
              help="Resampling scheme of the particle filter.")
@click.option("--ess-threshold", default=None, type=Fraction(),
              help="Resample when ESS < threshold·N (default: every step).")
@click.option("--lis-proposal", default="xi", show_default=True, type=click.Choice(["xi", "position"]),
              help="LIS's proposal: the noise move across the bearing, or §4.5.5's position move.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), help="Write results as JSON here.")
@click.option("--plots", "plots_dir", type=click.Path(file_okay=False),
              help="Write PNGs of error vs time step and error vs N into this folder.")
@engine_options("bearings-results")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
def bearings(ships, sequences, runs, steps, algos, particles, equal_time, seed, resample, ess_threshold, lis_proposal,
             json_path, plots_dir, workers, scheduler, in_process, out_dir, resume, quiet):
    """Bearings-only ship tracking (thesis §1.3.3, §4.5.5).

    Runs every algorithm at every N on SEQUENCES fixed sequences, RUNS times
    each, and prints the final-step and time-averaged position error with the
    CPU time per run (Table 4.3; with --ships 3, Table 4.4 / Fig. 4.22; with
    M > 1 ships also each ship's final-step error; ships beyond 3 lie on a
    circle, Fig. 4.31). Each
    sequence is a task of the evaluation engine (Dask; one file per sequence
    in OUT/tasks, --resume continues an interrupted reproduction).
    """
    cfg = BearingsConfig(ships=ships, sequences=sequences, runs=runs, steps=steps, algos=algos,
                         particles=particles, seed=seed, resample=resample, ess_threshold=ess_threshold,
                         proposal=lis_proposal)
    try:
        cfg.validate()
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    _plots_dir(plots_dir, "error_vs_time.png")
    check_writable(json_path, "--json file")
    if equal_time:
        cfg.entries, times = equal_time_pairs(cfg)
        click.echo("equal time: " + ", ".join(f"{a}:{n}" for a, n in cfg.entries) + " ("
                   + ", ".join(f"{k} {v:.1f} ms/run" for k, v in times.items()) + ")")
    tasks = bearing_tasks(cfg)
    out_path = _run(tasks, out_dir, "bearings", runner=run_bearing_task, scheduler=scheduler, workers=workers,
                    in_process=in_process, resume=resume, quiet=quiet)
    out = bearing_results(cfg, tasks, out_path)
    _report("bearings", out, out["config"], json_path, plots_dir, title=f"Bearings-only, {ships} ship(s)")
    if ships > 1:
        click.echo(format_ship_table(out["results"]))


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


def _clip_suite(clips_dir, default, make, frames, size, maker, prefix, quiet, **kw):
    """:func:`vistrack.reproduce.suite.clip_suite` in ``clips_dir`` (or ``default``), with a progress bar."""
    from vistrack.reproduce.suite import clip_suite

    from .options import Size

    with tqdm(total=make * frames, unit="frame", desc="making clips", disable=quiet, leave=False) as bar:
        return clip_suite(clips_dir or default, make, frames, Size().convert(size, None, None), maker, prefix,
                          progress=bar.update, **kw)


def _run(tasks, out_dir, desc, runner=None, **engine):
    """Run ``tasks`` on the evaluation engine into ``out_dir`` (created; see
    :func:`vistrack.cli.eval.run_tasks`: nothing in it is removed, each task file is replaced
    whole when its task finishes, and ``--resume`` keeps only files of the very same task);
    returns the folder."""
    from pathlib import Path

    from .eval import run_tasks

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise click.ClickException(f"cannot create --out folder {out_dir}: {e.strerror}") from None
    run_tasks(tasks, out, desc=desc, runner=runner, **engine)
    return out


@reproduce.command()
@suite_options("Folder of contour clip folders (each with video.mp4, groundtruth.csv, meta.json); "
               "made there with --make if missing.", "320x240", "ls-n-ips:30,bootstrap:2000",
               "ALGO:N pairs (bootstrap, ls-n-ips, lls, lis, avpf).", 10)
@engine_options("contour-results")
@output_options("Write P(lost) vs frame and error vs frame PNGs here.")
def contour(clips_dir, make, frames, size, entries, runs, seed, workers, scheduler, in_process, out_dir, resume,
            json_path, plots_dir, quiet):
    """Contour tracking in clutter with a distractor (thesis §4.3.2, Table 4.1).

    Tracks every clip RUNS times with every ALGO:N from the first frame's
    ground truth, as tasks of the evaluation engine (Dask; --resume continues
    an interrupted run); prints P(lost) (centre error > 50 px at 240-px width,
    scaled) at the last frame and averaged over frames, the mean error of
    runs not lost, and the filter's time per frame.
    """
    from vistrack.data_synth.contour import make_contour_clip

    _check_entries(entries)
    check_writable(json_path, "--json file")
    _plots_dir(plots_dir, "p_lost_vs_frame.png")
    clips = _clip_suite(clips_dir, "contour-clips", make, frames, size, make_contour_clip, "contour", quiet,
                        clutter="high", distractor=True)
    cfg = ContourConfig(clips=clips, entries=entries, runs=runs, seed=seed)
    tasks = contour_tasks(cfg)
    out = _run(tasks, out_dir, "contour", scheduler=scheduler, workers=workers,
               in_process=in_process, resume=resume, quiet=quiet)
    click.echo(f"{len(clips)} clips x {runs} runs")
    _report("contour", {"results": contour_results(tasks, out)}, entries_config(cfg), json_path, plots_dir)


@reproduce.command()
@click.option("--k", "k", type=click.Choice(["5", "8"]), default="5", show_default=True,
              help="5: deforming pentagon, N=50, PF-EIS vs PF-Doucet vs PF-Gordon (Fig. 2a); "
                   "8: N=20, PF-EIS-MT vs PF-EIS vs PF-Gordon (Fig. 2b).")
@click.option("--runs", default=80, show_default=True, type=click.IntRange(min=1), help="Monte-Carlo runs.")
@click.option("--steps", default=50, show_default=True, type=click.IntRange(min=1), help="Time steps T per run.")
@click.option("--seed", default=0, show_default=True, type=SEED,
              help="Random seed: the same seed gives the same output, bit for bit.")
@click.option("--algos", default=None, type=StrList(),
              help=f"Algorithms, comma-separated ({', '.join(LANDMARK_ALGOS)}) [default: the paper's for K].")
@click.option("-n", "--particles", default=None, type=click.IntRange(min=1),
              help="Particles N [default: the paper's, 50 for K=5 and 20 for K=8].")
@click.option("--mt-dims", default=None, type=click.IntRange(min=0),
              help="PF-EIS-MT: trailing entries of c that are mode-tracked [default: 10 for K=8, 4 for K=5].")
@engine_options("landmarks-results")
@output_options("Write mse_vs_time.png here.")
def landmarks(k, runs, steps, seed, algos, particles, mt_dims, workers, scheduler, in_process, out_dir, resume,
              json_path, plots_dir, quiet):
    """Landmark shape tracking (seed 000, §4, Fig. 2).

    Every run simulates a sequence from the known regular K-gon by the model
    (5)-(6) with the paper's parameters and tracks it with every algorithm.
    Prints the MSE of the configuration, Σ_k |ĥ_k - h_k|² with ĥ the
    weighted-mean configuration, averaged over runs and time steps, and the
    CPU time per run. Each run is a task of the evaluation engine (Dask; one
    file per run in OUT/tasks, --resume continues an interrupted reproduction;
    run r draws from SeedSequence(seed).spawn(runs)[r] whatever the workers).
    """
    try:
        cfg = LandmarksConfig(k=int(k), runs=runs, steps=steps, seed=seed, particles=particles,
                              algos=list(algos or []), mt_dims=mt_dims)
        cfg.validate()
        cfg.model()
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    check_writable(json_path, "--json file")
    _plots_dir(plots_dir, "mse_vs_time.png")
    tasks = landmark_tasks(cfg)
    out_path = _run(tasks, out_dir, f"landmarks K={k}", runner=run_landmark_task, scheduler=scheduler, workers=workers,
                    in_process=in_process, resume=resume, quiet=quiet)
    out = landmark_results(cfg, tasks, out_path)
    click.echo(f"K = {k}, {runs} runs x {steps} steps")
    _report("landmarks", out, out["config"], json_path, plots_dir, title=f"Landmark shape tracking, K = {k}")


@reproduce.command()
@suite_options("Folder of plate clip folders; made there with --make if missing [default: plate-clips; "
               "plate-overlap-clips with --overlap].", "640x480", "lis:100,bootstrap:750",
               "ALGO:N pairs (lis, bootstrap, lls, avpf; with --overlap: partitioned-lis, partitioned, "
               "branched-partitioned(-lis), lis, bootstrap) [default with --overlap: "
               "partitioned-lis:100,bootstrap:2000].", 20)
@click.option("--overlap", is_flag=True,
              help="Several plates at once: clips with up to three plates in view (6 cars, synth plate --overlap), "
                   "tracked with --targets slots and scored by MOTA and IDF1 against objects.csv.")
@click.option("--targets", default=3, show_default=True, type=click.IntRange(min=1),
              help="With --overlap: plate slots K.")
@click.option("--equal-time", is_flag=True,
              help="With --overlap: set every N after the first so that its time per frame matches the first "
                   "entry's (timed on 60 frames of the first clip, from a quarter of the way in).")
@engine_options("plate-results")
@output_options("Write P(lost) vs frame PNG here.")
@click.pass_context
def plate(ctx, clips_dir, make, frames, size, entries, runs, seed, overlap, targets, equal_time, workers, scheduler,
          in_process, out_dir, resume, json_path, plots_dir, quiet):
    """License-plate tracking on synthetic road clips (thesis §4.5.3, Figs. 4.15-4.16).

    Every clip is tracked RUNS times by every ALGO:N with no initial box: plates
    are acquired through the entering-car component and reported absent when
    the likelihood at the estimate says no plate. Prints the average per-frame
    P(lost) on frames with a plate (lost: no plate reported, or vertex error
    above a third of the plate height), the mean vertex error of frames not
    lost, false reports (a plate reported in a frame without one), the share of
    plate appearances acquired within 10 frames, and the time per frame.

    With --overlap (thesis App. C: several targets), prints per ALGO:N the mean
    MOTA and IDF1 over runs, identity switches, false positives and misses per
    run, the plates reported in frames without any, and the time per frame.
    """
    from vistrack.data_synth.plate import make_plate_clip

    if overlap:
        if plots_dir:
            raise click.UsageError("--plots is not for --overlap (its scores are one table)")
        if ctx.get_parameter_source("entries") == click.core.ParameterSource.DEFAULT:
            entries = [("partitioned-lis", 100), ("bootstrap", 2000)]
        from .reproduce_plates import overlap

        return overlap(clips_dir, make, frames, size, entries, runs, seed, targets, equal_time, quiet, json_path,
                       dict(scheduler=scheduler, workers=workers, in_process=in_process, resume=resume, quiet=quiet),
                       out_dir if ctx.get_parameter_source("out_dir") != click.core.ParameterSource.DEFAULT
                       else "plate-overlap-results")
    if equal_time or ctx.get_parameter_source("targets") != click.core.ParameterSource.DEFAULT:
        raise click.UsageError("--targets and --equal-time are for --overlap")
    _check_entries(entries)
    check_writable(json_path, "--json file")
    _plots_dir(plots_dir, "p_lost_vs_frame.png")
    clips = _clip_suite(clips_dir, "plate-clips", make, frames, size, make_plate_clip, "plate", quiet)
    cfg = PlateConfig(clips=clips, entries=entries, runs=runs, seed=seed)
    tasks = plate_tasks(cfg)
    out = _run(tasks, out_dir, "plate", runner=run_plate_task, scheduler=scheduler, workers=workers,
               in_process=in_process, resume=resume, quiet=quiet)
    click.echo(f"{len(clips)} clips x {runs} runs")
    _report("plate", {"results": plate_results(cfg, tasks, out)}, entries_config(cfg), json_path, plots_dir)


from . import reproduce_hs_sir  # noqa: E402,F401  (registers `reproduce hs-sir`)
