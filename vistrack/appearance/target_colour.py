"""The colour model of a target against its surroundings (Pérez et al. 2002; Comaniciu's
background weights): the colour term of the box, contour and plate models
(:mod:`vistrack.appearance.cues` describes the term)."""

from __future__ import annotations

import numpy as np

__all__ = ["TargetColour"]


class TargetColour:
    """The target's colour histogram against its background, and the colour term of a region.

    Parameters
    ----------
    inner, ring : array_like of shape (B,)
        Bin counts inside the target and in the ring (background) around it, first frame.
    lambda_colour, kappa : float
        ``λ_c`` and ``κ`` of :meth:`loglik` (module docstring).

    Attributes
    ----------
    q : ndarray of shape (B,)
        Target histogram, background-weighted and normalised.
    bg_weight : ndarray of shape (B,)
        Comaniciu's background weights ``v_u = min(1, b* / b_u)``.
    backprojection : ndarray of shape (B,) float32
        ``β_u = q_u / (q_u + b_u + 10⁻³)`` of the raw normalised histograms.
    """

    def __init__(self, inner, ring, *, lambda_colour=35.0, kappa=1.0):
        inner = np.asarray(inner, float)
        b = np.asarray(ring, float)
        b_min = b[b > 0].min() if (b > 0).any() else 1.0
        self.bg_weight = np.where(b > 0, np.minimum(1.0, b_min / np.maximum(b, 1e-12)), 1.0)
        self.lambda_colour, self.kappa = float(lambda_colour), float(kappa)
        self.q = self.normalise(inner)
        q_raw = inner / max(inner.sum(), 1)
        b_raw = b / max(b.sum(), 1)
        self.backprojection = (q_raw / (q_raw + b_raw + 1e-3)).astype(np.float32)
        self.bp = self.backprojection.astype(float)  # float64: what the compiled colour terms read

    def normalise(self, counts):
        """Background-weighted, normalised histograms of bin counts ``(..., B)``."""
        p = counts * self.bg_weight
        s = p.sum(axis=-1, keepdims=True)
        return p / np.where(s > 0, s, 1.0)

    def d2(self, counts):
        """``d²(h, q) = 1 - Σ_u sqrt(h_u q_u)`` for bin counts ``(..., B)``; empty: 1."""
        return 1.0 - np.sqrt(self.normalise(counts) * self.q).sum(axis=-1)

    def loglik(self, inner, ring):
        """``log r_c (...)`` of regions with bin counts ``inner`` and ``ring`` ``(..., B)``:
        ``-λ_c [d²(h_in, q) + κ (1 - d²(h_ring, q))] + λ_c (mean_in β - mean_ring β)``."""
        inner = np.asarray(inner, float)
        ring = np.asarray(ring, float)
        d = self.d2(inner) + self.kappa * (1.0 - self.d2(ring))
        contrast = (inner @ self.bp) / np.maximum(inner.sum(-1), 1) - (ring @ self.bp) / np.maximum(ring.sum(-1), 1)
        return self.lambda_colour * (contrast - d)

    def adapt(self, counts, rate):
        """``q <- (1 - rate) q + rate h`` for the bin counts ``(B,)`` of the estimate."""
        if np.sum(counts) > 0:
            self.q = (1 - rate) * self.q + rate * self.normalise(np.asarray(counts, float))
