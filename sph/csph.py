"""Corrected SPH (CSPH), total Lagrangian (000 §2; Bonet & Lok 1999, Bonet & Kulasegaram 2000).

Everything kernel-related is computed once, in the reference configuration X:

* neighbours within the kernel support 2h (:mod:`sph.neighbours`);
* the correction matrix L_a = (Σ_b V_b ∇W_b(X_a) ⊗ (X_b − X_a))⁻¹ (eq. 31, :func:`correction_matrices`);
* the corrected gradients G_ab = V_b L_a ∇W_b(X_a) (eq. 29, 34, :func:`corrected_gradients`), and
  beside each G_ab, in the same row, the reverse G_ba (:func:`reverse_gradients`), so that the force
  loop reads memory contiguously (notes.md: 3× faster than a reverse index).

Per evaluation:

* F_a = Σ_b (x_b − x_a) ⊗ G_ab (eq. 35 in the difference form; by eq. 30, Σ_b (X_b − X_a) ⊗ G_ab = I,
  so F is exact for every linear field x = A X + c, on any particle arrangement — the patch test);
* P_a from the shared material routine :func:`workbench.materials.kernels.material_point`
  (F is always 3×3; plane strain is F33 = 1 and the 2×2 block of P is used);
* the internal force from the stored energy Π = Σ_a V_a ψ(F_a) (eq. 7–12 in total-Lagrangian form):
  f_a = −∂Π/∂x_a = −Σ_b (V_b P_b G_ba − V_a P_a G_ab) (:func:`internal_force`). Π is invariant under
  rigid translations and rotations, so Σ_a f_a = 0 and Σ_a x_a × f_a = 0 to round-off: linear and
  angular momentum are conserved (eq. 16–28).

Drivers: explicit velocity Verlet (:mod:`sph.integrate`) with a CFL step, optional
mass-proportional damping and an optional energy-consistent hourglass control; a static Newton
solver with the assembled sparse tangent K = ∂²Π/∂x∂x from dP/dF and load stepping, with dynamic
relaxation (kinetic damping) as fallback. :func:`solve` dispatches on the scene.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numba import njit, prange

from workbench.fields import DEFAULT_FRAMES, Snapshots, series_name
from workbench.materials.kernels import material_point, svk_point

from . import lattice
from .diagnostics import energy_change, period_amplitude, probe_displacement
from .integrate import cfl_time_step, kick_drift_row, kick_row
from .kernels import JIT, N_CHUNKS, SUPPORT, dw_dr, kernel_code, w
from .neighbours import drop_cross_body, neighbour_list

DEFAULT_CORRECTION = "quadratic"
"""Gradient correction used by :func:`solve` unless ``correction=`` is given. The paper's
Bonet–Lok correction (``"linear"``, eq. 31) is first-order accurate at free surfaces, where its
one-sided stencil under-estimates bending strains: at H/Δx = 10 the plate period comes out 2.7 %
(node lattice) to 6 % (cell lattice) long and the cantilever 6 % too soft. The quadratic correction
keeps eq. 35 and the energy-consistent force and removes that error (0.2 % and 0.3 %)."""

SERIAL_BELOW = 20_000
"""Particle count under which the time loop runs on one thread: a step of a small body is
shorter than the cost of waking the thread pool several times per step (on a loaded 2-core
machine two threads made a 400-particle plate 50× slower)."""

FASTMATH = {"contract", "arcp"}
"""LLVM flags of the time loop: fused multiply–add and reciprocal multiplication only (no
reassociation, so sums keep their order and the conservation tests hold to round-off)."""


# ================================================================================================
# Reference configuration: correction (eq. 31) and corrected gradients (eq. 34)
# ================================================================================================

@njit(inline="always", **JIT)
def _inverse(M, d, out):
    """Inverse of the d×d (d = 1, 2, 3) block of M into out; returns the determinant."""
    if d == 1:
        det = M[0, 0]
        if det != 0.0:
            out[0, 0] = 1.0 / det
        return det
    if d == 2:
        det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
        if det != 0.0:
            out[0, 0] = M[1, 1] / det
            out[1, 1] = M[0, 0] / det
            out[0, 1] = -M[0, 1] / det
            out[1, 0] = -M[1, 0] / det
        return det
    c00 = M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1]
    c01 = M[1, 2] * M[2, 0] - M[1, 0] * M[2, 2]
    c02 = M[1, 0] * M[2, 1] - M[1, 1] * M[2, 0]
    det = M[0, 0] * c00 + M[0, 1] * c01 + M[0, 2] * c02
    if det != 0.0:
        out[0, 0] = c00 / det
        out[1, 0] = c01 / det
        out[2, 0] = c02 / det
        out[0, 1] = (M[0, 2] * M[2, 1] - M[0, 1] * M[2, 2]) / det
        out[1, 1] = (M[0, 0] * M[2, 2] - M[0, 2] * M[2, 0]) / det
        out[2, 1] = (M[0, 1] * M[2, 0] - M[0, 0] * M[2, 1]) / det
        out[0, 2] = (M[0, 1] * M[1, 2] - M[0, 2] * M[1, 1]) / det
        out[1, 2] = (M[0, 2] * M[1, 0] - M[0, 0] * M[1, 2]) / det
        out[2, 2] = (M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]) / det
    return det


@njit(parallel=True, **JIT)
def correction_matrices(X, V, indptr, indices, h, kind):
    """Eq. 31: L_a = (Σ_b V_b ∇W_b(X_a) ⊗ (X_b − X_a))⁻¹, shape (N, d, d).

    Returns (L, ok): ``ok[a]`` is False where the moment matrix is singular (too few or
    collinear neighbours); L_a is then the identity (uncorrected gradient)."""
    N, d = X.shape
    L = np.zeros((N, d, d))
    ok = np.ones(N, np.bool_)
    for a in prange(N):
        M = np.zeros((d, d))
        scale = 0.0
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            r2 = 0.0
            for k in range(d):
                r2 += (X[a, k] - X[b, k]) ** 2
            r = math.sqrt(r2)
            c = V[b] * dw_dr(r, h, kind, d) / r
            for i in range(d):
                for j in range(d):
                    # ∇W_b(X_a) ⊗ (X_b − X_a), ∇W_b(X_a) = W'(r) (X_a − X_b)/r
                    M[i, j] += c * (X[a, i] - X[b, i]) * (X[b, j] - X[a, j])
            scale += abs(c) * r2
        inv = np.zeros((d, d))
        det = _inverse(M, d, inv)
        if not (abs(det) > 1e-10 * max(scale, 1e-300) ** d):
            ok[a] = False
            for i in range(d):
                inv[i, i] = 1.0
        for i in range(d):
            for j in range(d):
                L[a, i, j] = inv[i, j]
    return L, ok


@njit(parallel=True, **JIT)
def corrected_gradients(X, V, indptr, indices, h, kind, L):
    """Eq. 29 and 34: G_ab = V_b L_a ∇W_b(X_a), stored per CSR pair, shape (nnz, d), 1/m."""
    N, d = X.shape
    G = np.empty((indices.shape[0], d))
    for a in prange(N):
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            r2 = 0.0
            for k in range(d):
                r2 += (X[a, k] - X[b, k]) ** 2
            r = math.sqrt(r2)
            c = V[b] * dw_dr(r, h, kind, d) / r
            for i in range(d):
                s = 0.0
                for j in range(d):
                    s += L[a, i, j] * (X[a, j] - X[b, j])
                G[p, i] = c * s
    return G


@njit(parallel=True, **JIT)
def quadratic_gradients(X, V, indptr, indices, h, kind):
    """Second-order corrected gradients (an option beside eq. 31/34): the moving-least-squares
    derivative with the quadratic basis p(Δ) = (Δ, Δ⊗Δ upper triangle)/h, weights V_b W_ab:
    G_ab = [M_a⁻¹ p(Δ_ab) V_b W_ab]_(first d), M_a = Σ_b V_b W_ab p p^T, Δ_ab = X_b − X_a.
    Then Σ_b Δ_ab ⊗ G_ab = I (eq. 30, linear completeness) and Σ_b (Δ_ab)_i (Δ_ab)_j G_ab = 0, so
    F (eq. 35) is exact for quadratic fields too — bending included — also at free surfaces where
    the first-order gradient is one-sided. Returns (G (nnz, d), ok (N,))."""
    N, d = X.shape
    m = d + d * (d + 1) // 2
    G = np.zeros((indices.shape[0], d))
    ok = np.ones(N, np.bool_)
    for a in prange(N):
        n = indptr[a + 1] - indptr[a]
        Pm = np.zeros((n, m))
        wv = np.zeros(n)
        for q in range(n):
            b = indices[indptr[a] + q]
            r2 = 0.0
            for k in range(d):
                r2 += (X[b, k] - X[a, k]) ** 2
            wv[q] = V[b] * w(math.sqrt(r2), h, kind, d)
            c = d
            for i in range(d):
                Pm[q, i] = (X[b, i] - X[a, i]) / h
                for j in range(i, d):
                    Pm[q, c] = (X[b, i] - X[a, i]) * (X[b, j] - X[a, j]) / (h * h)
                    c += 1
        M = np.zeros((m, m))
        for q in range(n):
            for i in range(m):
                for j in range(m):
                    M[i, j] += wv[q] * Pm[q, i] * Pm[q, j]
        if n < m or abs(np.linalg.det(M)) < 1e-12 * np.abs(M).max() ** m:
            ok[a] = False
            continue
        Minv = np.linalg.inv(M)
        for q in range(n):
            for i in range(d):
                s = 0.0
                for j in range(m):
                    s += Minv[i, j] * Pm[q, j]
                G[indptr[a] + q, i] = s * wv[q] / h
    return G, ok


@njit(parallel=True, **JIT)
def reverse_gradients(indptr, indices, G):
    """G_ba for every pair (a, b) of a's row, found once by binary search in b's sorted row;
    stored contiguously beside G_ab (shape (nnz, d))."""
    N = indptr.shape[0] - 1
    GT = np.empty_like(G)
    for a in prange(N):
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            lo = indptr[b]
            hi = indptr[b + 1]
            while lo < hi:
                mid = (lo + hi) // 2
                if indices[mid] < a:
                    lo = mid + 1
                else:
                    hi = mid
            for k in range(G.shape[1]):
                GT[p, k] = G[lo, k]
    return GT


@dataclass
class Discretisation:
    """The reference-configuration data of a CSPH body.

    X (N, d) m; V (N,) m^d; m (N,) kg; h m; indptr/indices CSR neighbours; G, GT (nnz, d) the
    corrected gradients G_ab and G_ba, 1/m; L (N, d, d) eq. 31; ok (N,) correction regular."""

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

    @property
    def n(self) -> int:
        return self.X.shape[0]

    @property
    def dim(self) -> int:
        return self.X.shape[1]

    def nbytes(self) -> int:
        return sum(a.nbytes for a in (self.X, self.V, self.m, self.indptr, self.indices, self.G,
                                      self.GT))


def discretise(X, V, rho: float, dx: float, h_ratio: float = 1.3,
               kernel: str = "cubic_spline", correction: str = "linear",
               body=None) -> Discretisation:
    """Neighbours, correction and corrected gradients of the particles X (N, d) with volumes V,
    spacing dx and smoothing length h = h_ratio·dx (kernel support 2h). ``body`` (N,) int,
    optional: particles of different bodies are not neighbours (separate bodies meet only
    through :mod:`sph.contact`).

    ``correction``: ``"linear"`` — Bonet–Lok, eq. 31 and 34 (the paper's CSPH); ``"quadratic"`` —
    :func:`quadratic_gradients` (exact for quadratic fields; the same force and conservation)."""
    if correction not in ("linear", "quadratic"):
        raise ValueError(f"correction: {correction!r} is not one of 'linear', 'quadratic'")
    if not (0.5 <= h_ratio <= 4.0):
        raise ValueError(f"h_ratio: {h_ratio} is not allowed; h/dx must lie in [0.5, 4]")
    X = np.ascontiguousarray(X, dtype=np.float64)
    V = np.ascontiguousarray(V, dtype=np.float64)
    kind = kernel_code(kernel)
    h = h_ratio * dx
    indptr, indices = neighbour_list(X, SUPPORT * h)
    if body is not None:
        indptr, indices = drop_cross_body(indptr, indices, np.asarray(body))
    L, ok = correction_matrices(X, V, indptr, indices, h, kind)
    if correction == "linear":
        G = corrected_gradients(X, V, indptr, indices, h, kind, L)
    else:
        G, ok = quadratic_gradients(X, V, indptr, indices, h, kind)
    GT = reverse_gradients(indptr, indices, G)
    return Discretisation(X, V, rho * V, h, kernel, indptr, indices, G, GT, L, ok)


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
    """Eq. 35 for every particle, (N, 3, 3)."""
    N = x.shape[0]
    F = np.empty((N, 3, 3))
    for a in prange(N):
        _deformation_gradient_row(a, x, indptr, indices, G, F[a])
    return F


@njit(inline="always", **JIT)
def _stress_row(a, x, indptr, indices, G, V, h_old, prm, want_tangent, F, P, A, h_new, VP,
                F_all, A_all, status):
    """F_a (eq. 35) → P_a by the shared material routine → VP_a = V_a P_a (d×d block).
    Also J_a > 0 is checked (status 1000 otherwise)."""
    d = x.shape[1]
    _deformation_gradient_row(a, x, indptr, indices, G, F)
    J = (F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1])
         - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
         + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0]))
    if not (J > 0.0):
        status[a] = 1000
        for i in range(d):
            for j in range(d):
                VP[a, i, j] = 0.0
        return
    st = material_point(F, h_old[a], prm, P, h_new[a], A, want_tangent)
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


@njit(parallel=True, **JIT)
def stress_pass(x, indptr, indices, G, V, h_old, prm, want_tangent, VP, h_new, F_all, A_all,
                status):
    """:func:`_stress_row` over all particles, in chunks that allocate their scratch once.

    VP (N, d, d) out: V_a P_a; h_new (N, nh) out; F_all (N, 3, 3) or (0, 3, 3): F out if non-empty;
    A_all (N, d, d, d, d) or empty: dP/dF out when ``want_tangent``; status (N,) int64 out."""
    N = x.shape[0]
    chunk = (N + N_CHUNKS - 1) // N_CHUNKS
    for c in prange(N_CHUNKS):
        F = np.empty((3, 3))
        P = np.empty((3, 3))
        A = np.empty((3, 3, 3, 3))
        for a in range(c * chunk, min(N, (c + 1) * chunk)):
            _stress_row(a, x, indptr, indices, G, V, h_old, prm, want_tangent, F, P, A, h_new,
                        VP, F_all, A_all, status)


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
    """f_a = −Σ_b (V_b P_b G_ba − V_a P_a G_ab) for every particle, (N, d), N (N/m in 2-D)."""
    N, d = VP.shape[0], VP.shape[1]
    f = np.empty((N, d))
    for a in prange(N):
        _force_row(a, VP, indptr, indices, G, GT, f)
    return f


class Body:
    """A CSPH body: discretisation, material and history, with the evaluation
    x ↦ (F, P, f) used by every driver."""

    def __init__(self, disc: Discretisation, material, history=None, hourglass: float = 0.0):
        self.disc = disc
        self.hourglass = float(hourglass)
        if not (self.hourglass >= 0 and math.isfinite(self.hourglass)):
            raise ValueError(f"hourglass: {hourglass} is not allowed; the coefficient must be >= 0")
        self.K_hg = (hourglass_stiffness(disc, self.hourglass, material.mu) if self.hourglass > 0
                     else None)
        self.material = material
        self.prm = material.params()
        d = disc.dim
        N = disc.n
        self.history = (material.initial_history(N) if history is None
                        else np.ascontiguousarray(history, dtype=np.float64))
        self.history_trial = self.history.copy()
        self.VP = np.zeros((N, d, d))
        self.F = np.zeros((N, 3, 3))
        self.status = np.zeros(N, np.int64)
        self._noA = np.zeros((0, d, d, d, d))

    def evaluate(self, x, tangent: bool = False):
        """Internal forces f (N, d) at positions x from the committed history; fills self.F,
        self.VP, self.history_trial, self.status; with ``tangent`` returns (f, A) with A the
        (N, d, d, d, d) block of dP/dF."""
        dsc = self.disc
        A = np.zeros((dsc.n,) + (dsc.dim,) * 4) if tangent else self._noA
        stress_pass(x, dsc.indptr, dsc.indices, dsc.G, dsc.V, self.history, self.prm, tangent,
                    self.VP, self.history_trial, self.F, A, self.status)
        f = internal_force(self.VP, dsc.indptr, dsc.indices, dsc.G, dsc.GT)
        if self.K_hg is not None:
            f -= self.K_hg @ x
        return (f, A) if tangent else f

    def tangent(self, A) -> sp.csr_matrix:
        """∂²(Π + Π_hg)/∂x∂x, (N d × N d)."""
        K = tangent_matrix(self.disc, A)
        if self.K_hg is not None:
            K = (K + sp.kron(self.K_hg, sp.identity(self.disc.dim), format="csr")).tocsr()
        return K

    def commit(self):
        """Accept the last evaluation's history (end of a converged load step or time step)."""
        self.history[:] = self.history_trial

    def stress(self, kind: str = "sigma"):
        """Stress of the last evaluation, (N, 3, 3): 'P', 'tau' or 'sigma' (Cauchy), Pa."""
        from workbench.materials.kernels import material_points

        P, _, _ = material_points(np.ascontiguousarray(self.F), self.history, self.prm[None],
                                  np.zeros(self.disc.n, np.int64))
        if kind == "P":
            return P
        tau = np.einsum("nij,nkj->nik", P, self.F)
        if kind == "tau":
            return tau
        return tau / np.linalg.det(self.F)[:, None, None]


# ================================================================================================
# Tangent stiffness K = ∂²Π/∂x∂x (for the static Newton solver)
# ================================================================================================

@njit(parallel=True, **JIT)
def _assemble_tangent(indptr, indices, G, V, A, offsets, rows, cols, vals):
    """COO triplets of K_(c k),(e l) = Σ_a V_a Σ_jm g_ac,j A_a[k,j,l,m] g_ae,m with the stencil of a
    {a} ∪ nbrs(a) and g_ab = G_ab, g_aa = −Σ_b G_ab (∂F_a/∂x_c = I ⊗ g_ac)."""
    N = indptr.shape[0] - 1
    d = G.shape[1]
    for a in prange(N):
        n = indptr[a + 1] - indptr[a] + 1
        g = np.empty((n, d))
        ids = np.empty(n, np.int64)
        ids[0] = a
        for k in range(d):
            g[0, k] = 0.0
        for q in range(1, n):
            p = indptr[a] + q - 1
            ids[q] = indices[p]
            for k in range(d):
                g[q, k] = G[p, k]
                g[0, k] -= G[p, k]
        pos = offsets[a]
        for s in range(n):
            for t in range(n):
                for k in range(d):
                    for l in range(d):
                        v = 0.0
                        for j in range(d):
                            for m in range(d):
                                v += g[s, j] * A[a, k, j, l, m] * g[t, m]
                        rows[pos] = ids[s] * d + k
                        cols[pos] = ids[t] * d + l
                        vals[pos] = V[a] * v
                        pos += 1


def tangent_matrix(disc: Discretisation, A: np.ndarray) -> sp.csr_matrix:
    """The symmetric Hessian ∂²Π/∂x∂x = −∂f/∂x, (N d × N d) CSR, from dP/dF blocks A (N, d,d,d,d)."""
    d = disc.dim
    n = np.diff(disc.indptr) + 1
    sizes = (n * n) * d * d
    offsets = np.zeros(disc.n + 1, np.int64)
    np.cumsum(sizes, out=offsets[1:])
    nnz = int(offsets[-1])
    rows = np.empty(nnz, np.int64)
    cols = np.empty(nnz, np.int64)
    vals = np.empty(nnz)
    _assemble_tangent(disc.indptr, disc.indices, disc.G, disc.V, A, offsets, rows, cols, vals)
    K = sp.csr_matrix((vals, (rows, cols)), shape=(disc.n * d, disc.n * d))
    K.sum_duplicates()
    return K


# ================================================================================================
# Zero-energy-mode (hourglass) control
# ================================================================================================

def hourglass_operator(disc: Discretisation) -> tuple[sp.csr_matrix, np.ndarray]:
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
    kind = kernel_code(disc.kernel)
    Wab = np.array([kernel_w(float(q), disc.h, kind, d) for q in r]) * disc.V[b_of]
    wsum = np.bincount(a_of, weights=Wab, minlength=N)
    c = Wab / wsum[a_of] / (r * r)
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


def hourglass_stiffness(disc: Discretisation, alpha: float, mu: float) -> sp.csr_matrix:
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


def hourglass_strain(disc: Discretisation, x: np.ndarray, D=None, c=None) -> float:
    """The spurious-mode measure: sqrt(Σ_a V_a Σ_b c_ab |δ_ab|² / Σ_a V_a), the root-mean-square
    non-linear (zero-energy-mode) strain, dimensionless; zero for every linear field."""
    if D is None:
        D, c = hourglass_operator(disc)
    a_of = np.repeat(np.arange(disc.n), np.diff(disc.indptr))
    delta = D @ x
    return float(np.sqrt(np.sum(disc.V[a_of] * c * np.sum(delta * delta, axis=1)) / disc.V.sum()))


# ================================================================================================
# Static equilibrium: Newton with load stepping, dynamic relaxation fallback
# ================================================================================================

@dataclass
class Constraints:
    """Kinematic boundary conditions on DOFs: ``fixed`` (N, d) bool, the DOFs whose position is
    prescribed (clamps, rollers, prescribed displacement); ``f_ext`` (N, d) applied dead loads, N."""

    fixed: np.ndarray
    f_ext: np.ndarray


def newton(body: Body, x: np.ndarray, cons: Constraints, x_target_fixed: np.ndarray,
           tol: float = 1e-9, max_iter: int = 30, force_scale: float | None = None):
    """Equilibrium f(x) + f_ext = 0 on the free DOFs with the fixed DOFs moved to
    ``x_target_fixed`` (N, d) (only its fixed entries are read), from the equilibrium ``x``.

    First iteration: the consistent predictor (old tangent, prescribed increment through K_fp).
    Converged when ‖R_free‖ ≤ tol·force_scale. Returns (x_new, converged, iterations); the body's
    trial history belongs to x_new (call ``body.commit()`` to accept)."""
    d = body.disc.dim
    fixed = cons.fixed.ravel()
    free = ~fixed
    x = x.copy()
    dxp = (x_target_fixed - x).ravel()[fixed]
    if force_scale is None:
        force_scale = max(np.abs(cons.f_ext).max(), 1e-300)
    for it in range(max_iter + 1):
        f, A = body.evaluate(x, tangent=True)
        if np.any(body.status != 0):
            return x, False, it
        R = -(f + cons.f_ext).ravel()
        Rf = R[free]
        if it > 0:
            if force_scale > 0 and np.linalg.norm(Rf) <= tol * force_scale:
                return x, True, it
        K = body.tangent(A)
        Kff = K[free][:, free]
        rhs = -Rf
        if it == 0 and np.any(dxp != 0):
            Kfp = K[free][:, fixed]
            rhs = rhs - Kfp @ dxp
        try:
            du = spla.spsolve(Kff.tocsc(), rhs)
        except Exception:  # singular tangent
            return x, False, it
        if not np.all(np.isfinite(du)):
            return x, False, it
        step = np.zeros(x.size)
        step[free] = du
        if it == 0:
            step[fixed] = dxp
        x = x + step.reshape(x.shape)
    return x, False, max_iter


def dynamic_relaxation(body: Body, x: np.ndarray, cons: Constraints, x_target_fixed: np.ndarray,
                       tol: float = 1e-6, max_steps: int = 2_000_000, force_scale: float | None = None,
                       dt_factor: float = 0.5, check_every: int = 10):
    """Equilibrium by explicit dynamics (the fused loop of :class:`Dynamics`) with kinetic damping:
    the velocities are zeroed whenever the kinetic energy, sampled every ``check_every`` steps,
    has passed a peak. Slower than Newton; kept as fallback and for the cost comparison.
    Converged when ‖f + f_ext‖ on the free DOFs ≤ tol·force_scale. Returns (x, converged, steps);
    the body's history is committed along the way (Dynamics commits every step)."""
    disc = body.disc
    mat = body.material
    dt = cfl_time_step(_spacing(disc), mat.wave_speed("strain"), dt_factor)
    if force_scale is None:
        force_scale = max(np.abs(cons.f_ext).max(), 1e-300)
    x0 = x.copy()
    x0[cons.fixed] = x_target_fixed[cons.fixed]
    dyn = Dynamics(body, np.zeros_like(x0), cons.fixed, dt, f_ext=cons.f_ext, x0=x0)
    ke_old = 0.0
    steps = 0
    free = ~cons.fixed
    while steps < max_steps:
        _, bad = dyn.advance(check_every)
        steps += check_every
        if bad >= 0 or not np.isfinite(dyn.v).all():
            return dyn.x, False, steps
        ke = float(np.sum(disc.m[:, None] * dyn.v * dyn.v))
        if ke < ke_old:
            dyn.v[:] = 0.0
            ke = 0.0
        ke_old = ke
        if steps % (10 * check_every) == 0:
            R = dyn.acc * disc.m[:, None]
            if np.linalg.norm(R[free]) <= tol * force_scale:
                return dyn.x, True, steps
    return dyn.x, False, steps


def _spacing(disc: Discretisation) -> float:
    """Smallest neighbour distance (the particle spacing), m."""
    a = np.repeat(np.arange(disc.n), np.diff(disc.indptr))
    r = np.linalg.norm(disc.X[disc.indices] - disc.X[a], axis=1)
    return float(r.min())


# ================================================================================================
# Explicit dynamics: fused stress / force / velocity-Verlet loop
# ================================================================================================

@njit(parallel=True, fastmath=FASTMATH, **JIT)
def _advance(n_steps, x, v, acc, m, f_ext, fixed, v_fix, dt, damping, indptr, indices, G, GT, V,
             h_a, h_b, prm, VP, status, probe_idx, probe_w, probe_comp, X, probe_out,
             hg_indptr, hg_indices, hg_data):
    """``n_steps`` velocity-Verlet steps from the synchronised state (x, v, acc):
    kick–drift; F → P (shared material routine) → V P; force → acceleration → kick.
    ``h_a`` holds the committed history on entry and on exit (``h_b`` is scratch).
    ``probe_out[s]`` = Σ w (x − X)[comp] after step s. The hourglass stiffness K_s (CSR arrays,
    empty when off) adds −K_s x to the force. Returns the first step with a failed
    material point (status ≠ 0) or −1."""
    N, d = x.shape
    chunk = (N + N_CHUNKS - 1) // N_CHUNKS
    dummyF = np.zeros((0, 3, 3))
    dummyA = np.zeros((0, d, d, d, d))
    hg_on = hg_indptr.shape[0] > 1
    svk = int(prm[0]) == 0
    # Without hourglass control the force loop reads no positions, so the next step's
    # kick–drift is fused into it (one pass less over the particles); the last step of the call
    # stops at the synchronised state.
    fuse = not hg_on
    for a in prange(N):
        kick_drift_row(a, x, v, acc, fixed, v_fix, dt, damping)
    for s in range(n_steps):
        nbad = 0
        for c in prange(N_CHUNKS):
            F = np.zeros((3, 3))
            P = np.empty((3, 3))
            A = np.empty((3, 3, 3, 3))
            for a in range(c * chunk, min(N, (c + 1) * chunk)):
                if d == 2:
                    nbad += _stress_row_2d(a, x, indptr, indices, G, V, h_a, prm, svk, F, P, A,
                                           h_b, VP, status)
                else:
                    _stress_row(a, x, indptr, indices, G, V, h_a, prm, False, F, P, A, h_b, VP,
                                dummyF, dummyA, status)
                    nbad += status[a] != 0
        last = s == n_steps - 1 or nbad > 0
        drift_here = fuse and not last
        for a in prange(N):
            # f_a = Σ_b (V_a P_a G_ab − V_b P_b G_ba); a = (f + f_ext)/m; second half kick
            if d == 2:
                _force_row_2d(a, VP, indptr, indices, G, GT, f_ext, acc)
            else:
                _force_row(a, VP, indptr, indices, G, GT, acc)
                for i in range(d):
                    acc[a, i] += f_ext[a, i]
            if hg_on:
                for i in range(d):
                    for q in range(hg_indptr[a], hg_indptr[a + 1]):
                        acc[a, i] -= hg_data[q] * x[hg_indices[q], i]
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
        u = 0.0
        for q in range(probe_idx.shape[0]):
            i = probe_idx[q]
            xi = x[i, probe_comp]
            if drift_here:
                xi -= dt * v[i, probe_comp]  # back to x_{n+1}
            u += probe_w[q] * (xi - X[i, probe_comp])
        probe_out[s] = u
        if nbad > 0:
            return s
        if not fuse and not last:
            for a in prange(N):
                kick_drift_row(a, x, v, acc, fixed, v_fix, dt, damping)
    return -1


@njit(inline="always", **JIT)
def _stress_row_2d(a, x, indptr, indices, G, V, h_old, prm, svk, F, P, A, h_new, VP, status):
    """2-D specialisation of :func:`_stress_row` (scalar accumulation of eq. 35, F33 = 1; the SVK
    law called directly from the shared library, others through ``material_point``).
    Returns 1 if the point failed, else 0."""
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
    if svk:
        st = svk_point(F, prm, P, A, False)
    else:
        st = material_point(F, h_old[a], prm, P, h_new[a], A, False)
    status[a] = st
    va = V[a]
    VP[a, 0, 0] = va * P[0, 0]
    VP[a, 0, 1] = va * P[0, 1]
    VP[a, 1, 0] = va * P[1, 0]
    VP[a, 1, 1] = va * P[1, 1]
    return 1 if st != 0 else 0


@njit(inline="always", **JIT)
def _force_row_2d(a, VP, indptr, indices, G, GT, f_ext, out):
    """2-D specialisation of :func:`_force_row` plus the external force, into ``out[a]``."""
    pa00 = VP[a, 0, 0]
    pa01 = VP[a, 0, 1]
    pa10 = VP[a, 1, 0]
    pa11 = VP[a, 1, 1]
    f0 = f_ext[a, 0]
    f1 = f_ext[a, 1]
    for p in range(indptr[a], indptr[a + 1]):
        b = indices[p]
        g0 = G[p, 0]
        g1 = G[p, 1]
        h0 = GT[p, 0]
        h1 = GT[p, 1]
        f0 += pa00 * g0 + pa01 * g1 - VP[b, 0, 0] * h0 - VP[b, 0, 1] * h1
        f1 += pa10 * g0 + pa11 * g1 - VP[b, 1, 0] * h0 - VP[b, 1, 1] * h1
    out[a, 0] = f0
    out[a, 1] = f1


class Dynamics:
    """Explicit CSPH state: positions, velocities, accelerations (velocity Verlet), fixed DOFs.

    ``init`` builds it; :meth:`advance` runs steps; :meth:`energies` returns (kinetic, strain)."""

    def __init__(self, body: Body, v0: np.ndarray, fixed: np.ndarray, dt: float,
                 damping: float = 0.0, f_ext: np.ndarray | None = None,
                 v_fix: np.ndarray | None = None, x0: np.ndarray | None = None):
        disc = body.disc
        self.body = body
        self.x = disc.X.copy() if x0 is None else np.ascontiguousarray(x0, dtype=np.float64).copy()
        self.v = np.ascontiguousarray(v0, dtype=np.float64).copy()
        self.fixed = np.ascontiguousarray(fixed, dtype=np.uint8)
        self.v_fix = np.zeros_like(self.x) if v_fix is None else np.ascontiguousarray(v_fix)
        self.v[self.fixed.astype(bool)] = self.v_fix[self.fixed.astype(bool)]
        self.f_ext = np.zeros_like(self.x) if f_ext is None else np.ascontiguousarray(f_ext)
        self.dt = dt
        self.damping = damping
        self.t = 0.0
        self.steps = 0
        f = body.evaluate(self.x)
        self.acc = (f + self.f_ext) / disc.m[:, None]
        self.h_scratch = body.history.copy()
        K = body.K_hg
        self._hg = ((K.indptr.astype(np.int64), K.indices.astype(np.int64), K.data)
                    if K is not None else (np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0)))

    def advance(self, n_steps: int, probe=None, comp: int = 1) -> tuple[np.ndarray, int]:
        """Run ``n_steps``; returns (probe history (n_steps,), index of the failing step or −1)."""
        import numba

        b, dsc = self.body, self.body.disc
        idx, w = probe if probe is not None else (np.zeros(0, np.int64), np.zeros(0))
        out = np.zeros(n_steps)
        nt = numba.get_num_threads()
        if dsc.n < SERIAL_BELOW:
            numba.set_num_threads(1)
        try:
            bad = self._advance(n_steps, idx, w, comp, out)
        finally:
            numba.set_num_threads(nt)
        done = n_steps if bad < 0 else bad + 1
        self.steps += done
        self.t += done * self.dt
        return out[:done], int(bad)

    def _advance(self, n_steps, idx, w, comp, out):
        b, dsc = self.body, self.body.disc
        return _advance(n_steps, self.x, self.v, self.acc, dsc.m, self.f_ext, self.fixed, self.v_fix,
                       self.dt, self.damping, dsc.indptr, dsc.indices, dsc.G, dsc.GT, dsc.V,
                       b.history, self.h_scratch, b.prm, b.VP, b.status, idx, w, comp, dsc.X, out,
                       *self._hg)

    def energies(self) -> tuple[float, float]:
        """(kinetic, stored) energy, J (J/m in 2-D); the stored energy from the shared material
        routine (:func:`sph.diagnostics.strain_energy`) plus the hourglass energy when on."""
        from .diagnostics import kinetic_energy, strain_energy

        F = deformation_gradients(self.x, self.body.disc.indptr, self.body.disc.indices,
                                  self.body.disc.G)
        e = strain_energy(F, self.body.disc.V, self.body.prm)
        if self.body.K_hg is not None:
            e += 0.5 * float(np.sum(self.x * (self.body.K_hg @ self.x)))
        return kinetic_energy(self.body.disc.m, self.v), e


