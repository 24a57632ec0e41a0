"""The command line's side of the batch engine (:mod:`vistrack.engine.grid`): a progress bar, its notes on
stderr and its refusals as one error line, for ``eval``, ``reproduce`` and ``demo``."""

from __future__ import annotations

from contextlib import contextmanager

import click
from tqdm import tqdm

from vistrack.engine.evaluation import OutLocked, TaskFailed, lock_out
from vistrack.engine.grid import EngineError, run_grid

__all__ = ["run_tasks"]


@contextmanager
def _locked(out):
    """:func:`vistrack.engine.tasks.lock_out` with its refusal as one error line."""
    try:
        with lock_out(out):
            yield
    except OutLocked as e:
        raise click.ClickException(str(e)) from None


def run_tasks(tasks, out, *, scheduler=None, workers=0, timeout=10, in_process=False, resume=False, quiet=False,
              desc="tasks", runner=None):
    """:func:`vistrack.engine.grid.run_grid` with a progress bar, its refusals and failures as one error line
    and its notes on stderr (even with ``quiet``)."""
    bar = []  # the progress bar, shown once the workers are there

    def progress(k):
        bar[0].update(k)

    try:
        run_grid(tasks, out, scheduler=scheduler, workers=workers, timeout=timeout, in_process=in_process,
                 resume=resume, progress=progress, runner=runner, notify=lambda m: click.echo(m, err=True),
                 on_ready=lambda: bar.append(tqdm(total=len(tasks), unit="task", desc=desc, disable=quiet)))
    except (OutLocked, EngineError, TaskFailed) as e:
        raise click.ClickException(str(e)) from None
    finally:
        for b in bar:
            b.close()
