"""``vistrack reproduce hs-sir``: SIR with history sampling (thesis §3.2.5,
:mod:`vistrack.reproduce.history_sampling`)."""

from __future__ import annotations

import click

from vistrack.registry import algos_for
from vistrack.reproduce.clip_suites import experiment_clips
from vistrack.reproduce.history_sampling import HSConfig, likelihood_params
from vistrack.reproduce.reproduction import reproduce

from .errors import one_line
from .options import option
from .progress import progress
from .reproduce_common import (
    check_suite_outputs,
    engine_options,
    equal_time_line,
    making_clips,
    output_options,
    results_lines,
    suite_options,
)

__all__ = ["Likelihood", "likelihood_text", "hs_sir"]


class Likelihood(click.ParamType):
    """``KEY=VALUE`` pairs, comma-separated (:func:`vistrack.reproduce.history_sampling.likelihood_params`)."""

    name = "KEY=VALUE,..."

    def convert(self, value, param, ctx):
        """Parse ``value`` into a dict; a bad pair fails with click's one-line usage error."""
        if isinstance(value, dict):
            return value
        try:
            return likelihood_params(value)
        except ValueError as e:
            self.fail(str(e), param, ctx)


def likelihood_text(params):
    """``{key: value}`` as ``--likelihood`` takes it: ``sigma_edge=4,q_miss=0.5`` (``""``: none)."""
    return ",".join(f"{k}={v}" for k, v in params.items())


@click.command("hs-sir")
@suite_options(HSConfig, "Folder of colour contour clip folders; made there with --make if missing "
               "[default: hs-sir-clips].",
               "ALGO:N pairs, any that runs on the contour model (" + ", ".join(algos_for(HSConfig.model)) + ").")
@click.option("--equal-time", is_flag=True,
              help="Set every N after the first so that its time per frame matches the first entry's (timed on "
                   "the first clip), as Table 3.1's counts were chosen.")
@option("--likelihood", source=HSConfig, shown=likelihood_text, show_default=False, type=Likelihood(),
              help="The edge likelihood's parameters for every algorithm, e.g. sigma_edge=4,q_miss=0.5,"
                   "clutter_density=0.5 (sigma_edge, q_miss, clutter_density, measure_per_segment, "
                   "edge_threshold) [default: the contour model's].")
@engine_options(HSConfig)
@output_options("Write P(lost) vs frame (Fig. 3.10) and error vs frame (Fig. 3.9) PNGs here.")
def hs_sir(clips_dir, make, frames, size, entries, runs, seed, equal_time, likelihood, workers, scheduler, in_process,
           out_dir, resume, json_path, plots_dir, quiet):
    """SIR with history sampling on colour contour clips (thesis §3.2.5, Table 3.1, Figs. 3.9-3.10).

    \b
    The innovations (the pose) come from the image only: the colour-blob
    proposal draws a cell of a ~24x18 grid ∝ the target's Gaussian colour
    likelihood averaged over it, then a uniform fine displacement (±5.5 px at
    240-px width), with its exact density. The history (the previous pose) is
    joined to them by
      basic-sir      at random (Fig. 3.2),
      hs-sir         resampling history-innovation pairs ∝ their weights (Fig. 3.4),
      rb-hs-sir      drawing the history ∝ ŵ K_1, weighted by the mixture (Fig. 3.5),
      rb-ss-hs-sir   the same on translation only, scale and rotation from K (Fig. 3.7).
    The clips (seeds 1..MAKE) have a coloured object and an identical distractor,
    so the proposal keeps drawing fake positions. Tracks every clip RUNS times
    with every ALGO:N as tasks of the evaluation engine (--resume continues);
    prints P(lost) (centre error > 50 px at 240-px width) at the last frame and
    averaged, the mean error of runs not lost and the time per frame.
    """
    check_suite_outputs("hs-sir", clips_dir, json_path)
    with making_clips(make, frames, quiet) as made, one_line():
        clips = experiment_clips("hs-sir", clips_dir, make, frames, size, made, grid=(entries, runs))
    cfg = HSConfig(clips=clips, entries=entries, runs=runs, seed=seed, likelihood=likelihood)
    with progress("hs-sir", quiet) as hooks:
        done = reproduce(cfg, out_dir, json_path=json_path, plots_dir=plots_dir, equal_time=equal_time,
                         on_equal_time=equal_time_line("frame"), scheduler=scheduler, workers=workers,
                         in_process=in_process, resume=resume, **hooks)
    click.echo(f"{len(clips)} clips x {runs} runs")
    click.echo(results_lines("hs-sir", done))
