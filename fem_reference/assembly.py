"""Total-Lagrangian finite-strain residual and tangent on scikit-fem.

With the displacement u and reference coordinates X, F = I + ∂u/∂X at every quadrature point; the
internal force and its tangent are

    f_int[a i] = ∫ P_iJ ∂N_a/∂X_J dV,        K[a i, b k] = ∫ ∂N_a/∂X_J A_iJkL ∂N_b/∂X_L dV,

A = ∂P/∂F (Bonet & Wood, *Nonlinear continuum mechanics for FEA*, ch. 8, total-Lagrangian form).
The constitutive update runs on arrays outside the forms (:mod:`fem_reference.constitutive`).

Two assemblies give the same matrices: the scikit-fem forms :data:`residual_form` and
:data:`tangent_form` (quadrature-point P and A passed as extra keyword arrays, notes.md), and the
vectorised element kernels of :class:`Discretisation` (one batched product over elements and
points, a sparsity pattern computed once, Dirichlet DOFs condensed out). The second is the one the
solvers use; a test checks it against the first. The consistent mass ρ ∫ N_a N_b dV and the body
force ∫ ρ g N_a dV take a density per element (a body of several materials).

F-bar (``Discretisation(..., fbar='linear')``; 2-D plane strain and 3-D; de Souza Neto, Perić,
Dutko & Owen 1996, *Int. J. Solids Struct.* 33; de Souza Neto, Perić & Owen, *Computational
methods for plasticity*, 2008, ch. 15): at every point the deformation gradient of the
discretisation's dimension d is replaced by

    F̄ = α F,   α = (J̄/J)^{1/d},   J = det F,   J̄_q = Σ_p Π_qp J_p  (q, p points of one element),

so that det F̄ = J̄ while the isochoric part of F is kept (in plane strain F̄33 = F33 = 1). Π is
the element's L²(dV) projection, on the reference element, of the point values of J onto a
low-order space (:func:`projection_matrices`):

- ``'linear'`` (the choice, ``fbar=True``): span{1, X, Y} in 2-D, span{1, X, Y, Z} in 3-D
  (unmapped, complete linear polynomials). For small strain this is the quadratic/discontinuous-
  linear pair Q2–P1 (Bathe's 9/3 element in 2-D, the 27/4 hexahedron in 3-D), which satisfies the
  inf–sup condition: no volumetric locking, no spurious pressure modes, optimal order. It is the
  element of record with the quadratic elements.
- ``'mean'``: the element mean of J (Q2–P0, or Q1–P0 on trilinear hexahedra, the classic F-bar
  element; inf–sup stable with Q2, but its piecewise-constant pressure is first-order: the limit
  pressure of the thick cylinder of tests/test_fem_locking.py comes out 10 %, 5.5 %, 2.7 % low with
  2, 4, 8 elements through the wall, against < 0.1 % for ``'linear'`` on all three).

Neither has spurious displacement modes: the deviatoric part of F̄ equals that of F and stays
fully integrated. The stress is σ̄ = σ(F̄) on the current volume (de Souza Neto's form, not
variational), i.e. in the reference frame the stress conjugate to ∂δu/∂X is

    P̃ = J σ̄ F⁻ᵀ = α^{1−d} P(F̄)                                              (fbar_stress)

(α⁻¹ P(F̄) in 2-D, α⁻² P(F̄) in 3-D); its linearisation (the tangent below, non-symmetric even for
hyperelastic laws) is

    dP̃ = [α^{2−d} A − Q ⊗ F⁻ᵀ] : dF + Q dJ̄/J̄,
    Q = (α^{1−d}/d) (A : F̄ + (1 − d) P(F̄)),    A = ∂P/∂F at F̄,
    dJ̄_q = Σ_p Π_qp J_p F_p⁻ᵀ : dF_p,

the second term coupling all points of an element.

Element deletion (:meth:`Discretisation.deactivate`): a deleted element keeps its points but its
integration weights are zero, so it contributes no force, stiffness or mass; the DOFs that no
active element touches are reported so that the problem can hold them.
"""
from __future__ import annotations

import numba
import numpy as np
import scipy.sparse as sp
import skfem
from skfem.helpers import ddot, dot

from .mesh import element_for
from workbench.linear_systems import rigid_body_modes


