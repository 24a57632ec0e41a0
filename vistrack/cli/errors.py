"""The library's refusals as the command line's one error line: an option that does not apply to the
model (:class:`~vistrack.registry.OptionError`) is a usage error (exit 2), bad input (``ValueError``,
``VideoError``) and an engine that cannot run or finish (:class:`~vistrack.batch.cluster.EngineError`,
:class:`~vistrack.batch.tasks.OutLocked`, :class:`~vistrack.batch.tasks.TaskFailed`) one
``Error:`` line (exit 1)."""

from __future__ import annotations

from contextlib import contextmanager

import click

from vistrack.batch.cluster import EngineError
from vistrack.batch.tasks import OutLocked, TaskFailed
from vistrack.io.outputs import OutputBusy
from vistrack.registry import OptionError

__all__ = ["one_line"]


@contextmanager
def one_line():
    """The block's refusals (module docstring) as click's exceptions: one line each."""
    try:
        yield
    except OptionError as e:
        raise click.UsageError(str(e)) from None
    except (ValueError, EngineError, OutLocked, TaskFailed, OutputBusy) as e:
        raise click.ClickException(str(e)) from None
