"""Energies per point (kernels.stored_energy_point, stored_energies, materials.energies): the stored
energy against the laws' definitions and as the potential of P (central differences), and the
energy balance ∫ P : dF = ψ + W_p + W_rel along uniaxial J2 paths, with and through failure, against
the exact work of the closed-form uniaxial solution."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from test_materials import (ALL, J2, MR, NEO, SVK, TOL_ENERGY_FD, TOL_ROUND, TOL_ROUND_J2, drive,
                            energy, random_F, rel, stress, uniaxial_F, uniaxial_reference)
from workbench.materials import (HIST_EPS_P, HIST_W_P, HIST_W_REL, MaterialTable, energies,
                                 evaluate, kernels)

# ψ + W_p of the kernel against the exact work of the closed-form uniaxial solution: the closed
# form is solved to 1e-15 (brentq) and integrated to 1e-13 (quad); the kernel's stress satisfies the
# yield condition to 1e-12 σ_y. 1e-10 relative leaves room for the round-off of the sums, and is far
# below any first-order bookkeeping error (σ_y,n+1 Δε_p instead of the exact increment: ~1e-4).
TOL_WORK = 1e-10


def psi(mat, F, h=None):
    F = np.ascontiguousarray(np.asarray(F, dtype=float).reshape(-1, 3, 3))
    if h is None:
        h = mat.initial_history(len(F))
    h = np.array(np.broadcast_to(np.asarray(h, dtype=float), (len(F), mat.n_history)))
    return kernels.stored_energies(F, h, mat.params()[None], np.zeros(len(F), np.int64))


def fd_grad_psi(mat, F, h, step=1e-6):
    Fs = np.repeat(F[None], 18, axis=0)
    for m, (k, l) in enumerate(np.ndindex(3, 3)):
        Fs[2 * m, k, l] += step
        Fs[2 * m + 1, k, l] -= step
    e = psi(mat, Fs, h)
    G = np.empty((3, 3))
    for m, (k, l) in enumerate(np.ndindex(3, 3)):
        G[k, l] = (e[2 * m] - e[2 * m + 1]) / (2 * step)
    return G


# --- stored energy -----------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(ALL))
def test_stored_energy_is_the_laws_definition(name):
    """Against the energies written from each law's definition in test_materials (numpy; for J2
    the Hencky energy of a virgin point, eigh and logs), and ψ(I) = 0."""
    mat = ALL[name]
    F = random_F(51, 5e-4 if name == "j2" else 0.25)
    tol = TOL_ROUND_J2 if name == "j2" else TOL_ROUND
    assert psi(mat, F)[0] == pytest.approx(energy(mat, F), rel=tol)
    assert abs(psi(mat, np.eye(3))[0]) <= TOL_ROUND * mat.mu * 1e-6  # exact 0 up to round-off


def elastic_states():
    """(label, material, F, h): P = ∂ψ/∂F must hold at each (an elastic step for J2)."""
    out = [(n, ALL[n], random_F(52, 0.25), ALL[n].initial_history(1)[0])
           for n in ("svk", "neo_hooke", "mooney_rivlin")]
    out.append(("j2_virgin", J2, random_F(1, 5e-4), J2.initial_history(1)[0]))  # elastic (test_materials)
    # J2 after plastic flow (Cp⁻¹ ≠ I), then a small elastic unloading step
    G = np.random.default_rng(54).standard_normal((3, 3))
    path = [np.eye(3) + 0.02 * k * G for k in range(1, 5)]
    _, hs = drive(J2, path)
    out.append(("j2_hardened", J2, np.eye(3) + 0.0795 * G, hs[-1]))
    # a failed J2 point under the compression rule, J < 1
    h = J2.initial_history(1)[0]
    dam = J2.replace(eps_L=0.01, failure="compression")
    h[HIST_EPS_P], h[10] = 0.02, 2.0
    out.append(("j2_failed", dam, 0.97 * random_F(55, 0.05), h))
    return out


@pytest.mark.parametrize("label,mat,F,h", elastic_states(), ids=lambda v: v if isinstance(v, str) else "")
def test_P_is_the_derivative_of_the_stored_energy(label, mat, F, h):
    P, hn, st = stress(mat, F, h)
    assert st[0] == 0 and np.array_equal(hn[0], h)  # an elastic step: the history is unchanged
    G = fd_grad_psi(mat, F, h)
    assert rel(P[0], G) < TOL_ENERGY_FD, rel(P[0], G)
    if label == "j2_failed":
        assert np.linalg.det(F) < 1 and np.max(np.abs(P)) > 0


def test_stored_energies_of_a_table_and_energies_wrapper():
    table = MaterialTable((SVK, J2, NEO, MR))
    mat_id = np.array([0, 1, 2, 3, 1, 0])
    F = np.stack([random_F(60 + k, 5e-4 if mat_id[k] == 1 else 0.2) for k in range(6)])
    r = evaluate(table, F, mat_id=mat_id)
    e = energies(table, F, r["history"], mat_id=mat_id)
    for k in range(6):
        alone = psi(table[mat_id[k]], F[k])[0]
        assert e["psi"][k] == alone
    assert np.all(e["W_p"] == 0) and np.all(e["W_rel"] == 0)  # elastic steps, no failure
    one = energies(J2, F[1])
    assert one["psi"] == pytest.approx(energy(J2, F[1]), rel=TOL_ROUND_J2)


# --- energy balance along uniaxial J2 paths ----------------------------------------------------
def hardening_work(mat, eps_p):
    """∫₀^{ε_p} σ_y dε_p by adaptive quadrature of the Swift curve (independent of the kernel)."""
    return quad(lambda e: mat.C * (e + mat.eps0) ** mat.n, 0.0, eps_p, epsabs=0, epsrel=1e-13)[0]


def exact_uniaxial_work(mat, eps):
    """∫₀^ε τ(e) de of the closed-form uniaxial curve, split at the yield strain."""
    ey = mat.sigma_y0 / mat.E
    f = lambda x: uniaxial_reference(mat, x)[0]
    if eps <= ey:
        return quad(f, 0.0, eps, epsabs=0, epsrel=1e-13)[0]
    return (quad(f, 0.0, ey, epsabs=0, epsrel=1e-13)[0]
            + quad(f, ey, eps, epsabs=0, epsrel=1e-13, limit=200)[0])


def trapezoid_work(Fs, Ps):
    """Σ ½ (P_{k−1} + P_k) : (F_k − F_{k−1}) from F = I, P = 0."""
    Fa = [np.eye(3)] + list(Fs)
    Pa = [np.zeros((3, 3))] + list(Ps)
    return sum(0.5 * np.sum((Pa[k - 1] + Pa[k]) * (Fa[k] - Fa[k - 1])) for k in range(1, len(Fa)))


def reference_trapezoid_error(mat, strains):
    """The quadrature error of the trapezoid rule on this path, from the closed form alone: the
    trapezoid of P11(F11) = τ(ln F11)/F11 over the same steps minus its exact integral
    ∫ τ dε (lateral P = 0 on the uniaxial path)."""
    eps = np.concatenate([[0.0], strains])
    f = np.array([uniaxial_reference(mat, e)[0] * math.exp(-e) if e > 0 else 0.0 for e in eps])
    trap = np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(np.exp(eps)))
    return trap - exact_uniaxial_work(mat, eps[-1])


def test_energy_balance_on_a_monotonic_uniaxial_path():
    """ψ_e and W_p each equal their closed forms (½ τ²/E; ∫ σ_y dε_p), and the trapezoid work
    ∫ P : dF over 1000 steps to ε = 0.1 equals ψ_e + W_p up to the trapezoid rule's own error on
    this path, e_q ≈ −97 J/m³ (2e-6 of the work; second order in the step, with one first-order
    step at the yield kink), computed from the closed form (reference_trapezoid_error)."""
    strains = np.linspace(0.0, 0.1, 1001)[1:]
    Fs = [uniaxial_F(J2, e) for e in strains]
    Ps, hs = drive(J2, Fs)
    e = energies(J2, Fs[-1], hs[-1])
    tau, ep, _ = uniaxial_reference(J2, strains[-1])
    assert e["psi"] == pytest.approx(0.5 * tau ** 2 / J2.E, rel=TOL_WORK)  # Hencky, uniaxial
    assert e["W_p"] == pytest.approx(hardening_work(J2, ep), rel=TOL_WORK)
    assert e["W_rel"] == 0.0
    W = trapezoid_work(Fs, Ps)
    S = e["psi"] + e["W_p"]
    e_q = reference_trapezoid_error(J2, strains)
    assert abs(S - exact_uniaxial_work(J2, strains[-1])) <= TOL_WORK * S
    assert abs(W - S) <= 1.01 * abs(e_q) + TOL_WORK * S, (W - S, e_q)
    assert abs((W - S) - e_q) <= TOL_WORK * S  # and the difference is that error itself
    assert abs(e_q) > 10 * TOL_WORK * S  # (the check above can tell the two apart)


@pytest.mark.parametrize("rule", ["literal", "compression"])
def test_energy_balance_through_failure(rule):
    """Uniaxial tension to failure (ε_L = 0.05, reached near ε = 0.052), on to ε = 0.06, then the
    axial strain driven back to −0.06 with the lateral stretch frozen. Every step:
    ∫ P : dF = ψ + W_p + W_rel, where the trapezoid rule's error is that of the closed form up to
    failure plus that of the failed point's closed form after it (τ = K ln J I for J < 1 under
    the compression rule, 0 under the literal one), and the step in which the point fails is
    taken with its end stress before the release (closed form), the energy released being W_rel."""
    epsL = 0.05
    mat = J2.replace(eps_L=epsL, failure=rule)
    up = np.linspace(0.0, 0.06, 601)[1:]
    Fs = [uniaxial_F(J2, e) for e in up]
    lat = Fs[-1][1, 1]
    down = np.linspace(0.06, -0.06, 121)[1:]
    Fs += [np.diag([math.exp(e), lat, lat]) for e in down]
    Ps, hs = drive(mat, Fs)
    k_fail = next(k for k, h in enumerate(hs[1:]) if h[HIST_EPS_P] >= epsL)
    assert 400 < k_fail < 600
    # released energy: the Hencky energy of the uniaxial state at the failing step (J > 1 there)
    tau_f, ep_f, _ = uniaxial_reference(J2, up[k_fail])
    h_end = hs[-1]
    assert h_end[HIST_EPS_P] == pytest.approx(ep_f, rel=1e-9)  # frozen since failure
    assert h_end[HIST_W_REL] == pytest.approx(0.5 * tau_f ** 2 / J2.E, rel=TOL_WORK)
    assert h_end[HIST_W_P] == pytest.approx(hardening_work(J2, ep_f), rel=TOL_WORK)
    J_end = np.linalg.det(Fs[-1])
    e = energies(mat, Fs[-1], h_end)
    K = mat.K
    psi_ref = 0.5 * K * math.log(J_end) ** 2 if (rule == "compression" and J_end < 1) else 0.0
    assert J_end < 1 and e["psi"] == pytest.approx(psi_ref, rel=TOL_ROUND, abs=0.0)
    # work: trapezoid with the failing step's end stress before the release
    W = trapezoid_work(Fs, Ps)
    dF = Fs[k_fail] - (Fs[k_fail - 1])
    P_pre = np.diag([tau_f * math.exp(-up[k_fail]), 0.0, 0.0])
    W += 0.5 * np.sum((P_pre - Ps[k_fail]) * dF)
    # the trapezoid rule's own error: up to failure from the uniaxial closed form; after it from
    # the failed point's closed form P = K ln J F⁻ᵀ (J < 1; 0 otherwise), whose exact work from
    # the failing step (J > 1) on is ψ(J_end) − 0
    e_q = reference_trapezoid_error(J2, up[: k_fail + 1])
    if rule == "compression":
        diag = np.array([np.diag(F) for F in Fs[k_fail:]])  # the path's F are diagonal
        J = np.prod(diag, axis=1)
        f = np.where(J < 1, K * np.log(np.minimum(J, 1.0)), 0.0)[:, None] / diag  # P_ii
        e_q += np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(diag, axis=0)) - psi_ref
    S = e["psi"] + e["W_p"] + e["W_rel"]
    assert abs((W - S) - e_q) <= TOL_WORK * S, (W - S, e_q)
    assert abs(W - S) <= 1.01 * abs(e_q) + TOL_WORK * S
    if rule == "compression":
        assert psi_ref > 1e-3 * S  # the compressive energy is a visible part of the balance
