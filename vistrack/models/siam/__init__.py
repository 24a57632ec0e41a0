"""The siam model: any object from a box, its likelihood and LIS's proposal a learned Siamese network's response.

- :mod:`.model`: :class:`Siam`, the state, dynamics, likelihood and estimate;
- :mod:`.network`: NanoTrack v3's backbone and head on onnxruntime, the crops;
- :mod:`.observation`: a frame's response in frame coordinates;
- :mod:`.proposal`: LIS's local proposal from the response;
- :mod:`.builder`: how ``run``, ``eval`` and :class:`vistrack.Tracker` build it (its registry entry).
"""

from .model import Siam

__all__ = ["Siam"]
