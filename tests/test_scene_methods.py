"""Issue 9's verification scenes run by every method through one driver: the bi-material bar (two
regions of different stiffness in one body, exact answer the series spring) and the 3-D cantilever
of rectangular section (against Timoshenko beam theory), written only with the scene API — `fem`,
`csph`, `hpm`, and classic SPH `sph`, whose static drive is dynamic relaxation through its own time
step (sph.relaxation).

References, each independent of the code under test: the series spring, Timoshenko beam theory
(Cowper's shear coefficient), the exact pure-bending field, and the equilibrium of classic SPH's
eq. 1–3 (003) linearised about the reference configuration, assembled from the SPH sums written out
in numpy over a k-d tree and solved directly (the answer the relaxation must reach).
"""
import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fem_reference import solve_model
from sph import driver, hpm, particles, relaxation
from sph.particles import discretise
from test_methods_3d import kernel_pairs
from workbench.scenes import BiMaterialBar, Cantilever3D

C3D = Cantilever3D()
"""L/H = 8, B = H, tip load P L²/(E I) = 0.01: small (δ/L = 0.3 %, strains ≤ 6e-4)."""
PARTICLE_RUNS = (("csph", 2), ("csph", 4), ("hpm", 2), ("hpm", 4), ("sph", 2))
FEM_ELEMENTS = 2
"""27-node hexahedra across H (tests/test_fem_model.py: within 1 % of the finest rung there)."""
# Classic SPH's relaxed state against the directly solved linearised equilibrium: the relaxation
# stops at ‖R‖ ≤ TOL ‖f‖ (1e-4), which moves the observed displacement or reaction by about TOL
# (sph.relaxation); the load's nonlinearity is O(strain²) relative here (< 1e-6). Ten times TOL
# covers the spread of the residual over modes; a relaxation stopped early or stuck in a wrong
# state is off by O(1).
TOL_RELAXED = 10 * relaxation.TOL


def tip_error(out) -> float:
    """Tip deflection over Timoshenko's, minus one, at the scene's load."""
    return float(out["tip_deflection"][0]) / C3D.timoshenko(C3D.loads[0]) - 1


@pytest.fixture(scope="module")
def cantilever():
    """(method, resolution) → the driver's result on C3D; ('fem', FEM_ELEMENTS) the FEM's."""
    runs = {key: driver.solve(key[0], C3D, key[1]) for key in PARTICLE_RUNS}
    runs[("fem", FEM_ELEMENTS)] = solve_model(C3D, FEM_ELEMENTS)
    for key, r in runs.items():
        assert r["status"] == ["ok"], (key, r["status"])
    return runs


# ------------------------------------------------------------------------------------------------
# the linearised classic SPH (003 eq. 1–3) in numpy
# ------------------------------------------------------------------------------------------------

def linear_sph(scene, res, lam, h_ratio=1.3):
    """Classic SPH of ``scene`` at ``res`` linearised about the reference configuration: with
    equal densities, eq. 1–3 are the gradient of ½ Σ_a V_a ε_a : C_a : ε_a, ε_a = sym L_a(u),
    L_a = Σ_b V_b (u_b − u_a) ⊗ ∇_a W_ab (sph.classic docstring), so K = Bᵀ diag(V_a C_a) B.
    Returns (particles, K (sparse, N d × N d), u (N, d) the equilibrium at the load λ = ``lam``
    with the scene's constraints, loads f (N, d))."""
    model, _ = driver.model_at(scene, res)
    ps = discretise(model, res)
    N, d = ps.X.shape
    i, j, g = kernel_pairs(ps.X, h_ratio * ps.dx)
    rows, cols, vals = [], [], []
    for k in range(d):
        for l in range(d):
            rows += [(i * d + k) * d + l] * 2
            cols += [j * d + k, i * d + k]
            vals += [ps.V[j] * g[:, l], -ps.V[j] * g[:, l]]
    B = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(N * d * d, N * d))
    B = 0.5 * (B + B[np.arange(N * d * d).reshape(N, d, d).transpose(0, 2, 1).ravel()])  # sym
    lam_ = np.array([m.lam for m in ps.table.materials])[ps.mat_id]
    mu = np.array([m.mu for m in ps.table.materials])[ps.mat_id]
    I = np.eye(d)
    C = (np.einsum("n,ij,kl->nijkl", lam_, I, I) + np.einsum("n,ik,jl->nijkl", mu, I, I)
         + np.einsum("n,il,jk->nijkl", mu, I, I)) * ps.V[:, None, None, None, None]
    r = np.arange(N * d * d).reshape(N, d * d)
    D = sp.csr_matrix((C.reshape(N, d * d, d * d).ravel(),
                       (np.repeat(r, d * d, axis=1).ravel(), np.tile(r, (1, d * d)).ravel())),
                      shape=(N * d * d, N * d * d))
    K = (B.T @ D @ B).tocsr()
    run = driver.Run(model, ps, driver.method_module("sph").build(ps))
    f = run.dead_forces(lam)
    fixed = ps.fixed.ravel()
    u = (run.prescribed_targets(lam) - ps.X).ravel() * fixed
    free = ~fixed
    u[free] = spla.spsolve(K[free][:, free].tocsc(), f.ravel()[free] - K[free][:, fixed] @ u[fixed])
    return ps, K, u.reshape(N, d), f


