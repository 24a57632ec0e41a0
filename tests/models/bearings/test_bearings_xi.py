"""The ξ proposal of the bearings model (vistrack.models.bearings.xi): its density matches its
samples, LIS with it is properly weighted (the mean weight is p(y | Z_{t-1}), by quadrature),
moves stay on the support of K, the same seed gives the same output, and the compiled kernels
(vistrack.models.bearings.kernels) equal the numpy path."""

import numpy as np
import pytest

from vistrack import kernels
from vistrack.data_synth.bearings_sequence import simulate
from vistrack.filters import LIS, filter_steps
from vistrack.models.bearings.model import Bearings, wrapped_cauchy_logpdf
from vistrack.models.bearings.xi import XiProposal
from vistrack.registry import make_filter

MODEL = Bearings(1)
S = 0.5 * MODEL.sigma_eta  # the position's noise std under K
PREV = np.array([-0.05, 0.002, 0.2, -0.05])


def ray(angle):
    """Unit vectors along and across the ray at ``angle``."""
    return np.array([np.cos(angle), np.sin(angle)]), np.array([-np.sin(angle), np.cos(angle)])


def obs_at_offset(pos, offset):
    """The bearing whose ray passes ``offset`` (across) from the point ``pos``."""
    return np.array([np.arctan2(pos[1], pos[0]) - np.arcsin(offset / np.hypot(*pos))])


def u_grid(a, m, s):
    """Abscissae resolving the Cauchy peak on the ray (scale ``γ a``) and the Gaussian about ``m``."""
    g = MODEL.gamma
    phi_max = np.arctan(0.5 * np.pi / g)
    peak = a * np.tan(g * np.tan(np.linspace(-phi_max, phi_max, 20001)[1:-1]))
    bulk = m + s * np.linspace(-12, 12, 2001)
    return np.unique(np.concatenate([peak[np.abs(peak) < 1.0], bulk]))


def states_at(x0, angle, u):
    """``x0`` with its position moved across the ray to the across-ray coordinates ``u``."""
    d, n = ray(angle)
    a = x0[[0, 2]] @ d
    z = np.repeat(x0[None], len(u), 0)
    z[:, [0, 2]] = a * d + u[:, None] * n
    return z


@pytest.mark.parametrize("first, offset", [(False, 0.5), (False, 4.0), (True, 0.5)])
def test_density_matches_samples(first, offset):
    """The empirical CDF of the drawn across-ray coordinate is the integral of ``logpdf``, and
    ``sample``'s ``log_q`` is ``logpdf`` of what it drew."""
    f = LIS(MODEL)
    kernel = f.prior_kernel if first else f.kernel
    prop = f.part("proposal", kernel)
    x0 = MODEL.predict(PREV[None], np.random.default_rng(1))[0]
    y = obs_at_offset(x0[[0, 2]] if first else PREV[[0, 2]] + PREV[[1, 3]], offset * S)
    n = 40_000
    x, prev = np.repeat(x0[None], n, 0), np.repeat(PREV[None], n, 0)
    z, _, log_q = prop.sample(x, y, np.random.default_rng(2), prev)
    np.testing.assert_allclose(log_q, prop.logpdf(z, x, y, prev), rtol=1e-12, atol=1e-9)
    _, nrm = ray(y[0])
    u = z[:, [0, 2]] @ nrm
    _, _, a, _, m, s = prop.frame(x[:1], y, prev[:1])
    grid = u_grid(a.item(), np.ravel(m)[0], np.ravel(s)[0])
    xg, pg = np.repeat(x0[None], len(grid), 0), np.repeat(PREV[None], len(grid), 0)
    dens = np.exp(prop.logpdf(states_at(x0, y[0], grid), xg, y, pg))
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(grid))])
    assert cdf[-1] == pytest.approx(1.0, abs=2e-3)
    checks = np.quantile(u, [0.01, 0.05, 0.2, 0.4, 0.5, 0.6, 0.8, 0.95, 0.99])
    emp = np.array([np.mean(u <= t) for t in checks])
    assert np.interp(checks, grid, cdf) == pytest.approx(emp, abs=5 * np.sqrt(0.25 / n) + 2e-3)


def evidence(a_mean, a_std, m_of_a, s, angle, nodes=24):
    """``p(y | Z_{t-1})`` by quadrature: Gauss-Hermite over the along-ray coordinate, the
    trapezoid over the across-ray one (``m_of_a(a)`` its conditional mean)."""
    t, w = np.polynomial.hermite_e.hermegauss(nodes)
    total = 0.0
    for ti, wi in zip(t, w / np.sqrt(2 * np.pi)):
        a = a_mean + a_std * ti
        m = m_of_a(a)
        u = u_grid(a, m, s)
        f = np.exp(-0.5 * ((u - m) / s) ** 2) / (s * np.sqrt(2 * np.pi))
        f *= np.exp(wrapped_cauchy_logpdf(np.arctan2(u, a), MODEL.one_minus_rho))
        total += wi * np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(u))
    return total


