"""Bearings-only ship tracking (thesis 001, §1.3.3 and §4.5.5).

Per ship the state is ``(x1, x2, x3, x4)``: vertical position and velocity,
horizontal position and velocity, in a frame fixed to the observer. Dynamics
``X_{t+1} = F X_t + G xi_t``, ``xi_t ~ N(0, sigma_eta^2 I_2)``; observation the
bearing ``theta = atan2(x3, x1)`` with wrapped-Cauchy noise

    r(y|theta) = (1 - rho^2) / (2 pi (1 + rho^2 - 2 rho cos(y - theta))).

``M`` ships move independently; the state is ``(N, 4M)`` (ship ``k`` in columns
``4k..4k+3``) and the likelihood is the product over ships (§4.5.5).

The noise enters through ``G`` only, so ``K`` lives on a 2-D affine subspace per
ship; :meth:`Bearings.transition_logpdf` is the density of ``xi`` recovered
from the velocity change, and :meth:`Bearings.with_local` moves the position
and adjusts the velocity deterministically (``Δv = 2 Δp``) so that perturbed
particles stay on that subspace — the "velocity adjusted deterministically
with the position" of §4.5.5.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize, special

from ...core.gaussian import diag_logpdf
from ...core.transition import is_prior
from ...proposals import GaussMixtureProposal, Window
from ..partitions import IndependentTargets
from .xi import XiProposal

__all__ = ["Bearings", "LIS_PROPOSALS", "wrapped_cauchy_logpdf", "gaussian_fit_to_cauchy", "simulate"]

F = np.array([[1.0, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]])
G = np.array([[0.5, 0], [1, 0], [0, 0.5], [0, 1]])

#: prior means of ships 1-3 (§1.3.3 and §4.5.5)
SHIP_MEANS = np.array(
    [
        [-0.05, 0.001, 0.2, -0.055],
        [0.02, -0.01, 0.6, -0.055],
        [0.05, -0.01, -0.2, -0.02],
    ]
)
#: prior covariance diagonal, 0.001 * (0.5^2, 0.005^2, 0.3^2, 0.01^2)
PRIOR_VAR = 0.001 * np.array([0.5**2, 0.005**2, 0.3**2, 0.01**2])

#: LIS proposals of :meth:`Bearings.lis_proposal`
LIS_PROPOSALS = ("xi", "position")

_POS = np.array([0, 2])
_VEL = np.array([1, 3])


def wrapped_cauchy_logpdf(delta, one_minus_rho):
    """Log wrapped-Cauchy density at angle difference ``delta``, stably.

    Uses ``1 + rho^2 - 2 rho cos d = (1 - rho)^2 + 4 rho sin^2(d / 2)`` and
    ``1 - rho^2 = (1 - rho)(1 + rho)`` with ``1 - rho`` given directly, so that no
    digits are lost when ``rho`` is within ``1e-5`` of one.
    """
    e = one_minus_rho
    rho = 1.0 - e
    s = np.sin(0.5 * np.asarray(delta))
    return np.log(e * (1.0 + rho)) - np.log(2 * np.pi) - np.log(e * e + 4.0 * rho * s * s)


def gaussian_fit_to_cauchy(gamma):
    """Standard deviation of the Gaussian closest in L2 to a Cauchy of scale ``gamma``.

    Minimises ``∫ (N(x; 0, s^2) - C(x; gamma))^2 dx``; with ``z = gamma/(s sqrt 2)`` the
    cross term is ``erfcx(z) / (s sqrt(2 pi))`` (the Voigt profile at 0). The
    answer is ``c * gamma`` with a constant ``c``.
    """

    def dist(log_c):
        s = np.exp(log_c)
        return 1.0 / (2 * s * np.sqrt(np.pi)) - 2.0 * special.erfcx(1.0 / (s * np.sqrt(2))) / (
            s * np.sqrt(2 * np.pi)
        )

    res = optimize.minimize_scalar(dist, bounds=(-3.0, 3.0), method="bounded")
    return float(np.exp(res.x)) * gamma


def ship_means(m):
    """Prior means for ``m`` ships: the thesis's three, then ships on a circle (Fig. 4.31)."""
    if m <= 3:
        return SHIP_MEANS[:m].copy()
    phi = 2 * np.pi * np.arange(m) / m
    radius, speed = 0.2, 0.0055  # velocity tangent to the circle
    return np.stack(
        [radius * np.cos(phi), -speed * np.sin(phi), radius * np.sin(phi), speed * np.cos(phi)],
        axis=1,
    )


