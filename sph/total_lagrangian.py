"""The total-Lagrangian gradient form shared by CSPH (paper 000) and, for its statics and the
integration-consistent variant, HPM (paper 004): everything that follows from

    F_a = Σ_b (x_b − x_a) ⊗ G_ab                         (000 eq. 35, difference form)

with G_ab a gradient per neighbour pair fixed in the reference configuration, and the internal
force derived from the stored energy Π = Σ_a V_a ψ(F_a) (000 eq. 7–24 in total-Lagrangian form):

    f_a = −∂Π/∂x_a = Σ_b (V_a P_a G_ab − V_b P_b G_ba)    (:func:`internal_force`).

Π is invariant under rigid translations and rotations, so Σ f = 0 and Σ x × f = 0 to round-off:
linear and angular momentum are conserved (eq. 16–28). The tangent K = ∂²Π/∂x∂x is symmetric
(:func:`tangent_matrix`), which the static Newton (:mod:`sph.static`) and the modal solve use.

* :class:`Discretisation` — reference positions, volumes, masses, CSR pairs, G_ab and G_ba;
* :func:`deformation_gradients`, :func:`stress_pass`, :func:`internal_force` — one evaluation;
* :class:`Body` — a discretisation with its materials (a :class:`~workbench.materials.MaterialTable`
  row per particle) and history, evaluated x ↦ (f, dP/dF);
* :func:`advance` — ``n`` velocity-Verlet steps fused into one compiled loop (stress, force,
  kicks and drift per particle), the explicit time loop of csph.

Held particles (a clamp block) enter F of their neighbours through their positions; with
``V_energy`` their integration volume may differ from the volume that gives their mass (zero for a
clamp modelled as such: it then adds no elastic layer).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numba import njit, prange

from workbench.materials import MaterialTable
from workbench.materials.kernels import material_point, material_points, svk_point

from .integrate import kick_drift_row, kick_row
from .kernels import JIT, N_CHUNKS
from .neighbours import sorted_position

FASTMATH = {"contract", "arcp"}
"""LLVM flags of the time loop: fused multiply–add and reciprocal multiplication only (no
reassociation, so sums keep their order and the conservation tests hold to round-off)."""

SERIAL_BELOW = 20_000
"""Particle count under which the time loop runs on one thread: a step of a small body is
shorter than the cost of waking the thread pool several times per step (on a loaded 2-core
machine two threads made a 400-particle plate 50× slower)."""


@dataclass
class Discretisation:
    """The reference-configuration data of a gradient-form body.

    X (N, d) m; V (N,) integration volumes, m^d; m (N,) kg; h m (kernel scale, for information);
    kernel name; indptr/indices CSR neighbours; G, GT (nnz, d) the gradients G_ab and G_ba, 1/m;
    L (N, d, d) the correction matrices where they exist (eq. 31); ok (N,) the gradient regular;
    correction: the gradient correction used ('linear', 'quadratic', 'wls' …). With symmetry
    planes (:mod:`sph.mirror`) ``indices`` also point at ghosts (≥ N): the mirror images of the
    particles ghost_src (n_g,), at ghost_sign ⊙ x_src + ghost_offset (n_g, d); V is then the full
    body's volume and w (N,) each particle's share of it."""

    X: np.ndarray
    V: np.ndarray
    m: np.ndarray
    h: float
    kernel: str
    indptr: np.ndarray
    indices: np.ndarray
    G: np.ndarray
    GT: np.ndarray
    L: np.ndarray
    ok: np.ndarray
    correction: str = ""
    ghost_src: np.ndarray | None = None
    ghost_sign: np.ndarray | None = None
    ghost_offset: np.ndarray | None = None
    w: np.ndarray | None = None

    @property
    def n_ghost(self) -> int:
        """Mirror images among the neighbours (:mod:`sph.mirror`): indices ≥ n are ghosts."""
        return 0 if self.ghost_src is None else self.ghost_src.shape[0]

    @property
    def V_energy(self) -> np.ndarray:
        """The volumes of the stored energy, work and reactions of these particles: V times the
        share w of a particle on symmetry planes (:mod:`sph.mirror`); V without them."""
        return self.V if self.w is None else self.V * self.w

    @property
    def member_src(self) -> np.ndarray:
        """(n + n_ghost,) the particle each index of ``indices`` stands for: itself, or a ghost's
        source."""
        src = np.arange(self.n, dtype=np.int64)
        return src if self.ghost_src is None else np.concatenate([src, self.ghost_src])

    def extend(self, x) -> np.ndarray:
        """Positions of the particles and their ghosts, (n + n_ghost, d); x itself without
        ghosts."""
        if self.ghost_src is None:
            return x
        from .mirror import with_images

        return with_images(x, self.ghost_src, self.ghost_sign, self.ghost_offset)

    def mirror_VP(self, VP) -> None:
        """The ghosts' rows of VP (n + n_ghost, d, d), in place: R (V P)_src R, R = diag(sign)."""
        if self.ghost_src is not None:
            from .mirror import image_rows

            VP[self.n:] = image_rows(VP[:self.n], self.ghost_src, self.ghost_sign)

    @property
    def n(self) -> int:
        return self.X.shape[0]

    @property
    def dim(self) -> int:
        return self.X.shape[1]

    def nbytes(self) -> int:
        return sum(a.nbytes for a in (self.X, self.V, self.m, self.indptr, self.indices, self.G,
                                      self.GT))


