"""Compiled kernels (numba) for the per-frame hot loops, beside the numpy paths they replace.

Each kernel computes what a numpy path of a model computes — the same samples, the same
arithmetic in the same order where that can be had, so that tracks stay identical — and is
tested against it (``tests/test_kernels.py``, which states each tolerance). The numpy paths stay
as the reference and as the fallback where numba is missing:

- :mod:`~vistrack.kernels.sampling`: bilinear samples exactly as ``cv2.remap`` (``INTER_LINEAR``,
  1/32-pixel fixed point) and numpy's pairwise summation;
- :mod:`~vistrack.kernels.contour`: the contour's measurement lines, edge features, likelihood and
  the local-search grid;
- :mod:`~vistrack.kernels.contour_search`: the contour's LMS local search fused into two passes;
- :mod:`~vistrack.kernels.plate`: the plate likelihood's 4-channel map and pixel-set means (the
  likelihood, the sparse search and the line scans);
- :mod:`~vistrack.kernels.plate_scan`: the plate LIS proposal's line scans of all particles in one
  call, and its cell draws;
- :mod:`~vistrack.kernels.appearance`: the box model's colour bins, per-bin integral images,
  colour term and template correlation;
- :mod:`~vistrack.kernels.bearings`: the bearings ξ proposal's move and first stage.

Every entry point releases the GIL (``nogil``): the decoding thread of ``vistrack run`` runs beside
them. Kernels are compiled on first use and cached on disk (``cache=True``; loading them takes 0.1–1 s,
which :func:`vistrack.tracking.warm_up` does before a run's clock starts). Hot loops pass only
scalars to helper functions: numba counts references on every call that passes an array, which
cost more than the sampling itself. :func:`use` says whether
the models call them: numba importable and the environment variable ``VISTRACK_NUMBA`` not ``0``;
:func:`numpy_paths` turns them off within a block (tests, benchmarks).
"""

from __future__ import annotations

import os
from contextlib import contextmanager

__all__ = ["AVAILABLE", "use", "numpy_paths"]

try:
    import numba  # noqa: F401

    AVAILABLE = True
except ImportError:  # pragma: no cover - numba is a dependency; the numpy paths still work
    AVAILABLE = False

_state = {"on": AVAILABLE and os.environ.get("VISTRACK_NUMBA", "1") != "0"}


def use():
    """Whether the models call the compiled kernels (else their numpy paths)."""
    return _state["on"]


@contextmanager
def numpy_paths(on=True):
    """Within the block the models take their numpy paths (``on=False``: the kernels, if numba is
    there); the previous setting is restored after."""
    old = _state["on"]
    _state["on"] = (not on) and AVAILABLE
    try:
        yield
    finally:
        _state["on"] = old
