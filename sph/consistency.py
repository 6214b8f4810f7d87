"""Integration-consistent gradients for total-Lagrangian particle methods (CSPH, HPM).

Both methods write the deformation gradient as F_a = Σ_b (x_b − x_a) ⊗ G_ab (000 eq. 35; 004 eq. 4
with G_ij = w_ij A_i⁻¹ X_ij) and the internal force as f = −∂Π/∂x, Π = Σ_a V_a ψ(F_a) (nodal
integration). With g_ac = G_ac (c ≠ a) and g_aa = −Σ_b G_ab, ∂F_a/∂x_c = I ⊗ g_ac and

    f_c = −Σ_a V_a P_a g_ac.

For a uniform stress P the force on particle c is −P Σ_a V_a g_ac, and the traction t = P N on the
boundary gives the consistent nodal load f_c^ext = P n_c with the boundary area vector
n_c = ∮ N_c N dΓ (N_c the particle's share function; zero for interior particles). A uniform
deformation is therefore a discrete equilibrium — the *force* patch test — only if

    Σ_a V_a g_ac = n_c                    (column or integration constraints, per particle c)   (I)

which nodal integration with kernel gradients violates for every particle within the support of a
boundary (the divergence theorem does not hold for the nodal quadrature: the integration
constraint of Chen, Wu, Yoon & You 2001 and Chen, Hillman & Rüter 2013, "An arbitrary order
variationally consistent integration for Galerkin meshfree methods", IJNME 95:387). The error is
first order in the spacing (the uniaxial block is 20 % too soft at 4 particles per edge).

This module changes G alone, by the smallest weighted correction δG that enforces (I) while keeping
F exact for affine (and, with the quadratic basis, quadratic) motions,

    Σ_c p(X_c − X_a) ⊗ G_ac = T          (row or reproducing constraints, per particle a)        (R)

(p(Δ) = Δ, T = I for the linear basis; p = (Δ, Δ_i Δ_k), T = (I, 0) for the quadratic one). Since
only G changes, F, the force −∂Π/∂x, the conservation of linear and angular momentum (F is a sum
of differences x_b − x_a, so Π is invariant under rigid motions for any G) and the symmetric
tangent K = ∂²Π/∂x∂x of :func:`sph.total_lagrangian.tangent_matrix` are kept unchanged.

The correction (:func:`consistent_gradients`) minimises Σ_p |δG_p|²/ω_p subject to (R) and (I).
With multipliers Λ_a (m×d, rows) and μ_c (d, columns),

    δG_ac = ω_ac [Λ_aᵀ p(X_ac) + V_a (μ_c − μ_a)],                                             (C1)

and eliminating Λ_a with the moment matrix M_a = Σ_c ω_ac p_ac p_acᵀ (m×m):

    δG_ac = ω_ac R_aᵀ M_a⁻¹ p_ac + V_a ω_ac [(I − Π_a) Δμ]_c,   Δμ_c = μ_c − μ_a,            (C2)

with R_a = T − Σ_c p_ac ⊗ G_ac the row residual of the base gradients and Π_a the ω-weighted
least-squares projection onto the basis on a's stencil, (Π_a u)_c = p_acᵀ M_a⁻¹ Σ_e ω_ae p_ae u_e.
Inserting (C2) into (I) gives, separately for each component j of μ, the sparse symmetric positive
semi-definite system

    K μ_j = r_j,   K = Σ_a V_a² B_aᵀ [W_a − W_a P_a M_a⁻¹ P_aᵀ W_a] B_a,                    (C3)
                   r_c = n_c − Σ_a V_a g_ac(G + δG⁰),

B_a the difference map μ ↦ (μ_c − μ_a)_c on a's stencil, W_a = diag(ω_ac), P_a the rows p_acᵀ.
Its null space is the polynomials of the basis (they pass every row's projection), so (C3) is
solvable iff Σ_c q(X_c) r_c = 0 for those polynomials q — for the linear basis
Σ_c n_c = 0 and Σ_c X_c ⊗ n_c = (Σ_a V_a) I, the divergence theorem of the discrete pair (V, n).
:func:`boundary_normals` gives such a pair on node lattices of axis-aligned boxes and their unions;
otherwise :func:`consistent_gradients` moves n on the boundary particles by the least amount that
makes (C3) solvable and reports it.

Column constraints of fixed degrees of freedom are dropped (their forces are reactions), i.e. μ_c,j
= 0 there (:func:`column_mask`).

What it takes for accuracy, beyond the patch test (measured on the 004 plate and cantilever, node
lattice; numbers in the report of this change):

* the quadratic base (``basis="quadratic"``: F exact for quadratic motions, so for pure bending
  at a free surface); with the linear (Bonet–Lok, or HPM's WLS) base the one-sided surface
  gradient leaves the plate period +2.3 % long at H/Δx = 10 even with exact integration;
* volumes exact for quadratics (:func:`boundary_normals` ``order=2``): the trapezoid volumes
  over-estimate the bending energy by 2(Δx/H)²;
* a clamp as a boundary of the body: no pairs across the clamp face (build the neighbours with a
  body label for the particles behind it), the particles on the face held. Held particles kept as
  neighbours (with zero volume) see u = 0 behind the face where the solution continues with a
  slope: F is wrong over a layer of width 2h, an O(Δx) softening (+0.48 % at H/Δx = 10);
* the clamped corners excluded from the integration (``exclude=`` of :func:`boundary_normals`):
  the stress is singular there;
* uniform weights ω (:func:`pair_weights`): the kernel weights concentrate the correction on the
  nearest pairs and leave −0.14 % at H/Δx = 10.

The multiplier system is factorised once (scipy's SuperLU in symmetric mode) and refined on the
true residual of the corrected gradients; set-up (2-D plate, 2 cores) 2 s at 2e4 particles and
18 s at 1e5 with the quadratic basis (10 s linear), 8–30× :func:`sph.csph.discretise`. In 3-D
the factors fill in (14.5 GB at 1e5 particles): above :data:`AMG_ABOVE` unknowns the system is
solved instead by conjugate gradients with the polynomial smoothed-aggregation hierarchy of
:mod:`sph.polynomial_amg`, whose memory grows linearly (32 kB a particle at 4e4 and 9e4).
"""
from __future__ import annotations

