"""The ``vistrack`` command line: parse, call the library, show progress, print.

Errors from bad input are one line (``Error: ...``) and a non-zero exit, never
a traceback.
"""

from __future__ import annotations

import sys
import warnings
from contextlib import contextmanager

from vistrack.system.signals import abort_on_interrupt, interrupt_aborts

with interrupt_aborts():  # Ctrl-C in the seconds the modules load: "Aborted.", 130, no traceback
    import click

    from vistrack import __version__
    from vistrack.io.outputs import OutputError, OutputIsInput, command_inputs
    from vistrack.system.resources import TooLarge, keep_freed_memory
    from vistrack.system.signals import Terminated, stop_on_signals

    from .demo import demo
    from .eval import eval_cmd
    from .fit import fit_plate
    from .reproduce import reproduce
    from .run import run
    from .synth import synth, synth_suite
    from .train_search import train_search
    from .trax import trax

__all__ = ["cli", "main"]


class VistrackGroup(click.Group):
    """The command group whose :meth:`main` gives one-line errors and exit codes (:func:`main`), so
    that click's ``CliRunner`` sees exactly what the console sees."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        """Run the group, turn usage errors into one line. SIGTERM stops any command as Ctrl-C does
        (files in progress are finished or removed, never left half-written); an operating-system
        error (disk full, permission denied) is one line too. Exits (``SystemExit``) with the code."""
        try:
            with stop_on_signals(), _one_line_warnings(), command_inputs():
                code = super().main(args=args, prog_name=prog_name or "vistrack", complete_var=complete_var,
                                    standalone_mode=False, **extra)
        except click.exceptions.NoArgsIsHelpError as e:
            click.echo(e.ctx.get_help() if e.ctx else str(e))
            sys.exit(0)
        except click.ClickException as e:
            msg = e.format_message().replace("\n", " ")
            click.echo(f"Error: {msg}", err=True)
            sys.exit(e.exit_code)
        except (click.exceptions.Abort, KeyboardInterrupt) as e:
            _stopped(e)
        except (OutputError, OutputIsInput, TooLarge) as e:  # one line: the output and the cause; the size, what fits
            click.echo(f"Error: {e}", err=True)
            sys.exit(1)
        except OSError as e:
            where = f": {e.filename}" if e.filename else ""
            click.echo(f"Error: {e.strerror or e}{where}", err=True)
            sys.exit(1)
        sys.exit(code if isinstance(code, int) else 0)


@click.group(cls=VistrackGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="vistrack")
def cli():
    """vistrack: particle-filter object tracking that uses the observation well.

    Algorithms from P. Torma's thesis (Bootstrap/CONDENSATION, AVPF, LLS, LIS)
    on a vectorised particle core. Run `vistrack COMMAND --help` for details.

    \b
    Examples:
      vistrack run my_video.mp4 --init x,y,w,h --out annotated.mp4   # track any object from a box
      vistrack run dashcam.mp4 --model plate --track plates.csv       # find and follow a license plate
      vistrack eval clips/ --algos lis,opencv-mil --runs 3 --out ev   # compare trackers on clips with ground truth
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
cli.add_command(trax)


@contextmanager
def _one_line_warnings():
    """Warnings (ground truth of another length, skipped frames, ...) as ``warning: message``
    lines, not Python's two lines with the source file and line."""
    saved = warnings.formatwarning
    warnings.formatwarning = lambda message, category, *args, **kw: f"warning: {message}\n"
    try:
        yield
    finally:
        warnings.formatwarning = saved


def _stopped(e):
    """Exit on Ctrl-C (130) or SIGTERM (143; :class:`~vistrack.system.signals.Terminated`), which click
    may have wrapped in ``Abort``."""
    term = any(isinstance(x, Terminated) for x in (e, e.__cause__, e.__context__))
    click.echo("Terminated." if term else "Aborted.", err=True)
    sys.exit(143 if term else 130)


def main(argv=None):
    """Console entry point: :meth:`VistrackGroup.main` on ``argv`` (default: the command line).
    On the process's own command line, a Ctrl-C once the command is done (its shut-down) ends it
    at once with ``Aborted.`` and 130, as in its start-up."""
    try:
        cli.main(args=argv)
    finally:
        if argv is None:
            abort_on_interrupt()
