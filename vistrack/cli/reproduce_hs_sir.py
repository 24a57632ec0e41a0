"""``vistrack reproduce hs-sir``: SIR with history sampling (thesis §3.2.5, :mod:`vistrack.reproduce.hs_sir`)."""

from __future__ import annotations

import click

from vistrack.engine.evaluation import entries_config
from vistrack.reproduce.hs_sir import HSConfig, equal_time_entries, hs_results, hs_tasks, likelihood_params

from .options import check_writable
from .reproduce_common import (_check_entries, _clip_suite, _plots_dir, _report, _run, engine_options,
                               output_options, suite_options)

__all__ = ["Likelihood", "hs_sir"]


class Likelihood(click.ParamType):
    """``KEY=VALUE`` pairs, comma-separated (:func:`vistrack.reproduce.hs_sir.likelihood_params`)."""

    name = "KEY=VALUE,..."

    def convert(self, value, param, ctx):
        """Parse ``value`` into a dict; a bad pair fails with click's one-line usage error."""
        if isinstance(value, dict):
            return value
        try:
            return likelihood_params(value)
        except ValueError as e:
            self.fail(str(e), param, ctx)



@click.command("hs-sir")
@suite_options("Folder of colour contour clip folders; made there with --make if missing "
               "[default: hs-sir-clips].", "240x180", "basic-sir:3000,rb-ss-hs-sir:400",
               "ALGO:N pairs: basic-sir, hs-sir, rb-hs-sir, rb-ss-hs-sir (and bootstrap, ls-n-ips, lis, ...).",
               10, frames=150)
@click.option("--equal-time", is_flag=True,
              help="Set every N after the first so that its time per frame matches the first entry's (timed on "
                   "the first clip), as Table 3.1's counts were chosen.")
@click.option("--likelihood", default="", type=Likelihood(),
              help="The edge likelihood's parameters for every algorithm, e.g. sigma_edge=4,q_miss=0.5,"
                   "clutter_density=0.5 (sigma_edge, q_miss, clutter_density, measure_per_segment, "
                   "edge_threshold) [default: the contour model's].")
@engine_options("hs-sir-results")
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
    from vistrack.data_synth.contour import make_contour_clip

    _check_entries(entries)
    check_writable(json_path, "--json file")
    _plots_dir(plots_dir, "p_lost_vs_frame.png")
    clips = _clip_suite(clips_dir, "hs-sir-clips", make, frames, size, make_contour_clip, "contour-color", quiet,
                        grid=(entries, runs), clutter="high", distractor=True, color=True)
    if equal_time:
        entries, times = equal_time_entries(clips[0], entries, likelihood=likelihood)
        click.echo("equal time: " + ", ".join(f"{a}:{n}" for a, n in entries) + " ("
                   + ", ".join(f"{k} {v:.1f} ms/frame" for k, v in times.items()) + ")")
    cfg = HSConfig(clips=clips, entries=entries, runs=runs, seed=seed, likelihood=likelihood)
    tasks = hs_tasks(cfg)
    out = _run(tasks, out_dir, "hs-sir", scheduler=scheduler, workers=workers, in_process=in_process, resume=resume,
               quiet=quiet)
    click.echo(f"{len(clips)} clips x {runs} runs")
    _report("hs-sir", {"results": hs_results(tasks, out)}, entries_config(cfg), json_path, plots_dir)