import math
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numba import njit, prange
from scipy.sparse.csgraph import connected_components

from .kernels import JIT, KERNELS, w as kernel_value
from .neighbours import _crosses, reverse_pairs, sorted_position

BASES = ("linear", "quadratic")
WEIGHTS = ("uniform", "kernel", "wls")


# ================================================================================================
# Boundary area vectors and dual-cell volumes of a node lattice
# ================================================================================================

def boundary_normals(nodes, dx: float, inside, origin=None, order: int = 1, exclude=None,
                     cracks=None):
    """Volumes V_c and boundary area vectors n_c = ∮ N_c N dΓ of lattice nodes.

    Each node's dual cell [X_c − Δx/2, X_c + Δx/2]^d is split into 2^d sub-cells of side Δx/2; a
    sub-cell belongs to the body when ``inside`` holds at its centre (X_c ± Δx/4 per axis). Then

        V_c = (Δx/2)^d · #(sub-cells of c inside),
        n_c = Σ over the faces of c's inside sub-cells whose other side is not an inside sub-cell
              (of c or of a neighbouring node) of (Δx/2)^(d−1) · (outward unit normal).

    The faces are closed, so Σ_c n_c = 0 exactly. A body whose boundary runs along lattice planes
    (axis-aligned boxes and unions of lattice-aligned boxes, node lattice with nodes on the faces)
    gets the trapezoid volumes, the trapezoid face shares and Σ_c X_c ⊗ n_c = (Σ_c V_c) I: the
    discrete divergence theorem that :func:`consistent_gradients` needs. Nodes outside the body
    (held particles behind a clamp) get V = 0.

    nodes (N, d) m, on a lattice of spacing ``dx`` (m) through ``origin`` (default: the first
    node); inside: a function (M, d) → (M,) bool. Returns (V (N,) m^d, n (N, d) m^(d−1)).

    ``order=2``: volumes that integrate quadratic polynomials exactly over the inside sub-cells.
    Each inside sub-cell's integral is spread over a 3^d tensor stencil of body nodes (V > 0 at
    order 1) by the integrals of the quadratic Lagrange polynomials over the sub-cell — per axis the
    centred stencil (I−1, I, I+1) where it exists, else the one-sided (I, I+1, I+2) or
    (I−2, I−1, I); where no such stencil exists (a body thinner than three nodes) the sub-cell
    stays with its owner. On a line of nodes 0, 1, 2, … from a face this is Gregory's end-corrected
    trapezoid rule, weights (3/8, 7/6, 23/24, 1, …) Δx: the energy of pure bending, quadratic in
    the distance from the neutral axis, is integrated exactly (the trapezoid rule over-estimates
    it by 2(Δx/H)²: 2 % at H/Δx = 10). Σ V_c, Σ V_c X_c and the boundary vectors n (unchanged,
    trapezoid shares) keep the discrete divergence theorem of the linear and quadratic bases.

    ``exclude`` (N,) bool: nodes that carry no volume — points where the integrand is singular,
    such as the corners of a clamped face (the stress there grows like r^(λ−1), λ ≈ 0.7: sampling
    it with a nodal weight makes the plate period converge at first order, −0.038 % at
    H/Δx = 40; without it −0.005 %). Each excluded node's volume goes in equal shares to its
    lattice neighbours (±Δx along each axis) in the body and not excluded: Σ V is kept, the first
    moments change by O(V_c Δx) at each such node (no positive rule exact for linears can
    skip a corner node: it is a vertex of the body).

    ``cracks`` (K, d, d) or None: pre-crack facets (:func:`workbench.crack_geometry.facets`). The
    face between two inside sub-cells of different nodes whose reference segment crosses a facet
    (the pair the neighbour list cuts, :func:`sph.neighbours.cut_pairs`) is exposed on both sides:
    each side of the crack is a body with a free face on the dual cells' boundary, and the
    discrete divergence theorem holds on each; the order-2 stencils take no node across a
    crack."""
    if order not in (1, 2):
        raise ValueError(f"order: {order!r} is not one of 1, 2")
    X = np.asarray(nodes, dtype=np.float64)
    if X.ndim != 2 or X.shape[1] not in (1, 2, 3) or X.shape[0] == 0:
        raise ValueError(f"nodes: expected shape (N, d) with N >= 1 and d in 1..3, got {X.shape}")
    if not (dx > 0 and math.isfinite(dx)):
        raise ValueError(f"dx: {dx!r} is not allowed; the lattice spacing must be > 0")
    N, d = X.shape
    o = X[0] if origin is None else np.asarray(origin, dtype=np.float64)
    I = np.rint((X - o) / dx).astype(np.int64)
    if np.abs(X - (o + I * dx)).max() > 1e-6 * dx:
        raise ValueError("nodes: not on a lattice of spacing dx through origin (off by more than "
                         "1e-6 dx)")
    F = (np.zeros((0, d, d)) if cracks is None or not len(cracks)
         else np.ascontiguousarray(cracks, dtype=np.float64))
    signs, ins, faces = _exposed_faces(X, I, o, dx, inside, F)
    area = (0.5 * dx) ** (d - 1)
    V = ins.reshape(N, 2 ** d).sum(axis=1) * (0.5 * dx) ** d  # inside sub-cells of each node
    n = np.zeros((N, d))
    for a, s, own, _ in faces:
        np.add.at(n[:, a], own, s * area)
    if order == 2:
        Imin = I.min(0)
        dims = I.max(0) - Imin + 1
        grid = np.full(int(np.prod(dims)), -1, np.int64)
        lin = np.ravel_multi_index(tuple((I - Imin).T), dims)
        grid[lin] = np.arange(N)
        V, lost = _quadratic_volumes(I - Imin, dims.astype(np.int64), grid,
                                     ins.reshape(N, 2 ** d), signs.astype(np.int64), V > 0,
                                     _STENCILS, _lagrange_table(), dx, X, F)
    if exclude is not None:
        exclude = np.asarray(exclude, dtype=bool)
        if exclude.shape != (N,):
            raise ValueError(f"exclude: expected shape (N,) = ({N},), got {exclude.shape}")
        V = _exclude(V, I, exclude)
    return V, n