# ================================================================================================
# Scenes
# ================================================================================================

def solve(scene, resolution: int, **options) -> dict:
    """Run CSPH on a scene (``workbench.scenes``): ``SSCurve`` (static Newton, J2, 3-D block),
    ``Cantilever`` (static Newton with load steps, DR fallback), ``Plate`` (explicit dynamics),
    and the stability scenes ``Ring``, ``Slab``, ``Rings`` (explicit dynamics, :mod:`sph.stability`).
    ``resolution``: cells per block edge (SS curve) or particles across H (2-D scenes).
    Options: ``h_ratio`` (1.3), ``kernel`` ('cubic_spline'), ``lattice`` ('cell'/'node'), and the
    scene-specific ones of :func:`solve_ss_curve`, :func:`solve_cantilever`, :func:`solve_plate`."""
    from workbench.scenes import Cantilever, Plate, SSCurve

    if not (isinstance(resolution, (int, np.integer)) and resolution >= 1):
        raise ValueError(f"resolution: {resolution!r} is not allowed; an integer >= 1")
    if isinstance(scene, SSCurve):
        return solve_ss_curve(scene, int(resolution), **options)
    if isinstance(scene, Cantilever):
        return solve_cantilever(scene, int(resolution), **options)
    if isinstance(scene, Plate):
        return solve_plate(scene, int(resolution), **options)
    from . import stability

    if stability.is_stability_scene(scene):
        return stability.solve("csph", scene, resolution, **options)
    raise ValueError(f"scene: {type(scene).__name__} is not supported by csph "
                     f"(SSCurve, Cantilever, Plate, Ring, Slab, Rings)")


