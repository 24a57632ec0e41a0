"""The first run after an install compiles the kernels, and says so.

The compiled kernels (:mod:`vistrack.kernels` and the model families' own) are compiled by numba on
first use and kept in its on-disk cache (``cache=True``: ``__pycache__`` beside the installed
sources, or ``$NUMBA_CACHE_DIR``), so they compile once per install; later runs load them (0.1–1
s). :func:`compile_notice` watches numba's own compile events (fired only when a kernel is not in
the cache): at the first it tells the user, once, ``compiling kernels (first run only, about N
s)``, so that a first run does not look hung (nor a progress bar estimate minutes for the
seconds the first frame takes).
"""

from __future__ import annotations

from contextlib import contextmanager

__all__ = ["compile_notice", "compile_message", "CompileWatch"]


def compile_message(seconds):
    """``compiling kernels (first run only, about N s)``: ``seconds``, what a model's kernels take to compile
    (its registry entry's :attr:`~vistrack.models.spec.ModelSpec.compile_seconds`,
    :func:`vistrack.registry.catalog.compile_seconds`)."""
    return f"compiling kernels (first run only, about {seconds} s)"


class CompileWatch:
    """What :func:`compile_notice` yields: ``message`` (set it once the model is known) and
    ``compiled`` (whether a kernel compiled)."""

    def __init__(self, message):
        self.message, self.compiled = message, False


@contextmanager
def compile_notice(notify, message="compiling kernels (first run only)"):
    """Within the block, call ``notify(watch.message)`` once when numba starts compiling a kernel (one
    not in its cache); nothing when every kernel loads from the cache, without numba, or with
    ``notify`` ``None``. Yields the :class:`CompileWatch`."""
    watch = CompileWatch(message)
    try:
        from numba.core import event
    except ImportError:  # pragma: no cover - numba is a dependency
        yield watch
        return

    class Listener(event.Listener):
        def on_start(self, ev):
            if not watch.compiled:
                watch.compiled = True
                if notify is not None:
                    notify(watch.message)

        def on_end(self, ev):
            pass

    with event.install_listener("numba:compile", Listener()):
        yield watch
