"""The bearings ξ proposal's Laplace parts (:class:`~vistrack.models.bearings.xi.XiProposal`), plain
numpy and scalar arithmetic: the numpy path calls it on arrays and :mod:`vistrack.models.bearings.kernels`
compiles this very function for its loop (it lives here so that the kernels need not import the
model that uses them)."""

from __future__ import annotations

import numpy as np

__all__ = ["laplace_parts"]

_LOG_SQRT_2PI = 0.5 * np.log(2 * np.pi)


def laplace_parts(a, m, s, gam):
    """``log_m1, log_m2, u_b, s_b`` of :meth:`XiProposal.parts` for arrays or scalars (the
    compiled kernel :mod:`vistrack.models.bearings.kernels` compiles this very function)."""
    c2 = s * s + (gam * a) ** 2
    log_m1 = np.log(a) - 0.5 * m * m / c2 - 0.5 * np.log(c2) - _LOG_SQRT_2PI
    u = m
    for _ in range(2):
        q = u * u + c2
        u = u + ((m - u) / (s * s) - 2 * u / q) / (1.0 / (s * s) + 2 * (c2 - u * u) / (q * q))
    q = u * u + c2
    s_b = 1.0 / np.sqrt(1.0 / (s * s) + 2 * (c2 - u * u) / (q * q))
    log_m2 = np.log(gam * a * a / (np.pi * q) * s_b / s) - 0.5 * ((u - m) / s) ** 2
    return log_m1, log_m2, u, s_b
