"""Bearings-only model (thesis §1.3.3, §4.5.5): stable likelihood, LIS proposal geometry, tracking, seeds."""

import numpy as np
import pytest
from scipy import integrate

from vistrack.core.particles import ParticleSet
from vistrack.data_synth.bearings_sequence import simulate
from vistrack.filters import filter_steps
from vistrack.models.bearings.model import Bearings, gaussian_fit_to_cauchy, wrapped_cauchy_logpdf
from vistrack.registry import make_filter


def naive_logpdf(d, rho):
    return np.log((1 - rho**2) / (2 * np.pi * (1 + rho**2 - 2 * rho * np.cos(d))))


def test_thesis_parameters():
    m = Bearings(1)
    assert m.sigma_eta == 1e-3
    assert 1 - m.one_minus_rho == 1 - 0.005**2
    assert m.prior_mean == pytest.approx([-0.05, 0.001, 0.2, -0.055])
    assert m.prior_std**2 == pytest.approx(0.001 * np.array([0.5**2, 0.005**2, 0.3**2, 0.01**2]))
    assert m.kappa == 100 and m.sigma_g == 5e-4
    m3 = Bearings(3)
    assert m3.prior_mean[4:] == pytest.approx([0.02, -0.01, 0.6, -0.055, 0.05, -0.01, -0.2, -0.02])


def test_wrapped_cauchy_matches_naive_form_for_moderate_rho():
    d = np.linspace(-np.pi, np.pi, 101)
    assert wrapped_cauchy_logpdf(d, 0.5) == pytest.approx(naive_logpdf(d, 0.5))


def test_wrapped_cauchy_is_a_density_even_when_very_peaky():
    e = 0.005**2
    peak = [-1e-3, -1e-4, 0.0, 1e-4, 1e-3]
    total = sum(
        integrate.quad(lambda t: np.exp(wrapped_cauchy_logpdf(t, e)), a, b, limit=200)[0]
        for a, b in zip([-np.pi] + peak, peak + [np.pi])
    )
    assert total == pytest.approx(1.0, rel=1e-6)
    at0 = wrapped_cauchy_logpdf(0.0, e)
    assert at0 == pytest.approx(np.log((2 - e) / (2 * np.pi * e)), rel=1e-12)
    assert np.isfinite(wrapped_cauchy_logpdf(np.pi, e))


def test_gaussian_fit_minimises_l2_distance():
    gamma = 2.5e-5
    s = gaussian_fit_to_cauchy(gamma)

    def l2(sig):
        x = np.linspace(-200 * gamma, 200 * gamma, 400001)
        g = np.exp(-0.5 * (x / sig) ** 2) / (sig * np.sqrt(2 * np.pi))
        c = gamma / (np.pi * (x**2 + gamma**2))
        return np.sum((g - c) ** 2) * (x[1] - x[0])

    assert l2(s) < l2(0.9 * s) and l2(s) < l2(1.1 * s)


def test_local_moves_stay_on_the_support_of_k(rng):
    m = Bearings(2)
    prev = m.sample_prior(50, rng)
    x = m.predict(prev, rng)
    z = m.with_local(x, m.local_coords(x) + 1e-3 * rng.standard_normal((50, 4)))
    xi = z[:, m.vel_idx] - prev[:, m.vel_idx]
    pos_from_xi = prev[:, m.pos_idx] + prev[:, m.vel_idx] + 0.5 * xi
    assert z[:, m.pos_idx] == pytest.approx(pos_from_xi, abs=1e-15)
    # K(x|prev) is the density of the noise xi that produced x
    xi_x = (x - m.predict_mean(prev))[:, m.vel_idx]
    expect = -0.5 * np.sum(xi_x**2, 1) / m.sigma_eta**2 - 4 * np.log(m.sigma_eta * np.sqrt(2 * np.pi))
    assert m.transition_logpdf(x, prev) == pytest.approx(expect)


def test_lis_proposal_lies_along_the_observed_bearing(rng):
    m = Bearings(1)
    x = m.sample_prior(20, rng)
    y = np.array([1.9])
    log_p, mu, cov = m.local_mixture(y, x)
    d = np.array([np.cos(1.9), np.sin(1.9)])
    mean = mu[:, 0, 0]
    assert np.abs(mean @ np.array([-d[1], d[0]])) == pytest.approx(np.zeros(20), abs=1e-15)
    w, v = np.linalg.eigh(cov[:, 0, 0])
    assert w[:, 1] / w[:, 0] == pytest.approx(np.full(20, m.kappa))
    assert np.abs(np.abs(v[:, :, 1] @ d)) == pytest.approx(np.ones(20))


def test_product_likelihood_over_ships(rng):
    m2, m1 = Bearings(2), Bearings(1)
    x = m2.sample_prior(10, rng)
    y = np.array([1.8, 1.5])
    total = m1.loglik(y[:1], x[:, :4]) + m1.loglik(y[1:], x[:, 4:])
    assert m2.loglik(y, x) == pytest.approx(total)


def test_observations_are_wrapped_cauchy_around_the_bearing():
    m = Bearings(1)
    rng = np.random.default_rng(3)
    x = np.repeat(m.prior_mean[None], 20000, 0)
    d = m.sample_observation(x, rng)[:, 0] - m.bearing(x)[:, 0]
    # Cauchy(0, gamma): the quartiles are ±gamma
    assert np.quantile(d, [0.25, 0.75]) == pytest.approx([-m.gamma, m.gamma], rel=0.05)


@pytest.mark.parametrize("algo", ["bootstrap", "avpf", "lis", "lls"])
def test_same_seed_same_output(algo):
    m = Bearings(1)
    _, ys = simulate(m, 5, np.random.default_rng(0))
    f = make_filter(algo, m)
    runs = [[p.states for p in filter_steps(f, ys, 30, np.random.default_rng(9))] for _ in range(2)]
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


def test_lis_tracks_and_beats_the_prior():
    """Over 5 sequences LIS (N=100) pins the ship far better than the prior spread."""
    m = Bearings(1)
    f = make_filter("lis", m)
    errs, prior_errs = [], []
    for s in range(5):
        xs, ys = simulate(m, 10, np.random.default_rng(100 + s))
        sets = list(filter_steps(f, ys, 100, np.random.default_rng(s)))
        errs.append(m.position_error(np.array([p.mean() for p in sets]), xs).mean())
        prior = ParticleSet(m.sample_prior(2000, np.random.default_rng(s)))
        prior_errs.append(m.position_error(prior.states, xs[0]).mean())
    assert np.mean(errs) < 0.012
    assert np.mean(errs) < 0.5 * np.mean(prior_errs)
