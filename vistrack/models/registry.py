"""The model registry: what each video model offers, read by ``run``, ``eval`` and ``vistrack.Tracker``.

An entry names the model, the algorithms that run on it (the default first), a one-line
description and how to build it: from a box in the first frame (``from_box``) and/or from a
clip (``from_clip``): a :class:`~vistrack.models.spec.ModelSpec`. Adding a model is its module plus
one :func:`register` call; each built-in model's entry is its package's ``builder.SPEC``
(:mod:`vistrack.models.box.builder`, :mod:`~vistrack.models.contour.builder`,
:mod:`~vistrack.models.plate.builder`, :mod:`~vistrack.models.landmarks.builder`).
"""

from __future__ import annotations

from .box.builder import SPEC as _BOX
from .contour.builder import SPEC as _CONTOUR
from .landmarks.builder import SPEC as _LANDMARKS
from .plate.builder import SPEC as _PLATE
from .spec import ModelSpec

__all__ = ["ModelSpec", "MODELS", "DEFAULT_MODEL", "register", "get_model_spec", "all_algos", "clip_model"]


#: the registered models by name: the built-in ones (each package's ``builder.SPEC``), then any
#: added by :func:`register`
MODELS: dict[str, ModelSpec] = {s.name: s for s in (_BOX, _CONTOUR, _PLATE, _LANDMARKS)}

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
