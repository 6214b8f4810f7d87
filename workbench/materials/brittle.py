"""A brittle solid with a fracture energy (issue 41 item 1): Rankine onset, linear softening
regularised by G_c over the crack band the method cracks, no plasticity. Law code 5 of
:mod:`workbench.materials`; built by :meth:`Material.brittle`.

The law
-------
* Strain and stress as the library's Saint Venant–Kirchhoff law (law 0, the same routine): E = ½(FᵀF − I),
  P = F S, with a scalar damage d ∈ [0, 1] acting on the tensile part of a volumetric–deviatoric
  split (Amor, Marigo & Maurini 2009):
  ψ(E, d) = (1 − d) ψ⁺(E) + ψ⁻(E),  ψ⁺ = ½K⟨tr E⟩₊² + μ dev E : dev E,  ψ⁻ = ½K⟨tr E⟩₋²,
  so S = λ' tr E I + 2μ' E with μ' = (1 − d)μ and λ' = K' − ⅔μ', K' = (1 − d)K in volumetric
  tension, K in compression (:func:`effective_lame`). A cracked point keeps its bulk stiffness in
  compression (cracks close, the halves do not interpenetrate) and loses tension and shear; a fully
  cracked one (d = 1) carries only τ ∝ K tr E in compression, as J2's ``'compression'`` failure mode.
* Onset (Rankine, maximum principal stress): the equivalent strain is the largest principal
  effective stress over E, ε̃ = max eig(λ tr E I + 2μ E)/E, and κ its largest value so far
  (:func:`equivalent_strain`). Cracking starts at κ = ε_cr = f_t/E.
* Softening (:func:`damage`): linear in uniaxial stress, σ = f_t (ε_f − κ)/(ε_f − ε_cr) from f_t at
  ε_cr to zero at ε_f, i.e. d(κ) = 1 − ε_cr (ε_f − κ)/(κ (ε_f − ε_cr)). Linear rather than
  exponential because it reaches d = 1 at a finite strain: a particle is then *failed* (crack fully
  opened, :mod:`workbench.materials.failure`) in finite time, which the crack rule, the connectivity
  check and the failure observables need; an exponential tail never ends.
* Regularisation (crack band, Bažant & Oh 1983): the area under the uniaxial curve, ½ f_t ε_f, is
  the fracture energy over the band width b, g = G_c/b, so ε_f = 2 G_c/(f_t b)
  (:func:`softening_strain`). b is the width of the band the method actually cracks: the particle
  methods crack a band of **two lattice columns** (a particle's deformation gradient is formed from
  its neighbours, so a jump between two columns is a strain of both; measured with the mortar law
  on the crack-band bar, :mod:`workbench.scenes.crack_band`, docs/fracture.md), so
  b = :data:`PARTICLE_BAND` · Δx, set by :func:`sph.particles.discretise`; the FEM takes one element,
  b = h. A material may give its own ``band`` (m) instead.
* Snap-back (G_c < f_t² b/(2E): ε_f would fall below ε_cr): as in Bažant & Oh's crack band model,
  the strength is reduced locally to the largest value without snap-back, f_t,eff = √(2 E G_c/b),
  where ε_f = ε_cr and the stress drops vertically at the peak (:func:`band_constants`); the energy
  per crack area stays G_c at any spacing. No parameter is capped by the spacing.
* Released energy (history): the dissipation rate is ψ⁺ ḋ; a step adds ½(ψ⁺_n + ψ⁺_{n+1}) Δd (the
  trapezoid rule, second order in the step; ψ⁺_n kept in the history). Then ∫ S : dE = ψ + W_rel.
* Tangent A = dP/dF: the SVK tangent with (λ', μ') at the step's damage (secant in the damage, as
  the mortar's; exact for elastic steps away from tr E = 0).

Parameter slots (``prm``, law 5): 0 law code 5; 1 Lamé λ, Pa; 2 μ, Pa; 3 f_t as given, Pa;
4 G_c, J/m²; 5 band width b, m; 6 effective strength f_t,eff, Pa; 7 ε_cr = f_t,eff/E; 8 ε_f;
9–11 unused.

History (:data:`N_HISTORY` = 4 columns; columns beyond are copied): 0 κ (largest equivalent strain
once it passed ε_cr, else what it was), 1 damage d, 2 released energy W_rel, J/m³ (reference
volume), 3 ψ⁺ at the end of the step, J/m³. A virgin point has all zeros.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .elastic import svk_point
from .tensor import INVERTED, JIT, _cofactor, _fail, eigh3

LAW_CODE = 5
N_HISTORY = 4
H_KAPPA = 0
H_DAMAGE = 1
H_W_RELEASED = 2
H_PSI_PLUS = 3

PARTICLE_BAND = 2.0
"""Width of the crack band of the particle methods over the spacing Δx: two lattice columns
(module docstring; measured with the mortar law on the crack-band bar, csph 1.9997 G_F with nodal
integration at every spacing, docs/fracture.md)."""


# --------------------------------------------------------------------------------------------
# the constants at a band width (Python)
# --------------------------------------------------------------------------------------------
def softening_strain(f_t: float, G_c: float, band: float) -> float:
    """ε_f = 2 G_c/(f_t b): the strain of zero stress of the linear softening whose area ½ f_t ε_f
    is G_c/b (the fracture energy spread over the band b)."""
    return 2.0 * G_c / (f_t * band)


def band_constants(E: float, f_t: float, G_c: float, band: float) -> tuple[float, float, float]:
    """(f_t,eff, ε_cr, ε_f) of the law at the band width b, m: f_t,eff = f_t unless
    G_c < f_t² b/(2E) (snap-back), where it is √(2 E G_c/b), the largest strength whose softening
    is not steeper than vertical (Bažant & Oh 1983), and ε_f = ε_cr = f_t,eff/E."""
    if not (band > 0 and math.isfinite(band)):
        raise ValueError(f"band: {band} m is not allowed; the crack band width must be > 0 and "
                         "finite")
    if G_c < f_t * f_t * band / (2.0 * E):
        ft = math.sqrt(2.0 * E * G_c / band)
        return ft, ft / E, ft / E
    return f_t, f_t / E, softening_strain(f_t, G_c, band)


def check_material(m) -> None:
    """The brittle constants of a :class:`Material` (E, ν, ρ are checked by ``validated``)."""
    if not (m.f_t > 0 and math.isfinite(m.f_t)):
        raise ValueError(f"f_t: {m.f_t} Pa is not allowed; the tensile strength must be > 0 and "
                         "finite")
    if not (m.G_c > 0 and math.isfinite(m.G_c)):
        raise ValueError(f"G_c: {m.G_c} J/m^2 is not allowed; the fracture energy must be > 0 "
                         "and finite")
    if not (m.band >= 0 and math.isfinite(m.band)):
        raise ValueError(f"band: {m.band} m is not allowed; the crack band width must be >= 0 "
                         "(0: the method's own) and finite")


def pack_params(m, p: np.ndarray) -> None:
    """Slots 3–8 of the parameter row of a brittle material (slots 0–2 are the common ones)."""
    if not m.band > 0:
        raise ValueError("band: the brittle law needs its crack band width; a method sets it from "
                         "its spacing (MaterialTable.with_band), or give Material.brittle(band=...)")
    ft, eps_cr, eps_f = band_constants(m.E, m.f_t, m.G_c, m.band)
    p[3] = m.f_t
    p[4] = m.G_c
    p[5] = m.band
    p[6] = ft
    p[7] = eps_cr
    p[8] = eps_f


# --------------------------------------------------------------------------------------------
# the equations
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def damage(kappa, eps_cr, eps_f):
    """d(κ) of the linear softening: 0 up to ε_cr, 1 − ε_cr(ε_f − κ)/(κ(ε_f − ε_cr)) between, 1
    from ε_f on (so that σ = (1 − d) E κ falls linearly from f_t to 0 in uniaxial stress)."""
    if kappa <= eps_cr:
        return 0.0
    if kappa >= eps_f:
        return 1.0
    return 1.0 - eps_cr * (eps_f - kappa) / (kappa * (eps_f - eps_cr))


@njit(**JIT)
def equivalent_strain(e00, e11, e22, e01, e02, e12, lam, mu, E):
    """Rankine's equivalent strain: the largest principal effective stress over E,
    max eig(λ tr E I + 2μ E)/E = (λ tr E + 2μ max eig E)/E."""
    e = eigh3(e00, e01, e02, e11, e12, e22)
    emax = max(e[0], max(e[1], e[2]))
    return (lam * (e00 + e11 + e22) + 2.0 * mu * emax) / E


@njit(**JIT)
def tensile_energy(e00, e11, e22, e01, e02, e12, lam, mu):
    """ψ⁺ = ½K⟨tr E⟩₊² + μ dev E : dev E, J/m³: the energy the damage degrades."""
    K = lam + 2.0 * mu / 3.0
    tr = e00 + e11 + e22
    m3 = tr / 3.0
    dev2 = ((e00 - m3) ** 2 + (e11 - m3) ** 2 + (e22 - m3) ** 2
            + 2.0 * (e01 * e01 + e02 * e02 + e12 * e12))
    tp = tr if tr > 0.0 else 0.0
    return 0.5 * K * tp * tp + mu * dev2


@njit(**JIT)
def effective_lame(tr, d, lam, mu):
    """(λ', μ') of S = λ' tr E I + 2μ' E at damage d: μ' = (1 − d)μ, λ' = K' − ⅔μ' with
    K' = (1 − d)K in volumetric tension (tr E > 0), K in compression."""
    K = lam + 2.0 * mu / 3.0
    mu_d = (1.0 - d) * mu
    K_d = (1.0 - d) * K if tr > 0.0 else K
    return K_d - 2.0 * mu_d / 3.0, mu_d