def solve_ss_curve(scene, resolution: int = 2, h_ratio: float = 1.3,
                   kernel: str = "cubic_spline", lattice_mode: str = "node", tol: float = 1e-10,
                   hourglass: float = 0.0, correction: str = DEFAULT_CORRECTION) -> dict:
    """Uniaxial tension of the 3-D block: ``resolution`` cells per edge on a node lattice
    ((resolution+1)³ particles including the faces), rollers on X=0, Y=0, Z=0, the X=a face moved
    axially to the log strain of each step of ``scene.strain_path()``; the equilibrium of every
    free particle is solved by Newton at each step, the J2 history committed per particle.

    ``stress``: axial Cauchy stress = axial reaction on the X=a face / current cross-section, the
    section from the mean lateral positions of the Y=a and Z=a face particles;
    ``stress_particle_average``: Σ V_a J_a σ_xx,a / Σ V_a J_a; ``nominal_stress``: reaction / a²."""
    t0 = time.perf_counter()
    a = scene.size
    mat = scene.material
    ps = lattice.block((a, a, a), resolution, mode=lattice_mode)
    disc = discretise(ps.X, ps.V, mat.rho, ps.dx, h_ratio, kernel, correction)
    body = Body(disc, mat, hourglass=hourglass)
    N = disc.n
    fixed = np.zeros((N, 3), bool)
    fixed[ps.sets["x0"], 0] = True
    fixed[ps.sets["y0"], 1] = True
    fixed[ps.sets["z0"], 2] = True
    fixed[ps.sets["x1"], 0] = True
    cons = Constraints(fixed, np.zeros((N, 3)))
    path = scene.strain_path()
    x = disc.X.copy()
    out = dict(strain=path, stress=np.full(path.size, np.nan), nominal_stress=np.full(path.size, np.nan),
               stress_particle_average=np.full(path.size, np.nan), newton_iterations=[],
               n_particles=N, status="ok")
    x1 = ps.sets["x1"]
    scale = mat.E * a * a * 1e-3
    for i, eps in enumerate(path):
        target = x.copy()
        target[x1, 0] = a * math.exp(eps)
        x_new, conv, it = newton(body, x, cons, target, tol=tol, force_scale=scale)
        if not conv:
            # load step cut into halves before giving up
            ok = False
            eps_old = path[i - 1] if i > 0 else 0.0
            xs = x
            for sub in range(1, 6):
                nsub = 2 ** sub
                xs = x
                ok = True
                saved = body.history.copy()
                for k in range(1, nsub + 1):
                    tg = xs.copy()
                    tg[x1, 0] = a * math.exp(eps_old + (eps - eps_old) * k / nsub)
                    xs, c2, _ = newton(body, xs, cons, tg, tol=tol, force_scale=scale)
                    if not c2:
                        ok = False
                        body.history[:] = saved
                        break
                    body.commit()
                if ok:
                    break
            if not ok:
                out["status"] = f"diverged: Newton at log strain {eps:.4g}"
                break
            x_new = xs
        else:
            body.commit()
        x = x_new
        out["newton_iterations"].append(it)
        f = body.evaluate(x)
        reaction = -float(f[x1, 0].sum())  # force the face needs: −(internal force) = ∂Π/∂x
        area = float(x[ps.sets["y1"], 1].mean() * x[ps.sets["z1"], 2].mean())
        out["stress"][i] = reaction / area
        out["nominal_stress"][i] = reaction / (a * a)
        sig = body.stress("sigma")
        J = np.linalg.det(body.F)
        out["stress_particle_average"][i] = float(np.sum(disc.V * J * sig[:, 0, 0]) / np.sum(disc.V * J))
    out["wall_time"] = time.perf_counter() - t0
    out["stress_measure"] = "axial reaction on X=a over the current section (mean lateral face positions)"
    return out


