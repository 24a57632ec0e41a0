"""Partitioned and branched partitioned sampling (thesis App. C, Figs. C.1, C.2).

Known answer: two independent 1-D random-walk targets with Gaussian likelihoods, one filter
step from a particle set concentrated at ``X_PREV``: the posterior of each target and the
marginal likelihood are closed-form (a Gaussian prediction times a Gaussian likelihood), so
the filters' estimates must match them within Monte-Carlo error, as in test_proper_weighting.
"""

import numpy as np
import pytest
from scipy import stats

import vistrack
from cli_helpers import run
from vistrack.core.particles import ParticleSet
from vistrack.filters import BranchedPartitioned
from vistrack.filters.branched_partitioned import cyclic_orderings
from vistrack.models import Bearings, GaussMixtureToy
from vistrack.models.partitions import IndependentTargets
from vistrack.registry import ALGORITHMS, make_filter
from weighting_helpers import one_step_runs

X_PREV = np.array([0.2, -0.1])
Q = 1.0
Y = np.array([0.9, -0.6])
S = np.array([0.08, 0.25])
N = 400
REPS = 100
PARTITIONED = ["partitioned", "branched-partitioned", "partitioned-lis", "branched-partitioned-lis"]


class TwoTargets(IndependentTargets):
    """Targets ``x_j' = x_j + N(0, Q)``, ``r_j = N(Y_j; x_j, S_j²)``: one partition each."""

    dim = 2
    partitions = (np.array([0]), np.array([1]))

    def __init__(self):
        self.targets = [GaussMixtureToy(q=Q, weights=(1.0,), means=(y,), stds=(s,), window=0.3) for y, s in zip(Y, S)]
        self.prior_mean = np.zeros(2)

    def target_model(self, j):
        return self.targets[j]

    def target_obs(self, obs, j):
        return None

    def sample_prior(self, n, rng):
        return rng.standard_normal((n, 2))

    def prior_logpdf(self, states):
        return stats.norm.logpdf(states).sum(axis=1)

    def predict(self, states, rng):
        return states + np.sqrt(Q) * rng.standard_normal(states.shape)

    def transition_logpdf(self, new, old):
        return stats.norm.logpdf(new - old, scale=np.sqrt(Q)).sum(axis=1)

    def loglik(self, obs, states):
        return sum(self.targets[j].loglik(None, states[:, j:j + 1]) for j in range(2))


class TemperedTwoTargets(TwoTargets):
    """``π_j = r_j^{1/2}``: the importance functions do not multiply to ``r``, so the final
    weights must carry ``r / Π π_j``."""

    factorised_likelihood = False

    def loglik_part(self, obs, states, j):
        return 0.5 * super().loglik_part(obs, states, j)


def exact():
    """Marginal likelihood and posterior means of the two targets after one step from X_PREV."""
    z = np.prod(stats.norm.pdf(Y, X_PREV, np.sqrt(Q + S**2)))
    mean = (X_PREV / Q + Y / S**2) / (1 / Q + 1 / S**2)
    return z, mean


def replicate(filt):
    """REPS one-step runs: ``(Σ w, posterior mean (2,))`` per run."""
    return one_step_runs(filt, ParticleSet(np.tile(X_PREV, (N, 1))), REPS,
                         lambda p: [np.exp(p.log_weights).sum(), *p.mean()])


@pytest.mark.slow
@pytest.mark.parametrize("model", [TwoTargets, TemperedTwoTargets])
@pytest.mark.parametrize("algo", PARTITIONED)
def test_properly_weighted_on_a_two_target_gaussian_toy(algo, model):
    est = replicate(make_filter(algo, model()))
    z, mean = exact()
    se = est.std(axis=0, ddof=1) / np.sqrt(REPS)
    assert abs(est[:, 0].mean() - z) < 4.5 * se[0], (est[:, 0].mean(), z, se[0])  # unbiased marginal likelihood
    for j in range(2):  # the self-normalised means: MC error plus a little O(1/N) bias
        assert abs(est[:, 1 + j].mean() - mean[j]) < 4.5 * se[1 + j] + 0.005, (j, est[:, 1 + j].mean(), mean[j])


