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
   de Souza Neto, Perić & Owen 2008, ch. 14), Swift hardening σ_y = C (ε_p + ε0)^n or linear
   hardening σ_y = σ_y0 + H ε_p on the Kirchhoff stress, damage D = ε_p/ε_L (paper 000 eq. 36)
   with the failed point's stress by :func:`failed_stress` once D ≥ 1, and the consistent
   algorithmic tangent (isotropic tensor function derivative, de Souza Neto Box A.6). The stress
   path works with matrix functions, ε = ½ ln b_e and the exponential map, evaluated by series
   near I (:func:`log_spd`, :func:`exp_sym`: the elastic strains of metals) and spectrally
   beyond; the tangent uses the closed-form eigen-decomposition :func:`eigh3` (no iteration).

Entry points: :func:`material_point` (one point, allocation-free for every law, inlined into its
numba callers — callable from other numba code inside its own ``prange``),
:func:`material_points` and :func:`material_points_tangent` (N points; they allocate the outputs
and run the parallel ``prange`` loop :func:`_points_into`, shared so that it compiles once).

Status codes: 0 ok, 1 local Newton of J2 not converged (the best iterate is returned),
2 J ≤ 0 or a non-positive trial stretch (P and A set to NaN, history copied), −1 unknown law.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from . import HIST_DAMAGE, HIST_EPS_P, HIST_W_P, HIST_W_REL, N_HISTORY_J2, N_PARAMS

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
def eigh3(a00, a01, a02, a11, a12, a22):
    """Closed-form (non-iterative) eigen-decomposition of the symmetric 3×3 matrix
    a = [[a00, a01, a02], [a01, a11, a12], [a02, a12, a22]].

    Returns the 12-tuple (x0, x1, x2, n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z): eigenvalues
    (unsorted) and orthonormal eigenvectors n_A, a = Σ x_A n_A ⊗ n_A.

    1. Deviator: q = tr a / 3, B = a − q I (divided by β = max |B_ij| if β is outside
       [1e-60, 1e60], so that |B|⁴ neither underflows nor overflows).
    2. Trigonometric (Cardano) form of the eigenvalues of B: p = √(tr B²/6), r = det B / (2p³),
       x_k = 2p cos(acos(r)/3 + 2πk/3). Only the eigenvalue farthest from the other two is taken
       from it (the largest if r ≥ 0, else the smallest): it is well conditioned for every r
       (dx/dr stays bounded as r → ±1, where acos is not), and it is separated from the others by
       at least √3 p ≥ 0.7 β (p ≥ β/√6).
    3. Its eigenvector: the largest of the three cross products of the rows of B − x I (rank 2;
       the sum of their squared norms is the product of its two non-zero singular values squared,
       ≥ 0.5 β⁴, so the largest is ≥ 0.4 β²: no cancellation).
    4. Deflation: an orthonormal basis (U, W) of the plane normal to it, the 2×2 matrix of B in
       that basis and its exact eigen-decomposition (rotation angle from the half-difference and
       the off-diagonal, written without cancellation). Near-repeated or repeated eigenvalues
       come from this 2×2 problem with absolute error O(eps |B|), not O(√eps) as from step 2.

    Backward error O(eps |a|) and orthogonality O(eps) everywhere (tests/test_materials_eigen.py
    against LAPACK): no ill-conditioned case is left for an iterative fallback, and the Jacobi
    solver this replaces is gone. A diagonal matrix (or one whose deviator is below 1e-300)
    returns its diagonal and I.
    """
    q = (a00 + a11 + a22) / 3.0
    b00 = a00 - q
    b11 = a11 - q
    b22 = a22 - q
    beta = max(abs(b00), abs(b11), abs(b22), abs(a01), abs(a02), abs(a12))
    if (a01 == 0.0 and a02 == 0.0 and a12 == 0.0) or not beta > 1e-300:
        return (a00, a11, a22, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    b01 = a01
    b02 = a02
    b12 = a12
    if not 1e-60 < beta < 1e60:  # keep |B|⁴ (the cross products' norms) inside the float range
        s = 1.0 / beta
        b00 *= s
        b11 *= s
        b22 *= s
        b01 *= s
        b02 *= s
        b12 *= s
    else:
        beta = 1.0
    p2 = (b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * (b01 * b01 + b02 * b02 + b12 * b12)) / 6.0
    p = math.sqrt(p2)
    det = (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02)
           + b02 * (b01 * b12 - b11 * b02))
    r = det / (2.0 * p2 * p)
    r = min(1.0, max(-1.0, r))
    # the largest eigenvalue if r ≥ 0, else the smallest (selects, not branches: r's sign is
    # data, a mispredicted branch costs as much as the arithmetic around it)
    phi = math.acos(r) / 3.0 + (0.0 if r >= 0.0 else 2.0 * math.pi / 3.0)
    d = 2.0 * p * math.cos(phi)
    # eigenvector of d: largest cross product of two rows of B − d I
    r00 = b00 - d
    r11 = b11 - d
    r22 = b22 - d
    # rows: (r00, b01, b02), (b01, r11, b12), (b02, b12, r22)
    c0x = b01 * b12 - b02 * r11
    c0y = b02 * b01 - r00 * b12
    c0z = r00 * r11 - b01 * b01
    c1x = b01 * r22 - b02 * b12
    c1y = b02 * b02 - r00 * r22
    c1z = r00 * b12 - b01 * b02
    c2x = r11 * r22 - b12 * b12
    c2y = b12 * b02 - b01 * r22
    c2z = b01 * b12 - r11 * b02
    m0 = c0x * c0x + c0y * c0y + c0z * c0z
    m1 = c1x * c1x + c1y * c1y + c1z * c1z
    m2 = c2x * c2x + c2y * c2y + c2z * c2z
    k0 = (m0 >= m1) & (m0 >= m2)
    k1 = m1 >= m2
    cx = c0x if k0 else (c1x if k1 else c2x)
    cy = c0y if k0 else (c1y if k1 else c2y)
    cz = c0z if k0 else (c1z if k1 else c2z)
    mc = m0 if k0 else (m1 if k1 else m2)
    # v = c/|c| and an orthonormal basis (U, W) of the plane normal to it, U built from c
    # itself so that the two square roots do not wait on each other
    ic = 1.0 / math.sqrt(mc)
    vx = cx * ic
    vy = cy * ic
    vz = cz * ic
    kx = abs(cx) > abs(cy)
    e1 = cx if kx else cy  # U = (−cz, 0, cx)/|.| or (0, cz, −cy)/|.|
    inv = 1.0 / math.sqrt(e1 * e1 + cz * cz)
    ux = -cz * inv if kx else 0.0
    uy = 0.0 if kx else cz * inv
    uz = cx * inv if kx else -cy * inv
    wx = (cy * uz - cz * uy) * ic
    wy = (cz * ux - cx * uz) * ic
    wz = (cx * uy - cy * ux) * ic
    # 2×2 matrix of B in (U, W)
    bux = b00 * ux + b01 * uy + b02 * uz
    buy = b01 * ux + b11 * uy + b12 * uz
    buz = b02 * ux + b12 * uy + b22 * uz
    bwx = b00 * wx + b01 * wy + b02 * wz
    bwy = b01 * wx + b11 * wy + b12 * wz
    bwz = b02 * wx + b12 * wy + b22 * wz
    m00 = ux * bux + uy * buy + uz * buz
    m01 = wx * bux + wy * buy + wz * buz
    m11 = wx * bwx + wy * bwy + wz * bwz
    mean = 0.5 * (m00 + m11)
    hd = 0.5 * (m00 - m11)
    rad = math.hypot(hd, m01)  # no underflow when the pair is (nearly) repeated
    # eigenvector (c, sn) of mean + rad: (hd + rad, m01) or (m01, rad − hd), whichever has no
    # cancellation, divided by rad first (so that its squares cannot underflow)
    if rad > 0.0:
        ir = 1.0 / rad
        kh = hd >= 0.0
        c = hd * ir + 1.0 if kh else m01 * ir
        sn = m01 * ir if kh else 1.0 - hd * ir
        inv = 1.0 / math.sqrt(c * c + sn * sn)
        c *= inv
        sn *= inv
    else:  # a repeated pair: any basis of the plane
        c = 1.0
        sn = 0.0
    return (q + beta * d, q + beta * (mean + rad), q + beta * (mean - rad),
            vx, vy, vz,
            c * ux + sn * wx, c * uy + sn * wy, c * uz + sn * wz,
            c * wx - sn * ux, c * wy - sn * uy, c * wz - sn * uz)


