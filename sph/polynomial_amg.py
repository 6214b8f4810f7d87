"""A geometric smoothed-aggregation hierarchy for operators that annihilate polynomials: the
multiplier system of the integration-consistent correction (:mod:`sph.consistency`, eq. C3).

That operator, K = Σ_a V_a² B_aᵀ [W_a − W_a P_a M_a⁻¹ P_aᵀ W_a] B_a, is zero on the polynomials
of the basis (each row's least-squares projection reproduces them), so it behaves like a
differential operator of order 2(k+1) for a basis of degree k: its condition grows like (L/Δx)⁶
with the quadratic basis, and on a two-ring stencil pyamg's strength graph is nearly complete, its
default aggregates take most of the body and the hierarchy does not coarsen (2 levels, operator
complexity 1.00, 379 CG iterations on the 3-D micro-cantilever at H/Δx = 5).

Here the aggregates are boxes of the particle lattice instead (:func:`box_aggregates`, side
``box`` spacings, doubled at each coarser level), the near-null space is the basis polynomials
(B (n, m): 1, X, and with the quadratic basis X_i X_k, centred and scaled), the tentative
prolongator fits B on each aggregate (pyamg's ``fit_candidates``) and drops the columns that an
aggregate cannot carry (a box cut by a face to one or two layers of particles holds no quadratic
across them: its fit is rank-deficient and the zero column would make the coarse operator
singular), and the prolongator is smoothed by one damped Jacobi step on the finest level
(Vaněk, Mandel & Brezina, *Computing* 56, 1996). Symmetric Gauss–Seidel smooths, SuperLU solves
the coarsest level, and the V-cycle preconditions conjugate gradients.

Measured on the 3-D micro-cantilever's system (quadratic basis, 2 cores under a load of 5–8):
boxes of 4 spacings take 16 and 24 iterations to 1e-10 at 11 000 and 36 000 unknowns, but their
smoothed prolongator reaches (4 + 2·4)/4 boxes each way and the Galerkin product at 86 000
unknowns took more than 5.6 GB; boxes of 6 (the default) take 65 at 36 000 unknowns (operator
complexity 1.14, coarse level 2 060 unknowns), set-up 5.6 s against 8.5 s and a third of the
time an iteration. A coarser level left unsmoothed does not converge within 150 iterations, so
every level is smoothed, and up to :data:`MAX_COARSE` unknowns are solved directly. pyamg's own
set-up keeps the rank-deficient columns as zero columns: with boxes of 4 at 36 000 unknowns CG
then diverged (residual ratio 1.9 after 500 iterations, pyamg's default candidate smoothing) or
crawled (1.5e-8 after 60), against 24 iterations to 1e-10 with them dropped.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

MAX_COARSE = 6000
"""Unknowns of a level that is solved directly (SuperLU) instead of coarsened further."""

MAXITER = 300
"""CG iterations before a solve is declared failed: the hierarchy takes 16–24 to 1e-10 on the
3-D micro-cantilever (module docstring)."""


def box_aggregates(P: np.ndarray, size: float) -> np.ndarray:
    """The index (n,) of the axis-aligned box of side ``size`` (m) that holds each point P (n, d),
    boxes numbered 0.. in lexicographic order of those that hold a point."""
    cell = np.floor((P - P.min(axis=0)) / size + 1e-9).astype(np.int64)
    _, agg = np.unique(cell, axis=0, return_inverse=True)
    return agg.ravel()


class PolynomialAMG:
    """A smoothed-aggregation hierarchy of the SPD matrix K (n, n) whose near-null space is the
    polynomial basis B (n, m) at the points X (n, d) of a lattice of spacing ``dx``: aggregates
    are boxes of ``box``·2^l spacings on level l (their points: the centroids of the level
    above), at most ``max_levels`` levels, the coarsest at most ``max_coarse`` unknowns
    (default :data:`MAX_COARSE`) or the last. ``smooth_levels``: levels whose prolongator is
    Jacobi-smoothed (the finest by default; smoothing coarser ones multiplies their operators'
    density for a few iterations).
    :meth:`solve` runs preconditioned CG."""

    def __init__(self, K, X: np.ndarray, B: np.ndarray, dx: float, box: int = 6,
                 max_levels: int = 3, max_coarse: int | None = None, smooth_levels: int = 3):
        max_coarse = MAX_COARSE if max_coarse is None else max_coarse
        state = np.random.get_state()  # pyamg's spectral radius estimate starts from a random
        np.random.seed(0)              # vector: the same hierarchy, hence iterations, every run
        try:
            self._build(K, X, B, dx, box, max_levels, max_coarse, smooth_levels)
        finally:
            np.random.set_state(state)

    def _build(self, K, X, B, dx, box, max_levels, max_coarse, smooth_levels):
        from pyamg.aggregation import fit_candidates
        from pyamg.aggregation.smooth import jacobi_prolongation_smoother
        from pyamg.multilevel import MultilevelSolver
        from pyamg.relaxation.smoothing import change_smoothers

        A = sp.csr_matrix(K)
        P = np.asarray(X, dtype=np.float64)
        Bl = np.asarray(B, dtype=np.float64)
        m = Bl.shape[1]
        levels = []
        size = box * dx
        for lev in range(max_levels - 1):
            if A.shape[0] <= max_coarse:
                break
            agg = box_aggregates(P, size)
            na = int(agg.max()) + 1
            AggOp = sp.csr_matrix((np.ones(agg.size), (np.arange(agg.size), agg)),
                                  shape=(agg.size, na))
            T, Bc = fit_candidates(AggOp, Bl)
            keep = np.asarray(np.sqrt(T.multiply(T).sum(axis=0))).ravel() > 0
            T = sp.csr_matrix(T)[:, np.nonzero(keep)[0]]
            Bc = Bc[keep]
            if lev < smooth_levels:
                Pr = jacobi_prolongation_smoother(A, T, A, Bc, omega=4.0 / 3.0)
            else:
                Pr = T
            Pr = sp.csr_matrix(Pr)
            level = MultilevelSolver.Level()
            level.A, level.P, level.R = A, Pr, sp.csr_matrix(Pr.T)
            levels.append(level)
            # the coarse unknowns' points: their aggregate's centroid
            cnt = np.bincount(agg, minlength=na)
            cent = np.zeros((na, P.shape[1]))
            np.add.at(cent, agg, P)
            cent /= cnt[:, None]
            owner = np.repeat(np.arange(na), m)[keep]
            P = cent[owner]
            A = sp.csr_matrix(level.R @ (A @ Pr))
            A.sum_duplicates()
            Bl = Bc
            size *= 2.0
        last = MultilevelSolver.Level()
        last.A = A
        levels.append(last)
        self.ml = MultilevelSolver(levels, coarse_solver="splu")
        sgs = ("gauss_seidel", {"sweep": "symmetric"})
        change_smoothers(self.ml, sgs, sgs)
        self.M = self.ml.aspreconditioner(cycle="V")
        self.shape = K.shape

    def solve(self, K, b: np.ndarray, rtol: float = 1e-10, maxiter: int | None = None, x0=None):
        """(x, converged, iterations): CG on K x = b preconditioned by one V-cycle, to
        ‖K x − b‖ ≤ rtol ‖b‖ (the true residual checked), within ``maxiter`` iterations
        (default :data:`MAXITER`)."""
        maxiter = MAXITER if maxiter is None else maxiter
        count = [0]

        def cb(_):
            count[0] += 1

        x, info = spla.cg(K, b, x0=x0, rtol=rtol, atol=0.0, maxiter=maxiter, M=self.M, callback=cb)
        ok = info == 0 and bool(np.all(np.isfinite(x)))
        if ok:
            ok = float(np.linalg.norm(K @ x - b)) <= 10.0 * rtol * float(np.linalg.norm(b))
        return x, ok, count[0]

    def complexity(self) -> float:
        """Operator complexity: Σ nnz over the levels / nnz of the finest."""
        return float(self.ml.operator_complexity())

    @property
    def levels(self) -> int:
        """Levels of the hierarchy (1: the matrix is solved directly)."""
        return len(self.ml.levels)
