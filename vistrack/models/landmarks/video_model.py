"""Landmark shape tracking on video (seed 000 §3–4): the landmark model whose observation is
the frame — bright blobs detected by a DoG and associated with the predicted landmarks."""

from __future__ import annotations

import numpy as np

from ...appearance.features import blob_peaks
from ..protocol import VideoModelBase
from .model import VIDEO_DYNAMICS, Landmarks

__all__ = ["LandmarkVideo"]


class LandmarkVideo(Landmarks, VideoModelBase):
    """The landmark model on video frames: pixels, blob detection and association.

    A configuration ``h`` lies at pixels ``centre + scale_px · (Re h, Im h)``.
    Observations (:meth:`observe`): bright blobs are the peaks of the small
    box-filter DoG above ``blob_threshold`` (:func:`~vistrack.appearance.features.blob_peaks`);
    landmark ``k`` observes the candidate nearest to its predicted position
    (the weighted mean of every particle's mean prediction), or nothing (NaN,
    no likelihood term) when no candidate is within ``gate_px``. Wrong
    associations — a clutter blob nearer than an occluded landmark — are what
    the clutter component of (6) absorbs; its variance defaults to half the
    frame diagonal, squared, in configuration units.

    Parameters
    ----------
    first : array (K, 2)
        Landmark pixels in the first frame: they fix ``X_0`` (shape, scale, rotation).
    size : (W, H)
    centre : (x, y), optional
        Centre of scale and rotation; default the landmarks' centroid.
    scale_px : float, optional
        Pixels per configuration unit; default the norm of the centred first landmarks,
        so that ``s_0 = 0``.
    sigma_o_px : float
        Observation noise (std of the complex Gaussian, px). Blob centres are
        accurate to ~0.1 px, but a small ``σ_o`` narrows the basin in which (6)
        treats a landmark as an inlier (``|Y_k - h_k| ≲ 3.3 σ_o``): after a 3σ jump
        of rotation and scale (about once per 200-frame clip) a filter with
        ``σ_o = 1.5`` px lost track on 1 of 5 clips; 3 px keeps all five.
    """

    def __init__(self, first, size, *, centre=None, scale_px=None, sigma_o_px=3.0, p=0.2, gate_px=30.0,
                 blob_threshold=25.0, **dynamics):
        first = np.asarray(first, float)
        if first.ndim != 2 or first.shape[1] != 2 or len(first) < 3:
            raise ValueError(f"need at least 3 landmark positions (x, y), got shape {first.shape}")
        self.size = tuple(int(v) for v in size)
        self.centre = first.mean(axis=0) if centre is None else np.asarray(centre, float)
        h0 = (first[:, 0] - self.centre[0]) + 1j * (first[:, 1] - self.centre[1])
        nrm = float(np.linalg.norm(h0 - h0.mean()))
        if nrm < 1e-6:
            raise ValueError("the first-frame landmarks all coincide")
        self.scale_px = nrm if scale_px is None else float(scale_px)
        hs = h0 / self.scale_px
        s0 = float(np.log(np.linalg.norm(hs - hs.mean())))
        theta0 = float(dynamics.pop("theta0", 0.0))
        z0 = (hs - hs.mean()) * np.exp(-s0 - 1j * theta0)
        half_diag = 0.5 * float(np.hypot(*self.size)) / self.scale_px
        params = {**VIDEO_DYNAMICS, **dynamics}
        super().__init__(len(first), z0=z0, s0=s0, theta0=theta0, sigma2_o=(sigma_o_px / self.scale_px) ** 2,
                         p=p, clutter_var=half_diag ** 2, **params)
        self.gate_px = float(gate_px)
        self.blob_threshold = float(blob_threshold)

    def to_pixels(self, h):
        """Complex configurations ``(..., K)`` to pixel coordinates ``(..., K, 2)``."""
        return np.stack([self.centre[0] + self.scale_px * h.real, self.centre[1] + self.scale_px * h.imag], axis=-1)

    def predicted_pixels(self, particles):
        """Landmark pixels ``(K, 2)`` predicted for the next frame from the previous ``particles``."""
        if particles is None:
            return self.to_pixels(self.configuration(self.prior_mean[None])[0])
        x = particles.states
        mean = self.advance(x, self.alpha_s * x[:, 0], self.alpha_theta * x[:, 1], self.c_prior_mean(x))
        return self.to_pixels(particles.weights @ self.configuration(mean))

    def observe(self, maps, particles):
        """``Y_t`` (complex ``(K,)``, NaN where missing) from a frame's feature maps."""
        peaks, _ = blob_peaks(maps.dog_small, self.blob_threshold)
        pred = self.predicted_pixels(particles)
        y = np.full(self.k, np.nan + 0j)
        if len(peaks):
            d = np.linalg.norm(pred[:, None, :] - peaks[None, :, :], axis=2)
            j = np.argmin(d, axis=1)
            ok = d[np.arange(self.k), j] <= self.gate_px
            pts = peaks[j[ok]]
            y[ok] = ((pts[:, 0] - self.centre[0]) + 1j * (pts[:, 1] - self.centre[1])) / self.scale_px
        return y

    def outline(self, states):
        """Landmark polygons in pixels, ``(n, K, 2)`` (one state: ``n = 1``), as every model's."""
        return self.to_pixels(self.configuration(np.atleast_2d(states)))

    def box(self, states):
        """Bounding boxes ``(n, 4)`` ``(x, y, w, h)`` of the landmark polygons."""
        pts = self.outline(states)
        lo, hi = pts.min(axis=1), pts.max(axis=1)
        return np.concatenate([lo, hi - lo], axis=1)

    def describe(self, state):
        """Track-CSV columns: centre, box, rotation (deg), scale ``e^s``, then ``lx0.., ly0..``."""
        s = np.asarray(state, float)
        pts = self.outline(s)[0]
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        c = pts.mean(axis=0)
        row = {"cx": c[0], "cy": c[1], "w": hi[0] - lo[0], "h": hi[1] - lo[1],
               "angle_deg": float(np.rad2deg(s[1])), "scale": float(np.exp(s[0]))}
        row.update({f"lx{i}": pts[i, 0] for i in range(self.k)})
        row.update({f"ly{i}": pts[i, 1] for i in range(self.k)})
        return row