@njit(**JIT)
def eig_sym3_closed(a, V):
    """:func:`eigh3` on arrays: a (3, 3) symmetric (its upper triangle is read), overwritten by
    diag(x); V (3, 3) output, the eigenvectors as columns, a_in = V diag(x) Vᵀ. Returns 0."""
    e = eigh3(a[0, 0], a[0, 1], a[0, 2], a[1, 1], a[1, 2], a[2, 2])
    for i in range(3):
        for j in range(3):
            a[i, j] = e[i] if i == j else 0.0
            V[i, j] = e[3 + 3 * j + i]
    return 0


# --------------------------------------------------------------------------------------------
# functions of symmetric 3×3 matrices (6-tuples: upper triangle a00, a01, a02, a11, a12, a22)
# --------------------------------------------------------------------------------------------
# ‖Y‖_F bound of the series of ln (at most 12 terms) and ‖D‖_F bound of the series of exp (at
# most 13 terms); beyond them the spectral form through eigh3 is cheaper.
LOG_SERIES_MAX = 0.2
EXP_SERIES_MAX = 0.25
SERIES_TOL = 2.0 ** -56  # relative truncation error of both series (an eighth of eps)


@njit(**JIT)
def _sym_mul(a, b):
    """Upper triangle of a b for symmetric a, b that commute (then a b is symmetric)."""
    return (a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
            a[0] * b[1] + a[1] * b[3] + a[2] * b[4],
            a[0] * b[2] + a[1] * b[4] + a[2] * b[5],
            a[1] * b[1] + a[3] * b[3] + a[4] * b[4],
            a[1] * b[2] + a[3] * b[4] + a[4] * b[5],
            a[2] * b[2] + a[4] * b[4] + a[5] * b[5])


