"""F-bar biquadratic quadrilaterals (fem_reference.assembly): a consistent tangent, quadratic Newton,
no spurious modes, no volumetric locking against two closed forms for the plane-strain thick-walled
cylinder (Lamé; the von Mises limit pressure), and point loads on the cantilever.

The cylinder: inner radius a = 1, outer b = 2, one quadrant of 4 (radial) × 8 (hoop) isoparametric
Q9 elements with symmetry rollers (fem_reference.drivers.cylinder_problem).
"""
import dataclasses

import numpy as np
import pytest

from fem_reference import solve
from fem_reference.drivers import cylinder_problem, solve_cylinder
from fem_reference.model import build, discretise
from fem_reference.static import load_path, newton
from workbench import analytic
from workbench.materials import Material
from workbench.scenes import Cantilever

A, B = 1.0, 2.0
E = 200e9
SIGMA_Y = 200e6


def j2(nu):
    """Elastic–perfectly plastic (Swift n = 0: σ_y = C, no hardening)."""
    return Material.j2(E=E, nu=nu, C=SIGMA_Y, eps0=1e-3, n=0.0)


def lame_bore(p, nu):
    """Plane-strain Lamé radial displacement at the bore under internal pressure p."""
    return (1 + nu) * p * A / (E * (B ** 2 - A ** 2)) * ((1 - 2 * nu) * A ** 2 + B ** 2)


# ------------------------------------------------------------------------------------------------
# consistency: tangent, Newton, spurious modes
# ------------------------------------------------------------------------------------------------

# Central differences with h·e ~ 1e-8 a on displacements ~ 1e-3 a: truncation ~(h e/u)² ~ 1e-10,
# round-off ~1e-16 |f|/(h e/u) ~ 1e-11 relative to the largest entry; 1e-6 leaves room for points
# whose return mapping has a tolerance of 1e-12.
TOL_FD = 1e-6


def _fd_check(problem, state, u, rng):
    free = problem.disc.free
    pt = problem.evaluate(u, state, tangent=True)
    K = problem.tangent(pt)
    e = np.zeros_like(u)
    e[free] = 1e-3 * A * rng.standard_normal(len(free))
    h = 1e-5
    fp = problem.evaluate(u + h * e, state, tangent=False)["f_int"][free]
    fm = problem.evaluate(u - h * e, state, tangent=False)["f_int"][free]
    fd = (fp - fm) / (2 * h)
    return np.abs(fd - K @ e[free]).max() / np.abs(fd).max()


@pytest.mark.parametrize("fbar", ["linear", "mean"])
def test_fbar_tangent_matches_finite_difference(fbar):
    rng = np.random.default_rng(3)
    # hyperelastic, nearly incompressible, at a random finite deformation (|H| ~ 1e-2)
    problem, _ = cylinder_problem(Material.neo_hooke(E=E, nu=0.499), A, B, 2, 4, "pressure", fbar)
    state = problem.initial_state()
    u = np.zeros(problem.disc.N)
    u[problem.disc.free] = 1e-2 * A * rng.standard_normal(len(problem.disc.free))
    err_el = _fd_check(problem, state, u, rng)
    # J2 while plastic: committed at bore displacement 3e-3 a (plastic zone part-way through the
    # wall), evaluated at the equilibrium of 4e-3 a (plastic increments at most points)
    problem, _ = cylinder_problem(j2(0.3), A, B, 2, 4, "displacement", fbar)
    _, state = load_path(problem, [3e-3], max_increment=1e-3)
    u0 = state.u.copy()
    u0[problem.disc.fixed] = problem.fixed_values(4e-3)
    res = newton(problem, state, u0, 4e-3)
    assert res.converged, res.reason
    assert np.max(res.point_state["history"][:, 9] - state.history[:, 9]) > 1e-4  # plastic
    err_pl = _fd_check(problem, state, res.u, rng)
    assert err_el < TOL_FD and err_pl < TOL_FD, (err_el, err_pl)


def test_fbar_newton_converges_quadratically():
    """J2 with F-bar, one step of the bore displacement from 1e-3 a (just yielded) to 3e-3 a (the
    plastic zone crosses most of the wall): once the relative residual is below 0.2,
    r_{k+1} ≤ C r_k² with C = 10 (the test of test_fem_assembly) until the round-off floor."""
    problem, _ = cylinder_problem(j2(0.3), A, B, 4, 8, "displacement", "linear")
    _, state = load_path(problem, [1e-3], max_increment=1e-3)
    u0 = state.u.copy()
    u0[problem.disc.fixed] = problem.fixed_values(3e-3)
    res = newton(problem, state, u0, 3e-3, rtol=1e-12, maxit=30)
    assert res.converged, res.reason
    r = np.array(res.residuals)
    assert r[-1] < 1e-11
    C = res.quadratic_constants(start=0.2, floor=1e-10)
    assert len(C) >= 2, f"too few iterates in the asymptotic range: {r}"
    assert max(C) < 10, f"r_(k+1)/r_k^2 = {C} from residuals {r}"


