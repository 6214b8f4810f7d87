"""The micro-cantilever study (studies/microcantilever/) at its quick setting and the scene's bad
input: one line naming the parameter and its allowed range, exit status 2 from the command line."""
import numpy as np
import pytest

from sph import driver
from studies.microcantilever.scene import MicroCantilever
from workbench.scenes.params import ParameterError, SceneError


@pytest.mark.parametrize("kw,name", [
    (dict(eps_L_low=0.0), "eps_L_low"), (dict(eps_L_high=-1.0), "eps_L_high"),
    (dict(gb_thickness=5e-6), "gb_thickness"), (dict(gb_thickness=0.0), "gb_thickness"),
    (dict(n_grains=2.5), "n_grains"), (dict(n_grains=0), "n_grains"),
    (dict(velocity=0.0), "velocity"), (dict(velocity=-1.0), "velocity")])
def test_bad_parameters(kw, name):
    with pytest.raises(ParameterError) as err:
        MicroCantilever(**kw)
    msg = str(err.value)
    assert msg.startswith(f"{name}:") and "allowed" in msg and "\n" not in msg


def test_grain_boundary_thinner_than_the_spacing():
    with pytest.raises(SceneError) as err:
        driver.model_at(MicroCantilever(gb_thickness=0.5e-6), 5)
    msg = str(err.value)
    assert msg.startswith("gb_thickness:") and "spacing" in msg and "\n" not in msg


@pytest.mark.parametrize("kw", [dict(block_margin=-1e-6)])
def test_bad_block_margin(kw):
    with pytest.raises(ParameterError) as err:
        MicroCantilever(**kw)
    assert str(err.value).startswith("block_margin:") and "allowed" in str(err.value)


def test_a_run_is_validated_on_its_own_ladder():
    """The checks before a run (resolutions, memory) take the ladder the run will take: the 3-D
    one for the 3-D scene (the 2-D ladder's H/Δx = 20 in 3-D would need about 25 GB and was
    refused), the 2-D one in 2-D."""
    from studies import common, microcantilever as mc
    from studies.microcantilever.ladders import RESOLUTIONS_3D

    _, lads = common.validate(mc, MicroCantilever())
    assert lads == {"csph": list(RESOLUTIONS_3D), "csph_bl": list(RESOLUTIONS_3D)}
    _, lads = common.validate(mc, MicroCantilever(dim=2))
    assert lads == {s: list(mc.RESOLUTIONS[s]) for s in ("csph", "csph_bl")}


