"""Process-level settings for tracking workloads."""

from __future__ import annotations

__all__ = ["keep_freed_memory", "available_memory", "prepare_worker"]

#: glibc ``mallopt`` parameters
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3


def keep_freed_memory():
    """Let glibc's ``malloc`` reuse freed memory for large arrays (a no-op where there is no glibc).

    The per-frame arrays over all particles are large (bootstrap-750 on a plate:
    7 MB per likelihood call) and short-lived. When glibc serves them by
    ``mmap`` — always, once anything sets a malloc parameter: Dask's nanny starts
    workers with ``MALLOC_TRIM_THRESHOLD_=65536`` — every call gets fresh pages
    that the kernel faults in and zeroes. A bootstrap-750 plate task took 10 s
    instead of 2.6 s in a Dask worker that way, 7 of them in the kernel, and
    even a plain process ran it at 15 ms per frame instead of 7. With this,
    arrays up to 32 MiB come from the heap, and up to 256 MiB of freed memory
    stays with the process. Called by the CLI at start and by every engine
    worker. Returns whether both settings took.
    """
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt  # the process's own symbols: glibc's where it runs on glibc
    except (OSError, AttributeError, TypeError):
        return False
    return bool(mallopt(_M_MMAP_THRESHOLD, 32 << 20)) and bool(mallopt(_M_TRIM_THRESHOLD, 256 << 20))


def available_memory():
    """Bytes of memory available to a new allocation now (``MemAvailable``; the physical
    memory where that cannot be read; ``None`` when neither can)."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        import os

        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return None


def prepare_worker():
    """Prepare an engine worker before its task: one worker per core, so keep OpenCV from starting threads
    of its own; and let ``malloc`` reuse freed memory (:func:`keep_freed_memory`)."""
    import cv2

    cv2.setNumThreads(1)
    keep_freed_memory()
