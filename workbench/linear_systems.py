"""The linear systems of the static and implicit solvers: K x = b, K the symmetric tangent of a
body on its free DOFs (:func:`sph.static.newton`, :class:`fem_reference.static.TangentSolver`).

A direct solve (SuperLU) is exact and robust, but a 3-D tangent fills in: the particle tangent
couples second neighbours (about 430 entries a row), the 27-node hexahedron's up to 375. At the 3-D
micro-cantilever's H/Δx = 10 (33 000 unknowns) one csph factorisation takes 61 s; the FEM's at
H/h = 10 (250 000 unknowns) 12.6 GB. Above :data:`AMG_ABOVE` unknowns in 3-D the system is solved
instead by conjugate gradients preconditioned with a smoothed-aggregation algebraic multigrid
hierarchy (pyamg; Vaněk, Mandel & Brezina, *Computing* 56, 1996) whose near-null space is the
body's rigid-body modes (:func:`rigid_body_modes`): at that csph system, 4 s to build the
hierarchy and 67 iterations, 12 s, to a residual of 1e-10 — and a Newton step solves only to
its :func:`forcing_term`, 1e-3 at first (4 iterations on a captured plastic tangent). A solve
that does not reach its tolerance (an indefinite tangent, a hierarchy that does not fit) falls
back to SuperLU, so the answer is the direct one's either way.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

AMG_ABOVE = {2: 400_000, 3: 20_000}
"""Unknowns above which K x = b is solved by AMG-preconditioned CG, per dimension. A 2-D
tangent's LU fills in little (a 2-D separator is a line) and the studies' 2-D systems, at most
about 1e5 unknowns, factorise in seconds: they stay direct. A 3-D one's fills in as the square
of a separator that is a surface; at 33 000 csph unknowns AMG-CG is already four times faster
(module docstring)."""

RTOL = 1e-10
"""Relative residual ‖K x − b‖ / ‖b‖ of an iterative solve when the caller names none: Newton
asks for 1e-8 of the load scale, so the linear error stays two orders below what Newton
tolerates. The Newton solvers pass their :func:`forcing_term` instead."""

FORCING_MAX = 1e-3
"""The loosest relative residual a Newton step's linear solve is given (:func:`forcing_term`)."""


def forcing_term(residual: float) -> float:
    """The relative residual η to which a Newton step's linear system is solved, given the
    Newton residual over its scale: η = min(:data:`FORCING_MAX`, 0.1 · residual) (Eisenstat &
    Walker, *SIAM J. Sci. Comput.* 17, 1996). With η = O(‖r‖) Newton's convergence stays
    quadratic, while the early iterations, far from the solution, take a few Krylov iterations
    instead of the 60–70 that :data:`RTOL` costs. Taken by both Newton solvers
    (:func:`sph.static.newton`, :func:`fem_reference.static.newton`); a direct solve ignores it."""
    return min(FORCING_MAX, 0.1 * float(residual))


MAXITER = 400
"""CG iterations before the AMG solve is declared failed (and the direct solve is taken): a
working hierarchy needs 50–100 at the sizes here."""


def rigid_body_modes(X: np.ndarray, dofs: np.ndarray | None = None) -> np.ndarray:
    """The rigid-body motions of points X (N, d) as DOF vectors (N·d, 3 in 2-D, 6 in 3-D), the
    DOFs ordered point-major (point a, component k → a·d + k), rotations about the centroid and
    scaled to the translations' size; only the rows ``dofs`` (indices or a mask) if given. The
    near-null space of an elastic body's stiffness: what smoothed aggregation must reproduce on
    its coarse levels."""
    X = np.asarray(X, float)
    N, d = X.shape
    c = X - X.mean(axis=0)
    scale = max(float(np.abs(c).max()), 1e-300)
    c = c / scale
    B = np.zeros((N, d, 3 if d == 2 else 6))
    for k in range(d):
        B[:, k, k] = 1.0
    if d == 2:
        B[:, 0, 2], B[:, 1, 2] = -c[:, 1], c[:, 0]
    else:
        for col, (i, j) in enumerate(((0, 1), (1, 2), (2, 0)), start=3):  # rotation in plane ij
            B[:, i, col], B[:, j, col] = -c[:, j], c[:, i]
    B = B.reshape(N * d, -1)
    return B if dofs is None else np.ascontiguousarray(B[dofs])


def use_amg(n: int, dim: int) -> bool:
    """Whether a system of ``n`` unknowns of a ``dim``-D body is solved iteratively."""
    return n > AMG_ABOVE.get(int(dim), AMG_ABOVE[3])