def linear_bar_reaction(sc, res):
    """(reaction of the linearised classic SPH, its Rayleigh bound): with the displacement U
    prescribed on X = L and no load, R U = uᵀKu at equilibrium and u minimises uᵀKu among fields
    with those boundary values, so R ≤ u_eᵀ K u_e / U for the exact series-spring field u_e."""
    ps, K, u, f = linear_sph(sc, res, 1.0)
    R = float((K @ u.ravel()).reshape(u.shape)[ps.sets["x1"], 0].sum())
    M1, M2 = [m.lam + 2 * m.mu for m in sc.materials()]
    s = sc.exact_reaction() / sc.H ** (sc.dim - 1)  # the axial stress
    xs = sc.split * sc.L
    ue = np.zeros_like(u)
    X = ps.X[:, 0]
    ue[:, 0] = np.where(X <= xs, s / M1 * X, s / M1 * xs + s / M2 * (X - xs))
    U = sc.strain * sc.L
    assert abs(ue[ps.sets["x1"], 0] - U).max() < 1e-12 * U
    return R, float(ue.ravel() @ (K @ ue.ravel())) / U


# ------------------------------------------------------------------------------------------------
# the bi-material bar
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("dim", [2, 3])
def test_bimaterial_bar_reaction_converges_to_the_series_spring(dim):
    """csph (per-particle materials: a material row per region). The strain jumps at the
    interface; the kernel's support smears it over about one spacing on either side, so the
    compliance of that band is in error by O(Δx/L): the reaction within Δx/(2L) of the series
    spring (5 % at 2 and 2.5 % at 4 particles across H; measured +3.6 % and +1.7 %), falling at
    first order (ratio > 1.6 from 2 to 4 across H; measured 2.1)."""
    sc = BiMaterialBar(dim=dim)
    err = []
    for res in (2, 4):
        r = driver.solve("csph", sc, res)
        assert r["status"] == ["ok"]
        err.append(r["reaction"][-1] / sc.exact_reaction() - 1)
        dx = sc.H / res
        assert abs(err[-1]) < dx / (2 * sc.L), (res, err)
    assert abs(err[0] / err[1]) > 1.6, err


SPH_BARS = ((2, 2), (2, 4), (2, 8), (3, 2))


@pytest.fixture(scope="module")
def sph_bars():
    """(dim, res) → classic SPH's relaxed result on BiMaterialBar(dim), without mirror images at
    its end x = 0 (mirror='none'): the linearised reference (linear_bar_reaction) is the one-sided
    discretisation, and the boundary deficiency below is what these runs are here to show."""
    return {(d, r): driver.solve("sph", BiMaterialBar(dim=d), r, mirror="none")
            for d, r in SPH_BARS}


@pytest.mark.parametrize("dim,res", SPH_BARS)
def test_sph_relaxation_reaches_the_linearised_equilibrium_bar(sph_bars, dim, res):
    """Dynamic relaxation (prescribed motion: the ramp, then kinetic damping) ends where the
    directly solved linearised classic SPH is: the reaction within TOL_RELAXED (strain 1e-6: the
    nonlinearity is 1e-6)."""
    out = sph_bars[(dim, res)]
    assert out["status"] == ["ok"], out["status"]
    assert out["iterations"][0] > 0
    R_lin, _ = linear_bar_reaction(BiMaterialBar(dim=dim), res)
    assert abs(out["reaction"][0] / R_lin - 1) < TOL_RELAXED, (out["reaction"][0], R_lin)


