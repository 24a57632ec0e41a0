"""``vistrack reproduce ...``: the seeds' experiments."""

from __future__ import annotations

import json
import os

import click
from tqdm import tqdm

from vistrack.reproduce.bearings import DEFAULT_ALGOS, BearingsConfig, bearing_results, bearing_tasks, run_bearing_task
from vistrack.reproduce.landmarks import (LANDMARK_ALGOS, LandmarksConfig, landmark_results, landmark_tasks,
                                          run_landmark_task)
from vistrack.reproduce.plate import PlateConfig, plate_results, plate_tasks, run_plate_task
from vistrack.evaluation import entries_config, write_atomic
from vistrack.reproduce.contour import ContourConfig, contour_results, contour_tasks

from .options import SEED, Fraction, IntList, StrList, check_writable

__all__ = ["reproduce"]


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

    def deco(f):
        for opt in reversed(opts):
            f = opt(f)
        return f

    return deco


def suite_options(clips_help, size, algos, algos_help, runs):
    """A clip suite's options (``--clips --make --frames --size --algos --runs --seed``), shared by
    the ``reproduce`` commands that track synthetic clips."""
    opts = [
        click.option("--clips", "clips_dir", type=click.Path(file_okay=False), help=clips_help),
        click.option("--make", "make", default=10, show_default=True, type=click.IntRange(min=1),
                     help="Clips to generate (seeds 1..MAKE) when --clips has none."),
        click.option("--frames", default=300, show_default=True, type=click.IntRange(min=2),
                     help="Frames per made clip."),
        click.option("--size", default=size, show_default=True, help="Frame size of made clips."),
        click.option("--algos", "entries", default=algos, show_default=True, type=Entries(), help=algos_help),
        click.option("--runs", default=runs, show_default=True, type=click.IntRange(min=1), help="Runs per clip."),
        click.option("--seed", default=0, show_default=True, type=SEED),
    ]

    def deco(f):
        for opt in reversed(opts):
            f = opt(f)
        return f

    return deco


@click.group()
def reproduce():
    """Reproduce the experiments of the seeds (tables and figures)."""


def _table(results):
    head = f"{'algo':<10} {'N':>6} {'ships':>5} {'final err':>10} {'± std':>9} {'mean err':>9} {'ms/run':>8}"
    lines = [head, "-" * len(head)]
    for r in results:
        lines.append(
            f"{r['algo']:<10} {r['particles']:>6d} {r['ships']:>5d} {r['mean_error_final']:>10.5f}"
            f" {r['std_error_final']:>9.5f} {r['mean_error']:>9.5f} {r['ms_per_run']:>8.2f}"
        )
    return "\n".join(lines)


@reproduce.command()
@click.option("--ships", default=1, show_default=True, type=int, help="Number of ships M (state dimension 4M).")
@click.option("--sequences", default=10, show_default=True, type=int, help="Fixed state/observation sequences.")
@click.option("--runs", default=100, show_default=True, type=int, help="Filter runs per sequence.")
@click.option("--steps", default=10, show_default=True, type=int, help="Time steps per sequence.")
@click.option("--algos", default=",".join(DEFAULT_ALGOS), show_default=True, type=StrList(),
              help="Algorithms, comma-separated (bootstrap, avpf, lis, lls).")
@click.option("--particles", default="100,500,3000", show_default=True, type=IntList(),
              help="Particle counts N, comma-separated.")
@click.option("--seed", default=0, show_default=True, type=SEED, help="Seed of sequences and runs.")
@click.option("--resample", default="systematic", show_default=True,
              type=click.Choice(["multinomial", "residual", "stratified", "systematic"]))
