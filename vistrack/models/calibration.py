"""A calibrated confidence: a logistic map from a model's cues to the probability that its estimate lies on
the object, with the threshold below which the object is reported lost (issue 44; the box and siam models).

``c = σ(β · (z - μ) / s + β_0)`` over the cues named in the calibration, read from a cue vector in the
order of the model's ``FEATURES``; fitted by ``benchmarks/fit_confidence.py`` and saved with
:meth:`Calibration.save_all` (one ``.npz`` holding an estimate's calibration, ``frame``, and a search
candidate's, ``candidate``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Calibration"]


@dataclass
class Calibration:
    """The logistic map from cues to a confidence, and the threshold of ``visible``.

    Attributes
    ----------
    names : tuple of str
        The cues used.
    mean, scale, coef : ndarray of shape (K,)
        ``μ``, ``s`` and ``β`` of each cue.
    intercept : float
        ``β_0``.
    threshold : float
        The object is reported lost below this confidence, and a search's candidate taken at or above it.
    features : tuple of str
        The order of the cue vectors it is applied to (the model's ``FEATURES``, or a prefix of them).
    hold : float
        Hysteresis: an object reported lost is reported again only at a confidence of ``threshold + hold`` or
        more (a long loss's frames stay lost through a passing rise of the confidence).
    """

    names: tuple
    mean: np.ndarray
    scale: np.ndarray
    coef: np.ndarray
    intercept: float
    threshold: float
    features: tuple = ()
    hold: float = 0.0

    #: the arrays of one calibration in the file, each saved as ``<part>_<key>`` (``hold``: where present)
    KEYS = ("names", "mean", "scale", "coef", "intercept", "threshold")

    @classmethod
    def load(cls, path, part="frame", features=()):
        """The calibration ``part`` (``"frame"``, ``"candidate"``) in ``path`` (an ``.npz`` of :meth:`save_all`),
        applied to cue vectors ordered as ``features``."""
        try:
            with np.load(path, allow_pickle=False) as d:
                v = [d[f"{part}_{k}"] for k in cls.KEYS]
                hold = float(d[f"{part}_hold"]) if f"{part}_hold" in d else 0.0
        except (OSError, ValueError, KeyError) as e:
            why = e.strerror if isinstance(e, OSError) and e.strerror else str(e).strip("'\"")
            raise ValueError(f"confidence: cannot read a calibration from {path} ({why})") from None
        return cls(tuple(str(n) for n in v[0]), *(a.astype(float) for a in v[1:4]), float(v[4]), float(v[5]),
                   tuple(features), hold)

    @classmethod
    def save_all(cls, path, parts, **extra):
        """Write the calibrations ``parts`` (``{"frame": ..., "candidate": ...}``) and ``extra`` arrays (the
        fit's provenance) to ``path``."""
        arrays = {}
        for part, c in parts.items():
            arrays.update({f"{part}_names": np.array(c.names), f"{part}_mean": c.mean, f"{part}_scale": c.scale,
                           f"{part}_coef": c.coef, f"{part}_intercept": np.float64(c.intercept),
                           f"{part}_threshold": np.float64(c.threshold), f"{part}_hold": np.float64(c.hold)})
        np.savez(path, **arrays, **extra)

    def index(self):
        """The columns ``(K,)`` of a cue vector (ordered as :attr:`features`) that the calibration reads."""
        return np.array([self.features.index(n) for n in self.names], np.intp)

    def __call__(self, features):
        """The confidence of cue vectors ``(..., F)`` ordered as :attr:`features` -> ``(...)`` in ``[0, 1]``."""
        z = (np.asarray(features, float)[..., self.index()] - self.mean) / self.scale
        return 1.0 / (1.0 + np.exp(-(z @ self.coef + self.intercept)))