def _exposed_faces(X, I, o, dx: float, inside, cracks=None):
    """The boundary faces of the half-spacing sub-cells of :func:`boundary_normals`: (signs (2^d, d)
    the sub-cells' sides, ins (N·2^d,) the sub-cells inside, faces [(axis a, direction s, owners of
    the exposed faces, which of them lie half a spacing from their owner)]). A face of a sub-cell
    on the side s of its node lies through the node, or half a spacing from it (on the dual
    cell's boundary) when the sub-cell is on that side. ``cracks`` (K, d, d): a face between
    sub-cells of two nodes whose segment crosses a facet is exposed too."""
    N, d = X.shape
    signs = np.array(np.meshgrid(*[(0, 1)] * d, indexing="ij")).reshape(d, -1).T  # (2^d, d)
    J = (2 * I[:, None, :] + signs[None]).reshape(-1, d)  # sub-cell indices, half-spacing grid
    owner = np.repeat(np.arange(N), 2 ** d)
    side = np.tile(signs, (N, 1))
    centres = o + (J - 0.5) * (0.5 * dx)
    ins = np.asarray(inside(centres), dtype=bool).reshape(-1)
    if ins.shape[0] != J.shape[0]:
        raise ValueError("inside: must return one bool per point")
    lo = J.min(0) - 1
    ext = J.max(0) - lo + 2

    def key(Jk):
        k = np.zeros(Jk.shape[0], np.int64)
        for a in range(d):
            k = k * ext[a] + (Jk[:, a] - lo[a])
        return k
    k_in = key(J[ins])
    by_key = np.argsort(k_in)
    keys_in = k_in[by_key]
    if keys_in.size and np.any(np.diff(keys_in) == 0):
        raise ValueError("nodes: duplicate lattice nodes")
    Jin, own, sin = J[ins], owner[ins], side[ins]
    cut = cracks is not None and len(cracks) > 0
    if cut:
        from workbench.crack_geometry import crosses

        own_sorted = own[by_key]
    faces = []
    for a in range(d):
        for s in (-1, 1):
            Jn = Jin.copy()
            Jn[:, a] += s
            kn = key(Jn)
            if keys_in.size:
                pos = np.minimum(np.searchsorted(keys_in, kn), keys_in.size - 1)
                exposed = keys_in[pos] != kn
                if cut:  # a face between two nodes' sub-cells across a pre-crack
                    other = own_sorted[pos]
                    cand = np.nonzero(~exposed & (other != own))[0]
                    exposed[cand] = crosses(X[own[cand]], X[other[cand]], cracks)
            else:
                exposed = np.ones(kn.size, bool)
            faces.append((a, s, own[exposed], sin[exposed, a] == (1 if s > 0 else 0)))
    return signs, ins, faces


def off_lattice_faces(nodes, dx: float, inside, origin=None, cracks=None) -> float:
    """The share of the boundary of the body ``inside`` (as :func:`boundary_normals` sees it) that
    lies half a spacing from the lattice nodes instead of through them: 0 for a union of boxes
    whose faces lie on lattice planes (node lattice), 1 for a cell lattice. Where it is not 0 the
    integration-consistent correction extrapolates the gradients of the outermost nodes to a face
    beyond them; on a node lattice with some faces off (a 3-D beam of odd H/Δx on a block whose
    faces are on the lattice) it is ill-posed — the corrections grow to ten times the gradients
    and the highest frequency forty-fold. ``cracks``: pre-crack facets, whose faces
    (:func:`boundary_normals`) lie on the dual cells' boundary, half a spacing from their nodes —
    off the lattice: with a pre-crack the highest frequency of the consistent correction grows
    with the resolution (ω_max Δx/c = 3.3, 7.5, 19 at 10, 18, 34 spacings across a centre-cracked
    plate, against 2.2 uncracked)."""
    X = np.asarray(nodes, dtype=np.float64)
    o = X[0] if origin is None else np.asarray(origin, dtype=np.float64)
    I = np.rint((X - o) / dx).astype(np.int64)
    _, _, faces = _exposed_faces(X, I, o, dx, inside, cracks)
    total = sum(f[2].size for f in faces)
    return float(sum(np.count_nonzero(f[3]) for f in faces) / total) if total else 0.0


_STENCILS = np.array([(-1, 0, 1), (0, 1, 2), (-2, -1, 0)], np.int64)
"""1-D node stencils of a half cell, by preference: centred, then one-sided (offsets from the owner
node). Stencils that skip the owner would extrapolate, with negative weights."""


def _lagrange_table():
    """w[c, side, e] = ∫ L_e(t) dt over the half cell t ∈ [−1/2, 0] (side 0) or [0, 1/2] (side 1),
    L_e the quadratic Lagrange polynomial of node e of the stencil ``_STENCILS[c]`` (units Δx)."""
    from numpy.polynomial import polynomial as Pn

    w = np.zeros((len(_STENCILS), 2, 3))
    for c, st in enumerate(_STENCILS):
        for e in range(3):
            coef = np.array([1.0])
            for f in range(3):
                if f != e:
                    coef = Pn.polymul(coef, np.array([-st[f], 1.0]) / (st[e] - st[f]))
            prim = Pn.polyint(coef)
            w[c, 0, e] = Pn.polyval(0.0, prim) - Pn.polyval(-0.5, prim)
            w[c, 1, e] = Pn.polyval(0.5, prim) - Pn.polyval(0.0, prim)
    return w


