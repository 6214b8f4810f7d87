"""J2 features beyond the Swift law of test_materials: linear hardening (the bilinear steel of paper
003), the failure rules once D = ε_p/ε_L ≥ 1 (paper 000 eq. 36), and the energies per point — each
against a closed form or central differences."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from test_materials import (TOL_FD, TOL_LATERAL, TOL_ROUND, TOL_UNIAXIAL, TOL_YIELD, drive,
                            fd_tangent, kirchhoff, mises, random_rotation, rel, stress, tangent)
from workbench.materials import (HIST_EPS_P, REBAR_003, Material, linear_hardening_modulus)

E_STEEL = 206e9
LIN = Material.j2_linear(E=E_STEEL, nu=0.3, sigma_y0=394e6, H=E_STEEL / 99)


# --- linear hardening --------------------------------------------------------------------------
def linear_uniaxial(mat, eps):
    """Exact uniaxial Kirchhoff stress of Hencky–J2 with σ_y = σ_y0 + H ε_p at log strain eps:
    elastic τ = E ε up to σ_y0; then τ = E (ε − ε_p) = σ_y0 + H ε_p, ε_p = (E ε − σ_y0)/(E + H).
    Lateral log strain −ν ε_e − ε_p/2 (plastic incompressibility)."""
    ep = max(0.0, (mat.E * eps - mat.sy0) / (mat.E + mat.H))
    ee = eps - ep
    return mat.E * ee, ep, -mat.nu * ee - ep / 2


def linear_uniaxial_F(mat, eps):
    _, _, lat = linear_uniaxial(mat, eps)
    return np.diag([math.exp(eps), math.exp(lat), math.exp(lat)])


def test_linear_hardening_modulus_from_the_post_yield_slope():
    # E_t = E/100 of paper 003 Fig. 14: H = E E_t/(E − E_t) = E/99, by hand
    assert linear_hardening_modulus(E_STEEL, E_STEEL / 100) == pytest.approx(E_STEEL / 99, rel=TOL_ROUND)
    assert REBAR_003.H == pytest.approx(E_STEEL / 99, rel=TOL_ROUND)
    assert REBAR_003.sigma_y0 == 394e6 and REBAR_003.E == E_STEEL and REBAR_003.nu == 0.3
    assert linear_hardening_modulus(E_STEEL, 0.0) == 0.0  # perfect plasticity
    p = LIN.params()  # layout (package docstring): σ_y0, H in slots 3, 4; σ_y(0) in 7; kind 1 in 10
    assert (p[3], p[4], p[5], p[7], p[10]) == (394e6, E_STEEL / 99, 0.0, 394e6, 1.0)
    with pytest.raises(ValueError, match="E_t"):
        linear_hardening_modulus(E_STEEL, E_STEEL)
    with pytest.raises(ValueError, match="H"):
        Material.j2_linear(E=E_STEEL, nu=0.3, sigma_y0=394e6, H=-1.0)
    with pytest.raises(ValueError, match="sigma_y0"):
        Material.j2_linear(E=E_STEEL, nu=0.3, sigma_y0=0.0, H=1e9)


def test_linear_exact_uniaxial_curve_and_post_yield_slope():
    strains = np.concatenate([np.linspace(5e-4, 0.004, 8), np.linspace(0.005, 0.2, 40)])
    Fs = [linear_uniaxial_F(LIN, e) for e in strains]
    Ps, hs = drive(LIN, Fs)
    taus = []
    for e, F, P, h in zip(strains, Fs, Ps, hs[1:]):
        tau_ref, ep_ref, _ = linear_uniaxial(LIN, e)
        tau = kirchhoff(P, F)
        taus.append(tau[0, 0])
        assert tau[0, 0] == pytest.approx(tau_ref, rel=TOL_UNIAXIAL)
        assert h[HIST_EPS_P] == pytest.approx(ep_ref, rel=TOL_UNIAXIAL, abs=1e-15)
        assert abs(tau[1, 1]) < TOL_LATERAL * tau_ref and abs(tau[2, 2]) < TOL_LATERAL * tau_ref
        assert mises(tau) <= (LIN.sy0 + LIN.H * h[HIST_EPS_P]) * (1 + TOL_YIELD)
    # the slope of τ against the log strain past yield is E_t = E H/(E + H) = E/100 exactly
    taus = np.array(taus)
    plastic = strains > LIN.sy0 / LIN.E
    slope = np.diff(taus[plastic]) / np.diff(strains[plastic])
    # τ carries round-off only (one exact Newton step, logs and exps: ≲ 1e-13); the differences
    # over Δε = 0.005 amplify it by τ/Δτ ≈ 60: 1e-9 is far above that and far below any error
    assert np.max(np.abs(slope / (E_STEEL / 100) - 1)) < 1e-9
    assert hs[-1][HIST_EPS_P] > 0.19


def linear_states():
    out = [("plastic_first", linear_uniaxial_F(LIN, 0.004), LIN.initial_history(1)[0])]
    _, hs = drive(LIN, [linear_uniaxial_F(LIN, e) for e in (0.004, 0.01, 0.02)])
    out.append(("uniaxial_rotated", random_rotation(31) @ linear_uniaxial_F(LIN, 0.03), hs[-1]))
    G = np.random.default_rng(32).standard_normal((3, 3))
    path = [np.eye(3) + 0.01 * k * G for k in range(1, 5)]
    _, hs = drive(LIN, path[:-1])
    out.append(("general", path[-1], hs[-1]))
    return out


@pytest.mark.parametrize("label,F,h", linear_states(), ids=lambda v: v if isinstance(v, str) else "")
def test_linear_tangent_is_finite_difference_of_P(label, F, h):
    A = tangent(LIN, F, h)
    Afd = fd_tangent(LIN, F, h, 1e-6)
    assert rel(A, Afd) < TOL_FD, rel(A, Afd)
    _, hn, _ = stress(LIN, F, h)
    assert hn[0, HIST_EPS_P] > h[HIST_EPS_P]  # a plastic step


# --- failure rules (paper 000 eq. 36) ----------------------------------------------------------
from test_materials import J2, uniaxial_reference  # noqa: E402  (Table 1 steel, Swift)

EPS_L = 0.05


def uniaxial_signed(mat, eps):
    """The exact uniaxial solution at log strain eps of either sign (the problem is odd in ε):
    τ11, ε_p, lateral log strain."""
    tau, ep, lat = uniaxial_reference(mat, abs(eps))
    s = 1.0 if eps >= 0 else -1.0
    return s * tau, ep, s * lat


def signed_F(mat, eps):
    _, _, lat = uniaxial_signed(mat, eps)
    return np.diag([math.exp(eps), math.exp(lat), math.exp(lat)])


def failure_path(sign):
    """Uniaxial loading (sign +1 tension, −1 compression) in steps of 0.01 to 0.12 (failure at
    ε_p = 0.05 on the way), then the axial strain driven back through 0 to the opposite sign with
    the lateral stretch frozen at its last value."""
    strains = sign * np.linspace(0.01, 0.12, 12)
    Fs = [signed_F(J2, e) for e in strains]
    lat = Fs[-1][1, 1]
    back = sign * np.linspace(0.1, -0.1, 11)
    Fs += [np.diag([math.exp(e), lat, lat]) for e in back]
    return Fs


@pytest.mark.parametrize("sign", [1, -1], ids=["tension", "compression"])
@pytest.mark.parametrize("rule", ["literal", "compression"])
def test_failure_rule_on_a_uniaxial_path(rule, sign):
    """Before failure the exact uniaxial curve; from the step in which ε_p reaches ε_L on: P = 0
    (literal), or τ = K ln J I where J < 1 and 0 elsewhere (compression); history frozen."""
    mat = J2.replace(eps_L=EPS_L, failure=rule)
    Fs = failure_path(sign)
    Ps, hs = drive(mat, Fs)
    n_failed = n_pressure = 0
    for k, (F, P, h) in enumerate(zip(Fs, Ps, hs[1:])):
        J = np.linalg.det(F)
        if h[HIST_EPS_P] < EPS_L:
            tau_ref, ep_ref, _ = uniaxial_signed(J2, math.log(F[0, 0]))
            assert kirchhoff(P, F)[0, 0] == pytest.approx(tau_ref, rel=TOL_UNIAXIAL)
            continue
        n_failed += 1
        assert h[HIST_EPS_P] / EPS_L == pytest.approx(h[10], rel=TOL_ROUND) and h[10] >= 1
        if k > 0 and hs[k][10] >= 1:
            assert np.array_equal(h, hs[k])  # frozen once failed
        A = tangent(mat, F, h)
        if rule == "compression" and J < 1:
            n_pressure += 1
            tau_ref = mat.K * math.log(J) * np.eye(3)  # closed form of the compression rule
            assert rel(kirchhoff(P, F), tau_ref) < TOL_ROUND
            assert rel(A, fd_tangent(mat, F, h, 1e-6)) < TOL_FD
        else:
            assert np.all(P == 0.0) and np.all(A == 0.0)
    assert 10 <= n_failed <= len(Fs) - 4  # failure mid-path (ε_p = 0.05 near ε = 0.052)
    if rule == "compression":
        assert n_pressure >= 5  # the path reaches J < 1 after failure, in both directions
    else:
        assert n_pressure == 0


def test_compression_rule_tangent_is_finite_difference_of_P():
    mat = J2.replace(eps_L=EPS_L, failure="compression")
    h = mat.initial_history(1)[0]
    h[HIST_EPS_P], h[10] = 0.07, 0.07 / EPS_L  # a failed point
    F = 0.97 * (random_rotation(41) @ (np.eye(3) + 0.05 * np.random.default_rng(42).standard_normal((3, 3))))
    assert np.linalg.det(F) < 1
    A = tangent(mat, F, h)
    assert rel(A, fd_tangent(mat, F, h, 1e-6)) < TOL_FD
    P, hn, _ = stress(mat, F, h)
    J = np.linalg.det(F)
    assert rel(P[0], mat.K * math.log(J) * np.linalg.inv(F).T) < TOL_ROUND
    assert np.array_equal(hn[0], h)


def test_failure_mode_is_validated():
    with pytest.raises(ValueError, match="failure"):
        J2.replace(failure="brittle")
    assert J2.failure == "compression" and J2.params()[11] == 1.0  # the default
    assert J2.replace(failure="literal").params()[11] == 0.0


# --- tables and wider history rows -------------------------------------------------------------
def test_wider_history_columns_are_carried_on_every_j2_path():
    """A J2 point in a table whose widest law has more history columns keeps the extra columns
    on every path: elastic, plastic, failing in this step, failed earlier, inverted F."""
    from workbench.materials import N_HISTORY_J2, kernels

    mat = J2.replace(eps_L=EPS_L, failure="compression")
    extra = np.array([3.5, -7.25, 1e300])
    h0 = np.concatenate([mat.initial_history(1)[0], extra])
    failed = h0.copy()
    failed[HIST_EPS_P], failed[10] = 0.06, 1.2
    near = h0.copy()
    _, hs = drive(mat, [signed_F(J2, e) for e in (0.01, 0.02, 0.03, 0.04, 0.049)])
    near[:N_HISTORY_J2] = hs[-1]
    cases = {"elastic": (np.eye(3) + 1e-4 * np.diag([1.0, -0.3, -0.3]), h0),
             "plastic": (signed_F(J2, 0.02), h0),
             "failing": (signed_F(J2, 0.06), near),
             "failed": (0.98 * np.eye(3), failed),
             "inverted": (np.diag([1.0, 1.0, -0.5]), h0)}
    F = np.stack([c[0] for c in cases.values()])
    h = np.stack([c[1] for c in cases.values()])
    prm = mat.params()[None]
    for fn in (kernels.material_points, kernels.material_points_tangent):
        out = fn(np.ascontiguousarray(F), h.copy(), prm, np.zeros(len(F), np.int64))
        hn = out[-2]
        assert np.array_equal(hn[:, N_HISTORY_J2:], h[:, N_HISTORY_J2:])
    P, hn, st = kernels.material_points(np.ascontiguousarray(F), h.copy(), prm, np.zeros(len(F), np.int64))
    assert list(st) == [0, 0, 0, 0, kernels.INVERTED]
    assert hn[1, HIST_EPS_P] > 0 and hn[2, 10] >= 1 and hn[2, 12] > 0  # plastic; failed, W_rel > 0


def test_table_of_j2_variants_matches_each_material_alone():
    """Swift (literal failure), linear (compression failure) and an elastic law in one table:
    every point gets exactly its own material's stress, tangent and history."""
    from workbench.materials import MaterialTable, evaluate

    from test_materials import SVK

    table = MaterialTable((J2.replace(eps_L=EPS_L, failure="literal"),
                           LIN.replace(eps_L=0.01, failure="compression"), SVK))
    mat_id = np.array([0, 1, 2, 0, 1, 1])
    F = np.stack([signed_F(J2, 0.03), linear_uniaxial_F(LIN, 0.02), np.eye(3) + 0.01 * np.ones((3, 3)),
                  signed_F(J2, -0.08), linear_uniaxial_F(LIN, -0.03), 0.97 * np.eye(3)])
    h = table.initial_history(mat_id)
    r1 = evaluate(table, F, h, mat_id=mat_id)  # first step from virgin: some fail at once
    r = evaluate(table, 0.999 * F, r1["history"], tangent=True, mat_id=mat_id)
    for k in range(len(F)):
        m = table[mat_id[k]]
        a1 = evaluate(m, F[k], h[k, : m.n_history] if m.n_history else None)
        a = evaluate(m, 0.999 * F[k], a1["history"], tangent=True)
        assert np.array_equal(r["stress"][k], a["stress"]) and np.array_equal(r["A"][k], a["A"])
        assert np.array_equal(r["history"][k, : m.n_history], a["history"])
    assert np.sum(r["history"][:, 10] >= 1) >= 2  # failed points of both rules are in the table
