"""``vistrack demo``: the README's main job on a generated clip and a real one, in under 40 s."""

from __future__ import annotations

import os
from pathlib import Path

import click

from vistrack.data_synth.contour import make_contour_clip
from vistrack.engine.evaluation import EvalConfig, load_task_results, summarize, task_list
from vistrack.engine.report import write_eval_outputs
from vistrack.io.clips import excerpt_clip
from vistrack.io.video import VideoError
from vistrack.registry import DEFAULT_MODEL, get_model_spec

from .grid import run_tasks
from .options import SEED
from .run import run

__all__ = ["demo"]

#: the comparison on the generated clip, box model, at about equal time per frame (docs/experiments.md)
DEMO_ALGOS = (("ls-n-ips", 30), ("lis", 30), ("bootstrap", 150))
#: the generated clip: sudden jumps of 38-51 px (12-16 % of the width, two thirds of the object's size)
#: with probability 0.04 per frame, in heavy clutter
CLIP = {"size": (320, 240), "clutter": "high", "distractor": False, "jump_prob": 0.04, "jump_size": (0.12, 0.16)}
#: the real clip: vistrack's default box tracker beside OpenCV's MIL
REAL_ALGOS = ((get_model_spec(DEFAULT_MODEL).default_algo, 100), ("opencv-mil", 1))
REAL_CLIP = Path("shared") / "data" / "real" / "girl_otb"


def find_real_clip():
    """The real clip of step 4 whichever the working folder: ``$VISTRACK_REAL_DATA/girl_otb``, else
    ``shared/data/real/girl_otb`` under the working folder, the installed package's folder or any folder
    above them (a clone's ``../shared``); ``None`` when there is none."""
    env = os.environ.get("VISTRACK_REAL_DATA")
    if env and (Path(env) / REAL_CLIP.name).exists():
        return Path(env) / REAL_CLIP.name
    cwd, pkg = Path.cwd().resolve(), Path(__file__).resolve().parent
    for base in [cwd, *cwd.parents, pkg, *pkg.parents]:
        if (base / REAL_CLIP).exists():
            return base / REAL_CLIP
    return None


def compare(clip, entries, model, runs, seed, out):
    """Evaluate ``entries`` ((algo, N) pairs) on ``clip`` over ``runs`` runs into folder ``out`` (as
    ``vistrack eval`` does, in this process); returns the report's averages table."""
    cfg = EvalConfig(clips=[clip], algos=[a for a, _ in entries], particles=sorted({n for _, n in entries}),
                     runs=runs, seed=seed, model=model, entries=list(entries))
    tasks = task_list(cfg, [clip])
    out.mkdir(parents=True, exist_ok=True)
    run_tasks(tasks, out, workers=1, in_process=True, desc="eval")
    results = load_task_results(tasks, out)
    write_eval_outputs(out, cfg, summarize(results), results)
    return (out / "report.md").read_text().split("\n\n## Per clip")[0].split("## Averages over clips\n\n")[-1]


@click.command()
@click.option("--out", "out_dir", default="vistrack-demo", show_default=True, type=click.Path(file_okay=False),
              help="Folder for clips, annotated videos, tracks, tables and plots.")
@click.option("--frames", default=100, show_default=True, type=click.IntRange(min=10),
              help="Number of frames to generate.")
@click.option("--runs", default=4, show_default=True, type=click.IntRange(min=1),
              help="Monte-Carlo runs per algorithm in the comparisons.")
@click.option("--seed", default=0, show_default=True, type=SEED,
              help="Random seed: the same seed gives the same output, bit for bit.")
@click.option("--real-clip", "real_clip", default=None, metavar="DIR",
              help="A real clip with box ground truth (any layout run reads); '' skips it. Default: "
                   "$VISTRACK_REAL_DATA/girl_otb, else shared/data/real/girl_otb in the working folder, the "
                   "package's folder or a folder above either (a clone's ../shared); skipped when none is found.")
@click.option("--real-frames", default=60, show_default=True, type=click.IntRange(min=10),
              help="Frames of the real clip to track.")
@click.pass_context
def demo(ctx, out_dir, frames, runs, seed, real_clip, real_frames):
    """Generate a clip of an object that jumps in heavy clutter, track it with the box model's
    LS-N-IPS, LIS and bootstrap at about equal time per frame (annotated videos, track CSVs, a
    comparison over runs with table and plots); then track the first frames of a real clip with
    vistrack's default box tracker and OpenCV's MIL.

    Everything goes into OUT (./vistrack-demo by default).
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise click.ClickException(f"cannot create {out}: {e.strerror}") from None
    clip = out / "clips" / "jumps"
    click.echo(f"1/4 generating a {frames}-frame 320x240 clip in {clip}: a textured object in heavy clutter that "
               "jumps 38-51 px every 25 frames or so")
    make_contour_clip(clip, frames=frames, seed=seed + 1, **CLIP)
    click.echo("2/4 tracking it once per algorithm (annotated video + track CSV)")
    made = []
    for algo, n in DEMO_ALGOS:
        video, track = out / f"jumps-{algo}.mp4", out / f"jumps-{algo}.csv"
        click.echo(f"  {algo} N={n}:")
        ctx.invoke(run, video=str(clip), model_name="box", algo=algo, particles=n, seed=seed, init_gt="",
                   out_path=str(video), track_path=str(track), quiet=False, show_particles=10)
        made += [video, track]
    click.echo(f"3/4 comparing them over {runs} runs (as vistrack eval does): "
               + ", ".join(f"{a} N={n}" for a, n in DEMO_ALGOS))
    click.echo(compare(clip, DEMO_ALGOS, "box", runs, seed, out / "eval"))
    made.append(out / "eval" / "report.md")
    real = Path(real_clip) if real_clip else (find_real_clip() if real_clip is None else None)
    if real is None or not real.exists():
        where = real_clip or ("(none given)" if real_clip == "" else f"{REAL_CLIP} above {Path.cwd()} or the package")
        click.echo(f"4/4 skipped: no real clip at {where} (--real-clip DIR: a clip with box ground truth, e.g. "
                   "OTB's Girl; or set VISTRACK_REAL_DATA to the folder holding girl_otb)")
    else:
        name = real.name if real.is_dir() else real.parent.name
        excerpt = out / "clips" / name
        try:
            excerpt_clip(real, excerpt, real_frames)
        except VideoError as e:
            raise click.ClickException(str(e)) from None
        got = sum(1 for _ in (excerpt / "img").iterdir())
        took = f"the first {real_frames} frames" if got >= real_frames else \
            f"all {got} frames (fewer than --real-frames {real_frames})"
        click.echo(f"4/4 {took} of {real} ({excerpt}): vistrack's default box tracker "
                   f"({REAL_ALGOS[0][0].upper()} N={REAL_ALGOS[0][1]}, {runs} runs) beside OpenCV MIL")
        click.echo(compare(excerpt, REAL_ALGOS, DEFAULT_MODEL, runs, seed, out / "eval-real"))
        made.append(out / "eval-real" / "report.md")
    click.echo("")
    click.echo(f"done. In {out}/:")
    for p in made:
        click.echo(f"  {p}" + (" (tables and plots; results.json, results.csv beside it)" if p.suffix == ".md" else ""))
