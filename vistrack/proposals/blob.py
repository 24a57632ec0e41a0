"""The colour-blob proposal of the history-sampling experiments (thesis 001, §3.2.5).

A Gaussian colour model of the target (:class:`GaussianColour`, learned from its pixels in
the first frame) gives every pixel of a frame its likelihood of being the target's colour;
the map is averaged over cells (about 24 x 18 of them across the frame: the thesis's 10-px
cells at 240 x 180), a cell is drawn ∝ its mean (mixed with a small uniform share ``floor``,
so that every translation of the frame keeps a positive density), and the translation is the
cell's centre plus a uniform "fine-scale" displacement. The thesis adds an integer
displacement in ``{-5..5}²`` px to 10-px cells; here the displacement is uniform on the
rectangle of ``spread`` (1.1) times the cell, the integer grid plus a uniform sub-pixel part,
so that the proposal has a density:

    π(x | Y_t) = Σ_c p_c 1[|x - m_c| <= h] / (4 h_x h_y),

``m_c`` the centre of cell ``c``, ``h = spread · cell / 2`` per axis (a point is covered by
at most 2 x 2 cells). :meth:`BlobProposal.logpdf` is that density exactly; it integrates to
one over the frame grown by ``h``. The proposal looks at the image only (Assumption 3.2.2).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["GaussianColour", "BlobProposal", "SubspaceProposal", "colour_features"]

#: added to R + G + B before dividing (dark pixels have no reliable chromaticity)
_DARK = 30.0


def colour_features(image):
    """Per-pixel features ``(H, W, m)`` float32: the chromaticity ``(r, g) = (R, G) / (R + G + B + 30)``
    of a BGR image (unchanged by a gain on the lighting), or the grey level / 255 of a grey one."""
    img = np.asarray(image, np.float32)
    if img.ndim == 2:
        return (img / 255.0)[..., None]
    s = img.sum(axis=2, keepdims=True) + _DARK
    return img[..., [2, 1]] / s


class GaussianColour:
    """A Gaussian ``N(μ, Σ)`` over :func:`colour_features` of the target's pixels.

    Parameters
    ----------
    mean : array_like of shape (m,)
    cov : array_like of shape (m, m)
    """

    def __init__(self, mean, cov):
        self.mean = np.asarray(mean, float)
        self.cov = np.asarray(cov, float)
        self.prec = np.linalg.inv(self.cov).astype(np.float32)

    @classmethod
    def fit(cls, frame, mask, reg=1e-4):
        """The mean and covariance (plus ``reg`` on the diagonal) of the features of
        ``frame``'s pixels where ``mask`` is non-zero."""
        keep = np.asarray(mask) > 0
        rows, cols = np.flatnonzero(keep.any(axis=1)), np.flatnonzero(keep.any(axis=0))
        if len(rows):  # the features of the mask's bounding box only: the same pixels in the same order
            box = np.s_[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]
            frame, keep = np.asarray(frame)[box], keep[box]
        f = colour_features(frame)[keep].astype(float)
        if len(f) < 2:
            raise ValueError("the colour model needs at least 2 target pixels")
        return cls(f.mean(axis=0), np.cov(f, rowvar=False).reshape(f.shape[1], f.shape[1]) + reg * np.eye(f.shape[1]))

    def likelihood(self, image):
        """``exp(-d²/2)`` per pixel ``(H, W)`` float32, ``d`` the Mahalanobis distance of its
        features to ``μ`` (the Gaussian up to its constant)."""
        e = colour_features(image) - self.mean.astype(np.float32)
        d2 = np.einsum("...i,ij,...j->...", e, self.prec, e)
        return np.exp(-0.5 * np.minimum(d2, 80.0))


