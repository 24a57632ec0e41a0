"""Local moves on translation (thesis 001, §4.4.3) for states ``(pose_t, pose_{t-1})``."""

from __future__ import annotations

__all__ = ["TranslationMoves"]


class TranslationMoves:
    """Mixin: the local coordinates are the current centre ``states[:, :2]``.

    For models whose state is the current pose followed by the previous one
    (``dim = 2 k``, the centre first in each), as the contour and box models.
    """

    def local_coords(self, states):
        """The current centre ``(N, 2)``."""
        return states[:, :2]

    def with_local(self, states, u):
        """Move the current centre to ``u (N, 2)`` (the previous pose stays)."""
        out = states.copy()
        out[:, :2] = u
        return out

    def with_local_prior(self, states, u):
        """First step: move both centres (zero initial velocity, as ``p_0`` has)."""
        out = self.with_local(states, u)
        k = self.dim // 2
        out[:, k:k + 2] = u
        return out
