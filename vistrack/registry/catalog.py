"""The models by name, and which algorithms run on each: read by ``run``, ``eval``, ``demo``,
``trax`` and ``vistrack.Tracker``.

An entry is a :class:`~vistrack.models.spec.ModelSpec`: the model's name, a one-line description,
how to build it (from a box in the first frame and/or from a clip), its options and the class of
the models it builds. The algorithms that run on it are derived, not listed: every algorithm of the
filter registry (:data:`~vistrack.registry.filter_specs.FILTERS`) whose protocols the class offers
(:func:`~vistrack.registry.filter_specs.runs_on`), in that registry's order, so the first is the model's
default. Adding a model is its module plus one :func:`register` call; each built-in model's entry is
its package's ``builder.SPEC`` (:mod:`vistrack.models.box.builder`, :mod:`~vistrack.models.contour.builder`,
:mod:`~vistrack.models.plate.builder`, :mod:`~vistrack.models.landmarks.builder`). The plate family's layouts
(:data:`LAYOUTS`) are listed here too: the choices of every ``--layout``.
"""

from __future__ import annotations

import dataclasses

from ..models.box.builder import SPEC as BOX
from ..models.contour.builder import SPEC as CONTOUR
from ..models.landmarks.builder import SPEC as LANDMARKS
from ..models.plate.builder import SPEC as PLATE
from ..models.plate.layout import LAYOUTS  # the plate layouts by name: --layout's choices, listed here
from ..models.spec import ModelSpec
from ..system.resources import check_memory
from .filter_specs import FILTERS, get_filter_spec, runs_on
from .option_types import check_model_options

__all__ = ["ModelSpec", "MODELS", "LAYOUTS", "DEFAULT_MODEL", "SEARCH_MODEL", "DEFAULT_PARTICLES", "REFERENCE_ALGO",
           "OptionError", "default_comparison", "check_particle_memory", "register", "get_model_spec", "algos_for",
           "all_algos", "check_algo", "clip_model", "model_params", "derived_algos", "targets_model",
           "run_option"]

#: the model ``run``, ``eval``, ``demo``, ``trax`` and ``vistrack.Tracker`` use when neither the user
#: nor the clip (its ``meta.json``) names one: any object, from a box
DEFAULT_MODEL = "box"
#: the model ``run`` uses on a video when neither the user (no model, no box) nor the clip names one:
#: the plate model, which finds plates by itself
SEARCH_MODEL = "plate"
#: the number of particles ``N`` of ``run``, ``trax`` and ``vistrack.Tracker`` when none is given
DEFAULT_PARTICLES = 100
#: the filter a comparison measures the others against by default (``eval --algos``): the bootstrap
#: filter (thesis 001 §2.6)
REFERENCE_ALGO = "bootstrap"


class OptionError(ValueError):
    """An algorithm or option that does not apply to the model (on the command line, a usage error)."""


def derived_algos(model_class, seed="001"):
    """The algorithms that run on ``model_class`` (:func:`~vistrack.registry.filter_specs.runs_on`), in
    the filter registry's order, each under the names the models of ``seed`` use."""
    return tuple(n for n, f in FILTERS.items() if f.listed_on(seed) and runs_on(f, model_class))


def _checked(spec, algos, model_class):
    """``algos`` as given for ``spec``, each checked to run on ``model_class`` (when known)."""
    bad = [a for a in algos if model_class is not None and (a not in FILTERS or not runs_on(FILTERS[a], model_class))]
    if bad:
        raise ValueError(f"model {spec.name!r}: {', '.join(bad)} does not run on {model_class.__name__}")
    return tuple(algos)


def register(spec):
    """Add ``spec`` to :data:`MODELS` (replacing one of the same name), its algorithms derived from its
    classes where it does not list them (:class:`~vistrack.models.spec.ModelSpec`); returns the entry."""
    cls = spec.model_class
    algos = derived_algos(cls, spec.seed) if spec.algos is None else _checked(spec, spec.algos, cls)
    multi = spec.multi_algos
    multi = (derived_algos(spec.targets_class, spec.seed) if spec.targets_class is not None else ()) \
        if multi is None else _checked(spec, multi, spec.targets_class)
    if not algos:
        raise ValueError(f"model {spec.name!r}: no algorithm runs on it (give its model_class, whose protocols "
                         "decide, or its algos)")
    entry = dataclasses.replace(spec, algos=algos, multi_algos=multi)
    MODELS[spec.name] = entry
    return entry


#: the registered models by name: the built-in ones (each package's ``builder.SPEC``), then any added
#: by :func:`register`
MODELS: dict[str, ModelSpec] = {}
for _spec in (BOX, CONTOUR, PLATE, LANDMARKS):
    register(_spec)


