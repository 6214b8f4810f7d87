"""The material-point kernels checked against independent facts: energies differentiated by finite
differences, central differences of P for the tangents, linear elasticity, frame indifference, the
exact uniaxial-stress solution of Hencky–J2 with Swift hardening, and the yield condition."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from workbench.materials import (HIST_DAMAGE, HIST_EPS_P, RING_RUBBER, TABLE1_STEEL, Material,
                                 evaluate, kernels)

# --- tolerances (relative unless said), each with the reason for its size --------------------
TOL_ROUND = 1e-12     # identities that hold up to round-off of a few dozen flops
TOL_ROUND_J2 = 1e-10  # the same through an eigen-solve, log and exp (κ of the logs ~ 1e2)
TOL_FD = 1e-6         # central differences: truncation O(h²) ~ 1e-12, round-off O(eps/h) ~ 1e-9
TOL_ENERGY_FD = 1e-7  # P vs central differences of ψ: round-off eps·ψ/h ~ 1e-9 of |P|
TOL_SMALL = 1e-4      # linearisation at δ = 1e-6: the neglected terms are O(δ · λ/μ) ≲ 1e-4
TOL_YIELD = 1e-8      # the local Newton stops at |r| ≤ 1e-12 σ_y; 1e-8 leaves round-off room
TOL_UNIAXIAL = 1e-6   # backward Euler is exact on this radial path; 1e-6 as the brief asks
TOL_LATERAL = 1e-8    # τ22 = τ33 = 0 exactly for the exact lateral strain: round-off of τ11 only

SVK = Material.svk(E=1.0e5, nu=0.3)
NEO = Material.neo_hooke(E=2.0e5, nu=0.45)
MR = RING_RUBBER
J2 = TABLE1_STEEL
ELASTIC = {"svk": SVK, "neo_hooke": NEO, "mooney_rivlin": MR}
ALL = dict(ELASTIC, j2=J2)


# --- helpers ---------------------------------------------------------------------------------
def stress(mat, F, h=None):
    """P, h_new, status at a batch of F (or one F) through material_points."""
    F = np.ascontiguousarray(np.asarray(F, dtype=float).reshape(-1, 3, 3))
    if h is None:
        h = mat.initial_history(len(F))
    # a writeable copy: a read-only array is another numba type, i.e. another compilation
    h = np.array(np.broadcast_to(np.asarray(h, dtype=float), (len(F), mat.n_history)))
    return kernels.material_points(F, h, mat.params()[None], np.zeros(len(F), np.int64))


def tangent(mat, F, h=None):
    F = np.ascontiguousarray(np.asarray(F, dtype=float).reshape(1, 3, 3))
    if h is None:
        h = mat.initial_history(1)
    h = np.ascontiguousarray(np.asarray(h, dtype=float).reshape(1, mat.n_history))
    P, A, hn, st = kernels.material_points_tangent(F, h, mat.params()[None], np.zeros(1, np.int64))
    assert st[0] == 0
    return A[0]


def fd_tangent(mat, F, h, step):
    """Central differences of P over the nine components of F (one batch of 18 points)."""
    Fs = np.repeat(F[None], 18, axis=0)
    for m, (k, l) in enumerate(np.ndindex(3, 3)):
        Fs[2 * m, k, l] += step
        Fs[2 * m + 1, k, l] -= step
    P, _, st = stress(mat, Fs, h)
    assert np.all(st == 0)
    A = np.empty((3, 3, 3, 3))
    for m, (k, l) in enumerate(np.ndindex(3, 3)):
        A[:, :, k, l] = (P[2 * m] - P[2 * m + 1]) / (2 * step)
    return A


def rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


def random_F(seed, amp):
    G = np.random.default_rng(seed).standard_normal((3, 3))
    F = np.eye(3) + amp * G
    assert np.linalg.det(F) > 0
    return F


def random_rotation(seed):
    Q, R = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else -Q


def kirchhoff(P, F):
    return P @ F.T


def mises(tau):
    s = tau - np.trace(tau) / 3 * np.eye(3)
    return math.sqrt(1.5 * np.sum(s * s))


def swift(mat, eps_p):
    return mat.C * (eps_p + mat.eps0) ** mat.n


def drive(mat, Fs, h0=None):
    """Step the material point along the path Fs, feeding back the history; lists of P, h."""
    h = mat.initial_history(1)[0] if h0 is None else h0
    Ps, hs = [], [h]
    for F in Fs:
        P, hn, st = stress(mat, F, h)
        assert st[0] == 0
        h = hn[0]
        Ps.append(P[0])
        hs.append(h)
    return Ps, hs


def plastic_path(seed, n=4, amp=0.05):
    G = np.random.default_rng(seed).standard_normal((3, 3))
    return [np.eye(3) + amp * (k + 1) / n * G for k in range(n)]


def uniaxial_reference(mat, eps):
    """Exact uniaxial Kirchhoff stress of Hencky–J2 with Swift hardening at total log strain eps:
    τ = E ε_e, ε = ε_e + ε_p, τ = C (ε_p + ε0)^n once yielded; lateral ε_lat = −ν ε_e − ε_p/2."""
    if mat.E * eps <= swift(mat, 0.0):
        ep = 0.0
    else:
        ep = brentq(lambda e: mat.E * (eps - e) - swift(mat, e), 0.0, eps, xtol=1e-16, rtol=1e-15)
    ee = eps - ep
    return mat.E * ee, ep, -mat.nu * ee - ep / 2


def uniaxial_F(mat, eps):
    _, _, lat = uniaxial_reference(mat, eps)
    return np.diag([math.exp(eps), math.exp(lat), math.exp(lat)])


# Energies written straight from the laws' definitions (independent of the kernels' P formulas).
def energy(mat, F):
    C = F.T @ F
    J = np.linalg.det(F)
    if mat.law == "svk":
        E = 0.5 * (C - np.eye(3))
        return 0.5 * mat.lam * np.trace(E) ** 2 + mat.mu * np.sum(E * E)
    if mat.law == "neo_hooke":
        return 0.5 * mat.mu * (np.trace(C) - 3) - mat.mu * math.log(J) + 0.5 * mat.lam * math.log(J) ** 2
    if mat.law == "mooney_rivlin":  # 004 eq. 12
        I1 = np.trace(C)
        I2 = 0.5 * (I1 ** 2 - np.trace(C @ C))
        I3 = np.linalg.det(C)
        c1, c2, lam = mat.c1, mat.c2, mat.lam_mr
        return (0.5 * c1 * I1 + 0.5 * c2 * I2
                - (1.5 * c1 * I3 ** (1 / 3) + 1.5 * c2 * I3 ** (2 / 3) - lam / 4 * math.log(I3) ** 2))
    if mat.law == "j2":  # Hencky, from a virgin state: ε = ½ ln(F Fᵀ)
        w, V = np.linalg.eigh(F @ F.T)
        e = 0.5 * np.log(w)
        return 0.5 * mat.lam * e.sum() ** 2 + mat.mu * np.sum(e * e)
    raise AssertionError(mat.law)


# --- tests -----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(ALL))
def test_zero_stress_at_identity(name):
    mat = ALL[name]
    P, h, st = stress(mat, np.eye(3))
    assert st[0] == 0
    # exact 0 up to round-off of the terms that cancel (for eq. 12: c1 + 3c2 − c2 − c1 − 2c2)
    assert np.max(np.abs(P)) <= TOL_ROUND * mat.mu, P
    if name == "j2":
        assert np.array_equal(h[0], mat.initial_history(1)[0])


@pytest.mark.parametrize("name", list(ALL))
def test_stress_is_derivative_of_energy(name):
    mat = ALL[name]
    F = random_F(1, 5e-4 if name == "j2" else 0.25)  # j2: stays below yield (elastic step)
    P, h, st = stress(mat, F)
    dpsi = np.empty((3, 3))
    step = 1e-6
    for k, l in np.ndindex(3, 3):
        Fp, Fm = F.copy(), F.copy()
        Fp[k, l] += step
        Fm[k, l] -= step
        dpsi[k, l] = (energy(mat, Fp) - energy(mat, Fm)) / (2 * step)
    if name == "j2":
        assert mises(kirchhoff(P[0], F)) < mat.sigma_y0  # really an elastic state
    assert rel(P[0], dpsi) < TOL_ENERGY_FD, rel(P[0], dpsi)


@pytest.mark.parametrize("name", list(ALL))
def test_small_strain_limit_is_linear_elasticity(name):
    mat = ALL[name]
    d = 1e-6
    G = np.random.default_rng(2).standard_normal((3, 3))
    F = np.eye(3) + d * G
    eps = 0.5 * d * (G + G.T)
    sig = mat.lam * np.trace(eps) * np.eye(3) + 2 * mat.mu * eps
    P, _, _ = stress(mat, F)
    assert rel(P[0], sig) < TOL_SMALL, rel(P[0], sig)
    # and the tangent at F = I is the isotropic elasticity tensor exactly
    I = np.eye(3)
    Cel = (mat.lam * np.einsum("ij,kl->ijkl", I, I)
           + mat.mu * (np.einsum("ik,jl->ijkl", I, I) + np.einsum("il,jk->ijkl", I, I)))
    A = tangent(mat, np.eye(3))
    assert rel(A, Cel) < TOL_ROUND, rel(A, Cel)


def test_mooney_rivlin_moduli_from_eq12():
    # linearising eq. 12 by hand: μ = c1 + c2, K = 2λ (pure dilation gives ψ = λ (ln J)²)
    mu = MR.c1 + MR.c2
    K = 2 * MR.lam_mr
    assert MR.mu == pytest.approx(mu, rel=TOL_ROUND)
    assert MR.K == pytest.approx(K, rel=TOL_ROUND)
    # and the kernel's response to a pure dilation J = 1 + δ: p = τ_ii/3 ≈ K δ
    dlt = 1e-7
    P, _, _ = stress(MR, (1 + dlt) ** (1 / 3) * np.eye(3))
    p = np.trace(P[0]) / 3 * (1 + dlt) ** (1 / 3)
    assert p == pytest.approx(K * dlt, rel=1e-5)  # O(δ) nonlinearity


@pytest.mark.parametrize("name", list(ELASTIC))
def test_elastic_tangent_is_finite_difference_of_P(name):
    mat = ELASTIC[name]
    F = random_F(3, 0.3)
    A = tangent(mat, F)
    Afd = fd_tangent(mat, F, None, 1e-6)
    assert rel(A, Afd) < TOL_FD, rel(A, Afd)


@pytest.mark.parametrize("name", list(ALL))
def test_hyperelastic_tangent_is_major_symmetric(name):
    mat = ALL[name]
    F = random_F(4, 5e-4 if name == "j2" else 0.3)  # j2: an elastic step (Hencky is hyperelastic)
    A = tangent(mat, F)
    if name == "j2":
        assert stress(mat, F)[1][0, HIST_EPS_P] == 0.0
    assert rel(A, A.transpose(2, 3, 0, 1)) < TOL_ROUND, rel(A, A.transpose(2, 3, 0, 1))


def j2_states():
    """(label, F, h_old) of the step whose tangent is checked."""
    out = [("elastic", random_F(5, 1e-4), J2.initial_history(1)[0])]
    path = plastic_path(6)
    _, hs = drive(J2, path[:-1])
    out.append(("plastic", path[-1], hs[-1]))
    # uniaxial: be_tr has a repeated eigenvalue, first from a virgin state, then mid-hardening
    out.append(("uniaxial_first", uniaxial_F(J2, 0.01), J2.initial_history(1)[0]))
    _, hs = drive(J2, [uniaxial_F(J2, e) for e in (0.01, 0.02, 0.03, 0.04)])
    out.append(("uniaxial", uniaxial_F(J2, 0.05), hs[-1]))
    # rotated uniaxial state: same repeated eigenvalue, non-diagonal F
    R = random_rotation(7)
    out.append(("uniaxial_rotated", R @ uniaxial_F(J2, 0.05), hs[-1]))
    return out


@pytest.mark.parametrize("label,F,h", j2_states(), ids=lambda v: v if isinstance(v, str) else "")
def test_j2_tangent_is_finite_difference_of_P(label, F, h):
    A = tangent(J2, F, h)
    Afd = fd_tangent(J2, F, h, 1e-6)
    assert rel(A, Afd) < TOL_FD, rel(A, Afd)
    _, hn, _ = stress(J2, F, h)
    plastic = hn[0, HIST_EPS_P] > h[HIST_EPS_P]
    assert plastic == (label != "elastic")
    if plastic:  # the plastic tangent is far from the elastic one: this test sees the difference
        assert rel(A, tangent(J2, F, hn[0])) > 0.1


@pytest.mark.parametrize("name", list(ALL))
def test_objectivity(name):
    mat = ALL[name]
    R = random_rotation(8)
    path = plastic_path(9) if name == "j2" else [random_F(9, 0.3)]
    Ps, hs = drive(mat, path)
    Pr, hr = drive(mat, [R @ F for F in path])
    tol = TOL_ROUND_J2 if name == "j2" else TOL_ROUND
    for a, b in zip(Pr, Ps):
        assert rel(a, R @ b) < tol, rel(a, R @ b)
    if name == "j2":
        assert hs[-1][HIST_EPS_P] > 0.01  # a plastic state was reached
        assert hr[-1][HIST_EPS_P] == pytest.approx(hs[-1][HIST_EPS_P], rel=tol)
        assert rel(hr[-1][:9], hs[-1][:9]) < tol  # Cp⁻¹ is a reference-configuration tensor


def test_stress_on_yield_surface_after_every_plastic_step():
    # a non-proportional path: stretch, then shear on top, then partly back
    rng = np.random.default_rng(10)
    G1, G2 = rng.standard_normal((2, 3, 3))
    path = ([np.eye(3) + 0.02 * k * G1 for k in range(1, 6)]
            + [np.eye(3) + 0.1 * G1 + 0.03 * k * G2 for k in range(1, 6)]
            + [np.eye(3) + 0.1 * G1 + (0.15 - 0.01 * k) * G2 for k in range(1, 4)])
    Ps, hs = drive(J2, path)
    n_plastic = 0
    for F, P, h_old, h in zip(path, Ps, hs[:-1], hs[1:]):
        q = mises(kirchhoff(P, F))
        sy = swift(J2, h[HIST_EPS_P])
        if h[HIST_EPS_P] > h_old[HIST_EPS_P]:
            n_plastic += 1
            assert q == pytest.approx(sy, rel=TOL_YIELD)
        else:
            assert q <= sy * (1 + TOL_YIELD)
    assert n_plastic >= 8


def test_exact_uniaxial_curve():
    strains = np.linspace(0.01, 0.3, 30)
    Fs = [uniaxial_F(J2, e) for e in strains]
    Ps, hs = drive(J2, Fs)
    for e, F, P, h in zip(strains, Fs, Ps, hs[1:]):
        tau_ref, ep_ref, _ = uniaxial_reference(J2, e)
        tau = kirchhoff(P, F)
        assert tau[0, 0] == pytest.approx(tau_ref, rel=TOL_UNIAXIAL)
        assert h[HIST_EPS_P] == pytest.approx(ep_ref, rel=TOL_UNIAXIAL)
        assert abs(tau[1, 1]) < TOL_LATERAL * tau_ref and abs(tau[2, 2]) < TOL_LATERAL * tau_ref
        assert np.max(np.abs(tau - np.diag(np.diag(tau)))) == 0.0  # diagonal F, diagonal τ
        assert mises(tau) == pytest.approx(swift(J2, h[HIST_EPS_P]), rel=TOL_YIELD)
    assert hs[-1][HIST_EPS_P] > 0.28


def test_damage_zeroes_stress_once_eps_p_reaches_eps_L():
    epsL = 0.05
    dam = J2.replace(eps_L=epsL, failure="literal")  # the rule as printed (more in test_materials_j2)
    Fs = [uniaxial_F(J2, e) for e in np.linspace(0.01, 0.15, 15)]
    Pd, hd = drive(dam, Fs)
    Pu, hu = drive(J2, Fs)
    n_failed = 0
    for F, P, Pref, h in zip(Fs, Pd, Pu, hd[1:]):
        if h[HIST_EPS_P] >= epsL:
            n_failed += 1
            assert np.all(P == 0.0)
            assert np.all(tangent(dam, F, h) == 0.0)  # further steps: zero stress and tangent
            assert h[HIST_DAMAGE] >= 1.0
        else:
            assert np.array_equal(P, Pref)  # D < 1 does not soften (000 eq. 36 is a switch)
            assert h[HIST_DAMAGE] == pytest.approx(h[HIST_EPS_P] / epsL, rel=TOL_ROUND)
    assert 5 <= n_failed < len(Fs)  # failure happened mid-path, not at the start
    assert np.all(hu[-1][HIST_DAMAGE] == 0.0)  # ε_L = inf: no damage


@pytest.mark.parametrize("name", list(ALL))
def test_inverted_point_reports_status_2(name):
    mat = ALL[name]
    F = np.diag([1.0, 1.0, -0.5])
    P, h, st = stress(mat, F)
    assert st[0] == kernels.INVERTED and np.all(np.isnan(P))
    if name == "j2":
        assert np.array_equal(h[0], mat.initial_history(1)[0])


def test_eigen_solver():
    rng = np.random.default_rng(11)
    R = random_rotation(12)
    mats = [rng.standard_normal((3, 3)) for _ in range(20)]
    mats = [m + m.T for m in mats] + [R @ np.diag([1.0, 2.0, 2.0]) @ R.T, np.eye(3),
                                      np.diag([1.0, 1.0 + 1e-15, 3.0]) + 1e-200 * np.ones((3, 3))]
    for S in mats:
        a = S.copy()
        V = np.empty((3, 3))
        assert kernels.eig_sym3_closed(a, V) == 0  # the closed form (more in test_materials_eigen)
        x = np.diag(a)
        scale = np.max(np.abs(S))
        assert np.max(np.abs(V @ np.diag(x) @ V.T - S)) < 1e-14 * scale * 10
        assert np.max(np.abs(V.T @ V - np.eye(3))) < 1e-14
        assert np.sort(x) == pytest.approx(np.linalg.eigvalsh(S), abs=1e-14 * scale * 10)


@pytest.mark.parametrize("name", list(ALL))
def test_batch_point_and_evaluate_agree(name):
    mat = ALL[name]
    N = 5
    F = np.stack([random_F(20 + n, 5e-4 if name == "j2" else 0.2) for n in range(N)])
    F[-1] = np.eye(3) + 0.05 * np.random.default_rng(30).standard_normal((3, 3))
    h = mat.initial_history(N)
    P, hn, st = stress(mat, F, h)
    Pt, A, ht, stt = kernels.material_points_tangent(F, h, mat.params()[None], np.zeros(N, np.int64))
    assert np.array_equal(P, Pt) and np.array_equal(hn, ht) and np.array_equal(st, stt)
    prm = mat.params()
    for n in range(N):  # the one-point entry used by other numba code
        P1 = np.empty((3, 3))
        h1 = np.empty(mat.n_history)
        A1 = np.empty((3, 3, 3, 3))
        s1 = kernels.material_point(F[n], h[n], prm, P1, h1, A1, True)
        assert s1 == st[n] and np.array_equal(P1, P[n]) and np.array_equal(A1, A[n])
        assert np.array_equal(h1, hn[n])
    r = evaluate(mat, F, tangent=True, stress="tau")
    assert rel(r["stress"], P @ F.transpose(0, 2, 1)) < TOL_ROUND
    assert r["A"].shape == (N, 3, 3, 3, 3) and r["history"].shape == (N, mat.n_history)
    r1 = evaluate(mat, F[0], stress="sigma")
    assert rel(r1["stress"], P[0] @ F[0].T / np.linalg.det(F[0])) < TOL_ROUND


def test_material_table_rows_match_each_material_alone():
    """A body of several materials (a region index per point into the parameter table) gives each
    point exactly the stress of its own material evaluated alone, history columns included."""
    from workbench.materials import MaterialTable, evaluate

    table = MaterialTable((SVK, J2, NEO))
    rng = np.random.default_rng(7)
    mat_id = rng.integers(0, 3, 12)
    F = np.stack([random_F(40 + n, 5e-4 if mat_id[n] == 1 else 0.1) for n in range(12)])
    r = evaluate(table, F, mat_id=mat_id, tangent=True)
    assert r["history"].shape == (12, J2.n_history)
    for n in range(12):
        alone = evaluate(table[mat_id[n]], F[n], tangent=True)
        assert np.array_equal(r["stress"][n], alone["stress"])
        assert np.array_equal(r["A"][n], alone["A"])
    assert np.all(r["history"][mat_id != 1] == 0.0)  # elastic points keep their (unused) columns


def test_parameter_layout():
    """Slots of ``Material.params()`` (package docstring): the small-strain moduli from E and ν by
    the textbook formulas, Swift constants, and the J2 kinds in slots 10 and 11."""
    from workbench.materials import N_PARAMS

    assert N_PARAMS == 12
    E, nu = 202e9, 0.3
    p = Material.j2(E=E, nu=nu, C=868.8e6, eps0=0.0013, n=0.179).params()
    assert p.shape == (N_PARAMS,) and p[0] == 3
    assert p[1] == pytest.approx(E * nu / ((1 + nu) * (1 - 2 * nu)), rel=TOL_ROUND)
    assert p[2] == pytest.approx(E / (2 * (1 + nu)), rel=TOL_ROUND)
    assert tuple(p[3:6]) == (868.8e6, 0.0013, 0.179) and p[6] == math.inf
    assert p[7] == pytest.approx(868.8e6 * 0.0013 ** 0.179, rel=TOL_ROUND)  # σ_y(0) for law 3
    assert p[10] == 0  # Swift hardening
    for name, mat in ELASTIC.items():
        assert mat.params().shape == (N_PARAMS,)
    with pytest.raises(ValueError, match="prm"):  # a table of the wrong width is refused
        kernels.material_points(np.eye(3)[None].copy(), np.zeros((1, 0)), SVK.params()[None, :10].copy(),
                                np.zeros(1, np.int64))


def test_return_map_meets_its_tolerance_after_every_plastic_step():
    """The local Newton may stop on an a-priori bound of its residual (j2.j2_return_map);
    the stress it returns must then satisfy the yield condition to the Newton tolerance
    prm[9] = 1e-12 (relative), plus the round-off of recomputing q from P in numpy
    (≈ 10 eps of the largest |τ_ij|, the pressure included)."""
    rng = np.random.default_rng(21)
    n_plastic = 0
    for trial in range(60):
        G = rng.standard_normal((3, 3))
        G /= np.linalg.norm(G)
        steps = rng.choice([1e-4, 1e-3, 1e-2, 5e-2])
        path = [np.eye(3) + steps * k * G for k in range(1, 6)]
        Ps, hs = drive(J2, path)
        for F, P, h_old, h in zip(path, Ps, hs[:-1], hs[1:]):
            if h[HIST_EPS_P] > h_old[HIST_EPS_P]:
                n_plastic += 1
                tau = kirchhoff(P, F)
                sy = swift(J2, h[HIST_EPS_P])
                bound = J2.tol * sy + 10 * np.finfo(float).eps * np.max(np.abs(tau))
                assert abs(mises(tau) - sy) <= bound, (abs(mises(tau) - sy) / sy, steps)
    assert n_plastic > 150