@njit(**JIT)
def _sym_norm2(a):
    """‖a‖_F² of a symmetric 6-tuple."""
    return (a[0] * a[0] + a[3] * a[3] + a[5] * a[5]
            + 2.0 * (a[1] * a[1] + a[2] * a[2] + a[4] * a[4]))


@njit(**JIT)
def _sym_spectral(x0, x1, x2, n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z):
    """Σ x_A n_A ⊗ n_A as a symmetric 6-tuple."""
    return (x0 * n0x * n0x + x1 * n1x * n1x + x2 * n2x * n2x,
            x0 * n0x * n0y + x1 * n1x * n1y + x2 * n2x * n2y,
            x0 * n0x * n0z + x1 * n1x * n1z + x2 * n2x * n2z,
            x0 * n0y * n0y + x1 * n1y * n1y + x2 * n2y * n2y,
            x0 * n0y * n0z + x1 * n1y * n1z + x2 * n2y * n2z,
            x0 * n0z * n0z + x1 * n1z * n1z + x2 * n2z * n2z)


@njit(**JIT)
def log_spd(b):
    """Matrix logarithm of a symmetric positive definite 3×3 b (6-tuple) → (ln b as a 6-tuple,
    ok). ok is False when b is not positive definite (or not finite).

    Near I, the series ln b = 2 atanh Y = 2 Σ_k Y^{2k+1}/(2k+1) with Y = (b − I)(b + I)⁻¹, whose
    eigenvalues are tanh(½ ln x_A): no eigen-decomposition, no special case for repeated
    eigenvalues. With z = ‖Y‖_F² the terms after the K-th sum to at most
    2‖Y‖ z^K/((2K + 1)(1 − z)); K is the first with z^K/((2K + 1)(1 − z)) ≤ 2⁻⁵⁶, Horner in
    Y² from the last term. Used while ‖Y‖_F ≤ LOG_SERIES_MAX (K ≤ 12: the elastic strains of
    metals, |ε_e| ≲ 0.2); beyond, the spectral form Σ ln x_A n_A ⊗ n_A (:func:`eigh3`)."""
    b00, b01, b02, b11, b12, b22 = b
    a00 = b00 + 1.0
    a11 = b11 + 1.0
    a22 = b22 + 1.0
    # cofactor (symmetric) and determinant of b + I
    c00 = a11 * a22 - b12 * b12
    c01 = b02 * b12 - b01 * a22
    c02 = b01 * b12 - a11 * b02
    c11 = a00 * a22 - b02 * b02
    c12 = b01 * b02 - a00 * b12
    c22 = a00 * a11 - b01 * b01
    det = a00 * c00 + b01 * c01 + b02 * c02
    Y = _sym_mul((b00 - 1.0, b01, b02, b11 - 1.0, b12, b22 - 1.0), (c00, c01, c02, c11, c12, c22))
    idet = 1.0 / det
    Y = (Y[0] * idet, Y[1] * idet, Y[2] * idet, Y[3] * idet, Y[4] * idet, Y[5] * idet)
    Z = _sym_mul(Y, Y)
    z = Z[0] + Z[3] + Z[5]  # ‖Y‖_F²
    if z <= LOG_SERIES_MAX * LOG_SERIES_MAX:
        K = 1
        t = z
        lim = SERIES_TOL * (1.0 - z)
        while t > lim * (2 * K + 1):
            t *= z
            K += 1
        c = 1.0 / (2 * K - 1)
        S = (c, 0.0, 0.0, c, 0.0, c)
        for k in range(K - 2, -1, -1):
            S = _sym_mul(Z, S)
            c = 1.0 / (2 * k + 1)
            S = (S[0] + c, S[1], S[2], S[3] + c, S[4], S[5] + c)
        L = _sym_mul(Y, S)
        return (2.0 * L[0], 2.0 * L[1], 2.0 * L[2], 2.0 * L[3], 2.0 * L[4], 2.0 * L[5]), True
    x0, x1, x2, n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z = eigh3(b00, b01, b02, b11, b12, b22)
    if not (x0 > 0.0 and x1 > 0.0 and x2 > 0.0):
        return (np.nan, np.nan, np.nan, np.nan, np.nan, np.nan), False
    return _sym_spectral(math.log(x0), math.log(x1), math.log(x2),
                         n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z), True