@njit(**JIT)
def _quadratic_volumes(I, dims, grid, ins, signs, usable, stencils, table, dx, X, F):
    """V_e = Σ over inside sub-cells s of Π_k table[c_k, side_k, e_k] Δx^d (see
    :func:`boundary_normals`, order 2); the stencil choice c_k per axis in the order of
    ``stencils``, the first whose 3^d nodes are all usable (body nodes not excluded, none across a
    pre-crack facet of F (K, d, d) from the owner at X (N, d)). Returns
    (V, number of sub-cells left with their owner for want of a stencil)."""
    N, d = I.shape
    V = np.zeros(N)
    nsub = ins.shape[1]
    ns = stencils.shape[0]
    ncomb = ns ** d
    choice = np.empty(d, np.int64)
    lost = 0
    for a in range(N):
        for s in range(nsub):
            if not ins[a, s]:
                continue
            found = False
            for comb in range(ncomb):
                t = comb
                for k in range(d):
                    choice[k] = t % ns
                    t //= ns
                valid = True
                for e in range(3 ** d):
                    t = e
                    lin = 0
                    for k in range(d):
                        node = I[a, k] + stencils[choice[k], t % 3]
                        t //= 3
                        if node < 0 or node >= dims[k]:
                            valid = False
                            break
                        lin = lin * dims[k] + node
                    if not valid:
                        break
                    b = grid[lin]
                    if b < 0 or not usable[b]:
                        valid = False
                        break
                    if b != a:
                        for f in range(F.shape[0]):
                            if _crosses(X, a, b, F, f):
                                valid = False
                                break
                        if not valid:
                            break
                if not valid:
                    continue
                found = True
                for e in range(3 ** d):
                    t = e
                    lin = 0
                    wgt = 1.0
                    for k in range(d):
                        ek = t % 3
                        t //= 3
                        lin = lin * dims[k] + I[a, k] + stencils[choice[k], ek]
                        wgt *= table[choice[k], signs[s, k], ek]
                    V[grid[lin]] += wgt * dx ** d
                break
            if not found:
                V[a] += (0.5 * dx) ** d
                lost += 1
    return V, lost


def _exclude(V, I, exclude):
    """V with the volume of each excluded node moved, in equal shares, to its axis neighbours
    (lattice indices I ± e_k) that have volume and are not excluded."""
    V = V.copy()
    N, d = I.shape
    index = {tuple(row): a for a, row in enumerate(I)}
    for a in np.nonzero(exclude & (V > 0))[0]:
        nb = []
        for k in range(d):
            for s in (-1, 1):
                key = list(I[a])
                key[k] += s
                b = index.get(tuple(key))
                if b is not None and V[b] > 0 and not exclude[b]:
                    nb.append(b)
        if nb:
            V[nb] += V[a] / len(nb)
            V[a] = 0.0
    return V


def box_inside(lo, hi, dx: float):
    """The predicate of the closed box [lo, hi] for :func:`boundary_normals` (a sub-cell centre is
    Δx/4 from any lattice plane, so the tolerance Δx/8 decides nothing but round-off)."""
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    tol = dx / 8

    def inside(P):
        return np.all((P >= lo - tol) & (P <= hi + tol), axis=1)

    return inside


# ================================================================================================
# Pair weights ω
# ================================================================================================

def pair_weights(X, indptr, indices, radius: float, kind: str = "kernel") -> np.ndarray:
    """Weights ω_p (nnz,) of the correction's norm Σ_p |δG_p|²/ω_p, per CSR pair (a, b), r = |X_ab|:

    * ``"kernel"``: the cubic spline W(r, radius/2)/W(0) (support ``radius``), so the correction
      fades out smoothly towards the edge of the stencil;
    * ``"wls"``: 1 − r²/radius² (HPM's weight, 004 eq. 6);
    * ``"uniform"``: 1.

    X (N, d) m; radius m (the support: 2h for CSPH, r_e for HPM)."""
    if kind not in WEIGHTS:
        raise ValueError(f"kind: {kind!r} is not one of {WEIGHTS}")
    if not (radius > 0 and math.isfinite(radius)):
        raise ValueError(f"radius: {radius!r} is not allowed; must be > 0")
    X = np.asarray(X, dtype=np.float64)
    a = np.repeat(np.arange(X.shape[0]), np.diff(indptr))
    r = np.linalg.norm(X[indices] - X[a], axis=1)
    if kind == "uniform":
        return np.ones(r.size)
    if kind == "wls":
        return np.maximum(1.0 - (r / radius) ** 2, 0.0)
    h = radius / 2
    d = X.shape[1]
    k = KERNELS["cubic_spline"]
    w0 = kernel_value(0.0, h, k, d)
    return np.array([kernel_value(float(q), h, k, d) for q in r]) / w0


# ================================================================================================
# The correction: row data (C2), the multiplier system (C3), the corrected gradients
# ================================================================================================

@njit(inline="always", **JIT)
def _basis(Delta, ell, quadratic, out):
    """p(Δ): Δ/ℓ (d) and, for the quadratic basis, Δ_i Δ_k/ℓ² (i ≤ k)."""
    d = Delta.shape[0]
    for i in range(d):
        out[i] = Delta[i] / ell
    if quadratic:
        c = d
        for i in range(d):
            for k in range(i, d):
                out[c] = Delta[i] * Delta[k] / (ell * ell)
                c += 1


@njit(parallel=True, **JIT)
def _row_geometry(X, indptr, indices, omega, quadratic, Pb, C, sig, kap, ok, ell):
    """Per row a: the basis p_ac (Pb, nnz×m) scaled by ℓ_a = max_c |X_ac| (ell, N),
    C_ac = ω_ac M_a⁻¹ p_ac (nnz×m), σ_ac = Σ_e Q_a,ec with Q_a = W_a − W_a P_a M_a⁻¹ P_aᵀ W_a
    (nnz), κ_a = Σ_c σ_ac (N) and the regularity of M_a (ok, N): everything of eq. C2–C3 that
    depends on the geometry and the weights only."""
    N, d = X.shape
    m = Pb.shape[1]
    for a in prange(N):
        p0 = indptr[a]
        n = indptr[a + 1] - p0
        Delta = np.empty(d)
        la = 0.0
        for q in range(n):
            b = indices[p0 + q]
            r2 = 0.0
            for k in range(d):
                r2 += (X[b, k] - X[a, k]) ** 2
            la = max(la, math.sqrt(r2))
        if la == 0.0:
            la = 1.0
        ell[a] = la
        M = np.zeros((m, m))
        y = np.zeros(m)
        for q in range(n):
            b = indices[p0 + q]
            for k in range(d):
                Delta[k] = X[b, k] - X[a, k]
            _basis(Delta, la, quadratic, Pb[p0 + q])
            wq = omega[p0 + q]
            for i in range(m):
                y[i] += wq * Pb[p0 + q, i]
                for j in range(m):
                    M[i, j] += wq * Pb[p0 + q, i] * Pb[p0 + q, j]
        scale = 0.0
        for i in range(m):
            scale = max(scale, abs(M[i, i]))
        if n < m or scale == 0.0 or abs(np.linalg.det(M / scale)) < 1e-12:
            ok[a] = False
            for q in range(n):
                sig[p0 + q] = 0.0
                for i in range(m):
                    C[p0 + q, i] = 0.0
            kap[a] = 0.0
            continue
        ok[a] = True
        Minv = np.linalg.inv(M)
        ka = 0.0
        for q in range(n):
            wq = omega[p0 + q]
            t = 0.0
            for i in range(m):
                c = 0.0
                for j in range(m):
                    c += Minv[i, j] * Pb[p0 + q, j]
                C[p0 + q, i] = wq * c
                t += y[i] * wq * c
            sig[p0 + q] = wq - t
            ka += wq - t
        kap[a] = ka


