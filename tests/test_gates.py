"""Gates that cannot slip (issue 42): every gate of every headline study fails when fed a
regression — three times its error (an ``error`` gate), a third of the smallest defect it stands
guard against (an ``exact`` gate), the other outcome (an ``outcome`` gate), the order a three-fold
error at the finest rung would show (an ``order`` gate) — each says why its reference is
independent of what it checks, a run that is missing or gave NaN fails its gate (never removes
it), and each study evaluates the number of gates it declares (``N_GATES``), which ``verify``
checks."""
import numpy as np
import pytest
import xarray as xr

import studies
from studies.common import Gate, count_gate


@pytest.fixture(scope="module")
def quick_gates(quick_verify):
    """The gates of each headline study, evaluated on the datasets `workbench verify --quick` wrote
    (tests/conftest.py: one run per session)."""
    out, _ = quick_verify
    gates = {}
    for name in studies.HEADLINE:
        with xr.open_dataset(out / f"{name}.nc") as ds:
            gates[name] = studies.get(name).gates(ds.load())
    return gates


KNOWN_SLIPS = {
    "plate csph at H/dx = 10: period vs FEM modal period":
        "the quick run's reference, the FEM extrapolated from 2, 4, 8 elements across H, lies "
        "0.015 % above the full run's (2 to 16): csph reads +0.016 % against it, +0.0305 % against "
        "the full one, whose tripled 0.09 % fails TOL_PERIOD_CONSISTENT (test below)",
    **{f"microcantilever {case} compression H/dx=5: failed particles outside the {where}":
       "none failed outside the low eps_L's material: a count of zero, which no factor moves; the "
       "issue's 80 % is the criterion, not an error model"
       for case, where in (("inter", "grain boundaries"), ("intra", "grains"))},
    **{f"microcantilever {case} compression H/dx=5: kinetic / elastic energy before the first "
       "failure": "0.27 % against the issue's 1 % for quasi-static loading, a physical criterion "
       "(the ramp's start-up transient 4/(omega_1 t)^2 alone is 0.4 %), not an error model"
       for case in ("inter", "intra")},
}
"""Gates of the quick run whose tripled error still passes: the tolerance is the error the method
should have and the run's error lies far below it (a cancellation no derivation promises); each
is named in issue 42's note. The set must be exactly this (a gate that joins it, or leaves it,
fails the test)."""


@pytest.mark.parametrize("study", studies.HEADLINE)
def test_every_gate_fails_a_threefold_regression(quick_gates, study):
    """Each gate passes on the quick run, fails when fed its regression (Gate.regressed: three
    times the error it recorded), and names its reference."""
    slipped = {}
    for g in quick_gates[study]:
        assert g.passed, g.line()
        assert g.kind in ("error", "exact", "order", "outcome"), g
        assert g.reference, f"{g.name}: no word on why its reference is independent"
        r = g.regressed(3.0)
        if r.passed:
            slipped[g.name] = f"{g.kind} {r.observed:.3g} within {g.tolerance:.3g}"
    known = {k: v for k, v in KNOWN_SLIPS.items() if k.startswith(study)}
    assert set(slipped) == set(known), slipped


@pytest.mark.parametrize("study", studies.HEADLINE)
def test_quick_run_evaluates_the_gates_it_declares(quick_gates, study):
    assert len(quick_gates[study]) == studies.get(study).N_GATES[True], \
        [g.name for g in quick_gates[study]]


def test_regression_of_each_kind():
    """Gate.regressed on each kind: an error gate at a third of its tolerance passes and fails
    tripled; an exact gate fails at a third of its defect; an outcome gate fails on the other
    outcome; an order gate of 2 against 1.5 fails at 2 − log2(3)."""
    e = Gate.at_most("e", 0.4, 1.0, "r", "ref")
    assert e.passed and not e.regressed().passed
    assert Gate.at_most("e", 0.3, 1.0, "r", "ref").regressed().passed  # a loose tolerance slips
    x = Gate.at_most("x", 1e-12, 1e-6, "r", "ref", defect=1e-3)
    assert x.passed and x.kind == "exact" and not x.regressed().passed
    assert Gate.at_most("x", 1e-12, 1e-3, "r", "ref", defect=1e-3).regressed().passed
    o = Gate.expect("o", "stable", "stable", "r", "ref")
    assert o.passed and not o.regressed().passed
    p = Gate.at_least("p", 2.0, 1.5, "r", "ref")
    assert p.passed and not p.regressed().passed


