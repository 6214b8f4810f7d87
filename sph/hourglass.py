"""Zero-energy-mode (hourglass) control of the gradient-form methods (csph).

Nodal integration sees a particle's neighbours only through F_a (eq. 35); a motion that leaves
every F_a unchanged costs no energy (a zero-energy mode). The control energy penalises, per pair,
the part of the relative motion that the local affine map F_a does not explain:

    δ_ab = (x_b − x_a) − F_a (X_b − X_a),   Π_hg = ½ α μ Σ_a V_a Σ_b c_ab |δ_ab|²,

with c_ab = w_ab / |X_ab|², w_ab = V_b W_ab / Σ_b V_b W_ab (W: the kernel, or HPM's weight
1 − r²/r_e² for its gradient). δ vanishes for every linear field (the
patch test is kept) and is objective; Π_hg is a quadratic form of each coordinate column, so its
force −K_s x is exact, constant-stiffness and momentum conserving.

With symmetry planes (:mod:`sph.mirror`) the pairs are the full body's: a neighbour may be a
ghost (index ≥ N, at sign ⊙ x_src + offset), so δ acts on the members' positions (the particles,
then the ghosts), K_s is (N + n_g)², each row a weighted by its share w_a V_a, and the force on the
real DOFs is the fold −T_kᵀ K_s x_ext,k of each coordinate column k (T_k: x_ext,k = T_k x_k +
offset_k, the ghost entries sign_k): the quarter's share of the full body's force, as for the
stored energy (:func:`folded_rows`, :func:`folded_hessian`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from numba import njit, prange

from .kernels import JIT, kernel_code


def hourglass_operator(disc) -> tuple[sp.csr_matrix, np.ndarray]:
    """The linear map x ↦ δ, δ_ab = (x_b − x_a) − F_a (X_b − X_a) for every CSR pair (a, b), as a
    sparse (nnz × M) matrix D acting on each coordinate column of the members' positions x
    (M = N + n_ghost: :meth:`~sph.total_lagrangian.Discretisation.extend`), and the pair weights
    c_ab = w_ab / |X_ab|², w_ab = V_b W_ab / Σ_b V_b W_ab (so Σ_b c_ab |δ_ab|² is a mean squared
    non-linear strain). δ vanishes for every linear field (patch test kept) and transforms as a
    vector under rigid motions."""
    from .kernels import w as kernel_w

    N, d = disc.n, disc.dim
    M = N + disc.n_ghost  # the members: the particles, then the ghosts of symmetry planes
    X = disc.extend(disc.X)  # a ghost's reference position is its source's, mirrored
    Vm = disc.V[disc.member_src]  # and its (full-body) volume its source's
    a_of = np.repeat(np.arange(N), np.diff(disc.indptr))
    b_of = disc.indices.astype(np.int64)
    Xab = X[b_of] - X[a_of]
    r = np.linalg.norm(Xab, axis=1)
    if disc.kernel == "wls":  # HPM's weight (004 eq. 6), r_e = disc.h
        Wab = np.maximum(1.0 - (r / disc.h) ** 2, 0.0) * Vm[b_of]
    else:
        kind = kernel_code(disc.kernel)
        Wab = np.array([kernel_w(float(q), disc.h, kind, d) for q in r]) * Vm[b_of]
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
                      shape=(nnz, M))
    return D, c


def hourglass_stiffness(disc, alpha: float, mu: float) -> sp.csr_matrix:
    """K_s (M × M, M = N + n_ghost) of the hourglass energy
    Π_hg = ½ α μ Σ_a V_a Σ_b c_ab |δ_ab|² = ½ Σ_k x_kᵀ K_s x_k over the members' positions x
    (V_a the share w_a V_a with symmetry planes, :attr:`~sph.total_lagrangian.Discretisation.V_energy`)
    (a quadratic form of each coordinate column, so its force −K_s x is exact and constant-
    stiffness; Π_hg is invariant under rigid motions, so momentum and angular momentum stay
    conserved). ``alpha`` dimensionless (0 switches it off), ``mu`` the shear modulus, Pa: one
    value, or (N,) the modulus of each particle a (the weight of its row)."""
    D, c = hourglass_operator(disc)
    a_of = np.repeat(np.arange(disc.n), np.diff(disc.indptr))
    mu = np.asarray(mu, dtype=np.float64)
    wts = alpha * (mu[a_of] if mu.ndim else mu) * disc.V_energy[a_of] * c
    K = (D.T @ sp.diags(wts) @ D).tocsr()
    K.sum_duplicates()
    return K


def _fold_signs(disc) -> np.ndarray:
    """(M, d) the factor of each member's coordinate k on its source's: 1 for the particles,
    the ghost's sign (:mod:`sph.mirror`) for the ghosts."""
    ones = np.ones((disc.n, disc.dim))
    return ones if not disc.n_ghost else np.concatenate([ones, disc.ghost_sign])


