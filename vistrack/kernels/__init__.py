"""Compiled kernels (numba) for the per-frame hot loops, beside the numpy paths they replace.

Each kernel computes what a numpy path of a model computes — the same samples, the same
arithmetic in the same order where that can be had, so that tracks stay identical — and is
tested against it (``tests/kernels/test_kernels.py``, which states each tolerance). The numpy paths stay
as the reference and as the fallback where numba is missing:

- :mod:`~vistrack.kernels.sampling`: bilinear samples exactly as ``cv2.remap`` (``INTER_LINEAR``,
  1/32-pixel fixed point) and numpy's pairwise summation;
- :mod:`~vistrack.appearance.cue_kernels`: colour bins, per-bin integral images, the colour term and the
  template correlation (the feature maps and the box, contour and plate appearance);
- :mod:`~vistrack.kernels.map_draws`: the grid proposal's draws (:class:`~vistrack.proposals.map_proposal.MapProposal`);
- :mod:`~vistrack.models.bearings.laplace_parts`: the bearings ξ proposal's Laplace parts, plain numpy that the
  bearings kernels compile.

Each model family keeps its own kernels in its package (:mod:`vistrack.models.box.kernels`,
:mod:`~vistrack.appearance.frame_kernels`, :mod:`~vistrack.appearance.dcf_kernels`,
:mod:`vistrack.models.contour.kernels`, :mod:`~vistrack.models.contour.search_kernels`,
:mod:`vistrack.models.plate.kernels`, :mod:`~vistrack.models.plate.scan_kernels`,
:mod:`vistrack.models.bearings.kernels`); this package holds what they share and :func:`use`.

Every entry point releases the GIL (``nogil``): the decoding thread of ``vistrack run`` runs beside
them. Kernels are compiled on first use and cached on disk (``cache=True``; loading them takes 0.1–1 s,
which :func:`vistrack.loop.stepper.warm_up` does before a run's clock starts). Hot loops pass only
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
    import numba
except ImportError:  # pragma: no cover - numba is a dependency; the numpy paths still work
    numba = None

#: whether numba can be imported (the kernels can be compiled)
AVAILABLE = numba is not None

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
