"""ParticleSet: log-sum-exp, ESS, weighted moments, degenerate steps."""

import warnings

import numpy as np
import pytest

from vistrack import DegenerateWeightsWarning, ParticleSet, ess, logsumexp, normalized_weights
from vistrack.filters import Bootstrap, filter_steps
from vistrack.models import GaussMixtureToy


def test_logsumexp_is_stable():
    lw = np.array([1000.0, 1000.0])
    assert logsumexp(lw) == pytest.approx(1000.0 + np.log(2))
    assert logsumexp(np.array([-np.inf, -np.inf])) == -np.inf
    rows = np.array([[0.0, np.log(3.0)], [-np.inf, -np.inf], [2000.0, 2000.0]])
    assert logsumexp(rows, axis=1) == pytest.approx([np.log(4.0), -np.inf, 2000.0 + np.log(2)])
    w = normalized_weights(np.array([-1e4, -1e4 + np.log(3)]))
    assert w == pytest.approx([0.25, 0.75])


def test_ess_known_values():
    assert ess(np.zeros(50)) == pytest.approx(50)
    one_hot = np.full(50, -np.inf)
    one_hot[4] = 0.0
    assert ess(one_hot) == pytest.approx(1.0)
    assert ess(np.array([np.log(0.5), np.log(0.5), -np.inf, -np.inf])) == pytest.approx(2.0)
    assert ess(np.full(3, np.nan)) == 0.0


def test_weighted_moments_match_numpy(rng):
    x = rng.standard_normal((200, 3))
    lw = rng.standard_normal(200)
    p = ParticleSet(x, lw)
    w = np.exp(lw) / np.exp(lw).sum()
    assert p.weights.sum() == pytest.approx(1.0)
    assert p.mean() == pytest.approx(np.average(x, axis=0, weights=w))
    assert p.cov() == pytest.approx(np.cov(x.T, aweights=w, bias=True))


def test_shape_validation():
    with pytest.raises(ValueError, match="log_weights must have shape"):
        ParticleSet(np.zeros((4, 2)), np.zeros(3))
    with pytest.raises(ValueError, match=r"loglik must have shape \(4,\), got \(3,\)"):
        ParticleSet(np.zeros((4, 2)), loglik=np.zeros(3))
    assert ParticleSet(np.zeros(5)).states.shape == (5, 1)


class BrokenLikelihood(GaussMixtureToy):
    """A likelihood that returns NaN and -inf: every weight is unusable."""

    def loglik(self, obs, states):
        out = np.full(len(states), -np.inf)
        out[::2] = np.nan
        return out


def test_degenerate_step_is_reported_and_recovered(rng):
    filt = Bootstrap(BrokenLikelihood())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sets = list(filter_steps(filt, [None] * 3, 40, rng))
    assert sum(issubclass(w.category, DegenerateWeightsWarning) for w in caught) == 3
    for p in sets:
        assert p.degenerate
        assert np.all(np.isfinite(p.states))
        assert p.ess == pytest.approx(40)


def test_make_filter_errors_are_clear():
    from vistrack.registry import make_filter

    with pytest.raises(ValueError, match="unknown algorithm 'nope'"):
        make_filter("nope", GaussMixtureToy())
    with pytest.raises(ValueError,
                       match="sir needs a model with sir_proposal .its proposal.; GaussMixtureToy does not"):
        make_filter("sir", GaussMixtureToy())


def test_ess_threshold_zero_never_resamples(rng):
    filt = Bootstrap(GaussMixtureToy(), ess_threshold=0.0)
    p = filt.first_step(None, 50, rng)
    q = filt.step(p, None, rng)
    # without resampling, weights accumulate: log w_2 = log w_1 + log r
    x = q.states
    expect = p.log_weights + filt.model.loglik(None, x)
    assert q.log_weights == pytest.approx(expect)


