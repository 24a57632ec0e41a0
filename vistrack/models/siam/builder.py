"""How ``run``, ``eval`` and :class:`vistrack.Tracker` build the siam model: its registry entry."""

from __future__ import annotations

from ..spec import ModelSpec
from .model import Siam

__all__ = ["SPEC"]


def from_box(frame, box, **params):
    """:class:`~vistrack.models.siam.model.Siam` started from ``box`` ``(x, y, w, h)`` in ``frame``."""
    return Siam(frame, box, **params)


SPEC = ModelSpec("siam", description="any object from a box: NanoTrack v3's learned response as the likelihood and "
                 "LIS's proposal", from_box=from_box, bytes_per_particle=8_000, model_class=Siam)
