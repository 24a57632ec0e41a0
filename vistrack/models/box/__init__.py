"""The box model: any object from a box (colour + template appearance, a correlation filter, a scale filter).

- :mod:`.model`: :class:`Box`, the state, dynamics, likelihood and local moves;
- :mod:`.correlation_proposal`: LIS's proposal from the correlation filter's response;
- :mod:`.scale_filter`: DSST's scale filter, a term of the likelihood and the proposal's scale;
- :mod:`.lost`, :mod:`.confidence`: what is reported lost, the calibrated confidence, re-detection;
- :mod:`.builder`: how ``run``, ``eval`` and :class:`vistrack.Tracker` build it (its registry entry);
- compiled kernels beside their numpy paths: :mod:`.kernels`, :mod:`.scale_kernels`.

The appearance cues it shares with the contour and plate models (colour against a ring, the grey
template, the correlation filter) are in :mod:`vistrack.appearance`.
"""

from .model import Box

__all__ = ["Box"]