# ================================================================================================
# Deformation gradient (eq. 35), stress (shared material routine), internal force
# ================================================================================================

@njit(inline="always", **JIT)
def _deformation_gradient_row(a, x, indptr, indices, G, F):
    """Eq. 35: F_a = Σ_b (x_b − x_a) ⊗ G_ab into the 3×3 F (F33 = 1 in 2-D)."""
    d = x.shape[1]
    for i in range(3):
        for j in range(3):
            F[i, j] = 0.0
    if d == 2:
        F[2, 2] = 1.0
    for p in range(indptr[a], indptr[a + 1]):
        b = indices[p]
        for i in range(d):
            dxi = x[b, i] - x[a, i]
            for j in range(d):
                F[i, j] += dxi * G[p, j]


@njit(parallel=True, **JIT)
def deformation_gradients(x, indptr, indices, G):
    """Eq. 35 for every particle (the rows of ``indptr``; x may also hold ghosts), (N, 3, 3)."""
    N = indptr.shape[0] - 1
    F = np.empty((N, 3, 3))
    for a in prange(N):
        _deformation_gradient_row(a, x, indptr, indices, G, F[a])
    return F


@njit(inline="always", **JIT)
def _stress_row(a, x, indptr, indices, G, V, h_old, prm, mat_id, want_tangent, F, P, A, h_new,
                VP, F_all, A_all, status):
    """F_a (eq. 35) → P_a by the shared material routine (row ``mat_id[a]`` of the parameter
    table) → VP_a = V_a P_a (d×d block). Also J_a > 0 is checked (status 1000 otherwise). A
    particle without integration volume (V_a = 0: a clamped corner, a particle failed under the
    'literal' rule, :mod:`sph.crack`) carries no stress: VP_a = 0, history kept, its material not
    evaluated."""
    d = x.shape[1]
    _deformation_gradient_row(a, x, indptr, indices, G, F)
    if V[a] == 0.0:
        _inactive_row(a, h_old, h_new, VP, status)
        if F_all.shape[0] > 0:
            for i in range(3):
                for j in range(3):
                    F_all[a, i, j] = F[i, j]
        return
    J = (F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1])
         - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
         + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0]))
    if not (J > 0.0):
        status[a] = 1000
        for i in range(d):
            for j in range(d):
                VP[a, i, j] = 0.0
        return
    st = material_point(F, h_old[a], prm[mat_id[a]], P, h_new[a], A, want_tangent)
    status[a] = st
    for i in range(d):
        for j in range(d):
            VP[a, i, j] = V[a] * P[i, j]
    if F_all.shape[0] > 0:
        for i in range(3):
            for j in range(3):
                F_all[a, i, j] = F[i, j]
    if want_tangent:
        for i in range(d):
            for j in range(d):
                for k in range(d):
                    for l in range(d):
                        A_all[a, i, j, k, l] = A[i, j, k, l]


@njit(inline="always", **JIT)
def _inactive_row(a, h_old, h_new, VP, status):
    """A particle without integration volume: VP_a = 0, status 0, history carried."""
    for i in range(VP.shape[1]):
        for j in range(VP.shape[2]):
            VP[a, i, j] = 0.0
    for k in range(h_old.shape[1]):
        h_new[a, k] = h_old[a, k]
    status[a] = 0


