"""Landmark shape tracking (seed 000, §3): PF-EIS / PF-EIS-MT's model.

- :mod:`.model`: :class:`Landmarks`, the shape-space state and its observation model;
- :mod:`.shape_space`: the tangent basis and shape steps; :mod:`.sim`: simulated sequences;
- :mod:`.video`: :class:`LandmarkVideo`, the model on a video's feature maps;
- :mod:`.builder`: its registry entry.
"""

from .model import Landmarks
from .video_model import LandmarkVideo

__all__ = ["LandmarkVideo", "Landmarks"]
