"""The hyperelastic laws of the library (no history; allocation-free), P(F) and dP/dF:

0. Saint Venant–Kirchhoff: S = λ tr(E) I + 2μ E, E = ½(FᵀF − I), P = F S.
1. Compressible neo-Hookean: P = μ(F − F⁻ᵀ) + λ ln J F⁻ᵀ.
2. Mooney–Rivlin-like law of paper 004 eq. 12,
   ψ = ½c1 I1 + ½c2 I2 − [3/2 c1 I3^{1/3} + 3/2 c2 I3^{2/3} − λ/4 (ln I3)²], S = 2 ∂ψ/∂C, which is
   P = (c1 + c2 I1) F − c2 F C − g(J) F⁻ᵀ with g = c1 J^{2/3} + 2 c2 J^{4/3} − 2λ ln J.
   Linearised: μ = c1 + c2, K = 2λ.

and their stored energies (:func:`elastic_energy`)."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .tensor import JIT, OK, INVERTED, _cofactor, _fail

# --------------------------------------------------------------------------------------------
# elastic laws (no history; allocation-free)
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def svk_point(F, prm, P, A, want_tangent):
    """Saint Venant–Kirchhoff: P = F (λ tr E I + 2μ E);
    A_ijkl = δ_ik S_lj + λ F_ij F_kl + μ b_ik δ_jl + μ F_il F_kj (b = F Fᵀ)."""
    lam = prm[1]
    mu = prm[2]
    cof, J = _cofactor(F)
    if not J > 0.0:
        _fail(P, A, want_tangent)
        return INVERTED
    f00 = F[0, 0]; f01 = F[0, 1]; f02 = F[0, 2]
    f10 = F[1, 0]; f11 = F[1, 1]; f12 = F[1, 2]
    f20 = F[2, 0]; f21 = F[2, 1]; f22 = F[2, 2]
    # E = ½(FᵀF − I)
    e00 = 0.5 * (f00 * f00 + f10 * f10 + f20 * f20 - 1.0)
    e11 = 0.5 * (f01 * f01 + f11 * f11 + f21 * f21 - 1.0)
    e22 = 0.5 * (f02 * f02 + f12 * f12 + f22 * f22 - 1.0)
    e01 = 0.5 * (f00 * f01 + f10 * f11 + f20 * f21)
    e02 = 0.5 * (f00 * f02 + f10 * f12 + f20 * f22)
    e12 = 0.5 * (f01 * f02 + f11 * f12 + f21 * f22)
    ltr = lam * (e00 + e11 + e22)
    s00 = ltr + 2.0 * mu * e00
    s11 = ltr + 2.0 * mu * e11
    s22 = ltr + 2.0 * mu * e22
    s01 = 2.0 * mu * e01
    s02 = 2.0 * mu * e02
    s12 = 2.0 * mu * e12
    P[0, 0] = f00 * s00 + f01 * s01 + f02 * s02
    P[0, 1] = f00 * s01 + f01 * s11 + f02 * s12
    P[0, 2] = f00 * s02 + f01 * s12 + f02 * s22
    P[1, 0] = f10 * s00 + f11 * s01 + f12 * s02
    P[1, 1] = f10 * s01 + f11 * s11 + f12 * s12
    P[1, 2] = f10 * s02 + f11 * s12 + f12 * s22
    P[2, 0] = f20 * s00 + f21 * s01 + f22 * s02
    P[2, 1] = f20 * s01 + f21 * s11 + f22 * s12
    P[2, 2] = f20 * s02 + f21 * s12 + f22 * s22
    if want_tangent:
        S = (s00, s01, s02, s01, s11, s12, s02, s12, s22)
        for i in range(3):
            for k in range(3):
                bik = F[i, 0] * F[k, 0] + F[i, 1] * F[k, 1] + F[i, 2] * F[k, 2]
                for j in range(3):
                    for l in range(3):
                        v = lam * F[i, j] * F[k, l] + mu * F[i, l] * F[k, j]
                        if j == l:
                            v += mu * bik
                        if i == k:
                            v += S[3 * l + j]
                        A[i, j, k, l] = v
    return OK


@njit(**JIT)
def neo_hooke_point(F, prm, P, A, want_tangent):
    """Compressible neo-Hooke: P = μ F + (λ ln J − μ) F⁻ᵀ;
    A_ijkl = μ δ_ik δ_jl + (μ − λ ln J) F⁻ᵀ_il F⁻ᵀ_kj + λ F⁻ᵀ_ij F⁻ᵀ_kl."""
    lam = prm[1]
    mu = prm[2]
    cof, J = _cofactor(F)
    if not J > 0.0:
        _fail(P, A, want_tangent)
        return INVERTED
    lnJ = math.log(J)
    c = (lam * lnJ - mu) / J  # multiplies cof = J F⁻ᵀ
    for i in range(3):
        for j in range(3):
            P[i, j] = mu * F[i, j] + c * cof[3 * i + j]
    if want_tangent:
        iJ = 1.0 / J
        g = (mu - lam * lnJ) * iJ * iJ
        lJ = lam * iJ * iJ
        for i in range(3):
            for j in range(3):
                for k in range(3):
                    for l in range(3):
                        v = g * cof[3 * i + l] * cof[3 * k + j] + lJ * cof[3 * i + j] * cof[3 * k + l]
                        if i == k and j == l:
                            v += mu
                        A[i, j, k, l] = v
    return OK


@njit(**JIT)
def mooney_rivlin_point(F, prm, P, A, want_tangent):
    """004 eq. 12 (see module docstring): P = a F − c2 b F − g F⁻ᵀ, a = c1 + c2 I1, b = F Fᵀ;
    A_ijkl = 2c2 F_ij F_kl + a δ_ik δ_jl − c2(δ_ik C_lj + F_il F_kj + b_ik δ_jl)
             − J g'(J) F⁻ᵀ_ij F⁻ᵀ_kl + g F⁻ᵀ_il F⁻ᵀ_kj."""
    lam = prm[1]
    c1 = prm[7]
    c2 = prm[8]
    cof, J = _cofactor(F)
    if not J > 0.0:
        _fail(P, A, want_tangent)
        return INVERTED
    lnJ = math.log(J)
    J23 = math.exp(2.0 / 3.0 * lnJ)
    J43 = J23 * J23
    g = c1 * J23 + 2.0 * c2 * J43 - 2.0 * lam * lnJ
    I1 = 0.0
    for i in range(3):
        for j in range(3):
            I1 += F[i, j] * F[i, j]
    a = c1 + c2 * I1
    iJ = 1.0 / J
    for i in range(3):
        # row i of b = F Fᵀ
        b0 = F[i, 0] * F[0, 0] + F[i, 1] * F[0, 1] + F[i, 2] * F[0, 2]
        b1 = F[i, 0] * F[1, 0] + F[i, 1] * F[1, 1] + F[i, 2] * F[1, 2]
        b2 = F[i, 0] * F[2, 0] + F[i, 1] * F[2, 1] + F[i, 2] * F[2, 2]
        for j in range(3):
            bF = b0 * F[0, j] + b1 * F[1, j] + b2 * F[2, j]
            P[i, j] = a * F[i, j] - c2 * bF - g * iJ * cof[3 * i + j]
    if want_tangent:
        Jdg = 2.0 / 3.0 * c1 * J23 + 8.0 / 3.0 * c2 * J43 - 2.0 * lam  # J g'(J)
        iJ2 = iJ * iJ
        for i in range(3):
            for j in range(3):
                for k in range(3):
                    bik = F[i, 0] * F[k, 0] + F[i, 1] * F[k, 1] + F[i, 2] * F[k, 2]
                    for l in range(3):
                        v = (2.0 * c2 * F[i, j] * F[k, l] - c2 * F[i, l] * F[k, j]
                             - Jdg * iJ2 * cof[3 * i + j] * cof[3 * k + l]
                             + g * iJ2 * cof[3 * i + l] * cof[3 * k + j])
                        if i == k:
                            Clj = F[0, l] * F[0, j] + F[1, l] * F[1, j] + F[2, l] * F[2, j]
                            v -= c2 * Clj
                            if j == l:
                                v += a
                        if j == l:
                            v -= c2 * bik
                        A[i, j, k, l] = v
    return OK


