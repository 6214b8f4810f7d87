"""Per-element materials (a MaterialTable and a material id per element): a bi-material bar in
series against its exact finite-strain solution, the one-row table against a plain Material, and
the consistent mass and body force with a density per element.

The bar: 0 ≤ X ≤ L = 2, material 0 (E₀) for X < 1, material 1 (E₁ = E₀/4) for X > 1, the same ν;
u_X = 0 on X = 0, a dead axial traction t (nominal, per reference area) on X = L, and rollers on
every lateral face (u_Y = 0 on Y = ±H/2; in 3-D also u_Z = 0 on Z = ±H/2). Each region is then
homogeneous with F = diag(λ_k, 1, F33) — F33 = 1 in 3-D and plane strain, and P33 = 0 solved for
F33 in plane stress — and P₁₁ = t in both (equilibrium). The displacement u_X(X) is piecewise
linear with its kink on an element boundary and u_Y = u_Z = 0: the exact solution lies in the
finite-element space, so the FEM must reproduce it to the solver tolerance. Closed forms (the
stretch λ_k of region k from P₁₁(λ_k) = t, solved to round-off):

- Saint Venant–Kirchhoff, 3-D or plane strain (uniaxial strain): P₁₁ = M λ (λ² − 1)/2 with the
  constrained modulus M = λ_L + 2μ = E(1 − ν)/((1 + ν)(1 − 2ν)).
- Saint Venant–Kirchhoff, plane stress (roller in Y, free in Z): S₃₃ = 0 gives
  E₃₃ = −λ_L E₁₁/(λ_L + 2μ), so P₁₁ = M' λ (λ² − 1)/2 with M' = E/(1 − ν²).
- compressible neo-Hooke, uniaxial strain (J = λ): P₁₁ = μ (λ − 1/λ) + λ_L ln(λ)/λ.

u_X(L) = L₀(λ₀ − 1) + L₁(λ₁ − 1); the tolerance is the Newton tolerance 1e-12 (relative
residual) carried to the displacement, plus round-off: 1e-9 relative.
"""
import numpy as np
import pytest
from scipy.optimize import brentq

from fem_reference.assembly import Discretisation
from fem_reference.boundary import Constraints, Loads
from fem_reference.mesh import box
from fem_reference.static import Problem, load_path
from workbench.materials import Material, MaterialTable

L, L0, HH = 2.0, 1.0, 0.5
E0, NU = 2.0e9, 0.3
TOL_EXACT = 1e-9


def stretch(mat: Material, t: float, plane) -> float:
    """λ with P₁₁(λ) = t (module docstring), to round-off."""
    lam_l, mu = mat.lam, mat.mu
    if mat.law == "svk":
        M = mat.E / (1 - mat.nu ** 2) if plane == "stress" else lam_l + 2 * mu
        f = lambda s: M * s * (s * s - 1) / 2 - t  # noqa: E731
    elif mat.law == "neo_hooke" and plane != "stress":
        f = lambda s: mu * (s - 1 / s) + lam_l * np.log(s) / s - t  # noqa: E731
    else:
        raise NotImplementedError
    return brentq(f, 0.6, 2.0, xtol=1e-16, rtol=1e-15)


def bar(d: int, order: int | None, law: str, plane, t: float, n_along: int = 4):
    lo, hi = (0.0,) + (-HH / 2,) * (d - 1), (L,) + (HH / 2,) * (d - 1)
    disc = Discretisation(box(lo, hi, (n_along,) + (1,) * (d - 1)), order=order)
    mats = MaterialTable(tuple(getattr(Material, law)(E=e, nu=NU) for e in (E0, E0 / 4)))
    mat_id = (disc.centroids()[:, 0] > L0).astype(np.int64)
    tol = 1e-9
    bc = Constraints(disc)
    bc.roller(lambda x: x[0] < tol, 0)
    for k in range(1, d):
        bc.roller(lambda x, k=k: np.abs(x[k]) > HH / 2 - tol, k)
    bc.apply()
    loads = Loads(disc)
    loads.traction(lambda x: x[0] > L - tol, np.eye(d)[0] * t)
    problem = Problem(disc, mats, plane, bc.values, loads, mat_id=mat_id)
    return problem, mats


