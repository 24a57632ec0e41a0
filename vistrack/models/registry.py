"""The model registry: what each video model offers, read by ``run``, ``eval`` and ``vistrack.Tracker``.

An entry names the model, the algorithms that run on it (the default first) and a one-line
description. Adding a model is its module plus one :func:`register` call.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ModelSpec", "MODELS", "register", "get_model_spec"]


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
    """

    name: str
    algos: tuple
    description: str
    box_init: bool = True

    @property
    def default_algo(self):
        return self.algos[0]


MODELS: dict[str, ModelSpec] = {}


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


_THESIS = ("lis", "bootstrap", "condensation", "ls-n-ips", "lls", "avpf")
register(ModelSpec("box", _THESIS, "any object from a box: colour + template appearance learned from the first frame"))
register(ModelSpec("contour", _THESIS, "B-spline contour on edges (thesis 001 §1.3.1)"))
register(ModelSpec("plate", ("lis", "bootstrap", "condensation", "lls", "avpf"),
                   "license-plate template (thesis 001 §1.3.2); acquires plates without a box"))
register(ModelSpec("landmarks", ("pf-eis-mt", "pf-eis", "pf-doucet", "pf-gordon", "bootstrap"),
                   "landmark shape (seed 000 §3)", box_init=False))