class BlobProposal:
    """``π(X_{t,1a} | Y_t)`` on translation from the colour-blob map (module docstring).

    Parameters
    ----------
    colour : GaussianColour
    image_of : callable
        ``image_of(obs) -> (image, x0, y0, f)``: the image the proposal looks at and where it
        lies in the frame (image pixel ``u`` is frame ``x0 + u / f``).
    cell : float
        Cell side in frame px.
    spread : float
        The fine displacement's rectangle, as a share of the cell (1.1: the thesis's ±5 px
        on 10-px cells).
    floor : float
        Uniform share of the cell probabilities.
    """

    def __init__(self, colour, image_of, cell, *, spread=1.1, floor=0.05):
        if not cell > 0 or not 0.0 < spread <= 2.0 or not 0.0 <= floor <= 1.0:
            raise ValueError(f"BlobProposal needs cell > 0, 0 < spread <= 2 and 0 <= floor <= 1, "
                             f"got {cell}, {spread}, {floor}")
        self.colour, self.image_of = colour, image_of
        self.cell, self.spread, self.floor = float(cell), float(spread), float(floor)
        self._cached = (None, None)

    def cell_map(self, obs):
        """``(p (gy, gx), origin (2,), cell (2,))``: the cell probabilities of ``obs``, the frame
        coordinates of the grid's corner and the cell sides (frame px); once per observation."""
        if self._cached[0] is obs:
            return self._cached[1]
        image, x0, y0, f = self.image_of(obs)
        h, w = image.shape[:2]
        c = self.cell * f  # cell side in image px
        gx, gy = max(1, int(round(w / c))), max(1, int(round(h / c)))
        step = max(1, int(min(w / gx, h / gy) // 5))  # about 5 x 5 samples per cell
        lik = self.colour.likelihood(image[::step, ::step])
        m = cv2.resize(lik, (gx, gy), interpolation=cv2.INTER_AREA).astype(float)
        total = m.sum()
        p = m / total if total > 0 else np.full(m.shape, 1.0 / m.size)
        p = (1.0 - self.floor) * p + self.floor / p.size
        out = (p, np.array([x0, y0], float), np.array([w / gx, h / gy]) / f)
        self._cached = (obs, out)
        return out

    def sample(self, n, obs, rng):
        """``n`` translations ``(n, 2)`` (frame px) drawn from ``π(. | obs)``."""
        p, origin, cell = self.cell_map(obs)
        cdf = np.cumsum(p.ravel())
        k = np.minimum(np.searchsorted(cdf, rng.random(n) * cdf[-1], side="right"), p.size - 1)
        i, j = np.divmod(k, p.shape[1])
        centre = origin + (np.stack([j, i], axis=1) + 0.5) * cell
        return centre + (2.0 * rng.random((n, 2)) - 1.0) * (0.5 * self.spread * cell)

    def logpdf(self, x, obs):
        """``log π(x | obs)`` of translations ``x (n, 2)`` (frame px), exactly; ``(n,)``."""
        p, origin, cell = self.cell_map(obs)
        h = 0.5 * self.spread * cell
        s = (np.asarray(x, float) - origin) / cell - 0.5  # position in cell units, 0 at the first centre
        j0 = np.floor(s).astype(np.intp)
        dens = np.zeros(len(s))
        for di in (0, 1):
            for dj in (0, 1):
                jj, ii = j0[:, 0] + dj, j0[:, 1] + di
                ok = (jj >= 0) & (jj < p.shape[1]) & (ii >= 0) & (ii < p.shape[0])
                ok &= np.abs(s[:, 0] - jj) * cell[0] <= h[0]
                ok &= np.abs(s[:, 1] - ii) * cell[1] <= h[1]
                dens += np.where(ok, p[np.clip(ii, 0, p.shape[0] - 1), np.clip(jj, 0, p.shape[1] - 1)], 0.0)
        with np.errstate(divide="ignore"):
            return np.log(dens) - np.log(4.0 * h[0] * h[1])


class SubspaceProposal:
    """Plain SIR's proposal from an image-only proposal on ``X_{t,1a}`` (§3.1, §3.2.4):
    ``x_1a ~ π(. | Y_t)``, ``x_1b ~ K_1b(. | x_1a, X_{t-1})``, the history ``f(X_{t-1})``, so
    ``π(X_t | X_{t-1}, Y_t) = π(x_1a | Y_t) K_1b(x_1b | x_1a, X_{t-1})`` and SIR's weight is
    ``r K_1a / π`` (Basic-SIR of Fig. 3.2 in its subspace form).

    Parameters
    ----------
    image : BlobProposal or similar
        ``sample(n, obs, rng)`` and ``logpdf(x1a, obs)``.
    kernel : Transition or PriorKernel
        The step's kernel (:mod:`vistrack.core.transition`), with the model's split.
    subspace_dim, innovation_dim : int
    """

    def __init__(self, image, kernel, subspace_dim, innovation_dim):
        self.image, self.kernel = image, kernel
        self.a, self.k = int(subspace_dim), int(innovation_dim)

    def sample(self, prev, obs, rng):
        """``n`` draws ``(n, a)`` of ``X_{t,1a}`` from the frame's colour-blob map."""
        x1a = self.image.sample(len(prev), obs, rng)
        x1b = self.kernel.sample_rest(x1a, prev, rng)
        return self.kernel.join(np.concatenate([x1a, x1b], axis=1), prev)

    def logpdf(self, new, prev, obs):
        """The proposal's exact log-density ``(n,)`` at ``x1a (n, a)``."""
        x1a = new[:, :self.a]
        return self.image.logpdf(x1a, obs) + self.kernel.rest_logpdf(new[:, self.a:self.k], x1a, prev)
