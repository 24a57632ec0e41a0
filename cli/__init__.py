"""The ``vistrack`` command line: parse, call the library, show progress, print.

Errors from bad input are one line (``Error: ...``) and a non-zero exit, never
a traceback.
"""

from __future__ import annotations

import sys

import click

from vistrack import __version__
from vistrack.runtime import keep_freed_memory

from .demo import demo
from .eval import eval_cmd
from .fit import fit_plate
from .reproduce import reproduce
from .run import run
from .synth import synth, synth_suite
from .train_search import train_search

__all__ = ["cli", "main"]


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="vistrack")
def cli():
    """vistrack: particle-filter object tracking that uses the observation well.

    Algorithms from P. Torma's thesis (Bootstrap/CONDENSATION, AVPF, LLS, LIS)
    on a vectorised particle core. Run `vistrack COMMAND --help` for details.

    \b
    Examples:
      vistrack demo                                  # generate, track, compare: ./vistrack-demo
      vistrack synth contour --out clip              # synthetic clip with ground truth
      vistrack run clip --algo ls-n-ips -n 30 --init-gt --out annotated.mp4 --track track.csv
      vistrack reproduce bearings --runs 20          # thesis §4.5.5, one ship
      vistrack reproduce bearings --ships 3 --particles 10,100
    """
    keep_freed_memory()


cli.add_command(reproduce)
cli.add_command(demo)
cli.add_command(eval_cmd)
cli.add_command(fit_plate)
cli.add_command(run)
cli.add_command(synth)
cli.add_command(synth_suite)
cli.add_command(train_search)


def main(argv=None):
    """Console entry point: run the group, turn usage errors into one line."""
    try:
        code = cli.main(args=argv, prog_name="vistrack", standalone_mode=False)
    except click.exceptions.NoArgsIsHelpError as e:
        click.echo(e.ctx.get_help() if e.ctx else str(e))
        sys.exit(0)
    except click.ClickException as e:
        msg = e.format_message().replace("\n", " ")
        click.echo(f"Error: {msg}", err=True)
        sys.exit(e.exit_code)
    except click.exceptions.Abort:
        click.echo("Aborted.", err=True)
        sys.exit(130)
    except KeyboardInterrupt:
        click.echo("Interrupted.", err=True)
        sys.exit(130)
    sys.exit(code if isinstance(code, int) else 0)