@njit(**JIT)
def exp_sym(D):
    """Matrix exponential of a symmetric 3×3 D (6-tuple) → 6-tuple.

    The Taylor series Σ D^k/k! (Horner, terms while ‖D‖^k/k! > 2⁻⁵⁶) while ‖D‖_F ≤
    EXP_SERIES_MAX (at most 13 terms: the return mapping's elastic deviator of metals); beyond,
    the spectral form Σ exp(d_A) n_A ⊗ n_A (:func:`eigh3`)."""
    d = math.sqrt(_sym_norm2(D))
    if d <= EXP_SERIES_MAX:
        K = 0
        t = 1.0
        while t > SERIES_TOL:
            K += 1
            t *= d / K
        c = 1.0 / K
        E = (1.0 + c * D[0], c * D[1], c * D[2], 1.0 + c * D[3], c * D[4], 1.0 + c * D[5])
        for k in range(K - 1, 0, -1):
            E = _sym_mul(D, E)
            c = 1.0 / k
            E = (1.0 + c * E[0], c * E[1], c * E[2], 1.0 + c * E[3], c * E[4], 1.0 + c * E[5])
        return E
    x0, x1, x2, n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z = eigh3(D[0], D[1], D[2], D[3], D[4], D[5])
    return _sym_spectral(math.exp(x0), math.exp(x1), math.exp(x2),
                         n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z)


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
def swift(C, eps0, n, eps_p):
    """Swift hardening σ_y = C (ε_p + ε0)^n (paper 000, Table 1) and its derivatives
    H = dσ_y/dε_p = n σ_y/(ε_p + ε0), H' = (n − 1) H/(ε_p + ε0) ≤ 0 and
    H'' = (n − 2) H'/(ε_p + ε0) ≥ 0; |H'| and H'' decrease with ε_p."""
    base = eps_p + eps0
    sy = C * base ** n
    H = n * sy / base
    dH = (n - 1.0) * H / base
    return sy, H, dH, (n - 2.0) * dH / base


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