def test_sph_bimaterial_bar_against_the_series_spring(sph_bars):
    """Classic SPH with the Eulerian kernel and no correction: a particle within 2h = 2.6 Δx of a
    face (the rollers and the loaded ends have no ghost particles) has a truncated kernel, its
    velocity gradient of a uniform stretch is short of it by the missing part (first-order boundary
    deficiency), so the bar is too soft by the share of the section in that layer, O(Δx/H). At
    2–8 across H the layer covers 65–100 % of the section: its error is of order one
    (measured −80 %, −58 %, −37 % in 2-D at 2, 4, 8 across; −91 % in 3-D at 2; the linearised
    reference continues with −22 % at 16), far outside csph's Δx/(2L). Checked:

    - the reaction lies below the Rayleigh bound u_eᵀKu_e/U of the exact field (the discrete
      minimum of energy; TOL_RELAXED for the relaxation) — the sign and size of the stiffness loss
      follow from the kernel sums alone — and above zero;
    - the error falls at each refinement with an order between 4 and 8 across of 1 ± 0.5: first
      order (a layer ∝ Δx), not yet asymptotic while the layer is most of the section (the
      linearised reference gives 0.65 from 4 to 8 and 0.77 from 8 to 16);
    - it is outside csph's bound Δx/(2L) at every resolution (classic SPH fails here, as 003 says
      uncorrected SPH does at boundaries)."""
    err = {}
    for (dim, res), out in sph_bars.items():
        sc = BiMaterialBar(dim=dim)
        R = float(out["reaction"][0])
        _, bound = linear_bar_reaction(sc, res)
        assert 0 < R < bound * (1 + TOL_RELAXED), (dim, res, R, bound, sc.exact_reaction())
        err[(dim, res)] = R / sc.exact_reaction() - 1
        assert abs(err[(dim, res)]) > sc.H / res / (2 * sc.L), (dim, res, err)
    e = [abs(err[(2, r)]) for r in (2, 4, 8)]
    assert e[0] > e[1] > e[2], err
    order = math.log2(e[1] / e[2])
    assert 0.5 < order < 1.5, f"observed order {order:.2f} ({err})"


# ------------------------------------------------------------------------------------------------
# the 3-D cantilever
# ------------------------------------------------------------------------------------------------

def test_cantilever_3d_against_timoshenko(cantilever):
    """csph at 4 particles across H and B: the 3-D continuum sits 0.9 % below Timoshenko theory
    (the FEM's converged hex27 value: clamp warping restraint and the shear coefficient), and the
    method's second-order error is (Δx/H)²/4 = 1.6 % at H/Δx = 4: 2.5 % in all (measured +0.58 %;
    at 2 across H, +38 %, outside it)."""
    assert abs(tip_error(cantilever[("csph", 4)])) < 0.025
    assert abs(tip_error(cantilever[("csph", 2)])) > 0.025


def pure_bending_energy_error(sc: Cantilever3D, res: int) -> float:
    """Relative error of HPM's stored energy for the exact 3-D pure-bending field of the beam
    (u = (−κxz, νκyz, κ(x² + ν(z² − y²))/2), σ_xx = −Eκz the only stress; energy ½ E I κ² L),
    on the beam's particles at H/Δx = res: the bending-stiffness error of the discretisation
    (WLS gradient at the free faces, trapezoid volumes)."""
    dx = sc.H / res
    X, V = particles.box((0, -sc.B / 2, -sc.H / 2), (sc.L, sc.B / 2, sc.H / 2), dx, "node")
    k, nu = 1e-4, sc.nu
    x, y, z = X.T
    u = np.stack([-k * x * z, nu * k * y * z, 0.5 * k * (x ** 2 + nu * (z ** 2 - y ** 2))], 1)
    e = hpm.potential_energy(hpm.build_model(X, V, sc.material, dx), X + u)
    return e / (0.5 * sc.E * k ** 2 * sc.I * sc.L) - 1


def hpm_tolerance(res: int) -> float:
    """Twice the compliance error 1/(1 + e_b) − 1 of HPM's bending stiffness at ``res``
    (test_hpm_cantilever3d_against_timoshenko)."""
    e_b = pure_bending_energy_error(C3D, res)
    assert e_b < 0
    return 2 * (1 / (1 + e_b) - 1)


def test_hpm_cantilever3d_against_timoshenko(cantilever):
    """Cantilever3D (L/H = 8) through the driver at H/Δx = 2 and 4, static Newton, against
    δ_T = P L³/(3EI) + P L/(κGA).

    HPM's error here is that of its bending stiffness, O(Δx²): the WLS gradient is first order
    in a layer of width ~r_e at the free faces and the trapezoid volumes over-integrate z² by
    2(Δx/H)², both second order in the energy. Hence:

    - the observed order log₂(e₂/e₄) lies in [1.5, 2.5];
    - the Richardson value (4δ₄ − δ₂)/3 removes the Δx² term and must meet δ_T within the beam
      theory's own error for this 3-D body, 2 % (shear is 1.2 % of δ_T, so Cowper's κ and the
      clamp's warping restraint are a fraction of that); an uncancelled discretisation error
      (a wrong limit, another order) fails it;
    - the error at H/Δx = 4 is below twice the compliance error 1/(1 + e_b) − 1 of the exact
      pure-bending field at that spacing (:func:`pure_bending_energy_error`, ≈ 10 %): the free
      faces along the span, and at most as much again at the root, where the same face error
      meets the held layers."""
    err = {res: tip_error(cantilever[("hpm", res)]) for res in (2, 4)}
    richardson = (4 * err[4] - err[2]) / 3
    assert abs(richardson) < 0.02, (
        f"Richardson error {richardson:.3%} (e2 {err[2]:.3%}, e4 {err[4]:.3%})")
    order = math.log2(err[2] / err[4])
    assert 1.5 < order < 2.5, f"observed order {order:.2f}"
    assert 0 < err[4] < hpm_tolerance(4), f"e4 {err[4]:.3%}"