@pytest.mark.parametrize("fbar", [None, "linear", "mean"])
def test_no_spurious_zero_energy_modes(fbar):
    """The unsupported 2 × 2 quarter ring at F = I: exactly the three rigid-body modes have zero
    stiffness (reduced integration would add hourglass modes). At F = I the F-bar tangent is the
    B-bar one and must be symmetric (Π is self-adjoint in the dV inner product)."""
    problem, _ = cylinder_problem(Material.neo_hooke(E=E, nu=0.4999), A, B, 2, 2, "pressure",
                                  fbar)
    problem.disc.set_fixed(np.array([], dtype=np.int64))
    state = problem.initial_state()
    K = problem.tangent(problem.evaluate(state.u, state)).toarray()
    assert np.abs(K - K.T).max() < 1e-12 * np.abs(K).max()
    w = np.linalg.eigvalsh(0.5 * (K + K.T))
    # zero: round-off of the stiffness (bulk modulus ~1.7e4 × shear); the smallest deformation
    # mode is a shear mode, orders of magnitude above
    n_zero = int(np.sum(np.abs(w) < 1e-10 * w.max()))
    assert n_zero == 3, (n_zero, w[:5] / w.max())


# ------------------------------------------------------------------------------------------------
# volumetric locking
# ------------------------------------------------------------------------------------------------

# Lamé, ν = 0.4999, dead bore pressure p = 1e-4 E. Idealisation errors of the comparison: the load
# is a dead nominal traction on the reference bore and the material finite-strain, both O(u/a) =
# O(2e-4) relative; quadratic geometry represents the circles to ~1e-4. The discretisation error of
# a non-locking 4 × 8 Q9 mesh on this smooth field is ~1e-4 (measured +5e-5 with F-bar). 1 % is far
# above all of these and far below the locking error of full 3×3 integration (measured −9.0 %;
# −57 % on 2 × 4), which must exceed 5 % so that the test fails if F-bar does nothing.
TOL_LAME = 0.01
LOCKED_LAME = 0.05


@pytest.mark.parametrize("law", ["neo_hooke", "j2"])
def test_fbar_does_not_lock_lame(law):
    nu = 0.4999
    # J2 stays elastic: the largest von Mises stress, √3 p b²/(b² − a²) ≈ 2.3 p = 46 MPa < σ_y
    mat = Material.neo_hooke(E=E, nu=nu) if law == "neo_hooke" else j2(nu)
    p = 1e-4 * E
    exact = lame_bore(p, nu)
    err = {}
    for fbar in ("linear", None):
        run = solve_cylinder(mat, A, B, 4, 8, [p], control="pressure", fbar=fbar)
        assert run["status"] == ["ok"], run["status"]
        err[fbar] = run["bore_displacement"][0] / exact - 1
    assert abs(err["linear"]) < TOL_LAME, err
    assert err[None] < -LOCKED_LAME, err


# Limit pressure of the elastic–perfectly plastic cylinder (von Mises, plane strain): once the wall
# is fully plastic, σ_θ − σ_r = 2σ_y/√3 and equilibrium give p = (2/√3) σ_y ln(b'/a'), with the
# current radii a' = a + u_a, b' = b + u_b (exact for the fully plastic incompressible state; we
# compare the Cauchy bore pressure — radial bore reaction over the current bore length — with it,
# so no small-strain approximation enters). Approximations left: the Kirchhoff stress yields
# (τ = Jσ; |J − 1| ≲ p/K ≈ 1e-3), the elastic compressibility keeps σ_z slightly off the mean of
# σ_r, σ_θ and the limit is approached asymptotically (the wall is fully plastic from u_a ≈ 3e-3 a;
# measured 0.9995 at 8e-3 a, 0.9998 at 1.5e-2 a with ν = 0.3). Using the reference radii instead
# would be 1.1 % off at u_a = 1.5e-2 a. Tolerance 1 %.
TOL_LIMIT = 0.01
BORE = [2e-3, 4e-3, 8e-3, 1.5e-2]  # prescribed radial bore displacement / a