@njit(parallel=True, **JIT)
def stress_pass(x, indptr, indices, G, V, h_old, prm, mat_id, want_tangent, VP, h_new, F_all,
                A_all, status):
    """:func:`_stress_row` over all particles (the rows of ``indptr``; x may also hold ghosts), in
    chunks that allocate their scratch once.

    prm (n_mat, N_PARAMS) the material table, mat_id (N,) its rows; VP (N, d, d) out: V_a P_a;
    h_new (N, nh) out; F_all (N, 3, 3) or (0, 3, 3): F out if non-empty; A_all (N, d, d, d, d)
    or empty: dP/dF out when ``want_tangent``; status (N,) int64 out."""
    N = indptr.shape[0] - 1
    chunk = (N + N_CHUNKS - 1) // N_CHUNKS
    for c in prange(N_CHUNKS):
        F = np.empty((3, 3))
        P = np.empty((3, 3))
        A = np.empty((3, 3, 3, 3))
        for a in range(c * chunk, min(N, (c + 1) * chunk)):
            _stress_row(a, x, indptr, indices, G, V, h_old, prm, mat_id, want_tangent, F, P, A,
                        h_new, VP, F_all, A_all, status)


@njit(inline="always", **JIT)
def _force_row(a, VP, indptr, indices, G, GT, f):
    """f_a = Σ_b (V_a P_a G_ab − V_b P_b G_ba) = −∂Π/∂x_a, written into f[a]."""
    d = f.shape[1]
    for i in range(d):
        f[a, i] = 0.0
    for p in range(indptr[a], indptr[a + 1]):
        b = indices[p]
        for i in range(d):
            s = 0.0
            for j in range(d):
                s += VP[a, i, j] * G[p, j] - VP[b, i, j] * GT[p, j]
            f[a, i] += s


@njit(parallel=True, **JIT)
def internal_force(VP, indptr, indices, G, GT):
    """f_a = −Σ_b (V_b P_b G_ba − V_a P_a G_ab) for every particle (the rows of ``indptr``; VP may
    also hold ghosts), (N, d), N (N/m in 2-D)."""
    N, d = indptr.shape[0] - 1, VP.shape[1]
    f = np.empty((N, d))
    for a in prange(N):
        _force_row(a, VP, indptr, indices, G, GT, f)
    return f


class Body:
    """A gradient-form body: discretisation, materials (``table`` and a row ``mat_id`` per
    particle) and history, with the evaluation x ↦ (F, P, f) used by every driver.

    ``hourglass`` (:mod:`sph.hourglass`, dimensionless α ≥ 0; 0: off) adds the energy-consistent
    zero-energy-mode control of csph."""

    def __init__(self, disc: Discretisation, table, mat_id=None, history=None,
                 hourglass: float = 0.0):
        from .hourglass import folded_rows, hourglass_stiffness

        self.disc = disc
        self.table = MaterialTable.of(table)
        N = disc.n
        self.mat_id = (np.zeros(N, np.int64) if mat_id is None
                       else np.ascontiguousarray(mat_id, dtype=np.int64))
        self.hourglass = float(hourglass)
        if not (self.hourglass >= 0 and math.isfinite(self.hourglass)):
            raise ValueError(f"hourglass: {hourglass} is not allowed; the coefficient must be >= 0")
        # K_hg over the members (the ghosts of symmetry planes included), its rows folded onto
        # the real DOFs per coordinate (sph.hourglass.folded_rows) for the force
        self.K_hg = (hourglass_stiffness(disc, self.hourglass, self.table.mu)
                     if self.hourglass > 0 else None)
        self.hg_rows = folded_rows(disc, self.K_hg) if self.K_hg is not None else None
        self.prm = self.table.params()
        d = disc.dim
        self.history = (self.table.initial_history(self.mat_id) if history is None
                        else np.ascontiguousarray(history, dtype=np.float64))
        self.history_trial = self.history.copy()
        self.VP = np.zeros((N + disc.n_ghost, d, d))
        self.F = np.zeros((N, 3, 3))
        self.status = np.zeros(N, np.int64)
        self._noA = np.zeros((0, d, d, d, d))

    @property
    def material(self):
        """The material of a one-material body (the table's first row)."""
        return self.table[0]

    def evaluate(self, x, tangent: bool = False):
        """Internal forces f (N, d) at positions x from the committed history; fills self.F,
        self.VP, self.history_trial, self.status; with ``tangent`` returns (f, A) with A the
        (N, d, d, d, d) block of dP/dF."""
        dsc = self.disc
        A = np.zeros((dsc.n,) + (dsc.dim,) * 4) if tangent else self._noA
        stress_pass(dsc.extend(x), dsc.indptr, dsc.indices, dsc.G, dsc.V, self.history, self.prm,
                    self.mat_id, tangent, self.VP, self.history_trial, self.F, A, self.status)
        dsc.mirror_VP(self.VP)
        f = internal_force(self.VP, dsc.indptr, dsc.indices, dsc.G, dsc.GT)
        if dsc.w is not None:  # the full body's force times the share (sph.mirror)
            f *= dsc.w[:, None]
        if self.K_hg is not None:
            f -= self.hourglass_force(x)
        return (f, A) if tangent else f

    def hourglass_force(self, x) -> np.ndarray:
        """R_k x_ext,k for each coordinate k (:func:`sph.hourglass.folded_rows`), (N, d): minus
        the hourglass control's force at positions x (N, d)."""
        indptr, indices, data = self.hg_rows
        xe = self.disc.extend(np.ascontiguousarray(x, dtype=np.float64))
        N, d = self.disc.n, self.disc.dim
        return np.stack([sp.csr_matrix((data[:, k], indices, indptr), shape=(N, len(xe)))
                         @ xe[:, k] for k in range(d)], axis=1)

    def tangent(self, A) -> sp.csr_matrix:
        """∂²(Π + Π_hg)/∂x∂x, (N d × N d)."""
        K = tangent_matrix(self.disc, A)
        if self.K_hg is not None:
            from .hourglass import folded_hessian

            K = (K + folded_hessian(self.disc, self.K_hg)).tocsr()
        return K

    def deformation_gradients(self, x):
        """Eq. 35 at positions x (N, d) — the ghosts of symmetry planes included — (N, 3, 3)."""
        d = self.disc
        return deformation_gradients(np.ascontiguousarray(d.extend(x)), d.indptr, d.indices, d.G)

    def commit(self):
        """Accept the last evaluation's history (end of a converged load step or time step)."""
        self.history[:] = self.history_trial

    def stress(self, kind: str = "sigma"):
        """Stress of the last evaluation, (N, 3, 3): 'P', 'tau' or 'sigma' (Cauchy), Pa."""
        P, _, _ = material_points(np.ascontiguousarray(self.F), self.history, self.prm, self.mat_id)
        if kind == "P":
            return P
        tau = np.einsum("nij,nkj->nik", P, self.F)
        if kind == "tau":
            return tau
        return tau / np.linalg.det(self.F)[:, None, None]


