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