class Bearings(IndependentTargets):
    """Bearings-only tracking of ``ships`` independent ships: one partition per ship
    (:class:`~vistrack.models.partitions.IndependentTargets`, App. C).

    Parameters
    ----------
    ships : int
        Number ``M`` of ships; the state has ``4 M`` components.
    sigma_eta : float
        Process noise standard deviation (0.001).
    one_minus_rho : float
        ``1 - rho`` of the wrapped Cauchy (``0.005**2``).
    kappa : float
        LIS proposal: variance ratio along/across the observed bearing (100).
    sigma_g : float
        LIS window standard deviation on each position coordinate (0.0005).
    proposal : {"xi", "position"}
        LIS's local proposal (:meth:`lis_proposal`): the move of the noise ``ξ`` across the
        observed bearing with its first stage (default), or §4.5.5's position move.
    means : array_like of shape (M, 4), optional
        Prior means; default :func:`ship_means`.
    """

    def __init__(self, ships=1, *, sigma_eta=1e-3, one_minus_rho=0.005**2, kappa=100.0, sigma_g=5e-4, means=None,
                 proposal="xi"):
        if ships < 1:
            raise ValueError(f"need at least one ship, got {ships}")
        if proposal not in LIS_PROPOSALS:
            raise ValueError(f"LIS proposal must be one of {', '.join(LIS_PROPOSALS)}, got {proposal!r}")
        self.ships = int(ships)
        self.dim = 4 * self.ships
        self.sigma_eta = float(sigma_eta)
        self.one_minus_rho = float(one_minus_rho)
        self.kappa = float(kappa)
        self.sigma_g = float(sigma_g)
        self.proposal = proposal
        self.prior_mean = (ship_means(self.ships) if means is None else np.asarray(means, float)).reshape(-1)
        self.prior_std = np.sqrt(np.tile(PRIOR_VAR, self.ships))
        # Wrapped Cauchy with rho = exp(-gamma) is the wrapped Cauchy(0, gamma).
        self.gamma = -np.log1p(-self.one_minus_rho)
        self.sigma_angle = gaussian_fit_to_cauchy(self.gamma)
        self.pos_idx = (4 * np.arange(self.ships)[:, None] + _POS).reshape(-1)
        self.vel_idx = (4 * np.arange(self.ships)[:, None] + _VEL).reshape(-1)
        self.partitions = tuple(np.arange(4 * k, 4 * k + 4) for k in range(self.ships))
        self._targets = {}

    # -- the model contract ---------------------------------------------------
    def sample_prior(self, n, rng):
        """``n`` draws ``(n, 4M)`` from ``p_0``: independent Gaussians about the ship means (§4.5.5,
        :data:`PRIOR_VAR`)."""
        return self.prior_mean + self.prior_std * rng.standard_normal((n, self.dim))

    def prior_logpdf(self, states):
        """``log p_0`` (diagonal Gaussian)."""
        return diag_logpdf(states, self.prior_mean, self.prior_std)

    def predict_mean(self, states):
        """``F X`` per ship: the mean of ``K``, ``(N, 4M)`` -> ``(N, 4M)`` (AVPF's first stage)."""
        s = states.reshape(len(states), self.ships, 4)
        return (s @ F.T).reshape(len(states), self.dim)

    def predict(self, states, rng):
        """``X_{t+1} = F X_t + G ξ_t``, ``ξ_t ~ N(0, σ_η² I_2)`` per ship (§1.3.3); ``(N, 4M)`` -> ``(N, 4M)``."""
        xi = self.sigma_eta * rng.standard_normal((len(states), self.ships, 2))
        return self.predict_mean(states) + (xi @ G.T).reshape(len(states), self.dim)

    def transition_logpdf(self, new, old):
        """``log K(new|old)`` as the density of ``xi = v_new - v_old`` (on the support of K)."""
        xi = new[:, self.vel_idx] - old[:, self.vel_idx]
        k = xi.shape[1]
        return -0.5 * np.sum(xi * xi, axis=1) / self.sigma_eta**2 - k * (
            np.log(self.sigma_eta) + 0.5 * np.log(2 * np.pi)
        )

    def bearing(self, states):
        """True bearings ``atan2(x3, x1)`` per ship, shape ``(N, M)``."""
        return np.arctan2(states[:, self.pos_idx[1::2]], states[:, self.pos_idx[0::2]])

    def loglik(self, obs, states):
        """``sum_k log r(y_k | theta_k)``; ``obs`` of shape ``(M,)``."""
        d = np.asarray(obs)[None, :] - self.bearing(states)
        return np.sum(wrapped_cauchy_logpdf(d, self.one_minus_rho), axis=1)

    def sample_observation(self, states, rng):
        """Bearings with wrapped-Cauchy noise (a Cauchy(0, gamma) draw wrapped to (-pi, pi])."""
        theta = self.bearing(states)
        noise = self.gamma * np.tan(np.pi * (rng.random(theta.shape) - 0.5))
        return np.angle(np.exp(1j * (theta + noise)))

    def positions(self, states):
        """Ship positions ``(N, M, 2)`` as ``(x1, x3)``."""
        return states[:, self.pos_idx].reshape(len(states), self.ships, 2)

    # -- local coordinates: the position of every ship -------------------------
    def local_coords(self, states):
        """The positions ``(x1, x3)`` of every ship, ``(N, 4M)`` -> ``(N, 2M)`` (§4.5.5)."""
        return states[:, self.pos_idx]

    def with_local(self, states, u):
        """Move positions to ``u``; velocities follow with ``Δv = 2 Δp`` (stays on supp K)."""
        out = states.copy()
        delta = u - states[:, self.pos_idx]
        out[:, self.pos_idx] = u
        out[:, self.vel_idx] += 2.0 * delta
        return out

    def with_local_prior(self, states, u):
        """Move positions to ``u`` keeping velocities (first step, where ``p_0`` is non-degenerate)."""
        out = states.copy()
        out[:, self.pos_idx] = u
        return out

    def local_mixture(self, obs, states):
        """LIS proposal of §4.5.5: one Gaussian per ship (a product over ships).

        Per ship: mean the predicted position projected onto the observed
        bearing ray; covariance ``U diag(kappa s^2, s^2) U^T`` with ``U`` the
        rotation by the bearing and ``s = R * sigma_angle`` the Gaussian fit of the
        wrapped Cauchy converted to distance at the predicted range ``R``.

        Returns ``log_p (N, M, 1)``, ``mu (N, M, 1, 2)``, ``cov (N, M, 1, 2, 2)``.
        """
        n, m = len(states), self.ships
        p = self.positions(states)  # (N, M, 2)
        d = np.stack([np.cos(obs), np.sin(obs)], axis=-1)  # (M, 2) unit vectors along the rays
        along = np.maximum(np.einsum("nmk,mk->nm", p, d), 0.0)
        mean = along[..., None] * d  # (N, M, 2)
        var = (np.maximum(np.hypot(p[..., 0], p[..., 1]), 1e-9) * self.sigma_angle) ** 2  # (N, M)
        dd = d[:, :, None] * d[:, None, :]  # (M, 2, 2) projector onto the ray
        shape = (self.kappa - 1.0) * dd + np.eye(2)  # kappa along the ray, 1 across
        cov = var[..., None, None] * shape
        return np.zeros((n, m, 1)), mean[:, :, None, :], cov[:, :, None]

    def window_std(self, kernel=None):
        """Window std per position coordinate: ``sigma_g``, matched to the spread of ``K``
        (position noise ``sigma_eta / 2``); on the first step, where ``p_0`` is the
        prediction density, the prior's position std (same rule, §4.4.1)."""
        if is_prior(kernel):
            return self.prior_std[self.pos_idx]
        return np.full(2 * self.ships, self.sigma_g)

    def lis_proposal(self, kernel=None):
        """LIS's local proposal: the ``ξ`` move across the observed bearing with a first stage
        (:class:`~vistrack.models.bearings.xi.XiProposal`), or with ``proposal="position"`` the
        §4.5.5 proposal with a Gaussian window (:meth:`window_std`) per ship."""
        if self.proposal == "xi":
            return XiProposal(self, kernel)
        var = self.window_std(kernel).reshape(self.ships, 2) ** 2
        return GaussMixtureProposal(self, var[:, :, None] * np.eye(2), kernel)

    def lls_window(self, kernel=None):
        """Gaussian window of std ``sigma_g`` on positions (for LLS)."""
        return Window("gaussian", self.window_std(kernel), grid=7)

    def target_model(self, j):
        """Ship ``j`` alone: a one-ship model with this model's parameters (its partition)."""
        if j not in self._targets:
            self._targets[j] = Bearings(1, sigma_eta=self.sigma_eta, one_minus_rho=self.one_minus_rho, kappa=self.kappa,
                                        sigma_g=self.sigma_g, means=self.prior_mean[self.partitions[j]][None],
                                        proposal=self.proposal)
        return self._targets[j]

    def target_obs(self, obs, j):
        """Ship ``j``'s bearing ``(1,)`` of ``obs (M,)``."""
        return np.asarray(obs)[j:j + 1]

    # -- one ship per particle (StackedPartitions) -----------------------------
    def sample_prior_parts(self, states, parts, rng):
        """Row ``i``'s ship ``parts[i]`` from its prior, ``(N, 4)``."""
        cols = self.part_columns[parts]
        return self.prior_mean[cols] + self.prior_std[cols] * rng.standard_normal(cols.shape)

    def predict_parts(self, states, parts, rng):
        """Row ``i``'s ship ``parts[i]`` moved by ``K`` (the same for every ship), ``(N, 4)``."""
        return self.target_model(0).predict(self.gather_parts(states, parts), rng)

    def loglik_parts(self, obs, x, states, parts):
        """``log r(y_j | θ_j)`` of row ``i``'s ship ``j = parts[i]`` (its state ``x[i]``), ``(N,)``."""
        return wrapped_cauchy_logpdf(np.asarray(obs)[parts] - np.arctan2(x[:, 2], x[:, 0]), self.one_minus_rho)

    # -- errors ---------------------------------------------------------------
    def position_error(self, estimate, truth):
        """Euclidean position error averaged over ships (§4.5.5)."""
        pe = self.positions(np.atleast_2d(estimate))
        pt = self.positions(np.atleast_2d(truth))
        return np.mean(np.linalg.norm(pe - pt, axis=-1), axis=-1)


def simulate(model, steps, rng, x0=None):
    """Simulate ``steps`` steps of ``model`` (the true ``x_1`` fixed at the prior mean, as in
    Gordon et al. 1993; thesis 001 §4.5.5).

    Returns
    -------
    states : ndarray (steps, d)
        ``x_1 .. x_T``; ``x_1`` is ``x0`` or the prior mean.
    obs : ndarray (steps, M)
        ``y_1 .. y_T``.
    """
    x = np.array(model.prior_mean if x0 is None else x0, dtype=float)[None, :]
    states, obs = [], []
    for t in range(steps):
        if t > 0:
            x = model.predict(x, rng)
        states.append(x[0])
        obs.append(model.sample_observation(x, rng)[0])
    return np.array(states), np.array(obs)
