"""The ξ proposal of bearings-only tracking: a Laplace move across the observed bearing
(thesis 001 §4.5.5; seed 000 §2, sampling the well-observed part from a Laplace approximation).

The bearing ``y`` of a ship pins its position to the ray ``{a d : a > 0}``,
``d = (cos y, sin y)``, within ``γ a`` (about ``5e-6`` at range 0.2), while the
process noise spreads the position over ``σ_η / 2 = 5e-4``. Write a ship's
position as ``a d + u n`` (``n`` the normal of the ray). Given the previous state
and the along-ray coordinate ``a``, the kernel's across-ray coordinate is Gaussian,
``u ~ N(m, s²)``: under ``K``, ``m = (F Z_{t-1})_pos · n`` and ``s = σ_η / 2`` (the
component ``ξ_⊥`` of the noise moves the position by ``ξ_⊥ / 2``); under ``p_0``
(the first step) ``m, s`` are the Gaussian conditional of the prior position.

The proposal keeps the prediction's ``a`` (a draw from ``K``'s own conditional)
and replaces its ``u`` by a draw from the two-part mixture

    π(u) = p_1 · T(u) + p_2 · N(u; u_b, s_b²).

``T``, the part on the ray, is the Laplace approximation of ``N(u; m, s²) r(y | u)`` with
Cauchy tails: a Cauchy on the bearing error ``δ = atan(u / a)`` (truncated to ``|δ| < π/2``)
centred at the mode of the Laplace fit, whose scale matches the curvature
``2/(γ a)² + 1/s²``. ``N(u_b, s_b²)``, the part off the ray, is the Laplace fit of the
Gaussian times the likelihood's Cauchy tail, ``N(u; m, s²) γ a² / (π (u² + c²))``
(log-concave), which holds the posterior's mass when the prediction is far from the ray.
``p_1 : p_2`` are the two parts' approximate masses (:meth:`XiProposal.parts`), so the
importance ratio ``N(u; m, s²) r(y|u) / π(u)`` hardly varies with ``u``, and their sum
approximates ``p(y | Z_{t-1})``: the first stage (:meth:`XiProposal.look_ahead`) that LIS
resamples with (the fully adapted auxiliary filter, App. B).

The move changes ``ξ`` only across the ray (velocity follows with ``Δv = 2 Δp``,
:meth:`~vistrack.models.bearings.model.Bearings.with_local`), so ``Z`` stays on the
support of ``K`` and LIS's ``K(Z)/K(X)`` ratio reduces to the ratio of the across-ray
conditionals: with ``log α = log N(u_X; m, s²)`` and ``log q = log π(u_Z)`` the LIS
weight (Prop. 4.5.1) is exactly ``N(u_Z; m, s²) r(y|Z) / π(u_Z)``.
"""

from __future__ import annotations

import numpy as np
from scipy import special

from ... import kernels
from ...core.transition import is_prior
from .laplace_parts import laplace_parts  # its home: numba compiles it there

__all__ = ["XiProposal"]

_LOG_SQRT_2PI = 0.5 * np.log(2 * np.pi)


def _norm_logpdf(u, m, s):
    """``log N(u; m, s²)``, broadcasting."""
    z = (u - m) / s
    return -0.5 * z * z - np.log(s) - _LOG_SQRT_2PI