@pytest.mark.parametrize("algo", ["bootstrap", "lis", "lls", "avpf"])
def test_a_step_hands_on_the_likelihood_of_its_particles(algo, rng):
    """``ParticleSet.loglik`` (what the birth reserve draws by) is ``log r`` at the new states."""
    from vistrack.registry import make_filter

    model = GaussMixtureToy()
    filt = make_filter(algo, model)
    p = filt.first_step(None, 200, rng)
    for _ in range(2):
        assert p.loglik is not None
        np.testing.assert_allclose(p.loglik, model.loglik(None, p.states))
        p = filt.step(p, None, rng)


def _spread_set(rng, n=64):
    """Particles around the toy's likelihood modes with unequal weights (ESS well below n)."""
    states = rng.normal(0.0, 1.5, size=(n, 1))
    return ParticleSet(states, rng.normal(0.0, 1.0, size=n))


def test_avpf_step_is_the_auxiliary_first_stage_then_k():
    """AVPF (Fig. B.1) as the shared step's first stage: ancestors drawn ∝ w r(Y|mu), offspring
    X ~ K(.|X_{t-1}) weighted r(Y|X) / r(Y|mu) — the same draws as writing Fig. B.1 out."""
    from vistrack.core.resampling import systematic
    from vistrack.filters import AVPF

    model = GaussMixtureToy()
    p = _spread_set(np.random.default_rng(1))
    q = AVPF(model).step(p, None, np.random.default_rng(7))
    rng = np.random.default_rng(7)
    log_mu = model.loglik(None, model.predict_mean(p.states))
    lam = np.exp(p.log_weights + log_mu - np.max(p.log_weights + log_mu))
    k = systematic(lam / lam.sum(), p.n, rng)
    x = model.predict(p.states[k], rng)
    np.testing.assert_array_equal(q.states, x)
    w_expect = np.exp(model.loglik(None, x) - log_mu[k])
    np.testing.assert_allclose(q.weights, w_expect / w_expect.sum(), rtol=1e-10)


def test_avpf_honours_the_ess_threshold():
    """When the policy keeps the set, the look-ahead divides out: AVPF's step is the bootstrap
    filter's (same draws, same weights); when the tilted ESS is low it resamples."""
    from vistrack.filters import AVPF

    model = GaussMixtureToy()
    p = _spread_set(np.random.default_rng(2))
    kept = AVPF(model, ess_threshold=0.0).step(p, None, np.random.default_rng(3))
    boot = Bootstrap(model, ess_threshold=0.0).step(p, None, np.random.default_rng(3))
    np.testing.assert_array_equal(kept.states, boot.states)
    np.testing.assert_allclose(kept.weights, boot.weights, rtol=1e-10)
    # a threshold of 0.5: the toy's peaky likelihood leaves the tilted ESS far below N / 2
    resampled = AVPF(model, ess_threshold=0.5).step(p, None, np.random.default_rng(3))
    always = AVPF(model).step(p, None, np.random.default_rng(3))
    np.testing.assert_array_equal(resampled.states, always.states)
    assert not np.array_equal(resampled.states, kept.states)


def test_the_first_step_predicts_with_the_prior_kernel(rng):
    """The first step is the ordinary step with p_0 in the place of K
    (:class:`~vistrack.core.transition.PriorKernel`), the LIS window built for p_0's spread."""
    from vistrack.core.transition import PriorKernel
    from vistrack.filters import LIS

    model = GaussMixtureToy(prior_mean=3.0, prior_var=0.25)
    filt = LIS(model)
    kernel = filt.prior_kernel
    assert isinstance(kernel, PriorKernel) and kernel.first and not filt.kernel.first
    prev = np.full((5, 1), -40.0)  # ignored by p_0
    draws = kernel.predict(prev, np.random.default_rng(0))
    np.testing.assert_array_equal(draws, model.sample_prior(5, np.random.default_rng(0)))
    np.testing.assert_allclose(kernel.logpdf(draws, prev), model.prior_logpdf(draws))
    assert filt.part("proposal", kernel) is filt.part("proposal", kernel)  # built once per kernel
    assert filt.part("proposal", filt.kernel) is filt.proposal