@numba.njit(parallel=True, cache=True)
def _element_tangent(G, A, dV, out):
    """K_e[a·d+i, b·d+k] = Σ_q dV_q Σ_JL G[a,J] A[i,J,k,L] G[b,L] for every element, in parallel
    over elements. G (nel, nqp, nb, d), A (nel, nqp, d, d, d, d), dV (nel, nqp)."""
    nel, nqp, nb, d = G.shape
    for e in numba.prange(nel):
        out[e, :, :] = 0.0
        t = np.empty(d)
        for q in range(nqp):
            w = dV[e, q]
            for a in range(nb):
                for i in range(d):
                    for k in range(d):
                        for L in range(d):
                            s = 0.0
                            for J in range(d):
                                s += G[e, q, a, J] * A[e, q, i, J, k, L]
                            t[L] = s * w
                        for b in range(nb):
                            s = 0.0
                            for L in range(d):
                                s += t[L] * G[e, q, b, L]
                            out[e, a * d + i, b * d + k] += s


@skfem.LinearForm
def residual_form(v, w):
    """∫ P : ∂v/∂X dV with P passed as quadrature-point data (d, d, nel, nqp)."""
    return ddot(w.P, v.grad)


@skfem.BilinearForm
def tangent_form(u, v, w):
    """∫ ∂v/∂X : A : ∂u/∂X dV with A passed as quadrature-point data (d, d, d, d, nel, nqp)."""
    return np.einsum("ijkl...,ij...,kl...->...", w.A, v.grad, u.grad)


def projection_matrices(X: np.ndarray, dV: np.ndarray, kind: str) -> np.ndarray:
    """Per element the matrix Π (nqp × nqp) that maps point values to the point values of their
    L²(dV) projection onto span{1} (``'mean'``) or span{1, X, Y[, Z]} (``'linear'``, coordinates
    centred on the element centroid and scaled by V_e^{1/d} for conditioning). X: (nel, nqp, d)
    point coordinates, dV: (nel, nqp). Π is a projection (Π² = Π) and reproduces the space
    exactly."""
    V = dV.sum(axis=1)
    if kind == "mean":
        return np.broadcast_to((dV / V[:, None])[:, None, :], dV.shape + (dV.shape[1],)).copy()
    Xc = np.einsum("eq,eqi->ei", dV, X) / V[:, None]
    Y = (X - Xc[:, None, :]) / (V ** (1.0 / X.shape[2]))[:, None, None]
    Phi = np.concatenate([np.ones(dV.shape + (1,)), Y], axis=2)  # (nel, nqp, d + 1)
    M = np.einsum("eqm,eq,eqn->emn", Phi, dV, Phi)
    return np.einsum("eqm,emn,epn,ep->eqp", Phi, np.linalg.inv(M), Phi, dV)


def qp_data(x: np.ndarray, nel: int, nqp: int) -> np.ndarray:
    """Point arrays (nel·nqp, …) as scikit-fem quadrature data (…, nel, nqp)."""
    x = x.reshape((nel, nqp) + x.shape[1:])
    return np.moveaxis(np.moveaxis(x, 0, -1), 0, -1)


@numba.njit(cache=True)
def _condensed_rows(nptr, ncol, d, red):
    """The row pointer (nf + 1,) of the free × free matrix whose node pattern is (nptr, ncol)
    (sorted), each node pair a d × d block; ``red`` (N,) the reduced index of each DOF a·d + i,
    −1 where fixed."""
    ns = nptr.shape[0] - 1
    nf = 0
    for k in range(red.shape[0]):
        if red[k] >= 0:
            nf += 1
    indptr = np.zeros(nf + 1, np.int64)
    for a in range(ns):
        cnt = 0
        for q in range(nptr[a], nptr[a + 1]):
            b = ncol[q]
            for j in range(d):
                if red[b * d + j] >= 0:
                    cnt += 1
        for i in range(d):
            r = red[a * d + i]
            if r >= 0:
                indptr[r + 1] = cnt
    for r in range(nf):
        indptr[r + 1] += indptr[r]
    return indptr


@numba.njit(cache=True)
def _condensed_columns(nptr, ncol, d, red, indptr, indices):
    """The column indices of :func:`_condensed_rows`' rows, sorted (``red`` increases with the
    DOF), written into ``indices`` (int32 or int64)."""
    ns = nptr.shape[0] - 1
    for a in range(ns):
        for i in range(d):
            r = red[a * d + i]
            if r < 0:
                continue
            p = indptr[r]
            for q in range(nptr[a], nptr[a + 1]):
                b = ncol[q]
                for j in range(d):
                    c = red[b * d + j]
                    if c >= 0:
                        indices[p] = c
                        p += 1


