"""License-plate template likelihood (thesis 001, §1.3.2, Table 1.1) — issue 6 groundwork.

``r = r^h · r^v · r^c`` with (Table 1.1's pixel sets from a
:class:`~vistrack.models.plate_layout.PlateLayout`)

    log r^h = κ (mean_{P^{h,e}} |∇_y I| - mean_{P^{h,fe}} (|G_s I| + |G_l I|))
    log r^v = κ (mean_{P^{v,e}} |∇_x I| - mean_{P^{v,fe}} (|G_s I| + |G_l I|))
    log r^c = κ (mean_{P^{sc}} |G_s I| + mean_{P^{bc}} |G_l I|)

``∇_y I`` responds to horizontal edges (the thesis's "horizontal edge image"),
``G_s``, ``G_l`` are the box-filter DoGs at two scales. Every map is divided
by its mean over the frame, so the terms are "times the frame's average" and
lighting changes cancel; ``κ`` (the thesis's proportionality) sets the
sharpness. Each pixel set is sampled on a regular grid of points inside its
rectangles (bilinear, one ``cv2.remap`` of a 4-channel map for all
particles), which handles the sheared parallelogram exactly.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..features import remap_points
from .plate_layout import LAYOUTS, plate_points

__all__ = ["PlateLikelihood"]

_SETS = ("h_edge", "h_free", "v_edge", "v_free", "small", "big")


def _grid_points(rects, per_unit=24):
    """Sample points (unit-square coords) inside each rectangle, about ``per_unit`` per unit length."""
    pts, owner = [], []
    for r in rects:
        x0, y0, x1, y1 = r
        nx = max(2, int(np.ceil((x1 - x0) * per_unit)))
        ny = max(2, int(np.ceil((y1 - y0) * per_unit)))
        a = x0 + (np.arange(nx) + 0.5) * (x1 - x0) / nx
        b = y0 + (np.arange(ny) + 0.5) * (y1 - y0) / ny
        aa, bb = np.meshgrid(a, b)
        pts.append(np.stack([aa.ravel(), bb.ravel()], axis=1))
    return np.concatenate(pts)


class PlateLikelihood:
    """The plate likelihood ``r(y | u, w, θ, s)`` for poses ``(N, 4)`` (or states whose first
    four columns are the pose).

    Parameters
    ----------
    layout : str or PlateLayout
    kappa : float
        Sharpness ``κ``.
    per_unit : int
        Sample points per unit length of the plate square in each pixel set.
    """

    def __init__(self, layout="jp", *, kappa=2.0, per_unit=24):
        self.layout = LAYOUTS[layout] if isinstance(layout, str) else layout
        self.kappa = float(kappa)
        sets = self.layout.sets()
        self.points = {k: _grid_points(sets[k], per_unit) for k in _SETS}
        self._all = np.concatenate([self.points[k] for k in _SETS])
        bounds = np.cumsum([0] + [len(self.points[k]) for k in _SETS])
        self._slices = {k: slice(bounds[i], bounds[i + 1]) for i, k in enumerate(_SETS)}

    def maps(self, obs):
        """The 4-channel map ``(|∇_x I|, |∇_y I|, |G_s I|, |G_l I|)``, each over its frame mean (cached)."""
        m = getattr(obs, "_plate_maps", None)
        if m is None:
            chans = [np.abs(obs.gx), np.abs(obs.gy), np.abs(obs.dog_small), np.abs(obs.dog_large)]
            chans = [c / max(float(cv2.mean(c)[0]), 1e-6) for c in chans]
            m = cv2.merge([c.astype(np.float32) for c in chans])
            obs._plate_maps = m
        return m

    def terms(self, obs, states):
        """``(log r^h, log r^v, log r^c)`` as three ``(N,)`` arrays."""
        pose = np.atleast_2d(states)[:, :4]
        pts = plate_points(pose, self._all, self.layout.aspect)  # (N, P, 2)
        v = remap_points(self.maps(obs), pts[..., 0].astype(np.float32), pts[..., 1].astype(np.float32))
        sl = self._slices

        def mean(name, ch):
            return v[:, sl[name], ch].mean(axis=1)

        k = self.kappa
        lines_h = mean("h_free", 2) + mean("h_free", 3)
        lines_v = mean("v_free", 2) + mean("v_free", 3)
        log_h = k * (mean("h_edge", 1) - lines_h)
        log_v = k * (mean("v_edge", 0) - lines_v)
        log_c = k * (mean("small", 2) + mean("big", 3))
        return log_h, log_v, log_c

    def loglik(self, obs, states):
        """``log r = log r^h + log r^v + log r^c`` ``(N,)``."""
        h, v, c = self.terms(obs, states)
        return h + v + c