class XiProposal:
    """LIS local proposal on the process noise across the observed bearing (module docstring).

    ``sample(x, obs, rng, prev) -> (z, log_alpha, log_q)`` as every LIS proposal
    (:class:`~vistrack.filters.lis.LIS`), and a first stage ``look_ahead(prev, obs, kernel)``.
    Arrays are ``(N, M)`` per particle and ship; where numba is, :mod:`vistrack.models.bearings.kernels`
    does :meth:`sample` and :meth:`look_ahead` in one compiled loop each (the numpy path is the
    reference).

    Parameters
    ----------
    model : Bearings
        The bearings model (``ships``, ``sigma_eta``, ``gamma``, position indices, prior).
    kernel : Transition or PriorKernel or None
        The step's kernel; ``None`` is ``K``. Under ``p_0`` the across-ray conditional is the
        prior's and velocities stay; under ``K`` it is the noise's and velocities follow.
    """

    def __init__(self, model, kernel=None):
        self.model = model
        self.first = is_prior(kernel)
        self.with_local = model.with_local_prior if self.first else model.with_local
        self._ix, self._iy = model.pos_idx[0::2], model.pos_idx[1::2]
        self._vx, self._vy = model.vel_idx[0::2], model.vel_idx[1::2]
        self._mean = model.prior_mean[self._ix], model.prior_mean[self._iy]
        self._var = model.prior_std[self._ix] ** 2, model.prior_std[self._iy] ** 2
        self._s = 0.5 * model.sigma_eta  # std of the position's across-ray noise under K
        # the compiled kernels' layout: indices of x1, x3, v1, v3 and the prior of x1, x3, (4, M) each
        self._idx = np.array([self._ix, self._iy, self._vx, self._vy], dtype=np.int64)
        self._prior = np.array([*self._mean, *self._var])
        if kernels.use():  # load the compiled kernels now (0.1-1 s), not in a filter's first step
            x = model.prior_mean[None]
            self.sample(x, self.model.bearing(x)[0], np.random.default_rng(0), x)
            self.look_ahead(x, self.model.bearing(x)[0])

    def frame(self, x, obs, prev):
        """The rays and the kernel's across-ray conditional.

        Returns
        -------
        c, sn : ndarray (M,)
            ``cos y, sin y``: the ray is ``d = (c, sn)``, its normal ``(-sn, c)``.
        a, u : ndarray (N, M)
            The along-ray and across-ray coordinates of the positions of ``x``.
        m, s : ndarray (N, M) or (M,) or float
            Mean and standard deviation of ``u`` given ``a`` (and ``prev``) under the kernel.
        """
        c, sn = np.cos(obs), np.sin(obs)
        px, py = x[:, self._ix], x[:, self._iy]
        a, u = px * c + py * sn, py * c - px * sn
        if self.first:  # the prior position N(mean, diag(var)) in the ray's frame, u given a
            (mx, my), (vx, vy) = self._mean, self._var
            vdd, vdn = vx * c * c + vy * sn * sn, (vy - vx) * c * sn
            m = my * c - mx * sn + vdn / vdd * (a - mx * c - my * sn)
            return c, sn, a, u, m, np.sqrt(vx * sn * sn + vy * c * c - vdn * vdn / vdd)
        qx, qy = prev[:, self._ix] + prev[:, self._vx], prev[:, self._iy] + prev[:, self._vy]
        return c, sn, a, u, qy * c - qx * sn, self._s

    def parts(self, a, m, s):
        """The posterior of ``u`` in two parts, with their approximate masses.

        On the ray, the likelihood's peak: mass ``a N(0; m, s² + γ²a²)``. Off it, the
        Gaussian times the likelihood's Cauchy tail ``γ a² / (π (u² + c²))``, ``c² = s² + γ²a²``
        (log-concave): its Laplace fit ``N(u_b, s_b²)`` from two Newton steps from ``m``, and
        the Laplace mass. The sum of the masses approximates ``p(y | a, Z_{t-1})``.
        ``a`` is clipped above 0. Returns ``log_m1, log_m2, u_b, s_b``, each ``(N, M)``.
        """
        return laplace_parts(a, m, s, self.model.gamma)

    def mixture(self, a, m, s):
        """The mixture's parts: ``log p_1, log p_2`` (normalised), the Cauchy's centre ``δ0``
        and scale ``g`` on the bearing error, ``lo, hi`` (the truncation, ``atan`` of the
        standardised ends ``±π/2``), and the off-ray part's ``u_b, s_b`` (:meth:`parts`).
        ``a`` clipped above 0."""
        log_m1, log_m2, u_b, s_b = self.parts(a, m, s)
        log_p1 = -np.logaddexp(0.0, log_m2 - log_m1)
        h = 2.0 / (self.model.gamma * a) ** 2 + 1.0 / (s * s)  # curvature of -log(N r) at the mode
        delta0 = np.arctan(m / (s * s * h * a))
        g = np.sqrt(2.0 / h) / a  # a Cauchy on δ with that curvature
        lo, hi = np.arctan((-0.5 * np.pi - delta0) / g), np.arctan((0.5 * np.pi - delta0) / g)
        return log_p1, log_m2 - log_m1 + log_p1, delta0, g, lo, hi, u_b, s_b

    def _log_mix(self, u, a, parts):
        """``log π(u)`` for the mixture ``parts`` of :meth:`mixture`."""
        log_p1, log_p2, delta0, g, lo, hi, u_b, s_b = parts
        e = (np.arctan(u / a) - delta0) / g
        # a truncated Cauchy on δ = atan(u / a), times the Jacobian dδ/du = a / (a² + u²)
        log_t = np.log(a / (g * (hi - lo) * (a * a + u * u))) - np.log1p(e * e)
        return np.logaddexp(log_p1 + log_t, log_p2 + _norm_logpdf(u, u_b, s_b))

    # -- the LIS contract ---------------------------------------------------------------
    def sample(self, x, obs, rng, prev=None):
        """Move every ship of the predictions ``x (N, 4M)`` across its observed ray.

        Returns ``(z (N, 4M), log_alpha (N,), log_q (N,))``: ``log_alpha`` is the kernel's
        across-ray log density of ``x``, ``log_q`` the mixture's of ``z`` (summed over ships).
        Draws one ``rng.random((2, N, M))``: the part (``w[0] < p_1``) and its quantile ``w[1]``.
        Compiled (:func:`vistrack.models.bearings.kernels.xi_move`, equal) where numba is.
        """
        if prev is None and not self.first:
            raise ValueError("the ξ proposal needs prev (Z_{t-1}) on every step after the first")
        obs = np.asarray(obs, dtype=float)
        w = rng.random((2, len(x), len(obs)))
        gz = special.ndtri(np.maximum(w[1], 1e-300))
        if kernels.use():
            from .kernels import xi_move

            return xi_move(x, x if prev is None else prev, np.cos(obs), np.sin(obs), w[0], w[1], gz,
                           self.model.gamma, self._s, self.first, self._idx, self._prior)
        c, sn, a, u, m, s = self.frame(x, obs, prev)
        a = np.maximum(a, 1e-12)
        parts = self.mixture(a, m, s)
        log_p1, _, delta0, g, lo, hi, u_b, s_b = parts
        u_t = a * np.tan(delta0 + g * np.tan(lo + w[1] * (hi - lo)))
        u_z = np.where(w[0] < np.exp(log_p1), u_t, u_b + s_b * gz)
        log_q = np.sum(self._log_mix(u_z, a, parts), axis=1)
        log_alpha = np.sum(_norm_logpdf(u, m, s), axis=1)
        du = u_z - u
        dp = np.empty(du.shape + (2,))
        dp[..., 0], dp[..., 1] = -du * sn, du * c
        return self.with_local(x, x[:, self.model.pos_idx] + dp.reshape(len(x), -1)), log_alpha, log_q

    def logpdf(self, z, x, obs, prev=None):
        """``log π(u_Z)`` of states ``z`` that :meth:`sample` could have drawn from ``x``, ``(N,)``."""
        c, sn, a, _, m, s = self.frame(x, np.asarray(obs, dtype=float), prev)
        a = np.maximum(a, 1e-12)
        u_z = z[:, self._iy] * c - z[:, self._ix] * sn
        return np.sum(self._log_mix(u_z, a, self.mixture(a, m, s)), axis=1)

    def look_ahead(self, prev, obs, kernel=None):
        """First-stage log weights ``log p̂(y | Z_{t-1}) (N,)``: the two masses of :meth:`parts` at the mean
        prediction's along-ray coordinate (the fully adapted auxiliary filter's first stage,
        App. B); ``None`` on the first step, where every particle is a fresh prior draw."""
        if self.first:
            return None
        obs = np.asarray(obs, dtype=float)
        if kernels.use():
            from .kernels import xi_look_ahead

            return xi_look_ahead(prev, np.cos(obs), np.sin(obs), self.model.gamma, self._s, self._idx)
        qx, qy = prev[:, self._ix] + prev[:, self._vx], prev[:, self._iy] + prev[:, self._vy]
        c, sn = np.cos(obs), np.sin(obs)
        a = np.maximum(qx * c + qy * sn, 1e-12)
        log_m1, log_m2, _, _ = self.parts(a, qy * c - qx * sn, self._s)
        return np.sum(np.logaddexp(log_m1, log_m2), axis=1)
