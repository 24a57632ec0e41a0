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
    from vistrack.filters import make_filter

    with pytest.raises(ValueError, match="unknown algorithm 'nope'"):
        make_filter("nope", GaussMixtureToy())
    with pytest.raises(ValueError, match="sir needs a model with sir_proposal .its proposal.; GaussMixtureToy does not"):
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
    from vistrack.filters import make_filter

    model = GaussMixtureToy()
    filt = make_filter(algo, model)
    p = filt.first_step(None, 200, rng)
    for _ in range(2):
        assert p.loglik is not None
        np.testing.assert_allclose(p.loglik, model.loglik(None, p.states))
        p = filt.step(p, None, rng)
