"""Equal-time particle counts (vistrack.scoring.metrics: the one place eval and the reproductions get them)."""

import numpy as np
import pytest

from vistrack.scoring.metrics import equal_time_n, equal_time_search


def linear(fixed, per):
    calls = []

    def t(n):
        calls.append(n)
        return fixed + per * n

    return t, calls


def test_a_straight_line_gives_the_exact_count():
    t, calls = linear(2.0, 0.01)  # 2 ms + 10 µs per particle
    budget = 2.0 + 0.01 * 730
    n, t1, t2 = equal_time_n(t, 100, budget)
    assert n == 730 and (t1, t2) == (t(100), t(200)) and calls[:2] == [100, 200]


def test_a_noisy_slope_cannot_pick_a_huge_count():
    # t(2n) timed below t(n): without a floor on the slope the line would pick N ~ 1e6
    times = {100: 5.0, 200: 4.9}
    n, _, _ = equal_time_n(times.get, 100, 6.0, min_slope=0.1)
    assert n == 100 + round(1.0 / (0.1 * 5.0 / 100))  # the slope taken as a tenth of t(n) / n


def test_the_checks_scale_an_over_budget_pick_down():
    # a line through 100 and 200 underestimates the cost of large N (cubic here)

    def t(n):
        return 1.0 + 1e-6 * n ** 3

    budget = 50.0
    n0 = equal_time_n(t, 100, budget)[0]
    n3 = equal_time_n(t, 100, budget, checks=3)[0]
    assert t(n0) > 1.25 * budget >= t(n3) and n3 < n0


def test_the_secant_search_finds_the_count_of_a_curved_cost():

    def t(n):
        return 0.5 + 0.002 * n ** 1.3

    budget = t(5000)
    n, tn = equal_time_search(t, 100, budget, steps=6)
    assert tn == t(n) and abs(np.log(tn / budget)) < 0.02


@pytest.mark.parametrize("n", [1, 7])
def test_counts_are_at_least_one(n):
    assert equal_time_n(lambda k: 10.0 * k, n, 0.001)[0] == 1
