"""FEM core: the vectorised assembly equals scikit-fem's forms, the tangent is the derivative of the
residual, Newton converges quadratically, plane stress solves P33 = 0."""
import dataclasses

import numpy as np
import pytest

from fem_reference.assembly import Discretisation
from fem_reference.constitutive import update
from fem_reference.model import build
from fem_reference.mesh import block, rectangle
from fem_reference.static import newton
from workbench.materials import Material
from workbench.scenes import Cantilever

BEAM = Material.svk(E=1.0e5, nu=0.3)

# Assembly of the same arrays by two routes: only round-off may differ.
TOL_SAME = 1e-12
# Central difference with h = 1e-7 on displacements of 1e-2: truncation ~h², round-off ~1e-16/h.
TOL_FD = 1e-6


@pytest.mark.parametrize("mesh", [rectangle(0.16, 0.02, 2), block(1.0, 2)], ids=["quad2", "hex1"])
def test_assembly_matches_skfem_forms_and_finite_differences(mesh):
    disc = Discretisation(mesh)
    rng = np.random.default_rng(0)
    u = 1e-4 * rng.standard_normal(disc.N) * (disc.mesh.p.max() - disc.mesh.p.min())
    out = update(BEAM, disc.displacement_gradient(u), None, "strain")
    f_fast, f_skfem = disc.internal_force(out["P"]), disc.skfem_internal_force(out["P"])
    assert np.abs(f_fast - f_skfem).max() <= TOL_SAME * np.abs(f_skfem).max()
    K_fast, K_skfem = disc.tangent(out["A"]).toarray(), disc.skfem_tangent(out["A"]).toarray()
    assert np.abs(K_fast - K_skfem).max() <= TOL_SAME * np.abs(K_skfem).max()
    # the tangent of a hyperelastic law is symmetric
    assert np.abs(K_fast - K_fast.T).max() <= TOL_SAME * np.abs(K_fast).max()
    e = rng.standard_normal(disc.N)
    h = 1e-7
    fp = disc.internal_force(update(BEAM, disc.displacement_gradient(u + h * e), None, "strain")["P"])
    fm = disc.internal_force(update(BEAM, disc.displacement_gradient(u - h * e), None, "strain")["P"])
    fd = (fp - fm) / (2 * h)
    err = np.abs(fd - K_fast @ e).max() / np.abs(fd).max()
    assert err < TOL_FD, f"tangent vs finite difference: {err:.2e}"


def test_newton_converges_quadratically():
    """From rest to P L²/(E I) = 0.5 in one step (a geometrically nonlinear step): once the
    relative residual is below 0.2, r_{k+1} ≤ C r_k² with C = 10 until the round-off floor
    (~1e-12 here: F = I + H stores H to ~1e-16/|H|), and the last iterate is below 1e-9."""
    problem = build(Cantilever(), 2).problem
    state = problem.initial_state()
    res = newton(problem, state, state.u.copy(), 0.5, rtol=1e-11, maxit=30)
    assert res.converged, res.reason
    r = np.array(res.residuals)
    assert r[-1] < 1e-9
    C = res.quadratic_constants(start=0.2, floor=1e-10)
    assert len(C) >= 2, f"too few iterates in the asymptotic range: {r}"
    assert max(C) < 10, f"r_(k+1)/r_k^2 = {C} from residuals {r}"


def test_plane_stress_solves_out_of_plane_stress():
    rng = np.random.default_rng(1)
    H = 0.05 * rng.standard_normal((20, 2, 2))
    out = update(BEAM, H, None, "stress")
    F = np.zeros((20, 3, 3))
    F[:, :2, :2] = H + np.eye(2)
    F[:, 2, 2] = out["F33"]
    from fem_reference.constitutive import points_3d
    P, A, _, _ = points_3d(BEAM, F, np.zeros((20, 0)), True)
    assert np.abs(P[:, 2, 2]).max() < 1e-9 * BEAM.E
    # the condensed tangent is the derivative of the in-plane P with F33 re-solved
    h = 1e-7
    dH = np.zeros((20, 2, 2))
    dH[:, 0, 1] = h
    Pp = update(BEAM, H + dH, None, "stress")["P"]
    Pm = update(BEAM, H - dH, None, "stress")["P"]
    fd = (Pp - Pm) / (2 * h)
    assert np.abs(fd - out["A"][:, :, :, 0, 1]).max() < 1e-5 * np.abs(out["A"]).max()