@njit(parallel=True, **JIT)
def _row_fix(indptr, indices, G, Pb, C, ell, ok, dG0, rres):
    """The row part of eq. C2: δG⁰_ac = ω_ac R_aᵀ M_a⁻¹ p_ac = R_aᵀ C_ac with the row residual
    R_a = T − Σ_c p_ac ⊗ G_ac (m×d; T = (I/ℓ_a, 0)); rres[a] = ℓ_a |R_a| (dimensionless)."""
    N = indptr.shape[0] - 1
    d = G.shape[1]
    m = Pb.shape[1]
    for a in prange(N):
        R = np.zeros((m, d))
        for i in range(d):
            R[i, i] = 1.0 / ell[a]
        for p in range(indptr[a], indptr[a + 1]):
            for i in range(m):
                for k in range(d):
                    R[i, k] -= Pb[p, i] * G[p, k]
        s = 0.0
        for i in range(m):
            for k in range(d):
                s += R[i, k] * R[i, k]
        rres[a] = math.sqrt(s) * ell[a]
        for p in range(indptr[a], indptr[a + 1]):
            for k in range(d):
                t = 0.0
                if ok[a]:
                    for i in range(m):
                        t += R[i, k] * C[p, i]
                dG0[p, k] = t


@njit(**JIT)
def _two_ring(indptr, indices, count_only, kptr, kind):
    """Sparsity of K: row c holds ∪_{a ∈ S(c)} S(a), S(a) = {a} ∪ nbrs(a) (sorted)."""
    N = indptr.shape[0] - 1
    mark = np.full(N, -1, np.int64)
    counts = np.zeros(N, np.int64)
    buf = np.empty(N, np.int64)
    for c in range(N):
        n = 0
        for qa in range(indptr[c] - 1, indptr[c + 1]):
            a = c if qa < indptr[c] else indices[qa]
            for qe in range(indptr[a] - 1, indptr[a + 1]):
                e = a if qe < indptr[a] else indices[qe]
                if mark[e] != c:
                    mark[e] = c
                    buf[n] = e
                    n += 1
        counts[c] = n
        if not count_only:
            row = np.sort(buf[:n])
            for i in range(n):
                kind[kptr[c] + i] = row[i]
    return counts


@njit(parallel=True, **JIT)
def _assemble(indptr, indices, rev, V2, omega, Pb, C, sig, kap, kptr, kind, data):
    """K of eq. C3 into the CSR pattern (kptr, kind), row c owned by one thread:
    K_cc += V_c² κ_c, K_ct += −V_c² σ_ct (t ∈ nbrs(c)); for a ∈ nbrs(c), s = pos(c in a's row):
    K_ca += −V_a² σ_as, K_ct += V_a² (ω_as δ_st − ω_as p_as·C_at) (t ∈ nbrs(a))."""
    N = indptr.shape[0] - 1
    m = Pb.shape[1]
    for c in prange(N):
        lo = kptr[c]
        hi = kptr[c + 1]
        for i in range(lo, hi):
            data[i] = 0.0
        if V2[c] != 0.0:
            data[sorted_position(kind, lo, hi, c)] += V2[c] * kap[c]
            for pt in range(indptr[c], indptr[c + 1]):
                data[sorted_position(kind, lo, hi, indices[pt])] -= V2[c] * sig[pt]
        for pc in range(indptr[c], indptr[c + 1]):
            a = indices[pc]
            if V2[a] == 0.0:
                continue
            ps = rev[pc]  # the pair (a, c) in a's row
            va = V2[a]
            data[sorted_position(kind, lo, hi, a)] -= va * sig[ps]
            ws = omega[ps]
            for pt in range(indptr[a], indptr[a + 1]):
                t = 0.0
                for i in range(m):
                    t += Pb[ps, i] * C[pt, i]
                v = -ws * t
                if pt == ps:
                    v += ws
                data[sorted_position(kind, lo, hi, indices[pt])] += va * v


@njit(parallel=True, **JIT)
def _apply(indptr, indices, V, omega, Pb, C, mu, G, out):
    """Eq. C2: out_ac = G_ac + V_a ω_ac (Δμ_c − p_ac · Σ_e C_ae Δμ_e), Δμ_e = μ_e − μ_a (G here
    already holds the row fix δG⁰)."""
    N = indptr.shape[0] - 1
    d = G.shape[1]
    m = Pb.shape[1]
    for a in prange(N):
        z = np.zeros((m, d))
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            for i in range(m):
                for j in range(d):
                    z[i, j] += C[p, i] * (mu[b, j] - mu[a, j])
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            for j in range(d):
                t = 0.0
                for i in range(m):
                    t += Pb[p, i] * z[i, j]
                out[p, j] = G[p, j] + V[a] * omega[p] * (mu[b, j] - mu[a, j] - t)


def column_sums(V, indptr, indices, G) -> np.ndarray:
    """s_c = Σ_a V_a g_ac (N, d): the left side of the integration constraint (I), with
    g_ac = G_ac (pair (a, c)) and g_cc = −Σ_b G_cb. The uniform-stress force is f_c = −P s_c."""
    N = len(indptr) - 1
    a = np.repeat(np.arange(N), np.diff(indptr))
    VG = V[a, None] * G
    s = np.zeros((N, G.shape[1]))
    np.add.at(s, indices, VG)
    np.add.at(s, a, -VG)
    return s


