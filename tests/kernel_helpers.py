"""Shared by the kernel tests: run the same computation on the numpy paths and on the kernels."""

from vistrack import kernels


def both(fn):
    """``fn()`` on the numpy paths, then on the kernels."""
    with kernels.numpy_paths():
        a = fn()
    with kernels.numpy_paths(False):
        b = fn()
    return a, b
