"""Shared pieces of the Laplace-proposal filters of seed 000 (PF-Doucet, PF-EIS, PF-EIS-MT).

The proposal ``N(m, Σ_IS)`` with ``Σ_IS = [∇²L(m)]⁻¹`` (eqs. 3–4) comes from the
model's :meth:`laplace` (mode and Hessian); these helpers sample it and give
its log-density.
"""

from __future__ import annotations

import numpy as np

from ..core.gaussian import mvn_logpdf, mvn_sample
from ..core.particles import ParticleSet
from .base import ParticleFilter

__all__ = ["LaplaceFilter", "laplace_covariance", "sample_laplace"]


def laplace_covariance(hess):
    """``Σ_IS = H⁻¹`` per particle, symmetrised."""
    cov = np.linalg.inv(hess)
    return 0.5 * (cov + np.swapaxes(cov, -1, -2))


def sample_laplace(mode, hess, rng):
    """``x ~ N(m, H⁻¹)`` per particle; returns ``(x, log N(x; m, H⁻¹))``."""
    cov = laplace_covariance(hess)
    x = mvn_sample(mode, cov, rng)
    return x, mvn_logpdf(x, mode, cov)


class LaplaceFilter(ParticleFilter):
    """Base of the seed-000 filters: the first frame holds the known ``X_0``.

    The landmark prior is a point mass at ``X_0``, so the first step keeps
    ``n`` copies of it, weighted by the first observation.
    """

    def first_step(self, obs, n, rng):
        """``n`` copies of the known ``X_0`` (``model.sample_prior``), weighted by ``log p(Y_1|X_0)``.

        Returns a :class:`~vistrack.core.particles.ParticleSet` of ``n`` states ``(n, d)``.
        """
        if n < 1:
            raise ValueError(f"number of particles must be positive, got {n}")
        x = self.model.sample_prior(n, rng)
        ll = self.model.loglik(obs, x)
        return ParticleSet(x, ll, loglik=ll)
