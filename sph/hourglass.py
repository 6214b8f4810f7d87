"""Zero-energy-mode (hourglass) control of the gradient-form methods (csph).

Nodal integration sees a particle's neighbours only through F_a (eq. 35); a motion that leaves
every F_a unchanged costs no energy (a zero-energy mode). The control energy penalises, per pair,
the part of the relative motion that the local affine map F_a does not explain:

    δ_ab = (x_b − x_a) − F_a (X_b − X_a),   Π_hg = ½ α μ Σ_a V_a Σ_b c_ab |δ_ab|²,

with c_ab = w_ab / |X_ab|², w_ab = V_b W_ab / Σ_b V_b W_ab (W: the kernel, or HPM's weight
1 − r²/r_e² for its gradient). δ vanishes for every linear field (the
patch test is kept) and is objective; Π_hg is a quadratic form of each coordinate column, so its
force −K_s x is exact, constant-stiffness and momentum conserving.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .kernels import kernel_code


def hourglass_operator(disc) -> tuple[sp.csr_matrix, np.ndarray]:
    """The linear map x ↦ δ, δ_ab = (x_b − x_a) − F_a (X_b − X_a) for every CSR pair (a, b), as a
    sparse (nnz × N) matrix D acting on each coordinate column of x, and the pair weights
    c_ab = w_ab / |X_ab|², w_ab = V_b W_ab / Σ_b V_b W_ab (so Σ_b c_ab |δ_ab|² is a mean squared
    non-linear strain). δ vanishes for every linear field (patch test kept) and transforms as a
    vector under rigid motions."""
    from .kernels import w as kernel_w

    N, d = disc.n, disc.dim
    a_of = np.repeat(np.arange(N), np.diff(disc.indptr))
    b_of = disc.indices.astype(np.int64)
    Xab = disc.X[b_of] - disc.X[a_of]
    r = np.linalg.norm(Xab, axis=1)
    if disc.kernel == "wls":  # HPM's weight (004 eq. 6), r_e = disc.h
        Wab = np.maximum(1.0 - (r / disc.h) ** 2, 0.0) * disc.V[b_of]
    else:
        kind = kernel_code(disc.kernel)
        Wab = np.array([kernel_w(float(q), disc.h, kind, d) for q in r]) * disc.V[b_of]
    wsum = np.bincount(a_of, weights=Wab, minlength=N)
    ws = wsum[a_of]
    c = np.divide(Wab, ws * r * r, out=np.zeros_like(Wab), where=ws > 0)  # V = 0 all round: no say
    # F_a X_ab = Σ_{c' in S_a} x_c' (g_ac' · X_ab), g_ab = G_ab, g_aa = −Σ_b G_ab
    rows, cols, vals = [np.arange(a_of.size)] * 2, [b_of, a_of], [np.ones(a_of.size), -np.ones(a_of.size)]
    nnz = a_of.size
    # neighbour terms: for pair p=(a,b) and each neighbour q=(a,e) of a: −(G_ae · X_ab) x_e
    starts = disc.indptr[a_of]
    counts = np.diff(disc.indptr)[a_of]
    rep_p = np.repeat(np.arange(nnz), counts)
    offs = np.arange(rep_p.size) - np.repeat(np.cumsum(counts) - counts, counts)
    q = starts[rep_p] + offs
    coef = np.einsum("ij,ij->i", disc.G[q], Xab[rep_p])
    rows.append(rep_p); cols.append(disc.indices[q].astype(np.int64)); vals.append(-coef)
    # self term: + (Σ_e G_ae · X_ab) x_a
    gsum = np.zeros((N, d))
    np.add.at(gsum, a_of, disc.G)
    rows.append(np.arange(nnz)); cols.append(a_of); vals.append(np.einsum("ij,ij->i", gsum[a_of], Xab))
    D = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(nnz, N))
    return D, c


def hourglass_stiffness(disc, alpha: float, mu: float) -> sp.csr_matrix:
    """K_s (N × N) of the hourglass energy Π_hg = ½ α μ Σ_a V_a Σ_b c_ab |δ_ab|² = ½ Σ_k x_kᵀ K_s x_k
    (a quadratic form of each coordinate column, so its force −K_s x is exact and constant-
    stiffness; Π_hg is invariant under rigid motions, so momentum and angular momentum stay
    conserved). ``alpha`` dimensionless (0 switches it off), ``mu`` the shear modulus, Pa."""
    D, c = hourglass_operator(disc)
    a_of = np.repeat(np.arange(disc.n), np.diff(disc.indptr))
    wts = alpha * mu * disc.V[a_of] * c
    K = (D.T @ sp.diags(wts) @ D).tocsr()
    K.sum_duplicates()
    return K


def hourglass_strain(disc, x: np.ndarray, D=None, c=None) -> float:
    """The spurious-mode measure: sqrt(Σ_a V_a Σ_b c_ab |δ_ab|² / Σ_a V_a), the root-mean-square
    non-linear (zero-energy-mode) strain, dimensionless; zero for every linear field."""
    if D is None:
        D, c = hourglass_operator(disc)
    a_of = np.repeat(np.arange(disc.n), np.diff(disc.indptr))
    delta = D @ x
    return float(np.sqrt(np.sum(disc.V[a_of] * c * np.sum(delta * delta, axis=1)) / disc.V.sum()))