@numba.njit(parallel=True, cache=True)
def _entry_slots(edofs, red, indptr, indices, nnz, out):
    """out[(e·nl + α)·nl + β] = the slot of element e's entry (α, β) (element DOFs ``edofs``
    (nel, nl)) in the pattern (indptr, indices): a binary search of the column in its row; nnz
    for an entry on a fixed row or column."""
    nel, nl = edofs.shape
    for e in numba.prange(nel):
        for al in range(nl):
            r = red[edofs[e, al]]
            base = (e * nl + al) * nl
            for be in range(nl):
                c = red[edofs[e, be]]
                if r < 0 or c < 0:
                    out[base + be] = nnz
                    continue
                lo, hi = indptr[r], indptr[r + 1]
                while lo < hi:
                    mid = (lo + hi) >> 1
                    if indices[mid] < c:
                        lo = mid + 1
                    else:
                        hi = mid
                out[base + be] = lo


class Discretisation:
    """A vector Lagrange discretisation of a mesh: basis, gradients and assembly.

    Attributes: ``basis`` (vector scikit-fem CellBasis), ``d`` (dimension), ``nel``, ``nqp``,
    ``G`` (nel, nqp, nb, d) reference gradients of the scalar shape functions, ``Nq`` (nel, nqp,
    nb) their values, ``dV`` (nel, nqp) quadrature weights × Jacobian (zero on deleted elements;
    ``dV0`` without deletion), ``active`` (nel,) bool, ``edofs`` (nel, nb·d) element DOFs (local
    index a·d + i; the vector DOF of scalar DOF s, component i, is s·d + i), ``sdofs`` (nel, nb)
    the scalar DOFs, ``N`` (number of DOFs), ``free`` (DOFs not held by Dirichlet conditions),
    ``Xq`` (nel, nqp, d) the reference coordinates of the points.
    """

    FBAR = (None, "linear", "mean")

    def __init__(self, mesh, fixed: np.ndarray | None = None, element=None, fbar=None,
                 order: int | None = None):
        """``element``: (scalar scikit-fem element, quadrature order) instead of the default of
        :func:`fem_reference.mesh.element_for` (which takes ``order``: 2 for 27-node hexahedra on
        a MeshHex). ``fbar``: None/False (standard displacement
        element), True or 'linear' (F-bar, J projected on linear polynomials per element) or
        'mean' (F-bar with the element mean of J); see the module docstring. In 2-D F-bar needs
        plane strain (the problem checks)."""
        if isinstance(fbar, bool):
            fbar = "linear" if fbar else None
        if fbar not in self.FBAR:
            raise ValueError(f"fbar: {fbar!r} is not one of None, True, 'linear', 'mean'")
        elem, intorder = element_for(mesh, order) if element is None else element
        self.mesh = mesh
        self.d = mesh.dim()
        self.basis = skfem.Basis(mesh, skfem.ElementVector(elem), intorder=intorder)
        sbasis = skfem.Basis(mesh, elem, intorder=intorder)
        self.nb = len(sbasis.basis)
        self.nel = mesh.nelements
        self.nqp = sbasis.dx.shape[1]
        # (nb, d, nel, nqp) -> (nel, nqp, nb, d)
        G = np.array([phi[0].grad for phi in sbasis.basis])
        self.G = np.ascontiguousarray(G.transpose(2, 3, 0, 1))
        self.Nq = np.ascontiguousarray(np.array([np.asarray(phi[0]) for phi in sbasis.basis])
                                       .transpose(1, 2, 0))
        self.dV0 = np.ascontiguousarray(sbasis.dx)
        self.dV = self.dV0.copy()
        self.active = np.ones(self.nel, dtype=bool)
        self.edofs = np.ascontiguousarray(self.basis.element_dofs.T)
        self.sdofs = np.ascontiguousarray(sbasis.element_dofs.T)
        if not np.array_equal(self.edofs.reshape(self.nel, self.nb, self.d),
                              self.sdofs[:, :, None] * self.d + np.arange(self.d)):
            raise RuntimeError("vector DOFs are not interleaved as s·d + i")
        self.N = self.basis.N
        self.Xq = np.ascontiguousarray(np.moveaxis(np.asarray(sbasis.global_coordinates()), 0, -1))
        self.node_X = np.ascontiguousarray(np.asarray(sbasis.doflocs).T)  # (nodes, d)
        self.fbar = fbar
        self.Pi = None if fbar is None else projection_matrices(self.Xq, self.dV0, fbar)
        self.set_fixed(np.array([], dtype=np.int64) if fixed is None else fixed)

    # -- Dirichlet condensation and the sparsity pattern ---------------------------------------
    def set_fixed(self, fixed: np.ndarray) -> None:
        """Hold ``fixed`` DOFs (their values are set in u by the driver); the pattern of the
        condensed tangent is computed once, at the first assembly."""
        self.fixed = np.unique(np.asarray(fixed, dtype=np.int64))
        mask = np.ones(self.N, dtype=bool)
        mask[self.fixed] = False
        self.free = np.flatnonzero(mask)
        self._inv = None
        self._near_null = None

    def near_null_space(self) -> np.ndarray:
        """The rigid-body modes on the free DOFs (len(free), 3 in 2-D, 6 in 3-D): the near-null
        space of the tangent for an AMG hierarchy (:mod:`workbench.linear_systems`)."""
        if self._near_null is None:
            self._near_null = rigid_body_modes(self.node_X, self.free)
        return self._near_null

    def _pattern(self) -> None:
        """The CSR pattern of the condensed tangent and the slot of every element-matrix entry in
        it (``_inv``, (nel·(nb·d)²,); slot nnz for an entry on a fixed row or column). Built from
        the node-to-node pattern, d × d blocks, by :func:`_condensed_rows`,
        :func:`_condensed_columns` and :func:`_entry_slots`: no array of the element entries'
        keys is formed (at 27-node hexahedra, H/h = 15 of the micro-cantilever, that took
        18 GB)."""
        d, nb = self.d, self.nb
        ns = self.N // d
        sd = self.sdofs
        rows = np.repeat(sd, nb, axis=1).ravel()
        cols = np.tile(sd, (1, nb)).ravel()
        npat = sp.csr_matrix((np.ones(rows.size, np.int8), (rows, cols)), shape=(ns, ns))
        del rows, cols
        npat.sum_duplicates()
        npat.sort_indices()
        red = -np.ones(self.N, dtype=np.int64)
        red[self.free] = np.arange(len(self.free))
        nptr, ncol = npat.indptr.astype(np.int64), npat.indices.astype(np.int64)
        del npat
        indptr = _condensed_rows(nptr, ncol, d, red)
        self._nnz = int(indptr[-1])
        itype = np.int32 if self._nnz < 2 ** 31 - 1 else np.int64  # scipy's index type
        indices = np.empty(self._nnz, itype)
        _condensed_columns(nptr, ncol, d, red, indptr, indices)
        self._inv = np.empty(self.nel * (nb * d) ** 2, np.int64)
        _entry_slots(np.ascontiguousarray(self.edofs, np.int64), red, indptr, indices, self._nnz,
                     self._inv)
        self._indptr, self._indices = indptr.astype(itype), indices

    # -- kinematics ----------------------------------------------------------------------------
    def displacement_gradient(self, u: np.ndarray) -> np.ndarray:
        """H = ∂u/∂X at every point, shape (nel·nqp, d, d)."""
        ue = u[self.edofs].reshape(self.nel, self.nb, self.d)  # (e, a, i)
        H = np.einsum("eai,eqaJ->eqiJ", ue, self.G, optimize=True)
        return H.reshape(-1, self.d, self.d)

    # -- assembly ------------------------------------------------------------------------------
    def internal_force(self, P: np.ndarray) -> np.ndarray:
        """f_int (N,) from P at the points (nel·nqp, d, d)."""
        P = P.reshape(self.nel, self.nqp, self.d, self.d) * self.dV[:, :, None, None]
        fe = np.einsum("eqiJ,eqaJ->eai", P, self.G, optimize=True)
        return np.bincount(self.edofs.ravel(), weights=fe.ravel(), minlength=self.N)

    def integrate(self, w: np.ndarray) -> float:
        """∫ w dV of a point field (nel·nqp,)."""
        return float(np.sum(w.reshape(self.nel, self.nqp) * self.dV))

    def element_tangent(self, A: np.ndarray) -> np.ndarray:
        """Element matrices K_e (nel, nb·d, nb·d) from A at the points (nel·nqp, d, d, d, d)."""
        d, nb = self.d, self.nb
        A = np.ascontiguousarray(A).reshape(self.nel, self.nqp, d, d, d, d)
        out = np.empty((self.nel, nb * d, nb * d))
        _element_tangent(self.G, A, self.dV, out)
        return out

    def tangent(self, A: np.ndarray) -> sp.csr_matrix:
        """The condensed tangent K_ff (free × free), CSR."""
        return self.assemble_elements(self.element_tangent(A))

    def assemble_elements(self, Ke: np.ndarray) -> sp.csr_matrix:
        """The condensed matrix (free × free, CSR) of element matrices Ke (nel, nb·d, nb·d)."""
        if self._inv is None:
            self._pattern()
        data = np.bincount(self._inv, weights=Ke.ravel(), minlength=self._nnz + 1)[:-1]
        nf = len(self.free)
        return sp.csr_matrix((data, self._indices, self._indptr), shape=(nf, nf))

    def element_matvec(self, Ke: np.ndarray, v: np.ndarray) -> np.ndarray:
        """K v (N,) for the full (uncondensed) matrix of the element matrices Ke and v (N,)."""
        fe = np.einsum("emn,en->em", Ke, v[self.edofs])
        return np.bincount(self.edofs.ravel(), weights=fe.ravel(), minlength=self.N)

    # -- F-bar ---------------------------------------------------------------------------------
    def fbar_kinematics(self, H: np.ndarray) -> dict:
        """F, J, J̄, α = (J̄/J)^{1/d} and H̄ = F̄ − I at the points from H (nel·nqp, d, d)."""
        F = H + np.eye(self.d)
        J = np.linalg.det(F)
        Jbar = np.einsum("eqp,ep->eq", self.Pi, J.reshape(self.nel, self.nqp)).ravel()
        with np.errstate(invalid="ignore", divide="ignore"):
            alpha = (Jbar / J) ** (1.0 / self.d)
        Hbar = alpha[:, None, None] * F - np.eye(self.d)
        return dict(F=F, J=J, Jbar=Jbar, alpha=alpha, Hbar=Hbar)

    def fbar_stress(self, kin: dict, P_bar: np.ndarray) -> np.ndarray:
        """P̃ = α^{1−d} P(F̄) (module docstring), the stress the internal force integrates."""
        return P_bar * (kin["alpha"] ** (1 - self.d))[:, None, None]

    def fbar_tangent(self, kin: dict, P_bar: np.ndarray, A_bar: np.ndarray) -> sp.csr_matrix:
        """The condensed F-bar tangent (module docstring) from the kinematics of
        :meth:`fbar_kinematics` and P, A = ∂P/∂F evaluated at F̄ (nel·nqp, d, d[, d, d])."""
        return self.assemble_elements(self.fbar_element_tangent(kin, P_bar, A_bar))

    def fbar_element_tangent(self, kin: dict, P_bar: np.ndarray, A_bar: np.ndarray) -> np.ndarray:
        """The element matrices (nel, nb·d, nb·d) of the F-bar tangent (:meth:`fbar_tangent`)."""
        d, nb, nel, nqp = self.d, self.nb, self.nel, self.nqp
        F, J, Jbar, alpha = kin["F"], kin["J"], kin["Jbar"], kin["alpha"]
        FinvT = np.swapaxes(np.linalg.inv(F), 1, 2)
        Fbar = alpha[:, None, None] * F
        Q = ((alpha ** (1 - d)) / d)[:, None, None] * (
            np.einsum("niJkL,nkL->niJ", A_bar, Fbar) + (1 - d) * P_bar)
        A_loc = (alpha ** (2 - d))[:, None, None, None, None] * A_bar \
            - np.einsum("niJ,nkL->niJkL", Q, FinvT)
        Ke = self.element_tangent(A_loc)
        # nonlocal part: Σ_qp [dV_q G_qaJ Q_qiJ / J̄_q] Π_qp [J_p F⁻ᵀ_p,kL G_pbL]
        Q = (Q / Jbar[:, None, None]).reshape(nel, nqp, d, d)
        R = np.einsum("eqaJ,eqiJ,eq->eqai", self.G, Q, self.dV, optimize=True)
        S = np.einsum("eqbL,eqkL->eqbk", self.G,
                      (J[:, None, None] * FinvT).reshape(nel, nqp, d, d), optimize=True)
        Ke += np.einsum("eqm,eqp,epn->emn", R.reshape(nel, nqp, nb * d), self.Pi,
                        S.reshape(nel, nqp, nb * d), optimize=True)
        return Ke

    # -- the same with scikit-fem forms (reference implementation) -----------------------------
    def skfem_internal_force(self, P: np.ndarray) -> np.ndarray:
        return residual_form.assemble(self.basis, P=qp_data(P, self.nel, self.nqp))

    def skfem_tangent(self, A: np.ndarray) -> sp.csr_matrix:
        return tangent_form.assemble(self.basis, A=qp_data(A, self.nel, self.nqp))

    def mass(self, rho) -> sp.csr_matrix:
        """Consistent mass matrix ρ ∫ N_a N_b δ_ik dV (full N × N, CSR); ``rho`` a density (kg/m³)
        or one per element (nel,). Deleted elements contribute nothing."""
        rho_e = np.broadcast_to(np.asarray(rho, dtype=float), (self.nel,))
        Me = np.einsum("eq,eqa,eqb->eab", self.dV * rho_e[:, None], self.Nq, self.Nq, optimize=True)
        ns = self.N // self.d
        r = np.broadcast_to(self.sdofs[:, :, None], Me.shape).ravel()
        c = np.broadcast_to(self.sdofs[:, None, :], Me.shape).ravel()
        Ms = sp.csr_matrix((Me.ravel(), (r, c)), shape=(ns, ns))
        Ms.sum_duplicates()
        return sp.kron(Ms, sp.identity(self.d), format="csr")  # interleaved: s·d + i

    def skfem_mass(self, rho: float) -> sp.csr_matrix:
        """The same as :meth:`mass` for a uniform ρ with a scikit-fem form (reference)."""

        @skfem.BilinearForm
        def mass_form(u, v, w):
            return rho * dot(u, v)

        return mass_form.assemble(self.basis).tocsr()

    def body_load(self, rho, g) -> np.ndarray:
        """Consistent nodal forces (N,) of the body force ρ g: ∫ ρ g_i N_a dV; ``rho`` (kg/m³)
        scalar or per element (nel,), g (d,) m/s²."""
        rho_e = np.broadcast_to(np.asarray(rho, dtype=float), (self.nel,))
        fe = np.einsum("eq,eqa->ea", self.dV * rho_e[:, None], self.Nq)
        fs = np.bincount(self.sdofs.ravel(), weights=fe.ravel(), minlength=self.N // self.d)
        return (fs[:, None] * np.asarray(g, dtype=float)[None, :]).ravel()

    # -- element deletion ----------------------------------------------------------------------
    def deactivate(self, elements) -> np.ndarray:
        """Delete ``elements`` (indices or a bool mask (nel,)): zero integration weights from now
        on. Returns the DOFs no active element touches any more (to be held)."""
        mask = np.zeros(self.nel, dtype=bool)
        mask[elements] = True
        self.active &= ~mask
        self.dV = self.dV0 * self.active[:, None]
        return self.orphan_dofs()

    def orphan_dofs(self) -> np.ndarray:
        """DOFs that belong to no active element."""
        used = np.zeros(self.N, dtype=bool)
        used[self.edofs[self.active].ravel()] = True
        return np.flatnonzero(~used)

    # -- geometry ------------------------------------------------------------------------------
    def centroids(self) -> np.ndarray:
        """Element centroids in the reference configuration, (nel, d): the dV-weighted mean of the
        quadrature points (the true centroid of a straight-sided element)."""
        return np.einsum("eq,eqi->ei", self.dV0, self.Xq) / self.dV0.sum(axis=1)[:, None]

    def volumes(self) -> np.ndarray:
        """Reference volumes (nel,) (areas per unit thickness in 2-D)."""
        return self.dV0.sum(axis=1)

    def probe(self, x) -> sp.csr_matrix:
        """The matrix (d·n, N) that interpolates a DOF vector at the points x (n, d) with the
        shape functions of the element containing each point: ``(disc.probe(x) @ u)`` reshaped
        to (d, n) is the displacement there."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if x.shape[1] != self.d:
            raise ValueError(f"x: points must have {self.d} coordinates, got shape {x.shape}")
        return self.basis.probes(x.T).tocsr()

    def interpolate(self, u: np.ndarray, x) -> np.ndarray:
        """u at the points x (n, d) → (n, d)."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        return (self.probe(x) @ u).reshape(self.d, len(x)).T

    # -- boundaries ----------------------------------------------------------------------------
    def dofs_where(self, where, component: int | None = None) -> np.ndarray:
        """DOFs (all components, or one) of the nodes (vertices, mid-side, face and centre
        nodes) at which ``where(x)`` is true; x (d, n) node coordinates → bool (n,)."""
        X = self.basis.doflocs
        mask = np.asarray(where(X), dtype=bool).reshape(-1)
        if mask.shape != (self.N,):
            raise ValueError("where: must return one bool per point of its (d, n) argument")
        if component is not None:
            if not 0 <= component < self.d:
                raise ValueError(f"component: {component} is not in [0, {self.d})")
            mask &= np.arange(self.N) % self.d == component
        return np.flatnonzero(mask)

    def facets_where(self, where) -> np.ndarray:
        """Boundary facets all of whose vertices satisfy ``where(x)`` (x (d, n) → bool (n,))."""
        bf = self.mesh.boundary_facets()
        verts = self.mesh.facets[:, bf]  # (vertices per facet, n)
        ok = np.asarray(where(self.mesh.p), dtype=bool)
        return bf[np.all(ok[verts], axis=0)]

    def _facets(self, test):
        """Facet indices from an index array or a test on facet midpoints (scikit-fem)."""
        if callable(test):
            return self.mesh.facets_satisfying(test)
        return np.asarray(test, dtype=np.int64)

    def dofs_on(self, test, component: int | None = None) -> np.ndarray:
        """DOFs (all components, or one) of the nodes/facets whose points satisfy test(x)."""
        dofs = self.basis.get_dofs(self.mesh.facets_satisfying(test)).flatten()
        if component is not None:
            dofs = dofs[dofs % self.d == component]  # interleaved: global = scalar·d + component
        return np.unique(dofs)

    def traction_load(self, test, t: np.ndarray) -> np.ndarray:
        """Consistent nodal forces of a uniform dead traction t (d,) (force per reference area)
        on the boundary facets satisfying test(x) (facet midpoints), or on the facets given as
        an index array (:meth:`facets_where`)."""
        fb = skfem.FacetBasis(self.mesh, self.basis.elem, facets=self._facets(test), intorder=4)
        t = np.asarray(t, dtype=float)

        @skfem.LinearForm
        def load(v, w):
            return sum(t[i] * v[i] for i in range(self.d))

        return load.assemble(fb)

    def pressure_load(self, test, p: float = 1.0) -> np.ndarray:
        """Consistent nodal forces of a dead pressure p on the boundary facets satisfying test(x):
        the nominal traction −p N with N the outward normal of the reference configuration
        (force per reference area, fixed in direction: exact only as the displacement → 0).
        ``test`` as in :meth:`traction_load`."""
        fb = skfem.FacetBasis(self.mesh, self.basis.elem, facets=self._facets(test), intorder=4)

        @skfem.LinearForm
        def load(v, w):
            return -p * sum(w.n[i] * v[i] for i in range(self.d))

        return load.assemble(fb)

    def point_load(self, x, force) -> np.ndarray:
        """Nodal force vector (N,) of a point force ``force`` (d,) (N per unit thickness in 2-D)
        on the node at x; raises ValueError unless a node lies within 1e-9 of the mesh size."""
        x = np.asarray(x, dtype=float)
        force = np.asarray(force, dtype=float)
        f = np.zeros(self.N)
        size = float(np.ptp(self.basis.doflocs, axis=1).max())
        for i in range(self.d):
            dof = self.node_dof(x, i)
            if np.linalg.norm(self.basis.doflocs[:, dof] - x) > 1e-9 * size:
                raise ValueError(f"x: {x.tolist()} is not a node of the mesh (point loads act "
                                 "on nodes)")
            f[dof] += force[i]
        return f

    def node_dof(self, x: np.ndarray, component: int) -> int:
        """The DOF of ``component`` at the node (vertex or higher-order node) nearest to x."""
        pts = self.basis.doflocs  # (d, N)
        comp = np.arange(self.N) % self.d == component
        dist = np.linalg.norm(pts - np.asarray(x, dtype=float)[:, None], axis=0)
        dist[~comp] = np.inf
        return int(np.argmin(dist))