def test_sph_relaxation_reaches_the_linearised_equilibrium_cantilever(cantilever):
    """Classic SPH on the cantilever at 2 across by dynamic relaxation (dead load: kinetic
    damping from rest): the tip probe's deflection within TOL_RELAXED of the directly solved
    linearised equilibrium (the load's nonlinearity, O((δ/L)²) ~ 1e-5, is inside it)."""
    out = cantilever[("sph", 2)]
    ps, _, u, _ = linear_sph(C3D, 2, C3D.loads[0])
    idx, w = ps.probes["tip_centre"]
    ref = -float(w @ u[idx, 2])
    assert abs(out["tip_deflection"][0] / ref - 1) < TOL_RELAXED, (out["tip_deflection"][0], ref)
    assert 0 < out["iterations"][0] < relaxation.MAX_STEPS


# Each method's tolerance on the tip deflection against Timoshenko at this small load, relative:
# fem — the continuum lies between Euler–Bernoulli (−1.2 %: the shear term) and Timoshenko
#   (tests/test_fem_model.py), the 27-node element at 2 across within 1 % of its finest rung:
#   [−2.2 %, 0];
# csph at 4 — 2.5 % (test_cantilever_3d_against_timoshenko);
# hpm at 4 — twice its bending-compliance error, ≈ 22 % (test_hpm_cantilever3d_against_timoshenko);
# sph at 2 — a factor of two either way, because classic SPH with the Eulerian kernel has no
#   consistency in a layer 2h = 2.6 Δx deep at every free face and the clamp, which at 2–8 across
#   is 65–100 % of the section: its error is of order one and not yet monotone in the resolution
#   (the linearised reference, directly solved: −41, +113, +39, +108, +55, +53 % at 2, 3, 4, 5,
#   6, 8 across; odd resolutions, with no particle on the neutral plane, the softer; the root's
#   first free layer zig-zags). It agrees with the others only in that sense.
CANTILEVER_TOLERANCE = {("fem", FEM_ELEMENTS): (-0.022, 0.0), ("csph", 4): (-0.025, 0.025),
                        ("sph", 2): (-0.5, 1.0)}


def test_cantilever_3d_every_method_agrees_with_timoshenko_and_the_others(cantilever):
    """fem, csph, hpm and sph on the same scene: each within its tolerance of Timoshenko
    (CANTILEVER_TOLERANCE), hence each pair within the sum of theirs — checked as well, on the
    deflections themselves."""
    tol = dict(CANTILEVER_TOLERANCE)
    h = hpm_tolerance(4)
    tol[("hpm", 4)] = (-h, h)
    err = {key: tip_error(cantilever[key]) for key in tol}
    for key, (lo, hi) in tol.items():
        assert lo < err[key] < hi, (key, err)
    keys = list(tol)
    for a in keys:
        for b in keys:
            da, db = (float(cantilever[k]["tip_deflection"][0]) for k in (a, b))
            width = (max(-tol[a][0], tol[a][1]) + max(-tol[b][0], tol[b][1]))
            assert abs(da - db) <= width * C3D.timoshenko(C3D.loads[0]), (a, b, err)


@pytest.mark.parametrize("method", ["csph", "sph"])
def test_a_static_path_stops_where_its_caller_says(method):
    """``on_record`` returning true ends a static path there, in Newton's path
    (sph.static.solve_path) and dynamic relaxation's (sph.relaxation.relax_path; classic SPH has
    no gradient form): the later load values are not run (NaN) and carry the status
    workbench.results.STOPPED, not a failure."""
    from workbench.results import STOPPED, path_ok
    from workbench.scenes import Cantilever

    seen = []

    def on_record(body, run, lam):
        seen.append(lam)
        return len(seen) == 1

    sc = Cantilever(loads=(0.2, 0.5, 1.0))
    out = driver.solve(method, sc, 3, on_record=on_record)
    assert out["status"] == ["ok", STOPPED, STOPPED] and all(path_ok(s) for s in out["status"])
    assert len(seen) == 1 and np.isfinite(out["tip_deflection"][0])
    assert np.all(np.isnan(out["tip_deflection"][1:]))
