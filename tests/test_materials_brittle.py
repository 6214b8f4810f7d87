"""The brittle law (workbench.materials.brittle, issue 41 item 1) at one point, against its closed
forms: the uniaxial softening curve, the energy per unit volume G_c/b, the snap-back strength of
Bažant & Oh, the compressive response of a cracked point, and the tangent."""
import math

import numpy as np
import pytest

from workbench.materials import Material, MaterialTable, energies, evaluate
from workbench.materials.brittle import H_DAMAGE, H_KAPPA, band_constants

E, NU, FT, GC, BAND = 200e9, 0.0, 1.0e9, 2.0e4, 0.002
"""A steel-like brittle solid; G_c = 20 kJ/m² over a 2 mm band: g = 1e7 J/m³, ε_f = 2g/f_t = 0.02
≫ ε_cr = 0.005 (no snap-back)."""
N_STEPS = 2000


def uniaxial(m, e_end, n=N_STEPS):
    """A uniaxial-strain path E_xx = 0 → e_end (ν = 0: uniaxial stress) in n equal steps. Returns
    the strains, the stresses S_xx, the work ∫S dE (trapezoid) and the final history and F."""
    from workbench.materials.kernels import material_point

    es = np.linspace(0.0, e_end, n + 1)
    F = np.tile(np.eye(3), (n + 1, 1, 1))
    F[:, 0, 0] = np.sqrt(1.0 + 2.0 * es)
    prm = m.params()
    h = m.initial_history(1)
    h_new = h.copy()
    P, A = np.empty((3, 3)), np.empty((3, 3, 3, 3))
    S = np.zeros(n + 1)
    for k in range(1, n + 1):  # the library's one-point dispatch (a parallel batch per step is slow)
        assert material_point(F[k], h[0], prm, P, h_new[0], A, False) == 0
        S[k] = P[0, 0] / F[k, 0, 0]
        h[:] = h_new
    work = float(np.sum(0.5 * (S[1:] + S[:-1]) * np.diff(es)))
    return es, S, work, h, F[-1]


def test_uniaxial_curve_is_the_linear_softening_and_releases_g_c_over_the_band():
    m = Material.brittle(E, NU, FT, GC, band=BAND)
    ft, eps_cr, eps_f = band_constants(E, FT, GC, BAND)
    assert (ft, eps_cr, eps_f) == pytest.approx((FT, FT / E, 2 * GC / (FT * BAND)), rel=1e-14)
    es, S, work, h, F = uniaxial(m, 1.25 * eps_f)
    closed = np.where(es <= eps_cr, E * es, np.clip(FT * (eps_f - es) / (eps_f - eps_cr), 0, None))
    # on a monotone path d(κ) is evaluated at the current strain: the curve is exact (round-off)
    assert S == pytest.approx(closed, abs=1e-9 * FT)
    en = energies(m, F, h[0])
    # the released energy by the trapezoid rule over the steps: O(Δε²) per step on the smooth
    # curve, (Δε/ε_f)² ~ 4e-7 overall, plus the kink at ε_cr (first order there, ~Δε/ε_f · ε_cr/ε_f
    # ~ 2e-4 of one step's share): 1e-5 of g
    g = GC / BAND
    assert en["W_rel"] == pytest.approx(g, rel=1e-5)
    assert en["psi"] == pytest.approx(0.0, abs=1e-12 * g)  # fully cracked in tension: nothing stored
    assert work == pytest.approx(en["psi"] + en["W_rel"], rel=1e-5)
    assert h[0, H_DAMAGE] == 1.0


