"""3-D FEM: F-bar in 3-D against volumetric locking on the thick-walled tube with plane-strain end
constraints (Lamé; the von Mises limit pressure), and the consistent F-bar tangent with J2 by
finite differences. (The 27-node hexahedron against Timoshenko beam theory, and the trilinear
hexahedron's shear locking, run on the 3-D cantilever scene: tests/test_fem_model.py.)
"""
import numpy as np
import pytest

from fem_reference.drivers import cylinder_problem, solve_cylinder
from fem_reference.static import load_path, newton
from workbench.materials import HIST_EPS_P, Material

# ------------------------------------------------------------------------------------------------
# volumetric locking: the tube a = 1 ≤ R ≤ b = 2 with u_Z = 0 on both end faces (plane strain)
# ------------------------------------------------------------------------------------------------

A_IN, B_OUT = 1.0, 2.0
E_ST = 200e9
SIGMA_Y = 200e6


def j2(nu):
    """Elastic–perfectly plastic (Swift n = 0: σ_y = C)."""
    return Material.j2(E=E_ST, nu=nu, C=SIGMA_Y, eps0=1e-3, n=0.0)


def lame_bore(p, nu):
    """Plane-strain Lamé radial displacement of the bore under internal pressure p."""
    return (1 + nu) * p * A_IN / (E_ST * (B_OUT ** 2 - A_IN ** 2)) * (
        (1 - 2 * nu) * A_IN ** 2 + B_OUT ** 2)


# Lamé at ν = 0.4999, p = 1e-4 E, 4 × 8 × 1 elements: the comparison's own errors are O(u/a) =
# 2e-4 (dead nominal pressure on the reference bore, finite strain) and the discretisation of a
# non-locking mesh on this smooth field is ~1e-4 (measured +4.8e-5 with F-bar): 1e-3. Full 3×3×3
# integration locks: measured −9.0 % (−57 % on 2 × 4); it must be beyond −5 %.
TOL_LAME = 1e-3
LOCKED = 0.05


def test_fbar_3d_does_not_lock_lame():
    nu = 0.4999
    p = 1e-4 * E_ST
    err = {}
    for fbar in ("linear", None):
        run = solve_cylinder(Material.neo_hooke(E=E_ST, nu=nu), A_IN, B_OUT, 4, 8, [p],
                             control="pressure", fbar=fbar, dim=3)
        assert run["status"] == ["ok"], run["status"]
        err[fbar] = run["bore_displacement"][0] / lame_bore(p, nu) - 1
    assert abs(err["linear"]) < TOL_LAME, err
    assert err[None] < -LOCKED, err


# The limit pressure of the fully plastic tube (von Mises, plane strain), p = (2/√3) σ_y ln(b'/a')
# with the current radii: the reasoning and tolerance of tests/test_fem_locking.py (the limit is
# approached asymptotically; Kirchhoff-stress yield, |J − 1| ≲ 1e-3): 1 %. On 2 × 4 × 1 elements
# F-bar is measured at 1.0001 p_lim; full integration at ν = 0.4999 locks (2.5 to 12 p_lim).
TOL_LIMIT = 0.01
BORE = [2e-3, 4e-3, 8e-3, 1.5e-2]


def test_fbar_3d_reaches_the_limit_pressure():
    ratio = {}
    for fbar in ("linear", None):
        run = solve_cylinder(j2(0.4999), A_IN, B_OUT, 2, 4, BORE, control="displacement",
                             fbar=fbar, max_increment=1e-3, dim=3)
        assert run["status"] == ["ok"] * len(BORE), run["status"]
        p_lim = 2 / np.sqrt(3) * SIGMA_Y * np.log((B_OUT + run["outer_displacement"])
                                                 / (A_IN + run["bore_displacement"]))
        ratio[fbar] = run["pressure"] / p_lim
    assert np.all(np.abs(ratio["linear"][2:] - 1) < TOL_LIMIT), ratio
    assert ratio[None][-1] > 1.3 and ratio[None][-1] > 1.1 * ratio[None][-2], ratio


# ------------------------------------------------------------------------------------------------
# consistent tangent of F-bar in 3-D
# ------------------------------------------------------------------------------------------------

# Central differences with h·e ~ 1e-8 a on displacements ~ 1e-3 a: truncation ~1e-10, round-off
# ~1e-11 relative; the return mapping's tolerance 1e-12. Measured 1e-9 to 7e-9.
TOL_FD = 1e-6


def _fd_check(problem, state, u, rng):
    free = problem.disc.free
    K = problem.tangent(problem.evaluate(u, state, tangent=True))
    e = np.zeros_like(u)
    e[free] = 1e-3 * A_IN * rng.standard_normal(len(free))
    h = 1e-5
    fp = problem.evaluate(u + h * e, state, tangent=False)["f_int"][free]
    fm = problem.evaluate(u - h * e, state, tangent=False)["f_int"][free]
    fd = (fp - fm) / (2 * h)
    return np.abs(fd - K @ e[free]).max() / np.abs(fd).max()


@pytest.mark.parametrize("fbar", ["linear", "mean"])
def test_fbar_3d_tangent_and_newton(fbar):
    rng = np.random.default_rng(3)
    # nearly incompressible neo-Hooke at a random finite deformation
    problem, _ = cylinder_problem(Material.neo_hooke(E=E_ST, nu=0.499), A_IN, B_OUT, 2, 4,
                                  "pressure", fbar, dim=3)
    state = problem.initial_state()
    u = np.zeros(problem.disc.N)
    u[problem.disc.free] = 1e-2 * A_IN * rng.standard_normal(len(problem.disc.free))
    err_el = _fd_check(problem, state, u, rng)
    # J2 while plastic: committed at bore displacement 3e-3 a, one Newton step to 4e-3 a
    problem, _ = cylinder_problem(j2(0.3), A_IN, B_OUT, 2, 4, "displacement", fbar, dim=3)
    _, state = load_path(problem, [3e-3], max_increment=1e-3)
    u0 = state.u.copy()
    u0[problem.disc.fixed] = problem.fixed_values(4e-3)
    res = newton(problem, state, u0, 4e-3, rtol=1e-12, maxit=30)
    assert res.converged, res.reason
    assert np.max(res.point_state["history"][:, HIST_EPS_P] - state.history[:, HIST_EPS_P]) > 1e-4
    err_pl = _fd_check(problem, state, res.u, rng)
    assert err_el < TOL_FD and err_pl < TOL_FD, (err_el, err_pl)
    # quadratic convergence (the criterion of tests/test_fem_assembly.py)
    C = res.quadratic_constants(start=0.2, floor=1e-10)
    assert len(C) >= 2 and max(C) < 10, (C, res.residuals)