def test_a_step_multiplies_the_weights_by_r_where_the_likelihood_factorises():
    """Fig. C.1's note: the final weights reuse the l_{t,j}; the set's loglik is Σ_j log π_j = log r."""
    model = TwoTargets()
    p = make_filter("partitioned", model).step(ParticleSet(np.tile(X_PREV, (50, 1))), None, np.random.default_rng(0))
    np.testing.assert_allclose(p.loglik, model.loglik(None, p.states))
    assert np.ptp(p.log_weights) > 0  # the last partition's weights are not resampled away


def test_orderings_are_the_cyclic_shifts_drawn_balanced_at_random():
    assert cyclic_orderings(3) == [(0, 1, 2), (1, 2, 0), (2, 0, 1)]
    filt = BranchedPartitioned(Bearings(3))
    assert filt.orderings == cyclic_orderings(3)
    rng = np.random.default_rng(0)
    draws = np.array([filt.assign(10, rng) for _ in range(3000)])
    assert all(np.bincount(d, minlength=3).tolist() == [4, 3, 3] for d in draws)  # array_split's sizes
    freq = np.stack([(draws == s).mean(axis=0) for s in range(3)])  # (ordering, particle)
    np.testing.assert_allclose(freq, np.array([[0.4], [0.3], [0.3]]) * np.ones((1, 10)), atol=0.04)
    assert not np.array_equal(draws[0], draws[1])
    with pytest.raises(ValueError, match="not a permutation"):
        BranchedPartitioned(Bearings(3), orderings=[(0, 1, 1)])


class Recording(TwoTargets):
    """Records ``(partition, rows)`` of every draw."""

    partitions = (np.array([0]), np.array([1]), np.array([2]))
    dim = 3

    def __init__(self):
        super().__init__()
        self.targets.append(self.targets[0])
        self.calls = []

    def predict_part(self, states, j, rng):
        self.calls.append((j, len(states)))
        return super().predict_part(states, j, rng)


def test_each_group_samples_the_partitions_in_its_ordering():
    model = Recording()
    filt = BranchedPartitioned(model, orderings=[(2, 0, 1), (0, 1, 2)])
    p = filt.step(ParticleSet(np.zeros((7, 3))), None, np.random.default_rng(1))
    assert model.calls == [(2, 4), (0, 4), (1, 4), (0, 3), (1, 3), (2, 3)]
    assert p.n == 7 and np.all(np.isfinite(p.log_weights))


@pytest.mark.slow
@pytest.mark.parametrize("algo", PARTITIONED)
def test_same_seed_same_output(algo):
    from vistrack.filters import filter_steps
    from vistrack.models.bearings.model import simulate

    model = Bearings(3)
    _, obs = simulate(model, 4, np.random.default_rng(2))
    runs = [[p for p in filter_steps(make_filter(algo, model), obs, 60, np.random.default_rng(5))] for _ in range(2)]
    for a, b in zip(*runs):
        assert np.array_equal(a.states, b.states) and np.array_equal(a.log_weights, b.log_weights)


def test_bearings_partitions_factorise_the_model(rng):
    model = Bearings(3)
    old = model.sample_prior(5, rng)
    new = model.predict(old, rng)
    obs = model.sample_observation(new, rng)[0]
    parts = model.partitions
    assert np.array_equal(np.concatenate(parts), np.arange(12))
    np.testing.assert_allclose(sum(model.loglik_part(obs, new, j) for j in range(3)), model.loglik(obs, new))
    np.testing.assert_allclose(sum(model.part_logpdf(new[:, c], old, j) for j, c in enumerate(parts)),
                               model.transition_logpdf(new, old))
    np.testing.assert_allclose(sum(model.prior_part_logpdf(new[:, c], old, j) for j, c in enumerate(parts)),
                               model.prior_logpdf(new))