def test_missing_gate_fails_and_says_why():
    g = Gate.missing("plate csph at H/dx = 40", "no run", 2e-4, "r", "ref")
    assert not g.passed and np.isnan(g.observed) and "not evaluated: no run" in g.line()
    assert not Gate.at_most("g", float("nan"), 1.0, "r").passed


def test_count_gate_fails_when_a_gate_vanished():
    gates = [Gate.at_most("a", 0.1, 1.0, "r")] * 3
    assert count_gate("plate", gates, 3).passed
    bad = count_gate("plate", gates, 4)
    assert not bad.passed and "3 (declared 4)" in bad.line()


# -- a NaN or missing run fails its gate --------------------------------------------------------

def plate_dataset(res=(5, 10, 20, 40), nan_at=None):
    """A plate dataset of the shape studies.plate.run writes, the discrete periods 0.1 % × (5/r)²
    off the reference (second order); ``nan_at``: (solver, resolution) whose run gave NaN."""
    from studies import plate

    solvers = ["analytic", "fem", "csph", "hpm", "hpm_vc"]
    T = 0.2553
    shp = (len(solvers), len(res))
    period = np.full(shp, np.nan)
    status = np.full(shp, "not run", dtype=object)
    for i, s in enumerate(solvers):
        for j, r in enumerate(res):
            if s == "analytic" or (s in ("hpm", "hpm_vc") and r != 10):
                continue
            period[i, j] = T * (1 + 1e-3 * (5 / r) ** 2 * (0.1 if s != "hpm" else 10))
            status[i, j] = "ok"
    period[0] = 0.2541
    amplitude = np.where(np.isfinite(period), 0.02, np.nan)
    drift = np.where(np.isfinite(period), 1e-6, np.nan)
    if nan_at is not None:
        i, j = solvers.index(nan_at[0]), list(res).index(nan_at[1])
        period[i, j] = amplitude[i, j] = drift[i, j] = np.nan
        status[i, j] = "unstable: NaN at t=0.1"
    dims = ("solver", "resolution")
    ds = xr.Dataset({"period": (dims, period), "amplitude": (dims, amplitude),
                     "energy_drift": (dims, drift), "status": (dims, status.astype(str)),
                     "fem_modal_converged": ((), T)},
                    coords={"solver": solvers, "resolution": list(res)},
                    attrs={"analytic_period": 0.2541})
    return plate, ds


def test_plate_nan_at_the_finest_fails_its_gate():
    """csph's H/Δx = 40 run gave NaN: the gate at 40 and the observed order are evaluated and fail
    (the old gates left both out, and the study passed with two gates fewer)."""
    plate, ok = plate_dataset()
    good = plate.gates(ok)
    assert all(g.passed for g in good) and len(good) == plate.N_GATES[False], \
        [g.line() for g in good]
    _, ds = plate_dataset(nan_at=("csph", 40))
    g = plate.gates(ds)
    assert len(g) == plate.N_GATES[False]
    failed = [x.name for x in g if not x.passed]
    assert failed == ["plate csph at H/dx = 40: period vs FEM modal period",
                      "plate csph: observed order of the period error"], failed


def test_plate_nan_at_h10_fails_all_three_gates():
    plate, ds = plate_dataset(nan_at=("hpm_vc", 10))
    g = plate.gates(ds)
    assert len(g) == plate.N_GATES[False]
    assert sorted(x.name for x in g if not x.passed) == sorted(
        f"plate hpm_vc at H/dx = 10: {w}" for w in (
            "period vs FEM modal period", "amplitude vs FEM dynamic amplitude",
            "|energy drift| over the run, no damping"))