def solve_cantilever(scene, resolution: int = 10, h_ratio: float = 1.1, kernel: str = "cubic_spline",
                     lattice_mode: str = "node", method: str = "newton", tol: float = 1e-8,
                     max_cuts: int = 6, hourglass: float = 0.0, correction: str = DEFAULT_CORRECTION,
                     fields=None, field_frames: int = DEFAULT_FRAMES, discretisation=None,
                     solver_name: str = "csph") -> dict:
    """Static tip-loaded cantilever (004 E), plane strain or stress per ``scene.plane`` (plane
    stress is not modelled: ValueError). The loads of ``scene.loads`` are applied in turn; each is
    reached by Newton with the increment halved on failure (``max_cuts`` times), then by dynamic
    relaxation (also selectable by ``method='dr'``). The tip load is a dead uniform shear traction
    on the tip face, distributed over the tip column in proportion to the particle volumes.

    ``fields`` (a folder, or None): the equilibrium of every load as one frame of the ParaView
    series ``cantilever_csph_H<resolution>.pvd`` (its "time" is the load P L²/(E I));
    ``field_frames`` is accepted for a common interface (every load is written).

    ``discretisation`` (optional): a function ``ParticleSet -> Discretisation`` replacing the
    corrected kernel gradients — any method whose F is Σ_b (x_b − x_a) ⊗ G_ab and whose force is
    −∂Π/∂x has this static solver; :func:`sph.hpm.solve_cantilever` passes its weighted-least-squares
    G (004 eq. 4) with ``solver_name='hpm'``."""
    if scene.plane != "strain":
        raise ValueError(f"plane: {scene.plane!r} is not supported by csph; allowed: 'strain'")
    if method not in ("newton", "dr"):
        raise ValueError(f"method: {method!r} is not one of 'newton', 'dr'")
    t0 = time.perf_counter()
    mat = scene.material
    ps = lattice.cantilever(scene, resolution, mode=lattice_mode)
    disc = (discretise(ps.X, ps.V, mat.rho, ps.dx, h_ratio, kernel, correction)
            if discretisation is None else discretisation(ps))
    body = Body(disc, mat, hourglass=hourglass)
    N = disc.n
    fixed = np.zeros((N, 2), bool)
    fixed[ps.sets["fixed"], :] = True
    tip = ps.sets["tip"]
    wts = disc.V[tip] / disc.V[tip].sum()
    x = disc.X.copy()
    loads = np.asarray(scene.loads, dtype=float)
    res = dict(load=loads, tip_deflection=np.full(loads.size, np.nan),
               tip_horizontal=np.full(loads.size, np.nan), wall_time=np.full(loads.size, np.nan),
               n_particles=N, status=[], iterations=np.zeros(loads.size, int), plane="strain")
    current = 0.0
    failed = False
    state = dict(t=0.0, x=x)
    snap = Snapshots.open(fields, series_name(scene.name, solver_name, resolution), disc.X, mat,
                          lambda: dict(t=state["t"], x=state["x"], v=np.zeros_like(state["x"]),
                                       F=deformation_gradients(state["x"], disc.indptr,
                                                               disc.indices, disc.G),
                                       history=body.history), len(loads), 1, max(1, len(loads)))
    for i, load in enumerate(loads):
        if failed:
            res["status"].append("not run: an earlier load failed")
            continue
        steps = [load]
        total_it = 0
        status = "ok"
        while steps:
            target = steps[0]
            f_ext = np.zeros((N, 2))
            f_ext[tip, 1] = -scene.force(target) * wts
            cons = Constraints(fixed, f_ext)
            scale = max(scene.force(target), 1e-300)
            if method == "newton":
                xn, conv, it = newton(body, x, cons, disc.X, tol=tol, force_scale=scale)
                total_it += it
                if not conv and len(steps) < 2 ** max_cuts and target - current > 1e-6 * load:
                    steps.insert(0, current + 0.5 * (target - current))
                    continue
                if not conv:
                    xn, conv, it = dynamic_relaxation(body, x, cons, disc.X, tol=tol * 100,
                                                      force_scale=scale)
                    status = "ok (dynamic relaxation fallback)" if conv else "diverged"
                    total_it += it
            else:
                xn, conv, it = dynamic_relaxation(body, x, cons, disc.X, tol=tol * 100,
                                                  force_scale=scale)
                total_it += it
                if not conv:
                    status = "diverged: dynamic relaxation"
            if not conv:
                failed = True
                break
            body.commit()
            x = xn
            current = target
            steps.pop(0)
        res["status"].append(status)
        res["iterations"][i] = total_it
        res["wall_time"][i] = time.perf_counter() - t0
        if failed:
            continue
        u = probe_displacement(ps, "tip_mid", x)
        if snap:
            state.update(t=float(load), x=x)
            snap(i + 1)
        res["tip_deflection"][i] = -u[1]
        res["tip_horizontal"][i] = -u[0]
    return res


