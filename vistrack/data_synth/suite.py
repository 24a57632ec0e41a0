"""``vistrack synth-suite``: a folder of clips of one kind for ``vistrack eval``, each with its kind's
defaults (contour: high clutter and a distractor; plate: 3 cars, the jp layout; landmarks: K = 5)."""

from __future__ import annotations

from pathlib import Path

from .clip_sizes import check_suite_disk
from .contour_clip import make_contour_clip
from .landmark_clip import make_landmark_clip
from .plate_clip import make_plate_clip
from .scene import SuiteNames, prepare_suite

__all__ = ["SUITES", "suite_names", "check_suite", "make_suite"]

#: per kind: the clip maker, its default frames and frame size
SUITES = {"contour": (make_contour_clip, 300, (320, 240)), "plate": (make_plate_clip, 300, (640, 480)),
          "landmarks": (make_landmark_clip, 200, (640, 480))}


def suite_names(kind, clips, seed):
    """The clips' folder names: ``<kind>-<seed>`` for the seeds ``seed .. seed + clips - 1``
    (:class:`~vistrack.data_synth.scene.SuiteNames`: a range, named as asked for)."""
    return SuiteNames(kind, seed, clips)


def check_suite(out, kind, clips, frames=None, size=None):
    """Raise :class:`~vistrack.system.resources.TooLarge` (one line, before anything is made) when ``clips``
    clips of ``kind`` (``frames`` and ``size`` default to the kind's) would not fit on the disk holding
    ``out`` (:func:`~vistrack.data_synth.clip_sizes.check_suite_disk`)."""
    _, frames_default, size_default = SUITES[kind]
    check_suite_disk(out, clips, frames or frames_default, size or size_default)


def make_suite(out, kind, clips=10, seed=1, frames=None, size=None, progress=None):
    """``clips`` clips of ``kind`` (:data:`SUITES`) into the folder ``out``, from seeds ``seed``, ``seed +
    1``, ...; ``frames`` and ``size`` default to the kind's. Their size on disk is checked first
    (:func:`check_suite`); ``out`` then holds this suite alone
    (:func:`~vistrack.data_synth.scene.prepare_suite`: an earlier suite's other clips go; a folder holding
    anything else is a ``ValueError``). ``progress(k)`` as frames are written. Returns the clip folders."""
    check_suite(out, kind, clips, frames, size)
    make, frames_default, size_default = SUITES[kind]
    out, names = Path(out), suite_names(kind, clips, seed)
    prepare_suite(out, names)
    for s in range(seed, seed + clips):
        make(out / names.name(s), frames=frames or frames_default, size=size or size_default, seed=s,
             progress=progress)
    return [out / n for n in names]