def cantilever_dataset(nan_fem=False, nan_at=None):
    """A cantilever dataset of the shape studies.cantilever.run writes (second-order errors)."""
    from studies import cantilever

    solvers = ["analytic", "fem", "csph", "hpm", "hpm_vc", "csph_quad"]
    res = [2, 4, 5, 8, 10, 16, 20, 40]
    loads = np.array([0.00192, 1.0, 2.0, 5.0])
    ladders = {"fem": (2, 4, 8, 16), "csph": (5, 10, 20, 40), "hpm": (5, 10, 20, 40),
               "hpm_vc": (5, 10, 20), "csph_quad": (5, 10, 20)}
    ref = np.array([1.0, 2.0, 3.0, 4.0])
    tip = np.full((len(solvers), len(res), len(loads)), np.nan)
    status = np.full((len(solvers), len(res)), "not run", dtype=object)
    for i, s in enumerate(solvers):
        if s == "analytic":
            tip[i] = ref * 0.99
            status[i] = "ok"
            continue
        for r in ladders[s]:
            j = res.index(r)
            tip[i, j] = ref * (1 + 1e-3 * (10 / r) ** 2 * (0.5 if s != "csph_quad" else 3))
            status[i, j] = "ok"
    if nan_fem:
        tip[1] = np.nan
        status[1] = "error: RuntimeError: singular"
    if nan_at is not None:
        i, j = solvers.index(nan_at[0]), res.index(nan_at[1])
        tip[i, j] = np.nan
        status[i, j] = "unstable: NaN at load 2"
    d3 = ("solver", "resolution", "load")
    ds = xr.Dataset({"tip_deflection": (d3, tip),
                     "status": (("solver", "resolution"), status.astype(str)),
                     "timoshenko": (("load",), ref * 1.005), "fem_converged": (("load",), ref)},
                    coords={"solver": solvers, "resolution": res, "load": loads})
    return cantilever, ds


def test_cantilever_nan_runs_fail_their_gates():
    """The FEM ladder failed: its two gates are evaluated and fail (the old gates left them out);
    csph's H/Δx = 40 gave NaN: its observed order fails (the old gate dropped the rung and fitted
    the order over the three left)."""
    cantilever, ok = cantilever_dataset()
    good = cantilever.gates(ok)
    assert all(g.passed for g in good) and len(good) == cantilever.N_GATES[False], \
        [g.line() for g in good]
    _, ds = cantilever_dataset(nan_fem=True)
    g = cantilever.gates(ds)
    assert len(g) == cantilever.N_GATES[False]
    assert [x.name for x in g if not x.passed][:2] == [
        "cantilever fem: small-load tip deflection vs Timoshenko",
        "cantilever fem: large-load tip deflection vs elastica"]
    _, ds = cantilever_dataset(nan_at=("csph", 40))
    g = cantilever.gates(ds)
    assert len(g) == cantilever.N_GATES[False]
    assert [x.name for x in g if not x.passed] == [
        "cantilever csph: observed order of the tip error (largest load)"]


def test_stability_crashed_run_is_not_an_expected_instability():
    """A run that raised ('error: ...') is not 'unstable': classic SPH's expected instability
    gate fails on it (it used to pass, reading the crash as the instability)."""
    from studies import stability

    solvers, scenes, factors = ["hpm", "sph", "csph"], ["ring", "slab", "rings", "plate"], [0.5, 1.0]
    stable = np.ones((3, 4, 2), bool)
    status = np.full((3, 4, 2), "ok", dtype=object)
    stable[1, :2] = False
    status[1, 0] = "unstable: clumping at t=0.01"
    status[1, 1] = "error: ValueError: boom"
    d = ("solver", "scene", "dt_factor")
    ds = xr.Dataset({"stable": (d, stable), "status": (d, status.astype(str))},
                    coords={"solver": solvers, "scene": scenes, "dt_factor": factors})
    g = {x.name: x for x in stability.gates(ds)}
    assert g["stability: sph ring at dt factor 0.5"].passed
    assert not g["stability: sph slab at dt factor 0.5"].passed


