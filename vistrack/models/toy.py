"""A 1-D Gaussian random walk with a Gauss-mixture likelihood (thesis 001, Figs. 4.1, 4.9), and
its AR(2) form for the history-sampling filters (§3.2).

The known-answer problem for proper weighting: the prediction ``p`` is Gaussian
and the likelihood ``f`` a Gauss mixture, so the posterior ``f p / I(f p)`` is a
Gauss mixture in closed form (Appendix D).
"""

from __future__ import annotations

import numpy as np

from ..core.gaussian import diag_logpdf, gaussian_product
from ..proposals import GaussMixtureProposal, Window
from .innovation import ARInnovation

__all__ = ["GaussMixtureToy", "AR2Toy", "GaussProposal"]


class GaussMixtureToy:
    """``x_t = x_{t-1} + N(0, q)``, ``r(y|x) = Σ_i p_i N(x; mu_i, s_i^2)`` (``obs`` ignored).

    Parameters
    ----------
    prior_mean, prior_var : float
        ``p_0``.
    q : float
        Process noise variance.
    weights, means, stds : array_like
        The likelihood mixture (fixed, peaky: the "curse of reliable observations").
    window : float
        Window scale for LLS (box half-width) and LIS (Gaussian std).
    """

    dim = 1

    def __init__(self, prior_mean=0.0, prior_var=1.0, q=1.0, weights=(0.3, 0.7), means=(-1.0, 1.5),
                 stds=(0.05, 0.02), window=0.5):
        self.prior_mean = float(prior_mean)
        self.prior_var = float(prior_var)
        self.q = float(q)
        w = np.asarray(weights, float)
        self.log_p = np.log(w / w.sum())
        self.mu = np.asarray(means, float)
        self.var = np.asarray(stds, float) ** 2
        self.window = float(window)

    def sample_prior(self, n, rng):
        """``n`` draws ``(n, 1)`` from ``p_0 = N(prior_mean, prior_var)``."""
        return self.prior_mean + np.sqrt(self.prior_var) * rng.standard_normal((n, 1))

    def prior_logpdf(self, states):
        """``log p_0`` of ``states (N, 1)`` -> ``(N,)``."""
        d = states[:, 0] - self.prior_mean
        return -0.5 * d * d / self.prior_var - 0.5 * np.log(2 * np.pi * self.prior_var)

    def predict(self, states, rng):
        """``x_t = x_{t-1} + N(0, q)``; ``(N, 1)`` -> ``(N, 1)``."""
        return states + np.sqrt(self.q) * rng.standard_normal(states.shape)

    def predict_mean(self, states):
        """The mean of ``K``: the states themselves, ``(N, 1)``."""
        return states.copy()

    def transition_logpdf(self, new, old):
        """``log N(new; old, q)`` row by row, ``(N,)``."""
        d = (new - old)[:, 0]
        return -0.5 * d * d / self.q - 0.5 * np.log(2 * np.pi * self.q)

    def loglik(self, obs, states):
        """``log Σ_i p_i N(x; μ_i, s_i²)`` of ``states (N, 1)`` -> ``(N,)`` (``obs`` ignored)."""
        x = states[:, :1]
        comp = self.log_p - 0.5 * (x - self.mu) ** 2 / self.var - 0.5 * np.log(2 * np.pi * self.var)
        mx = comp.max(axis=1, keepdims=True)
        return (mx + np.log(np.exp(comp - mx).sum(axis=1, keepdims=True)))[:, 0]

    def local_coords(self, states):
        """The state is its own local coordinate: ``(N, 1)``."""
        return states[:, :1]

    def with_local(self, states, u):
        """The states ``(N, 1)`` set to ``u``."""
        return np.asarray(u, float).reshape(len(states), 1)

    with_local_prior = with_local  # the state is its local coordinate

    def local_mixture(self, obs, states):
        """``q = f`` itself: LIS with this proposal is exact LLS (§4.5)."""
        n, k = len(states), len(self.mu)
        return (np.broadcast_to(self.log_p, (n, 1, k)), np.broadcast_to(self.mu[:, None], (n, 1, k, 1)),
                np.broadcast_to(self.var[:, None, None], (n, 1, k, 1, 1)))

    def lis_proposal(self, kernel=None):
        """LIS with ``q = f`` and a Gaussian window of std ``window`` (Fig. 4.17; exact LLS)."""
        return GaussMixtureProposal(self, np.array([[self.window**2]]), kernel)

    def lls_window(self, kernel=None):
        """LLS's box window of half-width ``window``, 41 cells."""
        return Window("box", [self.window], grid=41)

    def posterior(self, x_prev):
        """Exact ``f p / I(f p)`` for ``p = N(x_prev, q)``: ``(log weights, means, variances)``."""
        mu, cov, log_c = gaussian_product(self.mu[:, None], self.var[:, None, None],
                                          np.full((len(self.mu), 1), x_prev), np.full((len(self.mu), 1, 1), self.q))
        lw = self.log_p + log_c
        lw -= np.max(lw)
        lw -= np.log(np.sum(np.exp(lw)))
        return lw, mu[:, 0], cov[:, 0, 0]


