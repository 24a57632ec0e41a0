"""``vistrack train-search``: train (and cache) the contour model's neural-network local search."""

from __future__ import annotations

import click

from vistrack.models.contour import builder as contour
from vistrack.registry import read_support_points

from .errors import one_line
from .options import SEED, Output, Size, check_outputs, check_writable, option, size_text

__all__ = ["train_search"]


@click.command("train-search")
@click.option("--template", "template_path", required=True, type=click.Path(dir_okay=False),
              help="Contour support points in pixels as tracked (x y per line, JSON, or a clip's meta.json).")
@option("--size", source=contour.train_search, shown=size_text, type=Size(),
        help="Frame size of the video (λ's translation scales with the frame width).")
@option("--samples", source=contour.train_search, type=click.IntRange(min=100), help="Simulated training poses.")
@option("--seed", source=contour.train_search, type=SEED, help="Seed of the simulation and the network.")
@click.option("--out", "out_path", type=Output(dir_okay=False),
              help="Write the network here [default: the cache, $VISTRACK_CACHE or ~/.cache/vistrack].")
def train_search(template_path, size, samples, seed, out_path):
    """Train the neural-network local search of LS-N-IPS (thesis §4.3.1, Fig. 4.5) for a contour
    template, ahead of `vistrack run --algo ls-n-ips --search nn` (which otherwise trains it on
    first use, once per template, size and frame width) and cache it.

    \b
    Example:
      vistrack train-search --template clip/meta.json --size 320x240
    """
    check_writable(out_path, "--out")
    check_outputs({"--out": out_path}, None, [template_path])
    with one_line():
        _, info = contour.train_search(read_support_points(template_path), size, samples=samples, seed=seed,
                                       path=out_path, notify=lambda m: click.echo(m, err=True))
    if info["trained"]:
        click.echo(f"trained in {info['seconds']:.1f} s ({info['cpu_seconds']:.1f} s CPU): "
                   + (info["path"] if info["kept"] else "not kept (the cache cannot be written; see above)"))
    else:
        click.echo(f"already trained: {info['path']}")
