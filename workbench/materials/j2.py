"""Finite-strain J2 plasticity (paper 000): multiplicative split, Hencky elasticity
τ = λ tr(ε_e) I + 2μ ε_e, ε_e = ½ ln b_e, exponential-map return mapping in principal Kirchhoff
space (Simo 1992; de Souza Neto, Perić & Owen 2008, ch. 14), Swift hardening σ_y = C (ε_p + ε0)^n
or linear hardening σ_y = σ_y0 + H ε_p on the Kirchhoff stress, damage D = ε_p/ε_L (000 eq. 36)
with the failed point's stress by :func:`failed_stress` once D ≥ 1, and the consistent
algorithmic tangent (isotropic tensor function derivative, de Souza Neto Box A.6). The stress path
works with matrix functions, ε = ½ ln b_e and the exponential map, evaluated by series near I
(:func:`workbench.materials.tensor.log_spd`, :func:`~workbench.materials.tensor.exp_sym`: the
elastic strains of metals) and spectrally beyond; the tangent uses the closed-form
eigen-decomposition (no iteration). History layout in :mod:`workbench.materials.layout`."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .layout import HIST_DAMAGE, HIST_EPS_P, HIST_W_P, HIST_W_REL, N_HISTORY_J2
from .tensor import (EIG_GAP, INVERTED, JIT, NEWTON_MAXIT, NOT_CONVERGED, OK, _cofactor, _fail,
                     _sym_norm2, eigh3, exp_sym, log_spd)

# --------------------------------------------------------------------------------------------
# finite-strain J2
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def swift(C, eps0, n, eps_p):
    """Swift hardening σ_y = C (ε_p + ε0)^n (paper 000, Table 1) and its derivatives
    H = dσ_y/dε_p = n σ_y/(ε_p + ε0), H' = (n − 1) H/(ε_p + ε0) ≤ 0 and
    H'' = (n − 2) H'/(ε_p + ε0) ≥ 0; |H'| and H'' decrease with ε_p. The power as
    exp(n ln(ε_p + ε0)): a few ulp (|n ln(ε_p + ε0)| ≲ 1), at half the cost of pow."""
    base = eps_p + eps0
    sy = C * math.exp(n * math.log(base))
    ib = 1.0 / base
    H = n * sy * ib
    dH = (n - 1.0) * H * ib
    return sy, H, dH, (n - 2.0) * dH * ib


@njit(**JIT)
def linear_hardening(sy0, H, eps_p):
    """Linear hardening σ_y = σ_y0 + H ε_p and its derivatives H, 0, 0."""
    return sy0 + H * eps_p, H, 0.0, 0.0


@njit(**JIT)
def yield_stress(prm, eps_p):
    """Kirchhoff yield stress σ_y(ε_p) of a J2 parameter row and its derivatives (H, H', H''):
    :func:`swift` (prm[10] = 0) or :func:`linear_hardening` (prm[10] = 1). Both are concave
    (H' ≤ 0) with |H'| and |H''| non-increasing in ε_p, which :func:`j2_return_map` relies on."""
    if prm[10] == 1.0:
        return linear_hardening(prm[3], prm[4], eps_p)
    return swift(prm[3], prm[4], prm[5], eps_p)


@njit(**JIT)
def plastic_work(prm, eps_p, sy):
    """Plastic work per unit reference volume, J/m³, at equivalent plastic strain ε_p:
    W_p = ∫₀^{ε_p} σ_y(e) de, in closed form — Swift: [(ε_p + ε0) σ_y(ε_p) − ε0 σ_y(0)]/(n + 1),
    linear: σ_y0 ε_p + ½ H ε_p². sy: σ_y(ε_p) (the return mapping has it).

    Why this is the plastic work: the plastic power is τ : d_p = Δγ̇ τ : N = σ_y(ε_p) ε̇_p
    (associative J2, N = (3/2) s/q, and q = σ_y while ε_p grows), so W_p is a function of ε_p
    alone and each step's increment is integrated exactly, with no step-size error and no
    accumulated round-off. (The backward-Euler product σ_y(ε_p,n+1) Δε_p — the τ_{n+1} : Δε_p of
    the return mapping's discrete energy identity — is not exact: it exceeds the increment by
    ½ H Δε_p² + O(Δε_p³), first order in the step. Along a radial path the trapezoid-integrated
    work ½(τ_n + τ_{n+1}) : Δε equals Δψ_e + ½(σ_y,n + σ_y,n+1) Δε_p exactly, i.e. the
    trapezoid rule on σ_y, which differs from this increment by (1/12)|σ_y''| Δε_p³.)"""
    if prm[10] == 1.0:
        return eps_p * (prm[3] + 0.5 * prm[4] * eps_p)
    return ((eps_p + prm[4]) * sy - prm[4] * prm[7]) / (prm[5] + 1.0)


@njit(inline="always", **JIT)
def j2_return_map(q_tr, mu, prm, eps_p_n, sy, H, dH, ddH, tol):
    """Plastic multiplier of the radial return in principal Kirchhoff space (de Souza Neto et al.
    2008, Box 14.3): the root Δγ of r(Δγ) = q_tr − 3μΔγ − σ_y(ε_p,n + Δγ).

    r is decreasing and convex (σ_y concave): Newton steps δ_N = r/s (s = 3μ + H) from a point
    left of the root stay left of it and converge monotonically; they are safeguarded by
    bisection on the bracket [0, q_tr/3μ]. It stops at |r| ≤ tol σ_y, either measured, or
    bounded a priori for the second-order step δ = δ_N (1 + κ δ_N), κ = |H'|/(2s), from a point
    left of the root: by Taylor's theorem at Δγ, with r(Δγ) − s δ_N = 0,
        |r(Δγ + δ)| ≤ |H'| κ δ_N³ (1 + κ δ_N/2) + H'' δ³/6
    (H'' at Δγ bounds it on [Δγ, Δγ + δ]: it does not increase). When that is within tol σ_y the
    second-order step is accepted without evaluating σ_y again, with σ_y and H at the end from
    their Taylor expansions (errors ≤ H'' δ³/6 and H'' δ²/2). The steps of explicit dynamics
    (Δγ ≲ 1e-3) then cost two power functions in all with Swift (the yield check's and one
    here); the linear law stops after its first step.

    sy, H, dH, ddH: σ_y, H, H', H'' at ε_p,n (the caller's yield check has them). Returns
    (Δγ, σ_y, H, status), σ_y and H at ε_p,n + Δγ."""
    lo = 0.0
    hi = q_tr / (3.0 * mu)
    dg = 0.0
    for it in range(NEWTON_MAXIT):
        if it > 0:
            sy, H, dH, ddH = yield_stress(prm, eps_p_n + dg)
        r = q_tr - 3.0 * mu * dg - sy
        if abs(r) <= tol * sy:
            return dg, sy, H, OK
        if r > 0.0:
            lo = dg
        else:
            hi = dg
        if hi - lo <= 4e-16 * hi:  # bracket at round-off: nothing better is representable
            return dg, sy, H, OK
        i_s = 1.0 / (3.0 * mu + H)  # 1/s
        dN = r * i_s
        if r > 0.0:  # left of the root: try the second-order step with its a-priori bound
            kap = -0.5 * dH * i_s
            step = dN * (1.0 + kap * dN)
            bound = (-dH * kap * dN * dN * dN * (1.0 + 0.5 * kap * dN)
                     + ddH * step * step * step * (1.0 / 6.0))
            if bound <= tol * sy and dg + step < hi:
                return (dg + step, sy + step * (H + 0.5 * dH * step), H + dH * step, OK)
        if lo < dg + dN < hi:
            dg += dN
        else:
            dg = 0.5 * (lo + hi)
    sy, H, dH, ddH = yield_stress(prm, eps_p_n + dg)
    return dg, sy, H, NOT_CONVERGED


@njit(inline="always", **JIT)
def _be_trial(F, h):
    """Elastic trial left Cauchy–Green tensor be_tr = F Cp⁻¹ Fᵀ, Cp⁻¹ = h[0:9] (row-major,
    symmetric; an array or a 9-tuple): its upper triangle (b00, b01, b02, b11, b12, b22).
    Inlined by numba (see :func:`j2_point`)."""
    # T = F Cp⁻¹
    t00 = F[0, 0] * h[0] + F[0, 1] * h[3] + F[0, 2] * h[6]
    t01 = F[0, 0] * h[1] + F[0, 1] * h[4] + F[0, 2] * h[7]
    t02 = F[0, 0] * h[2] + F[0, 1] * h[5] + F[0, 2] * h[8]
    t10 = F[1, 0] * h[0] + F[1, 1] * h[3] + F[1, 2] * h[6]
    t11 = F[1, 0] * h[1] + F[1, 1] * h[4] + F[1, 2] * h[7]
    t12 = F[1, 0] * h[2] + F[1, 1] * h[5] + F[1, 2] * h[8]
    t20 = F[2, 0] * h[0] + F[2, 1] * h[3] + F[2, 2] * h[6]
    t21 = F[2, 0] * h[1] + F[2, 1] * h[4] + F[2, 2] * h[7]
    t22 = F[2, 0] * h[2] + F[2, 1] * h[5] + F[2, 2] * h[8]
    b00 = t00 * F[0, 0] + t01 * F[0, 1] + t02 * F[0, 2]
    b01 = 0.5 * (t00 * F[1, 0] + t01 * F[1, 1] + t02 * F[1, 2]
                 + t10 * F[0, 0] + t11 * F[0, 1] + t12 * F[0, 2])
    b02 = 0.5 * (t00 * F[2, 0] + t01 * F[2, 1] + t02 * F[2, 2]
                 + t20 * F[0, 0] + t21 * F[0, 1] + t22 * F[0, 2])
    b11 = t10 * F[1, 0] + t11 * F[1, 1] + t12 * F[1, 2]
    b12 = 0.5 * (t10 * F[2, 0] + t11 * F[2, 1] + t12 * F[2, 2]
                 + t20 * F[1, 0] + t21 * F[1, 1] + t22 * F[1, 2])
    b22 = t20 * F[2, 0] + t21 * F[2, 1] + t22 * F[2, 2]
    return b00, b01, b02, b11, b12, b22


@njit(**JIT)
def _theta(xa, xb, ta, tb, Daa, Dab, Dbb, Dba):
    """Off-diagonal modulus of the isotropic function τ(be): θ_ab = (τ_a − τ_b)/(x_a − x_b), or,
    when x_a and x_b coincide to EIG_GAP, its limit ∂τ_a/∂x_a − ∂τ_a/∂x_b symmetrised over a, b
    (∂τ_a/∂x_b = D_ab / 2x_b)."""
    gap = xa - xb
    if abs(gap) > EIG_GAP * max(xa, xb):
        return (ta - tb) / gap
    return 0.5 * ((Daa - Dab) / (2.0 * xa) + (Dbb - Dba) / (2.0 * xb))


@njit(**JIT)
def j2_tangent(A, P, Finv, n, u, x, tA, D):
    """Consistent tangent A_ijkl = ∂P_ij/∂F_kl of P = τ F⁻ᵀ, τ = Σ τ_A n_A ⊗ n_A an isotropic
    function of be_tr = F Cp⁻¹ Fᵀ (de Souza Neto et al. Box A.6), written with u_A = F⁻¹ n_A:
    since Cp⁻¹ Fᵀ n_A = F⁻¹ be_tr n_A = x_A u_A, n_A · dbe_tr · n_B = (x_B n_A ⊗ u_B +
    x_A n_B ⊗ u_A) : dF, and F⁻ᵀ = Σ n_A ⊗ u_A:

        A = Σ_AC D_AC (n_A ⊗ u_A) ⊗ (n_C ⊗ u_C)
          + Σ_{A<B} θ_AB (n_A ⊗ u_B + n_B ⊗ u_A) ⊗ (x_B n_A ⊗ u_B + x_A n_B ⊗ u_A)
          − P_il F⁻¹_jk,

    D_AB = ∂τ_A/∂ε_tr,B (principal algorithmic moduli, ε_tr,B = ½ ln x_B) and θ_AB from
    :func:`_theta`. Evaluated as A_ijkl = Σ_C c_C(i, j, k) u_C,l − F⁻¹_jk P_il, the three
    coefficients c_C formed once per (i, j, k).

    A (3, 3, 3, 3) output; P (3, 3); Finv: F⁻¹ row-major 9-tuple; n, u: 3-tuples of 3-tuples;
    x, tA: eigenvalues of be_tr and principal Kirchhoff stresses; D: 3-tuple of 3-tuples."""
    th01 = _theta(x[0], x[1], tA[0], tA[1], D[0][0], D[0][1], D[1][1], D[1][0])
    th02 = _theta(x[0], x[2], tA[0], tA[2], D[0][0], D[0][2], D[2][2], D[2][0])
    th12 = _theta(x[1], x[2], tA[1], tA[2], D[1][1], D[1][2], D[2][2], D[2][1])
    n0, n1, n2 = n
    u0, u1, u2 = u
    x0, x1, x2 = x
    for i in range(3):
        for j in range(3):
            g0 = n0[i] * u0[j]
            g1 = n1[i] * u1[j]
            g2 = n2[i] * u2[j]
            s0 = D[0][0] * g0 + D[1][0] * g1 + D[2][0] * g2
            s1 = D[0][1] * g0 + D[1][1] * g1 + D[2][1] * g2
            s2 = D[0][2] * g0 + D[1][2] * g1 + D[2][2] * g2
            q01 = th01 * (n0[i] * u1[j] + n1[i] * u0[j])
            q02 = th02 * (n0[i] * u2[j] + n2[i] * u0[j])
            q12 = th12 * (n1[i] * u2[j] + n2[i] * u1[j])
            for k in range(3):
                c0 = s0 * n0[k] + x0 * (q01 * n1[k] + q02 * n2[k])
                c1 = s1 * n1[k] + x1 * (q01 * n0[k] + q12 * n2[k])
                c2 = s2 * n2[k] + x2 * (q02 * n0[k] + q12 * n1[k])
                f = Finv[3 * j + k]
                for l in range(3):
                    A[i, j, k, l] = c0 * u0[l] + c1 * u1[l] + c2 * u2[l] - f * P[i, l]


@njit(**JIT)
def j2_point_tangent(A, P, Finv, be, K, mu, fac, cpl):
    """The tangent of a J2 point in its elastic or plastic step (:func:`j2_tangent`), from the
    closed-form eigen-decomposition of be_tr (:func:`eigh3`) and the principal algorithmic moduli
    D_AB = ∂τ_A/∂ε_tr,B = K + 2μ fac (δ_AB − ⅓) + cpl s_A s_B (de Souza Neto et al. Box 14.3:
    cpl = 4μ² (Δγ/q_tr − 1/(3μ + H)) (3/(2 q_tr))², 0 in an elastic step; s_A = 2μ dev ε_tr,A).

    A (3, 3, 3, 3) output; P (3, 3) the stress (written); Finv: F⁻¹ row-major 9-tuple; be:
    be_tr, 6-tuple; K, mu: bulk and shear moduli, Pa; fac = 1 − 3μΔγ/q_tr; cpl, 1/Pa, as
    above."""
    x0, x1, x2, n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z = eigh3(be[0], be[1], be[2],
                                                                    be[3], be[4], be[5])
    # principal trial log strains and stresses of the same state
    e0 = 0.5 * math.log(x0)
    e1 = 0.5 * math.log(x1)
    e2 = 0.5 * math.log(x2)
    tr = e0 + e1 + e2
    pe = K * tr
    s0 = 2.0 * mu * (e0 - tr / 3.0)
    s1 = 2.0 * mu * (e1 - tr / 3.0)
    s2 = 2.0 * mu * (e2 - tr / 3.0)
    # u_A = F⁻¹ n_A
    u0 = (Finv[0] * n0x + Finv[1] * n0y + Finv[2] * n0z,
          Finv[3] * n0x + Finv[4] * n0y + Finv[5] * n0z,
          Finv[6] * n0x + Finv[7] * n0y + Finv[8] * n0z)
    u1 = (Finv[0] * n1x + Finv[1] * n1y + Finv[2] * n1z,
          Finv[3] * n1x + Finv[4] * n1y + Finv[5] * n1z,
          Finv[6] * n1x + Finv[7] * n1y + Finv[8] * n1z)
    u2 = (Finv[0] * n2x + Finv[1] * n2y + Finv[2] * n2z,
          Finv[3] * n2x + Finv[4] * n2y + Finv[5] * n2z,
          Finv[6] * n2x + Finv[7] * n2y + Finv[8] * n2z)
    dd = 2.0 * mu * fac
    kd = K - dd / 3.0
    D = ((kd + dd + cpl * s0 * s0, kd + cpl * s0 * s1, kd + cpl * s0 * s2),
         (kd + cpl * s1 * s0, kd + dd + cpl * s1 * s1, kd + cpl * s1 * s2),
         (kd + cpl * s2 * s0, kd + cpl * s2 * s1, kd + dd + cpl * s2 * s2))
    j2_tangent(A, P, Finv, ((n0x, n0y, n0z), (n1x, n1y, n1z), (n2x, n2y, n2z)),
               (u0, u1, u2), (x0, x1, x2), (pe + fac * s0, pe + fac * s1, pe + fac * s2), D)


@njit(**JIT)
def failed_stress(cof, J, K, mode):
    """First Piola–Kirchhoff stress of a failed J2 point, D = ε_p/ε_L ≥ 1 (paper 000 eq. 36,
    "stress zero once D ≥ 1"), by the failure mode prm[11]:

    * 0 literal: P = 0, as printed;
    * 1 compression: only a compressive volumetric response is left, τ = K ln J I for J < 1 and
      0 otherwise (no tension, no shear, but no interpenetration either): P = K ln J F⁻ᵀ
      (ψ = ½ K (ln J)², :func:`failed_energy`; tangent :func:`failed_tangent`).

    cof, J: cofactor J F⁻ᵀ (row-major 9-tuple) and J = det F; K: bulk modulus, Pa. Returns P,
    row-major 9-tuple, Pa."""
    c = 0.0
    if mode == 1.0 and J < 1.0:
        c = K * math.log(J) / J
    return (c * cof[0], c * cof[1], c * cof[2], c * cof[3], c * cof[4], c * cof[5],
            c * cof[6], c * cof[7], c * cof[8])


@njit(**JIT)
def failed_tangent(A, cof, J, K, mode):
    """Tangent A_ijkl = ∂P_ij/∂F_kl of :func:`failed_stress`: 0 under the literal mode (and for
    J ≥ 1), K F⁻ᵀ_ij F⁻ᵀ_kl − K ln J F⁻ᵀ_il F⁻ᵀ_kj under the compression mode for J < 1.
    A (3, 3, 3, 3) output; cof, J, K, mode as :func:`failed_stress`."""
    a = 0.0
    b = 0.0
    if mode == 1.0 and J < 1.0:
        iJ = 1.0 / J
        a = K * iJ * iJ
        b = -K * math.log(J) * iJ * iJ
    for i in range(3):
        for j in range(3):
            for k in range(3):
                for l in range(3):
                    A[i, j, k, l] = (a * cof[3 * i + j] * cof[3 * k + l]
                                     + b * cof[3 * i + l] * cof[3 * k + j])


@njit(**JIT)
def failed_energy(J, K, mode):
    """Stored energy per unit reference volume, J/m³, of a failed point (:func:`failed_stress`):
    ψ = ½ K (ln J)² for J < 1 under the compression mode, 0 otherwise."""
    if mode == 1.0 and J < 1.0:
        lnJ = math.log(J)
        return 0.5 * K * lnJ * lnJ
    return 0.0


# the three outcomes of a J2 point, by which the end of j2_point writes P, the history and A
_J2_STEP = 0  # an elastic or plastic step of the J2 law
_FAILED = 1  # D ≥ 1, earlier or in this step: failed_stress
_INVALID = 2  # J ≤ 0 or a non-positive trial stretch: NaN


@njit(**JIT)
def j2_point(F, h_old, prm, P, h_new, A, want_tangent):
    """Finite-strain J2, exponential-map return mapping (de Souza Neto et al. Box 14.3) with the
    consistent tangent dP/dF (P = τ F⁻ᵀ; dτ from the isotropic function τ(be_tr), Box A.6).

    Written with matrix functions: ε_tr = ½ ln be_tr (:func:`log_spd`), the radial return scales
    its deviator by fac = 1 − 3μΔγ/q_tr, and the exponential map is be = exp(tr ε_tr·⅔) ·
    exp(fac dev ln be_tr) (:func:`exp_sym`), Cp⁻¹ = F⁻¹ be F⁻ᵀ. An elastic step (trial state
    inside the yield surface) skips the return mapping and the exponential map. The tangent alone
    needs the eigen-decomposition of be_tr (:func:`j2_point_tangent`), formed only with
    ``want_tangent``.

    h_old, h_new: (n_history ≥ 13,) = [Cp⁻¹ row-major, ε_p, D, W_p, W_rel, ...] (W_p:
    :func:`plastic_work`; W_rel: the stored energy ψ_e − ψ_failed released in the step in which
    the point fails, J/m³; further columns, of wider laws of a table, carried). Allocation-free.

    Written for speed: F, h_old and prm are read once at the start (into tuples), the computation
    runs on scalars and tuples (:func:`_cofactor`, :func:`_be_trial`, :func:`log_spd`,
    :func:`exp_sym`, :func:`j2_return_map` inlined by numba), and P and h_new are written once at
    the end. numba holds a reference on an array argument across every call it does not inline (an
    atomic increment and decrement, ≈ 8 ns per array and point): none on the inputs so; the
    outputs keep theirs (the spectral fallbacks' :func:`eigh3` is a call: inlining it there too
    would remove two more pairs, 2–4 % here, at about twice the compile time).
    """
    mu = prm[2]
    epsL = prm[6]
    tol = prm[9]
    mode = prm[11]
    K = prm[1] + (2.0 / 3.0) * mu
    row = (prm[0], prm[1], prm[2], prm[3], prm[4], prm[5], prm[6], prm[7], prm[8], prm[9],
           prm[10], prm[11])
    cp = (h_old[0], h_old[1], h_old[2], h_old[3], h_old[4], h_old[5], h_old[6], h_old[7],
          h_old[8])
    eps_p = h_old[HIST_EPS_P]
    dmg = h_old[HIST_DAMAGE]
    W_p = h_old[HIST_W_P]
    W_rel = h_old[HIST_W_REL]
    for m in range(N_HISTORY_J2, h_old.shape[0]):  # columns of wider laws: carried
        h_new[m] = h_old[m]
    cof, J = _cofactor(F)
    be = _be_trial(F, cp)
    iJ = 1.0 / J
    Finv = (cof[0] * iJ, cof[3] * iJ, cof[6] * iJ,
            cof[1] * iJ, cof[4] * iJ, cof[7] * iJ,
            cof[2] * iJ, cof[5] * iJ, cof[8] * iJ)

    status = OK
    case = _J2_STEP
    plastic = False
    fac = 1.0
    dg = 0.0
    q_tr = 0.0
    H = 0.0
    nan = np.nan
    Pt = (nan, nan, nan, nan, nan, nan, nan, nan, nan)
    if not J > 0.0:
        case = _INVALID
        status = INVERTED
    elif dmg >= 1.0:  # failed earlier (000 eq. 36): history frozen
        case = _FAILED
        Pt = failed_stress(cof, J, K, mode)
    else:
        L, ok = log_spd(be)  # 2 ε_tr
        if not ok:
            case = _INVALID
            status = INVERTED
        else:
            # trial Hencky stress: τ = K tr ε I + 2μ dev ε, ε = ½ L; q = √(3/2) |dev τ|
            trL = L[0] + L[3] + L[5]
            m3 = trL * (1.0 / 3.0)
            dL = (L[0] - m3, L[1], L[2], L[3] - m3, L[4], L[5] - m3)
            tre = 0.5 * trL
            p = K * tre
            dn2 = _sym_norm2(dL)
            # σ_y(0) ≤ σ_y(ε_p): below it the step is elastic without evaluating σ_y(ε_p) (or
            # q_tr: q_tr² = 3/2 μ² |dev L|² against σ_y(0)²)
            sy = row[7]
            if 1.5 * mu * mu * dn2 > sy * sy:
                q_tr = mu * math.sqrt(1.5 * dn2)
                sy, H, dH, ddH = yield_stress(row, eps_p)
                plastic = q_tr - sy > tol * sy
                if plastic:
                    dg, sy, H, status = j2_return_map(q_tr, mu, row, eps_p, sy, H, dH, ddH, tol)
                    fac = 1.0 - 3.0 * mu * dg / q_tr
            c = mu * fac
            t00 = p + c * dL[0]
            t01 = c * dL[1]
            t02 = c * dL[2]
            t11 = p + c * dL[3]
            t12 = c * dL[4]
            t22 = p + c * dL[5]
            # P = τ F⁻ᵀ
            Pt = (t00 * Finv[0] + t01 * Finv[1] + t02 * Finv[2],
                  t00 * Finv[3] + t01 * Finv[4] + t02 * Finv[5],
                  t00 * Finv[6] + t01 * Finv[7] + t02 * Finv[8],
                  t01 * Finv[0] + t11 * Finv[1] + t12 * Finv[2],
                  t01 * Finv[3] + t11 * Finv[4] + t12 * Finv[5],
                  t01 * Finv[6] + t11 * Finv[7] + t12 * Finv[8],
                  t02 * Finv[0] + t12 * Finv[1] + t22 * Finv[2],
                  t02 * Finv[3] + t12 * Finv[4] + t22 * Finv[5],
                  t02 * Finv[6] + t12 * Finv[7] + t22 * Finv[8])
            if plastic:
                # exponential map: be = exp(2 ε_e) = exp(tr L/3) exp(fac dev L);
                # Cp⁻¹ = F⁻¹ be F⁻ᵀ
                E = exp_sym((fac * dL[0], fac * dL[1], fac * dL[2], fac * dL[3], fac * dL[4],
                             fac * dL[5]))
                v = math.exp(m3)
                e00 = v * E[0]; e01 = v * E[1]; e02 = v * E[2]
                e11 = v * E[3]; e12 = v * E[4]; e22 = v * E[5]
                # T = F⁻¹ be (row i of F⁻¹ times be), then Cp⁻¹ = T F⁻ᵀ (upper triangle,
                # mirrored)
                r00 = Finv[0] * e00 + Finv[1] * e01 + Finv[2] * e02
                r01 = Finv[0] * e01 + Finv[1] * e11 + Finv[2] * e12
                r02 = Finv[0] * e02 + Finv[1] * e12 + Finv[2] * e22
                r10 = Finv[3] * e00 + Finv[4] * e01 + Finv[5] * e02
                r11 = Finv[3] * e01 + Finv[4] * e11 + Finv[5] * e12
                r12 = Finv[3] * e02 + Finv[4] * e12 + Finv[5] * e22
                r20 = Finv[6] * e00 + Finv[7] * e01 + Finv[8] * e02
                r21 = Finv[6] * e01 + Finv[7] * e11 + Finv[8] * e12
                r22 = Finv[6] * e02 + Finv[7] * e12 + Finv[8] * e22
                c01 = r00 * Finv[3] + r01 * Finv[4] + r02 * Finv[5]
                c02 = r00 * Finv[6] + r01 * Finv[7] + r02 * Finv[8]
                c12 = r10 * Finv[6] + r11 * Finv[7] + r12 * Finv[8]
                cp = (r00 * Finv[0] + r01 * Finv[1] + r02 * Finv[2], c01, c02,
                      c01, r10 * Finv[3] + r11 * Finv[4] + r12 * Finv[5], c12,
                      c02, c12, r20 * Finv[6] + r21 * Finv[7] + r22 * Finv[8])
                eps_p += dg
                dmg = eps_p / epsL  # ε_L = inf gives D = 0
                W_p = plastic_work(row, eps_p, sy)
                if dmg >= 1.0:  # fails in this step: its stored energy is released
                    psi_e = 0.25 * mu * fac * fac * dn2 + 0.5 * K * tre * tre
                    W_rel += psi_e - failed_energy(J, K, mode)
                    case = _FAILED
                    Pt = failed_stress(cof, J, K, mode)

    P[0, 0] = Pt[0]; P[0, 1] = Pt[1]; P[0, 2] = Pt[2]
    P[1, 0] = Pt[3]; P[1, 1] = Pt[4]; P[1, 2] = Pt[5]
    P[2, 0] = Pt[6]; P[2, 1] = Pt[7]; P[2, 2] = Pt[8]
    h_new[0] = cp[0]; h_new[1] = cp[1]; h_new[2] = cp[2]
    h_new[3] = cp[3]; h_new[4] = cp[4]; h_new[5] = cp[5]
    h_new[6] = cp[6]; h_new[7] = cp[7]; h_new[8] = cp[8]
    h_new[HIST_EPS_P] = eps_p
    h_new[HIST_DAMAGE] = dmg
    h_new[HIST_W_P] = W_p
    h_new[HIST_W_REL] = W_rel
    if want_tangent:
        if case == _J2_STEP:
            cpl = 0.0
            if plastic:
                cpl = 4.0 * mu * mu * (dg / q_tr - 1.0 / (3.0 * mu + H)) * (1.5 / q_tr) ** 2
            j2_point_tangent(A, P, Finv, be, K, mu, fac, cpl)
        elif case == _FAILED:
            failed_tangent(A, cof, J, K, mode)
        else:
            _fail(P, A, want_tangent)  # P (already NaN) and A := NaN
    return status


@njit(**JIT)
def j2_energy(F, h, prm):
    """ψ, J/m³, of a J2 point (Hencky): ψ = μ |dev ε_e|² + ½K (tr ε_e)², ε_e = ½ ln b_e,
    b_e = F Cp⁻¹ Fᵀ with the history h of the end of the step; a failed point (D ≥ 1):
    :func:`failed_energy`. NaN for J ≤ 0."""
    cof, J = _cofactor(F)
    if not J > 0.0:
        return np.nan
    lam = prm[1]
    mu = prm[2]
    K = lam + 2.0 * mu / 3.0
    if h[HIST_DAMAGE] >= 1.0:
        return failed_energy(J, K, prm[11])
    L, ok = log_spd(_be_trial(F, h))  # 2 ε_e
    if not ok:
        return np.nan
    m3 = (L[0] + L[3] + L[5]) / 3.0
    tr = 1.5 * m3  # tr ε_e
    dev2 = _sym_norm2((L[0] - m3, L[1], L[2], L[3] - m3, L[4], L[5] - m3))
    return 0.25 * mu * dev2 + 0.5 * K * tr * tr