@njit(**JIT)
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
        s = 3.0 * mu + H
        dN = r / s
        if r > 0.0:  # left of the root: try the second-order step with its a-priori bound
            kap = -0.5 * dH / s
            step = dN * (1.0 + kap * dN)
            bound = -dH * kap * dN * dN * dN * (1.0 + 0.5 * kap * dN) + ddH * step * step * step / 6.0
            if bound <= tol * sy and dg + step < hi:
                return (dg + step, sy + step * (H + 0.5 * dH * step), H + dH * step, OK)
        if lo < dg + dN < hi:
            dg += dN
        else:
            dg = 0.5 * (lo + hi)
    sy, H, dH, ddH = yield_stress(prm, eps_p_n + dg)
    return dg, sy, H, NOT_CONVERGED


@njit(**JIT)
def _be_trial(F, h):
    """Elastic trial left Cauchy–Green tensor be_tr = F Cp⁻¹ Fᵀ, Cp⁻¹ = h[0:9] (row-major,
    symmetric): its upper triangle (b00, b01, b02, b11, b12, b22)."""
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
def failed_stress(cof, J, K, mode, P, A, want_tangent):
    """Stress of a failed J2 point, D = ε_p/ε_L ≥ 1 (paper 000 eq. 36, "stress zero once
    D ≥ 1"), by the failure mode prm[11]:

    * 0 literal: P = 0 and A = 0, as printed;
    * 1 compression: only a compressive volumetric response is left, τ = K ln J I for J < 1 and
      0 otherwise (no tension, no shear, but no interpenetration either): P = K ln J F⁻ᵀ,
      A_ijkl = K F⁻ᵀ_ij F⁻ᵀ_kl − K ln J F⁻ᵀ_il F⁻ᵀ_kj (ψ = ½ K (ln J)², :func:`failed_energy`).

    cof, J: cofactor J F⁻ᵀ (row-major 9-tuple) and J = det F; K: bulk modulus, Pa."""
    if mode == 1.0 and J < 1.0:
        lnJ = math.log(J)
        iJ = 1.0 / J
        c = K * lnJ * iJ
        for i in range(3):
            for j in range(3):
                P[i, j] = c * cof[3 * i + j]
        if want_tangent:
            a = K * iJ * iJ
            b = -K * lnJ * iJ * iJ
            for i in range(3):
                for j in range(3):
                    for k in range(3):
                        for l in range(3):
                            A[i, j, k, l] = (a * cof[3 * i + j] * cof[3 * k + l]
                                             + b * cof[3 * i + l] * cof[3 * k + j])
    else:
        _zero(P, A, want_tangent)


@njit(**JIT)
def failed_energy(J, K, mode):
    """Stored energy per unit reference volume, J/m³, of a failed point (:func:`failed_stress`):
    ψ = ½ K (ln J)² for J < 1 under the compression mode, 0 otherwise."""
    if mode == 1.0 and J < 1.0:
        lnJ = math.log(J)
        return 0.5 * K * lnJ * lnJ
    return 0.0


