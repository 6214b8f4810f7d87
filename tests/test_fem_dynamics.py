"""Modal and Newmark with per-element materials (stiffness, density) and J2 history.

1. A rod of two materials in series (plane strain with rollers on both lateral faces: a 1-D rod of
   modulus M_k = λ_k + 2μ_k, density ρ_k), fixed at X = 0, free at X = L: the lowest frequency
   solves Z₀ cot(k₀ L₀) = Z₁ tan(k₁ L₁) with k_k = ω/c_k, c_k = √(M_k/ρ_k), Z_k = √(M_k ρ_k).
2. Newmark from the modal shape as initial velocity: the trapezoidal rule turns the frequency ω_h
   of the mesh into ω̃ with ω̃Δt = 2 arctan(ω_h Δt/2) exactly (linear problem), so the period
   from the tip history is T_h · Ω/(2 arctan(Ω/2)), Ω = ω_h Δt, and the energy is conserved.
3. J2 under uniaxial strain at a constant stretch rate, by Newmark: with u_X = v t on X = L and
   the initial velocity v X/L, u = v t X/L is an exact solution (homogeneous stress, zero
   acceleration) whatever the densities; the axial reaction is P₁₁(λ) A₀ with the closed form
   below and the equivalent plastic strain committed at every step is p(ε).
"""
import numpy as np
import pytest
from scipy.optimize import brentq

from fem_reference.assembly import Discretisation
from fem_reference.boundary import Constraints
from fem_reference.dynamic import newmark
from fem_reference.mesh import box
from fem_reference.modal import lowest_modes
from fem_reference.observe import reaction
from fem_reference.static import Problem
from fem_reference.model import period_amplitude
from workbench.materials import HIST_EPS_P, Material, MaterialTable, TABLE1_STEEL

L, L0, W = 1.0, 0.5, 0.1
ROD = MaterialTable((Material.svk(E=2e9, nu=0.3, rho=7800.0),
                     Material.svk(E=0.5e9, nu=0.25, rho=1200.0)))


def rod(n_per_half):
    disc = Discretisation(box((0.0, 0.0), (L, W), (2 * n_per_half, 1)))
    mat_id = (disc.centroids()[:, 0] > L0).astype(np.int64)
    bc = Constraints(disc)
    bc.roller(lambda x: x[0] < 1e-12, 0)
    bc.roller(lambda x: (x[1] < 1e-12) | (x[1] > W - 1e-12), 1)
    bc.apply()
    return Problem(disc, ROD, "strain", bc.values, lambda lam: np.zeros(disc.N), mat_id=mat_id)


def omega_exact():
    M = [m.lam + 2 * m.mu for m in ROD.materials]
    rho = [m.rho for m in ROD.materials]
    c = [np.sqrt(Mk / r) for Mk, r in zip(M, rho)]
    Z = [np.sqrt(Mk * r) for Mk, r in zip(M, rho)]
    f = lambda w: Z[0] * np.cos(w / c[0] * L0) * np.cos(w / c[1] * (L - L0)) \
        - Z[1] * np.sin(w / c[0] * L0) * np.sin(w / c[1] * (L - L0))  # noqa: E731
    # the first root: below the first quarter-wave frequency of the softer segment alone
    w_hi = np.pi / 2 * min(c) / min(L0, L - L0) * 2
    grid = np.linspace(1e-6 * w_hi, w_hi, 2001)
    i = np.flatnonzero(np.sign(f(grid[:-1])) != np.sign(f(grid[1:])))[0]
    return brentq(f, grid[i], grid[i + 1], xtol=1e-14, rtol=1e-15)


# Quadratic elements with the consistent mass over-estimate a frequency by ≈ (k h)⁴/1440 (the
# dispersion of the acoustic branch, h the element length); with 4 elements per segment
# k h ≤ 0.32 (the stiff segment): bound (k h)⁴/720 = 1.4e-5 (measured 6.1e-6), and the order 4.
def test_two_material_rod_frequency():
    w = omega_exact()
    err = {n: lowest_modes(rod(n), k=2)[0][0] / w - 1 for n in (2, 4)}
    kh = max(w / np.sqrt((m.lam + 2 * m.mu) / m.rho) for m in ROD.materials) * L0 / 4
    assert 0 < err[4] < kh ** 4 / 720, (err, kh ** 4 / 720)
    order = np.log2(err[2] / err[4])
    assert 3.5 < order < 4.5, (order, err)


