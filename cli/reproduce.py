"""``vistrack reproduce ...``: the seeds' experiments."""

from __future__ import annotations

import json
import os

import click
from tqdm import tqdm

from vistrack.reproduce.bearings import DEFAULT_ALGOS, BearingsConfig, run_bearings

from .options import IntList, StrList, check_writable

__all__ = ["reproduce"]


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
@click.option("--seed", default=0, show_default=True, type=int, help="Seed of sequences and runs.")
@click.option("--resample", default="systematic", show_default=True,
              type=click.Choice(["multinomial", "residual", "stratified", "systematic"]))
@click.option("--ess-threshold", default=None, type=float,
              help="Resample when ESS < threshold·N (default: every step).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), help="Write results as JSON here.")
@click.option("--plots", "plots_dir", type=click.Path(file_okay=False),
              help="Write PNGs of error vs time step and error vs N into this folder.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
def bearings(ships, sequences, runs, steps, algos, particles, seed, resample, ess_threshold, json_path,
             plots_dir, quiet):
    """Bearings-only ship tracking (thesis §1.3.3, §4.5.5).

    Runs every algorithm at every N on SEQUENCES fixed sequences, RUNS times
    each, and prints the final-step and time-averaged position error with the
    CPU time per run (Table 4.3; with --ships 3, Table 4.4 / Fig. 4.22).
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

    total = len(algos) * len(particles) * sequences * runs
    with tqdm(total=total, unit="run", desc="bearings", disable=quiet, leave=False) as bar:
        out = run_bearings(cfg, progress=bar.update)
    click.echo(_table(out["results"]))
    if json_path:
        with open(json_path, "w") as f:
            json.dump({"config": out["config"], "results": out["results"]}, f, indent=2)
        click.echo(f"results written to {json_path}")
    if plots_dir:
        from vistrack.plots import plot_error_vs_n, plot_error_vs_time

        a = plot_error_vs_time(out["curves"], os.path.join(plots_dir, "error_vs_time.png"),
                               title=f"Bearings-only, {ships} ship(s): error vs time (Fig. 4.18)")
        b = plot_error_vs_n(out["results"], os.path.join(plots_dir, "error_vs_n.png"),
                            title=f"Bearings-only, {ships} ship(s): final error vs N (Fig. 4.21)")
        click.echo(f"plots written to {a} and {b}")
