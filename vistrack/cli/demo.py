"""``vistrack demo``: the README's main job on a generated clip and a real one, in under 40 s
(:mod:`vistrack.demo.steps`)."""

from __future__ import annotations

from pathlib import Path

import click

from vistrack.demo.steps import (
    CLIP,
    CLIP_FOLDER,
    DEMO_ENTRIES,
    REAL_CLIP,
    REAL_ENTRIES,
    check_demo,
    compare,
    make_demo_clip,
    real_excerpt,
)
from vistrack.registry import DEFAULT_MODEL

from .errors import one_line
from .options import SEED, Output
from .progress import progress
from .run import run

__all__ = ["demo"]


def _entries(entries):
    """``ls-n-ips N=30, lis N=30, ...``."""
    return ", ".join(f"{a} N={n}" for a, n in entries)


def _step4(real, real_clip, real_frames, runs):
    """Step 4's line: the real clip's excerpt, or where none was found."""
    if real is None:
        where = real_clip or ("(none given)" if real_clip == "" else f"{REAL_CLIP} above {Path.cwd()} or the package")
        return (f"4/4 skipped: no real clip at {where} (--real-clip DIR: a clip with box ground truth, e.g. "
                "OTB's Girl; or set VISTRACK_REAL_DATA to the folder holding girl_otb)")
    took = f"the first {real_frames} frames" if real.frames >= real_frames else \
        f"all {real.frames} frames (fewer than --real-frames {real_frames})"
    return (f"4/4 {took} of {real.real} ({real.folder}): vistrack's default box tracker "
            f"({REAL_ENTRIES[0][0].upper()} N={REAL_ENTRIES[0][1]}) beside OpenCV MIL, {_runs(runs)} each")


def _runs(n):
    """``1 run``, ``4 runs``."""
    return f"{n} run{'' if n == 1 else 's'}"


def _made(out, paths):
    """The closing lines: every file made."""
    notes = {".md": " (tables and plots; results.json, results.csv beside it)",
             ".html": " (the same in a browser, with an annotated video per tracker)"}
    return "\n".join(["", f"done. In {out}/:"] + [f"  {p}{notes.get(p.suffix, '')}" for p in paths])


@click.command()
@click.option("--out", "out_dir", default="vistrack-demo", show_default=True, type=Output(file_okay=False),
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
    out, made, (w, h) = Path(out_dir), [], CLIP["size"]
    with one_line():
        check_demo(frames, runs, real_frames)
    click.echo(f"1/4 generating a {frames}-frame {w}x{h} clip in {out / CLIP_FOLDER}: a textured object in heavy "
               "clutter that jumps 38-51 px every 25 frames or so")
    with one_line():
        clip = make_demo_clip(out, frames, seed)
    click.echo("2/4 tracking it once per algorithm (annotated video + track CSV)")
    for algo, n in DEMO_ENTRIES:
        made += [out / f"jumps-{algo}.mp4", out / f"jumps-{algo}.csv"]
        click.echo(f"  {algo} N={n}:")
        ctx.invoke(run, video=str(clip), model_name=DEFAULT_MODEL, algo=algo, particles=n, seed=seed, init_gt="",
                   out_path=str(made[-2]), track_path=str(made[-1]), quiet=False, show_particles=10)
    click.echo(f"3/4 comparing them over {_runs(runs)} (as vistrack eval does): " + _entries(DEMO_ENTRIES))
    with progress("eval") as hooks:
        click.echo(compare(clip, DEMO_ENTRIES, DEFAULT_MODEL, runs, seed, out / "eval", **hooks))
        real = real_excerpt(real_clip, out / "clips", real_frames)
        click.echo(_step4(real, real_clip, real_frames, runs))
        if real is not None:
            click.echo(compare(real.folder, REAL_ENTRIES, DEFAULT_MODEL, runs, seed, out / "eval-real", **hooks))
    reports = [out / e / f"report.{x}" for e in ("eval", "eval-real")[:1 + (real is not None)] for x in ("md", "html")]
    click.echo(_made(out, made + reports))
