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
solvers use; a test checks it against the first.

F-bar (``Discretisation(..., fbar='linear')``, 2-D plane strain; de Souza Neto, Perić, Dutko & Owen
1996, *Int. J. Solids Struct.* 33; de Souza Neto, Perić & Owen, *Computational methods for
plasticity*, 2008, ch. 15): at every point the in-plane deformation gradient is replaced by

    F̄ = α F,   α = (J̄/J)^{1/2},   J = det F,   J̄_q = Σ_p Π_qp J_p  (q, p points of one element),

so that det F̄ = J̄ while the isochoric part of F is kept (F̄33 = F33 = 1). Π is the element's
L²(dV) projection, on the reference element, of the point values of J onto a low-order space:

- ``'linear'`` (the choice, ``fbar=True``): span{1, X, Y} (unmapped, complete linear
  polynomials). For small strain this is the biquadratic/discontinuous-linear pair Q2–P1 (Bathe's
  9/3 element), which satisfies the inf–sup condition: no volumetric locking, no spurious pressure
  modes, optimal order. It is the element of record.
- ``'mean'``: the element mean of J (Q2–P0; also inf–sup stable, but its piecewise-constant
  pressure is first-order: the limit pressure of the thick cylinder of tests/test_fem_locking.py
  comes out 10 %, 5.5 %, 2.7 % low with 2, 4, 8 elements through the wall, against < 0.1 % for
  ``'linear'`` on all three).

