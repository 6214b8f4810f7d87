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


def test_cost_to_accuracy_picks_the_cheapest_run_within_the_target():
    from app.report import cost_to_accuracy

    rows = [dict(solver="a", resolution=5, error=0.02, wall_time=1.0),
            dict(solver="a", resolution=10, error=0.002, wall_time=8.0),
            dict(solver="a", resolution=20, error=0.0005, wall_time=60.0),
            dict(solver="b", resolution=5, error=0.1, wall_time=3.0)]
    t = cost_to_accuracy(rows, 0.01)
    assert t[1][:2] == ["a", "resolution 10"] and t[1][3] == "8"
    assert t[2][:2] == ["b", "not reached on this ladder"]


def test_qualitative_gate_reads_as_outcome_and_fails_on_mismatch():
    from studies.common import Gate

    ok = Gate.expect("sph slab", "unstable", "unstable", "Swegle")
    bad = Gate.expect("hpm ring", "unstable", "stable", "004")
    assert ok.passed and not bad.passed
    assert "unstable (expected unstable)" in ok.line() and bad.line().startswith("FAIL")
