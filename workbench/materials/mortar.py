"""Mortar of paper 003 (Tokumaru, Sonoda, Fukazawa & Mokhatar, Proc. JCI 33(2), 2011, §3.2–3.3):
tension softening by stress release on an orthotropic degraded elastic matrix, Mises plasticity in
compression. Law code 4 of :mod:`workbench.materials`; built by :meth:`Material.mortar`.

The law (small strain in the paper; here in the Green–Lagrange strain, see below)
--------------------------------------------------------------------------------------
* Strain: E = ½(FᵀF − I), additive split E = E_e + E_p (Green–Naghdi), second Piola–Kirchhoff
  stress S from the degraded matrix, P = F S. Why Green–Lagrange: the law then lives in the
  reference frame, so it is objective without a stress rate (003 integrates a Jaumann rate), the
  damage tensor and E_p are reference tensors a rigid rotation leaves alone, the stress work is
  exactly ∫S:dE, the undamaged elastic law is the library's Saint Venant–Kirchhoff law (law 0), and
  its tangent is a short formula. At mortar strains (≤ 2·10⁻²) E differs from the Hencky strain by
  O(ε²) (< 1 %); large compressions, where SVK softens, are not the mortar's regime.
* Damage (003 §3.2 steps (1)–(3), Fig. 9, eq. 6), on a fixed orthogonal crack frame: the damage
  is a symmetric tensor Ω = Σ D_i m_i⊗m_i in the reference frame (the paper's D^L "rotated to the
  global axes by direction cosines"). Its crack axes m_i (D_i > 0) are set when the point first
  cracks and do not turn afterwards (:func:`crack_frame`): a virgin point takes the principal
  directions of the step's trial elastic strain; with one crack the two other axes are the
  principal directions of the strain in the plane normal to it; with two the third is fixed. Along
  each axis the damage is raised from the normal strain κ_i = m_i·E_e·m_i when κ_i > ε_cr = f_t/E,
  to D(κ_i) = 1 − φ(κ_i) (:func:`reduction_factor`, :func:`damage_value`), "the largest value
  reached kept" (:func:`raise_damage`). Past ε_0 the stored value is κ/ε_0 ≥ 1 (φ = 0 either
  way): it keeps two fully released axes apart, so that Ω's eigenbasis stays the crack frame.
  The paper re-evaluates principal strains every step without saying how the kept maxima follow a
  turning direction; raising Ω along turning principal directions (this law's first version) is
  not dissipative (see "Dissipation"). With a fixed frame it is, and for a crack that does not
  turn it is the same law.
* Dissipation (tension-only growth, :func:`cap_release`): at a fixed strain the stored energy is
  W = ½λ(Σφ̂_k e_k)² + μΣφ̂_k² e_k² + 2μΣ α_ij e_ij² in the crack frame (e_k = m_k·E_e·m_k,
  φ̂_k = φ_k on an open axis, 1 on a closed one), a quadratic in the open factors with gradient
  ∂W/∂φ_i = e_i b_i, b_i = (λ + 2μ)φ_i e_i + λΣ_k≠i φ̂_k e_k the normal stress σ'_ii over φ_i.
  Lowering φ_i therefore raises W wherever the normal stress across the crack is compressive,
  which eq. 6–8 allow (a tensile principal strain under strong lateral compression). So a crack
  grows only while its normal stress stays tensile: φ_i is held, where needed, at b_i ≥ 0 at the
  new factors of the trial strain (a crack does not grow under a compressive normal stress), and
  at b_i ≥ 0 at the mean factors ½(φ_n + φ_n+1) of the step's midpoint strain, which makes the
  step's released energy (below) exactly non-negative whenever the midpoint is the trial's
  (elastic steps). A consequence: uniaxial compression cracks nothing laterally in an elastic
  step (the lateral normal stress is zero, a crack there would release nothing); the paper's
  strain criterion would crack it once |σ| > f_t/ν.
* Reduction factors (eq. 6): φ_i = 1 − ω_i (clipped to [0, 1]) along the principal axes m_i of Ω
  (:func:`crack_frame`). 003 applies φ along the global x, y, z; here along the damage axes, which
  are the global axes whenever the cracks are, and which make the law objective and the same for a
  rotated path (the paper's diagonal-only D^G is not).
* Release rates (eq. 7) and the degraded matrix (eq. 8, after Carol, Rizzi & Willam 2001), in the
  damage frame (:func:`degraded_stress`):
  σ'_ii = φ̂_i (λ Σ_k φ̂_k e'_kk + 2μ φ̂_i e'_ii),  σ'_ij = 2μ φ̃_i φ̃_j e'_ij (i ≠ j),
  i.e. α_ii = φ_i² on the diagonal, φ_iφ_j λ coupling, α_ij = φ_iφ_j on shear. Under uniaxial
  stress along a damaged axis the compliance of this matrix is 1/(φ²E): σ = α_xx E ε exactly, which
  is what lets eq. 6–7 carry the softening curve of Fig. 8.
* Tension only (003: "these reductions act in tension only, not in compression"): the normal
  factor of axis i is φ̂_i = φ_i while the crack is open (m_i·E_e·m_i > 0, read from the trial
  elastic strain of the step, see "Order in a step") and 1 once it closes, so a closed crack carries compression as
  virgin mortar; damage never grows from compressive strain. The shear factors keep φ̃ (open or
  closed): then the stored energy is continuous when a crack closes (only the normal terms switch,
  and they switch where e'_ii = 0), and no energy is created by closure. (Full recovery of the
  shear terms on closure would make the energy jump by 2μ(1 − φ_i)φ_j e'_ij².)
* Linear release (Fig. 7–8, eq. 5, §4.1): uniaxial stress rises as E ε to f_t at ε_cr = f_t/E and
  falls linearly to zero at the release strain ε_0, σ = f_t(ε_0 − ε)/(ε_0 − ε_cr); the area under
  the curve, ½ f_t ε_0, is the fracture energy over the particle size, g_F = G_F/h (eq. 5). So
  φ(κ)² E κ = f_t(ε_0 − κ)/(ε_0 − ε_cr), i.e. φ = √(ε_cr (ε_0 − κ)/(κ (ε_0 − ε_cr))) on
  ε_cr < κ < ε_0, 1 below, 0 from ε_0 on. 003 §4.1 sets ε_0 = 17 000 µ for 5 mm particles: with
  f_t = 1.61 MPa that is G_F = ½ f_t ε_0 h = 68.4 N/m (:func:`fracture_energy`).
* What eq. 6 says, literally: "D^L = ε^L/0.001; we assumed that tensile failure occurs in a
  direction when its principal strain reaches 1000 µ and defined D so that φ is almost 0 there;
  D keeps its largest past value; φ ≥ 0.05 against instability from an extreme loss of interaction
  with the neighbours; the reductions act in tension only". Taken literally with α = φ², uniaxial
  stress would be σ = E ε (1 − ε/0.001)² from ε = 0 (no elastic range; peak 4/27·E·0.001 =
  1.76 MPa at 333 µ; φ = 0.05 at 950 µ; area E·0.001²/12 = 992 J/m³ ≈ 5 N/m at 5 mm), which
  contradicts §4.1 (full release at 17 000 µ), Fig. 14 (elastic to f_t) and eq. 5. We keep eq. 6's
  structure (damage from principal strains, φ = 1 − D, maximum kept, φ floor, eq. 7 rates) and
  replace D = ε/0.001 by the D(κ) above that realises the linear release of Fig. 8 to ε_0.
* The floor φ ≥ φ_min (0.05 in 003) is applied to the shear factors φ̃ = max(φ, φ_min) only: on
  the normal terms it would leave a residual stress 0.0025 E ε (0.5 MPa at 17 000 µ, 31 % of f_t)
  and the stress could never be "completely released" as §4.1 states. A fully released direction
  (φ = 0) thus still transfers a little shear, 2μ φ_min φ_j e'_ij, as the floor intends.
* Shear retention (the default; not 003): with ``shear_retention`` β > 0 the shear rates do not
  follow the opening. Once an axis has cracked (D_i > 0), every shear rate of a pair it belongs to
  is the constant β, α_ij = β if D_i > 0 or D_j > 0, else 1 (a fixed smeared crack with constant
  shear retention, Rots 1988, Rots & Blaauwendraad 1989: β = 0.05–0.2). Why: with eq. 7's rates
  α_ij = φ̃_iφ̃_j a crack that slides as it opens releases 2μ e'_ij²(−dα_ij) on top of its normal
  g_F, 1.14–5.64 g_F per axis on the path of ``studies/rc_beam/diagnose.tension_shear_path``
  (E_xy = 0 to 1 × (E_xx − 2ε_cr)); on the RC beam that is most of the released energy
  (studies/rc_beam/notes.md). With a constant rate the shear terms are a fixed quadratic of the
  strain once a crack is set, so a crack releases its normal g_F only ((λ + 2μ)/E g_F under
  uniaxial strain, whatever it slides). The drop 1 → β happens in the step an axis first cracks,
  where the frame is the principal frame of the step's trial strain (a first crack) or of its
  block normal to the crack (a second), so e'_ij = 0 there at the trial strain and the drop
  stores and releases (almost) nothing: the midpoint rule books 2μ(1 − β)e'_m,ij² of the step's
  midpoint strain, second order in the step. β is the same open or closed (the stored energy stays
  continuous at closure, as above) and φ_min no longer enters the law (it remains the kernel
  reduction's factor of 003 §4.2(2), :mod:`sph.classic`). Default β = 0.05: the low end of the
  fixed-crack range (a larger β locks stress across a crack whose principal directions turn,
  Rots 1988), and 003's own shear floor φ_min, so that a fully released axis against an uncracked
  one transfers the same shear as in 003 (2μ·0.05 e'_ij). β = 0 (``shear_retention=0``) is eq. 7
  as printed, for 003's comparisons.
* Fully released (for the kernel reduction of 003 §4.2(2), which belongs to the particle method):
  history column :data:`H_RELEASED` is 1.0 once some eigenvalue of Ω has reached 1 (a crack axis
  with φ = 0), else 0.0.
* Compression: associative Mises plasticity on S with linear isotropic hardening,
  σ_y = f_c + H ε̄_p, H = E/99 by default (uniaxial post-yield slope E H/(E + H) = E/100, Fig. 14).
  Return mapping (:func:`closest_point_return`): elastic trial S_tr = 𝒞:(E − E_p,n) with the
  step's degraded matrix 𝒞, then backward Euler, S + Δγ 𝒞:n(S) = S_tr and
  q(S) = σ_y(ε̄_p,n + Δγ), n = (3/2) s/q, i.e. the closest-point projection in the metric of 𝒞,
  by Newton on (S, Δγ) with backtracking, started from the step along the trial direction
  (:func:`trial_direction_step`, a quadratic in Δγ). For the undamaged (isotropic) matrix that
  start is the radial return and already the solution. (The trial-direction step alone has no root
  for about one in six strongly damaged states: the Newton is needed there.)
  Order in a step (the state is explicit in the step): the damage is raised and the open/closed
  state read from the trial elastic strain E − E_p,n, then the return is made with them. This is
  exact for elastic steps (the trial is the final elastic strain; a damaging step included) and
  for plastic steps that change neither. Where flow and cracking act in the same step, the damage
  is driven by the trial elastic strain (first order in the step: too much where the flow undoes
  a tensile elastic strain) and a crack that the return closes or opens keeps its trial state.
  (Iterating damage, open/closed state and return to a fixed point was tried: on heavily cracked
  points the softening–flow feedback converges slowly and a crack at closure alternates between
  its states — the consistent state lies on the switch, where σ'_ii is undetermined — so it did
  not settle within a few passes for ~40 % of such points. The explicit state is the documented
  choice.)
* Energies per unit reference volume: stored W = ½ E_e:𝒞:E_e (:func:`mortar_energy`), a
  hyperelastic potential at fixed damage; plastic work ΔW_p = (σ_y,n + ½HΔγ)Δγ (= ∫σ_y dε̄_p,
  exact for linear hardening); released (cracking) energy ΔW_r = W(E_m; Ω_n) − W(E_m; Ω_n+1), the
  elastic energy lost when the stiffness drops from the old to the new damage, at the midpoint
  E_m = ½(E_e,n + E_e,n+1) of the step's elastic strains (E_e,n is kept in the history): the
  midpoint rule for ∫ −½ E_e:d𝒞:E_e, second order in the step (along a uniaxial release in equal
  steps Δε its sum exceeds the exact ½ f_t ε_0 by exactly EΔε²/8). Then ∫S:dE ≈ W + W_p + W_r.
* Tangent A = dP/dF: exact for the algorithm at fixed damage (elastic steps; plastic steps: the
  consistent tangent of the return, dS/dE = (J⁻¹)_SS 𝒞 with J the Newton matrix at the solution,
  the classical one when undamaged); in a step where the damage grows the damage is held at its new
  value (secant in the damage), so A is the degraded tangent, not the softening one. The
  open/closed state is held (exact away from e'_ii = 0).

Parameter slots (``prm``, law 4): 0 law code 4; 1 Lamé λ, Pa; 2 μ, Pa; 3 f_t, Pa; 4 release strain
ε_0, -; 5 f_c (initial Mises yield stress), Pa; 6 hardening modulus H, Pa; 7 φ_min, -; 8 shear
retention β (0: eq. 7's rates as printed);
9 relative tolerance of the yield check.

History layout (:data:`N_HISTORY` = 23 columns; the point routine copies any columns beyond):

======  ====================================================================================
col     meaning
======  ====================================================================================
0–5     plastic Green–Lagrange strain E_p (xx, yy, zz, yz, xz, xy), reference frame
6–11    damage tensor Ω (xx, yy, zz, yz, xz, xy), reference frame (eigenvalues ≥ 1: κ/ε_0)
12      equivalent plastic strain ε̄_p
13      plastic work W_p, J/m³ (reference volume)
14      released (cracking) energy W_r, J/m³ (reference volume)
15      largest damage eigenvalue, clipped to [0, 1] (0: virgin; for field output)
16      fully released flag (1.0 / 0.0), see above
17–22   elastic strain E_e at the end of the step (xx, yy, zz, yz, xz, xy), for the midpoint
        rule of the released energy in the next step
======  ====================================================================================

A virgin point has all columns zero (so :meth:`Material.initial_history` needs no special case).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .elastic import svk_point
from .tensor import INVERTED, JIT, NEWTON_MAXIT, NOT_CONVERGED, OK, _cofactor, _fail
from .tensor import eig_sym3_closed as eig_sym3

LAW_CODE = 4
N_HISTORY = 23
H_EP = 0          # E_p, 6 columns
H_OMEGA = 6       # Ω, 6 columns
H_EPS_P = 12      # ε̄_p
H_W_PLASTIC = 13  # plastic work, J/m³
H_W_RELEASED = 14  # released (cracking) energy, J/m³
H_DAMAGE = 15     # largest damage eigenvalue
H_RELEASED = 16   # fully released flag
H_EE = 17         # elastic strain at the end of the step, 6 columns

# symmetric-tensor component order of the history (Voigt): xx, yy, zz, yz, xz, xy
_VI = (0, 1, 2, 1, 0, 0)
_VJ = (0, 1, 2, 2, 2, 1)
SQRT2 = math.sqrt(2.0)
DAMAGE_RESOLUTION = 1e-13  # smaller raises are round-off of n·Ω·n (~1e-16), not damage
OMEGA_CRACKED = 0.5 * DAMAGE_RESOLUTION  # an eigenvalue of Ω above this marks a crack axis


# the constants of a material (release strain, checks, parameter slots): .mortar_constants
from .mortar_constants import (check_material, fracture_energy, pack_params,  # noqa: F401, E402
                               release_strain)


# --------------------------------------------------------------------------------------------
# the equations
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def reduction_factor(kappa, eps_cr, eps_0):
    """003 eq. 6 (φ = 1 − D) with D(κ) chosen so that uniaxial stress follows the linear release of
    Fig. 8 (see the module docstring): φ = 1 for κ ≤ ε_cr, √(ε_cr(ε_0 − κ)/(κ(ε_0 − ε_cr))) on
    (ε_cr, ε_0), 0 from ε_0 on; κ the principal tensile strain."""
    if kappa <= eps_cr:
        return 1.0
    if kappa >= eps_0:
        return 0.0
    return math.sqrt(eps_cr * (eps_0 - kappa) / (kappa * (eps_0 - eps_cr)))


@njit(**JIT)
def _max_eig_bound(e):
    """Gershgorin bound on the largest eigenvalue of a symmetric 3×3 matrix."""
    b0 = e[0, 0] + abs(e[0, 1]) + abs(e[0, 2])
    b1 = e[1, 1] + abs(e[0, 1]) + abs(e[1, 2])
    b2 = e[2, 2] + abs(e[0, 2]) + abs(e[1, 2])
    return max(b0, max(b1, b2))


@njit(**JIT)
def factor(d):
    """The reduction factor of a damage value: φ = 1 − D clipped to [0, 1] (eq. 6)."""
    return min(1.0, max(0.0, 1.0 - d))


@njit(**JIT)
def damage_value(kappa, eps_cr, eps_0):
    """The damage along a crack axis whose normal strain has reached κ (eq. 6, φ = 1 − D):
    1 − φ(κ) (:func:`reduction_factor`) below ε_0, and κ/ε_0 ≥ 1 from ε_0 on, where φ = 0. The
    value beyond 1 changes nothing in the law (φ = max(0, 1 − D)); it keeps two fully released
    axes apart, so that the crack frame stays the eigenbasis of Ω."""
    if kappa >= eps_0:
        return kappa / eps_0
    return 1.0 - reduction_factor(kappa, eps_cr, eps_0)


@njit(**JIT)
def crack_frame(Om, cracked, Ee, a, Q, om):
    """The fixed orthogonal crack frame of a step (module docstring, "Damage").

    Om (3, 3) damage tensor (not modified), ``cracked``: whether it is non-zero; Ee (3, 3) the
    trial elastic strain; a (3, 3) scratch. Out: Q (3, 3) the axes as columns, om (3,) the damage
    along them, the crack axes (om > :data:`OMEGA_CRACKED`) first. The crack axes are the
    eigenvectors of Ω and do not turn; the axes not yet cracked span the rest, and there they are
    the principal directions of Ee's block (all three with no crack; a rotation in the plane
    normal to a single crack; the remaining direction with two). Returns the number of crack axes."""
    for i in range(3):
        om[i] = 0.0
    if cracked:
        for i in range(3):
            for j in range(3):
                a[i, j] = Om[i, j]
        eig_sym3(a, Q)
        for i in range(3):
            om[i] = a[i, i] if a[i, i] > OMEGA_CRACKED else 0.0
        for i in range(2):  # sort the axes by decreasing damage (three elements)
            for j in range(2 - i):
                if om[j] < om[j + 1]:
                    t = om[j]
                    om[j] = om[j + 1]
                    om[j + 1] = t
                    for r in range(3):
                        t = Q[r, j]
                        Q[r, j] = Q[r, j + 1]
                        Q[r, j + 1] = t
    k = 0
    for i in range(3):
        if om[i] > 0.0:
            k += 1
    if k == 0:
        for i in range(3):
            for j in range(3):
                a[i, j] = Ee[i, j]
        eig_sym3(a, Q)
    elif k == 1:
        e11 = 0.0
        e22 = 0.0
        e12 = 0.0
        for i in range(3):
            for j in range(3):
                e11 += Q[i, 1] * Ee[i, j] * Q[j, 1]
                e22 += Q[i, 2] * Ee[i, j] * Q[j, 2]
                e12 += Q[i, 1] * Ee[i, j] * Q[j, 2]
        th = 0.5 * math.atan2(2.0 * e12, e11 - e22)
        c = math.cos(th)
        s = math.sin(th)
        for r in range(3):
            u = Q[r, 1]
            v = Q[r, 2]
            Q[r, 1] = c * u + s * v
            Q[r, 2] = -s * u + c * v
    return k


@njit(**JIT)
def normal_strains(Q, e, out):
    """out[i] = m_i·e·m_i, the normal strains of e (3, 3) along the axes m_i (columns of Q)."""
    for A_ in range(3):
        s = 0.0
        for i in range(3):
            for j in range(3):
                s += Q[i, A_] * e[i, j] * Q[j, A_]
        out[A_] = s


@njit(**JIT)
def cap_release(e, phi_old, phi, lam, mu, midpoint):
    """Tension-only growth (module docstring, "Dissipation"). The normal stress of eq. 8 on axis
    i over its factor is b_i(φ) = (λ + 2μ)φ_i e_i + λ Σ_k≠i φ̂_k e_k (φ̂_k = φ_k open, 1 closed);
    along every open axis (e_i > 0) whose factor drops in the step, φ_i is raised, if need be (never
    above φ_i,old), until b_i ≥ 0 at the new factors, or, with ``midpoint``, at the mean factors
    ½(φ_old + φ). The stored energy at fixed e is a quadratic in the open factors whose gradient
    is e_i b_i, so W(φ) − W(φ_old) = Σ e_i b_i(½(φ_old + φ)) (φ_i − φ_i,old): either condition
    makes it ≤ 0; the first also leaves no compressive normal stress on a growing crack. e (3,)
    normal strains along the crack axes; phi_old, phi (3,), phi in place. Every axis is capped
    from the factors before the pass (one simultaneous pass, so that axes in the same state get
    the same cap): raising φ_k only raises every b_i, so afterwards all of them are ≥ 0."""
    c = lam + 2.0 * mu
    new0 = phi[0]
    new1 = phi[1]
    new2 = phi[2]
    for i in range(3):
        if e[i] > 0.0 and phi[i] < phi_old[i]:
            r = 0.0
            for k in range(3):
                if k != i:
                    f = 0.5 * (phi_old[k] + phi[k]) if midpoint else phi[k]
                    r += (f if e[k] > 0.0 else 1.0) * e[k]
            # b_i at the mean (midpoint) or new factor f_i; its root f* = −λr/((λ + 2μ)e_i)
            f_i = 0.5 * (phi_old[i] + phi[i]) if midpoint else phi[i]
            v = phi[i]
            if c * f_i * e[i] + lam * r < 0.0:
                f_star = -lam * r / (c * e[i])
                v = min(phi_old[i], 2.0 * f_star - phi_old[i] if midpoint else f_star)
            if i == 0:
                new0 = v
            elif i == 1:
                new1 = v
            else:
                new2 = v
    phi[0] = new0
    phi[1] = new1
    phi[2] = new2


@njit(**JIT)
def raise_damage(e_tr, e_mid, om_old, om, phi_old, phi, eps_cr, eps_0, lam, mu):
    """003 §3.2 steps (1)–(3) and eq. 6 on the fixed crack frame (:func:`crack_frame`).

    e_tr (3,) the trial elastic strain's normal strains along the axes; e_mid (3,) those of the
    step's midpoint elastic strain ½(E_e,n + trial); om_old (3,) the damage along the axes. Out:
    om (3,) the new damage: D(κ_i) (:func:`damage_value`) where κ_i = e_tr,i > ε_cr exceeds the old
    value by more than :data:`DAMAGE_RESOLUTION` (the largest value kept), then capped by
    :func:`cap_release` at e_tr and at e_mid; phi_old, phi (3,) the factors 1 − D clipped to
    [0, 1]. Returns the largest raise (0.0: no growth)."""
    for i in range(3):
        om[i] = om_old[i]
        phi_old[i] = factor(om_old[i])
        if e_tr[i] > eps_cr:
            d = damage_value(e_tr[i], eps_cr, eps_0)
            if d > om_old[i] + DAMAGE_RESOLUTION:
                om[i] = d
        phi[i] = factor(om[i])
    cap_release(e_tr, phi_old, phi, lam, mu, False)
    cap_release(e_mid, phi_old, phi, lam, mu, True)
    grew = 0.0
    for i in range(3):
        if phi[i] > factor(om[i]):  # capped: the damage of the raised factor
            om[i] = 1.0 - phi[i]
        if om[i] > om_old[i] + DAMAGE_RESOLUTION:
            grew = max(grew, om[i] - om_old[i])
        else:
            om[i] = om_old[i]
            phi[i] = phi_old[i]
    return grew


@njit(**JIT)
def release_state(Q, phi, phi_min, beta, e_sign, st):
    """The factors of eq. 7–8 at a point. st[0:3]: normal factors φ̂_i = φ_i along an open axis
    (m_i·e_sign·m_i > 0), 1 along a closed one (tension only); st[3:6]: shear release rates
    α_yz, α_xz, α_xy of the damage frame: with the shear retention β > 0 the constant β on a pair
    with a cracked axis (φ < 1) and 1 otherwise (module docstring, "Shear retention"); with β = 0
    eq. 7 as printed, φ̃_jφ̃_k, φ̃ = max(φ, φ_min)."""
    for i in range(3):
        en = 0.0
        for k in range(3):
            for l in range(3):
                en += Q[k, i] * e_sign[k, l] * Q[l, i]
        st[i] = phi[i] if en > 0.0 else 1.0
    if beta > 0.0:
        r0 = beta if phi[0] < 1.0 else 1.0
        r1 = beta if phi[1] < 1.0 else 1.0
        r2 = beta if phi[2] < 1.0 else 1.0
        st[3] = min(r1, r2)
        st[4] = min(r0, r2)
        st[5] = min(r0, r1)
        return
    f0 = max(phi[0], phi_min)
    f1 = max(phi[1], phi_min)
    f2 = max(phi[2], phi_min)
    st[3] = f1 * f2
    st[4] = f0 * f2
    st[5] = f0 * f1


@njit(**JIT)
def degraded_stress(e, Q, st, lam, mu, tmp, out):
    """003 eq. 8 (orthotropic degraded matrix after Carol et al.) in the damage frame:
    e' = Qᵀ e Q; σ'_ii = φ̂_i(λ Σ_k φ̂_k e'_kk + 2μ φ̂_i e'_ii); σ'_ij = 2μ α_ij e'_ij;
    out = Q σ' Qᵀ. e, out (3, 3) symmetric (distinct arrays), Q (3, 3), st (6,) from
    :func:`release_state`, tmp (3, 3) scratch. Linear in e at a fixed state."""
    for i in range(3):
        for j in range(3):
            out[i, j] = e[i, 0] * Q[0, j] + e[i, 1] * Q[1, j] + e[i, 2] * Q[2, j]
    for i in range(3):
        for j in range(i, 3):
            tmp[i, j] = Q[0, i] * out[0, j] + Q[1, i] * out[1, j] + Q[2, i] * out[2, j]
    f0 = st[0]
    f1 = st[1]
    f2 = st[2]
    e00 = f0 * tmp[0, 0]
    e11 = f1 * tmp[1, 1]
    e22 = f2 * tmp[2, 2]
    ltr = lam * (e00 + e11 + e22)
    s00 = f0 * (ltr + 2.0 * mu * e00)
    s11 = f1 * (ltr + 2.0 * mu * e11)
    s22 = f2 * (ltr + 2.0 * mu * e22)
    s12 = 2.0 * mu * st[3] * tmp[1, 2]
    s02 = 2.0 * mu * st[4] * tmp[0, 2]
    s01 = 2.0 * mu * st[5] * tmp[0, 1]
    # tmp = σ' Qᵀ, out = Q tmp
    for j in range(3):
        q0 = Q[j, 0]
        q1 = Q[j, 1]
        q2 = Q[j, 2]
        tmp[0, j] = s00 * q0 + s01 * q1 + s02 * q2
        tmp[1, j] = s01 * q0 + s11 * q1 + s12 * q2
        tmp[2, j] = s02 * q0 + s12 * q1 + s22 * q2
    for i in range(3):
        for j in range(i, 3):
            v = Q[i, 0] * tmp[0, j] + Q[i, 1] * tmp[1, j] + Q[i, 2] * tmp[2, j]
            out[i, j] = v
            out[j, i] = v


@njit(**JIT)
def _ddot(a, b):
    s = 0.0
    for i in range(3):
        for j in range(3):
            s += a[i, j] * b[i, j]
    return s


@njit(**JIT)
def _dev(a, out):
    """out = dev a (3×3); returns tr a / 3."""
    p = (a[0, 0] + a[1, 1] + a[2, 2]) / 3.0
    for i in range(3):
        for j in range(3):
            out[i, j] = a[i, j]
    for i in range(3):
        out[i, i] -= p
    return p


@njit(**JIT)
def _mandel(t, v):
    """Mandel vector of a symmetric 3×3 tensor: (xx, yy, zz, √2 yz, √2 xz, √2 xy)."""
    v[0] = t[0, 0]
    v[1] = t[1, 1]
    v[2] = t[2, 2]
    v[3] = SQRT2 * t[1, 2]
    v[4] = SQRT2 * t[0, 2]
    v[5] = SQRT2 * t[0, 1]


@njit(**JIT)
def _unmandel(v, t):
    """The symmetric 3×3 tensor of a Mandel vector."""
    t[0, 0] = v[0]
    t[1, 1] = v[1]
    t[2, 2] = v[2]
    t[1, 2] = t[2, 1] = v[3] / SQRT2
    t[0, 2] = t[2, 0] = v[4] / SQRT2
    t[0, 1] = t[1, 0] = v[5] / SQRT2


_MI = ((0, 5, 4), (5, 1, 3), (4, 3, 2))  # Mandel index of the pair (i, j)


@njit(**JIT)
def degraded_moduli(Q, st, lam, mu, B, tmp, Sb, v, C):
    """The matrix 𝒞 of eq. 8 in the reference frame, as a Mandel matrix C[0:6, 0:6] (out): its
    columns are eq. 8 applied to the Mandel basis tensors. B, tmp, Sb (3, 3), v (≥ 6,) scratch."""
    for J_ in range(6):
        for i in range(3):
            for j in range(3):
                B[i, j] = 0.0
        if J_ < 3:
            B[J_, J_] = 1.0
        else:
            i = _VI[J_]
            j = _VJ[J_]
            B[i, j] = 1.0 / SQRT2
            B[j, i] = 1.0 / SQRT2
        degraded_stress(B, Q, st, lam, mu, tmp, Sb)
        _mandel(Sb, v)
        for I_ in range(6):
            C[I_, J_] = v[I_]


@njit(**JIT)
def _isotropic_moduli(lam, mu, C):
    """Undamaged 𝒞 = λ 1⊗1 + 2μ I as a Mandel matrix C[0:6, 0:6] (out)."""
    for I_ in range(6):
        for J_ in range(6):
            C[I_, J_] = (lam if (I_ < 3 and J_ < 3) else 0.0) + (2.0 * mu if I_ == J_ else 0.0)


@njit(**JIT)
def trial_direction_step(q_tr, sy, H, s_tr, s_a):
    """Starting point of the return: the smallest Δγ > 0 with
    (3/2)|s_tr − Δγ s_a|² = (σ_y + HΔγ)² along the trial flow direction n_tr = (3/2)s_tr/q_tr,
    s_a = dev 𝒞:n_tr (Mandel vectors), a quadratic solved in its cancellation-free form. For the
    isotropic matrix s_a ∥ s_tr and this is the radial return Δγ = (q_tr − σ_y)/(3μ + H), the
    exact solution. Returns (Δγ, found)."""
    ss = 0.0
    aa = 0.0
    for I_ in range(6):
        ss += s_tr[I_] * s_a[I_]
        aa += s_a[I_] * s_a[I_]
    a2 = 1.5 * aa - H * H
    a1 = -(3.0 * ss + 2.0 * H * sy)
    a0 = q_tr * q_tr - sy * sy
    disc = a1 * a1 - 4.0 * a2 * a0
    den = -a1 + math.sqrt(max(disc, 0.0))
    if disc >= 0.0 and den > 0.0:
        return 2.0 * a0 / den, True
    return 0.0, False


@njit(**JIT)
def _mises_residual(C, sig, sig_tr, dg, sy_n, H, n, Cn, r):
    """Residual of the return (Mandel vectors): r[0:6] = σ − σ_tr + Δγ 𝒞n, r[6] = q − σ_y,n − HΔγ,
    with n = (3/2) dev σ / q written to n and 𝒞n to Cn. Returns (|r|, q)."""
    tr3 = (sig[0] + sig[1] + sig[2]) / 3.0
    ss = 0.0
    for I_ in range(6):
        s = sig[I_] - (tr3 if I_ < 3 else 0.0)
        n[I_] = s
        ss += s * s
    q = math.sqrt(1.5 * ss)
    c = 1.5 / q
    for I_ in range(6):
        n[I_] *= c
    norm = 0.0
    for I_ in range(6):
        v = 0.0
        for K in range(6):
            v += C[I_, K] * n[K]
        Cn[I_] = v
        r[I_] = sig[I_] - sig_tr[I_] + dg * v
        norm += r[I_] * r[I_]
    r[6] = q - sy_n - H * dg
    return math.sqrt(norm + r[6] * r[6]), q


@njit(**JIT)
def _mises_jacobian(C, dg, q, n, Cn, H, Jm):
    """∂r/∂(σ, Δγ) = [[I + Δγ 𝒞N, 𝒞n], [nᵀ, −H]] with N = ∂n/∂σ = (3/2q)(P_dev − ⅔ n⊗n), so
    (𝒞N)_IK = (3/2q)(C_IK − [K normal] ⅓ Σ_L normal C_IL − ⅔ (𝒞n)_I n_K). Jm (7, 7) out."""
    c = 1.5 / q
    for I_ in range(6):
        row3 = (C[I_, 0] + C[I_, 1] + C[I_, 2]) / 3.0
        for K in range(6):
            CN = c * (C[I_, K] - (row3 if K < 3 else 0.0) - 2.0 / 3.0 * Cn[I_] * n[K])
            Jm[I_, K] = (1.0 if I_ == K else 0.0) + dg * CN
        Jm[I_, 6] = Cn[I_]
        Jm[6, I_] = n[I_]
    Jm[6, 6] = -H


@njit(**JIT)
def _gauss_solve(Jm, X, nrhs):
    """Solve Jm Y = X[:, :nrhs] in place (7 × 7, Gaussian elimination with partial pivoting);
    Jm is destroyed, X holds Y. Returns False if a pivot is zero."""
    n = 7
    for k in range(n):
        p = k
        big = abs(Jm[k, k])
        for i in range(k + 1, n):
            if abs(Jm[i, k]) > big:
                big = abs(Jm[i, k])
                p = i
        if big == 0.0:
            return False
        if p != k:
            for j in range(k, n):
                t = Jm[k, j]
                Jm[k, j] = Jm[p, j]
                Jm[p, j] = t
            for j in range(nrhs):
                t = X[k, j]
                X[k, j] = X[p, j]
                X[p, j] = t
        for i in range(k + 1, n):
            f = Jm[i, k] / Jm[k, k]
            for j in range(k + 1, n):
                Jm[i, j] -= f * Jm[k, j]
            for j in range(nrhs):
                X[i, j] -= f * X[k, j]
    for k in range(n - 1, -1, -1):
        for j in range(nrhs):
            s = X[k, j]
            for i in range(k + 1, n):
                s -= Jm[k, i] * X[i, j]
            X[k, j] = s / Jm[k, k]
    return True


@njit(**JIT)
def closest_point_return(C, sig_tr, sy_n, H, tol, dg, sig, n, Cn, r, Jm, X, sig_try):
    """Mises plasticity of 003 §3.3 by backward Euler, the closest-point projection in the metric
    of the degraded matrix 𝒞 (Mandel C): σ + Δγ 𝒞:n(σ) = σ_tr, q(σ) = σ_y,n + HΔγ, by Newton on
    (σ, Δγ) with backtracking on |r|, from the start (sig, dg) given (the trial-direction step:
    for the isotropic matrix already the solution). sig (6,) in: start, out: solution; n, Cn:
    n(σ) and 𝒞n at the solution. Returns (Δγ, converged, q)."""
    big = 0.0
    for I_ in range(6):
        big = max(big, abs(sig_tr[I_]))
    scale = tol * sy_n + 64.0 * 2.2e-16 * big  # requested accuracy, or round-off of r
    res, q = _mises_residual(C, sig, sig_tr, dg, sy_n, H, n, Cn, r)
    for it in range(NEWTON_MAXIT):
        if res <= scale:
            return dg, True, q
        _mises_jacobian(C, dg, q, n, Cn, H, Jm)
        for i in range(7):
            X[i, 0] = -r[i]
        if not _gauss_solve(Jm, X, 1):
            return dg, False, q
        step = 1.0
        for ls in range(40):
            for I_ in range(6):
                sig_try[I_] = sig[I_] + step * X[I_, 0]
            dg_try = max(dg + step * X[6, 0], 0.0)
            res_try, q_try = _mises_residual(C, sig_try, sig_tr, dg_try, sy_n, H, n, Cn, r)
            if res_try < res:
                break
            step *= 0.5
        for I_ in range(6):
            sig[I_] = sig_try[I_]
        dg = dg_try
        res = res_try
        q = q_try
    return dg, res <= scale, q


@njit(**JIT)
def _first_piola_tangent(F, S, D, A):
    """A_ijkl = δ_ik S_lj + Σ_pq F_ip 𝔻_pjql F_kq, 𝔻 the 4th-order form of the Mandel matrix D
    (𝔻_ijkl = D[I(ij), J(kl)] c_I c_J, c = 1 on normal and 1/√2 on shear pairs)."""
    G = np.empty((3, 3, 3, 3))
    for p in range(3):
        for j in range(3):
            I_ = _MI[p][j]
            cI = 1.0 if I_ < 3 else 1.0 / SQRT2
            for l in range(3):
                for k in range(3):
                    s = 0.0
                    for q in range(3):
                        J_ = _MI[q][l]
                        cJ = 1.0 if J_ < 3 else 1.0 / SQRT2
                        s += D[I_, J_] * cI * cJ * F[k, q]
                    G[p, j, k, l] = s
    for i in range(3):
        for j in range(3):
            for k in range(3):
                for l in range(3):
                    v = F[i, 0] * G[0, j, k, l] + F[i, 1] * G[1, j, k, l] + F[i, 2] * G[2, j, k, l]
                    if i == k:
                        v += S[l, j]
                    A[i, j, k, l] = v


# --------------------------------------------------------------------------------------------
# the point routine and the stored energy
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def _green_lagrange(F):
    e00 = 0.5 * (F[0, 0] * F[0, 0] + F[1, 0] * F[1, 0] + F[2, 0] * F[2, 0] - 1.0)
    e11 = 0.5 * (F[0, 1] * F[0, 1] + F[1, 1] * F[1, 1] + F[2, 1] * F[2, 1] - 1.0)
    e22 = 0.5 * (F[0, 2] * F[0, 2] + F[1, 2] * F[1, 2] + F[2, 2] * F[2, 2] - 1.0)
    e12 = 0.5 * (F[0, 1] * F[0, 2] + F[1, 1] * F[1, 2] + F[2, 1] * F[2, 2])
    e02 = 0.5 * (F[0, 0] * F[0, 2] + F[1, 0] * F[1, 2] + F[2, 0] * F[2, 2])
    e01 = 0.5 * (F[0, 0] * F[0, 1] + F[1, 0] * F[1, 1] + F[2, 0] * F[2, 1])
    return e00, e11, e22, e12, e02, e01


@njit(**JIT)
def _elastic_strain(F, h, Ee):
    """Ee = E(F) − E_p (history columns 0–5)."""
    e00, e11, e22, e12, e02, e01 = _green_lagrange(F)
    Ee[0, 0] = e00 - h[0]
    Ee[1, 1] = e11 - h[1]
    Ee[2, 2] = e22 - h[2]
    Ee[1, 2] = e12 - h[3]
    Ee[0, 2] = e02 - h[4]
    Ee[0, 1] = e01 - h[5]
    Ee[2, 1] = Ee[1, 2]
    Ee[2, 0] = Ee[0, 2]
    Ee[1, 0] = Ee[0, 1]


@njit(**JIT)
def _load_omega(h, Om):
    for k in range(6):
        v = h[H_OMEGA + k]
        Om[_VI[k], _VJ[k]] = v
        Om[_VJ[k], _VI[k]] = v


@njit(**JIT)
def _midpoint(h_old, E_end, Em):
    """Em = ½(E_e,n + E_end): the step's midpoint elastic strain, E_e,n from the history."""
    for k in range(6):
        v = 0.5 * (h_old[H_EE + k] + E_end[_VI[k], _VJ[k]])
        Em[_VI[k], _VJ[k]] = v
        Em[_VJ[k], _VI[k]] = v


