"""Analytic references of the idealised problems (scenes.md), computed independently of every solver.

- :func:`uniaxial_curve`: exact uniaxial stress response of finite-strain J2 with Hencky elasticity,
  the exponential map and Swift hardening on the Kirchhoff stress, along any axial log-strain path.
- :func:`cantilever_tip`: Euler–Bernoulli and Timoshenko tip deflection (plane stress / strain).
- :func:`elastica_tip`: the inextensible elastica under a tip load of fixed direction
  (Bisshopp & Drucker 1945), by shooting to 1e-10.
- :func:`plate_mode_shape`, :func:`plate_period`, :func:`plate_amplitude`,
  :func:`plate_initial_velocity`: the thin-plate first mode of 004 eq. 13–16, with Gray et al.'s
  clamped–free mode shape.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

# ------------------------------------------------------------------------------------------------
# Uniaxial stress–strain curve
# ------------------------------------------------------------------------------------------------


def uniaxial_curve(material, log_strain) -> dict:
    """Exact uniaxial-stress response along an axial logarithmic-strain path.

    Under uniaxial stress the principal directions never rotate, so Hencky elasticity with the
    exponential map reduces exactly to 1-D small-strain plasticity in log strains:
    τ = E (ε − ε_p^axial), yield |τ| = C (ε̄_p + ε0)^n (isotropic hardening, ε̄_p accumulated),
    lateral log strain ε_lat = −ν τ/E − ε_p^axial / 2 (plastic incompressibility).
    Returns arrays: ``tau`` (axial Kirchhoff stress, Pa), ``sigma`` (Cauchy = τ/J,
    J = exp((1 − 2ν) τ/E)), ``nominal`` (force over initial area = τ/λ_axial, Pa), ``eps_p``
    (equivalent plastic strain), ``eng_strain`` (exp(ε) − 1).
    """
    eps = np.atleast_1d(np.asarray(log_strain, dtype=float))
    E, nu, C, e0, n = material.E, material.nu, material.C, material.eps0, material.n

    def sy(p):
        return C * (p + e0) ** n

    tau = np.empty_like(eps)
    epbar = np.empty_like(eps)
    ep_ax, pbar = 0.0, 0.0
    for i, e in enumerate(eps):
        t_tr = E * (e - ep_ax)
        f = abs(t_tr) - sy(pbar)
        if f > 0:
            # |τ_tr| − E Δγ − σ_y(ε̄_p + Δγ) = 0, monotone decreasing in Δγ
            g = lambda d: abs(t_tr) - E * d - sy(pbar + d)
            d = brentq(g, 0.0, abs(t_tr) / E, xtol=1e-16, rtol=1e-15, maxiter=200)
            ep_ax += math.copysign(d, t_tr)
            pbar += d
            t_tr = E * (e - ep_ax)
        tau[i] = t_tr
        epbar[i] = pbar
    # plastic axial strain at each step, recovered from τ
    ep_axial = eps - tau / E
    J = np.exp((1 - 2 * nu) * tau / E)
    return dict(tau=tau, sigma=tau / J, nominal=tau * np.exp(-eps), eps_p=epbar,
                eps_p_axial=ep_axial, eng_strain=np.expm1(eps),
                lateral_strain=-nu * tau / E - ep_axial / 2)


# ------------------------------------------------------------------------------------------------
# Cantilever
# ------------------------------------------------------------------------------------------------


def plane_moduli(E: float, nu: float, plane: str) -> tuple[float, float]:
    """Effective (E', ν') of a 2-D idealisation: plane strain E/(1−ν²), ν/(1−ν); plane stress E, ν."""
    if plane == "strain":
        return E / (1 - nu ** 2), nu / (1 - nu)
    if plane == "stress":
        return E, nu
    raise ValueError(f"plane: {plane!r} is not one of 'strain', 'stress'")


def cantilever_tip(scene, load: float, theory: str = "timoshenko") -> float:
    """Linear tip deflection, m, of the scene's cantilever under a dimensionless load P L²/(E I).

    Euler–Bernoulli δ = P L³/(3 E' I); Timoshenko adds P L/(κ G A) with κ = 5/6 (rectangle) and
    A = H per unit thickness. E' is the plane-strain or plane-stress modulus.
    """
    P = scene.force(load)
    Ep, nup = plane_moduli(scene.E, scene.nu, scene.plane)
    delta = P * scene.L ** 3 / (3 * Ep * scene.I)
    if theory == "euler_bernoulli":
        return delta
    if theory == "timoshenko":
        G = Ep / (2 * (1 + nup))
        return delta + P * scene.L / (5.0 / 6.0 * G * scene.H)
    raise ValueError(f"theory: {theory!r} is not one of 'euler_bernoulli', 'timoshenko'")


def elastica_tip(load: float) -> tuple[float, float]:
    """Inextensible elastica of a clamped beam under a tip force of fixed (transverse) direction.

    With θ(s) the slope and α = P L²/(E I): θ'' = −α cos θ, θ(0) = 0, θ'(1) = 0 (s in units of L).
    Returns (v/L, u/L): the tip deflection in the load direction and the horizontal shortening.
    Note: α here uses the bending stiffness E I of the idealisation; for a 2-D plane-strain beam pass
    the load scaled by E/E'.
    """
    a = float(load)
    if a <= 0:
        return 0.0, 0.0

    def rhs(s, y):
        th, k, x, v = y
        return [k, -a * math.cos(th), math.cos(th), math.sin(th)]

    def end(k0):
        sol = solve_ivp(rhs, (0, 1), [0.0, k0, 0.0, 0.0], rtol=1e-12, atol=1e-13, method="DOP853")
        return sol.y[:, -1]

    k0 = brentq(lambda k: end(k)[1], 0.0, a, xtol=1e-14, rtol=1e-14)
    th, k, x, v = end(k0)
    return float(v), float(1.0 - x)


def cantilever_elastica(scene, load: float) -> tuple[float, float]:
    """Elastica tip deflection and shortening, m, of the scene's 2-D beam: the dimensionless load
    P L²/(E I) is rescaled to the bending stiffness E' I of the plane idealisation."""
    Ep, _ = plane_moduli(scene.E, scene.nu, scene.plane)
    v, u = elastica_tip(load * scene.E / Ep)
    return v * scene.L, u * scene.L


# ------------------------------------------------------------------------------------------------
# Oscillating plate
# ------------------------------------------------------------------------------------------------


def plate_mode_shape(X, scene) -> np.ndarray:
    """Gray et al.'s clamped–free first mode f(x), x from the clamp (004 eq. 14 with the sign of the
    first bracket corrected, scenes.md)."""
    kL = scene.kL
    k = kL / scene.L
    x = np.asarray(X, dtype=float)
    return ((math.cos(kL) + math.cosh(kL)) * (np.cosh(k * x) - np.cos(k * x))
            + (math.sin(kL) - math.sinh(kL)) * (np.sinh(k * x) - np.sin(k * x)))


def plate_initial_velocity(scene, X) -> np.ndarray:
    """v_y(X) = V_f c0 f(X)/f(L) (004 eq. 13), m/s; zero in the clamp (X ≤ 0)."""
    X = np.asarray(X, dtype=float)
    f = plate_mode_shape(np.maximum(X, 0.0), scene) / plate_mode_shape(scene.L, scene)
    return scene.V_f * scene.c0 * np.where(X > 0, f, 0.0)


def plate_omega(scene) -> float:
    """Thin-plate angular frequency, rad/s: ω² = E H² k⁴ / (12 ρ (1 − ν²)) (004 eq. 15, plane strain)."""
    m = scene.material
    k = scene.kL / scene.L
    return math.sqrt(m.E * scene.H ** 2 * k ** 4 / (12 * m.rho * (1 - m.nu ** 2)))


def plate_period(scene) -> float:
    """Thin-plate period 2π/ω, s (≈ 0.2541 s for the paper's plate)."""
    return 2 * math.pi / plate_omega(scene)


def plate_amplitude(scene) -> float:
    """Linear tip amplitude V_f c0 / ω, m (A/L ≈ 0.115 for the paper's plate)."""
    return scene.V_f * scene.c0 / plate_omega(scene)


# Table I of 004: dimensionless period T c0 / L and amplitude A / L.
TABLE_I = {
    "analytic (004)": (72.39, 0.115),
    "Hamiltonian (004)": (74.38, 0.114),
    "Gray et al. 2001": (82.0, 0.125),
}


# ------------------------------------------------------------------------------------------------
# Crack band: the energy a band of J2-plus-damage material spends to fail
# ------------------------------------------------------------------------------------------------


def failure_energy_density(material, eps_L: float) -> float:
    """g(ε_L), J/m³: the energy a unit reference volume of a J2 material with damage D = ε_p/ε_L
    (000 eq. 36) spends under uniaxial stress until it fails — the area under its stress–strain
    curve up to ε_p = ε_L with the vertical drop there (Bažant & Oh 1983): the plastic work
    ∫₀^{ε_L} σ_y(e) de, integrated from the law's hardening curve (``material.yield_stress``) by
    adaptive quadrature, plus the elastic energy the drop releases, σ_y(ε_L)²/(2E). Written apart
    from the material code (its closed form :func:`workbench.materials.j2.plastic_work` and
    :func:`studies.microcantilever.scene.band_energy_density`), which it checks."""
    from scipy.integrate import quad

    sy = lambda e: float(material.yield_stress(e))  # noqa: E731
    W_p = quad(sy, 0.0, float(eps_L), epsabs=0.0, epsrel=1e-12, limit=200)[0]
    return W_p + sy(eps_L) ** 2 / (2.0 * material.E)


def crack_band_energy(material, eps_L: float, band: float, area: float) -> float:
    """The energy, J, a crack of ``area`` (m², or m per unit thickness in 2-D: the length of the
    section it crosses) takes in the crack-band model: a band ``band`` (m) wide of material failing
    at ε_p = ε_L, each unit volume spending g(ε_L) (:func:`failure_energy_density`):
    G = b · g(ε_L) · A. Under the regularised rule the particles' ε_L,eff keeps Δx·g(ε_L,eff) =
    b·g(ε_L) (:func:`studies.microcantilever.scene.crack_band_limit`), so a straight column of failed
    particles across the section takes this at every spacing."""
    return float(band) * failure_energy_density(material, eps_L) * float(area)