@njit(**JIT)
def _green_lagrange(F):
    e00 = 0.5 * (F[0, 0] * F[0, 0] + F[1, 0] * F[1, 0] + F[2, 0] * F[2, 0] - 1.0)
    e11 = 0.5 * (F[0, 1] * F[0, 1] + F[1, 1] * F[1, 1] + F[2, 1] * F[2, 1] - 1.0)
    e22 = 0.5 * (F[0, 2] * F[0, 2] + F[1, 2] * F[1, 2] + F[2, 2] * F[2, 2] - 1.0)
    e12 = 0.5 * (F[0, 1] * F[0, 2] + F[1, 1] * F[1, 2] + F[2, 1] * F[2, 2])
    e02 = 0.5 * (F[0, 0] * F[0, 2] + F[1, 0] * F[1, 2] + F[2, 0] * F[2, 2])
    e01 = 0.5 * (F[0, 0] * F[0, 1] + F[1, 0] * F[1, 1] + F[2, 0] * F[2, 1])
    return e00, e11, e22, e01, e02, e12


# --------------------------------------------------------------------------------------------
# the point routine and the stored energy
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def brittle_point(F, h_old, prm, P, h_new, A, want_tangent):
    """The brittle law at one point (module docstring). F (3, 3); h_old (≥ 4,) history (columns
    beyond 4 are copied); prm the parameter row. Out, in place: P (3, 3), h_new, with
    ``want_tangent`` A (3, 3, 3, 3) (secant in the damage). Returns the status: 0 ok, 2 J ≤ 0
    (P = NaN, history copied). Allocation-free."""
    lam = prm[1]
    mu = prm[2]
    eps_cr = prm[7]
    eps_f = prm[8]
    for m in range(N_HISTORY, h_old.shape[0]):
        h_new[m] = h_old[m]
    cof, J = _cofactor(F)
    if not J > 0.0:
        _fail(P, A, want_tangent)
        for m in range(N_HISTORY):
            h_new[m] = h_old[m]
        return INVERTED
    Emod = mu * (3.0 * lam + 2.0 * mu) / (lam + mu)
    e00, e11, e22, e01, e02, e12 = _green_lagrange(F)
    tr = e00 + e11 + e22
    kappa = h_old[H_KAPPA]
    d_old = h_old[H_DAMAGE]
    d = d_old
    # Gershgorin bound on the largest principal effective stress: below f_t no eigen-solve
    bound = max(e00 + abs(e01) + abs(e02), max(e11 + abs(e01) + abs(e12), e22 + abs(e02) + abs(e12)))
    if d_old < 1.0 and (lam * tr + 2.0 * mu * bound) / Emod > max(eps_cr, kappa):
        kappa = max(kappa, equivalent_strain(e00, e11, e22, e01, e02, e12, lam, mu, Emod))
        d = max(d_old, damage(kappa, eps_cr, eps_f))
    psi_p = tensile_energy(e00, e11, e22, e01, e02, e12, lam, mu)
    h_new[H_KAPPA] = kappa
    h_new[H_DAMAGE] = d
    h_new[H_W_RELEASED] = h_old[H_W_RELEASED] + 0.5 * (h_old[H_PSI_PLUS] + psi_p) * (d - d_old)
    h_new[H_PSI_PLUS] = psi_p
    lam_d, mu_d = effective_lame(tr, d, lam, mu)
    # Saint Venant–Kirchhoff with the degraded constants: a row (code, λ', μ') as a tuple, so that
    # the array version of svk_point, the elastic laws' hot path, is compiled untouched
    return svk_point(F, (0.0, lam_d, mu_d), P, A, want_tangent)


@njit(**JIT)
def brittle_energy(F, h, prm):
    """Stored energy per unit reference volume, J/m³, at F with the history h held fixed:
    ψ = (1 − d) ψ⁺ + ψ⁻ (module docstring). NaN if J ≤ 0."""
    cof, J = _cofactor(F)
    if not J > 0.0:
        return np.nan
    lam = prm[1]
    mu = prm[2]
    e00, e11, e22, e01, e02, e12 = _green_lagrange(F)
    tr = e00 + e11 + e22
    lam_d, mu_d = effective_lame(tr, h[H_DAMAGE], lam, mu)
    ee = e00 * e00 + e11 * e11 + e22 * e22 + 2.0 * (e01 * e01 + e02 * e02 + e12 * e12)
    return 0.5 * lam_d * tr * tr + mu_d * ee
