"""``vistrack synth-suite``: a folder of clips of one kind for ``vistrack eval``, each with its kind's
defaults (contour: high clutter and a distractor; plate: 3 cars, the jp layout; landmarks: K = 5)."""

from __future__ import annotations

from pathlib import Path

from .contour import make_contour_clip
from .landmarks import make_landmark_clip
from .plate import make_plate_clip
from .render import prepare_suite

__all__ = ["SUITES", "suite_names", "make_suite"]

#: per kind: the clip maker, its default frames and frame size
SUITES = {"contour": (make_contour_clip, 300, (320, 240)), "plate": (make_plate_clip, 300, (640, 480)),
          "landmarks": (make_landmark_clip, 200, (640, 480))}


def suite_names(kind, clips, seed):
    """The clips' folder names: ``<kind>-<seed>`` for the seeds ``seed .. seed + clips - 1``."""
    return [f"{kind}-{s:02d}" for s in range(seed, seed + clips)]


def make_suite(out, kind, clips, seed, frames=None, size=None, progress=None):
    """``clips`` clips of ``kind`` (:data:`SUITES`) into the folder ``out``, from seeds ``seed``, ``seed +
    1``, ...; ``frames`` and ``size`` default to the kind's. ``out`` then holds this suite alone
    (:func:`~vistrack.data_synth.render.prepare_suite`: an earlier suite's other clips go; a folder holding
    anything else is a ``ValueError``). ``progress(k)`` as frames are written. Returns the clip folders."""
    make, frames_default, size_default = SUITES[kind]
    out, names = Path(out), suite_names(kind, clips, seed)
    prepare_suite(out, names)
    for s, name in zip(range(seed, seed + clips), names):
        make(out / name, frames=frames or frames_default, size=size or size_default, seed=s, progress=progress)
    return [out / n for n in names]
