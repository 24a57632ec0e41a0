"""Shared by the kernel tests: run the same computation on the numpy paths and on the kernels; and the
kernels compiled once before the suite (``tests/conftest.py``)."""

import warnings

import numpy as np

from vistrack import kernels
from vistrack.filters import filter_steps
from vistrack.loop import Stepper
from vistrack.models.bearings.model import Bearings, simulate
from vistrack.models.plate.model import Plate
from vistrack.models.plate.plates import Plates
from vistrack.registry import make_filter, model_from_box


def both(fn):
    """``fn()`` on the numpy paths, then on the kernels."""
    with kernels.numpy_paths():
        a = fn()
    with kernels.numpy_paths(False):
        b = fn()
    return a, b


#: what is tracked to compile the kernels: ``(model, its options, the start box, frame size, filters)``, the
#: filters those whose steps call compiled code (a large box: the appearance maps shrunk; no correlation
#: filter: the box model's compiled LIS step; an edge-only contour: the compiled LMS search)
COMPILED = (("box", {}, (30, 40, 30, 30), (160, 120), ("lis", "ls-n-ips", "lls", "bootstrap")),
            ("box", {"dcf": False}, (30, 40, 30, 30), (160, 120), ("lis",)),
            ("box", {}, (30, 40, 130, 110), (320, 240), ("lis",)),
            ("contour", {}, (30, 40, 30, 30), (160, 120), ("lis", "ls-n-ips", "lls")),
            ("contour", {"colour": False}, (30, 40, 30, 30), (160, 120), ("ls-n-ips",)),
            ("plate", {}, (90, 90, 48, 12), (160, 120), ("lis", "bootstrap")),
            ("siam", {}, (30, 40, 30, 30), (160, 120), ("lis",)))


def _frames(size, n=4):
    """``n`` colour frames of a textured scene with a red box and a white plate-like bar moving right."""
    rng = np.random.default_rng(0)
    w, h = size
    base = (rng.random((h, w, 3)) * 160 + 40).astype(np.uint8)
    out = []
    for t in range(n):
        f = base.copy()
        f[40:150, 30 + t:160 + t] = (40, 60, 220)
        f[90:102, 90 + t:138 + t] = 245
        f[93:99, 96 + t:132 + t:4] = 20
        out.append((t, f))
    return out


def _track(filt, frames):
    for _ in Stepper(filt, 30, np.random.default_rng(0)).steps(frames):
        pass


def _jobs():
    """What :func:`compile_kernels` tracks, one entry per filter: ``(model, options, box, size, algo)``, then the
    plate search, several plates and the bearings ξ proposal."""
    return [(name, options, box, size, algo) for name, options, box, size, algos in COMPILED for algo in algos] + [
        "plate-search", "plates", "bearings"]


def _compile(job):
    if job == "plate-search":
        _track(make_filter("lis", Plate((160, 120))), _frames((160, 120)))
    elif job == "plates":
        _track(make_filter("partitioned-lis", Plates((160, 120), 2, "single-row")), _frames((160, 120)))
    elif job == "bearings":
        bearings = Bearings(ships=1)
        _, obs = simulate(bearings, 3, np.random.default_rng(0))
        for _ in filter_steps(make_filter("lis", bearings), obs, 30, np.random.default_rng(0)):
            pass
    else:
        name, options, box, size, algo = job
        frames = _frames(size)
        _track(make_filter(algo, model_from_box(name, frames[0][1], box, **options)), frames)


def compile_kernels(part=0, parts=1):
    """Every kernel the models' and filters' steps call, compiled (or loaded from numba's disk cache,
    ``cache=True``): each kernel of the package's manifest (``vistrack/system/kernel_manifest.json``: what every
    model and algorithm calls, for small and large frames) with its argument types, then what the manifest does not
    hold, tracked: a few frames of each model of :data:`COMPILED` with its filters, a plate acquired without a box,
    several plates with partitioned LIS and the bearings ξ proposal's LIS (then loaded from the cache). ``part``
    of ``parts``: every ``parts``-th of those from the ``part``-th (the processes that share the work)."""
    if not kernels.use():
        return
    from vistrack.system.compiling import kernel, manifest

    listed = [("kernel", *v) for _, v in sorted(manifest().get("kernels", {}).items())]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for job in (listed + _jobs())[part::parts]:
            if job[0] == "kernel":
                kernel(job[1], job[2]).compile(f"({job[3]},)")
            else:
                _compile(job)
