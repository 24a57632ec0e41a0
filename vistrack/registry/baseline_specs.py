"""The comparison trackers by name: the trackers ``eval --algos`` runs beside the particle filters
(:mod:`vistrack.baselines`), each a :class:`BaselineSpec`.

Adding a comparison tracker is its module in :mod:`vistrack.baselines` (a function that tracks a clip's
frames from a box) and one entry here: ``eval``, its task grid, its reports and ``--help`` read
everything they need of it from the entry.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Callable

from ..baselines.opencv import check_opencv, track_opencv

__all__ = ["BaselineSpec", "BASELINES", "register_baseline", "get_baseline_spec", "is_baseline", "check_baseline",
           "runs_once"]


@dataclass(frozen=True)
class BaselineSpec:
    """One comparison tracker by name.

    Attributes
    ----------
    name : str
        The ``eval --algos`` name (``opencv-mil``, ...).
    track : callable
        ``track(box, frames) -> (boxes (F, 4), ms (F,), index (F,))``: one run from ``box`` ``(x, y, w, h)``
        on the first of ``frames`` (``(index, frame)`` pairs): ``x, y, w, h`` per frame (NaN where it
        reported nothing), the milliseconds of each call, the frames' indices
        (:func:`~vistrack.baselines.opencv.track_opencv`).
    description : str
        What it is, in a line.
    randomised : bool
        Whether its result varies from run to run although no seed reaches it (OpenCV's MIL samples
        at random inside OpenCV): it then runs ``eval --runs`` times like the particle filters, else once.
    by : str
        Whose randomness it is, for the reports (``randomised inside OpenCV, not seeded``).
    needs : str
        What it needs beyond vistrack's dependencies, for ``--help`` (empty: nothing).
    check : callable or None
        ``check()`` raises ``ValueError`` (one line) where this installation cannot run it.
    """

    name: str
    track: Callable
    description: str = ""
    randomised: bool = False
    by: str = ""
    needs: str = ""
    check: Callable | None = None

    @property
    def runs_note(self):
        """How its runs are counted, for the reports' runs line: ``randomised inside OpenCV, not seeded``
        or ``deterministic``."""
        return f"randomised inside {self.by}, not seeded" if self.randomised else "deterministic"

    @property
    def help(self):
        """``opencv-kcf (needs opencv-contrib-python-headless)``: its name with what it needs, for ``--help``."""
        return self.name + (f" (needs {self.needs})" if self.needs else "")


def _opencv(name, ctor, description, randomised=False, needs=""):
    """The entry of OpenCV's tracker made by ``cv2.<ctor>`` (or ``cv2.legacy.<ctor>``)."""
    return BaselineSpec(name, partial(track_opencv, ctor), description, randomised, "OpenCV", needs,
                        partial(check_opencv, name, ctor, needs))


#: every comparison tracker by name, in the order ``--help`` lists them
BASELINES: dict[str, BaselineSpec] = {s.name: s for s in (
    _opencv("opencv-mil", "TrackerMIL_create", "OpenCV's MIL (multiple-instance learning)", randomised=True),
    _opencv("opencv-kcf", "TrackerKCF_create", "OpenCV's KCF (kernelised correlation filter)",
            needs="opencv-contrib-python-headless"),
    _opencv("opencv-csrt", "TrackerCSRT_create", "OpenCV's CSRT (discriminative correlation filter with channel "
            "and spatial reliability)", needs="opencv-contrib-python-headless"),
)}


def register_baseline(spec):
    """Add ``spec`` to :data:`BASELINES` (replacing one of the same name, else last); returns it."""
    BASELINES[spec.name] = spec
    return spec


def get_baseline_spec(name):
    """The entry of comparison tracker ``name``; a one-line ``ValueError`` naming them if unknown."""
    try:
        return BASELINES[name]
    except KeyError:
        raise ValueError(f"unknown comparison tracker {name!r}; choose from {', '.join(BASELINES)}") from None


def is_baseline(name):
    """Whether ``name`` is a comparison tracker (not a particle filter)."""
    return name in BASELINES


def runs_once(name):
    """Whether ``name`` runs once per clip whatever ``eval --runs``: a comparison tracker whose result does not
    vary from run to run (no seed reaches it; :attr:`BaselineSpec.randomised`)."""
    return is_baseline(name) and not BASELINES[name].randomised


def check_baseline(name):
    """Raise ``ValueError`` (one line) when comparison tracker ``name`` is unknown or cannot run here
    (:attr:`BaselineSpec.check`)."""
    spec = get_baseline_spec(name)
    if spec.check is not None:
        spec.check()
