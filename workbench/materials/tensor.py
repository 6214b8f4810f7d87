"""Numerics shared by the material laws: JIT options, status codes, the cofactor, the closed-form
eigen-decomposition of a symmetric 3×3 (:func:`eigh3`) and functions of symmetric matrices by series
near I and spectrally beyond (:func:`log_spd`, :func:`exp_sym`)."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

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
@njit(inline="always", **JIT)
def _cofactor(F):
    """Cofactor matrix cof(F) = J F⁻ᵀ (row-major 9-tuple) and J = det F. Inlined by numba, as
    :func:`log_spd` and :func:`exp_sym` are (see :func:`workbench.materials.j2.j2_point`)."""
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
# exp_sym's number of terms from ‖D‖_F² alone (no square root, no division in the loop): the
# first K ≥ 1 with d^K/K! ≤ SERIES_TOL is the first with d² ≤ EXP_TERMS_D2[K] =
# (SERIES_TOL K!)^(2/K) (increasing in K; EXP_TERMS_D2[13] > EXP_SERIES_MAX²). Arrays, not
# tuples: indexed at run time without a bounds check (a tuple's can raise, an exception path in
# every inlining caller).
EXP_TERMS_D2 = np.array([0.0] + [(SERIES_TOL * math.factorial(k)) ** (2.0 / k)
                                 for k in range(1, 16)])
RECIPROCALS = np.array([0.0] + [1.0 / k for k in range(1, 32)])  # 1/k: the series' coefficients


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


@njit(inline="always", **JIT)
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
        c = RECIPROCALS[2 * K - 1]
        S = (c, 0.0, 0.0, c, 0.0, c)
        for k in range(K - 2, -1, -1):
            S = _sym_mul(Z, S)
            c = RECIPROCALS[2 * k + 1]
            S = (S[0] + c, S[1], S[2], S[3] + c, S[4], S[5] + c)
        L = _sym_mul(Y, S)
        return (2.0 * L[0], 2.0 * L[1], 2.0 * L[2], 2.0 * L[3], 2.0 * L[4], 2.0 * L[5]), True
    x0, x1, x2, n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z = eigh3(b00, b01, b02, b11, b12, b22)
    if not (x0 > 0.0 and x1 > 0.0 and x2 > 0.0):
        return (np.nan, np.nan, np.nan, np.nan, np.nan, np.nan), False
    return _sym_spectral(math.log(x0), math.log(x1), math.log(x2),
                         n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z), True


@njit(inline="always", **JIT)
def exp_sym(D):
    """Matrix exponential of a symmetric 3×3 D (6-tuple) → 6-tuple.

    The Taylor series Σ D^k/k! (Horner, terms while ‖D‖^k/k! > 2⁻⁵⁶, their number K read from
    ‖D‖_F² and EXP_TERMS_D2) while ‖D‖_F ≤ EXP_SERIES_MAX (K ≤ 13: the return mapping's elastic
    deviator of metals); beyond, the spectral form Σ exp(d_A) n_A ⊗ n_A (:func:`eigh3`)."""
    d2 = _sym_norm2(D)
    if d2 <= EXP_SERIES_MAX * EXP_SERIES_MAX:
        K = 1
        while d2 > EXP_TERMS_D2[K]:
            K += 1
        c = RECIPROCALS[K]
        E = (1.0 + c * D[0], c * D[1], c * D[2], 1.0 + c * D[3], c * D[4], 1.0 + c * D[5])
        for k in range(K - 1, 0, -1):
            E = _sym_mul(D, E)
            c = RECIPROCALS[k]
            E = (1.0 + c * E[0], c * E[1], c * E[2], 1.0 + c * E[3], c * E[4], 1.0 + c * E[5])
        return E
    x0, x1, x2, n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z = eigh3(D[0], D[1], D[2], D[3], D[4], D[5])
    return _sym_spectral(math.exp(x0), math.exp(x1), math.exp(x2),
                         n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z)
