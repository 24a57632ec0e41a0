"""Process-level settings for tracking workloads, and the checks of the sizes a user gives
(particles, the task grid, clips, targets, steps) against memory and disk before any work starts:
a size too large for the machine is one :class:`TooLarge` line, never a process killed for memory."""

from __future__ import annotations

__all__ = ["keep_freed_memory", "available_memory", "prepare_worker", "TooLarge", "check_memory", "check_disk",
           "fmt_bytes", "WORKER_BYTES", "worker_count"]


class TooLarge(ValueError):
    """A size the user gave needs more memory or disk than the machine has (one line: what, how
    much, how much there is, and the largest that fits)."""

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


def fmt_bytes(n):
    """``n`` bytes as ``"1.5 GiB"`` (or MiB, TiB)."""
    for unit, k in (("TiB", 40), ("GiB", 30), ("MiB", 20)):
        if n >= 2**k or unit == "MiB":
            return f"{n / 2**k:.1f} {unit}"


def check_memory(need, what, most_of, share=0.5, available=None, per=""):
    """Raise :class:`TooLarge` when ``need`` bytes exceed ``share`` of the available memory:
    "``what`` about X GiB``per``, more than half of the Y GiB available; ``most_of(bytes)``"
    (``most_of`` says what fits in the bytes there are, e.g. "use at most 2097"). Returns ``need``."""
    avail = available_memory() if available is None else available
    if avail is not None and need > share * avail:
        raise TooLarge(f"{what} about {fmt_bytes(need)}{per}, more than half of the {fmt_bytes(avail)} available; "
                       f"{most_of(share * avail)}")
    return need


def check_disk(need, folder, what, most_of):
    """Raise :class:`TooLarge` when ``need`` bytes exceed the free space of the filesystem holding
    ``folder`` (its nearest existing parent): "``what`` about X GiB, more than the Y GiB free
    on FOLDER; ``most_of(bytes)``". Returns ``need``."""
    import shutil
    from pathlib import Path

    p = Path(folder).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        free = shutil.disk_usage(p).free
    except OSError:
        return need
    if need > free:
        raise TooLarge(f"{what} about {fmt_bytes(need)}, more than the {fmt_bytes(free)} free on {p}; "
                       f"{most_of(free)}")
    return need


#: memory a worker process of the batch engine holds before its task: vistrack, numpy, OpenCV, numba and
#: Dask loaded (about 125 MB measured; rounded up)
WORKER_BYTES = 160 << 20


def worker_count(requested, tasks, available=None, cores=None):
    """``(n, note)``: how many worker processes to start for ``tasks`` tasks when ``requested`` were asked
    for (0: one per core): no more than two per core of the machine (a process more keeps a core busy
    while another waits on its disk), one per task, and the processes half the available memory holds
    (:data:`WORKER_BYTES` each; at least one). ``note`` is one line saying what capped a number the
    user gave (``None`` when nothing did, or none was given)."""
    import os

    cores = cores or os.cpu_count() or 1
    avail = available_memory() if available is None else available
    fit = max(1, int(0.5 * avail // WORKER_BYTES)) if avail is not None else cores
    limits = [(2 * cores, f"two per core of the machine's {cores} cores"),
              (max(1, int(tasks)), f"{tasks} task(s) to run"),
              (fit, f"the {fit} worker processes half the {fmt_bytes(avail or 0)} of memory available holds")]
    n = min(int(requested) or cores, *(k for k, _ in limits))
    if not requested or n >= int(requested):
        return n, None
    why = next(w for k, w in limits if k == n)
    return n, f"note: --workers {requested} capped at {n} ({why})"