def test_newmark_period_and_energy_with_two_materials():
    problem = rod(4)
    disc = problem.disc
    omega, shapes = lowest_modes(problem, k=2)
    w = omega[0]
    phi = shapes[:, 0] / np.abs(shapes[:, 0]).max()
    steps_per_period = 40
    dt = 2 * np.pi / w / steps_per_period
    tip = disc.node_dof(np.array([L, 0.0]), 0)
    v0 = 1e-6 * w * L * phi  # amplitude 1e-6 L: geometric nonlinearity ~1e-6
    run = newmark(problem, v0, dt, 3 * steps_per_period, observe=lambda u: u[tip], rtol=1e-12)
    assert run["status"] == "ok", run["status"]
    Om = w * dt
    expect = 2 * np.pi / w * Om / (2 * np.arctan(Om / 2))
    T, _ = period_amplitude(run["time"], run["observed"])
    # the elongation itself is Ω²/12 = 2.1e-3; the zero crossings of the sampled sine are found by
    # linear interpolation, off by at most Ω²/24 · Δt/T = 2.6e-5 of the period (the geometric
    # nonlinearity adds ~1e-6): 5e-5 (measured 3e-6)
    assert abs(T / expect - 1) < 5e-5, (T / expect - 1, expect * w / (2 * np.pi) - 1)
    # the trapezoidal rule conserves the energy of a linear system: only the 1e-6 nonlinearity
    E = run["kinetic_energy"] + run["strain_energy"]
    assert np.abs(E / E[0] - 1).max() < 1e-6, np.abs(E / E[0] - 1).max()


# ------------------------------------------------------------------------------------------------
# J2, uniaxial strain, constant stretch rate (F = diag(λ, 1, 1), ε = ln λ)
# ------------------------------------------------------------------------------------------------
# Hencky elasticity with J2 flow: ε_p = p (1, −½, −½), tr ε_e = ε, von Mises q = 2μ(ε − 3p/2);
# elastic while 2με ≤ σ_y(0), then q = C (p + ε0)^n gives p; τ₁₁ = K ε + (2/3) q, P₁₁ = τ₁₁/λ.
# The FEM reproduces the homogeneous motion to the Newton tolerance (1e-10): 1e-8.
TOL_J2 = 1e-8


def uniaxial_strain_j2(mat, eps):
    mu, K = mat.mu, mat.K
    sy = lambda p: mat.C * (p + mat.eps0) ** mat.n  # noqa: E731
    out_P, out_p = [], []
    for e in eps:
        if 2 * mu * e <= sy(0.0):
            p, q = 0.0, 2 * mu * e
        else:
            p = brentq(lambda p: 2 * mu * (e - 1.5 * p) - sy(p), 0.0, e / 1.5, xtol=1e-16,
                       rtol=1e-15)
            q = sy(p)
        out_P.append((K * e + 2 / 3 * q) / np.exp(e))
        out_p.append(p)
    return np.array(out_P), np.array(out_p)