class AMGPreconditioner:
    """A smoothed-aggregation hierarchy of K with near-null space B (:func:`rigid_body_modes`),
    applied as one V-cycle per CG iteration. It may precondition a later, nearby matrix (the next
    Newton tangent): :meth:`solve` takes the matrix to solve with."""

    def __init__(self, K, B: np.ndarray):
        import pyamg

        K = sp.csr_matrix(K)
        self.shape = K.shape
        self.ml = pyamg.smoothed_aggregation_solver(K, B=np.asarray(B, float), symmetry="symmetric",
                                                    max_coarse=500)
        self.M = self.ml.aspreconditioner(cycle="V")

    def solve(self, K, b: np.ndarray, rtol: float = RTOL, maxiter: int = MAXITER,
              method: str = "cg"):
        """(x, converged, iterations): CG (``method='cg'``, K symmetric positive definite) or
        GMRES (``'gmres'``, restarted every 50) on K x = b with this hierarchy, to
        ‖K x − b‖ ≤ rtol ‖b‖."""
        count = [0]

        def cb(_):
            count[0] += 1

        if method == "cg":
            x, info = spla.cg(K, b, rtol=rtol, atol=0.0, maxiter=maxiter, M=self.M, callback=cb)
        else:
            x, info = spla.gmres(K, b, rtol=rtol, atol=0.0, restart=50, maxiter=maxiter // 50 + 1,
                                 M=self.M, callback=cb, callback_type="pr_norm")
        ok = info == 0 and bool(np.all(np.isfinite(x)))
        if ok:  # CG's recursive residual can drift from the true one: check the true one
            ok = float(np.linalg.norm(K @ x - b)) <= 10.0 * rtol * float(np.linalg.norm(b))
        return x, ok, count[0]


class KeptHierarchy:
    """An AMG hierarchy kept across the nearby systems of one run — the tangents of successive
    Newton iterations and load steps — by both Newton solvers (:func:`sph.static.solve_path`,
    :class:`fem_reference.static.TangentSolver`). Each solve tries the last hierarchy first,
    within :data:`REUSE_ITERATIONS`, and builds a new one where that misses (a tangent that has
    moved away: plastic flow, large rotation). ``method``: 'cg' (symmetric tangents) or
    'gmres'. Counts ``setups`` and ``iterations``."""

    REUSE_ITERATIONS = 100
    """Krylov iterations an old hierarchy may take on a new tangent before it is rebuilt (a fresh
    one takes 50–100 at the sizes of the 3-D studies)."""

    def __init__(self, method: str = "cg"):
        self.method = method
        self.amg = None
        self.setups = 0
        self.iterations = 0

    def solve(self, K, b: np.ndarray, near_null, rtol: float = RTOL):
        """x with ‖K x − b‖ ≤ rtol ‖b‖, or None where a fresh hierarchy misses too;
        ``near_null`` as :func:`solve_symmetric`'s, taken only when a hierarchy is built."""
        if self.amg is not None and self.amg.shape == K.shape:
            x, ok, its = self.amg.solve(K, b, rtol, self.REUSE_ITERATIONS, method=self.method)
            self.iterations += its
            if ok:
                return x
        B = near_null() if callable(near_null) else near_null
        self.amg = AMGPreconditioner(K, B)
        self.setups += 1
        x, ok, its = self.amg.solve(K, b, rtol, method=self.method)
        self.iterations += its
        return x if ok else None


def direct_factor(K):
    """b ↦ K⁻¹ b by SuperLU with the minimum-degree ordering on AᵀA + A (suits a structurally
    symmetric K), factorised once; a CSR K is factorised as the CSC matrix Kᵀ without a copy and
    solved with trans='T'."""
    if sp.issparse(K) and K.format == "csr":
        lu = spla.splu(K.T, permc_spec="MMD_AT_PLUS_A")
        return lambda b: lu.solve(b, trans="T")
    return spla.splu(sp.csc_matrix(K), permc_spec="MMD_AT_PLUS_A").solve


def direct_solve(K, b: np.ndarray) -> np.ndarray:
    """K⁻¹ b by :func:`direct_factor`."""
    return direct_factor(K)(b)


def solve_symmetric(K, b: np.ndarray, near_null=None, dim: int = 3, rtol: float = RTOL,
                    stats: dict | None = None, kept: KeptHierarchy | None = None) -> np.ndarray:
    """K⁻¹ b for a symmetric K: AMG-CG where :func:`use_amg` says so and ``near_null`` (the
    rigid-body modes, an array or a callable giving them) is given, SuperLU otherwise or when CG
    fails. ``kept``: the run's :class:`KeptHierarchy` (default: a hierarchy of this K alone).
    ``stats`` (a dict) collects 'amg_iterations', 'amg_failures' and 'direct' counts."""
    stats = {} if stats is None else stats
    if near_null is not None and use_amg(K.shape[0], dim):
        kept = KeptHierarchy() if kept is None else kept
        before = kept.iterations
        x = kept.solve(K, b, near_null, rtol)
        stats["amg_iterations"] = stats.get("amg_iterations", 0) + kept.iterations - before
        if x is not None:
            return x
        stats["amg_failures"] = stats.get("amg_failures", 0) + 1
    stats["direct"] = stats.get("direct", 0) + 1
    return direct_solve(K, b)