def _limit_ratio(run):
    p_lim = 2 / np.sqrt(3) * SIGMA_Y * np.log((B + run["outer_displacement"])
                                             / (A + run["bore_displacement"]))
    return run["pressure"] / p_lim


@pytest.mark.parametrize("nu", [0.3, 0.4999])
def test_fbar_reaches_the_limit_pressure(nu):
    """F-bar: the bore pressure levels off at the limit pressure (within 1 % at u_a = 8e-3 and
    1.5e-2 a). With ν = 0.4999 the full-integration element locks: its pressure keeps rising far
    past the limit (measured 1.47 and 1.83 p_lim). With ν = 0.3 the plastic flow alone does not lock
    Q9 with 3×3 Gauss on this axisymmetric problem (measured 0.9997, 1.0002 p_lim on 4 × 8;
    1.0055 on 2 × 4): there, the test checks F-bar only."""
    ratio = {}
    for fbar in ("linear", None):
        run = solve_cylinder(j2(nu), A, B, 4, 8, BORE, control="displacement", fbar=fbar,
                             max_increment=1e-3)
        assert run["status"] == ["ok"] * len(BORE), run["status"]
        ratio[fbar] = _limit_ratio(run)
    assert np.all(np.abs(ratio["linear"][2:] - 1) < TOL_LIMIT), ratio
    if nu > 0.49:
        assert ratio[None][-1] > 1.3 and ratio[None][-1] > 1.1 * ratio[None][-2], ratio


# ------------------------------------------------------------------------------------------------
# point loads
# ------------------------------------------------------------------------------------------------

SMALL = 0.00192  # P L²/(E I) of the cantilever scene's small load
# Timoshenko: the tolerance of test_fem_cantilever (the shear term of the beam theory, 1.34 %).
TOL_TIMOSHENKO = 0.015
# A point force on the tip mid-node adds the local (Flamant) indentation of a 2-D point load,
# ≈ 2P/(π E') ln(H/h) at the loaded node (unbounded as h → 0, hence compared on a fixed mesh),
# relative to the tip deflection 4 P (L/H)³/E': ln(H/h)/(2π (L/H)³) ≈ 6e-4 for 4 elements across
# H (node spacing h = H/8). Measured +5.9e-4 (and +3.8e-4, +8.1e-4 on 2 and 8 across: the ln 2
# steps of ~2e-4 of this estimate). The point load must deflect more, by less than 0.2 %.
TOL_POINT = 0.002


def tip_point_load(sc, resolution):
    """Tip deflection of the cantilever scene with its tip traction replaced by a point load of
    the same total force on the tip mid-point (L, 0) (a node: the force on that node alone)."""
    from workbench.scenes import model as M
    from workbench.scenes.shapes import Point

    model = sc.model(sc.H / resolution)
    model = dataclasses.replace(
        model, sets=model.sets + (M.Set("tip_point", Point((sc.L, 0.0))),),
        loads=(M.PointLoad("tip_point", (0.0, -sc.force(1.0)), scale=M.Proportional()),))
    fm = discretise(model, resolution)
    _, state = load_path(fm.problem, [SMALL])
    return -float((fm.probes["tip_mid"] @ state.u)[1])


def test_point_load_on_cantilever_tip():
    sc = dataclasses.replace(Cantilever(), loads=(SMALL,))
    timo = analytic.cantilever_tip(sc, SMALL)
    tr = solve(sc, 4)["tip_deflection"][0]
    pt = tip_point_load(sc, 4)
    assert abs(tr / timo - 1) < TOL_TIMOSHENKO and abs(pt / timo - 1) < TOL_TIMOSHENKO, \
        (tr / timo, pt / timo)
    assert 0 < pt / tr - 1 < TOL_POINT, pt / tr - 1
    # point loads add to the distributed ones: half as traction, half on the node gives the mean
    # of the two (superposition; geometric nonlinearity at this load is ~1e-6 relative)
    from fem_reference.static import Problem

    base = build(sc, 4).problem
    iy = base.disc.node_dof(np.array([sc.L, 0.0]), 1)
    half = Problem(base.disc, base.material, base.plane, base.fixed_values,
                   lambda lam: 0.5 * base.f_ext(lam),
                   point_loads=((np.array([sc.L, 0.0]), np.array([0.0, -0.5 * sc.force(1.0)])),))
    _, state = load_path(half, [SMALL])
    mixed = -state.u[iy]
    assert abs(mixed / (0.5 * (tr + pt)) - 1) < 1e-5, mixed / (0.5 * (tr + pt))
