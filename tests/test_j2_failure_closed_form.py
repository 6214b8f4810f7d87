"""The J2-plus-damage code path that the FEM and csph share (workbench.materials: the point
routine both call), against closed forms written apart from it (issue 42 item 5): a homogeneous
bar under uniaxial stress pulled to failure — its stress–strain curve, the failure at ε_p = ε_L
and the energy it spends, against the law integrated by scipy.integrate — and the crack band's
closed form b·g(ε_L)·A (workbench.analytic.crack_band_energy) that the micro-cantilever's
crack-band gate checks its fracture energy against. The first-failure gates compare csph with an
FEM that runs the same material code; these checks make a defect in it fail on its own."""
import math

import numpy as np
import pytest

from workbench import analytic
from workbench.materials import HIST_DAMAGE, HIST_EPS_P, HIST_W_P, HIST_W_REL, Material, evaluate
from studies.microcantilever.scene import MicroCantilever, band_energy_density

SCENE = MicroCantilever(dim=2)
GRAINS, GB = SCENE.materials(SCENE.H / 10)
STEEL = Material.j2(E=202e9, nu=0.3, C=868.8e6, eps0=0.0013, n=0.179, rho=7974.0)  # 000 Table 1
LINEAR = Material.j2_linear(E=206e9, nu=0.3, sigma_y0=394e6, H=206e9 / 99)

# Quadrature: adaptive, epsrel 1e-12 on a smooth integrand; the kernel's plastic work is a closed
# form of the same integral: they agree to round-off, 1e-10 (a defect — hardening on the Cauchy
# instead of the Kirchhoff stress, the work's power off by one — moves g by 1e-3 or more).
TOL_G = 1e-10
# The bar: lateral stretch solved to xtol 1e-15 (P22 = 0), the return mapping's Newton to 1e-12 of
# σ_y, logs and exponentials of the stress path: the kernel's τ11 equals the 1-D closed form to
# 1e-9 (backward Euler is exact on a radial path); a defect of the size above fails it.
TOL_CURVE = 1e-9
# The work done on the bar, ∫ τ11 dε11 by the trapezoid rule over N_STEPS steps Δε, against the
# energy the law says it spent (g): the rule's error on the curve, predicted (trapezoid_error): at
# the yield kink, a fraction s into its step, ½ s(1 − s) Δε² (E − E_t) (exact for the kink); on the
# smooth branch (Δε²/12)·∫τ'' dε ≤ (Δε²/12)·E_t(0⁺), the tangent slope falling from its value just
# past yield. Leading order only: the Swift curve turns within ε0 = 0.0013 ≈ Δε of yield, so the
# next terms are not small there; twice the prediction is the tolerance (steel: predicted 6.2e-4
# of g, 1.7e-4 for the micro-cantilever's grain boundaries). The kernel's own records, W_p + W_rel
# at failure, equal g(ε_p at failure) to round-off (TOL_G).
N_STEPS = 50


def trapezoid_error(mat, d_eps, g):
    """The trapezoid rule's leading error on the uniaxial curve, relative to g (comment above)."""
    H0 = mat.n * mat.sigma_y0 / mat.eps0  # dσ_y/dε_p at ε_p = 0 (Swift)
    E_t = mat.E * H0 / (mat.E + H0)
    s = (mat.sigma_y0 / mat.E / d_eps) % 1.0  # where in its step the yield kink lies
    return d_eps ** 2 * (0.5 * s * (1 - s) * (mat.E - E_t) + E_t / 12) / g


def swift_g(mat, eps_L):
    """g(ε_L) of Swift hardening by hand: C [(ε_L + ε0)^{n+1} − ε0^{n+1}]/(n + 1) + σ_y(ε_L)²/2E."""
    C, e0, n = mat.C, mat.eps0, mat.n
    sy = C * (eps_L + e0) ** n
    return C * ((eps_L + e0) ** (n + 1) - e0 ** (n + 1)) / (n + 1) + sy * sy / (2 * mat.E)


@pytest.mark.parametrize("mat,eps_L", [(STEEL, 0.05), (GB, SCENE.eps_L_low),
                                       (GRAINS[0], SCENE.eps_L_low)], ids=["steel", "gb", "grain0"])
