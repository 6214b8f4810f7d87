"""Static equilibrium: Newton–Raphson with a line search, load stepping with step cutting.

A :class:`Problem` is a discretisation with a material (or a table of materials and a material id
per element), the 2-D idealisation, the Dirichlet DOFs with their values as a function of the load
parameter λ, and the external force f_ext(λ). Its state (u, history and F33 at the points) is
committed only at a converged load step, so that a failed step is retried from the last converged
state with a smaller increment.

Element deletion (``Problem(..., deletion=True)``, for fracture): after every committed step the
elements that meet the failure criterion on the damage D of the J2 law (history column
``HIST_DAMAGE``; a point with D ≥ 1 carries no stress, 000 eq. 36) are deleted
(:meth:`~fem_reference.assembly.Discretisation.deactivate`): no force, stiffness or mass from then
on; the DOFs that no active element touches are held at their current displacement so that the
tangent stays regular. Criterion (``deletion``):

- ``'any'`` (``True``, the default): D ≥ 1 at any point of the element. An element with some
  failed points is under-integrated — it has zero-energy modes that nothing controls — so it must
  not outlive the step in which its first point failed: with ``'all'`` the micro-cantilever of
  :func:`fem_reference.drivers.solve_micro_cantilever` diverges at the first partly failed
  elements (inverted elements in the line search), with ``'any'`` it runs through to separation.
  The element's other points lose their stress one step early: the usual price of erosion (the
  crack is one element wide either way).
- ``'all'``: D ≥ 1 at every point; deleting then changes nothing but the regularity of the
  system (the material had already released the element). For homogeneous states.

Points with D ≥ 1 in the committed state are not evaluated (their stress and tangent are zero
and their F, which nothing resists, may be inverted). Within a Newton iteration a DOF whose every
point has just failed has an empty row; its diagonal is set to a positive value (its residual is
zero, so it does not move) until the step is committed and the element deleted.

Newton: K_ff Δu_f = −r_f with r = f_int(u) − f_ext(λ); the step length α comes from a secant line
search on g(α) = Δu·r(u + αΔu) (Crisfield, *Non-linear FEA of solids and structures*, vol. 1,
§9.3); the full step is taken whenever it reduces |g| enough, so the convergence stays quadratic
near the solution. A trial state with J ≤ 0 at any point, or a material point that failed, halves
α.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .assembly import Discretisation
from .constitutive import embed, stored_energy_density, update
from workbench.linear_systems import KeptHierarchy, direct_factor, forcing_term, use_amg
from workbench.materials import HIST_DAMAGE, Material, MaterialTable
from workbench.results import STOPPED


@dataclass
class State:
    """The committed state: displacement u (N,), history (points, n_history), F33 (points,)."""

    u: np.ndarray
    history: np.ndarray
    F33: np.ndarray


@dataclass
class Problem:
    """``material``: a :class:`~workbench.materials.Material` or a
    :class:`~workbench.materials.MaterialTable` with ``mat_id`` (nel,) the row of each element
    (default all 0; every quadrature point of an element takes its element's row; the history has
    the table's width). ``fixed_values(λ)`` gives the values of the Dirichlet DOFs ``disc.fixed``
    as they are when the problem is made (:class:`fem_reference.boundary.Constraints` builds both).
    ``f_ext(λ)`` holds the distributed loads (tractions, pressures, body forces;
    :class:`fem_reference.boundary.Loads`); ``point_loads``, a sequence of (x (d,), force (d,))
    pairs, adds point forces on the nodes at x, scaled by λ like f_ext. The element formulation
    (standard or F-bar) is the discretisation's (``disc.fbar``). ``deletion``: False, True (=
    'any'), 'any' or 'all': delete failed elements by that criterion (module docstring).
    ``nodal_mass`` (N,), kg per DOF, or None: a lumped (diagonal) mass added to the consistent mass
    of the elements — a rigid body carried by nodes (:func:`fem_reference.model.lump_mass`)."""

    disc: Discretisation
    material: Material | MaterialTable
    plane: str | None  # 'strain', 'stress' or None in 3-D
    fixed_values: Callable[[float], np.ndarray]  # λ -> values of disc.fixed (len(disc.fixed),)
    f_ext: Callable[[float], np.ndarray]  # λ -> (N,)
    point_loads: tuple = ()
    mat_id: np.ndarray | None = None
    deletion: bool | str = False
    nodal_mass: np.ndarray | None = None

    def __post_init__(self):
        disc = self.disc
        self.table = MaterialTable.of(self.material)
        if self.mat_id is None:
            self.mat_id = np.zeros(disc.nel, dtype=np.int64)
        mat_id = np.asarray(self.mat_id)
        if mat_id.shape != (disc.nel,) or not np.issubdtype(mat_id.dtype, np.integer):
            raise ValueError(f"mat_id: must be an integer array of shape ({disc.nel},), "
                             f"got {mat_id.dtype} {mat_id.shape}")
        if len(mat_id) and (mat_id.min() < 0 or mat_id.max() >= len(self.table)):
            raise ValueError(f"mat_id: values must lie in [0, {len(self.table)})")
        self.mat_id = mat_id.astype(np.int64)
        self.point_mat = np.repeat(self.mat_id, disc.nqp)
        # the points whose history has the damage column (J2); other laws (the mortar) use that
        # column for something else
        self.point_j2 = np.array([m.law == "j2" for m in self.table.materials])[self.point_mat]
        self._f_point = None
        if len(self.point_loads):
            self._f_point = sum(disc.point_load(x, f) for x, f in self.point_loads)
        if disc.fbar is not None and disc.d == 2 and self.plane != "strain":
            raise ValueError(f"plane: F-bar in 2-D needs plane strain, not {self.plane!r}")
        if self.deletion is True:
            self.deletion = "any"
        if self.deletion not in (False, None, "any", "all"):
            raise ValueError(f"deletion: {self.deletion!r} is not one of False, True, 'any', "
                             "'all'")
        if self.deletion and not self.point_j2.any():
            raise ValueError("deletion: needs a damage history (a J2 material in the table)")
        self.dirichlet = disc.fixed.copy()  # the DOFs fixed_values() answers for
        self.held = np.zeros(0, dtype=np.int64)  # DOFs of deleted material, held in place
        self.held_values = np.zeros(0)

    # -- data per element ------------------------------------------------------------------------
    @property
    def force_floor(self) -> float:
        """The smallest force scale of Newton's relative residual, N (N/m in 2-D): the force of a
        strain of 1e-6 on a cross-section of the body, 1e-6 E_max V^{(d−1)/d} (V the reference
        volume). A body that carries nothing (unloaded, or broken) then converges at a residual
        1e-6 rtol of that instead of chasing round-off relative to zero."""
        disc = self.disc
        E = max(m.E for m in self.table.materials)
        return 1e-6 * E * float(disc.dV0.sum()) ** ((disc.d - 1) / disc.d)

    def rho(self) -> np.ndarray:
        """Density of each element (nel,), kg/m³."""
        return self.table.rho(self.mat_id)

    def mass(self) -> sp.csr_matrix:
        """Consistent mass matrix (N × N) of the active elements, plus ``nodal_mass`` on the
        diagonal."""
        M = self.disc.mass(self.rho())
        if self.nodal_mass is not None:
            M = (M + sp.diags(np.asarray(self.nodal_mass, float))).tocsr()
        return M

    def external(self, lam: float) -> np.ndarray:
        """The external force vector (N,) at load parameter λ."""
        f = self.f_ext(lam)
        return f if self._f_point is None else f + lam * self._f_point

    def prescribed(self, lam: float) -> np.ndarray:
        """Values of all fixed DOFs ``disc.fixed`` at λ: the Dirichlet values, and the held DOFs
        of deleted material at their displacement when it was deleted."""
        fixed = self.disc.fixed
        if not len(self.held):
            return self.fixed_values(lam)
        g = np.zeros(len(fixed))
        if len(self.held):
            g[np.searchsorted(fixed, self.held)] = self.held_values
        if len(self.dirichlet):
            g[np.searchsorted(fixed, self.dirichlet)] = self.fixed_values(lam)
        return g

    failed_elements0 = None
    """bool (nel,) or None: the elements whose points start failed (a scene's failed regions,
    set by :func:`fem_reference.model.discretise`; :func:`workbench.materials.failure.set_failed`)."""

    def initial_state(self) -> State:
        n = self.disc.nel * self.disc.nqp
        h = self.table.initial_history(self.point_mat)
        if self.failed_elements0 is not None and self.failed_elements0.any():
            from workbench.materials.failure import set_failed

            set_failed(self.table, self.point_mat, h, np.repeat(self.failed_elements0, self.disc.nqp))
        return State(np.zeros(self.disc.N), h, np.ones(n))

    def damage(self, state: State) -> np.ndarray:
        """D (nel·nqp,) of the J2 law (000 eq. 36) in ``state``; 0 at the points of other laws."""
        if not self.point_j2.any():
            return np.zeros(len(self.point_j2))
        return np.where(self.point_j2, state.history[:, HIST_DAMAGE], 0.0)

    def live_points(self, state: State) -> np.ndarray:
        """bool (nel·nqp,): points of active elements not failed (D < 1) in ``state``."""
        return np.repeat(self.disc.active, self.disc.nqp) & (self.damage(state) < 1.0)

    # -- the material update ---------------------------------------------------------------------
    def evaluate(self, u: np.ndarray, state: State, tangent: bool = True) -> dict:
        """Material update from the committed ``state`` at displacement u: P, A, new history,
        status, F33, J (points), f_int (N,).

        With F-bar, the material is evaluated at F̄, ``P`` is the stress P̃ = α^{1−d} P(F̄) that
        the internal force integrates (its Cauchy stress P̃ Fᵀ/J is σ(F̄)), ``A`` is ∂P/∂F at F̄
        and ``fbar`` holds the kinematics for :meth:`tangent`; ``J`` is det F and ``Jbar`` J̄.
        Points that are not :meth:`live_points` get P = A = 0 and keep their history."""
        disc = self.disc
        d = disc.d
        H = disc.displacement_gradient(u)
        live = self.live_points(state)
        all_live = bool(live.all())
        kin = None
        if disc.fbar is not None:
            kin = disc.fbar_kinematics(H)
            good = np.all(kin["J"][live] > 0) and np.all(kin["Jbar"][live] > 0)
            Hm = kin["Hbar"] if good else H
        else:
            Hm = H
        if all_live:
            out = update(self.table, Hm, state.history, self.plane, tangent=tangent,
                         F33=state.F33, mat_id=self.point_mat)
        else:  # failed points carry no stress; every point failed: the body carries nothing
            n = len(H)
            out = dict(P=np.zeros((n, d, d)), A=None, history=state.history.copy(),
                       status=np.zeros(n, dtype=np.int64), F33=state.F33.copy())
            if tangent:
                out["A"] = np.zeros((n, d, d, d, d))
            if live.any():
                sub = update(self.table, Hm[live], state.history[live], self.plane,
                             tangent=tangent, F33=state.F33[live], mat_id=self.point_mat[live])
                out["P"][live] = sub["P"]
                out["history"][live] = sub["history"]
                out["status"][live] = sub["status"]
                out["F33"][live] = sub["F33"]
                if tangent:
                    out["A"][live] = sub["A"]
        if kin is not None:
            if not all_live:  # dead points: keep the kinematics finite for the tangent
                dead = ~live & ~((kin["J"] > 0) & (kin["Jbar"] > 0))
                kin["F"][dead] = np.eye(d)
                kin["J"][dead] = 1.0
                kin["Jbar"][dead] = 1.0
                kin["alpha"][dead] = 1.0
            out["J"], out["Jbar"], out["fbar"] = kin["J"], kin["Jbar"], kin
            J = np.minimum(kin["J"], kin["Jbar"])
            if good:
                out["P_bar"] = out["P"]
                out["P"] = disc.fbar_stress(kin, out["P"])
        else:
            Fd = H + np.eye(d)
            J = np.linalg.det(Fd) * (out["F33"] if d == 2 else 1.0)
            out["J"] = J
        out["live"] = live
        out["ok"] = bool(np.all(J[live] > 0) and np.all(np.isfinite(out["P"][live]))
                         and np.all(out["status"][live] == 0))
        out["f_int"] = disc.internal_force(out["P"]) if out["ok"] else None
        return out

    def element_tangent(self, pt: dict) -> np.ndarray:
        """Element tangent matrices (nel, nb·d, nb·d) at the point state ``pt``."""
        if self.disc.fbar is not None:
            return self.disc.fbar_element_tangent(pt["fbar"], pt["P_bar"], pt["A"])
        return self.disc.element_tangent(pt["A"])

    def tangent(self, pt: dict, Ke: np.ndarray | None = None) -> sp.csr_matrix:
        """The condensed tangent K_ff at the point state ``pt`` of :meth:`evaluate` (or of the
        element matrices ``Ke``); a DOF with an empty row — all its points failed within this
        step — gets a positive diagonal."""
        K = self.disc.assemble_elements(self.element_tangent(pt) if Ke is None else Ke)
        diag = K.diagonal()
        empty = diag == 0.0
        if empty.any():
            scale = float(np.mean(np.abs(diag[~empty]))) if (~empty).any() else 1.0
            K = (K + sp.diags(np.where(empty, scale, 0.0))).tocsr()
        return K

    def stored_energy(self, state: State) -> float:
        """∫ ψ dV over the live points, J (J/m in 2-D) (:func:`~.constitutive.
        stored_energy_density`, the library's closed forms)."""
        disc = self.disc
        live = self.live_points(state)
        F = embed(disc.displacement_gradient(state.u)[live], state.F33[live])
        w = np.zeros(disc.nel * disc.nqp)
        w[live] = stored_energy_density(self.table, F, state.history[live], self.point_mat[live])
        return disc.integrate(w)

    # -- element deletion ------------------------------------------------------------------------
    def delete_failed(self, state: State) -> np.ndarray:
        """Delete the active elements that meet the criterion (D ≥ 1 at any or at all points) in
        ``state``; hold the DOFs left without an element at their displacement in ``state``.
        Returns the deleted elements."""
        disc = self.disc
        if not self.deletion:
            return np.zeros(0, dtype=np.int64)
        D = self.damage(state).reshape(disc.nel, disc.nqp)
        crit = np.all if self.deletion == "all" else np.any
        failed = np.flatnonzero(disc.active & crit(D >= 1.0, axis=1))
        if len(failed):
            orphans = disc.deactivate(failed)
            new = np.setdiff1d(orphans, np.union1d(self.held, self.dirichlet))
            if len(new):
                self.held = np.concatenate([self.held, new])
                self.held_values = np.concatenate([self.held_values, state.u[new]])
                order = np.argsort(self.held)
                self.held, self.held_values = self.held[order], self.held_values[order]
            disc.set_fixed(np.union1d(self.dirichlet, self.held))
        return failed


@dataclass
class NewtonResult:
    converged: bool
    u: np.ndarray
    point_state: dict
    residuals: list = field(default_factory=list)  # ‖r_f‖ per iteration (relative)
    iterations: int = 0
    assembly_time: float = 0.0
    solve_time: float = 0.0
    reason: str = ""
    residual: np.ndarray | None = None  # (N,) f_int − f_ext [+ extra_rhs] at the last iterate:
    # on the fixed DOFs, the force of the supports on the body

    def quadratic_constants(self, start: float = 0.2, floor: float = 1e-10) -> list[float]:
        """C_k = r_{k+1} / r_k² over the iterates in the asymptotic range (r_k < ``start``) and
        above the round-off ``floor``: bounded C is quadratic convergence (a consistent tangent)."""
        r = self.residuals
        return [b / a ** 2 for a, b in zip(r[:-1], r[1:]) if a < start and b > floor]


class TangentSolver:
    """Solves the Newton systems K Δu = b of one run.

    Direct (SuperLU) by default. With ``reuse`` (the default above ``reuse_above`` unknowns), the
    last LU factors precondition GMRES on the new tangent; the tangent is factorised again only
    when GMRES has not reached the tolerance in ``max_krylov`` iterations. Newton asks for the
    forcing term η = min(1e-3, 0.1 ‖r‖/scale) (:func:`workbench.linear_systems.forcing_term`):
    with η = O(‖r‖) the convergence stays quadratic while most factorisations of a load or time
    step are saved.

    In 3-D above :data:`workbench.linear_systems.AMG_ABOVE` unknowns the systems are solved by a
    Krylov method (CG for the symmetric standard element, GMRES for F-bar's unsymmetric tangent)
    preconditioned by smoothed-aggregation AMG on the rigid-body modes of the free DOFs
    (:meth:`~fem_reference.assembly.Discretisation.near_null_space`); the hierarchy is kept and
    preconditions the next tangents (:class:`workbench.linear_systems.KeptHierarchy`); where a
    fresh hierarchy fails too, the system is factorised. :meth:`configure` (called by
    :func:`newton`) takes the near-null space, dimension and symmetry from the problem.
    """

    def __init__(self, reuse: bool | None = None, reuse_above: int = 20000, rtol: float = 1e-11,
                 max_krylov: int = 12):
        self.reuse, self.reuse_above, self.rtol, self.max_krylov = reuse, reuse_above, rtol, max_krylov
        self.lu = None
        self.factorisations = 0
        self.krylov_iterations = 0
        self.near_null, self.dim = None, None
        self.amg = KeptHierarchy("cg")

    def configure(self, problem) -> None:
        """Take the near-null space (a callable, evaluated at the first AMG build), dimension and
        symmetry of ``problem``'s tangent, once per solver."""
        if self.near_null is None:
            disc = problem.disc
            self.near_null, self.dim = disc.near_null_space, disc.d
            self.amg.method = "cg" if disc.fbar is None else "gmres"

    def _factor(self, K):
        self.factorisations += 1
        self.shape = K.shape
        self.lu = direct_factor(K)

    def solve(self, K, b, rtol: float | None = None, near: bool = True):
        """x with ‖K x − b‖ ≤ rtol ‖b‖ (rtol defaults to the solver's own). ``near``: the tangent
        is close to the last factorised one (Newton near convergence), worth a Krylov try."""
        rtol = self.rtol if rtol is None else rtol
        if self.near_null is not None and use_amg(K.shape[0], self.dim):
            x = self.amg.solve(K, b, self.near_null, rtol)
            if x is not None:
                return x
        reuse = self.reuse if self.reuse is not None else K.shape[0] > self.reuse_above
        if reuse and near and self.lu is not None and self.shape == K.shape:
            M = spla.LinearOperator(K.shape, matvec=self.lu, dtype=float)
            count = [0]

            def cb(_):
                count[0] += 1

            x, info = spla.gmres(K, b, M=M, rtol=rtol, atol=0.0, restart=self.max_krylov,
                                 maxiter=1, callback=cb, callback_type="pr_norm")
            self.krylov_iterations += count[0]
            if info == 0:
                return x
        self._factor(K)
        return self.lu(b)


def newton(problem: Problem, state: State, u0: np.ndarray, lam: float, rtol: float = 1e-9,
           maxit: int = 25, extra_matrix=None, extra_rhs: Callable | None = None,
           solver: TangentSolver | None = None, fixed_matrix: Callable | None = None
           ) -> NewtonResult:
    """Solve r(u) = f_int(u) − f_ext(λ) [+ extra_rhs(u)] = 0 on the free DOFs from the guess u0
    (fixed DOFs already set in u0). ``extra_matrix`` (free × free) is added to the tangent and
    ``extra_rhs(u)`` (N,) to the residual (the inertia of an implicit time step). ``solver``
    (a :class:`TangentSolver`, kept across the steps of a run) solves the linear systems.
    ``fixed_matrix``: a callable b ↦ A⁻¹ b with a fixed iteration matrix A (free × free, the
    extra matrix included) — modified Newton: the tangent is neither assembled nor factorised;
    the residual is the full one, so the converged answer is the same (linear convergence)."""
    solver = TangentSolver() if solver is None else solver
    solver.configure(problem)
    disc = problem.disc
    free = disc.free
    fext = problem.external(lam)
    u = u0.copy()
    res = NewtonResult(False, u, {})
    t0 = time.perf_counter()
    pt = problem.evaluate(u, state, tangent=True)
    res.assembly_time += time.perf_counter() - t0
    if not pt["ok"]:
        res.reason = "initial guess inverts an element or fails a material point"
        return res
    scale = None
    for it in range(maxit + 1):
        r = pt["f_int"] - fext
        if extra_rhs is not None:
            r = r + extra_rhs(u)
        res.residual = r
        rf = r[free]
        if scale is None:
            # force scale: applied load, or the reactions of a displacement-driven step; never
            # below the problem's floor (a body that carries nothing, e.g. after fracture)
            scale = max(np.linalg.norm(fext), np.linalg.norm(pt["f_int"]), np.linalg.norm(r),
                        problem.force_floor, 1e-300)
        rn = np.linalg.norm(rf) / scale
        res.residuals.append(float(rn))
        if not np.isfinite(rn):
            res.reason = "non-finite residual"
            return res
        if rn <= rtol:
            res.converged = True
            break
        if it >= 2 and rn <= 1e3 * rtol and rn > 0.5 * res.residuals[-2]:
            # stagnation at the round-off floor (F = I + H carries H to ~1e-16/|H| only)
            res.converged = True
            res.reason = "converged to the round-off floor"
            break
        if it == maxit:
            res.reason = f"no convergence in {maxit} iterations (residual {rn:.2e})"
            break
        t0 = time.perf_counter()
        if fixed_matrix is None:
            K = problem.tangent(pt)
            if extra_matrix is not None:
                K = K + extra_matrix
        t1 = time.perf_counter()
        if fixed_matrix is not None:
            du_f = fixed_matrix(-rf)
        else:  # near convergence the tangent barely changes: the last factors precondition GMRES
            du_f = solver.solve(K, -rf, rtol=forcing_term(rn), near=rn < 1e-2)
        res.solve_time += time.perf_counter() - t1
        res.assembly_time += t1 - t0
        du = np.zeros_like(u)
        du[free] = du_f
        # line search on g(α) = Δu·r(u + αΔu)
        g0 = float(du_f @ rf)
        alpha, trial, best = 1.0, None, None
        lo_a, lo_g = 0.0, g0
        t0 = time.perf_counter()
        for _ in range(8):
            ut = u + alpha * du
            pt_t = problem.evaluate(ut, state, tangent=True)
            if not pt_t["ok"]:
                alpha *= 0.5
                continue
            rt = pt_t["f_int"] - fext
            if extra_rhs is not None:
                rt = rt + extra_rhs(ut)
            g = float(du_f @ rt[free])
            if best is None or abs(g) < best[0]:
                best = (abs(g), ut, pt_t)
            if abs(g) <= 0.8 * abs(g0) or alpha < 0.05:
                trial = (ut, pt_t)
                break
            # secant between the last two points, kept inside [0.1 α, 1]
            a_new = alpha - g * (alpha - lo_a) / (g - lo_g) if g != lo_g else 0.5 * alpha
            lo_a, lo_g = alpha, g
            alpha = float(np.clip(a_new, 0.1 * alpha, 1.0))
        if trial is None and best is not None:
            trial = best[1:]  # no sufficient decrease: the best admissible point found
        res.assembly_time += time.perf_counter() - t0
        if trial is None:
            res.reason = "line search found no admissible step (J <= 0 or material failure)"
            res.iterations = it + 1
            return res
        u, pt = trial
        res.iterations = it + 1
    res.u, res.point_state = u, pt
    return res


def linear_predictor(problem: Problem, state: State, lam: float,
                     solver: TangentSolver | None = None) -> np.ndarray | None:
    """The first guess of a step to λ from the committed ``state``: u_n + Δu with the prescribed
    increment Δu_c = g(λ) − u_n,c on the fixed DOFs and, on the free ones, the linearised
    equilibrium K_ff Δu_f = f_ext,f(λ) − f_int,f(u_n) − K_fc Δu_c (the tangent at the committed
    state, elastic for J2). It spreads a prescribed motion over the body instead of concentrating
    it in the elements next to the fixed DOFs (which a damage law would see as a spurious
    failure). None if the committed state cannot be evaluated."""
    disc = problem.disc
    solver = TangentSolver() if solver is None else solver
    solver.configure(problem)
    pt = problem.evaluate(state.u, state, tangent=True)
    if not pt["ok"]:
        return None
    Ke = problem.element_tangent(pt)
    du = np.zeros(disc.N)
    du[disc.fixed] = problem.prescribed(lam) - state.u[disc.fixed]
    rhs = problem.external(lam) - pt["f_int"] - disc.element_matvec(Ke, du)
    K = problem.tangent(pt, Ke)
    del Ke, pt  # the element matrices (1.8 GB at the 3-D micro-cantilever's H/h = 15) and the
    # point tangents are not needed by the solve
    du[disc.free] = solver.solve(K, rhs[disc.free], near=False)
    return state.u + du


def commit(state: State, res: NewtonResult) -> State:
    return State(res.u.copy(), res.point_state["history"].copy(), res.point_state["F33"].copy())


def load_path(problem: Problem, targets, max_increment: float = np.inf, min_increment: float = 1e-6,
              rtol: float = 1e-9, maxit: int = 25, callback: Callable | None = None,
              solver: TangentSolver | None = None):
    """Follow λ = 0 → targets[0] → targets[1] … in increments of at most ``max_increment``,
    halving an increment whose Newton fails (down to ``min_increment`` relative to the target),
    predicting each step by extrapolating the last converged increment (by
    :func:`linear_predictor` at the first step, after a deletion, and on a retry).

    Calls ``callback(k, lam, state)`` when target k is reached; a true return value stops the path
    there (the later targets get the status :data:`workbench.results.STOPPED`). With
    ``problem.deletion``, failed elements are deleted after every converged increment
    (:meth:`Problem.delete_failed`). Returns
    (a list of dicts per target: lam, converged, status, residual_history (list of lists, one per
    increment), iterations, wall_time (cumulative, s), assembly_time, solve_time,
    newton_iterations, deleted (elements deleted while reaching this target); the final state).
    """
    state = problem.initial_state()
    disc = problem.disc
    solver = TangentSolver() if solver is None else solver
    lam = 0.0
    prev = None  # (lam, u) of the previous converged increment
    out = []
    t_start = time.perf_counter()
    failed = stopped = False
    for k, target in enumerate(targets):
        rec = dict(lam=float(target), converged=False, status="", residual_history=[], iterations=0,
                   assembly_time=0.0, solve_time=0.0, newton_iterations=[],
                   deleted=np.zeros(0, dtype=np.int64))
        if failed or stopped:
            rec["status"] = "diverged: an earlier load failed" if failed else STOPPED
            rec["wall_time"] = np.nan
            out.append(rec)
            continue
        step = min(max_increment, abs(target - lam))
        while abs(target - lam) > 1e-14 * max(1.0, abs(target)):
            new = lam + np.sign(target - lam) * min(step, abs(target - lam))
            extrapolated = prev is not None and prev[0] != lam
            if extrapolated:
                u0 = state.u + (new - lam) / (lam - prev[0]) * (state.u - prev[1])
            else:
                u0 = linear_predictor(problem, state, new, solver)
                if u0 is None:
                    u0 = state.u.copy()
            u0[disc.fixed] = problem.prescribed(new)
            res = newton(problem, state, u0, new, rtol=rtol, maxit=maxit, solver=solver)
            if not res.converged and extrapolated:
                # retry from the linearised predictor instead of the extrapolation
                u0 = linear_predictor(problem, state, new, solver)
                if u0 is None:
                    u0 = state.u.copy()
                u0[disc.fixed] = problem.prescribed(new)
                res2 = newton(problem, state, u0, new, rtol=rtol, maxit=maxit, solver=solver)
                res2.assembly_time += res.assembly_time
                res2.solve_time += res.solve_time
                res = res2
            rec["assembly_time"] += res.assembly_time
            rec["solve_time"] += res.solve_time
            rec["iterations"] += res.iterations
            if res.converged:
                rec["residual_history"].append(res.residuals)
                rec["newton_iterations"].append(res.iterations)
                prev = (lam, state.u.copy())
                state = commit(state, res)
                lam = new
                step = min(max_increment, 1.5 * step)
                gone = problem.delete_failed(state)
                if len(gone):
                    rec["deleted"] = np.concatenate([rec["deleted"], gone])
                    prev = None  # the failure is no trend to extrapolate
            else:
                step *= 0.5
                if step < min_increment * max(1.0, abs(target)):
                    rec["status"] = f"diverged at load {new:.6g}: {res.reason}"
                    failed = True
                    break
        rec["wall_time"] = time.perf_counter() - t_start
        if not failed:
            rec["converged"] = True
            rec["status"] = "ok"
            if callback is not None:
                stopped = bool(callback(k, lam, state))
        out.append(rec)
    return out, state
