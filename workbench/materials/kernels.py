"""Numba material-point kernels: first Piola–Kirchhoff stress P(F, history) and its consistent
tangent A = dP/dF for the four laws of :mod:`workbench.materials`.

Laws (dispatch on ``int(prm[0])``; parameter and history layouts in the package docstring):

0. Saint Venant–Kirchhoff: S = λ tr(E) I + 2μ E, E = ½(FᵀF − I), P = F S.
1. Compressible neo-Hookean: P = μ(F − F⁻ᵀ) + λ ln J F⁻ᵀ.
2. Mooney–Rivlin-like law of paper 004 eq. 12,
   ψ = ½c1 I1 + ½c2 I2 − [3/2 c1 I3^{1/3} + 3/2 c2 I3^{2/3} − λ/4 (ln I3)²], S = 2 ∂ψ/∂C, which is
   P = (c1 + c2 I1) F − c2 F C − g(J) F⁻ᵀ with g = c1 J^{2/3} + 2 c2 J^{4/3} − 2λ ln J.
   Linearised: μ = c1 + c2, K = 2λ.
3. Finite-strain J2 plasticity: multiplicative split, Hencky elasticity τ = λ tr(ε_e) I + 2μ ε_e,
   ε_e = ½ ln b_e, exponential-map return mapping in principal Kirchhoff space (Simo 1992;
   de Souza Neto, Perić & Owen 2008, ch. 14), Swift hardening σ_y = C (ε_p + ε0)^n on the Kirchhoff
   stress, damage D = ε_p/ε_L with zero stress once D ≥ 1 (paper 000 eq. 36), and the consistent
   algorithmic tangent (isotropic tensor function derivative, de Souza Neto Box A.6).

Entry points: :func:`material_point` (one point, allocation-free for the elastic laws, one small
scratch allocation for J2 — callable from other numba code inside its own ``prange``),
:func:`material_points` and :func:`material_points_tangent` (N points; they allocate the outputs
and run the parallel ``prange`` loop :func:`_points_into`, shared so that it compiles once).

Status codes: 0 ok, 1 local Newton of J2 not converged (the best iterate is returned),
2 J ≤ 0 or a non-positive trial stretch (P and A set to NaN, history copied), −1 unknown law.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from . import N_PARAMS

# JIT options in one place. error_model="numpy": divisions give inf/nan instead of raising, which
# keeps the hot loops free of Python error checks.
JIT = dict(cache=True, error_model="numpy")
JIT_PARALLEL = dict(JIT, parallel=True)

OK = 0
NOT_CONVERGED = 1
INVERTED = 2
UNKNOWN_LAW = -1

# relative gap between two eigenvalues of be_tr under which the divided difference
# (τ_A − τ_B)/(x_A − x_B) is replaced by its limit: the divided difference loses about
# eps/gap relative accuracy, the limit formula is off by O(gap); both are ≤ 1e-8 at this gap.
EIG_GAP = 1e-8
NEWTON_MAXIT = 200


# --------------------------------------------------------------------------------------------
# small helpers
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def _cofactor(F):
    """Cofactor matrix cof(F) = J F⁻ᵀ (row-major 9-tuple) and J = det F."""
    f00 = F[0, 0]; f01 = F[0, 1]; f02 = F[0, 2]
    f10 = F[1, 0]; f11 = F[1, 1]; f12 = F[1, 2]
    f20 = F[2, 0]; f21 = F[2, 1]; f22 = F[2, 2]
    c00 = f11 * f22 - f12 * f21
    c01 = f12 * f20 - f10 * f22
    c02 = f10 * f21 - f11 * f20
    c10 = f02 * f21 - f01 * f22
    c11 = f00 * f22 - f02 * f20
    c12 = f01 * f20 - f00 * f21
    c20 = f01 * f12 - f02 * f11
    c21 = f02 * f10 - f00 * f12
    c22 = f00 * f11 - f01 * f10
    J = f00 * c00 + f01 * c01 + f02 * c02
    return (c00, c01, c02, c10, c11, c12, c20, c21, c22), J


@njit(**JIT)
def _fail(P, A, want_tangent):
    """P (and A) := NaN."""
    for i in range(3):
        for j in range(3):
            P[i, j] = np.nan
    if want_tangent:
        for i in range(3):
            for j in range(3):
                for k in range(3):
                    for l in range(3):
                        A[i, j, k, l] = np.nan


@njit(**JIT)
def _zero(P, A, want_tangent):
    """P (and A) := 0 (a fully damaged point)."""
    for i in range(3):
        for j in range(3):
            P[i, j] = 0.0
    if want_tangent:
        for i in range(3):
            for j in range(3):
                for k in range(3):
                    for l in range(3):
                        A[i, j, k, l] = 0.0


@njit(**JIT)
def _copy(src, dst):
    for m in range(src.shape[0]):
        dst[m] = src[m]


@njit(**JIT)
def eig_sym3(a, V):
    """Cyclic Jacobi eigen-decomposition of a symmetric 3×3 matrix, in place.

    a: (3, 3), overwritten by diag(x) (its eigenvalues on the diagonal); V: (3, 3) output, the
    orthonormal eigenvectors as columns, a_in = V diag(x) Vᵀ. Returns the number of sweeps
    (−1 if 32 sweeps did not suffice; Jacobi converges quadratically, 3–5 sweeps are usual).
    """
    for i in range(3):
        for j in range(3):
            V[i, j] = 1.0 if i == j else 0.0
    for sweep in range(32):
        if a[0, 1] == 0.0 and a[0, 2] == 0.0 and a[1, 2] == 0.0:
            return sweep
        for pair in range(3):
            if pair == 0:
                p, q, r = 0, 1, 2
            elif pair == 1:
                p, q, r = 0, 2, 1
            else:
                p, q, r = 1, 2, 0
            apq = a[p, q]
            if apq == 0.0:
                continue
            app = a[p, p]
            aqq = a[q, q]
            if abs(apq) <= 1e-20 * (abs(app) + abs(aqq)):
                # far below round-off of the diagonal: dropping it changes nothing
                a[p, q] = 0.0
                a[q, p] = 0.0
                continue
            theta = (aqq - app) / (2.0 * apq)
            if abs(theta) > 1e150:
                t = 0.5 / theta
            else:
                t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                if theta < 0.0:
                    t = -t
            c = 1.0 / math.sqrt(t * t + 1.0)
            s = t * c
            a[p, p] = app - t * apq
            a[q, q] = aqq + t * apq
            a[p, q] = 0.0
            a[q, p] = 0.0
            arp = a[r, p]
            arq = a[r, q]
            a[r, p] = c * arp - s * arq
            a[p, r] = a[r, p]
            a[r, q] = s * arp + c * arq
            a[q, r] = a[r, q]
            for m in range(3):
                vp = V[m, p]
                vq = V[m, q]
                V[m, p] = c * vp - s * vq
                V[m, q] = s * vp + c * vq
    return -1


@njit(**JIT)
def swift(C, eps0, n, eps_p):
    """Swift hardening σ_y = C (ε_p + ε0)^n and its slope H = dσ_y/dε_p."""
    base = eps_p + eps0
    sy = C * base ** n
    return sy, n * sy / base


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


# --------------------------------------------------------------------------------------------
# finite-strain J2
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def j2_point(F, h_old, prm, P, h_new, A, want_tangent):
    """Finite-strain J2, exponential-map return mapping (de Souza Neto et al. Box 14.3) with the
    consistent tangent dP/dF (P = τ F⁻ᵀ; dτ from the isotropic function τ(be_tr), Box A.6).

    h_old, h_new: (11,) = [Cp⁻¹ row-major, ε_p, D]. One scratch allocation of 12 3×3 blocks.
    """
    lam = prm[1]
    mu = prm[2]
    Csw = prm[3]
    eps0 = prm[4]
    nsw = prm[5]
    epsL = prm[6]
    tol = prm[9]
    K = lam + 2.0 * mu / 3.0

    cof, J = _cofactor(F)
    if not J > 0.0:
        _fail(P, A, want_tangent)
        _copy(h_old, h_new)
        return INVERTED
    if h_old[10] >= 1.0:  # failed earlier (000 eq. 36): no stress, history frozen
        _zero(P, A, want_tangent)
        _copy(h_old, h_new)
        return OK

    w = np.empty((12, 3, 3))
    Finv = w[0]
    M = w[1]      # Cp⁻¹ Fᵀ
    a = w[2]      # be_tr, diagonalised in place
    V = w[3]      # eigenvectors n_A (columns)
    tau = w[4]
    dtdx = w[5]   # ∂τ_A/∂x_B
    theta = w[6]  # off-diagonal moduli of the isotropic function
    mA = w[7]     # rows: m_A = M n_A
    dXp = w[8]
    dYp = w[9]
    tmp = w[10]
    x = w[11, 0]   # eigenvalues of be_tr
    tA = w[11, 1]  # principal Kirchhoff stresses
    sA = w[11, 2]  # principal trial deviatoric Kirchhoff stresses

    iJ = 1.0 / J
    for i in range(3):
        for j in range(3):
            Finv[i, j] = cof[3 * j + i] * iJ
    # be_tr = F Cp⁻¹ Fᵀ
    for i in range(3):
        for j in range(3):
            M[i, j] = h_old[3 * i] * F[j, 0] + h_old[3 * i + 1] * F[j, 1] + h_old[3 * i + 2] * F[j, 2]
    for i in range(3):
        for j in range(3):
            a[i, j] = F[i, 0] * M[0, j] + F[i, 1] * M[1, j] + F[i, 2] * M[2, j]
    for i in range(3):
        for j in range(i + 1, 3):
            s = 0.5 * (a[i, j] + a[j, i])
            a[i, j] = s
            a[j, i] = s
    eig_sym3(a, V)
    for A_ in range(3):
        x[A_] = a[A_, A_]
    if not (x[0] > 0.0 and x[1] > 0.0 and x[2] > 0.0):
        _fail(P, A, want_tangent)
        _copy(h_old, h_new)
        return INVERTED

    # trial principal log strains and Kirchhoff stresses (Hencky)
    e0 = 0.5 * math.log(x[0])
    e1 = 0.5 * math.log(x[1])
    e2 = 0.5 * math.log(x[2])
    tre = e0 + e1 + e2
    p = K * tre
    sA[0] = 2.0 * mu * (e0 - tre / 3.0)
    sA[1] = 2.0 * mu * (e1 - tre / 3.0)
    sA[2] = 2.0 * mu * (e2 - tre / 3.0)
    q_tr = math.sqrt(1.5 * (sA[0] * sA[0] + sA[1] * sA[1] + sA[2] * sA[2]))

    eps_p_n = h_old[9]
    sy, H = swift(Csw, eps0, nsw, eps_p_n)
    status = OK
    dg = 0.0
    plastic = q_tr - sy > tol * sy
    if plastic:
        # q_tr − 3μΔγ − σ_y(ε_p,n + Δγ) = 0: decreasing and convex in Δγ, bracketed by
        # [0, q_tr/3μ]; Newton, with bisection whenever a step leaves the bracket.
        lo = 0.0
        hi = q_tr / (3.0 * mu)
        converged = False
        for it in range(NEWTON_MAXIT):
            sy, H = swift(Csw, eps0, nsw, eps_p_n + dg)
            r = q_tr - 3.0 * mu * dg - sy
            if abs(r) <= tol * sy:
                converged = True
                break
            if r > 0.0:
                lo = dg
            else:
                hi = dg
            if hi - lo <= 4e-16 * hi:  # bracket at round-off: nothing better is representable
                converged = True
                break
            dg_new = dg + r / (3.0 * mu + H)
            if not (lo < dg_new < hi):
                dg_new = 0.5 * (lo + hi)
            dg = dg_new
        if not converged:
            status = NOT_CONVERGED
    fac = 1.0 - 3.0 * mu * dg / q_tr if plastic else 1.0
    for A_ in range(3):
        tA[A_] = p + fac * sA[A_]
    for i in range(3):
        for j in range(3):
            tau[i, j] = V[i, 0] * tA[0] * V[j, 0] + V[i, 1] * tA[1] * V[j, 1] + V[i, 2] * tA[2] * V[j, 2]
    # P = τ F⁻ᵀ
    for i in range(3):
        for j in range(3):
            P[i, j] = tau[i, 0] * Finv[j, 0] + tau[i, 1] * Finv[j, 1] + tau[i, 2] * Finv[j, 2]

    # history
    if plastic:
        eps_p = eps_p_n + dg
        r32 = 1.5 * dg / q_tr
        eA0 = math.exp(2.0 * (e0 - r32 * sA[0]))
        eA1 = math.exp(2.0 * (e1 - r32 * sA[1]))
        eA2 = math.exp(2.0 * (e2 - r32 * sA[2]))
        for i in range(3):  # tmp = be = Σ exp(2ε_e,A) n_A ⊗ n_A
            for j in range(3):
                tmp[i, j] = V[i, 0] * eA0 * V[j, 0] + V[i, 1] * eA1 * V[j, 1] + V[i, 2] * eA2 * V[j, 2]
        for i in range(3):  # M = F⁻¹ be
            for j in range(3):
                dXp[i, j] = Finv[i, 0] * tmp[0, j] + Finv[i, 1] * tmp[1, j] + Finv[i, 2] * tmp[2, j]
        for i in range(3):  # Cp⁻¹ = F⁻¹ be F⁻ᵀ, symmetrised
            for j in range(i, 3):
                cij = dXp[i, 0] * Finv[j, 0] + dXp[i, 1] * Finv[j, 1] + dXp[i, 2] * Finv[j, 2]
                cji = dXp[j, 0] * Finv[i, 0] + dXp[j, 1] * Finv[i, 1] + dXp[j, 2] * Finv[i, 2]
                h_new[3 * i + j] = 0.5 * (cij + cji)
                h_new[3 * j + i] = h_new[3 * i + j]
        h_new[9] = eps_p
        h_new[10] = eps_p / epsL  # ε_L = inf gives D = 0
    else:
        _copy(h_old, h_new)
    if h_new[10] >= 1.0:
        _zero(P, A, want_tangent)
        return status

    if want_tangent:
        # principal algorithmic moduli D_AB = ∂τ_A/∂ε_tr,B, then ∂τ_A/∂x_B = D_AB / (2 x_B)
        cpl = 0.0
        if plastic:
            cpl = 4.0 * mu * mu * (dg / q_tr - 1.0 / (3.0 * mu + H)) * (1.5 / q_tr) ** 2
        for A_ in range(3):
            for B in range(3):
                d = K + 2.0 * mu * fac * ((1.0 if A_ == B else 0.0) - 1.0 / 3.0)
                d += cpl * sA[A_] * sA[B]
                dtdx[A_, B] = d / (2.0 * x[B])
        for A_ in range(3):
            theta[A_, A_] = 0.0
            for B in range(A_ + 1, 3):
                gap = x[A_] - x[B]
                if abs(gap) > EIG_GAP * max(x[A_], x[B]):
                    th = (tA[A_] - tA[B]) / gap
                else:  # repeated eigenvalues: the limit, symmetrised over A, B
                    th = 0.5 * (dtdx[A_, A_] - dtdx[A_, B] + dtdx[B, B] - dtdx[B, A_])
                theta[A_, B] = th
                theta[B, A_] = th
        # m_A = Cp⁻¹ Fᵀ n_A
        for A_ in range(3):
            for l in range(3):
                mA[A_, l] = M[l, 0] * V[0, A_] + M[l, 1] * V[1, A_] + M[l, 2] * V[2, A_]
        for k in range(3):
            for l in range(3):
                # dbe_tr = dF M + Mᵀ dFᵀ with dF = e_k⊗e_l, in the eigenbasis:
                # dX'_AB = n_A·dbe_tr·n_B = n_A,k m_B,l + m_A,l n_B,k
                for A_ in range(3):
                    for B in range(3):
                        dXp[A_, B] = V[k, A_] * mA[B, l] + mA[A_, l] * V[k, B]
                for A_ in range(3):
                    for B in range(3):
                        if A_ == B:
                            dYp[A_, A_] = (dtdx[A_, 0] * dXp[0, 0] + dtdx[A_, 1] * dXp[1, 1]
                                           + dtdx[A_, 2] * dXp[2, 2])
                        else:
                            dYp[A_, B] = theta[A_, B] * dXp[A_, B]
                # tmp = V dY' ; dτ = tmp Vᵀ (stored in dXp)
                for i in range(3):
                    for B in range(3):
                        tmp[i, B] = V[i, 0] * dYp[0, B] + V[i, 1] * dYp[1, B] + V[i, 2] * dYp[2, B]
                for i in range(3):
                    for j in range(3):
                        dXp[i, j] = tmp[i, 0] * V[j, 0] + tmp[i, 1] * V[j, 1] + tmp[i, 2] * V[j, 2]
                # dP = dτ F⁻ᵀ − P_il F⁻ᵀ_kj
                for i in range(3):
                    for j in range(3):
                        A[i, j, k, l] = (dXp[i, 0] * Finv[j, 0] + dXp[i, 1] * Finv[j, 1]
                                         + dXp[i, 2] * Finv[j, 2] - P[i, l] * Finv[j, k])
    return status


# --------------------------------------------------------------------------------------------
# public entry points
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def material_point(F, h_old, prm, P, h_new, A, want_tangent):
    """One material point.

    F: (3, 3) deformation gradient; h_old: (n_history,) history at the start of the step;
    prm: (10,) material parameters. Outputs, written in place: P (3, 3) first Piola–Kirchhoff
    stress, Pa; h_new (n_history,); A (3, 3, 3, 3) = ∂P_ij/∂F_kl, Pa, filled only when
    ``want_tangent`` (otherwise untouched: a shared dummy is fine). Returns the status code
    (0 ok, 1 J2 Newton not converged, 2 J ≤ 0 with P = NaN, −1 unknown law).
    From numba code pass ``want_tangent`` as a plain bool (``bool(True)``), not a literal
    ``True``: numba would compile the law kernels again for the literal.
    """
    law = int(prm[0])
    if law != 3:
        _copy(h_old, h_new)  # elastic laws: no history (nothing to copy when n_history = 0)
    if law == 0:
        return svk_point(F, prm, P, A, want_tangent)
    if law == 1:
        return neo_hooke_point(F, prm, P, A, want_tangent)
    if law == 2:
        return mooney_rivlin_point(F, prm, P, A, want_tangent)
    if law == 3:
        return j2_point(F, h_old, prm, P, h_new, A, want_tangent)
    _fail(P, A, want_tangent)
    return UNKNOWN_LAW


@njit(**JIT)
def _check(F, h_old, prm, mat_id):
    """Shapes and codes of a batch: F (N, 3, 3), h_old (N, n_history), prm (n_mat, N_PARAMS),
    mat_id (N,) indices into prm; n_history must hold the widest law of the table (the elastic
    laws ignore and keep any history columns)."""
    if prm.shape[1] != N_PARAMS:
        raise ValueError("prm: a parameter table needs N_PARAMS columns (Material.params())")
    for r in range(prm.shape[0]):
        law = int(prm[r, 0])
        if law < 0 or law > 3:
            raise ValueError("prm[:, 0]: unknown material law code")
        if law == 3 and h_old.shape[1] < 11:
            raise ValueError("h_old: J2 needs 11 history columns")
    if F.shape[1] != 3 or F.shape[2] != 3 or h_old.shape[0] != F.shape[0]:
        raise ValueError("F must be (N, 3, 3) and h_old (N, n_history)")
    if mat_id.shape[0] != F.shape[0]:
        raise ValueError("mat_id must be (N,)")
    for n in range(mat_id.shape[0]):
        if mat_id[n] < 0 or mat_id[n] >= prm.shape[0]:
            raise ValueError("mat_id: a material index outside the parameter table")


@njit(**JIT_PARALLEL)
def _points_into(F, h_old, prm, mat_id, P, h_new, A, status, want_tangent):
    """The parallel loop behind :func:`material_points` and :func:`material_points_tangent`
    (one parallel kernel for both keeps the first compilation short). Point n takes the
    parameter row ``prm[mat_id[n]]``. The law is dispatched per point by a branch the CPU
    predicts; the law kernels are called directly rather than through :func:`material_point`,
    whose non-inlined call halves the speed of the elastic laws. Without ``want_tangent``, A is a
    (1, 3, 3, 3, 3) dummy that is never written."""
    for n in prange(F.shape[0]):
        m = n if want_tangent else n - n  # (n - n: the parfor index type, not int64)
        row = prm[mat_id[n]]
        law = int(row[0])
        if law != 3:
            _copy(h_old[n], h_new[n])
        if law == 0:
            status[n] = svk_point(F[n], row, P[n], A[m], want_tangent)
        elif law == 1:
            status[n] = neo_hooke_point(F[n], row, P[n], A[m], want_tangent)
        elif law == 2:
            status[n] = mooney_rivlin_point(F[n], row, P[n], A[m], want_tangent)
        else:
            status[n] = j2_point(F[n], h_old[n], row, P[n], h_new[n], A[m], want_tangent)


@njit(**JIT)
def material_points(F, h_old, prm, mat_id):
    """Stress at N points, in parallel: F (N, 3, 3), h_old (N, n_history), prm (n_mat, N_PARAMS)
    parameter table (:meth:`workbench.materials.MaterialTable.params`), mat_id (N,) int64 rows
    of it → P (N, 3, 3), h_new (N, n_history), status (N,) int64."""
    _check(F, h_old, prm, mat_id)
    N = F.shape[0]
    P = np.empty((N, 3, 3))
    h_new = np.empty((N, h_old.shape[1]))
    status = np.empty(N, dtype=np.int64)
    # bool(...): a plain bool, not Literal[bool], so that the law kernels compile once for all
    # callers (a literal would give them a specialisation of their own)
    _points_into(F, h_old, prm, mat_id, P, h_new, np.empty((1, 3, 3, 3, 3)), status, bool(False))
    return P, h_new, status


@njit(**JIT)
def material_points_tangent(F, h_old, prm, mat_id):
    """Stress and tangent at N points, in parallel (arguments as :func:`material_points`):
    → P (N, 3, 3), A (N, 3, 3, 3, 3) with A[n, i, j, k, l] = ∂P_ij/∂F_kl, h_new (N, n_history),
    status (N,) int64."""
    _check(F, h_old, prm, mat_id)
    N = F.shape[0]
    P = np.empty((N, 3, 3))
    A = np.empty((N, 3, 3, 3, 3))
    h_new = np.empty((N, h_old.shape[1]))
    status = np.empty(N, dtype=np.int64)
    _points_into(F, h_old, prm, mat_id, P, h_new, A, status, bool(True))  # plain bool, see above
    return P, A, h_new, status