@click.option("--ess-threshold", default=None, type=Fraction(),
              help="Resample when ESS < threshold·N (default: every step).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), help="Write results as JSON here.")
@click.option("--plots", "plots_dir", type=click.Path(file_okay=False),
              help="Write PNGs of error vs time step and error vs N into this folder.")
@engine_options("bearings-results")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
def bearings(ships, sequences, runs, steps, algos, particles, seed, resample, ess_threshold, json_path,
             plots_dir, workers, scheduler, in_process, out_dir, resume, quiet):
    """Bearings-only ship tracking (thesis §1.3.3, §4.5.5).

    Runs every algorithm at every N on SEQUENCES fixed sequences, RUNS times
    each, and prints the final-step and time-averaged position error with the
    CPU time per run (Table 4.3; with --ships 3, Table 4.4 / Fig. 4.22). Each
    sequence is a task of the evaluation engine (Dask; one file per sequence
    in OUT/tasks, --resume continues an interrupted reproduction).
    """
    cfg = BearingsConfig(ships=ships, sequences=sequences, runs=runs, steps=steps, algos=algos,
                         particles=particles, seed=seed, resample=resample, ess_threshold=ess_threshold)
    try:
        cfg.validate()
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    if plots_dir:
        try:
            os.makedirs(plots_dir, exist_ok=True)
        except OSError as e:
            raise click.ClickException(f"cannot create --plots folder {plots_dir}: {e.strerror}") from None
        check_writable(os.path.join(plots_dir, "error_vs_time.png"), "plot")
    check_writable(json_path, "--json file")

    from .eval import run_tasks

    tasks = bearing_tasks(cfg)
    out_path = _fresh_out(out_dir, tasks, resume)
    run_tasks(tasks, out_path, scheduler=scheduler, workers=workers, in_process=in_process, resume=resume,
              quiet=quiet, desc="bearings", runner=run_bearing_task)
    out = bearing_results(cfg, tasks, out_path)
    click.echo(_table(out["results"]))
    if json_path:
        _write_json(json_path, out["config"], out["results"])
    if plots_dir:
        from vistrack.plots import plot_error_vs_n, plot_error_vs_time

        a = plot_error_vs_time(out["curves"], os.path.join(plots_dir, "error_vs_time.png"),
                               title=f"Bearings-only, {ships} ship(s): error vs time (Fig. 4.18)")
        b = plot_error_vs_n(out["results"], os.path.join(plots_dir, "error_vs_n.png"),
                            title=f"Bearings-only, {ships} ship(s): final error vs N (Fig. 4.21)")
        click.echo(f"plots written to {a} and {b}")


class Entries(click.ParamType):
    """``algo:N`` pairs, comma-separated, e.g. ``ls-n-ips:30,bootstrap:2000``."""

    name = "ALGO:N,..."

    def convert(self, value, param, ctx):
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


def _write_json(json_path, config, results):
    write_atomic(json_path, json.dumps({"config": config, "results": results}, indent=2))
    click.echo(f"results written to {json_path}")


def _check_entries(entries):
    from vistrack.filters import ALGORITHMS

    for algo, _ in entries:
        if algo not in ALGORITHMS:
            raise click.ClickException(f"unknown algorithm {algo!r}; choose from {', '.join(sorted(ALGORITHMS))}")


def _clip_suite(clips_dir, default, make, frames, size, maker, prefix, quiet, **kw):
    """The clip folders in ``clips_dir`` (or ``default``); ``make`` clips of seeds 1..make are
    generated there with ``maker`` when it has none."""
    from pathlib import Path

    from .options import Size

    base = Path(clips_dir) if clips_dir else Path(default)

    def found():
        return sorted(p for p in base.glob("[!.]*") if (p / "groundtruth.csv").is_file()) if base.is_dir() else []

    if not found():
        wh = Size().convert(size, None, None)
        base.mkdir(parents=True, exist_ok=True)
        with tqdm(total=make * frames, unit="frame", desc="making clips", disable=quiet, leave=False) as bar:
            for s in range(1, make + 1):
                maker(base / f"{prefix}-{s:02d}", frames=frames, size=wh, seed=s, progress=bar.update, **kw)
    return found()


def _fresh_out(out_dir, tasks, resume):
    """``out_dir`` created. Nothing in it is removed: without ``resume`` every task runs again
    and replaces its file whole when it finishes; with it, only task files computed by the very
    same task (fingerprint) are kept."""
    from pathlib import Path

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise click.ClickException(f"cannot create --out folder {out_dir}: {e.strerror}") from None
    return out


def _contour_table(results):
    head = (f"{'algo':<10} {'N':>6} {'P(lost) final':>13} {'P(lost) mean':>12} {'mean err px':>11}"
            f" {'ms/frame':>9} {'frames/s':>9} {'mean ESS':>9}")
    lines = [head, "-" * len(head)]
    for r in results:
        lines.append(f"{r['algo']:<10} {r['particles']:>6d} {r['p_lost_final']:>13.3f} {r['p_lost_mean']:>12.3f}"
                     f" {r['mean_error']:>11.2f} {r['ms_per_frame']:>9.2f} {r['frames_per_s']:>9.0f}"
                     f" {r['mean_ess']:>9.1f}")
    return "\n".join(lines)


@reproduce.command()
@suite_options("Folder of contour clip folders (each with video.mp4, groundtruth.csv, meta.json); "
               "made there with --make if missing.", "320x240", "ls-n-ips:30,bootstrap:2000",
               "ALGO:N pairs (bootstrap, ls-n-ips, lls, lis, avpf).", 10)
@engine_options("contour-results")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), help="Write results as JSON here.")
@click.option("--plots", "plots_dir", type=click.Path(file_okay=False),
              help="Write P(lost) vs frame and error vs frame PNGs here.")