# ================================================================================================
# Tangent stiffness K = ∂²Π/∂x∂x (static Newton, modal solve)
# ================================================================================================

@njit(**JIT)
def _tangent_pattern(indptr, indices, src):
    """The block sparsity of K: particle e is in row c when some stencil {a} ∪ nbrs(a) holds both,
    a stencil member m standing for particle src[m] (a ghost for its source, :mod:`sph.mirror`;
    src[m] = m for the particles). Returns the block CSR (bptr (N+1,), bcol (nnzb,)), each row
    sorted."""
    N = indptr.shape[0] - 1
    cnt = np.zeros(N + 1, np.int64)  # the owners a of each c: c ∈ src(stencil(a))
    for a in range(N):
        cnt[a + 1] += 1
        for p in range(indptr[a], indptr[a + 1]):
            cnt[src[indices[p]] + 1] += 1
    optr = np.cumsum(cnt)
    own = np.empty(optr[N], np.int64)
    fill = optr[:N].copy()
    for a in range(N):
        own[fill[a]] = a
        fill[a] += 1
        for p in range(indptr[a], indptr[a + 1]):
            c = src[indices[p]]
            own[fill[c]] = a
            fill[c] += 1
    mark = np.full(N, -1, np.int64)
    counts = np.zeros(N + 1, np.int64)
    rows = []
    for c in range(N):
        cols = []
        for q in range(optr[c], optr[c + 1]):
            a = own[q]
            for r in range(indptr[a], indptr[a + 1] + 1):
                e = a if r == indptr[a + 1] else src[indices[r]]
                if mark[e] != c:
                    mark[e] = c
                    cols.append(e)
        arr = np.array(cols, dtype=np.int64)
        arr.sort()
        rows.append(arr)
        counts[c + 1] = arr.shape[0]
    bptr = np.cumsum(counts)
    bcol = np.empty(bptr[-1], np.int64)
    for c in range(N):
        bcol[bptr[c]:bptr[c + 1]] = rows[c]
    return bptr, bcol