@njit(**JIT)
def j2_point(F, h_old, prm, P, h_new, A, want_tangent):
    """Finite-strain J2, exponential-map return mapping (de Souza Neto et al. Box 14.3) with the
    consistent tangent dP/dF (P = τ F⁻ᵀ; dτ from the isotropic function τ(be_tr), Box A.6).

    Written with matrix functions: ε_tr = ½ ln be_tr (:func:`log_spd`), the radial return scales
    its deviator by fac = 1 − 3μΔγ/q_tr, and the exponential map is be = exp(tr ε_tr·⅔) ·
    exp(fac dev ln be_tr) (:func:`exp_sym`), Cp⁻¹ = F⁻¹ be F⁻ᵀ. An elastic step (trial state
    inside the yield surface) skips the return mapping and the exponential map. The tangent alone
    needs the eigen-decomposition of be_tr (:func:`eigh3`), formed only with ``want_tangent``.

    h_old, h_new: (n_history ≥ 13,) = [Cp⁻¹ row-major, ε_p, D, W_p, W_rel, ...] (W_p:
    :func:`plastic_work`; W_rel: the stored energy ψ_e − ψ_failed released in the step in which
    the point fails, J/m³; further columns, of wider laws of a table, carried). Allocation-free.
    """
    lam = prm[1]
    mu = prm[2]
    epsL = prm[6]
    tol = prm[9]
    K = lam + 2.0 * mu / 3.0

    cof, J = _cofactor(F)
    if not J > 0.0:
        _fail(P, A, want_tangent)
        _copy(h_old, h_new)
        return INVERTED
    if h_old[HIST_DAMAGE] >= 1.0:  # failed earlier (000 eq. 36): history frozen
        failed_stress(cof, J, K, prm[11], P, A, want_tangent)
        _copy(h_old, h_new)
        return OK

    be = _be_trial(F, h_old)
    L, ok = log_spd(be)  # 2 ε_tr
    if not ok:
        _fail(P, A, want_tangent)
        _copy(h_old, h_new)
        return INVERTED
    iJ = 1.0 / J
    Finv = (cof[0] * iJ, cof[3] * iJ, cof[6] * iJ,
            cof[1] * iJ, cof[4] * iJ, cof[7] * iJ,
            cof[2] * iJ, cof[5] * iJ, cof[8] * iJ)

    # trial Hencky stress: τ = K tr ε I + 2μ dev ε, ε = ½ L; q = √(3/2) |dev τ|
    trL = L[0] + L[3] + L[5]
    m3 = trL / 3.0
    dL = (L[0] - m3, L[1], L[2], L[3] - m3, L[4], L[5] - m3)
    tre = 0.5 * trL
    p = K * tre
    dn2 = _sym_norm2(dL)
    q_tr = mu * math.sqrt(1.5 * dn2)

    eps_p_n = h_old[HIST_EPS_P]
    status = OK
    plastic = False
    sy = prm[7]  # σ_y(0) ≤ σ_y(ε_p): below it the step is elastic without evaluating σ_y(ε_p)
    H = 0.0
    dH = 0.0
    ddH = 0.0
    if q_tr > sy:
        sy, H, dH, ddH = yield_stress(prm, eps_p_n)
        plastic = q_tr - sy > tol * sy
    dg = 0.0
    fac = 1.0
    if plastic:
        dg, sy, H, status = j2_return_map(q_tr, mu, prm, eps_p_n, sy, H, dH, ddH, tol)
        fac = 1.0 - 3.0 * mu * dg / q_tr
    c = mu * fac
    t00 = p + c * dL[0]
    t01 = c * dL[1]
    t02 = c * dL[2]
    t11 = p + c * dL[3]
    t12 = c * dL[4]
    t22 = p + c * dL[5]
    # P = τ F⁻ᵀ
    P[0, 0] = t00 * Finv[0] + t01 * Finv[1] + t02 * Finv[2]
    P[0, 1] = t00 * Finv[3] + t01 * Finv[4] + t02 * Finv[5]
    P[0, 2] = t00 * Finv[6] + t01 * Finv[7] + t02 * Finv[8]
    P[1, 0] = t01 * Finv[0] + t11 * Finv[1] + t12 * Finv[2]
    P[1, 1] = t01 * Finv[3] + t11 * Finv[4] + t12 * Finv[5]
    P[1, 2] = t01 * Finv[6] + t11 * Finv[7] + t12 * Finv[8]
    P[2, 0] = t02 * Finv[0] + t12 * Finv[1] + t22 * Finv[2]
    P[2, 1] = t02 * Finv[3] + t12 * Finv[4] + t22 * Finv[5]
    P[2, 2] = t02 * Finv[6] + t12 * Finv[7] + t22 * Finv[8]

    if plastic:
        # exponential map: be = exp(2 ε_e) = exp(tr L/3) exp(fac dev L); Cp⁻¹ = F⁻¹ be F⁻ᵀ
        E = exp_sym((fac * dL[0], fac * dL[1], fac * dL[2], fac * dL[3], fac * dL[4], fac * dL[5]))
        v = math.exp(m3)
        e00 = v * E[0]; e01 = v * E[1]; e02 = v * E[2]
        e11 = v * E[3]; e12 = v * E[4]; e22 = v * E[5]
        # T = F⁻¹ be (row i of F⁻¹ times be), then Cp⁻¹ = T F⁻ᵀ (upper triangle, mirrored)
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
        h_new[0] = r00 * Finv[0] + r01 * Finv[1] + r02 * Finv[2]
        h_new[1] = c01
        h_new[2] = c02
        h_new[3] = c01
        h_new[4] = r10 * Finv[3] + r11 * Finv[4] + r12 * Finv[5]
        h_new[5] = c12
        h_new[6] = c02
        h_new[7] = c12
        h_new[8] = r20 * Finv[6] + r21 * Finv[7] + r22 * Finv[8]
        eps_p = eps_p_n + dg
        h_new[HIST_EPS_P] = eps_p
        h_new[HIST_DAMAGE] = eps_p / epsL  # ε_L = inf gives D = 0
        h_new[HIST_W_P] = plastic_work(prm, eps_p, sy)
        h_new[HIST_W_REL] = h_old[HIST_W_REL]
        for m in range(N_HISTORY_J2, h_old.shape[0]):  # columns of wider laws: carried
            h_new[m] = h_old[m]
        if h_new[HIST_DAMAGE] >= 1.0:  # fails in this step: its stored energy is released
            psi_e = 0.25 * mu * fac * fac * dn2 + 0.5 * K * tre * tre
            h_new[HIST_W_REL] += psi_e - failed_energy(J, K, prm[11])
            failed_stress(cof, J, K, prm[11], P, A, want_tangent)
            return status
    else:
        _copy(h_old, h_new)

    if want_tangent:
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
        # principal algorithmic moduli D_AB = ∂τ_A/∂ε_tr,B
        cpl = 0.0
        if plastic:
            cpl = 4.0 * mu * mu * (dg / q_tr - 1.0 / (3.0 * mu + H)) * (1.5 / q_tr) ** 2
        dd = 2.0 * mu * fac
        kd = K - dd / 3.0
        D = ((kd + dd + cpl * s0 * s0, kd + cpl * s0 * s1, kd + cpl * s0 * s2),
             (kd + cpl * s1 * s0, kd + dd + cpl * s1 * s1, kd + cpl * s1 * s2),
             (kd + cpl * s2 * s0, kd + cpl * s2 * s1, kd + dd + cpl * s2 * s2))
        j2_tangent(A, P, Finv, ((n0x, n0y, n0z), (n1x, n1y, n1z), (n2x, n2y, n2z)),
                   (u0, u1, u2), (x0, x1, x2), (pe + fac * s0, pe + fac * s1, pe + fac * s2), D)
    return status


