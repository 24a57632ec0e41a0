"""The algorithms by name: one :class:`FilterSpec` per ``--algo`` name, the one list of them.

A spec names the filter class, what it does, the seed section it implements and, for a name the
literature gives the same algorithm (``condensation`` for ``bootstrap``), which algorithm it is and
whose models list it under that name. Its options (defaults and help) are read from the class: its
constructor's keywords and their numpydoc entries (:func:`filter_options`). Which filter runs on
which model is not listed anywhere: a model class runs a filter when it offers every protocol the
filter needs (:meth:`~vistrack.filters.base.ParticleFilter.required`; :func:`runs_on`), and the model
registry (:mod:`vistrack.registry`) derives each model's algorithms from it.

:data:`FILTERS` is in the order of preference: a model's default algorithm is the first that runs
on it (partitioned LIS on several plates, PF-EIS-MT on landmarks, LIS on a box), and every list of a
model's algorithms keeps this order.
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Mapping
from dataclasses import dataclass

from ..core.hooks import class_offers
from ..filters.avpf import AVPF
from ..filters.basic_sir import BasicSIR
from ..filters.bootstrap import Bootstrap
from ..filters.branched_partitioned import BranchedPartitioned, BranchedPartitionedLIS
from ..filters.hs_sir import HSSIR
from ..filters.lis import LIS
from ..filters.lls import LLS
from ..filters.ls_n_ips import LSNIPS, LSNIPSNN
from ..filters.partitioned import Partitioned, PartitionedLIS
from ..filters.pf_doucet import PFDoucet
from ..filters.pf_eis import PFEIS
from ..filters.pf_eis_mt import PFEISMT
from ..filters.rb_hs_sir import RBHSSIR
from ..filters.rb_ss_hs_sir import RBSSHSSIR
from ..filters.sir import SIR

__all__ = ["Option", "FilterSpec", "FILTERS", "ALGORITHMS", "register_filter", "get_filter_spec", "make_filter",
           "runs_on", "filter_options"]


@dataclass(frozen=True)
class Option:
    """A keyword option of a filter or a model: its name, default and one-line help."""

    name: str
    default: object
    help: str


@dataclass(frozen=True)
class FilterSpec:
    """One algorithm by name.

    Attributes
    ----------
    name : str
        The ``--algo`` name.
    cls : type
        The filter class (a :class:`~vistrack.filters.base.ParticleFilter`).
    description : str
        What it does, in a line.
    seed : str
        The seed section it implements (``"001 §4.5"``: the thesis; ``"000 §3"``: the PF-EIS paper).
    alias_of : str or None
        For another name of an algorithm: that algorithm's name.
    named_in : tuple of str
        For such a name: the seeds (``"001"``, ``"000"``) whose models list it (a model's
        :attr:`~vistrack.models.spec.ModelSpec.seed`); every name is accepted wherever its algorithm runs.
    """

    name: str
    cls: type
    description: str
    seed: str
    alias_of: str | None = None
    named_in: tuple = ()

    @property
    def require(self):
        """The protocols the filter needs of a model (:meth:`~vistrack.filters.base.ParticleFilter.required`)."""
        return self.cls.required()

    @property
    def options(self):
        """Its options with defaults and help (:func:`filter_options`)."""
        return filter_options(self.cls)

    def listed_on(self, seed):
        """Whether the algorithm appears under this name in the lists of a model from ``seed``."""
        return self.alias_of is None or seed in self.named_in


def _entries(*specs):
    return {s.name: s for s in specs}


#: every algorithm by name, in the order of preference (module docstring)
FILTERS: dict[str, FilterSpec] = _entries(
    FilterSpec("partitioned-lis", PartitionedLIS, "partitioned sampling with LIS within each partition",
               "001 App. C"),
    FilterSpec("partitioned", Partitioned, "partitioned sampling: the state drawn and weighted one partition at a "
               "time", "001 App. C"),
    FilterSpec("branched-partitioned-lis", BranchedPartitionedLIS, "branched partitioned sampling with LIS within "
               "each partition", "001 App. C"),
    FilterSpec("branched-partitioned", BranchedPartitioned, "branched partitioned sampling: groups of particles "
               "take the partitions in different orders", "001 App. C"),
    FilterSpec("pf-eis-mt", PFEISMT, "PF-EIS with mode tracking of the residual directions", "000 §3"),
    FilterSpec("pf-eis", PFEIS, "efficient importance sampling: the Laplace proposal on the shape, the motion "
               "from the prior", "000 §2.2, §3.3"),
    FilterSpec("pf-doucet", PFDoucet, "the Laplace approximation of the optimal proposal over the whole state",
               "000 §1"),
    FilterSpec("pf-gordon", Bootstrap, "the bootstrap filter", "000 §1", alias_of="bootstrap", named_in=("000",)),
    FilterSpec("lis", LIS, "local importance sampling: a model-specific local proposal, properly weighted",
               "001 §4.5"),
    FilterSpec("bootstrap", Bootstrap, "predict with the dynamics K, weight by the likelihood r, resample",
               "001 §2.6"),
    FilterSpec("condensation", Bootstrap, "the bootstrap filter", "001 §2.6", alias_of="bootstrap",
               named_in=("001",)),
    FilterSpec("n-ips", Bootstrap, "the bootstrap filter", "001 §2.6", alias_of="bootstrap"),
    FilterSpec("ls-n-ips", LSNIPS, "bootstrap plus a local search toward the likelihood's peak", "001 §4.3"),
    FilterSpec("lls", LLS, "local likelihood sampling: perturb by r·g on a grid, the exact density in the weight",
               "001 §4.4"),
    FilterSpec("avpf", AVPF, "auxiliary variable particle filter", "001 App. B"),
    FilterSpec("sir", SIR, "a generic proposal π, weight r K / π", "001 §3.1"),
    FilterSpec("basic-sir", BasicSIR, "innovations from the image only, joined to histories at random",
               "001 §3.2.1"),
    FilterSpec("hs-sir", HSSIR, "history sampling: history-innovation pairs resampled by their weights",
               "001 §3.2.2"),
    FilterSpec("rb-hs-sir", RBHSSIR, "Rao-Blackwellised history sampling", "001 §3.2.3"),
    FilterSpec("rb-ss-hs-sir", RBSSHSSIR, "Rao-Blackwellised history sampling on a subspace (translation)",
               "001 §3.2.4"),
    FilterSpec("ls-n-ips-nn", LSNIPSNN, "LS-N-IPS with the model's learned (neural-network) local search",
               "001 §4.3.1"),
)


class _Classes(Mapping):
    """``name -> filter class`` over :data:`FILTERS` (a view: it follows :func:`register_filter`)."""

    def __getitem__(self, name):
        return FILTERS[name].cls

    def __iter__(self):
        return iter(FILTERS)

    def __len__(self):
        return len(FILTERS)


#: ``name -> filter class`` of every algorithm (a view of :data:`FILTERS`)
ALGORITHMS = _Classes()


def register_filter(spec):
    """Add ``spec`` to :data:`FILTERS` (replacing one of the same name, else last); returns it."""
    FILTERS[spec.name] = spec
    return spec


def get_filter_spec(name):
    """The spec of algorithm ``name``; a one-line ``ValueError`` naming the algorithms if unknown."""
    try:
        return FILTERS[name]
    except KeyError:
        raise ValueError(f"unknown algorithm {name!r}; choose from {', '.join(sorted(FILTERS))}") from None


def make_filter(name, model, **kwargs):
    """The filter registered as ``name`` on ``model`` (``kwargs``: its options, :attr:`FilterSpec.options`);
    a one-line ``ValueError`` if the name is unknown or the model lacks a part the filter needs."""
    return get_filter_spec(name).cls(model, **kwargs)


def runs_on(spec, model_class):
    """Whether ``model_class`` offers every protocol the filter of ``spec`` needs
    (:func:`~vistrack.core.hooks.class_offers`: the methods; the attributes, such as ``dim``, are
    checked when a filter is built on an instance)."""
    return all(class_offers(model_class, p) for p in spec.require)


_ENTRY = re.compile(r"^(\S[^:\n]*?)\s*:[^\n]*\n((?:[ \t]+\S[^\n]*\n?)*)", re.M)


def _parameter_help(cls):
    """``{name: first sentence}`` of the Parameters section of ``cls``'s numpydoc docstring."""
    doc = inspect.getdoc(cls) or ""
    section = re.search(r"^Parameters\n-+\n(.*?)(?=^\w[\w ]*\n-+\n|\Z)", doc, re.S | re.M)
    out = {}
    for names, text in _ENTRY.findall(section.group(1) + "\n" if section else ""):
        line = " ".join(text.split())
        for n in names.split(","):
            out.setdefault(n.strip(), line)
    return out


def filter_options(cls):
    """The keyword options of filter class ``cls`` and its bases (``resample``, ``ess_threshold``, ...):
    :class:`Option` with the constructor's default and the docstring's help, the class's own first."""
    out = {}
    for klass in cls.__mro__:
        init = vars(klass).get("__init__")
        if init is None:
            continue
        helps = _parameter_help(klass)
        for p in list(inspect.signature(init).parameters.values())[2:]:
            if p.default is not p.empty and p.name not in out:
                out[p.name] = Option(p.name, p.default, helps.get(p.name, ""))
    return tuple(out.values())