@pytest.mark.parametrize("offset", [0.0, 3.0, 4.0])
def test_lis_step_is_properly_weighted(offset):
    """From one previous state the mean LIS increment is ``p(y|Z_{t-1}) = E_K r(y|X)``."""
    q = PREV[[0, 2]] + PREV[[1, 3]]
    y = obs_at_offset(q, offset * S)
    d, nrm = ray(y[0])
    exact = evidence(q @ d, S, lambda a: q @ nrm, S, y[0])
    f = LIS(MODEL)
    n = 50_000
    _, log_incr, _, _ = f.propose(np.repeat(PREV[None], n, 0), y, np.random.default_rng(3), f.kernel)
    w = np.exp(log_incr)
    assert w.mean() == pytest.approx(exact, abs=5 * w.std() / np.sqrt(n))
    assert w.mean() ** 2 / np.mean(w * w) > 0.95  # near the optimal proposal: ESS over 95 % of N
    # the first stage predicts the weight
    assert np.exp(f.part("proposal", f.kernel).look_ahead(PREV[None], y)[0]) == pytest.approx(exact, rel=0.1)


def test_first_step_is_properly_weighted():
    """On the first step the mean increment is ``p(y) = E_{p_0} r(y|X_1)``."""
    mu, var = MODEL.prior_mean[[0, 2]], MODEL.prior_std[[0, 2]] ** 2
    y = obs_at_offset(mu, 0.005)
    d, nrm = ray(y[0])
    vdd, vdn, vnn = var @ d**2, var @ (d * nrm), var @ nrm**2
    exact = evidence(mu @ d, np.sqrt(vdd), lambda a: mu @ nrm + vdn / vdd * (a - mu @ d),
                     np.sqrt(vnn - vdn**2 / vdd), y[0])
    f = LIS(MODEL)
    n = 50_000
    _, log_incr, _, _ = f.propose(np.zeros((n, 4)), y, np.random.default_rng(4), f.prior_kernel)
    w = np.exp(log_incr)
    assert w.mean() == pytest.approx(exact, abs=5 * w.std() / np.sqrt(n))


def test_moves_stay_on_the_support_of_k():
    """Only the noise across the ray changes: the along-ray noise and ``Δv = 2 Δp`` hold."""
    rng = np.random.default_rng(5)
    m = Bearings(3)
    prev = m.sample_prior(200, rng)
    x = m.predict(prev, rng)
    y = m.sample_observation(x[:1], rng)[0]
    z, log_alpha, log_q = XiProposal(m).sample(x, y, rng, prev)
    xi_x = (x - m.predict_mean(prev))[:, m.vel_idx].reshape(200, 3, 2)
    xi_z = (z - m.predict_mean(prev))[:, m.vel_idx].reshape(200, 3, 2)
    d = np.stack([np.cos(y), np.sin(y)], -1)
    np.testing.assert_allclose(np.einsum("nmk,mk->nm", xi_z, d), np.einsum("nmk,mk->nm", xi_x, d), rtol=0, atol=1e-15)
    pos_from_xi = (prev[:, m.pos_idx] + prev[:, m.vel_idx] + 0.5 * (z - prev)[:, m.vel_idx])
    np.testing.assert_allclose(z[:, m.pos_idx], pos_from_xi, rtol=0, atol=1e-15)
    assert np.all(np.isfinite(log_alpha)) and np.all(np.isfinite(log_q))


@pytest.mark.parametrize("proposal", ["xi", "position"])
def test_same_seed_same_output(proposal):
    m = Bearings(2, proposal=proposal)
    _, ys = simulate(m, 5, np.random.default_rng(0))
    f = make_filter("lis", m)
    runs = [[p.states for p in filter_steps(f, ys, 30, np.random.default_rng(9))] for _ in range(2)]
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


def test_unknown_proposal_is_one_clear_error():
    with pytest.raises(ValueError, match="LIS proposal must be one of xi, position, got 'nope'"):
        Bearings(1, proposal="nope")


@pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")
@pytest.mark.parametrize("ships, first", [(1, False), (3, False), (3, True)])
def test_compiled_kernels_equal_the_numpy_path(ships, first):
    """vistrack.models.bearings.kernels: the same draws, the same moves and densities (1e-12 relative)."""
    m = Bearings(ships)
    rng = np.random.default_rng(0)
    prev = m.sample_prior(200, rng)
    x = m.sample_prior(200, rng) if first else m.predict(prev, rng)
    y = m.sample_observation(x[:1], rng)[0]
    f = LIS(m)
    prop = f.part("proposal", f.prior_kernel if first else f.kernel)
    outs = []
    for numpy_path in (True, False):
        with kernels.numpy_paths(numpy_path):
            outs.append((*prop.sample(x, y, np.random.default_rng(1), prev), prop.look_ahead(prev, y)))
    (z0, la0, lq0, ahead0), (z1, la1, lq1, ahead1) = outs
    np.testing.assert_allclose(z1, z0, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(la1, la0, rtol=1e-12)
    np.testing.assert_allclose(lq1, lq0, rtol=1e-12)
    assert (ahead0 is None) == first and (first or np.allclose(ahead1, ahead0, rtol=1e-12, atol=0))
