"""vistrack: particle filters that use the observation well (Torma 2007; Vaswani et al.).

The library never prints, parses argv or draws progress bars; see ``vistrack.cli``. Its names
load when first used (``vistrack.Tracker``), so that ``import vistrack`` and the command line start
at once.
"""

__all__ = ["Tracker", "ParticleSet", "DegenerateWeightsWarning", "ess", "logsumexp", "normalized_weights",
           "__version__"]

_PARTICLES = ("ParticleSet", "DegenerateWeightsWarning", "ess", "logsumexp", "normalized_weights")


def __getattr__(name):
    """``vistrack.Tracker``, the particle core's names and ``__version__``, loaded on first use (PEP 562)."""
    if name == "Tracker":
        from .api.tracker import Tracker

        return Tracker
    if name in _PARTICLES:
        from .core import particles

        return vars(particles)[name]
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("vistrack")
        except PackageNotFoundError:  # running from a source tree
            return "0.0.0+src"
    raise AttributeError(f"module 'vistrack' has no attribute {name!r}")


def __dir__():
    return sorted(__all__)