def test_newmark_j2_constant_stretch_rate():
    Lb, Wb, v = 4e-3, 1e-3, 1.0  # stretch rate v/L = 250 /s
    disc = Discretisation(box((0, 0, 0), (Lb, Wb, Wb), (4, 1, 1)))
    mats = MaterialTable((TABLE1_STEEL, TABLE1_STEEL.replace(rho=3 * TABLE1_STEEL.rho)))
    mat_id = np.array([0, 1, 0, 1])
    bc = Constraints(disc)
    bc.roller(lambda x: x[0] < 1e-12, 0)
    end = bc.prescribe(lambda x: x[0] > Lb - 1e-12, 0, lambda t: v * t)
    bc.roller(lambda x: (x[1] < 1e-12) | (x[1] > Wb - 1e-12), 1)
    bc.roller(lambda x: (x[2] < 1e-12) | (x[2] > Wb - 1e-12), 2)
    bc.apply()
    problem = Problem(disc, mats, None, bc.values, lambda t: np.zeros(disc.N), mat_id=mat_id)
    X = disc.basis.doflocs
    v0 = np.where(np.arange(disc.N) % 3 == 0, v * X[0] / Lb, 0.0)
    rec = []

    def cb(step, t, state, vel):
        rec.append((t, reaction(problem, state, dofs=end)[0],
                    state.history[:, HIST_EPS_P].copy()))

    dt = 1e-5
    run = newmark(problem, v0, dt, 20, observe=lambda u: u[end[0]], rtol=1e-10, callback=cb)
    assert run["status"] == "ok", run["status"]
    t = np.array([r[0] for r in rec])
    eps = np.log1p(v * t / Lb)
    P, p = uniaxial_strain_j2(TABLE1_STEEL, eps)
    R = np.array([r[1] for r in rec])
    assert p[-1] > 0.02  # well into the plastic range (σ_y/2μ = 1.7e-3)
    assert np.abs(R - P * Wb * Wb).max() < TOL_J2 * np.abs(P).max() * Wb * Wb
    ep = np.array([r[2] for r in rec])  # (steps, points)
    assert np.abs(ep - p[:, None]).max() < TOL_J2 * p.max() + 1e-15
    # kinetic energy of the exact velocity field ½ ∫ ρ (v X/L)² dV, constant
    rho = mats.rho(mat_id)
    ke = 0.5 * v ** 2 * Wb * Wb * sum(rho[e] * (((e + 1) * Lb / 4) ** 3 - (e * Lb / 4) ** 3)
                                      / (3 * Lb ** 2) for e in range(4))
    assert np.allclose(run["kinetic_energy"], ke, rtol=1e-9)


def test_newmark_deletes_a_failed_element():
    """The same motion with the second element's damage limit ε_L = 0.02 (in uniaxial strain
    ε̄_p = p): the reaction follows the closed form while p < ε_L; at the step where p passes
    ε_L that element fails, is deleted and loses its mass, and the run goes on."""
    Lb, Wb, v = 4e-3, 1e-3, 1.0
    disc = Discretisation(box((0, 0, 0), (Lb, Wb, Wb), (4, 1, 1)))
    weak = TABLE1_STEEL.replace(eps_L=0.02, rho=3 * TABLE1_STEEL.rho)
    mats = MaterialTable((TABLE1_STEEL, weak))
    mat_id = np.array([0, 1, 0, 0])
    bc = Constraints(disc)
    bc.roller(lambda x: x[0] < 1e-12, 0)
    end = bc.prescribe(lambda x: x[0] > Lb - 1e-12, 0, lambda t: v * t)
    bc.roller(lambda x: (x[1] < 1e-12) | (x[1] > Wb - 1e-12), 1)
    bc.roller(lambda x: (x[2] < 1e-12) | (x[2] > Wb - 1e-12), 2)
    bc.apply()
    problem = Problem(disc, mats, None, bc.values, lambda t: np.zeros(disc.N), mat_id=mat_id,
                      deletion=True)
    X = disc.basis.doflocs
    v0 = np.where(np.arange(disc.N) % 3 == 0, v * X[0] / Lb, 0.0)
    mass0 = problem.mass().sum() / 3
    rec = []
    run = newmark(problem, v0, 1e-5, 20, observe=lambda u: u[end[0]], rtol=1e-10,
                  callback=lambda s, t, st, vel: rec.append(
                      (t, reaction(problem, st, dofs=end)[0], disc.active.copy())))
    assert run["status"] == "ok", run["status"]
    t = np.array([r[0] for r in rec])
    P, p = uniaxial_strain_j2(TABLE1_STEEL, np.log1p(v * t / Lb))
    intact = np.array([r[2].all() for r in rec])
    assert intact[0] and not intact[-1]
    fail = np.flatnonzero(~intact)[0]
    assert p[fail - 1] < 0.02 <= p[fail]  # deleted at the step that crossed ε_L
    R = np.array([r[1] for r in rec])
    assert np.abs(R[:fail] - P[:fail] * Wb * Wb).max() < TOL_J2 * np.abs(P).max() * Wb * Wb
    assert run["deleted"].tolist() == [1]
    # the weak element (ρ 3×) had 3/6 of the mass: half is left
    assert problem.mass().sum() / 3 == pytest.approx(0.5 * mass0, rel=1e-12)