def test_cli_bad_input_exit_status(tmp_path, capsys):
    from app.cli import main

    assert main(["run", "microcantilever", "--quick", "--out", str(tmp_path),
                 "--set", "gb_thickness=2e-7"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "gb_thickness" in err
    assert main(["run", "microcantilever", "--quick", "--out", str(tmp_path),
                 "--set", "velocity=0"]) == 2


# ------------------------------------------------------------------------------------------------
# The study at its quick setting
# ------------------------------------------------------------------------------------------------

def test_microcantilever_quick_study(quick_verify):
    """``workbench verify --quick`` ran the study at its quick setting (both cases, 2-D, H/Δx = 5,
    the default rule; conftest's session fixture, not run again here): every gate passes on the
    dataset read back from ``microcantilever.nc``; it holds the load–deflection curves, failed
    fractions, energies and the energy of the main crack with units; the figures are written."""
    import xarray as xr

    import studies

    out, _ = quick_verify
    with xr.open_dataset(out / "microcantilever.nc") as ds:
        gates = studies.get("microcantilever").gates(ds)
        bad = [g.line() for g in gates if not g.passed]
        assert not bad, bad
        # 10 (five per case) + the FEM ladder + the slope of each case: the study's declared count
        assert len(gates) == studies.get("microcantilever").N_GATES[True] == 13
        for v in ("load", "deflection", "failed_fraction", "external_work", "kinetic_energy",
                  "fem_load", "fem_elastic_slope", "slope_error_fem", "elastic_energy",
                  "plastic_work", "released_energy", "fracture_energy"):
            assert ds[v].attrs["units"] and np.isfinite(ds[v].values).any(), v
        assert ds.attrs["plane"] == "strain"
        # the main crack crosses the section: at least one particle per row at H/dx = 5
        assert np.all(ds.n_crack.values >= 5), ds.n_crack.values
    assert (out / "microcantilever_cracks.png").exists()


# The material code path the FEM reference and csph share
# ------------------------------------------------------------------------------------------------

def _uniaxial_swift(mat, eps):
    """Closed form of Hencky–J2 with Swift hardening under uniaxial stress at total log strain
    ``eps`` (no rotation of the principal axes, so the exponential map reduces to 1-D plasticity in
    log strains): τ = E ε_e, ε = ε_e + ε_p and, once yielded, E ε_e = C (ε_p + ε0)^n (a scalar root
    by brentq); lateral log strain −ν ε_e − ε_p/2. Returns (τ11, ε_p, lateral strain)."""
    from scipy.optimize import brentq

    sy = lambda ep: mat.C * (ep + mat.eps0) ** mat.n  # noqa: E731
    ep = 0.0 if mat.E * eps <= sy(0.0) else brentq(lambda e: mat.E * (eps - e) - sy(e), 0.0, eps,
                                                  xtol=1e-16, rtol=1e-15)
    ee = eps - ep
    return mat.E * ee, ep, -mat.nu * ee - ep / 2


@pytest.mark.parametrize("case", ["inter", "intra"])
def test_material_code_against_closed_form(case):
    """Gates 1 and 2 compare csph with an FEM that runs the same J2-plus-damage code
    (workbench.materials.kernels: csph through material_points, the FEM through
    workbench.materials.evaluate with the tangent), so a bug there would move both sides alike.
    This checks that code apart, on the micro-cantilever's own materials (every grain's E and the
    boundaries', Swift C, ε0, n, ε_L of the case, the compression failure rule) in one table, on a
    homogeneous uniaxial-stress path through failure, against closed forms: before failure the
    Kirchhoff stress on the Swift curve and ε_p its closed form (the return mapping is exact on
    this radial path: round-off of the eigen-solve, log and exp, 1e-10), D = ε_p/ε_L; the point
    fails (D ≥ 1, stress zero in tension) at the first step whose closed-form ε_p reaches ε_L,
    that is past ε* = ε_L + C(ε_L + ε0)^n/E; the low-ε_L material fails, the others do not."""
    from workbench.materials import HIST_DAMAGE, HIST_EPS_P, MaterialTable, evaluate

    sc = MicroCantilever(dim=2, case=case)
    grains, gb = sc.materials(sc.H / 10)
    mats = list(grains) + [gb]
    table = MaterialTable(tuple(mats))
    ids = np.arange(len(mats))
    low = min(m.eps_L for m in mats)
    eps_star = max(low + m.C * (low + m.eps0) ** m.n / m.E for m in mats if m.eps_L == low)
    h = table.initial_history(ids)
    n_failed = np.zeros(len(mats), int)
    for eps in np.linspace(0.105, 2.005, 20) * eps_star:  # no step on eps_star itself
        ref = [_uniaxial_swift(m, eps) for m in mats]
        F = np.array([np.diag([np.exp(eps), np.exp(lat), np.exp(lat)]) for _, _, lat in ref])
        out = evaluate(table, F, h, tangent=True, stress="tau", mat_id=ids)
        assert np.all(out["status"] == 0)
        h = out["history"]
        for k, (m, (tau, ep, _)) in enumerate(zip(mats, ref)):
            if ep < m.eps_L:  # intact: the Swift curve, the closed-form ε_p, D = ε_p/ε_L
                assert out["stress"][k, 0, 0] == pytest.approx(tau, rel=1e-10), (k, eps)
                assert abs(out["stress"][k, 1, 1]) < 1e-8 * tau
                assert h[k, HIST_EPS_P] == pytest.approx(ep, rel=1e-10, abs=1e-15), (k, eps)
                assert h[k, HIST_DAMAGE] == pytest.approx(ep / m.eps_L, rel=1e-10, abs=1e-15)
                assert h[k, HIST_DAMAGE] < 1.0
            else:  # failed in the step its closed-form ε_p reached ε_L; tension: no stress left
                assert h[k, HIST_DAMAGE] >= 1.0, (k, eps)
                assert np.all(out["stress"][k] == 0.0)
                n_failed[k] += 1
    failing = np.array([m.eps_L == low for m in mats])
    assert np.all(n_failed[failing] >= 5) and np.all(n_failed[~failing] == 0), n_failed


# ------------------------------------------------------------------------------------------------
# Gate 1: the elastic slope against the FEM of the same grains and materials
# ------------------------------------------------------------------------------------------------

def test_richardson_limit_and_first_failure_interpolation():
    """The two helpers of gate 1 against closed forms: the Richardson limit of S = S∞ + C h^p is
    S∞ exactly; the first crossing of D = 1 is found by linear interpolation."""
    from studies.microcantilever.derive import SINGULAR_ORDER, fem_slope_limit, first_failure

    res = (5, 10, 20)
    S = [2.0 + 3.0 * (1.0 / r) ** SINGULAR_ORDER for r in res]
    assert abs(fem_slope_limit(res, S) - 2.0) < 1e-12
    d = np.array([1.0, 2.0, 3.0, 4.0])
    F = 10 * d
    u, L = first_failure(d, F, np.array([0.2, 0.6, 1.4, 2.0]))
    assert abs(u - 2.5) < 1e-12 and abs(L - 25.0) < 1e-12
    assert np.isnan(first_failure(d, F, np.full(4, 0.5))[0])


@pytest.fixture(scope="module")
def fem_quick():
    from studies.microcantilever.ladders import FEM_MAX_ROOT, QUICK_FEM_RESOLUTIONS
    from studies.microcantilever.static import fem_ladder

    # the path of gate 2 (to 0.3 µm): the first failures in the root region on both meshes
    return fem_ladder(MicroCantilever(dim=2), QUICK_FEM_RESOLUTIONS, FEM_MAX_ROOT)


def test_fem_ladder_converges_at_the_singular_order(fem_quick):
    """The FEM reference (plane strain Q9, J2 with Swift per grain) on H/h = 5, 10: the slope falls
    towards its limit (the compliance of the re-entrant corners converges from the stiff side),
    the window of the csph fit is elastic on both meshes, and both cases fail first where the
    low ε_L is. The slope's observed order over H/h = 5, 10, 20 is the singular order's."""
    from studies.microcantilever.derive import SINGULAR_ORDER

    S = fem_quick["slopes"]
    assert np.all(np.isfinite(S)) and S[1] < S[0]
    for r in fem_quick["resolutions"]:
        run = fem_quick["runs"][r]
        assert run["status"] == "ok"
        inside = run["deflection"] <= fem_quick["window"][1]
        assert np.all(run["eps_p_max"][inside] == 0.0)
    rel = (S[0] - S[1]) / S[1]
    assert 0.02 < rel < 0.1, rel
    # the observed order of the slope on three meshes, H/h = 5, 10, 20 (20 at its first, elastic
    # path point only): from the successive differences, log2(d1/d2), at the singular order 1.09
    # within its pre-asymptotic band (measured 1.26; a mesh error of the order h² or a
    # non-converging h^0.5 falls outside it). (It replaces an algebraic identity of the
    # Richardson formula, which held whatever the order.)
    from studies.microcantilever.ladders import FEM_MAX_ROOT
    from studies.microcantilever.static import fem_ladder

    S3 = fem_ladder(MicroCantilever(dim=2), (5, 10, 20), FEM_MAX_ROOT, full=(5,))["slopes"]
    np.testing.assert_allclose(S3[:2], S, rtol=1e-9)
    order = np.log2((S3[0] - S3[1]) / (S3[1] - S3[2]))
    assert 0.75 * SINGULAR_ORDER < order < 1.5 * SINGULAR_ORDER, (S3, order)
    for case in ("inter", "intra"):
        u, L = fem_quick["first_failure"][case].T
        assert np.all(np.isfinite(u)) and np.all(u < 0.1e-6)


def test_ladder_with_first_points_only_and_its_3d_variables(fem_quick):
    """The 3-D run's ladder form (FEM_FULL_PATH_3D): meshes outside ``full`` solve the first,
    elastic path point only. On the 2-D meshes: their slope and the limit are the full ladder's
    (the same solve), the rest of their path NaN, and the csph window the finest full run's (the
    last elastic point of H/h = 5's path). A 3-D dataset carries the ladder in N (not N/m) and
    gate 1's FEM check."""
    import dataclasses

    from studies.microcantilever.dataset import dataset
    from studies.microcantilever.gates import gates
    from studies.microcantilever.ladders import CASES, FEM_MAX_ROOT
    from studies.microcantilever.report import report_notes
    from studies.microcantilever.static import fem_ladder

    part = fem_ladder(MicroCantilever(dim=2), (5, 10), FEM_MAX_ROOT, full=(5,))
    np.testing.assert_allclose(part["slopes"], fem_quick["slopes"], rtol=1e-9)
    assert part["slope_limit"] == pytest.approx(fem_quick["slope_limit"], rel=1e-9)
    fine = part["runs"][10]
    assert len(fine["load"]) == len(fem_quick["runs"][10]["load"])
    assert np.isfinite(fine["load"][0]) and np.all(np.isnan(fine["load"][1:]))
    coarse = fem_quick["runs"][5]
    d_yield = coarse["deflection"][np.flatnonzero(coarse["eps_p_max"] == 0)[-1]]
    assert part["window"] == pytest.approx((0.25 * d_yield, d_yield), rel=1e-12)
    for case in ("inter", "intra"):
        assert np.all(np.isnan(part["first_failure"][case][1]))
    ds = dataset(dataclasses.replace(MicroCantilever(), dim=3), {}, ["compression"], [5], part)
    assert ds.fem_load.attrs["units"] == "N" and ds.attrs["plane"] == "none (3-D)"
    assert any("FEM H/h=10" in g.name for g in gates(ds))
    assert "27-node hexahedra" in report_notes(ds)[0]
    # with the static slope ladder of the default 3-D run: its own gates, no root-region ones
    lim = part["slope_limit"]
    static = {r: dict(elastic_slope=lim * (1 + 0.06 * (r / 5) ** -1.5), wall_time=1.0,
                      status="ok", first_failure_root={c: (np.nan, np.nan) for c in CASES})
              for r in (5, 10, 15)}
    three_d = dataclasses.replace(MicroCantilever(), dim=3)
    ds = dataset(three_d, {}, ["compression"], [5], part, static)
    assert ds.static_elastic_slope.attrs["units"] == "N/m" and "static_root_error" not in ds
    assert ds.attrs["static_slope_order"] == pytest.approx(1.5, rel=1e-9)
    names = [g.name for g in gates(ds)]
    assert any("observed order of the elastic slope" in n for n in names), names
    assert any("csph static H/dx=15 (the finest)" in n for n in names), names
    assert not any("root region" in n for n in names), names
    assert any("gate 1, static csph" in n for n in report_notes(ds))
    # root_ladder's form (the FEM's root runs present): the root region's gates too, in N, each
    # gate of the finest once
    for r in static:
        static[r]["first_failure_root"] = {c: (2e-7, 1e-3) for c in CASES}
    ds = dataset(three_d, {}, ["compression"], [5], dict(part, root_runs=part["runs"]), static)
    assert ds.static_first_failure_root_load.attrs["units"] == "N"
    names = [g.name for g in gates(ds)]
    assert sum("csph static H/dx=15 (the finest): elastic slope" in n for n in names) == 1, names
    assert sum("csph static H/dx=15 (the finest): load at the first failure" in n
               for n in names) == 2, names
    notes = report_notes(ds)
    assert any("gate 2" in n and " N, limit" in n for n in notes), notes
    assert "along the root path" in notes[0]


def test_root_path_stops_after_both_first_failures(fem_quick):
    """The root ladder's path (root_ladder_path: the elastic first point, then steps of
    ROOT_LADDER_STEP·H), here on the 2-D meshes H/h = 5, 10: each run stops at the first path point
    where both cases have failed in the root region (NaN beyond), its first point gives the
    slope of the meshes outside ``full``, and the first-failure loads are those of the fine path
    (steps of FEM_STEP·H to 0.02 H, then ROOT_STEP·H) within 0.5 %: linear interpolation between
    path points is second order in the step, and four times the fine path's last step costs
    0.03 % (inter) and 0.11 % (intra) at H/h = 10 (studies.microcantilever.ROOT_LADDER_STEP); a
    path that stopped one point early has no failure at all (NaN)."""
    from studies.microcantilever.ladders import CASES, FEM_MAX_ROOT
    from studies.microcantilever.static import fem_ladder, root_ladder_path

    lad = fem_ladder(MicroCantilever(dim=2), (5, 10), FEM_MAX_ROOT, full=(5,), root_path=True)
    np.testing.assert_allclose(lad["slopes"], fem_quick["slopes"], rtol=1e-9)
    path = root_ladder_path(MicroCantilever(dim=2))
    for r, run in lad["root_runs"].items():
        assert run["status"] == "ok"
        np.testing.assert_array_equal(run["deflection"], path)
        done = np.flatnonzero(np.isfinite(run["load"]))
        k = done[-1]
        assert len(done) == k + 1 < len(path), (r, done)
        assert all(run["damage_root"][c][k] >= 1 for c in CASES)
        assert not all(run["damage_root"][c][k - 1] >= 1 for c in CASES)
    for c in CASES:
        np.testing.assert_allclose(lad["first_failure_root"][c][:, 1],
                                   fem_quick["first_failure_root"][c][:, 1], rtol=5e-3)


def test_csph_elastic_slope_against_the_fem(fem_quick):
    """Gate 1 at H/Δx = 5 in 2-D: the csph slope over the FEM's elastic window, from the first
    0.4 µs of the quick run (the patch reaches 0.04 µm), within max(1 %, e(5)) of the FEM's
    Richardson limit; e(5) = 13 % is the FEM's own error at the same nodal spacing (H/h = 2.5,
    extrapolated from H/h = 5 at the singular order 1.09: studies.microcantilever.TOL_SLOPE).
    csph is at 8 % (5.4 % lower at H/Δx = 10, its own ladder converging at order 1.0 to within
    1 % of the FEM's limit): a three-fold regression fails."""
    import dataclasses

    from studies.microcantilever.derive import csph_slope
    from studies.microcantilever.gates import slope_tolerance
    from studies.microcantilever.ladders import scene_for

    sc = dataclasses.replace(scene_for(MicroCantilever(dim=2), "inter", "compression"), t_end=4e-7)
    out = driver.solve("csph", sc, 5, crack="visibility")
    assert out["status"] == "ok" and not np.any(np.asarray(out["failed"]) > 0)
    S = csph_slope(out["deflection_down"], out["load"], out["time"], np.inf, fem_quick["window"])
    err = abs(S / fem_quick["slope_limit"] - 1)
    assert err <= slope_tolerance(fem_quick, 5), (S, fem_quick["slope_limit"], err)


def test_first_failure_in_the_root_region(fem_quick):
    """Gate 2 at H/Δx = 5: the static csph's load at the first failure in the root region (the
    tension half of the root half, no singular point) against the FEM's Richardson limit from
    H/h = 5, 10, within max(3 %, e(5)), e(5) = e_FEM(5)·2^p the FEM's own error at the same nodal
    spacing (studies.microcantilever.TOL_FIRST_FAILURE: 26 % intra, 48 % inter from these two
    meshes); csph is 20 % and 30 % high there (against the limit of H/h = 5, 10, 20, 40: 9.4 %
    and 11.6 % at H/Δx = 10, 2.1 % and 1.15 % at 40), so a three-fold regression fails. And the
    failure anywhere, at the singular points, has no such limit: its FEM load falls by more from
    H/h = 5 to 10 than the root region's (20–31 % against 6–10 %). The static run's elastic slope
    (the secant at its first path point, elastic, as the FEM's) is within gate 1's tolerance at
    H/Δx = 5 (13 % from these two meshes; csph is 8 % from their limit, 1.8 % above the FEM at
    H/h = 5)."""
    from studies.microcantilever.derive import SINGULAR_ORDER
    from studies.microcantilever.gates import TOL_FIRST_FAILURE, slope_tolerance
    from studies.microcantilever.static import csph_static, root_ladder_path

    st = csph_static(MicroCantilever(dim=2), 5)
    assert st["status"] == "ok"
    assert st["eps_p_max"][0] == 0 and st["eps_p_max"][-1] > 0
    err = abs(st["elastic_slope"] / fem_quick["slope_limit"] - 1)
    assert err <= slope_tolerance(fem_quick, 5), (st["elastic_slope"], fem_quick["slope_limit"])
    for case in ("inter", "intra"):
        root = fem_quick["first_failure_root"][case][:, 1]
        anywhere = fem_quick["first_failure"][case][:, 1]
        assert np.all(np.isfinite(root)) and np.all(np.isfinite(anywhere))
        assert 1 - anywhere[1] / anywhere[0] > 1.5 * (1 - root[1] / root[0]) > 0, (anywhere, root)
        lim = fem_quick["root_limit"][case]
        tol = max(TOL_FIRST_FAILURE, fem_quick["root_error"][case][0] * 2 ** SINGULAR_ORDER)
        err = abs(st["first_failure_root"][case][1] / lim - 1)
        assert err <= tol, (case, st["first_failure_root"][case], lim, err, tol)
    # the root ladder's path, stopped once both cases have failed there: the same first
    # failures within the 0.5 % of its coarser steps (test_root_path_stops_after_both_first_failures)
    coarse = csph_static(MicroCantilever(dim=2), 5, path=root_ladder_path(MicroCantilever(dim=2)),
                         until_root_failure=True)
    assert coarse["status"] == "ok" and coarse["elastic_slope"] == st["elastic_slope"]
    n = len(coarse["damage_root"]["inter"])
    assert n < len(root_ladder_path(MicroCantilever(dim=2)))
    assert np.all(np.isnan(coarse["load"][n:]))
    for case in ("inter", "intra"):
        assert coarse["damage_root"][case][-1] >= 1
        assert coarse["first_failure_root"][case][1] == pytest.approx(
            st["first_failure_root"][case][1], rel=5e-3)


def test_the_3d_root_region_keeps_clear_of_the_re_entrant_edges():
    """In 3-D the root region leaves out a cylinder of radius EDGE_CLEARANCE·H about each edge
    where a side face of the beam meets the block (x = 0, y = ±B/2), a singular line; in 2-D
    (no such edge) the region is the tension half of the root half alone."""
    from studies.microcantilever.static import EDGE_CLEARANCE, root_region

    sc = MicroCantilever()
    d = EDGE_CLEARANCE * sc.H
    top, edge = 0.4 * sc.H, 0.5 * sc.B
    X = np.array([[0.0, 0.0, top],                          # mid-width at the root: in
                  [0.7 * d, -(edge - 0.7 * d), top],        # ρ = 0.99 d from the edge: out
                  [0.8 * d, edge - 0.6 * d, top],           # ρ = d: in
                  [0.1 * d, edge - 0.1 * d, top],           # at the edge's top end: out
                  [1.01 * d, edge, top],                    # on the side face, beyond it: in
                  [0.3 * sc.L, 0.0, -top],                  # compression half: out
                  [0.6 * sc.L, 0.0, top]])                  # beyond L/2: out
    np.testing.assert_array_equal(root_region(sc, X), [1, 0, 1, 0, 1, 0, 0])
    np.testing.assert_array_equal(root_region(MicroCantilever(dim=2), X[:, [0, 2]]),
                                  [1, 1, 1, 1, 1, 0, 0])


def test_limit_spread_of_a_richardson_limit():
    """limit_spread: zero for values converging exactly at the singular order; for values
    converging at another order q, |L(p) − L|/L(p) with L(p) the singular-order extrapolation of
    the two finest (closed form below); NaN below three meshes or without an observed order."""
    from studies.microcantilever.derive import SINGULAR_ORDER, fem_slope_limit, limit_spread

    res = np.array([5, 10, 20, 40])
    assert limit_spread(res, 100 + 30 * res ** -SINGULAR_ORDER) == pytest.approx(0, abs=1e-12)
    v = 100 + 30 * res ** -2.0
    lp = v[-1] + (v[-1] - v[-2]) / (2 ** SINGULAR_ORDER - 1)
    assert fem_slope_limit(res, v) == pytest.approx(lp, rel=1e-14)
    assert limit_spread(res, v) == pytest.approx(abs(lp - 100) / lp, rel=1e-9)
    assert limit_spread(res, v) > 1e-4
    assert np.isnan(limit_spread(res[:2], v[:2]))
    assert np.isnan(limit_spread(res[:3], [1.0, 2.0, 1.5]))


def test_observed_order_of_three_meshes_at_any_ratio():
    """_order3: the order of values converging exactly as r^-p, for a constant ratio (closed
    form) and for 5, 10, 15 (a root of the ratio equation); NaN where the differences change
    sign or no positive order fits."""
    from studies.microcantilever.derive import _order3

    for res in ((5, 10, 20), (5, 10, 15), (4, 7, 15)):
        r = np.array(res, float)
        for p in (0.6, 1.089, 2.0):
            assert _order3(res, 3.0 + 2.0 * r ** -p) == pytest.approx(p, rel=1e-8), (res, p)
    assert np.isnan(_order3((5, 10, 15), [1.0, 2.0, 1.5]))
    assert np.isnan(_order3((5, 10, 15), [1.0, 1.5, 1.5000001]))  # Δ₁/Δ₂ beyond any order


@pytest.mark.parametrize("errors,passed", [
    ((0.0569, 0.0186, 0.0086), True),    # the 3-D measurement
    ((0.0569, 0.0186, 0.012), False),    # the finest over the 1 %
    ((0.0098, 0.0097, 0.0096), False),   # within every bound but not converging: order 0.05
    ((0.065, 0.061, 0.058), False),      # stagnating (nodal integration): order 0.1
    ((0.13, 0.0186, 0.0086), False)])    # the coarsest beyond max(1 %, e_FEM(5)(10/5)^p)
def test_static_slope_gates(errors, passed):
    """The 3-D run's gate 1 on its static ladder: each slope within max(1 %, e(r)), the
    observed order at least half the singular order, the finest within 1 % of a limit whose own
    uncertainty is at most half of that."""
    import xarray as xr

    from studies.microcantilever.gates import static_slope_gates

    sr = [5, 10, 15]
    ds = xr.Dataset(coords={"static_resolution": sr, "fem_resolution": [5, 10, 15]})
    ds["static_slope_error"] = ("static_resolution", list(errors))
    ds["fem_slope_error"] = ("fem_resolution", [0.0546, 0.0257, 0.0165])
    ds.attrs["static_slope_order"] = float(np.polyfit(np.log(1 / np.array(sr)), np.log(errors), 1)[0])
    ds.attrs["fem_slope_limit_spread"] = 0.00015
    g = static_slope_gates(ds)
    assert len(g) == 6
    assert all(x.passed for x in g) == passed, [(x.name, x.observed, x.tolerance) for x in g]


def test_static_ladder_reaches_the_finest_resolution():
    """Gate 2's static runs: the run's resolutions and STATIC_FINEST (40), whatever the ladder."""
    from studies.microcantilever.ladders import STATIC_FINEST, static_resolutions

    assert STATIC_FINEST == 40
    assert static_resolutions((5, 10, 20)) == [5, 10, 20, 40]
    assert static_resolutions([10, 5]) == [5, 10, 40]
    assert static_resolutions((40, 50)) == [40, 50]


@pytest.mark.parametrize("slope,root,spread,status,passed", [
    (0.0033, (0.0115, 0.0208), 0.004, "ok", True),
    (0.011, (0.0115, 0.0208), 0.004, "ok", False),   # slope over the 1 %
    (0.0033, (0.0115, 0.031), 0.004, "ok", False),   # intra's load over 3 %
    (0.0033, (0.0115, 0.0208), 0.016, "ok", False),  # the limit itself too uncertain
    (np.nan, (np.nan, np.nan), 0.004, "unstable", False)])  # a finest run that did not end
def test_finest_gates(slope, root, spread, status, passed):
    """Gate 1 at the finest (static csph, H/Δx = 40): the issue's bounds as written, 1 % on the
    slope and 3 % on the first-failure load, each against a limit whose own uncertainty is at
    most half of it; a failed or missing finest run fails, it is not left out."""
    import xarray as xr

    from studies.microcantilever.gates import finest_gates

    sr = [5, 10, 20, 40]
    ds = xr.Dataset(coords={"case": ["inter", "intra"], "static_resolution": sr})
    ds["static_slope_error"] = ("static_resolution", [0.1, 0.05, 0.02, slope])
    ds["static_root_error"] = (("case", "static_resolution"),
                               [[0.2, 0.1, 0.04, root[0]], [0.2, 0.1, 0.04, root[1]]])
    ds["static_status"] = ("static_resolution", ["ok", "ok", "ok", status])
    ds["fem_root_limit_spread"] = ("case", [0.004, spread])
    ds.attrs["fem_slope_limit_spread"] = 0.0006
    g = finest_gates(ds)
    assert len(g) == 6 and all("H/dx=40" in x.name for x in g if "csph" in x.name)
    assert all(x.passed for x in g) == passed, [(x.name, x.observed, x.tolerance) for x in g]


def test_root_variables_on_their_own_coordinate():
    """Gate 2's static runs are stored on ``static_resolution`` (the ladder and 40), with each
    error against the FEM's limit and its observed order (least squares): errors made to fall as
    r^-1.5 read back 1.5; a run that has yielded at its first point has no slope (NaN)."""
    import xarray as xr

    from studies.microcantilever.dataset import _root_variables, _static_variables
    from studies.microcantilever.gates import finest_gates
    from studies.microcantilever.ladders import CASES

    sr = [5, 10, 20, 40]
    lim, slim = 180.0, 1.6e9
    static = {r: dict(first_failure_root={c: (2e-7, lim * (1 + 0.3 * (r / 5) ** -1.5))
                                          for c in CASES},
                      elastic_slope=slim * (1 + 0.08 * (r / 5) ** -1.5) if r > 5 else np.nan,
                      wall_time=1.0, status="ok") for r in sr}
    fr = np.array([[2e-7, 200.0], [2e-7, 190.0]])
    fem = dict(first_failure_root={c: fr for c in CASES}, root_limit={c: lim for c in CASES},
               root_limit_spread={c: 0.001 for c in CASES},
               root_error={c: np.array([0.1, 0.05]) for c in CASES},
               root_order={c: np.nan for c in CASES}, slope_limit=slim)
    ds = xr.Dataset(coords={"case": list(CASES), "fem_resolution": [5, 10]})
    _static_variables(ds, fem, static)
    _root_variables(ds, fem, static)
    assert list(ds.static_resolution.values) == sr
    assert ds.static_root_error.sel(case="intra", static_resolution=40) == pytest.approx(
        0.3 * 8 ** -1.5, rel=1e-12)
    assert np.allclose(ds.static_root_order.values, 1.5, rtol=1e-12)
    assert np.isnan(ds.static_slope_error.sel(static_resolution=5))
    assert ds.static_slope_error.sel(static_resolution=40) == pytest.approx(0.08 * 8 ** -1.5)
    ds.attrs["fem_slope_limit_spread"] = 0.0006
    assert all(g.passed for g in finest_gates(ds))


def test_energy_balance_and_quasi_static_measures():
    """Gates 2 and 4 read run_summary: on made-up histories with a known imbalance and a known
    kinetic/elastic ratio (closed forms), the balance error is the largest |W − ΣE|/W over the
    records (from the first with W > 0) and the ratio the largest K/E over the second half of
    the time to the first failure."""
    from studies.microcantilever.derive import run_summary

    t = np.linspace(0.0, 5e-6, 401)
    W = 1e-9 * (t / t[-1]) ** 2
    K = np.where(t < 2e-6, 0.004, 0.0) * W  # K/E = 0.004/0.996 up to the failure at 2 µs ...
    K[(t > 1.5e-6) & (t < 1.6e-6)] *= 2  # ... and twice that over 1.5–1.6 µs
    E, Wp, R = W - K, 0 * t, 0 * t
    E[300] *= 1.0 - 0.007 / (1 - 0.004 * (t[300] < 2e-6))  # 0.7 % of W missing at one record
    out = dict(time=t, load=1e3 * t, deflection_down=0.2 * t, failed=(t >= 2e-6).astype(float),
               external_work=W, kinetic_energy=K, strain_energy=E, plastic_work=Wp,
               released_energy=R, status="ok")
    s = run_summary(out, MicroCantilever(dim=2))
    assert s["energy_balance_error"] == pytest.approx(0.007, rel=1e-9)
    assert s["kinetic_ratio"] == pytest.approx(0.008 / 0.992, rel=1e-9)


@pytest.mark.parametrize("t_first, expected", [(0.55e-6, 0.002), (0.45e-6, 0.02)])
def test_quasi_static_window_starts_after_the_ramp(t_first, expected):
    """Gate 4's window starts at the end of the velocity ramp (t_ramp = 0.5 µs) when the first
    failure comes after it: a K/E of 2 % inside the ramp (the start-up transient) is not read, the
    0.2 % after it is; a failure within the ramp keeps the second half of the time to it."""
    from studies.microcantilever.derive import run_summary

    scene = MicroCantilever(dim=2)
    assert scene.t_ramp == pytest.approx(0.5e-6)
    t = np.linspace(0.0, 1e-6, 1001)
    W = 1e-9 * (t / t[-1]) ** 2
    K = np.where(t < scene.t_ramp, 0.02, 0.002) * W
    out = dict(time=t, load=1e3 * t, deflection_down=0.2 * t, failed=(t >= t_first).astype(float),
               external_work=W, kinetic_energy=K, strain_energy=W - K, plastic_work=0 * t,
               released_energy=0 * t, status="ok")
    s = run_summary(out, scene)
    assert s["kinetic_ratio"] == pytest.approx(expected / (1 - expected), rel=1e-9)


# ------------------------------------------------------------------------------------------------
# Gate 5: the crack band
# ------------------------------------------------------------------------------------------------

def _swift_g(C, eps0, n, E, eps):
    """The area under the uniaxial curve of a Swift J2 law failing at ε_p = eps, written out here
    (closed form): ∫₀^eps C (ε0 + e)^n de + σ_y(eps)²/(2E)."""
    sy = C * (eps0 + eps) ** n
    return C / (n + 1) * ((eps0 + eps) ** (n + 1) - eps0 ** (n + 1)) + sy * sy / (2 * E)


def test_crack_band_limit_keeps_the_energy_per_crack_area():
    """ε_L,eff of the crack band: spacing·g(ε_L,eff) = band·g(ε_L) with g the closed-form area
    under the uniaxial Swift curve to failure (to the bisection's 1e-12, checked at 1e-9); ε_L
    itself where the spacing is the band; each grain its own modulus; the band below
    spacing·g(0)/g(ε_L) refused with one line naming ``band``."""
    from studies.microcantilever.scene import TABLE2_E, crack_band_limit
    from workbench.materials import Material

    sc = MicroCantilever(dim=2, case="intra", band=1e-6)
    for r in (5, 10, 20):
        dx = sc.H / r
        grains, gb = sc.limits(dx)
        assert gb == sc.eps_L_high
        for k, eps in enumerate(grains):
            E = TABLE2_E[k]
            lhs = dx * _swift_g(sc.C, sc.eps0, sc.n, E, eps)
            rhs = sc.band * _swift_g(sc.C, sc.eps0, sc.n, E, sc.eps_L_low)
            assert lhs == pytest.approx(rhs, rel=1e-9), (r, k)
    assert MicroCantilever(dim=2, band=1e-6).limits(1e-6)[1] == pytest.approx(0.002, rel=1e-9)
    assert MicroCantilever(dim=2).limits(0.25e-6)[1] == 0.002  # no band: eps_L as given
    mat = Material.j2(E=202e9, nu=0.3, C=868.8e6, eps0=0.0013, n=0.179)
    with pytest.raises(SceneError) as err:
        crack_band_limit(mat, 0.002, 0.1e-6, 1e-6)
    msg = str(err.value)
    assert msg.startswith("band:") and "allowed" in msg and "\n" not in msg


def _lattice_out(failed_at, dx=0.5e-6):
    """A made-up final state on a lattice 10 x 5 µm with the held faces at x = 0: the failed
    particles at the given (i, j) and W_p = 1e6, W_rel = 2e5 J/m³ in each (0 elsewhere)."""
    from workbench.materials import HIST_W_P, HIST_W_REL

    nx, ny = 21, 11
    I, J = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    X = np.stack([I.ravel() * dx, J.ravel() * dx - 2.5e-6], axis=1)
    failed = np.zeros(len(X), bool)
    for i, j in failed_at:
        failed[i * ny + j] = True
    h = np.zeros((len(X), 13))
    h[failed, HIST_W_P], h[failed, HIST_W_REL] = 1e6, 2e5
    V = np.full(len(X), dx * dx)
    return dict(X=X, failed_particles=failed, history=h, volume=V,
                released_energy=np.array([0.0, float(V @ h[:, HIST_W_REL]) + 3e-8]))


def test_fracture_energy_of_the_main_crack():
    """The main crack is the group of failed particles spanning most of the height: a column of
    11 at x = 2 µm stepping sideways once, against a patch of 3 at the top near x = 8 µm; its
    energy is Σ V (W_p + W_rel) over it plus what cut pairs released (the run's released energy
    less Σ V W_rel), in closed form."""
    from studies.microcantilever.derive import crack_particles, fracture_energy

    dx = 0.5e-6
    crack = [(4, j) for j in range(6)] + [(5, j) for j in range(6, 11)]
    patch = [(16, 10), (17, 10), (17, 9)]
    out = _lattice_out(crack + patch, dx)
    on = crack_particles(out, dx)
    assert on.sum() == len(crack) and not on[[i * 11 + j for i, j in patch]].any()
    G, G_all, n = fracture_energy(out, dx)
    assert n == len(crack)
    assert G == pytest.approx(len(crack) * dx * dx * 1.2e6 + 3e-8, rel=1e-12)
    assert G_all == pytest.approx(len(crack + patch) * dx * dx * 1.2e6 + 3e-8, rel=1e-12)


def test_fracture_energy_at_the_separation():
    """G is taken from the state at which the crack cut the body (the driver's
    ``at_separation``): a particle that fails later (here one at the top face beside the crack,
    after the cut) is left out, and the released energy is the one then; ``at='end'`` takes the
    final state; without a separation the final state is the crack's."""
    from studies.microcantilever.derive import fracture_energy
    from workbench.materials import HIST_W_P

    dx = 0.5e-6
    crack = [(4, j) for j in range(11)]
    later = _lattice_out(crack + [(3, 10)], dx)
    cut = _lattice_out(crack, dx)
    cut["history"][:, HIST_W_P] *= 0.5  # the crack's plastic work then, before it grew further
    later["at_separation"] = dict(history=cut["history"], failed_particles=cut["failed_particles"],
                                  released_energy=float(cut["released_energy"][-1]))
    per = dx * dx * (0.5e6 + 2e5)  # V (W_p + W_rel) of a crack particle at the cut
    G, _, n = fracture_energy(later, dx)
    assert n == 11 and G == pytest.approx(11 * per + 3e-8, rel=1e-12)
    G_end, _, n_end = fracture_energy(later, dx, at="end")
    assert n_end == 12 and G_end == pytest.approx(12 * dx * dx * 1.2e6 + 3e-8, rel=1e-12)
    later["at_separation"] = None
    assert fracture_energy(later, dx) == fracture_energy(later, dx, at="end")


def test_band_gate():
    """Gate 5 passes a regularised ladder spread by 8 % and fails one spread by 12 % (max/min − 1
    against 10 %), over the runs whose band (1 µm) is wider than the spacing (H = 5 µm: H/Δx =
    10, 15, 20; the run at 5, where the band is one spacing, is left out however far off it is);
    a run of them without a fracture energy fails it; the literal ladder's power of Δx is read
    back (G ∝ Δx exactly: 1)."""
    import xarray as xr

    from studies.microcantilever.derive import band_ladder, fracture_ladder, spacing_power
    from studies.microcantilever.gates import band_gates
    from studies.microcantilever.report import fracture_note

    res = np.array([5, 10, 15, 20])

    def ds_with(reg):
        G = np.full((1, 2, 2, 4), np.nan)
        G[0, :, 0] = 6e-6 * 5 / res  # compression (literal eps_L): ~ dx
        G[0, :, 1] = reg
        dims = ("solver", "case", "rule", "resolution")
        return xr.Dataset({"fracture_energy": (dims, G),
                           "status": (dims, np.full(G.shape, "ok"))},
                          coords={"solver": ["csph"], "case": ["inter", "intra"],
                                  "rule": ["compression", "regularised"], "resolution": res},
                          attrs={"param_H": 5e-6, "param_band": 0.0})

    def spread(gates):  # the spread gates; the value gates (against b g H) are checked below
        return [g for g in gates if "spread" in g.name]

    ok = spread(band_gates(ds_with([9e-6, 6.0e-6, 6.3e-6, 6.48e-6])))
    bad = spread(band_gates(ds_with([6.0e-6, 6.0e-6, 6.3e-6, 6.72e-6])))
    gone = spread(band_gates(ds_with([6.0e-6, 6.0e-6, np.nan, 6.1e-6])))
    assert len(ok) == 2 and all(g.passed for g in ok)
    note = fracture_note(ds_with([9e-6, 6.0e-6, 6.3e-6, 6.48e-6]), "inter")
    assert "max/min - 1 = 8.0 % over H/dx = 10, 15, 20 (band > dx)" in note  # the gate's ladder
    assert len(bad) == 2 and not any(g.passed for g in bad)
    assert len(gone) == 2 and not any(g.passed for g in gone)
    assert list(band_ladder(ds_with([6e-6] * 4), "inter")[0]) == [10, 15, 20]
    wide = ds_with([6e-6] * 4)
    wide.attrs["param_band"] = 2e-6  # wider than the spacing at 5 too
    assert list(band_ladder(wide, "inter")[0]) == [5, 10, 15, 20]
    r, G = fracture_ladder(ds_with([6e-6] * 4), "inter", "compression")
    assert spacing_power(r, G) == pytest.approx(1.0, rel=1e-12)


def test_band_gate_checks_the_value_against_the_closed_form():
    """Gate 5 also reads each case's energy against its closed form b g(ε_L) H
    (studies.crack_band.band_value_gate, one gate per case): the closed form itself passes, 50 %
    above it fails (|G/G_c − 1| r/3 = 1.7 at r = 10), and so does a NaN."""
    import xarray as xr

    from studies.crack_band import microcantilever_band_closed_form
    from studies.microcantilever.derive import band_width
    from studies.microcantilever.gates import band_gates

    res = np.array([5, 10, 15, 20])
    attrs = {"param_H": 5e-6, "param_band": 0.0}

    def ds_with(scale):
        G = np.full((1, 2, 2, 4), np.nan)
        dims = ("solver", "case", "rule", "resolution")
        ds = xr.Dataset({"fracture_energy": (dims, G), "status": (dims, np.full(G.shape, "ok"))},
                        coords={"solver": ["csph"], "case": ["inter", "intra"],
                                "rule": ["compression", "regularised"], "resolution": res},
                        attrs=attrs)
        for k, case in enumerate(("inter", "intra")):
            ds.fracture_energy[0, k, 1] = scale * microcantilever_band_closed_form(
                attrs, case, band_width(ds))
        return ds

    def value(gates):
        return [g for g in gates if "closed form" in g.name]

    assert len(value(band_gates(ds_with(1.0)))) == 2
    assert all(g.passed for g in value(band_gates(ds_with(1.0))))
    assert not any(g.passed for g in value(band_gates(ds_with(1.5))))
    assert not any(g.passed for g in value(band_gates(ds_with(np.nan))))


def test_deletion_summary_counts_the_deleted_elements_by_region():
    """Gate 6's measure for the FEM with element deletion: the deleted elements per region and
    their share where the case's low ε_L is (the boundaries for inter, the grains for intra)."""
    from studies.microcantilever.derive import deletion_summary

    names = ["grain0", "grain1", "gb01"]
    region = np.array([0, 0, 2, 2, 1, 1, 2])
    s = deletion_summary("inter", names, region, [2, 3, 6, 0])
    assert s == dict(n_deleted=4, share_low=0.75, regions="gb01 3, grain0 1")
    s = deletion_summary("intra", names, region, [2, 3, 6, 0])
    assert s["share_low"] == 0.25
    assert deletion_summary("intra", names, region, [])["n_deleted"] == 0


def test_background_process_returns_and_ends():
    """The 3-D run's FEM ladder runs in a spawned process beside the particle runs: its result
    comes back, and closing it ends the process."""
    import operator

    from studies.microcantilever.study import _Background

    job = _Background(operator.add, 2, 3)
    try:
        assert job.result() == 5
    finally:
        job.close()
    assert not job.process.is_alive()


def test_background_process_that_dies_is_a_result_not_a_hang():
    """A background job whose process is killed (as the kernel kills one for memory) or whose
    function raises gives one line saying so, and the study records it as gate 1's failure
    instead of waiting for ever; the particle runs are kept."""
    import os
    import signal
    import time

    import xarray as xr

    from studies.microcantilever.gates import gates
    from studies.microcantilever.study import BackgroundFailed, _Background

    job = _Background(time.sleep, 30.0)
    try:
        os.kill(job.process.pid, signal.SIGKILL)
        with pytest.raises(BackgroundFailed, match="signal 9"):
            job.result()
    finally:
        job.close()
    job = _Background(int, "not a number")
    try:
        with pytest.raises(BackgroundFailed, match="^ValueError: invalid literal"):
            job.result()
    finally:
        job.close()
    ds = xr.Dataset(coords={"case": [], "rule": [], "resolution": []})
    ds.attrs["fem_reference_failed"] = "3-D FEM ladder: the process ended without a result"
    g = [x for x in gates(ds) if "FEM reference" in x.name]
    assert len(g) == 1 and not g[0].passed


@pytest.mark.parametrize("dim", [2, 3])
def test_patch_ends_on_the_nearest_lattice_lines(dim):
    """MicroCantilever.patch_edges: on the study's ladder (H/Δx = 5, 10, 20) the patch is
    [0.8 L, 0.9 L] itself; off it the ends are the lattice lines nearest to 0.8 L and 0.9 L
    (written out here from the node lattice x = −block + kΔx), and the particles the model puts in
    the patch are the lattice nodes of the top face between them, ends included."""
    from sph.particles import discretise

    sc = MicroCantilever(dim=dim)
    for r in (5, 10, 20):
        a, b = sc.patch_edges(sc.H / r)
        assert a == pytest.approx(0.8 * sc.L, rel=1e-12) and b == pytest.approx(0.9 * sc.L, rel=1e-12)
    for r in (6, 7, 8, 9):
        dx = sc.H / r
        nodes = -sc.block + dx * np.arange(int(round((sc.L + sc.block) / dx)) + 1)
        a, b = sc.patch_edges(dx)
        assert a == pytest.approx(nodes[np.argmin(abs(nodes - 0.8 * sc.L))], abs=1e-9 * dx)
        assert b == pytest.approx(nodes[np.argmin(abs(nodes - 0.9 * sc.L))], abs=1e-9 * dx)
        if dim == 2:
            ps = discretise(sc.model(dx), r)
            X = ps.X[ps.sets["patch"]]
            assert X[:, 0].min() == pytest.approx(a, abs=1e-9 * dx)
            assert X[:, 0].max() == pytest.approx(b, abs=1e-9 * dx)
            assert np.allclose(X[:, 1], sc.H / 2)
            assert len(X) == int(round((b - a) / dx)) + 1


def test_slope_off_the_ladder_against_the_fem_of_the_same_model(fem_quick):
    """At H/Δx = 6 the patch's ends fall between lattice lines: static csph and the FEM (H/h = 6)
    of the same model, first path point (elastic), 2-D. Their difference is the two
    discretisations' error at this spacing; gate 1's error model bounds it by the FEM's own error
    at the same nodal spacing, max(1 %, e_FEM(5)·(2·5/6)^p) (slope_tolerance at 6: e_FEM(5) from
    H/h = 5 and 10). They agree to 1.9 % with the nearest-line ends; with the ends inside the patch
    (before patch_edges) csph's end particles stood 0.83 µm apart and its slope was 32 % below the
    FEM's, which kept nodes 1.67 µm apart at its spacing h/2."""
    from studies.microcantilever.gates import slope_tolerance
    from studies.microcantilever.ladders import FEM_STEP
    from studies.microcantilever.static import csph_static, fem_static

    sc = MicroCantilever(dim=2)
    st = csph_static(sc, 6, fem_max=FEM_STEP)
    fe = fem_static(sc, 6, fem_max=FEM_STEP)
    assert st["status"] == "ok" and fe["status"] == "ok"
    S_csph = st["load"][0] / st["deflection"][0]
    S_fem = fe["load"][0] / fe["deflection"][0]
    tol = slope_tolerance(fem_quick, 6)
    assert abs(S_csph / S_fem - 1) <= tol, (S_csph, S_fem, tol)


def test_the_root_ladder_runs_from_the_command_line_and_gates_its_own_runs(tmp_path, capsys):
    """`workbench run microcantilever_root` (:func:`studies.microcantilever.root_ladder`: gate 2
    of the 3-D scene, apart from the default run), on the 2-D scene at H/Δx = H/h = 5, 10: a
    dataset of the FEM's and static csph's runs along the root path alone, written and read back,
    whose gates check each csph load at the first failure in the root region against the FEM's
    limit within max(3 %, e(r)) (csph is 24 and 12 % high for inter, 20 and 9 % for intra, within
    30/14 % and 26/12 %), and whose gates at the finest fail with two meshes: no observed order,
    so no uncertainty of the limit (NaN), and H/Δx = 10 is not within the issue's 3 %. Its
    figure, its accuracy-against-cost rows (csph and the FEM per case) and its report notes."""
    from studies.microcantilever import root as study
    from workbench import results
    from app import cli

    argv = ["run", "microcantilever_root", "--set", "dim=2", "--resolution", "5", "--resolution",
            "10", "--out", str(tmp_path)]
    assert cli.main(argv) == 0
    printed = capsys.readouterr().out
    ds = results.read(tmp_path / "microcantilever_root.nc")
    assert list(ds.static_resolution.values) == [5, 10] and "static_root_error" in ds
    assert np.all(ds.static_status.values == "ok") and np.all(ds.fem_root_wall_time.values > 0)
    g = study.gates(ds)
    per_resolution = [x for x in g if "csph static H/dx=" in x.name and "finest" not in x.name]
    assert len(per_resolution) == 4 and all(x.passed for x in per_resolution), per_resolution
    finest = [x for x in g if "finest" in x.name or "uncertainty" in x.name]
    assert finest and not any(x.passed for x in finest)
    assert sum(line.lstrip().startswith("FAIL") for line in printed.splitlines()) == len(finest)
    rows = study.errors(ds)
    assert sorted({r["solver"] for r in rows}) == ["csph (inter)", "csph (intra)", "fem (inter)",
                                                   "fem (intra)"]
    assert all(np.isfinite(r["error"]) and r["wall_time"] > 0 for r in rows) and len(rows) == 8
    assert (tmp_path / "microcantilever_root_first_failure.png").stat().st_size > 0
    notes = study.report_notes(ds)
    assert sum(n.startswith("gate 2 (first failure in the root region") for n in notes) == 2
