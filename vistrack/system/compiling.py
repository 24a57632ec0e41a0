"""The first run after an install compiles the kernels, and says what it does.

The compiled kernels (:mod:`vistrack.kernels`, :mod:`vistrack.appearance` and the model families' own) are
compiled by numba on first use and kept in its on-disk cache (``cache=True``: ``__pycache__`` beside the
installed sources, or ``$NUMBA_CACHE_DIR``), so they compile once per install; later runs load them (0.1–1
s). Which kernels a model and an algorithm call, with their argument types, is listed in
``kernel_manifest.json`` beside this module (written by ``python tools/kernel_manifest.py``, checked by
the tests), so that :meth:`Compiler.compile` compiles exactly those of the run's model and algorithm, each
once, before tracking starts, and can say how far it is: ``progress(done, total)`` from the first kernel
that is not in the cache on (nothing at all when every one loads from it). A kernel the list does not name
(a model option's own) compiles when first called, and is counted too while the :class:`Compiler` is
open. The time it takes is not promised: the count and the clock are shown instead (a busy machine takes
twice as long as an idle one).
"""

from __future__ import annotations

import functools
import importlib
import json
from contextlib import contextmanager
from pathlib import Path

__all__ = ["MANIFEST", "Compiler", "compiling", "kernels_for", "kernel", "signature_text", "manifest"]

#: the kernels of each ``model/algo`` (``kernels``: ``[module, name, argument types]`` by id; ``runs``: the ids
#: of each model and algorithm, in the order they are first called)
MANIFEST = Path(__file__).with_name("kernel_manifest.json")


@functools.cache
def manifest():
    """The kernel manifest (:data:`MANIFEST`) as a dict; empty where it is missing."""
    try:
        return json.loads(MANIFEST.read_text())
    except OSError:  # pragma: no cover - package data
        return {"kernels": {}, "runs": {}}


def kernels_for(model, algos, targets=False):
    """The ``(module, name, argument types)`` of the kernels that ``model`` calls with each of ``algos``
    (``targets``: tracking several targets), each once, in the order they are first called."""
    m = manifest()
    ids = dict.fromkeys(k for a in algos for k in m["runs"].get(f"{model}/{a}" + ("/targets" if targets else ""), ()))
    return [tuple(m["kernels"][k]) for k in ids]


def kernel(module, name):
    """The compiled kernel ``name`` of the module ``module`` (a manifest entry's)."""
    return getattr(importlib.import_module(module), name)


def signature_text(args):
    """numba argument types as the text numba reads back (``uint8[:, :, ::1], float64, int64``)."""
    from numba.core import types

    def one(t):
        if isinstance(t, types.Literal):  # a constant in a kernel's call of another: never from Python
            raise ValueError(f"no text for {t}")
        if isinstance(t, types.Array):
            if not t.mutable or not t.aligned or t.layout not in "CFA":
                raise ValueError(f"no text for {t}")
            dims = [":"] * t.ndim
            if t.layout == "C":
                dims[-1] = "::1"
            elif t.layout == "F":
                dims[0] = "::1"
            return f"{one(t.dtype)}[{', '.join(dims)}]"
        if isinstance(t, types.Boolean):
            return "boolean"
        if isinstance(t, types.UniTuple):
            return f"UniTuple({one(t.dtype)}, {t.count})"
        if isinstance(t, types.Tuple):
            return f"Tuple(({', '.join(one(u) for u in t.types)},))"
        if isinstance(t, types.NoneType):
            return "none"
        if isinstance(t, (types.Integer, types.Float, types.Complex)):
            return str(t)
        raise ValueError(f"no text for {t}")

    return ", ".join(one(t) for t in args)


class Compiler:
    """The kernels compiled within a :func:`compiling` block, counted for ``progress(done, total)`` (called
    from the first compile on; never when every kernel loads from the cache); ``enabled=False`` (the models
    take their numpy paths: :func:`vistrack.kernels.use`): :meth:`compile` compiles nothing."""

    def __init__(self, progress=None, enabled=True):
        self.progress, self.enabled = progress, enabled
        self.done = self.total = 0
        self.compiled = False  # a kernel was compiled (not loaded from the cache)
        self._listed = False  # within compile(): the loop counts
        self._depth = 0

    def compile(self, model, algos, targets=False):
        """Compile, or load from numba's cache, the kernels ``model`` calls with each of ``algos``
        (:func:`kernels_for`), each once; nothing where the compiler is not :attr:`enabled`."""
        if not self.enabled:
            return
        todo = kernels_for(model, algos, targets)
        self.total += len(todo)
        self._listed = True
        try:
            for module, name, args in todo:
                kernel(module, name).compile(f"({args},)")
                self.done += 1
                self._tell()
        finally:
            self._listed = False

    def _tell(self):
        if self.compiled and self.progress is not None:
            self.progress(self.done, self.total)

    def _start(self):
        """numba starts compiling a kernel (of the list, or one it does not name: counted too)."""
        self._depth += 1
        if self._depth > 1:
            return
        if not self._listed:
            self.total += 1
        if not self.compiled:
            self.compiled = True
            self._tell()

    def _end(self):
        self._depth -= 1
        if self._depth == 0 and not self._listed:
            self.done += 1
            self._tell()


@contextmanager
def compiling(progress=None, enabled=True):
    """Within the block, count the kernels numba compiles (:class:`Compiler`, yielded: its :meth:`compile`
    compiles a model's and algorithm's kernels up front, where ``enabled``) and tell ``progress(done, total)``
    from the first compile on; nothing when every kernel loads from the cache or without numba."""
    compiler = Compiler(progress, enabled)
    try:
        from numba.core import event
    except ImportError:  # pragma: no cover - numba is a dependency
        yield compiler
        return

    class Listener(event.Listener):
        def on_start(self, ev):
            compiler._start()

        def on_end(self, ev):
            compiler._end()

    with event.install_listener("numba:compile", Listener()):
        yield compiler