def test_plane_stress_cantilever_is_softer_by_one_minus_nu_squared():
    """At the small load the plane-stress beam is softer than the plane-strain beam by ≈ 1/(1−ν²)
    (exactly so for Euler–Bernoulli; shear changes the ratio by well under 1 %)."""
    from fem_reference import solve

    sc = dataclasses.replace(Cantilever(), loads=(0.00192,))
    strain = solve(sc, 2)["tip_deflection"][0]
    stress = solve(dataclasses.replace(sc, plane="stress"), 2)["tip_deflection"][0]
    assert stress / strain == pytest.approx(1 / (1 - 0.3 ** 2), rel=1e-2)


@pytest.mark.parametrize("mesh", [rectangle(0.16, 0.02, 2), block(1.0, 2)], ids=["quad2", "hex2"])
def test_condensed_tangent_is_the_free_block_of_the_summed_element_matrices(mesh):
    """The condensed tangent (the pattern from node blocks, each element entry's slot found in
    it) equals scipy's sum of the element matrices over their DOFs, restricted to the free rows
    and columns — pattern and values — with a third of the DOFs held."""
    import scipy.sparse as sp

    disc = Discretisation(mesh)
    disc.set_fixed(np.arange(0, disc.N, 3))
    rng = np.random.default_rng(1)
    Ke = rng.standard_normal((disc.nel,) + (disc.edofs.shape[1],) * 2)
    K = disc.assemble_elements(Ke)
    nl = disc.edofs.shape[1]
    rows = np.repeat(disc.edofs, nl, axis=1).ravel()
    cols = np.tile(disc.edofs, (1, nl)).ravel()
    ref = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(disc.N, disc.N))[disc.free][:, disc.free]
    ref.sort_indices()
    K.sort_indices()
    assert np.array_equal(K.indptr, ref.indptr) and np.array_equal(K.indices, ref.indices)
    assert np.abs((K - ref).toarray()).max() <= TOL_SAME * np.abs(ref.toarray()).max()


def test_reused_factors_give_the_same_path():
    """GMRES preconditioned by the last LU factors (the large-problem solver) follows the direct
    solver's Newton path: same iterations, same answer to the Newton tolerance."""
    from fem_reference.static import TangentSolver, load_path

    out = []
    for reuse in (False, True):
        problem = build(Cantilever(), 2).problem
        iy = problem.disc.node_dof(np.array([0.16, 0.0]), 1)
        solver = TangentSolver(reuse=reuse)
        recs, state = load_path(problem, (1.0, 3.0), max_increment=3.0, solver=solver)
        out.append((-state.u[iy], [r["newton_iterations"] for r in recs], solver.factorisations))
    (v0, it0, f0), (v1, it1, f1) = out
    assert v1 == pytest.approx(v0, rel=1e-8)
    assert it1 == it0
    assert f1 < f0, f"factorisations direct {f0}, reused {f1}"


def test_failed_run_is_a_result_not_a_crash():
    """contract.md: a run that does not converge returns NaN values and a status saying why."""
    from fem_reference import solve

    sc = dataclasses.replace(Cantilever(), loads=(5.0, 6.0))
    # an unattainable tolerance: every increment fails, down to the smallest one (one Newton
    # iteration alone is not enough: after the linearised predictor small increments converge)
    r = solve(sc, 1, maxit=1, rtol=1e-30, max_increment=5.0)
    assert all(s.startswith("diverged") for s in r["status"]), r["status"]
    assert np.all(np.isnan(r["tip_deflection"]))