def row_residual(X, indptr, indices, G, basis: str = "linear") -> np.ndarray:
    """max_a of |Σ_c p(X_c − X_a) ⊗ G_ac − T| (linear part dimensionless, quadratic part in m),
    per particle (N,): the reproducing conditions (R) (F exact for affine, and quadratic,
    motions)."""
    N, d = X.shape
    a = np.repeat(np.arange(N), np.diff(indptr))
    D = X[indices] - X[a]
    lin = np.zeros((N, d, d))
    np.add.at(lin, a, D[:, :, None] * G[:, None, :])
    res = np.abs(lin - np.eye(d)).reshape(N, -1).max(1)
    if basis == "quadratic":
        iu = np.triu_indices(d)
        Q = D[:, iu[0]] * D[:, iu[1]]
        quad = np.zeros((N, Q.shape[1], d))
        np.add.at(quad, a, Q[:, :, None] * G[:, None, :])
        res = np.maximum(res, np.abs(quad).reshape(N, -1).max(1))
    return res


def _polys(Xs, quadratic):
    """[1, p(X)] of the points Xs (n, d), centred and scaled (the null space of eq. C3)."""
    c = Xs.mean(0)
    L = max(np.abs(Xs - c).max(), 1e-300)
    Y = (Xs - c) / L
    cols = [np.ones(len(Xs))] + [Y[:, i] for i in range(Y.shape[1])]
    if quadratic:
        d = Y.shape[1]
        cols += [Y[:, i] * Y[:, k] for i in range(d) for k in range(i, d)]
    return np.stack(cols, axis=1)