@njit(**JIT)
def _identity_frame(Q, phi):
    for i in range(3):
        phi[i] = 1.0
        for j in range(3):
            Q[i, j] = 1.0 if i == j else 0.0


@njit(**JIT)
def _return(Cm, S, s_tr, q_tr, sy, H, tol, vecs, Jm, X, nf):
    """The plastic corrector of one pass: the start along the trial direction, then
    :func:`closest_point_return`. S (3, 3) in: trial stress, out: returned stress; nf (3, 3) out:
    the flow direction n at the solution; vecs rows 2, 3 out: n and 𝒞n (Mandel) for the tangent.
    Returns (Δγ, converged, q)."""
    sig_tr = vecs[0]
    sig = vecs[1]
    nv = vecs[2]
    Cn = vecs[3]
    r = vecs[4]
    sig_try = vecs[5]
    s_trv = vecs[6]
    s_av = vecs[7]
    _mandel(S, sig_tr)
    _mandel(s_tr, s_trv)
    c = 1.5 / q_tr
    for I_ in range(6):
        nv[I_] = c * s_trv[I_]
    for I_ in range(6):
        v = 0.0
        for K in range(6):
            v += Cm[I_, K] * nv[K]
        Cn[I_] = v
    t3 = (Cn[0] + Cn[1] + Cn[2]) / 3.0
    for I_ in range(6):
        s_av[I_] = Cn[I_] - (t3 if I_ < 3 else 0.0)
    dg0, found = trial_direction_step(q_tr, sy, H, s_trv, s_av)
    for I_ in range(6):
        sig[I_] = sig_tr[I_] - dg0 * Cn[I_]
    dg, conv, q_f = closest_point_return(Cm, sig_tr, sy, H, tol, dg0, sig, nv, Cn, r, Jm, X,
                                         sig_try)
    _unmandel(sig, S)
    _unmandel(nv, nf)
    return dg, conv, q_f


