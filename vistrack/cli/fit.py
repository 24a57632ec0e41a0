"""``vistrack fit-plate``: fit the plate likelihood's coefficients on synthetic plate clips."""

from __future__ import annotations

import click

from vistrack.models.plate.fitting import fit_plate_coefficients
from vistrack.registry import LAYOUTS

from .options import FloatList, option


@click.command("fit-plate")
@click.argument("clips", type=click.Path(exists=True, file_okay=False))
@option("--layout", source=fit_plate_coefficients, type=click.Choice(list(LAYOUTS)),
        help="Plate layout the template is fitted to: Japanese two-row (jp) or single-row.")
@option("--rounds", source=fit_plate_coefficients, type=click.IntRange(min=0),
        help="Refits with hard negatives mined by the current coefficients.")
@click.option("--scales", type=FloatList(), metavar="S0,S1",
              help="Scale-banded coefficients: fit them at these two plate widths (px), interpolated in log s.")
def fit_plate(clips, layout, rounds, scales):
    """Fit the plate likelihood's term coefficients on the plate clips in CLIPS (folders made by
    ``vistrack synth plate``) and print them as ``LEARNT_WEIGHTS`` takes them.

    \b
    Example (the shipped coefficients; seeds 101-116):
      vistrack fit-plate train/ --scales 40,80
    """
    if scales is not None and len(scales) != 2:
        raise click.UsageError("--scales takes two plate widths, S0,S1")
    try:
        fit = fit_plate_coefficients(clips, layout, rounds=rounds, scales=tuple(scales) if scales else None)
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    for k, v in fit["samples"].items():
        click.echo(f"{k:>7}: n={v['n']:6d}  log-odds 1/50/99 % {v['log_odds_1_50_99']}  > 0: {v['above_0']:.3f}")
    if fit["scales"] is None:
        click.echo("weights = {" + ", ".join(f'"{n}": {v:.4f}' for n, v in fit["weights"].items()) + "}")
        click.echo(f"bias = {fit['bias']:.4f}")
    else:
        click.echo("weights = {" + ", ".join(f'"{n}": ({a:.4f}, {c:.4f})' for n, (a, c) in fit["weights"].items())
                   + "}")
        click.echo(f"bias = ({fit['bias'][0]:.4f}, {fit['bias'][1]:.4f}), scales = {fit['scales']}")
