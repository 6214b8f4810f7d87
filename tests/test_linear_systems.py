"""The linear systems of the Newton solvers (:mod:`workbench.linear_systems`): the rigid-body modes
are the null space of a free body's stiffness; AMG-preconditioned CG (and GMRES for F-bar's
unsymmetric tangent) solves what the direct solver solves; a system it cannot solve falls back to
the direct one; the FEM's and csph's Newton paths are the same with either solver.

The AMG solver is taken only above :data:`workbench.linear_systems.AMG_ABOVE` unknowns; the tests
lower the threshold so that small systems take it.
"""
import numpy as np
import pytest
import scipy.sparse as sp

import workbench.linear_systems as ls
from fem_reference.drivers import cylinder_problem
from fem_reference.static import TangentSolver, load_path
from workbench.materials import Material

E, NU = 200e9, 0.3


@pytest.fixture
def amg_everywhere(monkeypatch):
    """Every system above the dense limit takes the AMG solver."""
    monkeypatch.setitem(ls.AMG_ABOVE, 2, 0)
    monkeypatch.setitem(ls.AMG_ABOVE, 3, 0)


def tube(dim, fbar=None, material=None):
    material = Material.neo_hooke(E=E, nu=NU) if material is None else material
    return cylinder_problem(material, 1.0, 2.0, 4, 8, control="displacement", fbar=fbar,
                            dim=dim)[0]


def elastic_tangent(problem):
    st = problem.initial_state()
    return problem.tangent(problem.evaluate(st.u, st, tangent=True))


@pytest.mark.parametrize("dim", [2, 3])
def test_rigid_body_modes_are_the_null_space_of_a_free_body(dim):
    """The tangent of the unconstrained tube at rest annihilates every rigid-body mode (to
    round-off: ‖K B‖ ≤ 1e-12 ‖K‖ ‖B‖), and the modes are independent (3 in 2-D, 6 in 3-D)."""
    problem = tube(dim)
    problem.disc.set_fixed(np.array([], np.int64))
    K = elastic_tangent(problem)
    B = problem.disc.near_null_space()
    assert B.shape == (problem.disc.N, 3 if dim == 2 else 6)
    assert np.linalg.matrix_rank(B) == B.shape[1]
    normK = sp.linalg.norm(K)
    for j in range(B.shape[1]):
        assert np.linalg.norm(K @ B[:, j]) <= 1e-12 * normK * np.linalg.norm(B[:, j]), j


def test_amg_solves_what_the_direct_solver_solves(amg_everywhere):
    """The held 3-D tube's elastic system: AMG-CG without a direct solve, and the same answer.
    The error of a solve to a relative residual ρ is at most κ ρ; the tube's κ is ~1e4 (27-node
    hexahedra, 4 × 8 elements), so at ρ = 1e-10 the answers agree to 1e-6 at least."""
    problem = tube(3)
    K = elastic_tangent(problem)
    b = np.random.default_rng(0).standard_normal(K.shape[0])
    stats = {}
    x = ls.solve_symmetric(K, b, near_null=problem.disc.near_null_space, dim=3, stats=stats)
    assert stats.get("direct", 0) == 0 and stats["amg_iterations"] > 0, stats
    x_direct = ls.direct_solve(K, b)
    assert np.linalg.norm(x - x_direct) <= 1e-6 * np.linalg.norm(x_direct)


def test_a_kept_hierarchy_serves_the_next_tangent_and_is_rebuilt_where_it_misses(amg_everywhere):
    """KeptHierarchy: the hierarchy of the tube's tangent solves a nearby one (the tangent scaled
    by 1.01 plus a small shift, as the next Newton tangent) without a new set-up, to the same
    tolerance; a matrix it no longer fits (the shift into the spectrum's middle, where CG fails
    within REUSE_ITERATIONS) costs a rebuild — and that fresh hierarchy failing too returns None
    (the caller's direct solve)."""
    problem = tube(3)
    K = elastic_tangent(problem)
    b = np.random.default_rng(1).standard_normal(K.shape[0])
    kept = ls.KeptHierarchy()
    nn = problem.disc.near_null_space
    for Kn in (K, (1.01 * K + 1e-3 * float(K.diagonal().mean()) * sp.identity(K.shape[0])).tocsr()):
        x = kept.solve(Kn, b, nn)
        assert x is not None and np.linalg.norm(Kn @ x - b) <= 10 * ls.RTOL * np.linalg.norm(b)
    assert kept.setups == 1
    Kin = (K - 0.3 * float(K.diagonal().mean()) * sp.identity(K.shape[0])).tocsr()
    assert kept.solve(Kin, b, nn) is None and kept.setups == 2


