"""``vistrack demo``: the README's main job on a generated clip, in under a minute."""

from __future__ import annotations

from pathlib import Path

import click

from vistrack.data_synth.contour import make_contour_clip
from vistrack.data_synth.plate import make_plate_clip
from vistrack.evaluation import EvalConfig, load_task_results, summarize, task_list
from vistrack.report import write_eval_outputs

from .eval import run_tasks
from .options import SEED
from .run import run

__all__ = ["demo"]

DEMO_ALGOS = (("ls-n-ips", 30), ("lis", 30), ("bootstrap", 300))
PLATE_ALGOS = (("lis", 100), ("bootstrap", 750))


@click.command()
@click.option("--out", "out_dir", default="vistrack-demo", show_default=True, type=click.Path(file_okay=False),
              help="Folder for clips, annotated videos, tracks, table and plots.")
@click.option("--frames", default=150, show_default=True, type=click.IntRange(min=10))
@click.option("--runs", default=3, show_default=True, type=click.IntRange(min=1),
              help="Monte-Carlo runs per algorithm in the comparison.")
@click.option("--seed", default=0, show_default=True, type=SEED)
@click.pass_context
def demo(ctx, out_dir, frames, runs, seed):
    """Generate a contour clip (clutter, distractor) and a road clip with plates, track them
    with LS-N-IPS, LIS and bootstrap, write annotated videos, track CSVs, a comparison table
    and plots.

    Everything goes into OUT (./vistrack-demo by default).
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise click.ClickException(f"cannot create {out}: {e.strerror}") from None
    clip = out / "clips" / "contour"
    click.echo(f"1/4 generating a {frames}-frame 320x240 contour clip in {clip}")
    make_contour_clip(clip, frames=frames, size=(320, 240), seed=seed + 1, clutter="high", distractor=True)
    click.echo("2/4 tracking it once per algorithm (annotated video + track CSV)")
    made = []
    for algo, n in DEMO_ALGOS:
        video, track = out / f"contour-{algo}.mp4", out / f"contour-{algo}.csv"
        click.echo(f"  {algo} N={n}:")
        ctx.invoke(run, video=str(clip), algo=algo, particles=n, seed=seed, init_gt="", out_path=str(video),
                   track_path=str(track), quiet=False, show_particles=10)
        made += [video, track]
    plate = out / "clips" / "plate"
    plate_frames = min(frames, 120)
    click.echo(f"3/4 generating a {plate_frames}-frame 640x480 road clip in {plate}; tracking its plates "
               "without an initial box (acquired as cars enter)")
    make_plate_clip(plate, frames=plate_frames, size=(640, 480), seed=seed + 1, cars=2)
    for algo, n in PLATE_ALGOS:
        video, track = out / f"plate-{algo}.mp4", out / f"plate-{algo}.csv"
        click.echo(f"  {algo} N={n}:")
        ctx.invoke(run, video=str(plate), algo=algo, particles=n, seed=seed, out_path=str(video),
                   track_path=str(track), quiet=False, show_particles=10)
        made += [video, track]
    click.echo(f"4/4 comparing the contour trackers over {runs} runs (as vistrack eval does): "
               + ", ".join(f"{a} N={n}" for a, n in DEMO_ALGOS))
    cfg = EvalConfig(clips=[clip], algos=[a for a, _ in DEMO_ALGOS], particles=sorted({n for _, n in DEMO_ALGOS}),
                     runs=runs, seed=seed, model="contour", entries=list(DEMO_ALGOS))
    tasks = task_list(cfg, [clip])
    ev = out / "eval"
    ev.mkdir(exist_ok=True)
    run_tasks(tasks, ev, workers=1, in_process=True, desc="eval")
    results = load_task_results(tasks, ev)
    write_eval_outputs(ev, cfg, summarize(results), results)
    click.echo((ev / "report.md").read_text().split("\n\n## Per clip")[0].split("## Averages over clips\n\n")[-1])
    click.echo("")
    click.echo(f"done. In {out}/:")
    for p in made:
        click.echo(f"  {p}")
    click.echo(f"  {out / 'eval' / 'report.md'} (table and plots), results.json, results.csv")