@click.option("--quiet", "-q", is_flag=True)
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

    from .eval import run_tasks

    _check_entries(entries)
    check_writable(json_path, "--json file")
    clips = _clip_suite(clips_dir, "contour-clips", make, frames, size, make_contour_clip, "contour", quiet,
                        clutter="high", distractor=True)
    cfg = ContourConfig(clips=clips, entries=entries, runs=runs, seed=seed)
    tasks = contour_tasks(cfg)
    out = _fresh_out(out_dir, tasks, resume)

    run_tasks(tasks, out, scheduler=scheduler, workers=workers, in_process=in_process, resume=resume, quiet=quiet,
              desc="contour")
    results = contour_results(tasks, out)
    click.echo(f"{len(clips)} clips x {runs} runs")
    click.echo(_contour_table(results))
    if json_path:
        _write_json(json_path, entries_config(cfg), results)
    if plots_dir:
        from vistrack.plots import plot_per_frame

        os.makedirs(plots_dir, exist_ok=True)
        lab = {f"{r['algo']}, N={r['particles']}": r for r in results}
        a = plot_per_frame({k: r["p_lost_per_frame"] for k, r in lab.items()},
                           os.path.join(plots_dir, "p_lost_vs_frame.png"), ylabel="P(lost)",
                           title="Contour: probability of losing the object (Fig. 3.10)")
        b = plot_per_frame({k: r["error_per_frame"] for k, r in lab.items()},
                           os.path.join(plots_dir, "error_vs_frame.png"), ylabel="mean centre error (px), runs not lost",
                           title="Contour: tracking error (Fig. 3.9)")
        click.echo(f"plots written to {a} and {b}")


def _landmarks_table(results):
    head = f"{'algo':<10} {'N':>4} {'K':>2} {'mean MSE':>9} {'final MSE':>10} {'median run':>10} {'ms/run':>8}"
    lines = [head, "-" * len(head)]
    for r in results:
        lines.append(f"{r['algo']:<10} {r['particles']:>4d} {r['k']:>2d} {r['mean_mse']:>9.4f} {r['final_mse']:>10.4f}"
                     f" {r['median_run_mse']:>10.4f} {r['ms_per_run']:>8.1f}")
    return "\n".join(lines)


@reproduce.command()
@click.option("--k", "k", type=click.Choice(["5", "8"]), default="5", show_default=True,
              help="5: deforming pentagon, N=50, PF-EIS vs PF-Doucet vs PF-Gordon (Fig. 2a); "
                   "8: N=20, PF-EIS-MT vs PF-EIS vs PF-Gordon (Fig. 2b).")
@click.option("--runs", default=80, show_default=True, type=click.IntRange(min=1), help="Monte-Carlo runs.")
@click.option("--steps", default=50, show_default=True, type=click.IntRange(min=1), help="Time steps T per run.")
@click.option("--seed", default=0, show_default=True, type=SEED)
@click.option("--algos", default=None, type=StrList(),
              help=f"Algorithms, comma-separated ({', '.join(LANDMARK_ALGOS)}) [default: the paper's for K].")
@click.option("-n", "--particles", default=None, type=click.IntRange(min=1),
              help="Particles N [default: the paper's, 50 for K=5 and 20 for K=8].")
@click.option("--mt-dims", default=None, type=click.IntRange(min=0),
              help="PF-EIS-MT: trailing entries of c that are mode-tracked [default: 10 for K=8, 4 for K=5].")
