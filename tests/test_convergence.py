"""The ladder extension rule: extend while the order is unsettled and the budget allows."""
import numpy as np
import pytest

from studies import convergence as cv


def test_settled_on_clean_power_law():
    res = np.array([5, 10, 20])
    assert cv.settled(res, 2.0 * res ** -2.0)
    assert cv.report(res, res ** -2.0)["order"] == pytest.approx(2.0)


def test_pre_asymptotic_ladder_is_extended_within_budget():
    res = np.array([5, 10, 20])
    err = res ** -2.0 + 0.5 * res ** -0.5 * (res < 8)  # first level pre-asymptotic
    assert not cv.settled(res, err)
    wall = 1e-3 * res ** 2.0
    assert cv.predicted_time(res, wall, 40) == pytest.approx(1.6, rel=1e-9)
    assert cv.extend(res, err, wall, budget=2.0) == 40
    assert cv.extend(res, err, wall, budget=1.0) is None
    assert cv.extend(res, 2.0 * res ** -2.0, wall, budget=100.0) is None