def test_partitioned_on_a_model_without_partitions_is_one_clear_line(capsys):
    with pytest.raises(ValueError, match=r"^partitioned needs a model with .*partitions \(Partitions\); "
                                         r"GaussMixtureToy does not supply them$"):
        make_filter("partitioned", GaussMixtureToy())
    with pytest.raises(ValueError, match="algorithm 'branched-partitioned' does not run on the box model"):
        vistrack.Tracker(algo="branched-partitioned")
    code, out, err = run(["reproduce", "bearings", "--ships", "2", "--algos", "ls-n-ips", "-q"], capsys)
    assert code != 0 and err.strip() == ("Error: ls-n-ips needs a model with local_search (LocalSearch); "
                                         "Bearings does not supply it")
    assert {"partitioned", "branched-partitioned"} <= set(ALGORITHMS)


def test_reproduce_bearings_many_ships_at_equal_time(tmp_path, capsys):
    import json

    js = tmp_path / "r.json"
    code, out, err = run(["reproduce", "bearings", "--ships", "3", "--sequences", "1", "--runs", "2", "--steps", "3",
                          "--particles", "40", "--algos", "bootstrap,partitioned,branched-partitioned",
                          "--equal-time", "--in-process", "--workers", "1", "--out", str(tmp_path / "res"),
                          "--json", str(js), "-q"], capsys)
    assert code == 0, err
    assert out.startswith("equal time: bootstrap:40, partitioned:") and "final-step error per ship" in out
    rows = json.loads(js.read_text())["results"]
    assert [r["algo"] for r in rows] == ["bootstrap", "partitioned", "branched-partitioned"]
    for r in rows:
        assert len(r["ship_error_final"]) == 3 and r["ships"] == 3
        assert r["mean_error_final"] == pytest.approx(np.mean(r["ship_error_final"]))


class StackedTwoTargets(TwoTargets):
    """:class:`TwoTargets` drawing and weighing one partition per particle in one call
    (:class:`~vistrack.models.partitions.StackedPartitions`): branched partitioning runs every
    group at once."""

    calls = None

    def sample_prior_parts(self, states, parts, rng):
        return rng.standard_normal((len(states), 1))

    def predict_parts(self, states, parts, rng):
        if self.calls is not None:
            self.calls.append(parts.copy())
        return self.gather_parts(states, parts) + np.sqrt(Q) * rng.standard_normal((len(states), 1))

    def loglik_parts(self, obs, values, states, parts):
        return stats.norm.logpdf(values[:, 0], Y[parts], S[parts])


class TemperedStackedTwoTargets(StackedTwoTargets):
    factorised_likelihood = False

    def loglik_parts(self, obs, values, states, parts):
        return 0.5 * super().loglik_parts(obs, values, states, parts)

    def loglik_part(self, obs, states, j):
        return 0.5 * super().loglik_part(obs, states, j)


@pytest.mark.parametrize("model", [StackedTwoTargets, TemperedStackedTwoTargets])
def test_branched_with_every_group_at_once_is_properly_weighted(model):
    from vistrack.models.partitions import StackedPartitions

    assert isinstance(model(), StackedPartitions) and not isinstance(TwoTargets(), StackedPartitions)
    test_properly_weighted_on_a_two_target_gaussian_toy("branched-partitioned", model)


def test_every_group_at_once_draws_each_particles_ordering_in_one_call_per_stage():
    model = StackedTwoTargets()
    model.calls = []
    filt = BranchedPartitioned(model, orderings=[(1, 0), (0, 1)])
    p = filt.step(ParticleSet(np.zeros((7, 2))), None, np.random.default_rng(1))
    # the particles sorted by group: 4 of ordering (1, 0), then 3 of (0, 1); one call per stage
    assert [c.tolist() for c in model.calls] == [[1, 1, 1, 1, 0, 0, 0], [0, 0, 0, 0, 1, 1, 1]]
    assert p.n == 7 and np.all(np.isfinite(p.log_weights))


