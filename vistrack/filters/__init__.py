"""Particle filters, one module per algorithm, all with ``step(particles, obs, rng)``.

See the algorithm table of README.md and docs/architecture.md; aliases follow the literature's names.
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
    "ALGORITHMS",
    "make_filter",
]

ALGORITHMS = {
    "bootstrap": Bootstrap,
    "condensation": Bootstrap,
    "n-ips": Bootstrap,
    "pf-gordon": Bootstrap,
    "sir": SIR,
    "basic-sir": BasicSIR,
    "hs-sir": HSSIR,
    "rb-hs-sir": RBHSSIR,
    "rb-ss-hs-sir": RBSSHSSIR,
    "avpf": AVPF,
    "lls": LLS,
    "lis": LIS,
    "ls-n-ips": LSNIPS,
    "ls-n-ips-nn": LSNIPSNN,
    "pf-doucet": PFDoucet,
    "pf-eis": PFEIS,
    "pf-eis-mt": PFEISMT,
    "partitioned": Partitioned,
    "partitioned-lis": PartitionedLIS,
    "branched-partitioned": BranchedPartitioned,
    "branched-partitioned-lis": BranchedPartitionedLIS,
}


def make_filter(name, model, **kwargs):
    """The filter registered as ``name`` on ``model``; a clear ``ValueError`` if unknown."""
    try:
        cls = ALGORITHMS[name]
    except KeyError:
        raise ValueError(
            f"unknown algorithm {name!r}; choose from {', '.join(sorted(ALGORITHMS))}"
        ) from None
    return cls(model, **kwargs)
