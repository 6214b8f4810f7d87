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


@pytest.mark.parametrize("study", studies.HEADLINE)
def test_every_gate_fails_a_threefold_regression(quick_gates, study):
    """Each gate passes on the quick run, fails when fed its regression (Gate.regressed: three
    times the error it recorded; an acceptance criterion, which has no error model, violated),
    and names its reference. No exceptions."""
    slipped = {}
    for g in quick_gates[study]:
        assert g.passed, g.line()
        assert g.kind in ("error", "exact", "order", "outcome", "criterion"), g
        assert g.reference, f"{g.name}: no word on why its reference is independent"
        r = g.regressed(3.0)
        if r.passed:
            slipped[g.name] = f"{g.kind} {r.observed:.3g} within {g.tolerance:.3g}"
    assert not slipped, slipped


@pytest.mark.parametrize("study", studies.HEADLINE)
def test_quick_run_evaluates_the_gates_it_declares(quick_gates, study):
    assert len(quick_gates[study]) == studies.get(study).N_GATES[True], \
        [g.name for g in quick_gates[study]]


def test_regression_of_each_kind():
    """Gate.regressed on each kind: an error gate at a third of its tolerance passes and fails
    tripled; an exact gate fails at a third of its defect; an outcome gate fails on the other
    outcome; an order gate of 2 against 1.5 fails at 2 − log2(3); a criterion fails just above
    its bound."""
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
    c = Gate.criterion("c", 0.0, 0.2, "r", "ref")  # a count of zero: three times it is zero
    assert c.passed and c.kind == "criterion" and not c.regressed().passed
    assert Gate.criterion("c", 0.2, 0.2, "r", "ref").passed  # the bound itself is met
    assert not Gate.criterion("c", float("nan"), 0.2, "r", "ref").passed


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

def plate_dataset(res=(5, 10, 20, 40), nan_at=None, nan_modal_at=None):
    """A plate dataset of the shape studies.plate.run writes, the discrete periods 0.1 % × (5/r)²
    off the reference (second order), csph's modal periods alike; ``nan_at``: (solver,
    resolution) whose run gave NaN; ``nan_modal_at``: the csph rung whose modal run did."""
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
    modal = np.full(shp, np.nan)
    modal[2] = T * (1 + 1e-4 * (5 / np.asarray(res, float)) ** 2)
    if nan_modal_at is not None:
        modal[2, list(res).index(nan_modal_at)] = np.nan
    dims = ("solver", "resolution")
    ds = xr.Dataset({"period": (dims, period), "amplitude": (dims, amplitude),
                     "energy_drift": (dims, drift), "status": (dims, status.astype(str)),
                     "modal_period": (dims, modal), "fem_modal_converged": ((), T)},
                    coords={"solver": solvers, "resolution": list(res)},
                    attrs={"analytic_period": 0.2541})
    return plate, ds


def test_plate_nan_at_the_finest_fails_its_gate():
    """csph's H/Δx = 40 run gave NaN: the gate at 40 is evaluated and fails (the old gates left it
    out); its modal run at 40 gave NaN: the observed order is evaluated and fails."""
    plate, ok = plate_dataset()
    good = plate.gates(ok)
    assert all(g.passed for g in good) and len(good) == plate.N_GATES[False], \
        [g.line() for g in good]
    _, ds = plate_dataset(nan_at=("csph", 40))
    g = plate.gates(ds)
    assert len(g) == plate.N_GATES[False]
    failed = [x.name for x in g if not x.passed]
    assert failed == ["plate csph at H/dx = 40: period vs FEM modal period"], failed
    _, ds = plate_dataset(nan_modal_at=40)
    g = plate.gates(ds)
    assert len(g) == plate.N_GATES[False]
    assert [x.name for x in g if not x.passed] == [
        "plate csph: observed order of the (modal) period error"]
    _, ds = plate_dataset(nan_modal_at=10)  # csph's period gate at 10 is the modal one
    g = plate.gates(ds)
    assert len(g) == plate.N_GATES[False]
    assert [x.name for x in g if not x.passed] == [
        "plate csph at H/dx = 10: modal period vs FEM modal period",
        "plate csph: observed order of the (modal) period error"]
    g = plate.gates(ok.drop_vars("modal_period"))  # a dataset without them: fails, says why
    assert [x.shown for x in g if not x.passed] == [
        "not evaluated: no modal periods in the dataset"] * 2


# The recorded full plate run (`workbench run plate`, 2 shared cores): the FEM's modal periods at
# 2, 4, 8, 16 elements across H (its dynamic run at 8: amplitude); csph's dynamic periods (the
# study's) and modal periods (the linearised eigenproblem, driver.solve(..., drive=Modal(1))) at
# H/Δx = 5, 10, 20, 40; hpm and hpm_vc at 10; periods s, amplitudes m, energy drifts.
FEM_MODAL = (0.25438521, 0.25499238, 0.25520061, 0.2552773)
FEM_AMPLITUDE_8 = 0.0229703917
CSPH_DYNAMIC = (0.25631088, 0.25534929, 0.255259, 0.25527305)
CSPH_MODAL = (0.25635094, 0.25538569, 0.25529733, 0.25530503)
AT_10 = {"csph": (0.2553492868, 0.0229723848, 8.75e-7), "hpm": (0.2597860426, 0.0233195916, 8.45e-7),
         "hpm_vc": (0.2552035162, 0.0229624265, 5.17e-7)}