@njit(**JIT)
def mortar_point(F, h_old, prm, P, h_new, A, want_tangent):
    """003 mortar at one point (module docstring). F (3, 3); h_old (≥ 23,) history (columns beyond
    23 are copied to h_new); prm (≥ 10,) parameter row. Out, in place: P (3, 3) first
    Piola–Kirchhoff stress, Pa; h_new; with ``want_tangent`` A (3, 3, 3, 3) = ∂P_ij/∂F_kl, Pa
    (exact at fixed damage, see the module docstring). Returns the status: 0 ok; 1 the Newton of
    the return did not converge (its last iterate is taken); 2 J ≤ 0 (P = NaN, history copied). Virgin elastic
    points take an allocation-free path (the SVK law, law 0); the others one scratch allocation,
    two for a plastic step or with the tangent."""
    lam = prm[1]
    mu = prm[2]
    ft = prm[3]
    eps0 = prm[4]
    fc = prm[5]
    H = prm[6]
    phi_min = prm[7]
    beta = prm[8]
    tol = prm[9]
    Emod = mu * (3.0 * lam + 2.0 * mu) / (lam + mu)
    eps_cr = ft / Emod

    for m in range(N_HISTORY, h_old.shape[0]):
        h_new[m] = h_old[m]
    cof, J = _cofactor(F)
    if not J > 0.0:
        _fail(P, A, want_tangent)
        for m in range(N_HISTORY):
            h_new[m] = h_old[m]
        return INVERTED

    ebar_n = h_old[H_EPS_P]
    damaged_n = h_old[H_DAMAGE] > 0.0
    if ebar_n == 0.0 and not damaged_n:
        # virgin point: when no principal strain can exceed ε_cr (Gershgorin) and S is inside the
        # yield surface, the step is Saint Venant–Kirchhoff: no eigen-solve, no allocation
        e00, e11, e22, e12, e02, e01 = _green_lagrange(F)
        bound = max(e00 + abs(e01) + abs(e02),
                    max(e11 + abs(e01) + abs(e12), e22 + abs(e02) + abs(e12)))
        if bound <= eps_cr:
            tr3 = (e00 + e11 + e22) / 3.0
            d0 = e00 - tr3
            d1 = e11 - tr3
            d2 = e22 - tr3
            q = 2.0 * mu * math.sqrt(1.5 * (d0 * d0 + d1 * d1 + d2 * d2
                                            + 2.0 * (e01 * e01 + e02 * e02 + e12 * e12)))
            if q - fc <= tol * fc:
                for m in range(H_EE):
                    h_new[m] = h_old[m]
                h_new[H_EE] = e00
                h_new[H_EE + 1] = e11
                h_new[H_EE + 2] = e22
                h_new[H_EE + 3] = e12
                h_new[H_EE + 4] = e02
                h_new[H_EE + 5] = e01
                return svk_point(F, prm, P, A, want_tangent)

    w = np.empty((19, 3, 3))  # scratch (one more allocation for a plastic step or the tangent)
    Ee = w[0]      # elastic strain of the step (final)
    Etr = w[1]     # trial elastic strain E − E_p,n
    Om = w[2]      # damage tensor
    Q = w[3]       # damage axes (columns)
    S = w[4]       # second Piola–Kirchhoff stress
    nf = w[5]      # flow direction n
    s_tr = w[7]    # trial deviator
    tmp = w[9]
    a = w[10]
    V = w[11]
    om_o = w[12, 0]         # damage along the crack axes, old
    om = w[12, 1]           # and new
    e_t = w[12, 2]          # normal strains along the axes: of the trial elastic strain
    e_m = w[16, 2]          # and of the midpoint guess ½(E_e,n + trial)
    So = w[13]
    st = w[14].reshape(9)   # factors of eq. 7–8 (6 used)
    sto = w[15].reshape(9)
    phi = w[16, 0]
    phio = w[16, 1]
    Em = w[17]              # midpoint elastic strain of the step (released energy)
    stm = w[18].reshape(9)

    _elastic_strain(F, h_old, Etr)
    _load_omega(h_old, Om)

    # state of the step (explicit in the step): damage raised along the fixed crack frame from
    # the trial elastic strain (eq. 6, Fig. 9, the largest value kept; tension-only growth),
    # open/closed read from the trial
    grew = False
    wmax = 0.0
    if damaged_n or _max_eig_bound(Etr) > eps_cr:
        crack_frame(Om, damaged_n, Etr, a, Q, om_o)
        _midpoint(h_old, Etr, Em)  # the guess: the trial as the step's end
        normal_strains(Q, Etr, e_t)
        normal_strains(Q, Em, e_m)
        grew = raise_damage(e_t, e_m, om_o, om, phio, phi, eps_cr, eps0, lam, mu) > 0.0
        if grew:
            for i in range(3):
                for j in range(3):
                    Om[i, j] = (om[0] * Q[i, 0] * Q[j, 0] + om[1] * Q[i, 1] * Q[j, 1]
                                + om[2] * Q[i, 2] * Q[j, 2])
        wmax = max(om[0], max(om[1], om[2]))
    else:
        _identity_frame(Q, phi)
    damaged = damaged_n or grew
    release_state(Q, phi, phi_min, beta, Etr, st)

    # elastic trial (eq. 8), Mises check, closest-point return with the step's matrix
    degraded_stress(Etr, Q, st, lam, mu, tmp, S)
    _dev(S, s_tr)
    q_tr = math.sqrt(1.5 * _ddot(s_tr, s_tr))
    sy = fc + H * ebar_n
    plastic = q_tr - sy > tol * sy
    dg = 0.0
    q_f = 0.0
    status = OK
    if plastic or want_tangent:
        buf = np.empty(3 * 49 + 8 * 7)
        Cm = buf[0:49].reshape((7, 7))      # 𝒞 as a Mandel matrix (6×6 used)
        Jm = buf[49:98].reshape((7, 7))     # Newton matrix of the return
        X = buf[98:147].reshape((7, 7))     # its solutions
        vecs = buf[147:203].reshape((8, 7))
        if damaged:
            degraded_moduli(Q, st, lam, mu, a, tmp, V, vecs[7], Cm)
        else:
            _isotropic_moduli(lam, mu, Cm)
    if plastic:
        dg, conv, q_f = _return(Cm, S, s_tr, q_tr, sy, H, tol, vecs, Jm, X, nf)
        if not conv:
            status = NOT_CONVERGED
    for i in range(3):
        for j in range(3):
            Ee[i, j] = Etr[i, j] - dg * nf[i, j] if plastic else Etr[i, j]

    # energies per unit reference volume
    W_p = h_old[H_W_PLASTIC] + (sy + 0.5 * H * dg) * dg
    W_r = h_old[H_W_RELEASED]
    if grew:  # midpoint rule: W(E_m; Ω_n) − W(E_m; Ω_n+1), E_m = ½(E_e,n + E_e,n+1)
        _midpoint(h_old, Ee, Em)
        release_state(Q, phi, phi_min, beta, Em, stm)
        degraded_stress(Em, Q, stm, lam, mu, tmp, So)
        W_new = 0.5 * _ddot(Em, So)
        release_state(Q, phio, phi_min, beta, Em, sto)  # the same frame: the crack axes do not turn
        degraded_stress(Em, Q, sto, lam, mu, tmp, So)
        W_old = 0.5 * _ddot(Em, So)
        W_r += W_old - W_new

    # P = F S
    for i in range(3):
        for j in range(3):
            P[i, j] = F[i, 0] * S[0, j] + F[i, 1] * S[1, j] + F[i, 2] * S[2, j]

    # history
    released = h_old[H_RELEASED] > 0.0 or wmax >= 1.0
    for k in range(6):
        h_new[H_EP + k] = h_old[H_EP + k] + dg * nf[_VI[k], _VJ[k]] if plastic else h_old[H_EP + k]
        h_new[H_OMEGA + k] = Om[_VI[k], _VJ[k]]
        h_new[H_EE + k] = Ee[_VI[k], _VJ[k]]
    h_new[H_EPS_P] = ebar_n + dg
    h_new[H_W_PLASTIC] = W_p
    h_new[H_W_RELEASED] = W_r
    h_new[H_DAMAGE] = min(wmax, 1.0) if damaged else 0.0
    h_new[H_RELEASED] = 1.0 if released else 0.0

    if want_tangent:
        if plastic:
            # consistent tangent of the return: J [dσ; dΔγ] = [𝒞 dE; 0], so dS/dE = (J⁻¹)_σσ 𝒞
            _mises_jacobian(Cm, dg, q_f, vecs[2], vecs[3], H, Jm)  # at the solution
            for I_ in range(7):
                for J_ in range(6):
                    X[I_, J_] = Cm[I_, J_] if I_ < 6 else 0.0
            _gauss_solve(Jm, X, 6)
            _first_piola_tangent(F, S, X, A)
        else:
            _first_piola_tangent(F, S, Cm, A)
    return status