@engine_options("landmarks-results")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), help="Write results as JSON here.")
@click.option("--plots", "plots_dir", type=click.Path(file_okay=False), help="Write mse_vs_time.png here.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
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
    if plots_dir:
        try:
            os.makedirs(plots_dir, exist_ok=True)
        except OSError as e:
            raise click.ClickException(f"cannot create --plots folder {plots_dir}: {e.strerror}") from None
        check_writable(os.path.join(plots_dir, "mse_vs_time.png"), "plot")
    from .eval import run_tasks

    tasks = landmark_tasks(cfg)
    out_path = _fresh_out(out_dir, tasks, resume)
    run_tasks(tasks, out_path, scheduler=scheduler, workers=workers, in_process=in_process, resume=resume,
              quiet=quiet, desc=f"landmarks K={k}", runner=run_landmark_task)
    out = landmark_results(cfg, tasks, out_path)
    click.echo(f"K = {k}, {runs} runs x {steps} steps")
    click.echo(_landmarks_table(out["results"]))
    if json_path:
        _write_json(json_path, out["config"], out["results"])
    if plots_dir:
        from vistrack.plots import plot_error_vs_time

        a = plot_error_vs_time(out["curves"], os.path.join(plots_dir, "mse_vs_time.png"),
                               ylabel="MSE of the configuration", title=f"Landmark shape tracking, K = {k} (Fig. 2)")
        click.echo(f"plot written to {a}")


def _plate_table(results):
    head = (f"{'algo':<10} {'N':>5} {'P(lost)':>8} {'vertex err':>10} {'false rep.':>10} {'acq<=10':>8}"
            f" {'never':>6} {'mean acq':>8} {'ms/frame':>9} {'frames/s':>9} {'ESS':>6}")
    lines = [head, "-" * len(head)]
    for r in results:
        fmt = lambda v, f: "-" if v is None else format(v, f)  # noqa: E731
        lines.append(f"{r['algo']:<10} {r['particles']:>5d} {r['p_lost']:>8.3f} {fmt(r['mean_vertex_error'], '10.2f')}"
                     f" {r['false_reports']:>10d} {fmt(r['acquired_within'], '8.2f')} {r['never_acquired']:>6d}"
                     f" {fmt(r['mean_acquisition_delay'], '8.1f')} {r['ms_per_frame']:>9.2f}"
                     f" {r['frames_per_s']:>9.0f} {r['mean_ess']:>6.1f}")
    return "\n".join(lines)


@reproduce.command()
@suite_options("Folder of plate clip folders; made there with --make if missing [default: plate-clips].",
               "640x480", "lis:100,bootstrap:750", "ALGO:N pairs (lis, bootstrap, lls, avpf).", 20)
@engine_options("plate-results")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), help="Write results as JSON here.")
@click.option("--plots", "plots_dir", type=click.Path(file_okay=False), help="Write P(lost) vs frame PNG here.")
@click.option("--quiet", "-q", is_flag=True)
def plate(clips_dir, make, frames, size, entries, runs, seed, workers, scheduler, in_process, out_dir, resume,
          json_path, plots_dir, quiet):
    """License-plate tracking on synthetic road clips (thesis §4.5.3, Figs. 4.15-4.16).

    Every clip is tracked RUNS times by every ALGO:N with no initial box: plates
    are acquired through the entering-car component and reported absent when
    the likelihood at the estimate says no plate. Prints the average per-frame
    P(lost) on frames with a plate (lost: no plate reported, or vertex error
    above a third of the plate height), the mean vertex error of frames not
    lost, false reports (a plate reported in a frame without one), the share of
    plate appearances acquired within 10 frames, and the time per frame.
    """
    from vistrack.data_synth.plate import make_plate_clip

    from .eval import run_tasks

    _check_entries(entries)
    check_writable(json_path, "--json file")
    clips = _clip_suite(clips_dir, "plate-clips", make, frames, size, make_plate_clip, "plate", quiet)
    cfg = PlateConfig(clips=clips, entries=entries, runs=runs, seed=seed)
    tasks = plate_tasks(cfg)
    out = _fresh_out(out_dir, tasks, resume)
    run_tasks(tasks, out, scheduler=scheduler, workers=workers, in_process=in_process, resume=resume, quiet=quiet,
              desc="plate", runner=run_plate_task)
    results = plate_results(cfg, tasks, out)
    click.echo(f"{len(clips)} clips x {runs} runs")
    click.echo(_plate_table(results))
    if json_path:
        _write_json(json_path, entries_config(cfg), results)
    if plots_dir:
        from vistrack.plots import plot_per_frame

        os.makedirs(plots_dir, exist_ok=True)
        curves = {f"{r['algo']}, N={r['particles']}": [float("nan") if v is None else v for v in r["p_lost_per_frame"]]
                  for r in results if r["p_lost_per_frame"] is not None}
        a = plot_per_frame(curves, os.path.join(plots_dir, "p_lost_vs_frame.png"),
                           ylabel="P(lost), frames with a plate",
                           title="Plates: probability of losing the plate (Fig. 4.15)")
        click.echo(f"plot written to {a}")
