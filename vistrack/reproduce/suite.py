"""The synthetic clip suites the contour and plate experiments run on."""

from __future__ import annotations

from pathlib import Path

from ..data_synth.render import check_suite_disk

__all__ = ["clip_suite"]


def clip_suite(base, make, frames, size, maker, prefix, progress=None, **kw):
    """The clip folders in ``base`` (those with a ``groundtruth.csv``; hidden ones, such as a clip
    being written, are skipped), sorted.

    When ``base`` holds none, ``make`` clips of seeds ``1..make`` are generated there first,
    each by ``maker(base / f"{prefix}-{seed:02d}", frames=frames, size=size, seed=seed,
    progress=progress, **kw)`` (e.g. :func:`vistrack.data_synth.contour.make_contour_clip`).

    Parameters
    ----------
    base : path-like
    make, frames : int
        Clips to make, frames per clip.
    size : tuple of int
        ``(width, height)`` of made clips.
    maker : callable
    prefix : str
    progress : callable or None
        Called with the number of frames written, as they are.
    """
    base = Path(base)

    def found():
        return sorted(p for p in base.glob("[!.]*") if (p / "groundtruth.csv").is_file()) if base.is_dir() else []

    if not found():
        check_suite_disk(base, make, frames, size)
        base.mkdir(parents=True, exist_ok=True)
        for s in range(1, make + 1):
            maker(base / f"{prefix}-{s:02d}", frames=frames, size=size, seed=s, progress=progress, **kw)
    return found()
