"""Particle filters, one module per algorithm, all with ``step(particles, obs, rng)``.

:mod:`vistrack.registry.filter_specs` names them (``FILTERS``, ``make_filter``); aliases follow the literature's
names.
"""

from .avpf import AVPF
from .base import ParticleFilter, filter_steps
from .basic_sir import BasicSIR
from .bootstrap import Bootstrap
from .branched_partitioned import BranchedPartitioned, BranchedPartitionedLIS
from .history import HistorySampling
from .hs_sir import HSSIR
from .lis import LIS, GaussMixtureProposal
from .lls import LLS, Window
from .ls_n_ips import LSNIPS, LSNIPSNN
from .partitioned import Partitioned, PartitionedLIS
from .pf_doucet import PFDoucet
from .pf_eis import PFEIS
from .pf_eis_mt import PFEISMT
from .rb_hs_sir import RBHSSIR
from .rb_ss_hs_sir import RBSSHSSIR
from .sir import SIR

__all__ = [
    "ParticleFilter",
    "filter_steps",
    "Bootstrap",
    "SIR",
    "HistorySampling",
    "BasicSIR",
    "HSSIR",
    "RBHSSIR",
    "RBSSHSSIR",
    "AVPF",
    "LLS",
    "Window",
    "LIS",
    "LSNIPS",
    "LSNIPSNN",
    "PFDoucet",
    "PFEIS",
    "PFEISMT",
    "GaussMixtureProposal",
    "Partitioned",
    "PartitionedLIS",
    "BranchedPartitioned",
    "BranchedPartitionedLIS",
]
