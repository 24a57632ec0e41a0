"""The command line's side of the batch engine (:mod:`vistrack.batch.cluster`): a progress bar and the
engine's notes on stderr, for ``eval``, ``reproduce`` and ``demo``."""

from __future__ import annotations

from contextlib import contextmanager

import click
from tqdm import tqdm

from .errors import one_line

__all__ = ["progress"]


@contextmanager
def progress(desc, quiet=False):
    """The engine's hooks (``progress``, ``on_ready``, ``notify``: a progress bar ``desc`` for each grid, shown
    once the workers are there, unless ``quiet``, and the notes on stderr even then) for the block, whose
    refusals are one error line (:func:`~vistrack.cli.errors.one_line`)."""
    bar = []

    def ready(total):  # a new grid in the block: a new bar
        for b in bar:
            b.close()
        bar.append(tqdm(total=total, unit="task", desc=desc, disable=quiet))

    hooks = {"progress": lambda k: bar[-1].update(k), "notify": lambda m: click.echo(m, err=True), "on_ready": ready}
    try:
        with one_line():
            yield hooks
    finally:
        for b in bar:
            b.close()