def test_snap_back_reduces_the_strength_and_keeps_the_energy():
    """G_c < f_t² b/(2E): the strength is √(2 E G_c/b) (Bažant–Oh's crack band), the stress drops
    vertically at the peak, and the energy per unit volume is still G_c/b."""
    Gc = 1000.0  # f_t² b/(2E) = 5000 J/m²
    m = Material.brittle(E, NU, FT, Gc, band=BAND)
    ft, eps_cr, eps_f = band_constants(E, FT, Gc, BAND)
    assert ft == pytest.approx(math.sqrt(2 * E * Gc / BAND), rel=1e-14) and eps_f == eps_cr
    es, S, work, h, F = uniaxial(m, 2 * eps_cr)
    step = es[1]
    assert ft - E * step <= S.max() <= ft  # the peak is the last step below ε_cr
    # the drop happens within the step that crosses ε_cr: the trapezoid there is first order,
    # its error at most ½ E ε_cr Δε of g = ½ E ε_cr², i.e. Δε/ε_cr = 2·2/N_STEPS relative
    assert energies(m, F, h[0])["W_rel"] == pytest.approx(Gc / BAND, rel=2 * step / eps_cr)


def test_cracked_point_carries_compression_but_no_tension_or_shear():
    m = Material.brittle(2.1e11, 0.3, 1e9, 2e4, band=BAND)
    h = m.initial_history(1)
    h[0, H_DAMAGE] = 1.0
    K = m.K
    for e, compressed in ((-1e-3, True), (1e-3, False)):
        F = np.eye(3) * math.sqrt(1 + 2 * e)  # Green–Lagrange E = e I
        S = evaluate(m, F, h)["stress"] / math.sqrt(1 + 2 * e)
        want = 3 * K * e * np.eye(3) if compressed else np.zeros((3, 3))
        assert S == pytest.approx(want, abs=1e-9 * K * 1e-3)
    F = np.eye(3)
    F[0, 1] = 1e-3  # simple shear (tr E = ½γ² > 0): nothing carried
    assert np.abs(evaluate(m, F, h)["stress"]).max() < 1e-9 * m.mu * 1e-3


def test_tangent_is_the_derivative_of_the_stress_at_fixed_damage():
    """Central differences of P against A at a partly damaged state with tr E > 0 (step 1e-7 of
    F: truncation O(step²)|A| ~ 1e-14 |A|, round-off ~ 1e-16 |P|/1e-7 ~ 1e-12 |A|; 1e-6)."""
    m = Material.brittle(2.1e11, 0.3, 1e9, 2e4, band=BAND)
    h = m.initial_history(1)
    h[0, H_DAMAGE] = 0.4
    h[0, H_KAPPA] = 1.0  # κ far above the strains: the damage stays 0.4
    rng = np.random.default_rng(3)
    F = np.eye(3) + 1e-3 * rng.standard_normal((3, 3)) + 2e-3 * np.eye(3)
    A = evaluate(m, F, h, tangent=True)["A"]
    d = 1e-7
    num = np.zeros((3, 3, 3, 3))
    for k in range(3):
        for l in range(3):
            dF = np.zeros((3, 3))
            dF[k, l] = d
            num[:, :, k, l] = (evaluate(m, F + dF, h)["stress"]
                               - evaluate(m, F - dF, h)["stress"]) / (2 * d)
    assert num == pytest.approx(A, abs=1e-6 * np.abs(A).max())


def test_constants_are_checked_and_the_band_is_required():
    with pytest.raises(ValueError, match="^G_c: "):
        Material.brittle(E, NU, FT, 0.0)
    with pytest.raises(ValueError, match="^f_t: "):
        Material.brittle(E, NU, -1.0, GC)
    with pytest.raises(ValueError, match="^band: "):
        Material.brittle(E, NU, FT, GC).params()  # the method sets it (MaterialTable.with_band)
    t = MaterialTable((Material.brittle(E, NU, FT, GC), Material.brittle(E, NU, FT, GC, band=0.5)))
    assert t.with_band(0.004).params()[:, 5].tolist() == [0.004, 0.5]  # a material's own band kept


def test_particle_methods_take_a_band_of_two_spacings():
    """sph.particles.discretise gives the brittle law the band 2 Δx (PARTICLE_BAND)."""
    from sph.particles import discretise
    from workbench.scenes.crack_band import MortarBar

    sc = MortarBar(law="brittle")
    ps = discretise(sc.model(sc.B / 4), 4)
    rows = [k for k, mt in enumerate(ps.table.materials) if mt.law == "brittle"]
    assert rows and all(ps.table.materials[k].band == pytest.approx(2 * sc.B / 4) for k in rows)
