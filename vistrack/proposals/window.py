"""The window function ``g`` of LLS and LIS on a model's local coordinates, with its
sampling grid (thesis 001, §4.4–4.5)."""

from __future__ import annotations

import itertools

import numpy as np

from ..core.gaussian import diag_logpdf

__all__ = ["Window"]


class Window:
    """A window function ``g`` on ``m`` local coordinates, with its sampling grid.

    Parameters
    ----------
    kind : {"box", "gaussian"}
        ``box``: uniform on ``[-half_width, half_width]``; ``gaussian``: zero-mean with
        standard deviations ``scale``, the grid truncated at ``truncate`` std.
    scale : array_like of shape (m,)
        Half-widths (box) or standard deviations (gaussian).
    grid : int
        Grid cells per local dimension (``grid ** m`` likelihood evaluations per particle).
    """

    def __init__(self, kind, scale, *, grid=9, truncate=4.0):
        if kind not in ("box", "gaussian"):
            raise ValueError(f"window must be 'box' or 'gaussian', got {kind!r}")
        self.kind = kind
        self.scale = np.atleast_1d(np.asarray(scale, dtype=float))
        if np.any(self.scale <= 0):
            raise ValueError("window scale must be positive")
        self.grid = int(grid)
        half = self.scale if kind == "box" else truncate * self.scale
        self.cell = 2.0 * half / self.grid
        axes = [(-h + c * (np.arange(self.grid) + 0.5)) for h, c in zip(half, self.cell)]
        self.offsets = np.array(list(itertools.product(*axes)))  # (G^m, m)
        self.log_cell = float(np.sum(np.log(self.cell)))
        self._half = half
        self.log_g_offsets = self.logpdf(self.offsets)

    @property
    def dim(self):
        """Number ``m`` of local coordinates."""
        return self.scale.size

    def logpdf(self, d):
        """``log g(d)`` for offsets ``d (..., m)``; ``g`` integrates to one."""
        d = np.asarray(d, dtype=float)
        if self.kind == "box":
            inside = np.all(np.abs(d) <= self._half * (1 + 1e-12), axis=-1)
            return np.where(inside, -np.sum(np.log(2.0 * self.scale)), -np.inf)
        return diag_logpdf(d, 0.0, self.scale)