# -- the gates of the full runs, on their recorded errors ----------------------------------------
# The quick run holds a part of the gates; the full runs (too slow for the tests) hold the rest.
# For those the errors the README and the study modules record are fed three-fold to the study's
# own tolerance. Where a tripled recorded error still passes, the tolerance is the method's expected
# error and the recorded error lies far below it (a cancellation the derivation cannot promise):
# marked, strict, so that the list stays the true one (issue 42's note names each).
SLIPS = pytest.mark.xfail(strict=True, reason="recorded error far below the method's expected error")
RECORDED = [
    ("plate", "TOL_PERIOD_CONSISTENT", 3.05e-4, "csph at H/dx = 10, dynamic (issue 42)"),
    ("plate", "TOL_PERIOD_CONSISTENT", 3e-4, "hpm_vc at H/dx = 10, modal (README)"),
    ("plate", "TOL_PERIOD_FINE", 7e-5, "csph at H/dx = 40, modal (tests/test_consistency.py)"),
    ("plate", "TOL_PERIOD", 1.8e-2, "hpm at H/dx = 10 (README)"),
    ("plate", "TOL_FEM_THIN_PLATE", 4.7e-3, "FEM at 16 across H (notes.md: 0.2553 s)"),
    ("cantilever", "TOL_CONSISTENT_FEM", 1.0e-3, "csph at H/dx = 10, largest load (README)"),
    pytest.param("cantilever", "TOL_CONSISTENT_FEM", 3e-4, "hpm_vc at H/dx = 10 (README)",
                 marks=SLIPS),
    ("cantilever", "TOL_PAPER_FEM", 3.5e-3, "csph_quad at H/dx = 10 (README)"),
    ("cantilever", "TOL_FEM_ELASTICA", 1.9e-2, "FEM at load 5 (tests/test_fem_cantilever.py)"),
    ("rc_beam", "TOL_SLOW", 3.7e-2, "slow impact, csph at 8 ms (studies/rc_beam/slow_impact.py)"),
    ("microcantilever", "TOL_SLOPE", 8.6e-3, "csph static H/dx = 15, 3-D, the finest (README)"),
    ("microcantilever", "TOL_SLOPE", 3.5e-3, "csph static H/dx = 40, 2-D root ladder (README)"),
    ("microcantilever", "TOL_FIRST_FAILURE", 2.15e-2, "intra, csph static H/dx = 40, 2-D (README)"),
]


@pytest.mark.parametrize("study,tolerance,recorded,source", RECORDED)
def test_full_run_gates_fail_a_threefold_recorded_error(study, tolerance, recorded, source):
    tol = getattr(studies.get(study), tolerance)
    assert recorded <= tol, f"{source}: the recorded error fails the gate itself"
    assert not Gate.at_most(tolerance, recorded, tol, source).regressed(3.0).passed, \
        f"{source}: {3 * recorded:.3g} within {tolerance} = {tol:.3g}"


def test_exactness_gates_of_the_full_run_catch_their_defect():
    """The exactness gates of the full runs fail at a third of the defect they stand guard
    against (their quick counterparts are fed it in test_every_gate_fails_a_threefold_regression)."""
    from studies import plate, rc_beam, ss_curve, stability_theory

    for tol, defect in ((rc_beam.TOL_ENERGY, rc_beam.ENERGY_DEFECT[False]),
                        (rc_beam.TOL_MOMENTUM, rc_beam.MOMENTUM_DEFECT),
                        (plate.TOL_DRIFT, plate.DRIFT_DEFECT),
                        (ss_curve.TOL_CONSISTENT, ss_curve.DEFECT),
                        (stability_theory.TOL_SECULAR, stability_theory.SECULAR_DEFECT)):
        assert not Gate.at_most("x", 0.0, tol, "r", "ref", defect=defect).regressed().passed, tol


@pytest.mark.parametrize("r,recorded", [
    (5, 5.69e-2), (10, 1.86e-2),
    pytest.param(15, 8.6e-3, marks=SLIPS)])
def test_microcantilever_3d_static_slope_gates_fail_a_threefold_recorded_error(r, recorded):
    """The default 3-D run's static csph slopes (README: +5.69, +1.86, +0.86 % at H/Δx = 5, 10,
    15 from the FEM's limit, whose own error at H/h = 5 is 8778.3/8324.1 − 1) against their
    tolerance max(1 %, e_FEM(5)(10/r)^p). At 15 the error model asks 3.5 % and csph is at 0.86 %:
    a tripled error passes (the finest's own 1 % gate, TOL_SLOPE, fails it)."""
    from studies.microcantilever.gates import _tolerance

    tol = _tolerance(5, 8778.3 / 8324.1 - 1, r)
    assert recorded <= tol
    assert not Gate.at_most("slope", recorded, tol, "r", "ref").regressed(3.0).passed, (r, tol)
