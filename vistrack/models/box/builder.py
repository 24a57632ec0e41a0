"""How ``run``, ``eval`` and :class:`vistrack.Tracker` build the box model: its registry entry."""

from __future__ import annotations

from ...appearance.cues import Appearance
from ..spec import ModelSpec
from .model import Box

__all__ = ["SPEC"]


def from_box(frame, box, **params):
    """:class:`~vistrack.models.box.Box` started from ``box`` ``(x, y, w, h)`` in ``frame``."""
    return Box(frame, box, **params)


SPEC = ModelSpec("box", description="any object from a box: colour + template appearance learned from the first frame",
                 from_box=from_box, bytes_per_particle=32_000, model_class=Box, passes_on=(Appearance,))