CASES = [  # (d, element order, law, plane)
    (2, None, "svk", "strain"),
    (2, None, "svk", "stress"),
    (3, 1, "svk", None),
    (3, 2, "svk", None),
    (3, 2, "neo_hooke", None),
]


@pytest.mark.parametrize("d,order,law,plane", CASES,
                         ids=["q9-strain", "q9-stress", "hex8", "hex27", "hex27-neohooke"])
def test_bimaterial_bar_is_exact(d, order, law, plane):
    # a finite strain: 5 % stretch of the soft region
    soft = getattr(Material, law)(E=E0 / 4, nu=NU)
    t = 0.05 * soft.E
    problem, mats = bar(d, order, law, plane, t)
    _, state = load_path(problem, [1.0], max_increment=0.5, rtol=1e-12)
    lam = [stretch(m, t, plane) for m in mats.materials]
    X = problem.disc.basis.doflocs
    comp = np.arange(problem.disc.N) % d
    ux = np.where(X[0] < L0, X[0] * (lam[0] - 1), L0 * (lam[0] - 1) + (X[0] - L0) * (lam[1] - 1))
    exact = np.where(comp == 0, ux, 0.0)
    scale = L0 * (lam[0] - 1) + (L - L0) * (lam[1] - 1)
    err = np.abs(state.u - exact).max() / scale
    assert err < TOL_EXACT, f"max nodal error / tip displacement = {err:.2e}"
    # the stiff and the soft region really differ (the test sees the material ids)
    assert (lam[1] - 1) / (lam[0] - 1) > 3.5


def test_one_row_table_is_the_material():
    """A Material and MaterialTable((Material,)) give the same run bit for bit."""
    mat = Material.svk(E=E0, nu=NU)
    out = []
    for m in (mat, MaterialTable((mat,))):
        problem, _ = bar(2, None, "svk", "strain", 0.01 * E0)
        problem = Problem(problem.disc, m, "strain", problem.fixed_values, problem.f_ext)
        _, state = load_path(problem, [1.0], rtol=1e-12)
        out.append(state.u)
    assert np.array_equal(out[0], out[1])


def test_bad_material_ids_are_refused():
    problem, mats = bar(2, None, "svk", "strain", 1.0)
    disc = problem.disc
    with pytest.raises(ValueError, match="mat_id"):
        Problem(disc, mats, "strain", problem.fixed_values, problem.f_ext,
                mat_id=np.full(disc.nel, 2))
    with pytest.raises(ValueError, match="mat_id"):
        Problem(disc, mats, "strain", problem.fixed_values, problem.f_ext,
                mat_id=np.zeros(disc.nel + 1, dtype=int))


# The vectorised mass against scikit-fem's form: the same integrals, round-off only.
TOL_SAME = 1e-12


@pytest.mark.parametrize("d,order", [(2, None), (3, 1), (3, 2)], ids=["q9", "hex8", "hex27"])
def test_mass_and_body_force_per_element(d, order):
    lo, hi = (0.0,) * d, (2.0,) + (1.0,) * (d - 1)
    disc = Discretisation(box(lo, hi, (4,) + (2,) * (d - 1)), order=order)
    M = disc.mass(7.0)
    ref = disc.skfem_mass(7.0)
    assert abs(M - ref).max() <= TOL_SAME * abs(ref).max()
    # a density per element: the total mass of each component is Σ ρ_e V_e (the constant field
    # u = e_i is in the space: 1ᵀ M_ii 1 = ∫ ρ), and the body force sums to Σ ρ_e V_e g
    rho = np.where(disc.centroids()[:, 0] < 1.0, 1000.0, 7800.0)
    m_exact = 1000.0 * 1.0 * 1.0 + 7800.0 * 1.0 * 1.0  # volumes 1 and 1 (the box is 2 × 1 (× 1))
    M = disc.mass(rho)
    e0 = (np.arange(disc.N) % d == 0).astype(float)
    assert e0 @ (M @ e0) == pytest.approx(m_exact, rel=1e-13)
    g = np.arange(1, d + 1, dtype=float)
    f = disc.body_load(rho, g)
    total = np.array([f[i::d].sum() for i in range(d)])
    assert np.allclose(total, m_exact * g, rtol=1e-13)
