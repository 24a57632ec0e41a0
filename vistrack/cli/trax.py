"""``vistrack trax``: vistrack as a tracker of the VOT toolkit, over the TraX protocol."""

from __future__ import annotations

import click

from vistrack.api.trax_server import ClientError, SessionError, serve

from .options import SEED, option

__all__ = ["trax"]


@click.command()
@option("--model", source=serve, help="Tracking model (any that starts from a box).")
@click.option("--algo", default=None, help="Particle filter [default: the model's].")
@option("-n", "--particles", source=serve, type=click.IntRange(min=1), help="Number of particles N.")
@option("--seed", source=serve, type=SEED, help="Random seed (same seed, same boxes).")
def trax(model, algo, particles, seed):
    """Serve one TraX session on standard input and output (the VOT toolkit starts this command;
    the boxes equal `vistrack run FRAMES --init x,y,w,h` with the same options and seed).
    Needs the optional vot-trax package: pip install "vistrack[trax]".

    \b
    trackers.ini:
      [vistrack]
      label = vistrack
      protocol = trax
      command = vistrack trax --seed 0
    """
    try:
        serve(model, algo, particles, seed)
    except ImportError as e:
        raise click.ClickException(f"vistrack trax needs the vot-trax package ({e}): pip install 'vistrack[trax]'") \
            from None
    except (ValueError, SessionError, ClientError) as e:  # options (before the hello), the session, the client
        raise click.ClickException(str(e)) from None