@njit(**JIT)
def _assemble_tangent(indptr, indices, G, V, A, bptr, bcol, d, src, sign, vals):
    """K_(c k),(e l) += V_a Σ_jm g_ac,j A_a[k,j,l,m] g_ae,m for every stencil a ∪ nbrs(a), with
    g_ab = G_ab, g_aa = −Σ_b G_ab (∂F_a/∂x_c = I ⊗ g_ac), written straight into the CSR values of
    the block pattern (row (c, k): the blocks e of row c, each d wide). A stencil member m is
    particle src[m] with the factor sign[m, k] on its DOF k (a ghost, :mod:`sph.mirror`: the fold
    Tᵀ K T; src[m] = m and sign 1 for the particles). Serial: stencils overlap."""
    N = indptr.shape[0] - 1
    for i in range(vals.shape[0]):
        vals[i] = 0.0
    g = np.empty((64, d))
    ids = np.empty(64, np.int64)
    sg = np.empty((64, d))
    B = np.empty((64, d, d, d))
    for a in range(N):
        n = indptr[a + 1] - indptr[a] + 1
        if n > g.shape[0]:
            g = np.empty((2 * n, d))
            ids = np.empty(2 * n, np.int64)
            sg = np.empty((2 * n, d))
        ids[0] = a
        for k in range(d):
            g[0, k] = 0.0
            sg[0, k] = 1.0
        for q in range(1, n):
            p = indptr[a] + q - 1
            m = indices[p]
            ids[q] = src[m]
            for k in range(d):
                g[q, k] = G[p, k]
                g[0, k] -= G[p, k]
                sg[q, k] = sign[m, k]
        Va = V[a]
        if Va == 0.0:
            continue
        if B.shape[0] < n:
            B = np.empty((2 * n, d, d, d))
        for s in range(n):  # B_s[k, l, m] = V_a Σ_j g_sj A_a[k, j, l, m]
            for k in range(d):
                for l in range(d):
                    for m in range(d):
                        v = 0.0
                        for j in range(d):
                            v += g[s, j] * A[a, k, j, l, m]
                        B[s, k, l, m] = Va * v
        for s in range(n):
            c = ids[s]
            row_len = (bptr[c + 1] - bptr[c]) * d
            for t in range(n):
                e = ids[t]
                pos = sorted_position(bcol, bptr[c], bptr[c + 1], e) - bptr[c]
                for k in range(d):
                    base = bptr[c] * d * d + k * row_len + pos * d
                    for l in range(d):
                        v = 0.0
                        for m in range(d):
                            v += B[s, k, l, m] * g[t, m]
                        vals[base + l] += v * sg[s, k] * sg[t, l]


def _fold(disc: Discretisation):
    """(src, sign) of the stencil members — the particles, then the ghosts (:mod:`sph.mirror`)."""
    N, d = disc.n, disc.dim
    sign = np.ones((N, d)) if not disc.n_ghost else np.concatenate([np.ones((N, d)), disc.ghost_sign])
    return disc.member_src, np.ascontiguousarray(sign)


def tangent_pattern(disc: Discretisation):
    """The DOF-level CSR pattern (indptr, indices) of K and the block pattern (bptr, bcol), built
    once per discretisation (cached on it)."""
    cached = getattr(disc, "_tangent_pattern", None)
    if cached is not None:
        return cached
    d = disc.dim
    bptr, bcol = _tangent_pattern(disc.indptr, disc.indices, _fold(disc)[0])
    nb = np.diff(bptr)
    row_len = np.repeat(nb * d, d)  # every DOF row (c, k) holds the blocks of row c, d wide
    indptr = np.zeros(disc.n * d + 1, np.int64)
    np.cumsum(row_len, out=indptr[1:])
    cols = (bcol[:, None] * d + np.arange(d)[None, :]).ravel()  # block columns → DOF columns
    indices = np.concatenate([np.tile(cols[bptr[c] * d:bptr[c + 1] * d], d)
                              for c in range(disc.n)])
    cached = (indptr, indices, bptr, bcol)
    disc._tangent_pattern = cached
    return cached


def tangent_matrix(disc: Discretisation, A: np.ndarray) -> sp.csr_matrix:
    """The symmetric Hessian ∂²Π/∂x∂x = −∂f/∂x, (N d × N d) CSR with sorted indices, from dP/dF
    blocks A (N, d,d,d,d), assembled into the pattern of :func:`tangent_pattern`. With symmetry
    planes (:mod:`sph.mirror`): the Hessian of Π_q = Σ w_a V_a ψ(F_a) over the real and ghost
    positions, folded onto the real DOFs, Tᵀ K_ext T (x_ghost = sign ⊙ x_src + offset)."""
    d = disc.dim
    indptr, indices, bptr, bcol = tangent_pattern(disc)
    vals = np.empty(indices.shape[0])
    _assemble_tangent(disc.indptr, disc.indices, disc.G, disc.V_energy, A, bptr, bcol, d,
                      *_fold(disc), vals)
    K = sp.csr_matrix((vals, indices, indptr), shape=(disc.n * d, disc.n * d))
    K.has_sorted_indices = True
    return K