def consistent_gradients(X, V, indptr, indices, G, normals, free, basis: str = "linear",
                         weights=None, adjust_normals: bool = True, check: bool = True,
                         refine: int = 10, solver: str = "auto"):
    """The smallest weighted change of the gradients G (eq. C1–C3) that makes the force patch test
    exact: Σ_a V_a g_ac = n_c on every imposed column (c, j) (integration constraint (I)) and
    Σ_c p(X_c − X_a) ⊗ G_ac = T on every row (F exact for affine motions, with
    ``basis="quadratic"`` for quadratic ones too).

    X (N, d) m reference positions; V (N,) m^d the integration volumes (0 for held particles that
    should carry no energy); indptr (N+1,), indices (nnz,) the CSR neighbour list (symmetric, rows
    sorted, as :func:`sph.neighbours.neighbour_list`); G (nnz, d) 1/m the base gradients (any
    that satisfy (R) — Bonet–Lok, quadratic MLS, HPM's WLS; a row residual is corrected too);
    normals (N, d) m^(d−1) the boundary area vectors n_c (:func:`boundary_normals`); free (N, d)
    bool the imposed columns — a fixed degree of freedom (c, j) carries a reaction, its column is
    dropped (see :func:`column_mask`); weights (nnz,) ω_p > 0 or None (uniform; see
    :func:`pair_weights`); adjust_normals: move n on the boundary particles (‖n_c‖ > 0) by the least
    amount that makes eq. C3 solvable when (V, n) violate the discrete divergence theorem
    (otherwise those columns keep a residual; a traction must then be distributed by the adjusted
    n, ``info["normals"]``, for the patch test to hold); refine: passes of iterative refinement on
    the true column residual (the multipliers of C3 can be large and smooth and δG loses digits
    to cancellation; each pass gains ~20×, the quadratic basis at 1e5 particles needs ~8);
    solver: how eq. C3 is solved — ``"direct"`` (SuperLU), ``"amg"`` (conjugate gradients with
    the polynomial smoothed-aggregation hierarchy of :class:`sph.polynomial_amg.PolynomialAMG`,
    to :data:`AMG_RTOL` on the first pass; a pass that misses falls back to SuperLU) or
    ``"auto"`` (AMG for more than :data:`AMG_ABOVE` unknowns in 3-D, direct otherwise).

    The null space of C3 (polynomials of the basis vanishing on the dropped columns, per connected
    body) is removed by fixing μ = 0 at as many well-spread particles (pivoted QR of the
    polynomials' values), which changes no δG; one SuperLU factorisation (symmetric mode) serves
    all components j with the same imposed set.

    Returns (G_new (nnz, d), info) with info: ``row_residual`` (max over a of |(R) − T|),
    ``column_residual`` (max over imposed (c, j) of |Σ_a V_a g_ac,j − n_c,j| / max|n|),
    ``base_column_residual`` (the same for G), ``normals`` (the n actually enforced),
    ``normals_adjustment`` (max |Δn| / max |n|), ``incompatibility`` (the same before adjusting),
    ``correction`` (max |δG| / max |G|), ``pinned`` (multipliers fixed to remove the null space),
    ``singular_rows`` (rows whose moment matrix is singular: not corrected), ``time`` (s, by part),
    ``refinements``, ``residual_history``, ``n_unknowns``, ``solver`` (the one used, per group
    of components), ``solver_iterations`` (CG iterations, all passes and components),
    ``solver_levels`` (of each group's hierarchy; 1 for a direct solve) and ``solver_fallbacks``
    (AMG solves that missed their tolerance and were done by SuperLU)."""
    if basis not in BASES:
        raise ValueError(f"basis: {basis!r} is not one of {BASES}")
    if solver not in SOLVERS:
        raise ValueError(f"solver: {solver!r} is not one of {SOLVERS}")
    t0 = time.perf_counter()
    X = np.ascontiguousarray(X, dtype=np.float64)
    N, d = X.shape
    V = np.ascontiguousarray(V, dtype=np.float64)
    indptr = np.ascontiguousarray(indptr, dtype=np.int64)
    indices = np.ascontiguousarray(indices)
    G = np.ascontiguousarray(G, dtype=np.float64)
    n_in = np.asarray(normals, dtype=np.float64)
    free = np.asarray(free, dtype=bool)
    if V.shape != (N,) or np.any(V < 0) or not np.all(np.isfinite(V)):
        raise ValueError(f"V: expected (N,) = ({N},) finite volumes >= 0")
    if G.shape != (indices.shape[0], d):
        raise ValueError(f"G: expected shape (nnz, d) = ({indices.shape[0]}, {d}), got {G.shape}")
    if n_in.shape != (N, d) or free.shape != (N, d):
        raise ValueError(f"normals, free: expected shape (N, d) = ({N}, {d})")
    nnz = indices.shape[0]
    if weights is None:
        omega = np.ones(nnz)
    else:
        omega = np.ascontiguousarray(weights, dtype=np.float64)
        if omega.shape != (nnz,) or not np.all(omega > 0):
            raise ValueError("weights: expected (nnz,) weights > 0")
    quadratic = basis == "quadratic"
    m = d + (d * (d + 1) // 2 if quadratic else 0)
    Pb = np.zeros((nnz, m))
    C = np.zeros((nnz, m))
    sig = np.zeros(nnz)
    kap = np.zeros(N)
    ok = np.ones(N, np.bool_)
    ell = np.ones(N)
    _row_geometry(X, indptr, indices, omega, quadratic, Pb, C, sig, kap, ok, ell)
    t_rows = time.perf_counter()

    rev = reverse_pairs(indptr, indices)
    dummy_p = np.zeros(1, np.int64)
    counts = _two_ring(indptr, indices, True, dummy_p, dummy_p)
    kptr = np.zeros(N + 1, np.int64)
    np.cumsum(counts, out=kptr[1:])
    kind = np.empty(int(kptr[-1]), np.int64)
    _two_ring(indptr, indices, False, kptr, kind)
    data = np.empty(kind.size)
    V2 = np.where(ok, V * V, 0.0)
    _assemble(indptr, indices, rev, V2, omega, Pb, C, sig, kap, kptr, kind, data)
    K = sp.csr_matrix((data, kind, kptr), shape=(N, N))
    K.eliminate_zeros()
    t_asm = time.perf_counter()

    # per group of components j with the same imposed set: the unknowns (imposed columns less the
    # pins that remove the null space of eq. C3) and one factorisation
    groups = {}
    for j in range(d):
        groups.setdefault(free[:, j].tobytes(), []).append(j)
    ncomp, label = connected_components(K, directed=False)
    diagK = K.diagonal()
    nscale = max(np.abs(n_in).max(), 1e-300)
    n_used = n_in.copy()
    dG0 = np.zeros((nnz, d))
    rres = np.zeros(N)
    _row_fix(indptr, indices, G, Pb, C, ell, ok, dG0, rres)
    r = n_in - column_sums(V, indptr, indices, G + dG0)
    incompat = 0.0
    pinned = 0
    solvers = []
    for key, js in groups.items():
        act = free[:, js[0]] & (diagK > 0)
        pins = np.zeros(N, bool)
        for comp in range(ncomp):
            nodes = np.nonzero(label == comp)[0]
            if not act[nodes].any():
                continue
            Phi = _polys(X[nodes], quadratic)
            A_loc = act[nodes]
            PhiI = Phi[~A_loc]
            if PhiI.shape[0]:
                _, S, Vt = np.linalg.svd(PhiI, full_matrices=True)
                rank = int(np.sum(S > 1e-10 * S.max()))
                Z = Vt[rank:].T
            else:
                Z = np.eye(Phi.shape[1])
            if Z.shape[1] == 0:
                continue
            PA = Phi[A_loc] @ Z  # the null polynomials at the imposed nodes
            _, _, piv = sla.qr(PA.T, mode="economic", pivoting=True)
            act_nodes = nodes[A_loc]
            pins[act_nodes[piv[:Z.shape[1]]]] = True
            # solvability: Σ_c q(X_c) r_c = 0 for the null polynomials q; the least change of n on
            # the boundary particles of this component that restores it
            bnd = np.linalg.norm(n_in[act_nodes], axis=1) > 0
            if not bnd.any():
                continue
            PB = PA[bnd]
            idx_b = act_nodes[bnd]
            for j in js:
                dn = -PB @ np.linalg.lstsq(PB.T @ PB, PA.T @ r[act_nodes, j], rcond=None)[0]
                incompat = max(incompat, float(np.abs(dn).max()) / nscale)
                if adjust_normals:
                    r[idx_b, j] += dn
                    n_used[idx_b, j] += dn
        pinned = max(pinned, int(pins.sum()))
        idx = np.nonzero(act & ~pins)[0]
        if idx.size:
            Kaa = K[idx][:, idx]
            if solver == "amg" or (solver == "auto" and d == 3 and idx.size > AMG_ABOVE):
                from .polynomial_amg import PolynomialAMG

                Kaa = sp.csr_matrix(Kaa)
                amg = PolynomialAMG(Kaa, X[idx], _polys(X[idx], quadratic),
                                    _spacing(X, indptr, indices))
                solvers.append((js, idx, _IterativeSolve(Kaa, amg)))
            else:
                solvers.append((js, idx, _direct(Kaa)))
    t_fact = time.perf_counter()

    # solve, apply (eq. C2) and refine on the true residual of the corrected gradients: the
    # multipliers of eq. C3 can be large and smooth (near-polynomial), and δG, their local
    # non-polynomial part, then loses digits to cancellation; each pass removes most of it
    G_cur = G
    cres = []
    for it in range(1 + refine):
        if it > 0:
            _row_fix(indptr, indices, G_cur, Pb, C, ell, ok, dG0, rres)
            r = n_used - column_sums(V, indptr, indices, G_cur + dG0)
        mu = np.zeros((N, d))
        for js, idx, lu in solvers:
            for j in js:
                mu[idx, j] = lu.solve(r[idx, j], AMG_RTOL if it == 0 else AMG_RTOL_REFINE)
        G_next = np.empty_like(G)
        _apply(indptr, indices, V, omega, Pb, C, mu, G_cur + dG0, G_next)
        G_cur = G_next
        res = n_used - column_sums(V, indptr, indices, G_cur)
        cres.append(float(np.abs(res[free]).max() / nscale) if free.any() else 0.0)
        if cres[-1] < 1e-14 or (it > 0 and cres[-1] > 0.5 * cres[-2]):
            break
    G_new = G_cur
    t_solve = time.perf_counter()

    s0 = column_sums(V, indptr, indices, G)
    info = dict(normals=n_used, pinned=pinned, n_unknowns=int(free.sum()),
                singular_rows=np.nonzero(~ok)[0],
                normals_adjustment=float(np.abs(n_used - n_in).max() / nscale),
                incompatibility=incompat, refinements=len(cres) - 1, residual_history=cres,
                solver=[type(lu).__name__ == "_IterativeSolve" and "amg" or "direct"
                        for _, _, lu in solvers],
                solver_iterations=sum(getattr(lu, "iterations", 0) for _, _, lu in solvers),
                solver_levels=[getattr(getattr(lu, "amg", None), "levels", 1)
                               for _, _, lu in solvers],
                solver_fallbacks=sum(getattr(lu, "fallbacks", 0) for _, _, lu in solvers),
                column_residual=cres[-1],
                base_column_residual=float(np.abs((s0 - n_in)[free]).max() / nscale)
                if free.any() else 0.0,
                correction=float(np.abs(G_new - G).max() / max(np.abs(G).max(), 1e-300)),
                time=dict(rows=t_rows - t0, assemble=t_asm - t_rows, factorise=t_fact - t_asm,
                          solve=t_solve - t_fact))
    if check:
        okr = ok if ok.any() else np.ones(N, bool)
        info["row_residual"] = float(row_residual(X, indptr, indices, G_new, basis)[okr].max())
    info["time"]["total"] = time.perf_counter() - t0
    return G_new, info


SOLVERS = ("auto", "direct", "amg")

AMG_ABOVE = 30_000
"""Unknowns of eq. C3 above which ``solver="auto"`` solves it by AMG-CG in 3-D. Measured on the
3-D micro-cantilever (quadratic basis, two groups of components, 2 cores under a load of 5–8):
at 12 000 particles (11 000 unknowns) SuperLU's whole correction is 4× faster (12.5 s against
50 s); at 38 000 (36 000 unknowns) the two take about the same time (157 s, 173 s) and AMG a
third of the memory (1.2 GB against 3.3 GB); at 87 800 particles AMG takes 435 s and 2.8 GB,
where SuperLU took 623 s and 14.5 GB at 101 000 on an idle machine."""

AMG_RTOL = 1e-10
"""Relative residual of the first AMG-CG solve of eq. C3: the refinement passes re-solve on the
true column residual, so an inexact solve still reaches the ~1e-14 the direct one reaches."""

AMG_RTOL_REFINE = 1e-6
"""Relative residual of the refinement passes' solves: their right side is already the residual
of the last pass (1e-9 of the first), so 1e-6 of it is below the round-off of δG."""


def _spacing(X, indptr, indices) -> float:
    """The median over particles of the distance to the nearest neighbour (m): the lattice
    spacing, for the aggregates of :class:`sph.polynomial_amg.PolynomialAMG`."""
    a = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    dist = np.linalg.norm(X[indices] - X[a], axis=1)
    dist[dist == 0] = np.inf
    rows = np.diff(indptr) > 0
    near = np.minimum.reduceat(dist, indptr[:-1][rows])
    near = near[np.isfinite(near)]
    return float(np.median(near)) if near.size else 1.0


class _direct:
    """b ↦ K⁻¹ b by one SuperLU factorisation (symmetric mode) of K."""

    def __init__(self, K):
        self.lu = spla.splu(sp.csc_matrix(K), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                            options=dict(SymmetricMode=True))

    def solve(self, b, rtol=None):
        return self.lu.solve(b)


class _IterativeSolve:
    """b ↦ K⁻¹ b by AMG-preconditioned CG to a relative residual ``rtol``; a solve that misses it
    (after :data:`sph.polynomial_amg.MAXITER` iterations) is done by SuperLU, factorised then
    and kept. Counts ``iterations`` and ``fallbacks``."""

    def __init__(self, K, amg):
        self.K, self.amg = K, amg
        self.lu = None
        self.iterations = 0
        self.fallbacks = 0

    def solve(self, b, rtol=AMG_RTOL):
        if self.lu is None:
            if not np.any(b):
                return np.zeros_like(b)
            x, ok, its = self.amg.solve(self.K, b, rtol)
            self.iterations += its
            if ok:
                return x
            self.fallbacks += 1
            self.lu = _direct(self.K)
        return self.lu.solve(b)


def column_mask(fixed, mode: str = "dof") -> np.ndarray:
    """The imposed columns ``free`` (N, d) of :func:`consistent_gradients` from the fixed degrees of
    freedom ``fixed`` (N, d) bool.

    ``"dof"``: column (c, j) is imposed where DOF (c, j) is free. The force f_c,i = −Σ_j P_ij
    (s_c,j − n_c,j) then balances on every free DOF for every uniform P whose P_ij vanishes where
    (c, j) is dropped and (c, i) free — in particular on a symmetry (roller) plane, where the
    symmetric state has no shear stress on the plane, and for a diagonal P (the uniaxial block).
    ``"particle"``: every column of a particle with any free DOF — exact for every uniform P
    (shear along a roller plane loaded by its traction included), at the cost of more
    constraints. On a symmetry plane use ``"dof"``: the half model of a clamped–clamped beam
    then matches the full model's first period to 5e-6 at H/Δx = 10 ("particle": 3e-4)."""
    fixed = np.asarray(fixed, dtype=bool)
    if mode == "dof":
        return ~fixed
    if mode == "particle":
        return np.repeat((~fixed).any(axis=1, keepdims=True), fixed.shape[1], axis=1)
    raise ValueError(f"mode: {mode!r} is not one of 'dof', 'particle'")


def consistent_discretisation(disc, V_integration, normals, free, basis: str = "quadratic",
                              weights: str | np.ndarray = "uniform", **options):
    """A :class:`sph.total_lagrangian.Discretisation` whose gradients satisfy the force patch test: ``disc``
    (any G with F = Σ (x_b − x_a) ⊗ G_ab: CSPH's, or HPM's through
    :func:`sph.hpm.wls_discretisation`) with G replaced by :func:`consistent_gradients`, G_ba
    recomputed, and V = ``V_integration`` (the energy Σ V_a ψ(F_a); masses ``disc.m`` unchanged).
    ``weights``: a kind of :func:`pair_weights` (radius: the support 2h, or r_e for
    ``disc.kernel == "wls"``) or an array. Returns (Discretisation, info)."""
    from .correction import reverse_gradients
    from .kernels import SUPPORT
    from .total_lagrangian import Discretisation

    if isinstance(weights, str):
        radius = disc.h if disc.kernel == "wls" else SUPPORT * disc.h
        weights = pair_weights(disc.X, disc.indptr, disc.indices, radius, weights)
    Vi = np.ascontiguousarray(V_integration, dtype=np.float64)
    G, info = consistent_gradients(disc.X, Vi, disc.indptr, disc.indices, disc.G, normals, free,
                                   basis, weights, **options)
    GT = reverse_gradients(disc.indptr, disc.indices, G)
    new = Discretisation(disc.X, Vi, disc.m, disc.h, disc.kernel, disc.indptr, disc.indices,
                         G, GT, disc.L, disc.ok)
    return new, info
