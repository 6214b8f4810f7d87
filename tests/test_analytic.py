"""The analytic references checked against independent facts: closed forms derived another way,
published tables, and the mode shape's boundary conditions."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from workbench import analytic
from workbench.materials import TABLE1_STEEL
from workbench.scenes import Cantilever, Plate


def test_uniaxial_curve_elastic_branch_is_hencky():
    # below yield: τ = E ε exactly, J = exp((1−2ν) ε) for uniaxial Hencky stress
    eps = np.array([1e-4, 1e-3])
    r = analytic.uniaxial_curve(TABLE1_STEEL, eps)
    assert np.allclose(r["tau"], TABLE1_STEEL.E * eps, rtol=1e-14)
    assert np.allclose(r["sigma"], r["tau"] / np.exp((1 - 2 * 0.3) * eps), rtol=1e-14)
    assert np.all(r["eps_p"] == 0)


def test_uniaxial_curve_on_swift_curve_after_yield():
    m = TABLE1_STEEL
    eps = np.linspace(0.01, 0.3, 30)
    r = analytic.uniaxial_curve(m, eps)
    assert np.allclose(r["tau"], m.C * (r["eps_p"] + m.eps0) ** m.n, rtol=1e-12)
    assert np.allclose(eps, r["tau"] / m.E + r["eps_p"], rtol=1e-12)


def test_considere_point_near_log_strain_018():
    # nominal stress τ e^{-ε} is maximal where dτ/dε = τ (Considère); notes.md: near ε = 0.18.
    eps = np.linspace(0.05, 0.3, 2501)
    nominal = analytic.uniaxial_curve(TABLE1_STEEL, eps)["nominal"]
    assert eps[np.argmax(nominal)] == pytest.approx(0.18, abs=0.01)


def test_unload_is_elastic_with_slope_E():
    eps = np.array([0.1, 0.099, 0.098])
    r = analytic.uniaxial_curve(TABLE1_STEEL, eps)
    assert np.diff(r["tau"]) == pytest.approx([-TABLE1_STEEL.E * 0.001] * 2, rel=1e-9)
    assert r["eps_p"][1] == r["eps_p"][0]


@pytest.mark.parametrize("alpha,v_ref,u_ref", [
    # Bisshopp & Drucker (1945), Table 1: tip deflection and shortening over L
    (1.0, 0.3017, 0.0564), (2.0, 0.4935, 0.1606), (5.0, 0.7138, 0.3876), (10.0, 0.8106, 0.5550)])
def test_elastica_matches_bisshopp_drucker(alpha, v_ref, u_ref):
    v, u = analytic.elastica_tip(alpha)
    assert v == pytest.approx(v_ref, abs=2e-4)  # the table's four digits
    assert u == pytest.approx(u_ref, abs=2e-4)


def test_elastica_against_elliptic_integral_form():
    # First integral θ'²/2 = α (sin θ0 − sin θ): the tip's x = sqrt(2 sin θ0 / α), and the length
    # 1 = ∫0^θ0 dθ / sqrt(2α (sin θ0 − sin θ)). Solve θ0 from the latter, compare x.
    alpha = 3.0
    from scipy.optimize import brentq

    def length(t0):
        # substitution sin θ = sin θ0 − w² removes the endpoint singularity
        s0 = math.sin(t0)
        f = lambda w: 2 / (math.sqrt(2 * alpha) * math.sqrt(1 - (s0 - w * w) ** 2))
        return quad(f, 0, math.sqrt(s0), epsabs=1e-13)[0] - 1.0

    t0 = brentq(length, 1e-3, math.pi / 2 - 1e-3, xtol=1e-14)
    v, u = analytic.elastica_tip(alpha)
    assert 1 - u == pytest.approx(math.sqrt(2 * math.sin(t0) / alpha), rel=1e-8)


def test_elastica_small_load_is_linear():
    v, _ = analytic.elastica_tip(1e-3)
    assert v == pytest.approx(1e-3 / 3, rel=1e-5)


def test_cantilever_timoshenko_adds_shear():
    s = Cantilever()
    eb = analytic.cantilever_tip(s, 1.0, "euler_bernoulli")
    # plane strain: E' = E/(1−ν²); δ = P L³ / (3 E' I) with P L²/(E I) = 1 → δ = L (1−ν²)/3
    assert eb == pytest.approx(s.L * (1 - s.nu ** 2) / 3, rel=1e-12)
    ti = analytic.cantilever_tip(s, 1.0)
    # shear term P L / (κ G H), κ = 5/6, relative to bending: (E'/(κ G)) (H/L)² / 4 ... ≈ 1 %
    assert 1.005 < ti / eb < 1.03


def test_plate_mode_shape_free_end():
    # clamped–free: f(0) = f'(0) = 0, moment f''(L) = 0 and shear f'''(L) = 0 (scenes.md)
    s = Plate()
    k = s.kL / s.L
    f = lambda x: analytic.plate_mode_shape(x, s)
    h = 1e-3 * s.L
    x = s.L
    d2 = (f(x + h) - 2 * f(x) + f(x - h)) / h ** 2
    d3 = (f(x + 2 * h) - 2 * f(x + h) + 2 * f(x - h) - f(x - 2 * h)) / (2 * h ** 3)
    scale = abs(f(s.L))
    assert abs(f(0.0)) < 1e-12 * scale
    assert abs(d2) < 1e-5 * scale * k ** 2
    assert abs(d3) < 1e-4 * scale * k ** 3


def test_plate_table_I_analytic_values():
    # Table I of 004: T c0 / L = 72.39 and A / L = 0.115 (thin-plate theory; the paper rounds)
    s = Plate()
    assert analytic.plate_period(s) * s.c0 / s.L == pytest.approx(72.39, rel=1e-3)
    assert analytic.plate_amplitude(s) / s.L == pytest.approx(0.115, rel=5e-3)
    # notes.md: T = 0.2541 s
    assert analytic.plate_period(s) == pytest.approx(0.2541, abs=1e-4)
    v = analytic.plate_initial_velocity(s, np.array([-0.01, 0.0, s.L]))
    assert v[0] == 0 and v[1] == 0 and v[2] == pytest.approx(s.V_f * s.c0, rel=1e-12)
