"""``vistrack demo``: the README's main job on a generated clip and a real one, in under 40 s
(:mod:`vistrack.demo.steps`)."""

from __future__ import annotations

from pathlib import Path

import click

from vistrack.demo.steps import DemoConfig, run_demo

from .options import SEED, Output, option
from .progress import Bars, progress
from .run import lost_notice

__all__ = ["demo"]


def _made(out, paths):
    """The closing lines: every file made."""
    notes = {".md": " (tables and plots; results.json, results.csv beside it)",
             ".html": " (the same in a browser, with an annotated video per tracker)"}
    return "\n".join(["", f"done. In {out}/:"] + [f"  {p}{notes.get(p.suffix, '')}" for p in paths])


@click.command()
@option("--out", "out_dir", source=DemoConfig, key="out", type=Output(file_okay=False),
        help="Folder for clips, annotated videos, tracks, tables and plots.")
@option("--frames", source=DemoConfig, type=click.IntRange(min=10), help="Number of frames to generate.")
@option("--runs", source=DemoConfig, type=click.IntRange(min=1),
        help="Monte-Carlo runs per algorithm in the comparisons.")
@option("--seed", source=DemoConfig, type=SEED, help="Random seed: the same seed gives the same output, bit for bit.")
@click.option("--real-clip", "real_clip", default=None, metavar="DIR",
              help="A real clip with box ground truth (any layout run reads); '' skips it. Default: "
                   "$VISTRACK_REAL_DATA/girl_otb, else shared/data/real/girl_otb in the working folder, the "
                   "package's folder or a folder above either (a clone's ../shared); skipped when none is found.")
@option("--real-frames", source=DemoConfig, type=click.IntRange(min=10), help="Frames of the real clip to track.")
def demo(out_dir, frames, runs, seed, real_clip, real_frames):
    """Generate a clip of an object that jumps in heavy clutter, track it with the box model's
    LS-N-IPS, LIS and bootstrap at about equal time per frame (annotated videos, track CSVs, a
    comparison over runs with table and plots); then track the first frames of a real clip with
    vistrack's default box tracker and OpenCV's MIL.

    Everything goes into OUT (./vistrack-demo by default).
    """
    bars = Bars()
    tracking = {"note": bars.note, "lost": lost_notice(bars.note), "compiling_progress": bars.compiling,
                "frames": bars.frames}
    with progress("eval", bars=bars) as grid:  # its refusals: one error line
        made = run_demo(out_dir, frames=frames, runs=runs, seed=seed, real_clip=real_clip, real_frames=real_frames,
                        say=bars.echo, tracking=tracking, grid=grid)
    click.echo(_made(Path(out_dir), made))
