"""vistrack as a component: the OpenCV-shaped :class:`Tracker` (also ``vistrack.Tracker``) and the TraX
server :func:`serve` (``vistrack trax``; its errors in :mod:`vistrack.api.trax_server`)."""

from .tracker import Tracker
from .trax_server import serve

__all__ = ["Tracker", "serve"]
