"""``vistrack reproduce ...``: the seeds' experiments."""

from __future__ import annotations


import click

from vistrack.reproduce.bearings import (DEFAULT_ALGOS, BearingsConfig, bearing_results, bearing_tasks,
                                         equal_time_pairs, format_ship_table, run_bearing_task)
from vistrack.reproduce.landmarks import (STREAMS, LandmarksConfig, landmark_results, landmark_tasks,
                                          run_landmark_task)
from vistrack.reproduce.plate import PlateConfig, plate_results, plate_tasks, run_plate_task
from vistrack.engine.evaluation import entries_config
from vistrack.reproduce.contour import ContourConfig, contour_results, contour_tasks

from .options import SEED, Fraction, IntList, StrList, check_writable
from .reproduce_common import (_check_entries, _clip_suite, _plots_dir, _report, _run, engine_options,
                               output_options, suite_options)

__all__ = ["reproduce"]


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
              help=f"Algorithms, comma-separated ({', '.join(STREAMS)}) [default: the paper's for K].")
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


from .reproduce_hs_sir import hs_sir  # noqa: E402

reproduce.add_command(hs_sir)
