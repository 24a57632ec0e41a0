"""The one registry of vistrack's filters and models: what runs, under which name, on what.

- :mod:`vistrack.registry.filter_specs`: the algorithms by name (:class:`~vistrack.registry.filter_specs.FilterSpec`:
  the class, the protocols it needs, its options with defaults and help);
- :mod:`.catalog`: the models by name (:class:`~vistrack.models.spec.ModelSpec`: how to build one, its
  options) and which algorithms run on each, derived from the protocols its class offers;
- :mod:`.builders`: a registered model built by name, from a box or a clip.

``run``, ``eval``, ``demo``, ``trax``, ``reproduce`` and :class:`vistrack.Tracker` take their choices and
defaults from here.
"""

from ..models.spec import ModelOption, ModelSpec
from .builders import build_model, model_from_box, read_support_points
from .catalog import (
    BASELINE,
    DEFAULT_MODEL,
    DEFAULT_PARTICLES,
    MODELS,
    SEARCH_MODEL,
    OptionError,
    algos_for,
    all_algos,
    check_algo,
    check_particle_memory,
    clip_model,
    default_comparison,
    derived_algos,
    get_model_spec,
    model_params,
    register,
)
from .filter_specs import ALGORITHMS, FILTERS, FilterSpec, Option, get_filter_spec, make_filter, register_filter

__all__ = ["FILTERS", "ALGORITHMS", "FilterSpec", "Option", "get_filter_spec", "make_filter", "register_filter",
           "ModelSpec", "ModelOption", "MODELS", "DEFAULT_MODEL", "SEARCH_MODEL", "DEFAULT_PARTICLES", "BASELINE",
           "OptionError", "default_comparison", "check_particle_memory", "register", "get_model_spec", "algos_for",
           "all_algos", "check_algo", "clip_model", "derived_algos", "model_params", "build_model", "model_from_box",
           "read_support_points"]
