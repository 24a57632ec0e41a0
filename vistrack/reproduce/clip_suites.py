"""The synthetic clip suites the contour, history-sampling and plate experiments run on."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..data_synth.clip_sizes import check_suite_disk
from ..data_synth.contour_clip import make_contour_clip
from ..data_synth.plate_clip import make_plate_clip
from ..data_synth.scene import SuiteNames, prepare_suite
from ..evaluation.experiment import check_grid_size

__all__ = ["Suite", "SUITES", "clip_suite", "experiment_clips"]


@dataclass(frozen=True)
class Suite:
    """An experiment's clip suite: the folder of its clips by default, their names' prefix, the clip maker and
    its options, and what ``--make``, ``--frames`` and ``--size`` make by default."""

    folder: str
    prefix: str
    maker: Callable
    options: dict = field(default_factory=dict)
    make: int = 10
    frames: int = 300
    size: tuple = (320, 240)


#: per experiment: its clip suite
SUITES = {
    "contour": Suite("contour-clips", "contour", make_contour_clip, {"clutter": "high", "distractor": True}),
    "hs-sir": Suite("hs-sir-clips", "contour-color", make_contour_clip,
                    {"clutter": "high", "distractor": True, "color": True}, frames=150, size=(240, 180)),
    "plate": Suite("plate-clips", "plate", make_plate_clip, size=(640, 480)),
    "plates": Suite("plate-overlap-clips", "plate-overlap", make_plate_clip, {"overlap": True, "cars": 6},
                    size=(640, 480)),
}


def experiment_clips(experiment, clips_dir, make, frames, size, progress=None, grid=None):
    """The clips of ``experiment`` (:data:`SUITES`) in ``clips_dir`` (``None``: its default folder), made
    there first when it holds none (:func:`clip_suite`); ``grid``: ``(entries, runs)``, the task grid of
    ``make`` clips of ``frames`` frames checked against memory before anything is made
    (:func:`~vistrack.evaluation.experiment.check_grid_size`: a one-line
    :class:`~vistrack.system.resources.TooLarge`)."""
    if grid is not None:
        check_grid_size(make, *grid, frames)
    suite = SUITES[experiment]
    return clip_suite(clips_dir or suite.folder, make, frames, size, suite.maker, suite.prefix, progress=progress,
                      **suite.options)


def clip_suite(base, make, frames, size, maker, prefix, progress=None, **kw):
    """The clip folders in ``base`` (those with a ``groundtruth.csv``; hidden ones, such as a clip
    being written, are skipped), sorted.

    When ``base`` holds none, ``make`` clips of seeds ``1..make`` are generated there first (a
    ``base`` that holds other files or folders is refused with a one-line ``ValueError``: the clips
    would be mixed with them, :func:`~vistrack.data_synth.scene.prepare_suite`), each by
    ``maker(base / f"{prefix}-{seed:02d}", frames=frames, size=size, seed=seed, progress=progress, **kw)``
    (e.g. :func:`vistrack.data_synth.contour_clip.make_contour_clip`).

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
        prepare_suite(base, SuiteNames(prefix, 1, make))
        base.mkdir(parents=True, exist_ok=True)
        for s in range(1, make + 1):
            maker(base / f"{prefix}-{s:02d}", frames=frames, size=size, seed=s, progress=progress, **kw)
    return found()
