"""The command line's progress bars and notes on stderr, for ``run``, ``eval``, ``reproduce`` and ``demo``.

A command shows one bar at a time (:class:`Bars`): the kernels compiling (the first run after an install),
the frames tracked, the tasks of a grid. A bar is closed (its last state drawn and its line ended) as soon
as its work is done and before another bar or anything else is printed, so that what follows starts a line
of its own, in a terminal and in a file alike; notes printed while a bar runs go above it
(:meth:`Bars.note`).
"""

from __future__ import annotations

import sys
from contextlib import contextmanager

from tqdm import tqdm

from .errors import one_line

__all__ = ["Bars", "progress"]

#: what the kernels' bar says (numba compiles them once per install: :mod:`vistrack.system.compiling`)
COMPILING = "compiling kernels (first run only)"


class Bars:
    """A command's progress bars on stderr, one at a time (module docstring); none with ``quiet``."""

    def __init__(self, quiet=False):
        self.quiet = quiet
        self.bar = None
        self.kind = None

    def _open(self, kind, **kw):
        self.close()
        self.kind = kind
        self.bar = tqdm(disable=self.quiet, dynamic_ncols=True, file=sys.stderr, **kw)
        return self.bar

    def close(self):
        """Close the bar shown (its last state drawn and its line ended)."""
        if self.bar is not None:
            self.bar.close()
        self.bar = self.kind = None

    def compiling(self, done, total):
        """``progress(done, total)`` of :func:`vistrack.system.compiling.compiling`: a bar of the kernels, closed
        when the last is done (a kernel the list did not name, compiled later, opens it again)."""
        bar = self.bar if self.kind == "compiling" else self._open("compiling", desc=COMPILING, unit="kernel",
                                                                    total=total)
        bar.total = total
        bar.n = done
        bar.refresh()
        if done >= total:
            self.close()

    def frames(self, label, total, initial=0):
        """A bar of ``total`` frames (``None``: unknown) from ``initial`` on; returns ``progress(ess)``."""
        bar = self._open("frames", desc=label, total=total, initial=initial, unit="frame")

        def progress(ess):
            bar.update(1)
            bar.set_postfix(ess=f"{ess:.1f}", refresh=False)

        return progress

    def tasks(self, desc, total):
        """A bar of ``total`` tasks, closed when the last is done; returns ``progress(k)``."""
        bar = self._open("grid", desc=desc, total=total, unit="task")

        def progress(k):
            bar.update(k)
            if bar.n >= total and self.bar is bar:
                self.close()

        return progress

    def note(self, line):
        """``line`` on stderr, above the bar shown."""
        tqdm.write(line, file=sys.stderr)

    def echo(self, text, err=False):
        """``text`` on stdout (stderr), after the bar shown is closed."""
        import click

        self.close()
        click.echo(text, err=err)


@contextmanager
def progress(desc, quiet=False, bars=None):
    """The engine's hooks (``progress``, ``on_ready``, ``notify``: a progress bar ``desc`` for each grid, shown
    once the workers are there and closed when its last task is done, unless ``quiet``; the notes on stderr
    even then) for the block, whose refusals are one error line (:func:`~vistrack.cli.errors.one_line`).
    ``bars``: the command's :class:`Bars` (a new one by default)."""
    bars = bars or Bars(quiet)
    tick = []

    def ready(total):  # a new grid in the block: a new bar
        tick[:] = [bars.tasks(desc, total)]

    hooks = {"progress": lambda k: tick[-1](k), "notify": lambda m: bars.echo(m, err=True), "on_ready": ready}
    try:
        with one_line():
            yield hooks
    finally:
        bars.close()
