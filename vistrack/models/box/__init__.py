"""The box model: any object from a box (colour + template appearance, a correlation filter).

- :mod:`.model`: :class:`Box`, the state, dynamics, likelihood and local moves;
- :mod:`.appearance`, :mod:`.appearance_map`, :mod:`.target_colour`: the appearance learned from the
  first frame (colour against the ring around the box, a grey template), shared with the contour's
  colour term and the plate model;
- :mod:`.correlation`: the correlation filter, LIS's proposal and a likelihood term;
- :mod:`.builder`: how ``run``, ``eval`` and :class:`vistrack.Tracker` build it (its registry entry);
- compiled kernels beside their numpy paths: :mod:`.kernels`, :mod:`.frame_kernels`,
  :mod:`.dcf_kernels` (the colour and template kernels shared with the other models are in
  :mod:`vistrack.kernels.appearance`).
"""

from .appearance import Appearance
from .correlation import CorrelationFilter
from .model import Box

__all__ = ["Appearance", "Box", "CorrelationFilter"]
