"""The Period observable (issue 40.1, issue 38.4): a period measured about the history's own mean,
one definition for the particle methods and the FEM, and NaN with a reason where there is no
oscillation to measure."""
import math

import numpy as np
import pytest

from workbench.oscillation import measure_period

T = 0.7
t = np.linspace(0.0, 2.3, 401)  # 3.3 periods, 122 samples per period


def test_one_definition_for_every_method():
    import fem_reference.model as fem
    import sph.diagnostics as diag
    from workbench import oscillation

    assert diag.period_amplitude is fem.period_amplitude is oscillation.period_amplitude


@pytest.mark.parametrize("mean", [-0.1, 5.0, 0.0])
def test_period_about_the_mean(mean):
    """A beam swinging under gravity between its rest shape and twice its sag never changes sign:
    u = −A (1 − cos ωt); a history about a large offset neither. The crossings of the history's
    own mean give the period; the crossing times are interpolated linearly between samples, off
    by O((ω Δt)²/24) of a half period at a peak's curvature — with 122 samples per period below
    1e-4 of the period (zero crossings gave NaN, or the period of the noise about zero)."""
    from sph.diagnostics import period_amplitude

    u = mean + 0.1 * (np.sin if mean == 0.0 else np.cos)(2 * np.pi * t / T)
    Tm, _ = period_amplitude(t, u)
    assert Tm == pytest.approx(T, rel=1e-4)
    m = measure_period(t, u)
    assert m["status"] == "ok" and m["mean"] == pytest.approx(mean, abs=1e-5)
    assert m["oscillation"] == pytest.approx(0.1, rel=1e-3)


def test_swinging_from_rest_with_round_off_at_the_start():
    """The issue's case: released from rest, u starts at 0 with round-off of either sign (x − X)
    and swings below zero; the zero crossings of that noise made a period 70x too short."""
    from sph.diagnostics import period_amplitude

    u = -0.1 * (1 - np.cos(2 * np.pi * t / T)) + 1e-17 * (-1.0) ** np.arange(len(t))
    assert period_amplitude(t, u)[0] == pytest.approx(T, rel=1e-4)


def test_no_oscillation_is_nan_and_says_why():
    from fem_reference.model import period_amplitude

    # round-off about zero (the plate at V_f = 1e-300: positions of size 0.24 m, u = x − X)
    noise = 4e-16 * np.random.default_rng(0).standard_normal(len(t))
    assert math.isnan(period_amplitude(t, noise, 0.24)[0])
    assert "round-off" in measure_period(t, noise, 0.24)["status"]
    # a drift and a single swing: fewer than 1.5 cycles
    for u in (t, np.sin(2 * np.pi * t / (2 * t[-1]))):
        m = measure_period(t, u)
        assert math.isnan(m["period"]) and m["status"].startswith("no oscillation"), m
    # a real oscillation far below the body's size but far above round-off is measured
    assert measure_period(t, 1e-9 * np.sin(2 * np.pi * t / T), 0.24)["period"] == pytest.approx(T, rel=1e-4)


def test_plate_at_round_off_velocity_has_no_period():
    """Issue 38.4: the plate with V_f = 1e-300 moves by round-off only; its 'period' was 0.004 s
    (the true one 0.254 s) with status ok."""
    from sph import driver
    from workbench.scenes.headline import Plate

    from workbench.oscillation import with_period_notes

    out = driver.solve("csph", Plate(V_f=1e-300, periods=1.5), 5)
    assert math.isnan(out["period"])
    assert out["status"] == "ok"  # the run itself; the period says why it has no value
    assert "round-off" in out["period_status"]
    # the status the plate study (and a user's scene's dataset) stores
    assert with_period_notes(out["status"], out, ["period"]).startswith("ok (period: no oscillation")
    assert with_period_notes("ok", {"period_status": "ok"}, ["period"]) == "ok"