def test_a_system_amg_cannot_solve_falls_back_to_the_direct_solve(amg_everywhere):
    """A strongly indefinite matrix (the tangent shifted by 0.3 of its mean diagonal, into the
    middle of its spectrum): CG does not reach the tolerance in its iterations, the direct solve
    answers, and the statistics say so."""
    problem = tube(3)
    K = elastic_tangent(problem)
    shift = 0.3 * float(K.diagonal().mean())
    Kin = (K - shift * sp.identity(K.shape[0])).tocsr()
    b = np.ones(K.shape[0])
    stats = {}
    x = ls.solve_symmetric(Kin, b, near_null=problem.disc.near_null_space, dim=3, stats=stats)
    assert stats == dict(amg_iterations=ls.MAXITER, amg_failures=1, direct=1), stats
    assert np.linalg.norm(Kin @ x - b) <= 1e-8 * np.linalg.norm(b)


@pytest.mark.parametrize("fbar", [None, "linear"])
def test_fem_newton_path_is_the_same_with_amg(fbar, monkeypatch):
    """The 3-D tube, J2, pushed into the plastic range by a bore displacement: the Newton path
    with AMG (CG for the standard element's symmetric tangent, GMRES for F-bar's unsymmetric one)
    ends where the direct solver's does, to the Newton tolerance (1e-9 of the load: displacements
    to 1e-7), with no factorisation."""
    material = Material.j2(E=E, nu=NU, C=200e6, eps0=1e-3, n=0.1)
    loads = (2e-3, 4e-3)
    out = {}
    for amg in (False, True):
        monkeypatch.setitem(ls.AMG_ABOVE, 3, 0 if amg else 10 ** 9)
        problem = tube(3, fbar=fbar, material=material)
        solver = TangentSolver()
        recs, state = load_path(problem, loads, max_increment=2e-3, solver=solver)
        assert all(r["status"] == "ok" for r in recs), recs
        out[amg] = (state.u, solver)
    (u0, s0), (u1, s1) = out[False], out[True]
    assert s1.factorisations == 0 and s1.amg.setups >= 1 and s0.amg.setups == 0
    assert np.linalg.norm(u1 - u0) <= 1e-7 * np.linalg.norm(u0)


def test_csph_static_3d_is_the_same_with_amg(monkeypatch):
    """The 3-D micro-cantilever's elastic slope by static csph (H/Δx = 5, the grain boundary's
    thickness; 5 000 free DOFs): the same with AMG-CG as with the direct solve, to the Newton
    tolerance (1e-8), though Newton solves its systems inexactly: the first iteration of a step
    to the loosest forcing term (FORCING_MAX), the last ones tighter."""
    import sph.static as st
    from studies.microcantilever import MicroCantilever
    from studies.microcantilever.ladders import FEM_STEP
    from studies.microcantilever.static import csph_static

    sc = MicroCantilever(dim=3)
    slope = {}
    calls = []
    real = ls.solve_symmetric

    def spy(*a, **kw):
        stats = kw.setdefault("stats", {})
        x = real(*a, **kw)
        calls.append(dict(stats, rtol=kw["rtol"]))
        return x

    monkeypatch.setattr(st, "solve_symmetric", spy)
    for amg in (False, True):
        monkeypatch.setitem(ls.AMG_ABOVE, 3, 0 if amg else 10 ** 9)
        calls.clear()
        slope[amg] = csph_static(sc, 5, fem_max=FEM_STEP)["elastic_slope"]
        assert calls and all(("direct" in c) != amg for c in calls), calls
    rtols = [c["rtol"] for c in calls]
    assert max(rtols) == ls.FORCING_MAX and min(rtols) < 1e-2 * ls.FORCING_MAX, rtols
    assert slope[True] == pytest.approx(slope[False], rel=1e-8)
