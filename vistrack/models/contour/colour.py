"""The contour model's colour term (real footage; beyond the seeds): the box model's colour
term (:class:`~vistrack.appearance.cues.TargetColour`) on points inside the curve against a
band outside it (:mod:`~vistrack.models.contour.model` module docstring)."""

from __future__ import annotations

import numpy as np

from ...appearance.cues import TargetColour
from ...appearance.features import is_grey

__all__ = ["ContourColour"]


class ContourColour:
    """Mixin of :class:`~vistrack.models.contour.model.Contour`: :meth:`learn_colour`,
    :meth:`colour_loglik` and the colour-blob proposal's view of the frame (§3.2.5)."""

    #: the colour term (:meth:`learn_colour`); ``None``: edges only
    colour = None

    @property
    def blob_cell(self):
        """The colour-blob proposal's cell: 1/24 of the frame width (10 px at 240 x 180, §3.2.5)."""
        return self.frame_size[0] / 24.0

    def blob_image(self, obs):
        """The colour-blob proposal looks at the whole frame."""
        return obs.frame, 0.0, 0.0, 1.0

    def learn_colour(self, frame, *, lambda_colour=15.0, kappa=1.0, band=(0.1, 0.25), grey=None):
        """Turn on the colour term, learned from ``frame`` at the initial pose (module docstring).

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3) uint8 BGR, or (H, W)
            The first frame.
        lambda_colour, kappa : float
            ``λ_c``, ``κ`` of :class:`~vistrack.appearance.cues.TargetColour`.
        band : tuple of float
            Offsets of the outside sample points along the normals, as shares of the size.
        grey : bool or None
            Grey-level bins; ``None``: :func:`~vistrack.appearance.features.is_grey` of the frame.

        Returns
        -------
        TargetColour
        """
        import cv2

        from ...appearance.features import colour_bins, n_colour_bins

        self.colour_grey = is_grey(frame) if grey is None else bool(grey)
        self.n_bins = n_colour_bins(self.colour_grey)
        labels = colour_bins(frame, self.colour_grey)
        h, w = labels.shape
        curve = self.outline(self.prior_mean[None])[0]
        inside = np.zeros((h, w), np.uint8)
        cv2.fillPoly(inside, [np.round(curve).astype(np.int32)], 1)
        x0, y0 = curve.min(axis=0)
        x1, y1 = curve.max(axis=0)
        g = 0.75 * ((x1 - x0) + (y1 - y0))
        around = np.zeros((h, w), np.uint8)
        around[max(0, int(y0 - g)):max(0, int(y1 + g) + 1), max(0, int(x0 - g)):max(0, int(x1 + g) + 1)] = 1
        around[inside > 0] = 0

        def count(m):
            return np.bincount(labels[m > 0], minlength=self.n_bins).astype(float)

        self.colour = TargetColour(count(inside), count(around), lambda_colour=lambda_colour, kappa=kappa)
        rings_in = [self.meas0[::2] * s for s in (0.35, 0.7)] + [np.zeros((1, 2))]
        rings_out = [self.meas0[::2] + d * self.size * self.meas_normals0[::2] for d in band]
        self.colour_points_in = np.concatenate(rings_in)
        self.colour_points_out = np.concatenate(rings_out)
        return self.colour

    def _label_counts(self, labels, pts):
        """Bin counts ``(..., B)`` of the labels at points ``(..., P, 2)`` (nearest pixel;
        points outside the frame are not counted)."""
        h, w = labels.shape
        xi = np.floor(pts[..., 0]).astype(np.intp)
        yi = np.floor(pts[..., 1]).astype(np.intp)
        ok = (xi >= 0) & (xi < w) & (yi >= 0) & (yi < h)
        b = self.n_bins
        lab = np.where(ok, labels[np.clip(yi, 0, h - 1), np.clip(xi, 0, w - 1)], b).astype(np.intp)
        rows = int(np.prod(lab.shape[:-1]))
        lab = lab.reshape(rows, -1) + (b + 1) * np.arange(rows)[:, None]
        counts = np.bincount(lab.ravel(), minlength=rows * (b + 1)).reshape(rows, b + 1)[:, :b]
        return counts.reshape(pts.shape[:-2] + (b,))

    def colour_loglik(self, obs, z, offsets=None):
        """``log r_c`` of poses ``z (N, 4)``: ``(N,)``; with translations ``offsets (G, 2)``,
        of every pose shifted by every offset: ``(N, G)``. Zero without a colour term."""
        if self.colour is None:
            n = len(z)
            return np.zeros(n) if offsets is None else np.zeros((n, len(offsets)))
        labels = obs.colour_labels(self.colour_grey)
        p_in = self.place_points(z, self.colour_points_in)
        p_out = self.place_points(z, self.colour_points_out)
        if offsets is not None:
            d = np.asarray(offsets, float)[None, :, None, :]
            p_in, p_out = p_in[:, None] + d, p_out[:, None] + d
        return self.colour.loglik(self._label_counts(labels, p_in), self._label_counts(labels, p_out))
