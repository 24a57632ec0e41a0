"""Resampling (thesis App. A): unbiased counts, lower variance, known answers (Stone Soup style)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vistrack.resampling import SCHEMES, get_scheme, needs_resampling

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