# ================================================================================================
# Explicit dynamics: fused stress / force / velocity-Verlet loop
# ================================================================================================

@njit(parallel=True, fastmath=FASTMATH, **JIT)
def _advance(n_steps, x, v, acc, m, f_ext, fixed, v_fix, dt, damping, indptr, indices, G, GT, V,
             h_a, h_b, prm, mat_id, all_svk, VP, status, hg_indptr, hg_indices, hg_data, imp,
             dcols, xe, gsrc, gsign, goff, w):
    """``n_steps`` velocity-Verlet steps from the synchronised state (x, v, acc):
    kick–drift; F → P (shared material routine) → V P; force → acceleration → kick.
    ``h_a`` holds the committed history on entry and on exit (``h_b`` is scratch). The hourglass
    stiffness adds −R_k x_k to the force (CSR rows of :func:`sph.hourglass.folded_rows`, data
    (nnz, d), indices into the positions with the ghosts; empty when off). ``imp`` (N, d), or
    (0, d) to skip: adds on every fixed DOF the impulse of the force acting on it,
    Σ_steps ½ (f_n + f_n+1) dt (:func:`_impulse_row`). ``dcols`` (n_mat,): the damage column
    of each material's history (:func:`workbench.materials.failure.damage_columns`, −1: cannot
    fail) — the loop stops after the first step in which a point reaches damage ≥ 1, i.e. fails
    (for the pairs of :mod:`sph.crack` to be updated); empty: no such stop. Returns (steps done, why): why
    0 all done, 1 a failed material point (status ≠ 0) in the last step, 2 a point newly
    damaged. Symmetry planes (:mod:`sph.mirror`; gsrc empty: none): ``xe`` (N + n_g, d) scratch
    for the positions with the ghosts gsign ⊙ x[gsrc] + goff, the ghosts' V P mirrored after
    the stress pass, the internal force times the shares ``w`` (N,)."""
    N, d = x.shape
    ng = gsrc.shape[0]
    xs = xe if ng > 0 else x
    track = imp.shape[0] > 0
    chunk = (N + N_CHUNKS - 1) // N_CHUNKS
    dummyF = np.zeros((0, 3, 3))
    dummyA = np.zeros((0, d, d, d, d))
    hg_on = hg_indptr.shape[0] > 1
    # Without hourglass control the force loop reads no positions, so the next step's
    # kick–drift is fused into it (one pass less over the particles); the last step of the call
    # stops at the synchronised state.
    fuse = not hg_on
    watch = dcols.shape[0] > 0
    for a in prange(N):
        kick_drift_row(a, x, v, acc, fixed, v_fix, dt, damping)
    for s in range(n_steps):
        nbad = 0
        nnew = 0
        if ng > 0:
            for a in prange(N):
                for i in range(d):
                    xe[a, i] = x[a, i]
            for g in prange(ng):
                for i in range(d):
                    xe[N + g, i] = gsign[g, i] * x[gsrc[g], i] + goff[g, i]
        for c in prange(N_CHUNKS):
            F = np.zeros((3, 3))
            P = np.empty((3, 3))
            A = np.empty((3, 3, 3, 3))
            for a in range(c * chunk, min(N, (c + 1) * chunk)):
                if d == 2:
                    nbad += _stress_row_2d(a, xs, indptr, indices, G, V, h_a, prm, mat_id, all_svk,
                                           F, P, A, h_b, VP, status)
                else:
                    _stress_row(a, xs, indptr, indices, G, V, h_a, prm, mat_id, False, F, P, A,
                                h_b, VP, dummyF, dummyA, status)
                    nbad += status[a] != 0
                if watch:
                    c = dcols[mat_id[a]]
                    if c >= 0 and h_b[a, c] >= 1.0 and h_a[a, c] < 1.0:
                        nnew += 1
        for g in prange(ng):
            for i in range(d):
                for j in range(d):
                    VP[N + g, i, j] = gsign[g, i] * VP[gsrc[g], i, j] * gsign[g, j]
        last = s == n_steps - 1 or nbad > 0 or nnew > 0
        drift_here = fuse and not last
        for a in prange(N):
            # f_a = Σ_b (V_a P_a G_ab − V_b P_b G_ba); a = (f + f_ext)/m; second half kick
            o0 = acc[a, 0] * m[a]  # the force of the previous step (for the impulse)
            o1 = acc[a, 1] * m[a]
            o2 = acc[a, d - 1] * m[a]
            if d == 2:
                _force_row_2d(a, VP, indptr, indices, G, GT, f_ext, w[a], acc)
            else:
                _force_row(a, VP, indptr, indices, G, GT, acc)
                for i in range(d):
                    acc[a, i] = w[a] * acc[a, i] + f_ext[a, i]
            if hg_on:
                for i in range(d):
                    for q in range(hg_indptr[a], hg_indptr[a + 1]):
                        acc[a, i] -= hg_data[q, i] * xs[hg_indices[q], i]
            if track:
                _impulse_row(a, acc, fixed, o0, o1, o2, dt, imp)
            ma = 1.0 / m[a]
            for i in range(d):
                acc[a, i] *= ma
            kick_row(a, v, acc, fixed, v_fix, dt, damping)
            if drift_here:
                kick_drift_row(a, x, v, acc, fixed, v_fix, dt, damping)
        if h_a.shape[1] > 0:
            for a in prange(N):
                for k in range(h_a.shape[1]):
                    h_a[a, k] = h_b[a, k]
        if nbad > 0:
            return s + 1, 1
        if nnew > 0:
            return s + 1, 2
        if not fuse and not last:
            for a in prange(N):
                kick_drift_row(a, x, v, acc, fixed, v_fix, dt, damping)
    return n_steps, 0