FULL_PLATE_SLIPS = {
    "plate csph at H/dx = 10: amplitude vs FEM dynamic amplitude":
        "the tolerance carries the period's error into A = V/omega and adds the FEM's own; the "
        "amplitudes agree far closer (+0.009 %) than that model says, and no derivation of their "
        "own error is at hand. The FEM reference is itself not converged in its time step: its "
        "dynamic amplitude at 8 across H is 0.0229704 m at the study's 100 Newmark steps per "
        "period and 0.0229527 m at 200 (-0.077 %); at 4 across H 0.0229572, 0.0229387, "
        "0.0229481 m at 100, 200, 400 (not monotone: the higher modes' phase errors move the "
        "tip's peak); its mesh ladder at 100 steps (4, 8, 16 across H: 0.0229572, 0.0229704, "
        "0.0229751 m, order 1.5) puts its mesh error at 8 at 0.033 %, less than the step's. "
        "Against the 200-step FEM csph reads +0.086 %: the +0.009 % is partly the "
        "reference's step error, which the tolerance's own-error term (the mesh's period error, "
        "0.047 %) does not hold; the fix is a reference converged in its step (more steps and a "
        "step-halving error estimate), which needs a new full run",
    "plate hpm_vc at H/dx = 10: amplitude vs FEM dynamic amplitude":
        "as csph's: +0.035 % against a model of 0.11 % (+0.042 % against the 200-step FEM)",
}
"""Gates of the recorded full plate run whose tripled error still passes, each with why (the set
must be exactly this)."""


def recorded_plate_dataset():
    """The recorded full run in a plate dataset (studies.plate.run's shape)."""
    from studies import plate

    res = [2, 4, 5, 8, 10, 16, 20, 40]
    _, ds = plate_dataset(res=tuple(res))
    ds = ds.copy(deep=True)
    for v in ("period", "amplitude", "energy_drift", "modal_period"):
        ds[v][:] = np.nan
    ds.status[:] = "not run"
    ds.period.loc["analytic"] = ds.attrs["analytic_period"]
    ds.status.loc["analytic"] = "ok"
    ds.period.loc["fem", [2, 4, 8, 16]] = np.array(FEM_MODAL)
    ds.amplitude.loc["fem", 8] = FEM_AMPLITUDE_8
    ds.status.loc["fem", [2, 4, 8, 16]] = "ok"
    ds.period.loc["csph", [5, 10, 20, 40]] = np.array(CSPH_DYNAMIC)
    ds.modal_period.loc["csph", [5, 10, 20, 40]] = np.array(CSPH_MODAL)
    ds.status.loc["csph", [5, 10, 20, 40]] = "ok"
    for s, (T, A, d) in AT_10.items():
        ds.period.loc[s, 10], ds.amplitude.loc[s, 10], ds.energy_drift.loc[s, 10] = T, A, d
        ds.status.loc[s, 10] = "ok"
    ds.amplitude.loc["csph", 10], ds.energy_drift.loc["csph", 10] = AT_10["csph"][1:]
    ds["fem_modal_converged"] = ((), plate._extrapolated(ds.period.sel(solver="fem").values,
                                                          ds.resolution.values))
    return plate, ds


def test_every_gate_of_the_recorded_full_plate_run_fails_a_threefold_regression():
    """All of the full run's gates (N_GATES) pass on its recorded values; each fails its
    regression but those of FULL_PLATE_SLIPS, named with why."""
    plate, ds = recorded_plate_dataset()
    gates = plate.gates(ds)
    assert len(gates) == plate.N_GATES[False]
    assert all(g.passed for g in gates), [g.line() for g in gates if not g.passed]
    slipped = {g.name for g in gates if g.regressed(3.0).passed}
    assert slipped == set(FULL_PLATE_SLIPS), slipped