@njit(**JIT)
def elastic_energy(F, prm):
    """ψ(F), J/m³, of the hyperelastic laws:

    0 SVK: ψ = ½λ (tr E)² + μ E : E.
    1 neo-Hooke: ψ = ½μ (I1 − 3) − μ ln J + ½λ (ln J)².
    2 Mooney–Rivlin-like (004 eq. 12): ψ = ½c1 I1 + ½c2 I2 − [3/2 c1 I3^{1/3} + 3/2 c2 I3^{2/3}
      − λ/4 (ln I3)²], I3 = J².

    NaN for J ≤ 0 or another law."""
    law = int(prm[0])
    cof, J = _cofactor(F)
    if not J > 0.0:
        return np.nan
    lam = prm[1]
    mu = prm[2]
    # C = FᵀF
    c00 = F[0, 0] * F[0, 0] + F[1, 0] * F[1, 0] + F[2, 0] * F[2, 0]
    c11 = F[0, 1] * F[0, 1] + F[1, 1] * F[1, 1] + F[2, 1] * F[2, 1]
    c22 = F[0, 2] * F[0, 2] + F[1, 2] * F[1, 2] + F[2, 2] * F[2, 2]
    c01 = F[0, 0] * F[0, 1] + F[1, 0] * F[1, 1] + F[2, 0] * F[2, 1]
    c02 = F[0, 0] * F[0, 2] + F[1, 0] * F[1, 2] + F[2, 0] * F[2, 2]
    c12 = F[0, 1] * F[0, 2] + F[1, 1] * F[1, 2] + F[2, 1] * F[2, 2]
    I1 = c00 + c11 + c22
    lnJ = math.log(J)
    if law == 0:
        E00 = 0.5 * (c00 - 1.0)
        E11 = 0.5 * (c11 - 1.0)
        E22 = 0.5 * (c22 - 1.0)
        trE = E00 + E11 + E22
        EE = (E00 * E00 + E11 * E11 + E22 * E22
              + 0.5 * (c01 * c01 + c02 * c02 + c12 * c12))  # 2 (½ c_ij)² per off-diagonal pair
        return 0.5 * lam * trE * trE + mu * EE
    if law == 1:
        return 0.5 * mu * (I1 - 3.0) - mu * lnJ + 0.5 * lam * lnJ * lnJ
    if law == 2:
        c1 = prm[7]
        c2 = prm[8]
        trCC = c00 * c00 + c11 * c11 + c22 * c22 + 2.0 * (c01 * c01 + c02 * c02 + c12 * c12)
        I2 = 0.5 * (I1 * I1 - trCC)
        J23 = math.exp(2.0 / 3.0 * lnJ)
        return (0.5 * c1 * I1 + 0.5 * c2 * I2 - 1.5 * c1 * J23 - 1.5 * c2 * J23 * J23
                + lam * lnJ * lnJ)  # λ/4 (ln I3)² = λ (ln J)²
    return np.nan