def _bar_from_rest(v=5.0, n=8):
    """The J2 bar of the tests above, at rest, its end X = L pulled at v from t = 0: a plastic
    wave, no homogeneous solution to start Newton from."""
    Lb, Wb = 4e-3, 1e-3
    disc = Discretisation(box((0, 0, 0), (Lb, Wb, Wb), (n, 1, 1)))
    bc = Constraints(disc)
    bc.roller(lambda x: x[0] < 1e-12, 0)
    bc.prescribe(lambda x: x[0] > Lb - 1e-12, 0, lambda t: v * t)
    bc.roller(lambda x: (x[1] < 1e-12) | (x[1] > Wb - 1e-12), 1)
    bc.roller(lambda x: (x[2] < 1e-12) | (x[2] > Wb - 1e-12), 2)
    bc.apply()
    return Problem(disc, TABLE1_STEEL, None, bc.values, lambda t: np.zeros(disc.N))


def test_newmark_cuts_a_step_newton_cannot_take():
    """With three Newton iterations allowed, the first step of 1 µs does not converge: without
    step cutting the run stops there; with it the run goes on in halved steps, and its axial
    displacements are as close to a run at a quarter of the step as the uncut run at the full
    step with enough iterations (the halves are finer steps of the same scheme)."""
    problem = _bar_from_rest()
    v0 = np.zeros(problem.disc.N)
    ux = lambda u: u[::3].copy()  # noqa: E731
    stuck = newmark(problem, v0, 1e-6, 20, observe=ux, maxit=3, max_cuts=0)
    assert stuck["status"].startswith("diverged at t=1e-06")
    cut = newmark(problem, v0, 1e-6, 20, observe=ux, maxit=3)
    assert cut["status"] == "ok" and len(cut["time"]) == 21
    assert len(cut["newton_iterations"]) > 20  # some steps were cut
    full = newmark(problem, v0, 1e-6, 20, observe=ux)
    fine = newmark(problem, v0, 0.25e-6, 80, observe=ux)
    ref = fine["observed"][::4]
    assert np.abs(cut["observed"] - ref).max() <= np.abs(full["observed"] - ref).max()


def test_newmark_reaction_impulse_is_the_momentum_change():
    """on_step's r on the fixed DOFs is the supports' force M a + f_int − f_ext: summed over the
    axial fixed DOFs (both ends) and integrated by the trapezoidal rule it equals the change of
    the bar's axial momentum 1ᵀ M v (Σ f_int = 0 for any displacement: the shape functions sum
    to one; no external force), to the Newton tolerance (1e-10 of the force scale: 1e-8 here)."""
    problem = _bar_from_rest()
    disc = problem.disc
    axial = np.arange(disc.N) % 3 == 0
    fixed_x = np.intersect1d(disc.fixed, np.flatnonzero(axial))
    impulse, prev, last_v = [0.0], [0.0], [None]  # at rest at t = 0: r₀ = 0

    def on_step(t, h, r):
        now = r[fixed_x].sum()
        impulse[0] += 0.5 * h * (prev[0] + now)
        prev[0] = now

    run = newmark(problem, np.zeros(disc.N), 1e-6, 20, observe=lambda u: 0.0, on_step=on_step,
                  callback=lambda s, t, st, v: last_v.__setitem__(0, v.copy()))
    assert run["status"] == "ok"
    momentum = float((problem.mass() @ last_v[0])[axial].sum())
    assert abs(momentum) > 0
    assert impulse[0] == pytest.approx(momentum, rel=1e-8)