class GaussProposal:
    """An image-only proposal ``N(mean, std²)`` on ``X_{t,1a}`` (ignores ``obs``)."""

    def __init__(self, mean, std):
        self.mean, self.std = np.atleast_1d(np.asarray(mean, float)), np.atleast_1d(np.asarray(std, float))

    def sample(self, n, obs, rng):
        """``n`` draws ``(n, 1)`` of the fixed Gaussian (the observation is ignored)."""
        return self.mean + self.std * rng.standard_normal((n, len(self.mean)))

    def logpdf(self, x, obs):
        """Its log-density at ``x (n, 1)``, ``(n,)``."""
        return diag_logpdf(x, self.mean, self.std)


class AR2Toy(ARInnovation, GaussMixtureToy):
    """A 1-D AR(2) toy with a closed-form posterior for the history-sampling filters (§3.2).

    State ``(u_t, u_{t-1})``, or with ``rest=True`` ``(u_t, v_t, u_{t-1}, v_{t-1})``:
    ``u_t = u_{t-1} + a (u_{t-1} - u_{t-2}) + N(0, q)``; ``v_t`` (the ``1b`` part, which ``r``
    does not see) the same with noise ``q_v``. ``r(y | X) = Σ_i p_i N(u_t; μ_i, s_i²)`` as
    :class:`GaussMixtureToy`'s; ``p_0``: ``u ~ N(prior_mean, prior_var)`` (``v ~ N(0, 1)``) at
    rest; the image-only proposal :class:`GaussProposal` on ``u``.
    """

    subspace_dim = 1

    def __init__(self, a=0.5, q=0.09, q_v=0.25, rest=False, proposal=(0.5, 1.5), **kwargs):
        super().__init__(q=q, **kwargs)
        self.k = 2 if rest else 1
        self.dim = 2 * self.k
        self.damping = np.full(self.k, float(a))
        self.noise_std = np.sqrt([q, q_v][:self.k])
        self.init_pose = np.array([self.prior_mean, 0.0][:self.k])
        self.prior_std = np.array([np.sqrt(self.prior_var), 1.0][:self.k])
        self.proposal = GaussProposal(*proposal)

    def innovation_std(self, old):
        """Std ``(N, 1)`` of the innovation given ``old``."""
        return np.broadcast_to(self.noise_std, (len(old), self.k))

    def predict_mean(self, states):
        """The mean of ``K(.|states)``, ``(N, 2)``: AR(2) on the current value, the history its old value."""
        z1, z2 = states[:, :self.k], states[:, self.k:]
        return np.concatenate([z1 + self.damping * (z1 - z2), z1], axis=1)

    def predict(self, states, rng):
        """A draw ``(N, 2)`` from ``K(.|states)``."""
        out = self.predict_mean(states)
        out[:, :self.k] += self.noise_std * rng.standard_normal((len(states), self.k))
        return out

    def transition_logpdf(self, new, old):
        """``log K(new|old)`` per particle, ``(N,)``."""
        return diag_logpdf(new[:, :self.k], self.predict_mean(old)[:, :self.k], self.noise_std)

    def sample_prior(self, n, rng):
        """``n`` draws ``(n, 2)`` from ``p_0``."""
        return self.join_prior(self.init_pose + self.prior_std * rng.standard_normal((n, self.k)))

    def prior_logpdf(self, states):
        """``log p_0`` per state, ``(N,)``."""
        return diag_logpdf(states[:, :self.k], self.init_pose, self.prior_std)

    def innovation_proposal(self, kernel=None):
        """The innovation's image-only proposal: a fixed Gaussian (:class:`GaussProposal`)."""
        return self.proposal