def test_grouped_resampling_stays_in_each_group_with_the_schemes_counts():
    from vistrack.core.resampling import Groups, grouped, residual, stratified, systematic

    rng = np.random.default_rng(3)
    sizes = np.array([5, 1, 8, 3])
    groups = Groups(sizes)
    w = rng.random(17) ** 4
    w /= np.add.reduceat(w, groups.starts)[groups.of]
    for _ in range(200):
        idx = grouped(systematic, w, groups, rng)
        assert np.array_equal(groups.of[idx], groups.of)  # every offspring's parent is in its group
        counts = np.bincount(idx, minlength=17)
        expected = sizes[groups.of] * w
        assert np.all((counts == np.floor(expected)) | (counts == np.ceil(expected)))
    freq = np.mean([np.bincount(grouped(stratified, w, sizes, rng), minlength=17) for _ in range(2000)], axis=0)
    np.testing.assert_allclose(freq, sizes[groups.of] * w, atol=0.05)
    assert grouped(residual, w, groups, rng) is None


def test_each_group_keeps_its_total_weight_and_its_own_ess_test():
    from vistrack.core.resampling import Groups

    filt = BranchedPartitioned(Bearings(2), ess_threshold=0.5)
    log_w = np.log(np.array([1.0, 1.0, 1.0, 1.0, 4.0, 0.001, 0.001, 0.001]))
    x = np.arange(8.0)[:, None]
    idx, lw = filt._resample_groups(x, log_w, Groups([4, 4]), np.random.default_rng(0))
    assert idx[:4].tolist() == [0, 1, 2, 3] and lw[:4].tolist() == log_w[:4].tolist()  # ESS 4 of 4: kept
    assert idx[4:].tolist() == [4, 4, 4, 4]  # ESS about 1 of 4: resampled within the group
    np.testing.assert_allclose(np.exp(lw[4:]).sum(), np.exp(log_w[4:]).sum())
    filt = BranchedPartitioned(Bearings(2), resample="residual")  # no grouped form: group by group
    idx, lw = filt._resample_groups(x, log_w, Groups([4, 4]), np.random.default_rng(0))
    assert idx[:4].tolist() == [0, 1, 2, 3] and idx[4:].tolist() == [4, 4, 4, 4]


def test_bearings_stacked_partitions_equal_the_partitions_one_by_one(rng):
    model = Bearings(3)
    old = model.sample_prior(6, rng)
    new = model.predict(old, rng)
    obs = model.sample_observation(new, rng)[0]
    parts = np.array([2, 0, 1, 1, 0, 2])
    vals = model.gather_parts(new, parts)
    assert np.array_equal(vals, np.stack([new[i, model.partitions[j]] for i, j in enumerate(parts)]))
    want = np.array([model.loglik_part(obs, new[i:i + 1], j)[0] for i, j in enumerate(parts)])
    np.testing.assert_allclose(model.loglik_parts(obs, vals, new, parts), want, rtol=1e-12)
    for j in range(3):  # the same draws as partition j's own call
        same = np.full(6, j)
        assert np.array_equal(model.predict_parts(old, same, np.random.default_rng(j)),
                              model.predict_part(old, j, np.random.default_rng(j)))
        np.testing.assert_allclose(model.sample_prior_parts(old, same, np.random.default_rng(j)),
                                   model.sample_prior_part(old, j, np.random.default_rng(j)), rtol=1e-14)
    out = old.copy()
    model.scatter_parts(out, parts, vals)
    assert np.array_equal(model.gather_parts(out, parts), vals)
    untouched = np.ones(old.shape, bool)
    untouched[np.arange(6)[:, None], model.part_columns[parts]] = False
    assert np.array_equal(out[untouched], old[untouched])