def test_failure_energy_density_is_the_integral_of_the_law(mat, eps_L):
    """g(ε_L) by quadrature (analytic) against Swift's integral by hand, and the scene's code path
    (band_energy_density: the kernel's closed-form plastic work, which sets the crack band's
    ε_L,eff) against both."""
    g = analytic.failure_energy_density(mat, eps_L)
    assert g == pytest.approx(swift_g(mat, eps_L), rel=TOL_G)
    assert band_energy_density(mat, eps_L) == pytest.approx(g, rel=TOL_G)


def test_failure_energy_density_linear_hardening():
    eps_L = 0.03
    sy = LINEAR.sy0 + LINEAR.H * eps_L
    g = LINEAR.sy0 * eps_L + 0.5 * LINEAR.H * eps_L ** 2 + sy * sy / (2 * LINEAR.E)
    assert analytic.failure_energy_density(LINEAR, eps_L) == pytest.approx(g, rel=TOL_G)
    assert band_energy_density(LINEAR, eps_L) == pytest.approx(g, rel=TOL_G)


def test_crack_band_energy_closed_form_of_the_micro_cantilever():
    """b·g·H, 2-D (J/m): the band of 1 µm straight across the 5 µm section of the grain-boundary
    material and of grain 0 — by hand, µJ/m."""
    b, H = 1e-6, SCENE.H
    for mat in (GB, GRAINS[0]):
        G = analytic.crack_band_energy(mat, SCENE.eps_L_low, b, H)
        assert G == pytest.approx(b * H * swift_g(mat, SCENE.eps_L_low), rel=TOL_G)
        assert 3.5e-6 < G < 4.5e-6  # the study's comment: 4.12 and 4.01 µJ/m


def lateral_equilibrium(mat, lam_axial, h, lam):
    """The lateral stretch λ at which P22 = P33 = 0 of F = diag(λ_a, λ, λ) from history h: Newton
    on the kernel's own P22 with its tangent dP22/dλ = A2222 + A2233, from the last step's λ (the
    bar is free laterally; quadratic convergence, to 1e-15 of λ)."""
    for _ in range(20):
        out = evaluate(mat, np.diag([lam_axial, lam, lam]), h, tangent=True)
        A = out["A"]
        step = out["stress"][1, 1] / (A[1, 1, 1, 1] + A[1, 1, 2, 2])
        lam -= step
        if abs(step) < 1e-15:
            return lam
    raise AssertionError("lateral equilibrium: Newton did not converge")


def trapezoid(tau, eps):
    """∫ τ dε by the trapezoid rule from (0, 0)."""
    t, e = np.concatenate([[0.0], tau]), np.concatenate([[0.0], eps])
    return float(np.sum(0.5 * (t[1:] + t[:-1]) * np.diff(e)))


@pytest.mark.parametrize("mat,eps_L,eps_end", [(STEEL, 0.05, 0.06), (GB, SCENE.eps_L_low, 0.006)],
                         ids=["steel", "microcantilever_gb"])
def test_homogeneous_bar_to_failure_against_the_closed_form(mat, eps_L, eps_end):
    """A homogeneous bar under uniaxial stress (lateral faces free), axial log strain to eps_end in
    N_STEPS steps through the point routine: before failure τ11 on the closed-form curve
    (analytic.uniaxial_curve: 1-D return mapping in log strains); the bar fails in the step where
    ε_p reaches ε_L (the step's lateral stretch that of the law without failure, whose stress the
    failure releases) and from there carries no tension (the compression rule: P = 0 for J ≥ 1;
    the literal rule's P = 0 everywhere is tests/test_materials_j2.py's); the
    energy it spent — the kernel's W_p + W_rel at failure, and the work ∫ τ dε done on it up to
    the failing state — is g(ε_p at failure) of the law integrated by quadrature."""
    intact = mat.replace(eps_L=math.inf)
    mat = mat.replace(eps_L=eps_L, failure="compression")  # the micro-cantilever's rule
    eps = np.linspace(0.0, eps_end, N_STEPS + 1)[1:]
    ref = analytic.uniaxial_curve(mat, eps)
    h, lam, taus, k_fail = mat.initial_history(1)[0], 1.0, [], None
    for k, e in enumerate(eps):
        if k_fail is None:
            lam = lateral_equilibrium(intact, math.exp(e), h, lam)
        F = np.diag([math.exp(e), lam, lam])
        out = evaluate(mat, F, h)
        hn = out["history"]
        if k_fail is None and hn[HIST_DAMAGE] >= 1.0:
            k_fail, ep_f = k, hn[HIST_EPS_P]
            taus.append(float(mat.yield_stress(ep_f)))  # the uniaxial stress the failure released
        elif k_fail is None:
            taus.append((out["stress"] @ F.T)[0, 0])
            assert taus[-1] == pytest.approx(ref["tau"][k], rel=TOL_CURVE)
            assert hn[HIST_EPS_P] == pytest.approx(ref["eps_p"][k], rel=TOL_CURVE, abs=1e-15)
        else:
            assert np.all(out["stress"] == 0.0)  # J ≥ 1: no tension
            assert np.array_equal(hn, h)  # history frozen
        if k == k_fail:
            assert np.all(out["stress"] == 0.0)
            assert hn[HIST_W_P] + hn[HIST_W_REL] == pytest.approx(
                analytic.failure_energy_density(mat, ep_f), rel=TOL_G)
            assert eps_L <= ep_f <= eps_L + eps_end / N_STEPS  # within the step's strain
        h = hn
    assert k_fail is not None and 0 < k_fail < N_STEPS - 1, k_fail
    g = analytic.failure_energy_density(mat, ep_f)
    # the work done: the trapezoid over the kernel's stresses, whose only error is the rule's own
    # on the closed-form curve (the same sum over the closed form's stresses, to TOL_CURVE)
    W = trapezoid(np.array(taus), eps[: k_fail + 1])
    W_ref = trapezoid(np.append(ref["tau"][:k_fail], taus[-1]), eps[: k_fail + 1])
    assert W == pytest.approx(W_ref, rel=TOL_CURVE)
    assert abs(W / g - 1) < 2 * trapezoid_error(mat, eps_end / N_STEPS, g), (W / g - 1)


