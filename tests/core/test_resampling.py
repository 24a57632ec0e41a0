"""Resampling (thesis App. A): unbiased counts, lower variance, known answers (Stone Soup style)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vistrack.core.particles import ParticleSet
from vistrack.core.resampling import SCHEMES, get_scheme, needs_resampling
from vistrack.filters import ParticleFilter
from vistrack.filters.resampler import BirthReserve, Resampler, make_resampler

ALL = sorted(SCHEMES)
LOW_VARIANCE = ["residual", "stratified", "systematic"]


def counts_over_repeats(scheme, w, reps, seed=0):
    rng = np.random.default_rng(seed)
    n = len(w)
    return np.array([np.bincount(scheme(w, n, rng), minlength=n) for _ in range(reps)])


@pytest.fixture(scope="module")
def weights():
    w = np.random.default_rng(7).gamma(0.7, size=40)
    return w / w.sum()


@pytest.mark.parametrize("name", ALL)
def test_expected_counts_equal_n_w(name, weights):
    reps = 4000
    c = counts_over_repeats(SCHEMES[name], weights, reps)
    n = len(weights)
    expected = n * weights
    # Binomial bound on the std of each count (multinomial is the largest-variance scheme)
    se = np.sqrt(n * weights * (1 - weights) / reps) + 1e-3
    assert np.all(np.abs(c.mean(axis=0) - expected) < 5 * se)
    assert np.all(c.sum(axis=1) == n)


@pytest.mark.parametrize("name", LOW_VARIANCE)
def test_low_variance_schemes_beat_multinomial(name, weights):
    reps = 3000
    var_multi = counts_over_repeats(SCHEMES["multinomial"], weights, reps).var(axis=0).sum()
    var = counts_over_repeats(SCHEMES[name], weights, reps, seed=1).var(axis=0).sum()
    assert var < 0.5 * var_multi


@pytest.mark.parametrize("name", LOW_VARIANCE)
def test_uniform_weights_give_every_index_once(name, rng):
    idx = SCHEMES[name](np.full(25, 1 / 25), 25, rng)
    assert sorted(idx) == list(range(25))


@pytest.mark.parametrize("name", ALL)
def test_single_nonzero_weight_gives_n_copies(name, rng):
    w = np.zeros(10)
    w[3] = 1.0
    assert np.all(SCHEMES[name](w, 10, rng) == 3)


@pytest.mark.parametrize("name", ALL)
def test_weight_on_even_indices_only(name, rng):
    w = np.zeros(20)
    w[::2] = rng.random(10)
    w /= w.sum()
    idx = SCHEMES[name](w, 200, rng)
    assert len(idx) == 200 and np.all(idx % 2 == 0)


@settings(max_examples=60, deadline=None)
@given(
    w=st.lists(st.floats(0, 1), min_size=1, max_size=30).filter(lambda v: sum(v) > 1e-6),
    n=st.integers(1, 60),
    name=st.sampled_from(ALL),
    seed=st.integers(0, 2**32 - 1),
)
def test_indices_valid_for_any_weights(w, n, name, seed):
    w = np.asarray(w) / np.sum(w)
    idx = SCHEMES[name](w, n, np.random.default_rng(seed))
    assert idx.shape == (n,)
    assert np.all((idx >= 0) & (idx < len(w)))
    assert np.all(w[idx] > 0)
    if name == "residual":
        counts = np.bincount(idx, minlength=len(w))
        assert np.all(counts >= np.floor(n * w) - 1e-9)


def test_policy_and_registry():
    assert needs_resampling(100.0, 100, None)
    assert needs_resampling(100.0, 100, 1.0)
    assert needs_resampling(40.0, 100, 0.5)
    assert not needs_resampling(60.0, 100, 0.5)
    with pytest.raises(ValueError, match="unknown resampling scheme 'nope'"):
        get_scheme("nope")


# -- birth reserve (filters.resampler.BirthReserve) ---------------------------------------


class _Births:
    """A model whose births are the particles with a positive first coordinate."""

    def __init__(self, birth_reserve=0.0):
        self.birth_reserve = birth_reserve

    @staticmethod
    def entering(states):
        return states[:, 0] > 0


def _births_set(n=40, n_born=8, w_born=1e-6, seed=3, loglik=False):
    """Particles ``(±index, ...)``: the last ``n_born`` are births holding ``w_born`` of the weight
    (with ``loglik``, each particle has a log-likelihood, drawn independently of its weight)."""
    rng = np.random.default_rng(seed)
    w = rng.gamma(0.7, size=n)
    born = np.arange(n) >= n - n_born
    w[~born] *= (1 - w_born) / w[~born].sum()
    w[born] *= w_born / w[born].sum()
    states = np.where(born, 1.0, -1.0)[:, None] * np.arange(1, n + 1)[:, None]
    ll = 3 * rng.standard_normal(n) if loglik else None
    return ParticleSet(states, np.log(w), loglik=ll), w, born


@pytest.mark.slow
@pytest.mark.parametrize("loglik", [False, True], ids=["by-weight", "by-likelihood"])
@pytest.mark.parametrize("name", ["multinomial", "systematic"])
def test_birth_reserve_keeps_offspring_weights_unbiased(name, loglik):
    """With ε of the draws reserved for births, every parent's offspring carry its weight in
    expectation (E Σ_offspring w' = w_i), and the births get n (ε + (1 - ε) W_B) draws — whether
    the reserve goes ∝ the weights or ∝ the likelihoods."""
    eps, reps = 0.1, 4000
    ps, w, born = _births_set(loglik=loglik)
    n = ps.n
    res = ParticleFilter(_Births(eps), resample=name).resampler
    assert isinstance(res, BirthReserve) and res.eps == eps
    rng = np.random.default_rng(11)
    carried, n_born = np.zeros(n), 0
    for _ in range(reps):
        idx, log_w = res(ps, rng)
        parent = np.abs(ps.states[idx, 0]).astype(int) - 1
        carried += np.bincount(parent, weights=np.exp(log_w), minlength=n)
        n_born += born[parent].sum()
    pi, _ = res.probs(ps)
    assert np.isclose(pi.sum(), 1.0)
    assert np.isclose(pi[born].sum(), eps + (1 - eps) * w[born].sum())
    # each offspring of i carries w_i / (n π_i); its count has variance at most n π_i (1 - π_i)
    se = w / (n * pi) * np.sqrt(n * pi * (1 - pi) / reps)
    assert np.all(np.abs(carried / reps - w) < 5 * se + 1e-12)
    p_born = pi[born].sum()
    assert abs(n_born / reps - n * p_born) < 5 * np.sqrt(n * p_born * (1 - p_born) / reps)
    # without the reserve the births, at 1e-6 of the weight, are all but never drawn
    assert n * w[born].sum() < 1e-4


def test_no_birth_reserve_is_plain_resampling():
    ps, w, born = _births_set()
    for model, kw in ((_Births(0.0), {}), (_Births(0.2), {"birth_reserve": 0.0}), (object(), {"birth_reserve": 0.2})):
        res = ParticleFilter(model, **kw).resampler
        assert type(res) is Resampler
        got, log_w = res(ps, np.random.default_rng(5))
        idx = SCHEMES["systematic"](w, ps.n, np.random.default_rng(5))
        assert np.array_equal(got, idx)
        assert np.allclose(log_w, -np.log(ps.n))
    # the model's reserve is the default; an explicit one overrides it
    assert make_resampler(_Births(0.2)).eps == 0.2
    assert make_resampler(_Births(0.2), birth_reserve=0.05).eps == 0.05
    with pytest.raises(ValueError, match=r"birth_reserve must be in \[0, 1\), got 1.0"):
        ParticleFilter(_Births(0.2), birth_reserve=1.0)
    # all the weight on births (the first step draws every particle from p_0): plain resampling
    one = ParticleSet(np.arange(1.0, 11.0)[:, None])
    pi, log_w = make_resampler(_Births(0.3)).probs(one)
    assert np.allclose(pi, one.weights) and np.all(log_w == 0)


class _Young(_Births):
    """A model whose reserve is a set it computes from the particle set (``reserved``), here the
    particles with a positive first coordinate; its ``entering`` marks none."""

    def reserved(self, particles):
        return particles.states[:, 0] > 0

    @staticmethod
    def entering(states):
        return np.zeros(len(states), bool)


def test_the_reserve_takes_the_models_reserved_set():
    """A model's ``reserved(particles)`` (e.g. lineages a few frames old) replaces ``entering`` as
    the reserve's set: the same probabilities as for births at those particles."""
    ps, w, born = _births_set()
    pi_young, carry_young = make_resampler(_Young(0.1)).probs(ps)
    pi_born, carry_born = make_resampler(_Births(0.1)).probs(ps)
    np.testing.assert_allclose(pi_young, pi_born)
    np.testing.assert_allclose(carry_young, carry_born)
    assert np.isclose(pi_young[born].sum(), 0.1 + 0.9 * w[born].sum())


def test_the_reserve_goes_by_likelihood_when_the_filter_gives_it():
    """With ``particles.loglik`` the reserve's share of each birth is ∝ its likelihood ``r``, not
    its weight: a birth on the narrow peak of a plate coming into view outweighed by births in a
    broad empty region (their weight is the likelihood's mass in their search windows) keeps the
    reserve's draws."""
    eps = 0.05
    ps, w, born = _births_set(loglik=True)
    ll = ps.loglik
    pi, carry = make_resampler(_Births(eps)).probs(ps)
    rho = np.where(born, np.exp(ll - ll[born].max()), 0.0)
    np.testing.assert_allclose(pi, (1 - eps) * w + eps * rho / rho.sum())
    np.testing.assert_allclose(carry, np.log(w / pi))
    # the likeliest birth has the least weight of the births: still the most draws
    i = np.flatnonzero(born)
    lw = np.log(w)
    lw[i] = np.log(1e-6 / len(i)) - (ll[i] - ll[i].min())  # the likelier, the less weight
    ps2 = ParticleSet(ps.states, lw, loglik=ll)
    pi2, _ = make_resampler(_Births(eps)).probs(ps2)
    best = i[np.argmax(ll[i])]
    assert np.argmax(np.where(born, pi2, -1)) == best and ps2.weights[best] == ps2.weights[i].min()
    assert pi2[best] > 1e3 * ps2.weights[best]
    # a loglik without a finite value on the births: back to the weights
    ps3 = ParticleSet(ps.states, ps.log_weights, loglik=np.where(born, -np.inf, 0.0))
    pi3, _ = make_resampler(_Births(eps)).probs(ps3)
    by_weight = make_resampler(_Births(eps)).probs(ParticleSet(ps.states, ps.log_weights))[0]
    np.testing.assert_allclose(pi3, by_weight)