def test_plate_gates_on_the_recorded_full_run():
    """The recorded full run passes the csph gates at H/Δx = 40 and the order gate, and each fails
    its regression (three times the error at 40; the order less log2(3)). The old order gate, on
    the dynamic periods against the modal limit, read 1.18 from the same run (their error tends to
    the finite amplitude's shift, −0.02 %, not to zero): it failed a run without a defect."""
    from studies.common import observed_order

    plate, ds = recorded_plate_dataset()
    ref = float(ds.fem_modal_converged)
    g = {x.name: x for x in plate.gates(ds)}
    fine = g["plate csph at H/dx = 40: period vs FEM modal period"]
    order = g["plate csph: observed order of the (modal) period error"]
    for x in (fine, order):
        assert x.passed and not x.regressed(3.0).passed, x.line()
    assert order.observed == pytest.approx(1.91, abs=0.01)
    # csph's period at 10 like with like (modal against the modal limit): +0.025 %, and a tripled
    # error fails; the dynamic period against it (+0.011 %, the old gate) mixes the finite
    # amplitude's −0.014 % in, and its tripled error passed the same derivation's tolerance
    at10 = g["plate csph at H/dx = 10: modal period vs FEM modal period"]
    assert at10.passed and not at10.regressed(3.0).passed, at10.line()
    assert at10.observed == pytest.approx(CSPH_MODAL[1] / ref - 1, rel=1e-9)
    assert 3 * abs(CSPH_DYNAMIC[1] / ref - 1) < plate.TOL_PERIOD_MODAL
    h = 1.0 / np.array([5, 10, 20, 40])
    assert observed_order(h, np.array(CSPH_DYNAMIC) - ref) < plate.MIN_ORDER  # the old gate
    # the dynamic periods' error tends to a constant: the finite amplitude's shift, which the
    # modal periods do not have (dynamic/modal − 1 the same on every rung, −0.013 … −0.016 %)
    shift = np.array(CSPH_DYNAMIC) / np.array(CSPH_MODAL) - 1
    assert np.all((-2e-4 < shift) & (shift < -1e-4)), shift


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
# own tolerance (the plate's whole full run: test_every_gate_of_the_recorded_full_plate_run_...).
# Where a tripled recorded error still passes, the tolerance is the method's expected error and
# the recorded error lies far below it (a cancellation the derivation cannot promise): marked,
# strict, with why, so that the list stays the true one (issue 42's note names each).
RECORDED = [
    ("plate", "TOL_PERIOD_CONSISTENT", 3e-4, "hpm_vc at H/dx = 10, modal (README)"),
    ("plate", "TOL_FEM_THIN_PLATE", 4.7e-3, "FEM at 16 across H (notes.md: 0.2553 s)"),
    ("cantilever", "TOL_CONSISTENT_FEM", 1.0e-3, "csph at H/dx = 10, largest load (README)"),
    pytest.param("cantilever", "TOL_CONSISTENT_FEM", 3e-4, "hpm_vc at H/dx = 10 (README)",
                 marks=pytest.mark.xfail(strict=True, reason=(
                     "cannot be tightened: the expected error at H/dx = 10 is the bulk's O(dx^2) "
                     "term plus the clamp's corner term; hpm_vc's bulk, measured on the free-free "
                     "beam without corners (tests/test_consistency.py's set-up, H/dx = 5, 10, 20, "
                     "40: period +0.208, +0.0435, +0.0100, +0.0025 % from the order-2 limit, "
                     "order 2.2), is +0.087 % of the compliance, and its +0.03 % on the cantilever "
                     "leaves a corner term of -0.06 %, of the bulk's size and opposite sign: a "
                     "tolerance catching the tripled 0.09 % would lie at the bulk term alone. No "
                     "like-with-like quantity exists in the study: its other rungs carry the same "
                     "two terms (at 20: +0.020 % and about -0.025 % at the corner's order ~1.2, a "
                     "cancellation again), an order gate cannot see a constant factor, and gating "
                     "the corner term apart needs a model of its size that no derivation gives"))),
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


@pytest.mark.parametrize("r,recorded", [(5, 5.69e-2), (10, 1.86e-2), (15, 8.6e-3)])
def test_microcantilever_3d_static_slope_gates_fail_a_threefold_recorded_error(r, recorded):
    """The default 3-D run's static csph slopes (README: +5.69, +1.86, +0.86 % at H/Δx = 5, 10,
    15 from the FEM's limit, whose own error at H/h = 5 is 8778.3/8324.1 − 1) against the gates
    that read them: each rung's max(1 %, e_FEM(5)(10/r)^p) and, at the finest (15), the issue's
    1 % (TOL_SLOPE, finest_slope_gates). A tripled error fails one of them at least: at 5 and 10
    the rung's own; at 15 the rung's error model asks 3.5 % — csph lies 4 times below the FEM's
    error at the same nodal spacing, a margin the model cannot promise, so the rung's tolerance
    stays the model's — and the finest's 1 % fails the tripled 2.6 %."""
    from studies.microcantilever.gates import TOL_SLOPE, _tolerance
    from studies.microcantilever.ladders import STATIC_RESOLUTIONS_3D

    tols = [_tolerance(5, 8778.3 / 8324.1 - 1, r)]
    if r == max(STATIC_RESOLUTIONS_3D):
        tols.append(TOL_SLOPE)
    assert all(recorded <= t for t in tols)
    assert any(not Gate.at_most("slope", recorded, t, "r", "ref").regressed(3.0).passed
               for t in tols), (r, tols)