@njit(**JIT)
def mortar_energy(F, h, prm):
    """Stored (elastic) energy per unit reference volume, J/m³, of the mortar at F (3, 3) with the
    history h (≥ 23,) held fixed: W = ½ E_e : 𝒞 : E_e, 𝒞 the degraded matrix of eq. 8 at the
    damage of h and the open/closed state of E_e = E(F) − E_p. NaN if J ≤ 0."""
    lam = prm[1]
    mu = prm[2]
    phi_min = prm[7]
    beta = prm[8]
    cof, J = _cofactor(F)
    if not J > 0.0:
        return np.nan
    w = np.empty((8, 3, 3))
    Ee = w[0]
    Om = w[1]
    Q = w[2]
    S = w[3]
    a = w[4]
    tmp = w[5]
    st = w[6].reshape(9)
    phi = w[7, 0]
    _elastic_strain(F, h, Ee)
    if h[H_DAMAGE] > 0.0:
        _load_omega(h, Om)
        om = w[7, 1]
        crack_frame(Om, True, Ee, a, Q, om)
        for i in range(3):
            phi[i] = factor(om[i])
    else:
        _identity_frame(Q, phi)
    release_state(Q, phi, phi_min, beta, Ee, st)
    degraded_stress(Ee, Q, st, lam, mu, tmp, S)
    return 0.5 * _ddot(Ee, S)


@njit(**JIT)
def mortar_energies(F, h, prm):
    """:func:`mortar_energy` at N points: F (N, 3, 3), h (N, ≥ 23), prm (≥ 10,) → (N,) J/m³."""
    out = np.empty(F.shape[0])
    for n in range(F.shape[0]):
        out[n] = mortar_energy(F[n], h[n], prm)
    return out
