"""Weighted particle sets (thesis 001, §2.2–2.4).

A particle set is two arrays: ``states`` of shape ``(N, d)`` and
``log_weights`` of shape ``(N,)``. Weights live in log space; they are
normalised with log-sum-exp only when a normalised quantity is asked for.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "ParticleSet",
    "DegenerateWeightsWarning",
    "normalized_weights",
    "logsumexp",
    "ess",
]


class DegenerateWeightsWarning(RuntimeWarning):
    """Every weight of a step was zero or NaN; the particles were re-drawn."""


def logsumexp(log_w, axis=None):
    """``log(sum(exp(log_w)))`` over ``axis`` without overflow; ``-inf`` where all are ``-inf``."""
    log_w = np.asarray(log_w, dtype=float)
    m = np.max(log_w, axis=axis, keepdims=True)
    shift = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore"):
        out = shift + np.log(np.sum(np.exp(log_w - shift), axis=axis, keepdims=True))
    out = np.where(m == np.inf, np.inf, out)
    return out.item() if axis is None else np.squeeze(out, axis=axis)


def normalized_weights(log_w):
    """Normalised weights ``w_i = exp(l_i) / sum_j exp(l_j)`` (log-sum-exp).

    Returns ``None`` when no weight is positive and finite (all ``-inf`` or NaN).
    """
    log_w = np.asarray(log_w, dtype=float)
    clean = np.where(np.isnan(log_w), -np.inf, log_w)
    m = np.max(clean)
    if not np.isfinite(m):
        return None
    w = np.exp(clean - m)
    return w / w.sum()


def ess(log_w):
    """Effective sample size ``1 / sum w_i^2`` of normalised weights (§2.4); 0 if degenerate."""
    w = normalized_weights(log_w)
    return 0.0 if w is None else float(1.0 / np.dot(w, w))


@dataclass
class ParticleSet:
    """Particles ``states (N, d)`` with ``log_weights (N,)``.

    Attributes
    ----------
    states : ndarray of shape (N, d), float64
    log_weights : ndarray of shape (N,), float64
        Unnormalised log-weights; equal weights by default.
    degenerate : bool
        True when the step that produced this set met all-zero/NaN weights
        and recovered by re-drawing from the prediction.
    loglik : ndarray of shape (N,) or None
        ``log r(Y_t | X_t)`` of each particle at the observation that weighted
        it, where the filter computed it (the birth reserve of
        :class:`~vistrack.filters.resampler.BirthReserve` draws ∝ it).
    """

    states: np.ndarray
    log_weights: np.ndarray = None
    degenerate: bool = field(default=False, compare=False)
    loglik: np.ndarray = field(default=None, compare=False)

    def __post_init__(self):
        self.states = np.asarray(self.states, dtype=np.float64)
        if self.states.ndim == 1:
            self.states = self.states[:, None]
        if self.states.ndim != 2:
            raise ValueError(f"states must have shape (N, d), got {self.states.shape}")
        n = self.states.shape[0]
        if self.log_weights is None:
            self.log_weights = np.full(n, -np.log(n))
        self.log_weights = np.asarray(self.log_weights, dtype=np.float64)
        if self.log_weights.shape != (n,):
            raise ValueError(
                f"log_weights must have shape ({n},), got {self.log_weights.shape}"
            )
        if self.loglik is not None:
            self.loglik = np.asarray(self.loglik, dtype=np.float64)
            if self.loglik.shape != (n,):
                raise ValueError(f"loglik must have shape ({n},), got {self.loglik.shape}")

    @property
    def n(self):
        """Number of particles N."""
        return self.states.shape[0]

    @property
    def dim(self):
        """State dimension d."""
        return self.states.shape[1]

    @property
    def weights(self):
        """Normalised weights (uniform if the set is degenerate); computed once per
        ``log_weights`` array (a read-only copy: the resampler, the estimate and the ESS share it)."""
        cached = self.__dict__.get("_weights")
        if cached is not None and cached[0] is self.log_weights:
            return cached[1]
        w = normalized_weights(self.log_weights)
        w = np.full(self.n, 1.0 / self.n) if w is None else w
        w.flags.writeable = False
        self.__dict__["_weights"] = (self.log_weights, w)
        return w

    @property
    def ess(self):
        """Effective sample size ``1 / sum w^2``."""
        return ess(self.log_weights)

    def mean(self):
        """Weighted mean, shape ``(d,)``."""
        return self.weights @ self.states

    def cov(self):
        """Weighted covariance ``sum w (x - m)(x - m)^T``, shape ``(d, d)``."""
        w = self.weights
        dx = self.states - w @ self.states
        return (dx * w[:, None]).T @ dx

    def resample(self, idx):
        """Equally weighted set ``states[idx]``."""
        return ParticleSet(self.states[idx])


def checked_weights(log_w, what="step"):
    """Return ``(log_w, degenerate)``; on all-zero/NaN weights warn and return uniform weights.

    Used by filters: when ``degenerate`` the caller replaces the states by the
    equally weighted prediction.
    """
    log_w = np.where(np.isnan(log_w), -np.inf, log_w)
    if np.isfinite(np.max(log_w)):
        return log_w, False
    warnings.warn(
        f"all particle weights were zero or NaN in {what}; particles re-drawn from the prediction",
        DegenerateWeightsWarning,
        stacklevel=3,
    )
    return np.full(len(log_w), -np.log(len(log_w))), True
