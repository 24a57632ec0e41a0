"""The history-sampling family (thesis 001, §3.2): Basic-SIR, HS-SIR, RB-HS-SIR, RB-SS-HS-SIR.

Known answers on the 1-D AR(2) toy (:class:`vistrack.models.AR2Toy`): from a fixed weighted
set of distinct histories, one step must give unbiased estimates of ``∫ h r K_1 p`` (closed
form: Gaussian products, App. D) for ``h`` of the innovation, of the history and of both (the
association); the history-index law of Fig. 3.5 is checked against its formula.
"""

import numpy as np
import pytest
from scipy import stats

from vistrack.core.particles import ParticleSet
from vistrack.filters import RBHSSIR
from vistrack.filters.history import draw_rows
from vistrack.models import AR2Toy, GaussMixtureToy
from vistrack.registry import ALGORITHMS, make_filter
from weighting_helpers import exact_moments, one_step_runs

FAMILY = ("basic-sir", "hs-sir", "rb-hs-sir", "rb-ss-hs-sir")
N, COPIES, REPS = 120, 3, 150


def toy(rest):
    return AR2Toy(rest=rest, stds=(0.15, 0.1), proposal=(0.4, 1.2))


def previous(model, seed=7):
    """``N`` particles: ``N / COPIES`` distinct histories (moving, so ``K_1`` differs by velocity)
    each ``COPIES`` times, with uneven weights."""
    rng = np.random.default_rng(seed)
    m = N // COPIES
    z1 = rng.normal(0.3, 0.9, (m, model.k))
    z2 = z1 - rng.normal(0.0, 0.5, (m, model.k))
    w = rng.gamma(2.0, size=m)
    w /= w.sum()
    return np.repeat(np.concatenate([z1, z2], axis=1), COPIES, axis=0), np.repeat(w / COPIES, COPIES)


def moments(model, p):
    w, x = np.exp(p.log_weights), p.states
    out = {"1": w.sum(), "u": w @ x[:, 0], "u2": w @ x[:, 0] ** 2, "hist": w @ x[:, model.k],
           "u_hist": w @ (x[:, 0] * x[:, model.k])}
    if model.k == 2:
        out.update({"v": w @ x[:, 1], "v_hist": w @ (x[:, 1] * x[:, 2])})
    out["mean_u"] = p.mean()[0]
    return out


def replicate(filt, model, first=False):
    states, w = previous(model)
    return one_step_runs(filt, ParticleSet(states, np.log(w)), REPS, lambda p: moments(model, p),
                         first=N if first else None)


CASES = [(a, rest, {}) for a in FAMILY for rest in (False, True)] + [
    ("hs-sir", True, {"resample": "multinomial"}), ("rb-hs-sir", True, {"resample": "stratified"}),
    ("rb-ss-hs-sir", True, {"ess_threshold": 0.0}), ("basic-sir", True, {"resample": "residual"})]


@pytest.mark.slow
@pytest.mark.parametrize("algo,rest,opts", CASES,
                         ids=[f"{a}-{'uv' if r else 'u'}" + "".join(f"-{v}" for v in o.values()) for a, r, o in CASES])
def test_unnormalised_weights_are_unbiased(algo, rest, opts):
    """E[Σ w h(X_t)] = ∫ h r K_1 p for h of the innovation, the history and both (Definition 2.2.1)."""
    model = toy(rest)
    est = replicate(make_filter(algo, model, **opts), model)
    exact = exact_moments(model, *previous(model))
    for key, truth in exact.items():
        e = est[key]
        se = e.std(ddof=1) / np.sqrt(len(e))
        assert abs(e.mean() - truth) < 4.5 * se + 1e-12, \
            f"{algo} {key}: {e.mean():.5g} vs exact {truth:.5g} (se {se:.2g})"
    # the self-normalised posterior mean: O(1/N) bias on top of Monte-Carlo error
    post = exact["u"] / exact["1"]
    assert abs(est["mean_u"].mean() - post) < 4.5 * est["mean_u"].std(ddof=1) / np.sqrt(REPS) + 0.02


@pytest.mark.parametrize("algo", FAMILY)
def test_first_step_is_the_step_with_p0(algo):
    """The first step weighs by p_0 in the place of K_1, and starts at rest (history = innovation)."""
    model = toy(True)
    est = replicate(make_filter(algo, model), model, first=True)
    for key, truth in exact_moments(model).items():
        se = est[key].std(ddof=1) / np.sqrt(REPS)
        assert abs(est[key].mean() - truth) < 4.5 * se + 1e-12, f"{algo} {key}"