@njit(inline="always", **JIT)
def _impulse_row(a, f, fixed, o0, o1, o2, dt, imp):
    """imp[a, k] += ½ (f_n + f_n+1)_k dt on the fixed DOFs k of particle a: the trapezoid impulse
    of the force (internal plus dead) over one step, o the force f_n of the step before, f[a] the
    new one. For a DOF moving at the constant velocity v_fix the constraint then does the work
    −v_fix · imp: velocity Verlet's discrete work on it, Σ ½ (f_n + f_n+1) · (x_n+1 − x_n)."""
    if fixed[a, 0]:
        imp[a, 0] += 0.5 * dt * (o0 + f[a, 0])
    if fixed[a, 1]:
        imp[a, 1] += 0.5 * dt * (o1 + f[a, 1])
    if f.shape[1] == 3 and fixed[a, 2]:
        imp[a, 2] += 0.5 * dt * (o2 + f[a, 2])


@njit(inline="always", **JIT)
def _stress_row_2d(a, x, indptr, indices, G, V, h_old, prm, mat_id, all_svk, F, P, A, h_new, VP,
                   status):
    """2-D specialisation of :func:`_stress_row` (scalar accumulation of eq. 35, F33 = 1; a body
    of Saint Venant–Kirchhoff materials calls that law directly from the shared library, others go
    through ``material_point``). Returns 1 if the point failed, else 0."""
    if V[a] == 0.0:
        _inactive_row(a, h_old, h_new, VP, status)
        return 0
    xa0 = x[a, 0]
    xa1 = x[a, 1]
    f00 = 0.0
    f01 = 0.0
    f10 = 0.0
    f11 = 0.0
    for p in range(indptr[a], indptr[a + 1]):
        b = indices[p]
        d0 = x[b, 0] - xa0
        d1 = x[b, 1] - xa1
        g0 = G[p, 0]
        g1 = G[p, 1]
        f00 += d0 * g0
        f01 += d0 * g1
        f10 += d1 * g0
        f11 += d1 * g1
    F[0, 0] = f00
    F[0, 1] = f01
    F[1, 0] = f10
    F[1, 1] = f11
    F[2, 2] = 1.0
    if not (f00 * f11 - f01 * f10 > 0.0):
        status[a] = 1000
        VP[a, 0, 0] = 0.0
        VP[a, 0, 1] = 0.0
        VP[a, 1, 0] = 0.0
        VP[a, 1, 1] = 0.0
        return 1
    if all_svk:
        st = svk_point(F, prm[mat_id[a]], P, A, False)
    else:
        st = material_point(F, h_old[a], prm[mat_id[a]], P, h_new[a], A, False)
    status[a] = st
    va = V[a]
    VP[a, 0, 0] = va * P[0, 0]
    VP[a, 0, 1] = va * P[0, 1]
    VP[a, 1, 0] = va * P[1, 0]
    VP[a, 1, 1] = va * P[1, 1]
    return 1 if st != 0 else 0


