"""vistrack: particle filters that use the observation well (Torma 2007; Vaswani et al.).

The library never prints, parses argv or draws progress bars; see ``vistrack.cli``.
"""

from importlib.metadata import PackageNotFoundError, version

from .core.particles import DegenerateWeightsWarning, ParticleSet, ess, logsumexp, normalized_weights
from .track.tracker import Tracker

try:
    __version__ = version("vistrack")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0.0.0+src"

__all__ = ["Tracker", "ParticleSet", "DegenerateWeightsWarning", "ess", "logsumexp", "normalized_weights",
           "__version__"]