def test_the_checks_catch_a_defect_of_the_law():
    """A hardening law off by the smallest defect the gates guard against (the yield stress 0.1 %
    high, as hardening on the Cauchy instead of the Kirchhoff stress at these strains) moves g
    far beyond TOL_G: the closed form can tell it from the kernel's."""
    off = STEEL.replace(C=STEEL.C * 1.001)
    assert abs(band_energy_density(off, 0.05) / analytic.failure_energy_density(STEEL, 0.05) - 1) \
        > 1e3 * TOL_G


# The recorded full 2-D micro-cantilever study (studies/microcantilever.py, the comment at
# TOL_BAND): the regularised rule's fracture energy, µJ/m, at H/Δx = 10, 15, 20 (band 1 µm).
BAND_LADDER = (10, 15, 20)
BAND_RECORDED = {"inter": (4.45, 4.28, 4.63), "intra": (4.25, 4.38, 4.01)}
BAND_MATERIAL = {"inter": GB, "intra": GRAINS[0]}  # where the low ε_L is, along the crack


@pytest.mark.parametrize("case", ["inter", "intra"])
def test_band_value_gate_on_the_recorded_run(case):
    """The crack-band gate against the closed form b g(ε_L) H passes the recorded energies and
    fails three times their error; a run that reported none fails it."""
    from studies.crack_band import band_value_gate

    b = 1e-6
    closed = analytic.crack_band_energy(BAND_MATERIAL[case], SCENE.eps_L_low, b, SCENE.H)
    G = np.array(BAND_RECORDED[case]) * 1e-6
    g = band_value_gate(case, BAND_LADDER, G, closed, b)
    assert g.passed and g.reference and not g.regressed(3.0).passed, g.line()
    tripled = closed * (1 + 3 * (G / closed - 1))  # the same errors, three times
    assert not band_value_gate(case, BAND_LADDER, tripled, closed, b).passed
    assert not band_value_gate(case, BAND_LADDER, np.append(G[:2], np.nan), closed, b).passed


def test_closed_form_from_a_dataset_s_scene_parameters():
    """The study's dataset carries the scene as param_* attributes (numpy scalars, as read back
    from netCDF): the closed form built from them is the scene's."""
    from studies.crack_band import microcantilever_band_closed_form
    from workbench.results import provenance

    attrs = {k: (np.float64(v) if isinstance(v, float) else np.int64(v) if isinstance(v, int)
                 and not isinstance(v, bool) else v)
             for k, v in provenance("microcantilever", SCENE).items()}
    for case, mat in BAND_MATERIAL.items():
        assert microcantilever_band_closed_form(attrs, case, 1e-6) == pytest.approx(
            analytic.crack_band_energy(mat, SCENE.eps_L_low, 1e-6, SCENE.H), rel=1e-14)
