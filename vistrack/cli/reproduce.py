"""``vistrack reproduce ...``: the seeds' experiments."""

from __future__ import annotations

import click
from click.core import ParameterSource

from vistrack.core.resampling import SCHEMES
from vistrack.models.bearings.model import LIS_PROPOSALS, Bearings
from vistrack.registry import algos_for, derived_algos
from vistrack.reproduce.bearings import BearingsConfig, format_ship_table
from vistrack.reproduce.clip_suites import experiment_clips
from vistrack.reproduce.contour import ContourConfig
from vistrack.reproduce.landmarks import PAPER, STREAMS, LandmarksConfig
from vistrack.reproduce.multi_plate import PlatesConfig, plate_experiment
from vistrack.reproduce.plate import PlateConfig
from vistrack.reproduce.reproduction import reproduce as run_reproduction

from .errors import one_line
from .options import SEED, Fraction, IntList, Output, StrList, joined, option
from .progress import progress
from .reproduce_common import (
    check_suite_outputs,
    default_entries,
    engine_options,
    equal_time_line,
    making_clips,
    output_options,
    results_lines,
    suite_options,
)
from .reproduce_hs_sir import hs_sir

__all__ = ["reproduce"]


@click.group()
def reproduce():
    """Reproduce the experiments of the seeds (tables and figures)."""


@reproduce.command()
@option("--ships", source=BearingsConfig, type=int, help="Number of ships M (state dimension 4M).")
@option("--sequences", source=BearingsConfig, type=int, help="Fixed state/observation sequences.")
@option("--runs", source=BearingsConfig, type=int, help="Filter runs per sequence.")
@option("--steps", source=BearingsConfig, type=int, help="Time steps per sequence.")
@option("--algos", source=BearingsConfig, shown=joined, type=StrList(),
        help="Algorithms, comma-separated (" + ", ".join(derived_algos(Bearings)) + ").")
@option("--particles", source=BearingsConfig, shown=joined, type=IntList(), help="Particle counts N, comma-separated.")
@click.option("--equal-time", is_flag=True, help="Run the first algorithm at each N and every other at the N that "
              "takes as long per run (timed here on the first sequence).")
@option("--seed", source=BearingsConfig, type=SEED, help="Seed of sequences and runs.")
@option("--resample", source=BearingsConfig, type=click.Choice(list(SCHEMES)),
        help="Resampling scheme of the particle filter.")
@click.option("--ess-threshold", default=None, type=Fraction(),
              help="Resample when ESS < threshold·N (default: every step).")
@option("--lis-proposal", source=BearingsConfig, key="proposal", type=click.Choice(list(LIS_PROPOSALS)),
        help="LIS's proposal: the noise move across the bearing, or §4.5.5's position move.")
@click.option("--json", "json_path", type=Output(dir_okay=False), help="Write results as JSON here.")
@click.option("--plots", "plots_dir", type=Output(file_okay=False),
              help="Write PNGs of error vs time step and error vs N into this folder.")
@engine_options(BearingsConfig)
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
    with progress("bearings", quiet) as hooks:
        done = run_reproduction(cfg, out_dir, json_path=json_path, plots_dir=plots_dir,
                                title=f"Bearings-only, {ships} ship(s)", equal_time=equal_time,
                                on_equal_time=equal_time_line("run"), scheduler=scheduler, workers=workers,
                                in_process=in_process, resume=resume, **hooks)
    click.echo(results_lines("bearings", done))
    if ships > 1:
        click.echo(format_ship_table(done.out["results"]))


@reproduce.command()
@suite_options(ContourConfig, "Folder of contour clip folders (each with video.mp4, groundtruth.csv, meta.json); "
               "made there with --make if missing.",
               "ALGO:N pairs (" + ", ".join(algos_for(ContourConfig.model)) + ").")
@engine_options(ContourConfig)
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
    check_suite_outputs("contour", clips_dir, json_path)
    with making_clips(make, frames, quiet) as made, one_line():
        clips = experiment_clips("contour", clips_dir, make, frames, size, made, grid=(entries, runs))
    cfg = ContourConfig(clips=clips, entries=entries, runs=runs, seed=seed)
    with progress("contour", quiet) as hooks:
        done = run_reproduction(cfg, out_dir, json_path=json_path, plots_dir=plots_dir, scheduler=scheduler,
                                workers=workers, in_process=in_process, resume=resume, **hooks)
    click.echo(f"{len(clips)} clips x {runs} runs")
    click.echo(results_lines("contour", done))


