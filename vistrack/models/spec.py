"""What a video model offers ``run``, ``eval`` and ``vistrack.Tracker``: its registry entry's form.

Each model package's ``builder`` module defines one :class:`ModelSpec` (``SPEC``);
:mod:`vistrack.models.registry` holds them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

__all__ = ["ModelSpec", "THESIS_ALGOS", "HISTORY_ALGOS"]

#: the thesis's filters (001 §4) that run on any model with a transition kernel and a local proposal
THESIS_ALGOS = ("lis", "bootstrap", "condensation", "ls-n-ips", "lls", "avpf")
#: SIR and the history-sampling family (§3.2) with the colour-blob proposal: models with an innovation split
HISTORY_ALGOS = ("sir", "basic-sir", "hs-sir", "rb-hs-sir", "rb-ss-hs-sir")


@dataclass(frozen=True)
class ModelSpec:
    """One registered video model.

    Attributes
    ----------
    name : str
    algos : tuple of str
        Algorithms that run on it, the default first.
    description : str
    box_init : bool
        Whether it can start from an ``(x, y, w, h)`` box.
    from_box : callable or None
        ``from_box(frame, box, **params) -> model``: started from ``box`` ``(x, y, w, h)`` in the
        first ``frame`` (BGR or grey array); what ``vistrack.Tracker`` and ``run --init`` call.
    from_clip : callable or None
        ``from_clip(clip, *, init, init_gt, template, **params) -> model`` for ``run`` and
        ``eval`` on a clip; ``None``: ``from_box`` at the start box (``init`` or the first
        ground-truth row) in the clip's first frame.
    lost_rule : {"centre", "plate"}
        How ``eval`` decides a frame is lost (:func:`vistrack.core.metrics.lost_frames`).
    bytes_per_particle : int
        Peak working memory of one step per particle (bytes; measured, rounded up), for
        :func:`vistrack.core.runtime.check_particle_memory`.
    """

    name: str
    algos: tuple
    description: str
    box_init: bool = True
    from_box: Callable | None = None
    from_clip: Callable | None = None
    lost_rule: str = "centre"
    bytes_per_particle: int = 64_000
    #: algorithms that track several targets at once (``run``/``eval --targets K``), the default first
    multi_algos: tuple = ()

    @property
    def default_algo(self):
        """The default algorithm: the first of :attr:`algos`."""
        return self.algos[0]