@njit(inline="always", **JIT)
def _force_row_2d(a, VP, indptr, indices, G, GT, f_ext, wa, out):
    """2-D specialisation of :func:`_force_row`, times the share ``wa`` (:mod:`sph.mirror`; 1
    without symmetry planes), plus the external force, into ``out[a]``."""
    pa00 = VP[a, 0, 0]
    pa01 = VP[a, 0, 1]
    pa10 = VP[a, 1, 0]
    pa11 = VP[a, 1, 1]
    f0 = 0.0
    f1 = 0.0
    for p in range(indptr[a], indptr[a + 1]):
        b = indices[p]
        g0 = G[p, 0]
        g1 = G[p, 1]
        h0 = GT[p, 0]
        h1 = GT[p, 1]
        f0 += pa00 * g0 + pa01 * g1 - VP[b, 0, 0] * h0 - VP[b, 0, 1] * h1
        f1 += pa10 * g0 + pa11 * g1 - VP[b, 1, 0] * h0 - VP[b, 1, 1] * h1
    out[a, 0] = wa * f0 + f_ext[a, 0]
    out[a, 1] = wa * f1 + f_ext[a, 1]


def advance(body: Body, x, v, acc, f_ext, fixed, v_fix, dt: float, damping: float,
            n_steps: int, h_scratch, impulse=None, on_damage=None) -> int:
    """``n_steps`` fused velocity-Verlet steps of ``body`` from the synchronised state (x, v, acc),
    in place; ``f_ext`` (N, d) dead forces, ``fixed`` (N, d) uint8 DOFs following ``v_fix``;
    ``impulse`` (N, d) or None: the impulse of the force on each fixed DOF is added to it
    (:func:`_impulse_row`); ``on_damage(new)``, or None: called at the synchronised state after
    every step in which a point failed (damage ≥ 1, :mod:`workbench.materials.failure`; ``new`` True) and at the end of the call
    (False), for :mod:`sph.crack` to update the pairs; it returns whether they changed, and then
    the acceleration is that of the new pairs (:func:`_new_force`); the steps then go on.
    Bodies under :data:`SERIAL_BELOW` particles run on one thread.
    Returns the steps completed (fewer when a material point failed: J ≤ 0 or the return
    mapping)."""
    from workbench.materials.failure import damage_columns

    import numba

    dsc = body.disc
    hg = (body.hg_rows if body.hg_rows is not None
          else (np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros((0, x.shape[1]))))
    nt = numba.get_num_threads()
    if dsc.n < SERIAL_BELOW:
        numba.set_num_threads(1)
    imp = impulse if impulse is not None else np.zeros((0, x.shape[1]))
    dcols = (damage_columns(body.table) if on_damage is not None
             else np.zeros(0, np.int64))
    d = x.shape[1]
    if dsc.n_ghost:
        mir = (np.empty((dsc.n + dsc.n_ghost, d)), dsc.ghost_src.astype(np.int64),
               dsc.ghost_sign, dsc.ghost_offset, dsc.w)
    else:
        mir = (np.empty((0, d)), np.zeros(0, np.int64), np.empty((0, d)), np.empty((0, d)),
               np.ones(dsc.n))
    done = 0
    try:
        while done < n_steps:
            k, why = _advance(n_steps - done, x, v, acc, dsc.m, f_ext, fixed, v_fix, dt, damping,
                              dsc.indptr, dsc.indices, dsc.G, dsc.GT, dsc.V, body.history,
                              h_scratch, body.prm, body.mat_id, body.table.all_svk, body.VP,
                              body.status, *hg, imp, dcols, *mir)
            done += int(k)
            if why == 1:
                break
            if why == 2 and on_damage(True):
                _new_force(body, x, acc, f_ext)
        if done == n_steps and on_damage is not None and on_damage(False):
            _new_force(body, x, acc, f_ext)
    finally:
        numba.set_num_threads(nt)
    return done


def _new_force(body: Body, x, acc, f_ext) -> None:
    """The acceleration at the synchronised positions x after the pairs changed (:mod:`sph.crack`),
    in place: (f(x) + f_ext)/m with the new pairs, for the next step's first half-kick. The
    velocity is left as the finished step made it, with the force of the potential it integrated
    (the step is consistent with that potential, the next one with the new: the energy balance
    keeps its O(dt²)). Before, the next step began with the force of the old pairs, so the broken
    pairs acted half a step longer on particles whose own stress had gone (measured, the literal
    rule, studies.microcantilever 2-D H/Δx = 5: failed particles at up to 2.4 and 3.3 m/s
    (inter, intra) before, 1.8 and 2.1 m/s with it). Redoing the finished step's second
    half-kick with the new force too removed more of that kick but broke the balance by
    ½ dt v·Δf at every change (0.71 and 0.85 % of the external work against 0.19 and 0.22 %)."""
    acc[:] = (body.evaluate(np.ascontiguousarray(x)) + f_ext) / body.disc.m[:, None]