@reproduce.command()
@option("--k", "k", source=LandmarksConfig, shown=str, type=click.Choice([str(k) for k in PAPER]),
        help="5: deforming pentagon, N=50, PF-EIS vs PF-Doucet vs PF-Gordon (Fig. 2a); "
             "8: N=20, PF-EIS-MT vs PF-EIS vs PF-Gordon (Fig. 2b).")
@option("--runs", source=LandmarksConfig, type=click.IntRange(min=1), help="Monte-Carlo runs.")
@option("--steps", source=LandmarksConfig, type=click.IntRange(min=1), help="Time steps T per run.")
@option("--seed", source=LandmarksConfig, type=SEED,
        help="Random seed: the same seed gives the same output, bit for bit.")
@click.option("--algos", default=None, type=StrList(),
              help=f"Algorithms, comma-separated ({', '.join(STREAMS)}) [default: the paper's for K].")
@click.option("-n", "--particles", default=None, type=click.IntRange(min=1),
              help="Particles N [default: the paper's, 50 for K=5 and 20 for K=8].")
@click.option("--mt-dims", default=None, type=click.IntRange(min=0),
              help="PF-EIS-MT: trailing entries of c that are mode-tracked [default: 10 for K=8, 4 for K=5].")
@engine_options(LandmarksConfig)
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
    with one_line():
        cfg = LandmarksConfig(k=int(k), runs=runs, steps=steps, seed=seed, particles=particles,
                              algos=list(algos or []), mt_dims=mt_dims)
    with progress(f"landmarks K={k}", quiet) as hooks:
        done = run_reproduction(cfg, out_dir, json_path=json_path, plots_dir=plots_dir,
                                title=f"Landmark shape tracking, K = {k}", scheduler=scheduler, workers=workers,
                                in_process=in_process, resume=resume, **hooks)
    click.echo(f"K = {k}, {runs} runs x {steps} steps")
    click.echo(results_lines("landmarks", done))


@reproduce.command()
@suite_options(PlateConfig, "Folder of plate clip folders; made there with --make if missing [default: plate-clips; "
               "plate-overlap-clips with --overlap].", "ALGO:N pairs (" + ", ".join(algos_for(PlateConfig.model))
               + "; with --overlap: " + ", ".join(algos_for(PlatesConfig.model, targets=True))
               + ") [default with --overlap: " + default_entries(PlatesConfig) + "].")
@click.option("--overlap", is_flag=True,
              help="Several plates at once: clips with up to three plates in view (6 cars, synth plate --overlap), "
                   "tracked with --targets slots and scored by MOTA and IDF1 against objects.csv.")
@option("--targets", source=PlatesConfig, type=click.IntRange(min=1), help="With --overlap: plate slots K.")
@click.option("--equal-time", is_flag=True,
              help="With --overlap: set every N after the first so that its time per frame matches the first "
                   "entry's (timed on 60 frames of the first clip, from a quarter of the way in).")
@engine_options(PlateConfig)
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
    given = {n for n in ("entries", "targets", "out_dir") if ctx.get_parameter_source(n) != ParameterSource.DEFAULT}
    if overlap and plots_dir:
        raise click.UsageError("--plots is not for --overlap (its scores are one table)")
    if not overlap and (equal_time or "targets" in given):
        raise click.UsageError("--targets and --equal-time are for --overlap")
    experiment = "plates" if overlap else "plate"
    check_suite_outputs(experiment, clips_dir, json_path)
    with making_clips(make, frames, quiet) as made, one_line():
        clips = experiment_clips(experiment, clips_dir, make, frames, size, made, grid=(entries, runs))
    cfg, out = plate_experiment(clips, runs=runs, seed=seed, overlap=overlap, targets=targets,
                                entries=entries if "entries" in given or not overlap else None,
                                out=out_dir if "out_dir" in given else None)
    with progress(experiment, quiet) as hooks:
        done = run_reproduction(cfg, out, json_path=json_path, plots_dir=plots_dir, equal_time=equal_time,
                                on_equal_time=equal_time_line("frame"), scheduler=scheduler, workers=workers,
                                in_process=in_process, resume=resume, **hooks)
    click.echo(f"{len(clips)} clips x {runs} runs" + (f", K = {targets} plate slots" if overlap else ""))
    click.echo(results_lines(experiment, done))


reproduce.add_command(hs_sir)
