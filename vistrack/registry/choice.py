"""Which model and algorithm a run tracks with, and why: one rule, said on one line.

The model is ``--model`` when given; else the one the clip's ``meta.json`` names (a synthetic clip's,
or a clip that ``vistrack demo`` wrote); else the box model when there is a start box (``--init`` or
``--init-gt``: any object); else the plate model (:data:`~vistrack.registry.catalog.SEARCH_MODEL`), which
looks for a license plate by itself. The algorithm is ``--algo`` when given, else the model's default (its
first several-target algorithm with ``--targets``).
"""

from __future__ import annotations

from dataclasses import dataclass

from .catalog import DEFAULT_MODEL, DEFAULT_MODEL_WHY, MODELS, SEARCH_MODEL, get_model_spec

__all__ = ["Choice", "choose"]


@dataclass(frozen=True)
class Choice:
    """A run's model and algorithm with the reason for each (``model_why``, ``algo_why``)."""

    model: str
    algo: str
    model_why: str
    algo_why: str

    def line(self, particles):
        """The one line ``run`` prints: ``tracking with the box model (why) and lis (why), N=100``."""
        return (f"tracking with the {self.model} model ({self.model_why}) and {self.algo} ({self.algo_why}), "
                f"N={particles}")


def choose(clip, *, model=None, algo=None, init=None, init_gt=None, targets=None):
    """The :class:`Choice` for a run on ``clip`` (:class:`~vistrack.io.clips.Clip`) with the user's
    ``--model``, ``--algo``, ``--init``, ``--init-gt`` and ``--targets`` (``None`` where not given).

    Raises ``ValueError`` when the clip's ``meta.json`` names a model this version does not have."""
    if model is not None:
        name, why = model, "--model"
    elif clip.model_name is not None:
        name = clip.model_name
        if name not in MODELS:
            raise ValueError(f"{clip.folder}: meta.json names model {name!r}, which this version cannot track")
        why = f"named in {clip.folder / 'meta.json'}"
        if name != DEFAULT_MODEL:
            why += f"; --model {DEFAULT_MODEL} tracks any object"
    elif init is not None or init_gt is not None:
        name, why = DEFAULT_MODEL, DEFAULT_MODEL_WHY
    else:
        name, why = SEARCH_MODEL, ("no --init and no model in meta.json: it looks for a license plate in the first "
                                   "30 frames; to track any other object give --init x,y,w,h")
    if algo is not None:
        return Choice(name, algo, why, "--algo")
    spec = get_model_spec(name)
    if targets is not None:
        return Choice(name, (spec.multi_algos or spec.algos)[0], why, "the default with --targets")
    return Choice(name, spec.default_algo, why, f"the {name} model's default")