# --------------------------------------------------------------------------------------------
# stored energies
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def stored_energy_point(F, h, prm):
    """Stored (elastic) energy per unit reference volume ψ(F, h), J/m³, of one point, in closed
    form; P = ∂ψ/∂F at fixed history (for J2: within an elastic step).

    0 SVK: ψ = ½λ (tr E)² + μ E : E.
    1 neo-Hooke: ψ = ½μ (I1 − 3) − μ ln J + ½λ (ln J)².
    2 Mooney–Rivlin-like (004 eq. 12): ψ = ½c1 I1 + ½c2 I2 − [3/2 c1 I3^{1/3} + 3/2 c2 I3^{2/3}
      − λ/4 (ln I3)²], I3 = J².
    3 J2 (Hencky): ψ = μ |dev ε_e|² + ½K (tr ε_e)², ε_e = ½ ln b_e, b_e = F Cp⁻¹ Fᵀ with the
      history h of the end of the step; a failed point (D ≥ 1): :func:`failed_energy`.

    F: (3, 3); h: (n_history,) history (read by J2 only); prm: (N_PARAMS,) row. NaN for J ≤ 0 or
    an unknown law code."""
    law = int(prm[0])
    cof, J = _cofactor(F)
    if not J > 0.0:
        return np.nan
    lam = prm[1]
    mu = prm[2]
    if law == 3:
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


