"""Oscillating plate (004 D) with CSPH: energy conservation of the undamped symplectic run, the
period and amplitude gates against the FEM at H/Δx = 10 (issue 4 item 6), convergence of the
period with refinement, a blow-up reported as a status, the hourglass option."""
import dataclasses
import math

import fem_reference as fem
import numpy as np
import pytest

from sph import driver
from studies.plate import (TOL_AMPLITUDE_CONSISTENT, TOL_DRIFT, TOL_PERIOD_CONSISTENT,
                           TOL_PERIOD_MODAL)
from workbench.analytic import plate_amplitude
from workbench.scenes import Plate
from workbench.scenes.model import Modal

# The study's tolerances (studies/plate.py says why each is what it is): integration-consistent
# CSPH (issue 10) is second order, its period at H/Δx = 10 within the bulk error plus the finite
# amplitude's shift (the paper's nodal CSPH misses it: −0.19 % quadratic, +2.7 % Bonet–Lok); the
# amplitude A ∝ V c0/ω carries the period's error plus the peak's sampling.
PERIOD_GATE = TOL_PERIOD_CONSISTENT
MODAL_GATE_10 = TOL_PERIOD_MODAL  # the modal period, like with like: no finite-amplitude term
AMPLITUDE_GATE = TOL_AMPLITUDE_CONSISTENT
THIN_PLATE_GATE = 0.05  # the linear thin-plate amplitude ignores the 2-D and nonlinear effects
ENERGY_GATE = TOL_DRIFT  # issue 4: total energy within 0.1 % over two periods without damping
# The modal period at H/Δx = 20: second order from the bulk's 0.04 % at 10 (free–free beam,
# tests/test_consistency.py) predicts 0.01 %, the clamped corners' term falls alike (was 5e-4
# against a measured −0.0041 %, which a ten-fold regression passed; a tripled 0.012 % fails now).
MODAL_GATE_20 = 1e-4


def csph(scene, resolution, **options):
    return driver.solve("csph", scene, resolution, **options)


def modal_period(scene, resolution):
    return driver.solve("csph", scene, resolution, drive=Modal(3))["periods"]


def fem_period(scene):
    return fem.reference(scene, "period")


def test_energy_conserved_over_two_periods_coarse():
    # H/Δx = 4 keeps it fast; velocity Verlet's energy error is bounded (symplectic) and
    # O(dt²): measured 6e-6 of the initial energy at dt_factor 0.3
    r = csph(Plate(), 4)
    assert r["status"] == "ok"
    E = r["kinetic_energy"] + r["strain_energy"]
    assert r["time"][-1] >= 2 * 0.25
    drift = (E.max() - E.min()) / E[0]
    assert drift < ENERGY_GATE, drift
    assert np.isfinite(r["period"])


def test_plate_period_and_amplitude_gate_h10(quick_verify):
    """The csph plate at H/Δx = 10 as `workbench verify --quick` ran it (plate.nc; one run per test
    session, tests/conftest.py): period and modal period (the quick run computes it at 10, the
    study's period gate) against the FEM's converged modal period, amplitude against the FEM's
    dynamic run and, looser, the linear thin-plate value V_f c0/ω, energy drift."""
    import xarray as xr

    out, proc = quick_verify
    assert proc.returncode == 0, proc.stderr[-2000:]
    with xr.open_dataset(out / "plate.nc") as ds:
        pt = ds.sel(solver="csph", resolution=10)
        assert str(pt.status.values) == "ok"
        period, amplitude, drift = float(pt.period), float(pt.amplitude), float(pt.energy_drift)
        modal = float(pt.modal_period)
    scene = Plate()
    err_T = period / fem_period(scene) - 1
    assert abs(err_T) < PERIOD_GATE, err_T  # measured +0.016 %
    err_M = modal / fem_period(scene) - 1
    assert abs(err_M) < MODAL_GATE_10, err_M  # recorded +0.025 % against the FEM's limit
    err_A = amplitude / fem.reference(scene, "amplitude") - 1
    assert abs(err_A) < AMPLITUDE_GATE, err_A  # measured +0.008 %
    assert abs(amplitude / plate_amplitude(scene) - 1) < THIN_PLATE_GATE
    assert abs(drift) < ENERGY_GATE, drift


def test_period_converges_with_refinement():
    """Linearised (modal) period of the discrete plate at H/Δx = 5, 10, 20: successive differences
    shrink by more than 3× (observed order > 1.5; measured 3.4) and the finest is within
    MODAL_GATE_20 of the FEM (second order from the bulk's 0.04 % at H/Δx = 10 predicts 0.01 %;
    measured −0.0041 %; the nodal CSPH's limit lay 0.16 % above the FEM's)."""
    scene = Plate()
    T = np.array([modal_period(scene, r)[0] for r in (5, 10, 20)])
    d1, d2 = abs(T[1] - T[0]), abs(T[2] - T[1])
    order = math.log2(d1 / d2)
    assert order > 1.5, (T, order)
    assert abs(T[2] / fem_period(scene) - 1) < MODAL_GATE_20, T


def test_dynamic_period_matches_modal_period():
    """The explicit run's period (crossings of the history's mean) equals the linearised one to the
    nonlinearity of the 0.12 L amplitude (measured 0.01 % at H/Δx = 5). 1.75 periods: a period is
    measured from three crossings at least (workbench.oscillation.MIN_CROSSINGS)."""
    scene = Plate()
    r = csph(dataclasses.replace(scene, periods=1.75), 5)
    T = modal_period(scene, 5)[0]
    assert abs(r["period"] / T - 1) < 5e-3


def test_blow_up_is_a_status_not_an_exception():
    r = csph(dataclasses.replace(Plate(), dt_factor=3.0, periods=0.2), 4)
    assert r["status"].startswith("unstable:") and "at t=" in r["status"], r["status"]
    assert math.isnan(r["period"])


def test_hourglass_control_reduces_the_spurious_mode_measure():
    scene = Plate()
    scene = dataclasses.replace(scene, periods=0.6)
    off = csph(scene, 5)
    on = csph(scene, 5, hourglass=1.0)
    assert on["status"] == off["status"] == "ok"
    assert on["hourglass_strain"].max() < off["hourglass_strain"].max()
    E = on["kinetic_energy"] + on["strain_energy"]
    assert (E.max() - E.min()) / E[0] < ENERGY_GATE  # the hourglass energy is conservative