class Fixed:
    """A proposal that always gives ``x`` (density 1 there, for the weight's formula)."""

    def __init__(self, x):
        self.x = np.atleast_1d(x)

    def sample(self, n, obs, rng):
        return np.tile(self.x, (n, 1))

    def logpdf(self, x, obs):
        return np.zeros(len(x))


def test_history_index_law_of_fig_3_5():
    """p(I = l) ∝ ŵ_l K_1(x | X̂^{(l)}): systematic uniforms over identical rows give every
    history floor or ceil of N p_l of the draws; every weight is r Σ_l ŵ_l K_1 / (π N)."""
    model = AR2Toy()
    hist = np.array([[0.0, -0.2], [0.4, 0.5], [0.3, 0.0], [-0.5, -0.6]])
    w = np.array([0.1, 0.2, 0.3, 0.4])
    n = 1000
    states, log_w = np.repeat(hist, n // 4, axis=0), np.repeat(np.log(w / (n // 4)), n // 4)
    x = 0.35
    k1 = np.exp(model.transition_logpdf(np.tile([x, 0.0], (4, 1)), hist))
    law = w * k1 / np.sum(w * k1)
    filt = RBHSSIR(model, proposal=Fixed(x), ess_threshold=0.0)
    for seed in range(5):
        p = filt.step(ParticleSet(states, log_w), None, np.random.default_rng(seed))
        counts = np.array([np.sum(p.states[:, 1] == h[0]) for h in hist])
        assert counts.sum() == n
        assert np.all(np.abs(counts - n * law) < 1.0), (counts, n * law)
        weight = model.loglik(None, np.array([[x, 0.0]]))[0] + np.log(np.sum(w * k1)) - np.log(n)
        np.testing.assert_allclose(p.log_weights, weight, rtol=0, atol=1e-10)


@pytest.mark.parametrize("scheme", ["multinomial", "stratified", "systematic", "residual"])
def test_each_row_draw_has_its_rows_law(scheme):
    """draw_rows: the k-th draw follows row k's law whatever the coupling across rows."""
    from vistrack.core.resampling import get_scheme

    p = np.array([[0.7, 0.2, 0.1], [0.1, 0.1, 0.8], [1 / 3, 1 / 3, 1 / 3], [0.0, 0.5, 0.5]])
    rng = np.random.default_rng(3)
    counts = np.zeros((4, 3))
    reps = 3000
    with np.errstate(divide="ignore"):
        log_p = np.log(p)
    for _ in range(reps):
        counts[np.arange(4), draw_rows(log_p, rng, get_scheme(scheme))] += 1
    assert counts[3, 0] == 0
    for row, q in zip(counts, p):
        ok = q > 0
        assert stats.chisquare(row[ok], reps * q[ok]).pvalue > 1e-4, (scheme, row, reps * q)


def test_same_seed_same_particles():
    model = toy(True)
    states, w = previous(model)
    for algo in FAMILY:
        a, b = (make_filter(algo, model).step(ParticleSet(states, np.log(w)), None, np.random.default_rng(5))
                for _ in range(2))
        assert np.array_equal(a.states, b.states) and np.array_equal(a.log_weights, b.log_weights)


@pytest.mark.parametrize("algo", FAMILY)
def test_model_without_split_is_one_clear_line(algo):
    with pytest.raises(ValueError,
                       match=rf"^{algo} needs a model with .*\(InnovationSplit\); GaussMixtureToy does not"):
        make_filter(algo, GaussMixtureToy())
    assert algo in ALGORITHMS


def test_blocks_do_not_change_the_draws():
    """associate evaluates the (N, C) law in blocks of rows: same draws, same sums, any block size."""
    from vistrack.core.resampling import systematic
    from vistrack.filters.history import associate

    log_p = np.random.default_rng(1).normal(0, 2, (50, 7))
    runs = [associate(lambda rows: log_p[rows], 50, 7, np.random.default_rng(4), systematic, budget=b)
            for b in (7, 60, 10_000)]
    for idx, s in runs[1:]:
        assert np.array_equal(idx, runs[0][0]) and np.array_equal(s, runs[0][1])
