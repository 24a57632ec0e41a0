"""The model registry: what each video model offers, read by ``run``, ``eval`` and ``vistrack.Tracker``.

An entry names the model, the algorithms that run on it (the default first), a one-line
description and how to build it: from a box in the first frame (``from_box``) and/or from a
clip (``from_clip``). Adding a model is its module plus one :func:`register` call; the
built-in models are registered in :mod:`vistrack.builders`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

__all__ = ["ModelSpec", "MODELS", "DEFAULT_MODEL", "register", "get_model_spec", "all_algos", "clip_model"]


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
        How ``eval`` decides a frame is lost (:func:`vistrack.metrics.lost_frames`).
    bytes_per_particle : int
        Peak working memory of one step per particle (bytes; measured, rounded up), for
        :func:`vistrack.runtime.check_particle_memory`.
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


MODELS: dict[str, ModelSpec] = {}

#: the model ``run``, ``eval``, ``demo`` and ``vistrack.Tracker`` use when neither the user nor the
#: clip (its ``meta.json``) names one: any object, from a box
DEFAULT_MODEL = "box"


def register(spec):
    """Add ``spec`` to :data:`MODELS` (replacing one of the same name); returns it."""
    MODELS[spec.name] = spec
    return spec


def get_model_spec(name):
    """The spec of model ``name``; a clear ``ValueError`` if unknown."""
    try:
        return MODELS[name]
    except KeyError:
        raise ValueError(f"unknown model {name!r}; choose from {', '.join(MODELS)}") from None


def all_algos():
    """Every algorithm some registered model runs (single- and several-target), in registration order:
    the choices of ``run --algo`` and ``eval --algos``."""
    return tuple(dict.fromkeys(a for spec in MODELS.values() for a in (*spec.algos, *spec.multi_algos)))


def clip_model(named=None):
    """The model a clip is tracked with when no ``--model`` is given: the one its ``meta.json`` names
    (``named``), else :data:`DEFAULT_MODEL`."""
    return named or DEFAULT_MODEL