def solve_plate(scene, resolution: int = 10, h_ratio: float = 1.1, kernel: str = "cubic_spline",
                lattice_mode: str = "node", damping: float = 0.0, dt_factor: float | None = None,
                hourglass: float = 0.0, correction: str = DEFAULT_CORRECTION,
                periods: float | None = None, record_every: int | None = None,
                max_steps: int = 50_000_000, fields=None,
                field_frames: int = DEFAULT_FRAMES, energy_growth: float = 0.5) -> dict:
    """Oscillating cantilever plate (004 D), plane strain, explicit velocity Verlet.

    dt = dt_factor · Δx / c_p (``scene.dt_factor`` unless given). Runs ``scene.periods`` thin-plate
    periods (or ``periods``). ``period`` is twice the mean interval between the zero crossings of
    the tip mid-point's vertical displacement after t = 0; ``amplitude`` the largest |u_tip|.
    Energies are recorded every ``record_every`` steps (default: about 400 records per run). A non-finite state or a failed material
    point, or a total energy *grown* by more than ``energy_growth`` of the initial energy (the
    one-sided criterion of :func:`sph.diagnostics.energy_change`, shared with hpm and sph), ends
    the run with status 'unstable: <reason> at t=…'; ``energy_drift`` is the relative change of the
    total energy over the run.

    ``fields`` (a folder, or None): write the particle fields (displacement, velocity, Cauchy
    stress, von Mises stress; ε_p and damage for J2) as the ParaView series
    ``plate_csph_H<resolution>.pvd`` there, about ``field_frames`` frames over the run
    (:class:`workbench.fields.Snapshots`; the results do not change)."""
    from workbench.analytic import plate_initial_velocity, plate_period

    dt_factor = scene.dt_factor if dt_factor is None else dt_factor
    t0 = time.perf_counter()
    mat = scene.material
    ps = lattice.plate(scene, resolution, mode=lattice_mode)
    disc = discretise(ps.X, ps.V, mat.rho, ps.dx, h_ratio, kernel, correction)
    body = Body(disc, mat, hourglass=hourglass)
    N = disc.n
    fixed = np.zeros((N, 2), np.uint8)
    fixed[ps.sets["fixed"], :] = 1
    v0 = np.zeros((N, 2))
    v0[:, 1] = plate_initial_velocity(scene, disc.X[:, 0])
    v0[fixed.astype(bool)] = 0.0
    dt = cfl_time_step(ps.dx, mat.wave_speed("strain"), dt_factor)
    T = plate_period(scene) * (scene.periods if periods is None else periods)
    n_steps = min(int(math.ceil(T / dt)), max_steps)
    dyn = Dynamics(body, v0, fixed, dt, damping)
    if record_every is None:
        record_every = max(20, n_steps // 400)
    t_setup = time.perf_counter() - t0
    probe = ps.probes["tip_mid"]
    tip = np.zeros(n_steps + 1)
    times, ke, se = [0.0], [], []
    D, c = hourglass_operator(disc)
    hgs = [hourglass_strain(disc, dyn.x, D, c)]
    k0, s0 = dyn.energies()
    ke.append(k0)
    se.append(s0)
    status = "ok"
    t_loop = 0.0
    done = 0
    snap = Snapshots.open(fields, series_name(scene.name, "csph", resolution), disc.X, mat,
                          lambda: _field_state(dyn), n_steps, record_every, field_frames)
    if snap:
        snap(0)
    while done < n_steps:
        n = min(record_every, n_steps - done)
        tl = time.perf_counter()
        hist, bad = dyn.advance(n, probe, 1)
        t_loop += time.perf_counter() - tl
        tip[done + 1: done + 1 + hist.size] = hist
        done += hist.size
        if bad >= 0:
            status = f"unstable: material point failed (J <= 0 or return mapping) at t={dyn.t:.6g}"
            break
        if not (np.all(np.isfinite(hist)) and np.isfinite(dyn.v).all()):
            status = f"unstable: non-finite state at t={dyn.t:.6g}"
            break
        if snap:
            snap(done)
        k, s = dyn.energies()
        times.append(dyn.t)
        hgs.append(hourglass_strain(disc, dyn.x, D, c))
        ke.append(k)
        se.append(s)
        grew, change = energy_change(ke[0] + se[0], k + s, ke[0] + se[0], energy_growth)
        if grew:
            status = f"unstable: total energy grew by {change:+.3g} at t={dyn.t:.4g} s"
            break
    if snap:
        snap(done, final=True)
    tip = tip[: done + 1]
    t_hist = np.arange(done + 1) * dt
    period, amplitude = period_amplitude(t_hist, tip)
    if status != "ok":
        period = amplitude = math.nan
    e_run = np.asarray(ke) + np.asarray(se)
    drift = float((e_run[-1] - e_run[0]) / e_run[0]) if e_run[0] > 0 else math.nan
    return dict(period=period, amplitude=amplitude, time=t_hist, tip_displacement=tip,
                energy_drift=drift, dissipated=max(0.0, -drift) if math.isfinite(drift) else math.nan,
                energy_time=np.asarray(times), kinetic_energy=np.asarray(ke),
                strain_energy=np.asarray(se), hourglass_strain=np.asarray(hgs), wall_time=time.perf_counter() - t0,
                loop_time=t_loop, setup_time=t_setup, n_particles=N,
                n_free=int(N - len(ps.sets["fixed"])), status=status, steps=done, dt=dt,
                plane="strain", lattice=lattice_mode)


def _field_state(dyn: "Dynamics") -> dict:
    """The synchronised state of an explicit run for a field snapshot (F recomputed, eq. 35)."""
    b = dyn.body
    F = deformation_gradients(dyn.x, b.disc.indptr, b.disc.indices, b.disc.G)
    return dict(t=dyn.t, x=dyn.x, v=dyn.v, F=F, history=b.history)


def modal_period(scene, resolution: int = 10, h_ratio: float = 1.1, kernel: str = "cubic_spline",
                 lattice_mode: str = "node", correction: str = DEFAULT_CORRECTION,
                 hourglass: float = 0.0, n_modes: int = 3) -> np.ndarray:
    """Periods, s, of the lowest ``n_modes`` small-amplitude modes of the discrete CSPH plate:
    the generalised eigenproblem K φ = ω² M φ on the free DOFs, with K the tangent (Hessian of Π)
    in the reference configuration and M the lumped particle masses. The linearisation of exactly
    what :func:`solve_plate` integrates — cheap (one sparse shift-invert solve) — for convergence
    studies and the clamp and correction comparisons."""
    mat = scene.material
    ps = lattice.plate(scene, resolution, mode=lattice_mode)
    disc = discretise(ps.X, ps.V, mat.rho, ps.dx, h_ratio, kernel, correction)
    body = Body(disc, mat, hourglass=hourglass)
    _, A = body.evaluate(disc.X.copy(), tangent=True)
    K = body.tangent(A)
    free = np.ones((disc.n, 2), bool)
    free[ps.sets["fixed"]] = False
    free = free.ravel()
    Kf = K[free][:, free].tocsc()
    M = sp.diags(np.repeat(disc.m, 2)[free]).tocsc()
    w2 = spla.eigsh(Kf, k=n_modes, M=M, sigma=0, which="LM", return_eigenvectors=False)
    return np.sort(2 * np.pi / np.sqrt(np.abs(w2)))[::-1]