@njit(**JIT_PARALLEL)
def _energies_into(F, h, prm, mat_id, out):
    for n in prange(F.shape[0]):
        out[n] = stored_energy_point(F[n], h[n], prm[mat_id[n]])


@njit(**JIT)
def stored_energies(F, h, prm, mat_id):
    """Stored energy per unit reference volume of N points, J/m³, in parallel: F (N, 3, 3),
    h (N, n_history) (of the end of the step), prm (n_mat, N_PARAMS), mat_id (N,) → ψ (N,).
    With the J2 history columns W_p and W_rel, ψ + W_p + W_rel is the work done on each point."""
    _check(F, h, prm, mat_id)
    out = np.empty(F.shape[0])
    _energies_into(F, h, prm, mat_id, out)
    return out


# --------------------------------------------------------------------------------------------
# public entry points
# --------------------------------------------------------------------------------------------
@njit(inline="always", **JIT)
def material_point(F, h_old, prm, P, h_new, A, want_tangent):
    """One material point.

    F: (3, 3) deformation gradient; h_old: (n_history,) history at the start of the step;
    prm: (10,) material parameters. Outputs, written in place: P (3, 3) first Piola–Kirchhoff
    stress, Pa; h_new (n_history,); A (3, 3, 3, 3) = ∂P_ij/∂F_kl, Pa, filled only when
    ``want_tangent`` (otherwise untouched: a shared dummy is fine). Returns the status code
    (0 ok, 1 J2 Newton not converged, 2 J ≤ 0 with P = NaN, −1 unknown law).
    From numba code pass ``want_tangent`` as a plain bool (``bool(True)``), not a literal
    ``True``: numba would compile the law kernels again for the literal. Inlined into its numba
    callers (a dispatch of a few lines; as a call of its own it cost about 40 ns per point).
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
        if law == 3:
            if h_old.shape[1] < N_HISTORY_J2:
                raise ValueError("h_old: J2 needs N_HISTORY_J2 = 13 history columns")
            if prm[r, 10] != 0.0 and prm[r, 10] != 1.0:
                raise ValueError("prm[:, 10]: J2 hardening kind must be 0 (Swift) or 1 (linear)")
            if prm[r, 11] != 0.0 and prm[r, 11] != 1.0:
                raise ValueError("prm[:, 11]: J2 failure mode must be 0 (literal) or 1 (compression)")
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