Neither has spurious displacement modes: the deviatoric part of F̄ equals that of F and stays
fully (3×3) integrated, and in plane strain a zero deviatoric strain is a zero strain. The stress
is σ̄ = σ(F̄) on the current volume (de Souza Neto's form, not variational), i.e. in the reference
frame the stress conjugate to ∂δu/∂X is P̃ = J σ̄ F⁻ᵀ = α⁻¹ P(F̄); its linearisation (the
tangent below, non-symmetric even for hyperelastic laws) is

    dP̃ = [A − Q ⊗ F⁻ᵀ] : dF + Q dJ̄/J̄,     Q = ½ (A : F − α⁻¹ P(F̄)),    A = ∂P/∂F at F̄,
    dJ̄_q = Σ_p Π_qp J_p F_p⁻ᵀ : dF_p,

the second term coupling all points of an element.
"""
from __future__ import annotations

import numba
import numpy as np
import scipy.sparse as sp
import skfem
from skfem.helpers import ddot, dot

from .mesh import element_for


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
    L²(dV) projection onto span{1} (``'mean'``) or span{1, X, Y} (``'linear'``, coordinates
    centred on the element centroid and scaled by √V_e for conditioning). X: (nel, nqp, 2) point
    coordinates, dV: (nel, nqp). Π is a projection (Π² = Π) and reproduces the space exactly."""
    V = dV.sum(axis=1)
    if kind == "mean":
        return np.broadcast_to((dV / V[:, None])[:, None, :], dV.shape + (dV.shape[1],)).copy()
    Xc = np.einsum("eq,eqi->ei", dV, X) / V[:, None]
    Y = (X - Xc[:, None, :]) / np.sqrt(V)[:, None, None]
    Phi = np.concatenate([np.ones(dV.shape + (1,)), Y], axis=2)  # (nel, nqp, 3)
    M = np.einsum("eqm,eq,eqn->emn", Phi, dV, Phi)
    return np.einsum("eqm,emn,epn,ep->eqp", Phi, np.linalg.inv(M), Phi, dV)


def qp_data(x: np.ndarray, nel: int, nqp: int) -> np.ndarray:
    """Point arrays (nel·nqp, …) as scikit-fem quadrature data (…, nel, nqp)."""
    x = x.reshape((nel, nqp) + x.shape[1:])
    return np.moveaxis(np.moveaxis(x, 0, -1), 0, -1)


class Discretisation:
    """A vector Lagrange discretisation of a mesh: basis, gradients and assembly.

    Attributes: ``basis`` (vector scikit-fem CellBasis), ``d`` (dimension), ``nel``, ``nqp``,
    ``G`` (nel, nqp, nb, d) reference gradients of the scalar shape functions, ``dV`` (nel, nqp)
    quadrature weights × Jacobian, ``edofs`` (nel, nb·d) element DOFs (local index a·d + i),
    ``N`` (number of DOFs), ``free`` (DOFs not held by Dirichlet conditions).
    """

    FBAR = (None, "linear", "mean")

    def __init__(self, mesh, fixed: np.ndarray | None = None, element=None, fbar=None):
        """``element``: (scalar scikit-fem element, quadrature order) instead of the default of
        :func:`fem_reference.mesh.element_for`. ``fbar``: None/False (standard displacement
        element), True or 'linear' (F-bar, J projected on linear polynomials per element) or
        'mean' (F-bar with the element mean of J); see the module docstring. F-bar is 2-D only
        (the problem must be plane strain)."""
        if isinstance(fbar, bool):
            fbar = "linear" if fbar else None
        if fbar not in self.FBAR:
            raise ValueError(f"fbar: {fbar!r} is not one of None, True, 'linear', 'mean'")
        elem, intorder = element_for(mesh) if element is None else element
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
        self.dV = np.ascontiguousarray(sbasis.dx)
        self.edofs = np.ascontiguousarray(self.basis.element_dofs.T)
        self.N = self.basis.N
        self.fbar = fbar
        if fbar is not None:
            if self.d != 2:
                raise ValueError(f"fbar: {fbar!r} is implemented in 2-D (plane strain) only")
            X = np.moveaxis(np.asarray(sbasis.global_coordinates()), 0, -1)  # (nel, nqp, 2)
            self.Pi = projection_matrices(X, self.dV, fbar)
        else:
            self.Pi = None
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

    def _pattern(self) -> None:
        red = -np.ones(self.N, dtype=np.int64)
        red[self.free] = np.arange(len(self.free))
        nl = self.edofs.shape[1]
        r = np.broadcast_to(red[self.edofs][:, :, None], (self.nel, nl, nl)).ravel()
        c = np.broadcast_to(red[self.edofs][:, None, :], (self.nel, nl, nl)).ravel()
        keep = (r >= 0) & (c >= 0)
        nf = len(self.free)
        key = r[keep] * nf + c[keep]
        # the canonical CSR pattern (scipy's compiled COO→CSR), then each entry's slot in it
        pat = sp.csr_matrix((np.ones(len(key), dtype=np.int8), (r[keep], c[keep])), shape=(nf, nf))
        pat.sum_duplicates()
        rows = np.repeat(np.arange(nf, dtype=np.int64), np.diff(pat.indptr))
        uniq = rows * nf + pat.indices
        # slot of every element-matrix entry; entries on a fixed row or column go to slot nnz
        slot = np.full(r.shape, len(uniq), dtype=np.int64)
        slot[keep] = np.searchsorted(uniq, key)
        self._inv, self._nnz = slot, len(uniq)
        self._indices, self._indptr = pat.indices, pat.indptr

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

    # -- F-bar ---------------------------------------------------------------------------------
    def fbar_kinematics(self, H: np.ndarray) -> dict:
        """F, J, J̄, α = (J̄/J)^{1/2} and H̄ = F̄ − I at the points from H (nel·nqp, 2, 2)."""
        F = H + np.eye(self.d)
        J = np.linalg.det(F)
        Jbar = np.einsum("eqp,ep->eq", self.Pi, J.reshape(self.nel, self.nqp)).ravel()
        with np.errstate(invalid="ignore", divide="ignore"):
            alpha = np.sqrt(Jbar / J)
        Hbar = alpha[:, None, None] * F - np.eye(self.d)
        return dict(F=F, J=J, Jbar=Jbar, alpha=alpha, Hbar=Hbar)

    def fbar_tangent(self, kin: dict, P_bar: np.ndarray, A_bar: np.ndarray) -> sp.csr_matrix:
        """The condensed F-bar tangent (module docstring) from the kinematics of
        :meth:`fbar_kinematics` and P, A = ∂P/∂F evaluated at F̄ (nel·nqp, 2, 2[, 2, 2])."""
        d, nb, nel, nqp = self.d, self.nb, self.nel, self.nqp
        F, J, Jbar, alpha = kin["F"], kin["J"], kin["Jbar"], kin["alpha"]
        FinvT = np.swapaxes(np.linalg.inv(F), 1, 2)
        Q = 0.5 * (np.einsum("niJkL,nkL->niJ", A_bar, F) - P_bar / alpha[:, None, None])
        A_loc = A_bar - np.einsum("niJ,nkL->niJkL", Q, FinvT)
        Ke = self.element_tangent(A_loc)
        # nonlocal part: Σ_qp [dV_q G_qaJ Q_qiJ / J̄_q] Π_qp [J_p F⁻ᵀ_p,kL G_pbL]
        Q = (Q / Jbar[:, None, None]).reshape(nel, nqp, d, d)
        R = np.einsum("eqaJ,eqiJ,eq->eqai", self.G, Q, self.dV, optimize=True)
        S = np.einsum("eqbL,eqkL->eqbk", self.G,
                      (J[:, None, None] * FinvT).reshape(nel, nqp, d, d), optimize=True)
        Ke += np.einsum("eqm,eqp,epn->emn", R.reshape(nel, nqp, nb * d), self.Pi,
                        S.reshape(nel, nqp, nb * d), optimize=True)
        return self.assemble_elements(Ke)

    # -- the same with scikit-fem forms (reference implementation) -----------------------------
    def skfem_internal_force(self, P: np.ndarray) -> np.ndarray:
        return residual_form.assemble(self.basis, P=qp_data(P, self.nel, self.nqp))

    def skfem_tangent(self, A: np.ndarray) -> sp.csr_matrix:
        return tangent_form.assemble(self.basis, A=qp_data(A, self.nel, self.nqp))

    def mass(self, rho: float) -> sp.csr_matrix:
        """Consistent mass matrix ρ ∫ N_a N_b δ_ik dV (full N × N)."""

        @skfem.BilinearForm
        def mass_form(u, v, w):
            return rho * dot(u, v)

        return mass_form.assemble(self.basis).tocsr()

    # -- boundaries ----------------------------------------------------------------------------
    def dofs_on(self, test, component: int | None = None) -> np.ndarray:
        """DOFs (all components, or one) of the nodes/facets whose points satisfy test(x)."""
        dofs = self.basis.get_dofs(self.mesh.facets_satisfying(test)).flatten()
        if component is not None:
            dofs = dofs[dofs % self.d == component]  # interleaved: global = scalar·d + component
        return np.unique(dofs)

    def traction_load(self, test, t: np.ndarray) -> np.ndarray:
        """Consistent nodal forces of a uniform dead traction t (d,) (force per reference area)
        on the boundary facets satisfying test(x)."""
        fb = skfem.FacetBasis(self.mesh, self.basis.elem, facets=self.mesh.facets_satisfying(test),
                              intorder=4)
        t = np.asarray(t, dtype=float)

        @skfem.LinearForm
        def load(v, w):
            return sum(t[i] * v[i] for i in range(self.d))

        return load.assemble(fb)

    def pressure_load(self, test, p: float = 1.0) -> np.ndarray:
        """Consistent nodal forces of a dead pressure p on the boundary facets satisfying test(x):
        the nominal traction −p N with N the outward normal of the reference configuration
        (force per reference area, fixed in direction: exact only as the displacement → 0)."""
        fb = skfem.FacetBasis(self.mesh, self.basis.elem, facets=self.mesh.facets_satisfying(test),
                              intorder=4)

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
