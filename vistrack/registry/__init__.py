"""The one registry of vistrack: what runs, under which name, on what.

- :mod:`vistrack.registry.filter_specs`: the algorithms by name (:class:`~vistrack.registry.filter_specs.FilterSpec`:
  the class, the protocols it needs, its options with defaults and help);
- :mod:`.catalog`: the models by name (:class:`~vistrack.models.spec.ModelSpec`: how to build one, its
  options) and which algorithms run on each, derived from the protocols its class offers; the plate layouts;
- :mod:`.baseline_specs`: the comparison trackers by name (:class:`~vistrack.registry.baseline_specs.BaselineSpec`:
  how to run one, whether it is randomised, what it needs);
- :mod:`.comparisons`: what the seeds' experiments and the demo compare;
- :mod:`.builders`: a registered model built by name, from a box or a clip; :mod:`.choice`: which model and
  algorithm a run tracks with, and why.

``run``, ``eval``, ``demo``, ``trax``, ``reproduce`` and :class:`vistrack.Tracker` take their choices and
defaults from here.
"""

from ..models.spec import ModelOption, ModelSpec
from .baseline_specs import (
    BASELINES,
    BaselineSpec,
    check_baseline,
    get_baseline_spec,
    is_baseline,
    register_baseline,
    runs_once,
)
from .builders import build_model, model_from_box, read_support_points
from .catalog import (
    DEFAULT_MODEL,
    DEFAULT_PARTICLES,
    LAYOUTS,
    MODELS,
    REFERENCE_ALGO,
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
    run_option,
    targets_model,
)
from .filter_specs import ALGORITHMS, FILTERS, FilterSpec, Option, get_filter_spec, make_filter, register_filter

__all__ = ["FILTERS", "ALGORITHMS", "FilterSpec", "Option", "get_filter_spec", "make_filter", "register_filter",
           "ModelSpec", "ModelOption", "MODELS", "LAYOUTS", "DEFAULT_MODEL", "SEARCH_MODEL", "DEFAULT_PARTICLES",
           "REFERENCE_ALGO", "OptionError", "default_comparison", "check_particle_memory", "register",
           "get_model_spec", "algos_for", "all_algos", "check_algo", "clip_model", "derived_algos", "model_params",
           "targets_model", "run_option", "build_model", "model_from_box", "read_support_points",
           "BASELINES", "BaselineSpec", "register_baseline", "get_baseline_spec", "is_baseline", "check_baseline",
           "runs_once"]