def get_model_spec(name):
    """The entry of model ``name``; a clear ``ValueError`` if unknown."""
    try:
        return MODELS[name]
    except KeyError:
        raise ValueError(f"unknown model {name!r}; choose from {', '.join(MODELS)}") from None


def algos_for(name, targets=False):
    """The algorithms that run on model ``name`` (with ``targets``: on its several-target form), the
    default first."""
    spec = get_model_spec(name)
    return spec.multi_algos if targets else spec.algos


def all_algos():
    """Every algorithm some registered model runs (single- and several-target), in registration order:
    the choices of ``run --algo`` and ``eval --algos``."""
    return tuple(dict.fromkeys(a for spec in MODELS.values() for a in (*spec.algos, *spec.multi_algos)))


def check_algo(name, algo, targets=False, who=None):
    """Raise :class:`OptionError` (one line naming those that do) unless ``algo`` runs on model ``name`` (with
    ``targets``: on its several-target form); ``who`` names the algorithm in the message (default
    ``algo``)."""
    spec, allowed = get_model_spec(name), algos_for(name, targets)
    if algo in allowed:
        return
    hint = f"; partitioned sampling tracks several {name}s: add --targets K" \
        if not targets and algo in spec.multi_algos else ""
    raise OptionError(f"{who or algo} does not run on the {name} model{' with --targets' if targets else ''}; "
                     f"choose from {', '.join(allowed)}{hint}")


def default_comparison():
    """The algorithms ``eval`` compares by default: the default model's default, then :data:`REFERENCE_ALGO`."""
    return (get_model_spec(DEFAULT_MODEL).default_algo, REFERENCE_ALGO)


def targets_model(name=None):
    """The model that tracks several targets at once (``run``/``eval --targets``): ``name``, else the first
    registered model with a several-target form (:attr:`~vistrack.models.spec.ModelSpec.targets_class`)."""
    return name or next(n for n, s in MODELS.items() if s.targets_class is not None)


def check_particle_memory(n, bytes_per_particle, algo="", share=0.5, available=None, targets=1):
    """Raise :class:`~vistrack.system.resources.TooLarge` (one line) when ``n`` particles (of ``targets`` plate
    slots each) would need more than ``share`` of the available memory per frame: the model's
    ``bytes_per_particle`` (the peak working memory of one step, measured with tracemalloc: about 23 KB per
    particle for the box model, 16–39 KB for the contour, 37 KB for the plate) times the filter ``algo``'s
    ``memory_factor`` (8 for LLS). Returns the estimate in bytes."""
    factor = FILTERS[algo].cls.memory_factor if algo in FILTERS else 1
    each = int(bytes_per_particle) * factor * int(targets)
    return check_memory(int(n) * each, f"{n} particles{f' of {targets} targets' if targets > 1 else ''} need",
                        lambda room: f"use at most {int(room // each)}" + (" particles" if targets > 1 else ""),
                        share, available, per=" per frame")


def clip_model(named=None):
    """The model a clip is tracked with when no ``--model`` is given: the one its ``meta.json`` names
    (``named``), else :data:`DEFAULT_MODEL`."""
    return named or DEFAULT_MODEL


def run_option(flag):
    """The model option that ``run``'s ``flag`` sets (:class:`~vistrack.models.spec.ModelOption`: its default
    and help), of the first model that takes it; ``None`` where none does."""
    return next((s.option(flag) for s in MODELS.values() if s.option(flag) is not None), None)


def model_params(name, flags, algo=None):
    """The builder parameters of model ``name`` that ``run``'s ``flags`` (``{flag: value}``; ``None``:
    not given) set (:attr:`~vistrack.models.spec.ModelSpec.options`); a one-line :class:`OptionError` for a
    flag the model has no option for (naming the models that do) or one not for ``algo``."""
    spec, params = get_model_spec(name), {}
    for flag, value in flags.items():
        if value is None:
            continue
        opt = spec.option(flag)
        if opt is None or (opt.needs is not None and opt.needs not in get_filter_spec(algo).require):
            takes = [s for s in MODELS.values() if s.option(flag)]
            algos = [a for s in takes if s.option(flag).needs is not None for a in s.algos
                     if s.option(flag).needs in FILTERS[a].require]
            where = " and ".join(s.name for s in takes) + (" models" if len(takes) > 1 else " model")
            raise OptionError(f"{flag} is for " + (f"--algo {', '.join(algos)} on the " if algos else "the ") + where)
        params[opt.name] = value if opt.value is None else opt.value
    check_model_options(spec, params)  # the check vistrack.Tracker makes of the same options
    return params