def folded_rows(disc, K: sp.csr_matrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows R_k = T_kᵀ K (N × M) of the force −R_k x_ext,k on the real DOFs of coordinate k,
    as one CSR pattern (indptr (N+1,), indices into the members (nnz,), data (nnz, d): column k the
    values of R_k). A ghost's row of K is added to its source's row times the ghost's sign on
    axis k; without ghosts R_k = K for every k."""
    C = K.tocoo()
    src = disc.member_src
    rows = src[C.row]
    vals = C.data[:, None] * _fold_signs(disc)[C.row]
    order = np.lexsort((C.col, rows))
    rows, cols, vals = rows[order], C.col[order].astype(np.int64), vals[order]
    new = np.ones(rows.size, bool)
    new[1:] = (rows[1:] != rows[:-1]) | (cols[1:] != cols[:-1])
    start = np.flatnonzero(new)
    data = np.add.reduceat(vals, start, axis=0) if rows.size else vals
    indptr = np.zeros(disc.n + 1, np.int64)
    np.add.at(indptr, rows[start] + 1, 1)
    return np.cumsum(indptr), np.ascontiguousarray(cols[start]), np.ascontiguousarray(data)


def folded_hessian(disc, K: sp.csr_matrix) -> sp.csr_matrix:
    """∂²Π_hg/∂x∂x on the real DOFs, (N d × N d): Σ_k T_kᵀ K T_k on the DOFs of coordinate k
    (kron(K, I) without ghosts)."""
    N, d = disc.n, disc.dim
    if not disc.n_ghost:
        return sp.kron(K, sp.identity(d), format="csr")
    M = K.shape[0]
    sg = _fold_signs(disc)
    out = None
    for k in range(d):
        T = sp.csr_matrix((sg[:, k], (np.arange(M), disc.member_src)), shape=(M, N))
        E = sp.csr_matrix(([1.0], ([k], [k])), shape=(d, d))
        Kk = sp.kron((T.T @ K @ T).tocsr(), E, format="csr")
        out = Kk if out is None else out + Kk
    return out.tocsr()


def hourglass_energy(disc, K: sp.csr_matrix, x: np.ndarray) -> float:
    """Π_hg = ½ Σ_k x_ext,kᵀ K x_ext,k at positions x (N, d) of the real particles (the ghosts
    mirrored from them), J (J/m in 2-D)."""
    xe = disc.extend(np.ascontiguousarray(x, dtype=np.float64))
    return 0.5 * float(np.sum(xe * (K @ xe)))


def hourglass_strain(disc, x: np.ndarray, D=None, c=None) -> float:
    """The spurious-mode measure: sqrt(Σ_a V_a Σ_b c_ab |δ_ab|² / Σ_a V_a), the root-mean-square
    non-linear (zero-energy-mode) strain, dimensionless; zero for every linear field."""
    if D is None:
        D, c = hourglass_operator(disc)
    a_of = np.repeat(np.arange(disc.n), np.diff(disc.indptr))
    delta = D @ disc.extend(x)
    V = disc.V_energy  # the shares of the full body with symmetry planes
    return float(np.sqrt(np.sum(V[a_of] * c * np.sum(delta * delta, axis=1)) / V.sum()))


# ================================================================================================
# The energy in the zero-energy modes: the kinetic energy of the non-affine part of the motion
# ================================================================================================
#
# A zero-energy mode is, by definition, a motion the method's stored energy does not see; its
# energy therefore cannot be read from the method's own strain energy (for the unstabilised method
# it is zero there) and shows as kinetic energy of a motion that no local affine velocity field
# represents. We measure it, the same way for every method (independent of the method's own
# gradient, so that csph and hpm are compared on one footing), by a local orthogonal projection:
# around each particle a, over its reference neighbours b (HPM's weight w_ab = 1 − |X_ab|²/r_e²,
# r_e = 2.1Δx, and w_aa = 1 for a itself), the weighted least-squares fit of the velocities by an
# affine field of the *current* positions, v_b ≈ c_a + L_a (x_b − x_a). The fit is an orthogonal
# projection in the inner product Σ_b w_ab (·)·(·), so the local kinetic energy splits exactly
# (Pythagoras) into the affine part and the residual r_ab = v_b − c_a − L_a (x_b − x_a):
#
#     K_loc = Σ_a ½ m_a Σ_b ŵ_ab |v_b|²  =  K_aff + K_hg,   K_hg = Σ_a ½ m_a Σ_b ŵ_ab |r_ab|²,
#     ŵ_ab = w_ab / Σ_b w_ab,
#
# and K_hg/K_loc ∈ [0, 1]. A translation, a rigid rotation and any uniform strain rate give
# K_hg = 0 exactly; a smooth field of wavelength λ gives K_hg/K_loc = O((Δx/λ)⁴) (the residual is
# the curvature term, O((Δx/λ)²) in amplitude); a particle-scale zig-zag gives K_hg/K_loc = O(1).
# Physical waves at the particle scale count as well: none is resolved there.

@njit(parallel=True, **JIT)
def _nonaffine_rows(x, v, m, indptr, indices, w, hg, loc):
    """Per particle a: hg[a] = ½ m_a Σ_b ŵ_ab |r_ab|², loc[a] = ½ m_a Σ_b ŵ_ab |v_b|² (b over a and
    its CSR neighbours, ŵ normalised, the fit of the module comment), J (J/m in 2-D)."""
    N, d = x.shape
    nb = d + 1
    for a in prange(N):
        A = np.zeros((nb, nb))
        B = np.zeros((nb, d))
        phi = np.zeros(nb)
        wsum = 1.0
        vv = 0.0
        # a itself (w_aa = 1, φ = (1, 0))
        A[0, 0] += 1.0
        for k in range(d):
            B[0, k] += v[a, k]
            vv += v[a, k] * v[a, k]
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            wb = w[p]
            if wb <= 0.0:
                continue
            phi[0] = 1.0
            for k in range(d):
                phi[k + 1] = x[b, k] - x[a, k]
            for r in range(nb):
                for s in range(nb):
                    A[r, s] += wb * phi[r] * phi[s]
                for k in range(d):
                    B[r, k] += wb * phi[r] * v[b, k]
            wsum += wb
            for k in range(d):
                vv += wb * v[b, k] * v[b, k]
        coef = np.linalg.pinv(A) @ B  # (d+1, d): c_a and L_aᵀ
        res = 0.0
        for k in range(d):
            e = v[a, k] - coef[0, k]
            res += e * e
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            wb = w[p]
            if wb <= 0.0:
                continue
            for k in range(d):
                e = v[b, k] - coef[0, k]
                for l in range(d):
                    e -= coef[l + 1, k] * (x[b, l] - x[a, l])
                res += wb * e * e
        hg[a] = 0.5 * m[a] * res / wsum
        loc[a] = 0.5 * m[a] * vv / wsum


class NonAffineEnergy:
    """K_hg and K_loc of the comment above for particles with reference positions X (N, d), m,
    spacing dx, m; ``re_ratio`` r_e/Δx of the weights (HPM's 2.1 by default); ``body`` (N,) labels
    (no weights across bodies). Call with current positions x (N, d), m, velocities v (N, d), m/s,
    and masses m (N,), kg: returns (K_hg, K_loc), J (J/m in 2-D)."""

    def __init__(self, X, dx: float, re_ratio: float = 2.1, body=None):
        from .neighbours import weighted_neighbourhood

        if not (dx > 0 and 1.0 < re_ratio <= 6.0):
            raise ValueError(f"re_ratio: {re_ratio!r} is not allowed; r_e/Δx must lie in (1, 6] "
                             "(and dx > 0)")
        self.indptr, self.indices, _, self.w = weighted_neighbourhood(X, re_ratio * dx, body)

    def per_particle(self, x, v, m) -> tuple[np.ndarray, np.ndarray]:
        """(hg, loc), each (N,), J: the particles' shares of K_hg and K_loc."""
        N = len(x)
        hg, loc = np.zeros(N), np.zeros(N)
        _nonaffine_rows(np.ascontiguousarray(x, dtype=np.float64),
                        np.ascontiguousarray(v, dtype=np.float64),
                        np.ascontiguousarray(m, dtype=np.float64), self.indptr, self.indices,
                        self.w, hg, loc)
        return hg, loc

    def __call__(self, x, v, m) -> tuple[float, float]:
        hg, loc = self.per_particle(x, v, m)
        return float(hg.sum()), float(loc.sum())
