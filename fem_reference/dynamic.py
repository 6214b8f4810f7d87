"""Implicit dynamics: Newmark's average-acceleration rule (β = 1/4, γ = 1/2, the trapezoidal
rule), unconditionally stable and energy-conserving for linear problems, second-order accurate.

    M a_{n+1} + f_int(u_{n+1}) = f_ext(t_{n+1}),
    u_{n+1} = u_n + Δt v_n + Δt²/4 (a_n + a_{n+1}),    v_{n+1} = v_n + Δt/2 (a_n + a_{n+1}),

solved for u_{n+1} by Newton with the effective tangent K + 4/Δt² M (Hughes, *The finite element
method*, §9.1). Mass-proportional damping C = c M (``damping`` c, 1/s) adds C v_{n+1} to the
balance, v_{n+1} = 2(u_{n+1} − u_n)/Δt − v_n, and 2c/Δt M to the tangent. The load parameter of the :class:`~fem_reference.static.Problem` is the time: the
Dirichlet values and f_ext are evaluated at t_{n+1}. M is the consistent mass with each element's
density; the history (J2) is committed at every converged step, and with ``problem.deletion``
failed elements are deleted after it (M is then rebuilt without them). Kinetic energy ½vᵀMv and
stored energy ∫ ψ dV (:meth:`~fem_reference.static.Problem.stored_energy`) are recorded every
step. ``initial_tangent``: modified Newton with the effective matrix K₀ + (4/Δt² + 2c/Δt) M of
the initial state factorised once (again after a deletion) — the same answer to the Newton
tolerance (the residual is the full nonlinear one) for a run that stays near its initial state
(small-displacement elastic dynamics), at one factorisation instead of one or two per step.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from .static import Problem, TangentSolver, commit, newton


def newmark(problem: Problem, v0: np.ndarray, dt: float, n_steps: int, observe,
            rtol: float = 1e-10, maxit: int = 20, snapshot=None, callback=None,
            damping: float = 0.0, initial_tangent: bool = False):
    """Advance from u = 0 (the prescribed values of the fixed DOFs at t = 0) with initial velocity
    v0 (N,) for ``n_steps`` steps of ``dt``. On the fixed DOFs v0 must be the rate of the
    prescribed motion at t = 0 (zero on a clamp): the consistent mass couples their acceleration
    into the free DOFs.

    ``observe(u)`` returns the scalar (or array) recorded each step (e.g. a tip displacement);
    ``snapshot(step, t, u, v)`` (optional) is called at the start and after every step (field
    output; it decides which steps it writes); ``callback(step, t, state, v)`` (optional) too, with
    the committed :class:`~fem_reference.static.State`.
    The initial acceleration solves M a₀ = f_ext(0) − f_int(u₀) − c M v₀ on the free DOFs
    (``damping`` c, 1/s: mass-proportional damping, module docstring). ``initial_tangent``:
    modified Newton with the initial effective matrix (module docstring).
    Returns dict(time, observed, kinetic_energy, strain_energy (stored energy of the live
    points, J: the library's closed forms), status, newton_iterations, deleted (elements, in
    order)).
    """
    disc = problem.disc
    M_full = problem.mass()
    state = problem.initial_state()
    state.u[disc.fixed] = problem.prescribed(0.0)
    u = state.u.copy()
    v = np.array(v0, dtype=float)
    a = np.zeros(disc.N)
    pt0 = problem.evaluate(u, state, tangent=False)
    r0 = problem.external(0.0) - pt0["f_int"]
    if damping:
        r0 = r0 - damping * (M_full @ v)
    if np.any(r0[disc.free] != 0):
        M_ff = M_full[disc.free][:, disc.free].tocsc()
        a[disc.free] = spla.splu(M_ff).solve(r0[disc.free])
    c = 4.0 / dt ** 2

    t = [0.0]
    obs = [observe(u)]
    ke = [0.5 * v @ (M_full @ v)]
    se = [problem.stored_energy(state)]
    iters = []
    deleted = []
    status = "ok"
    solver = TangentSolver()
    M_ff = M_full[disc.free][:, disc.free].tocsr()

    def effective(st):
        """b ↦ (K₀ + (c + 2 damping/Δt) M_ff)⁻¹ b with the tangent at ``st``, factorised once."""
        K0 = problem.tangent(problem.evaluate(st.u, st, tangent=True))
        return spla.splu((K0 + (c + 2.0 * damping / dt) * M_ff).tocsc()).solve

    iteration = effective(state) if initial_tangent else None
    if snapshot is not None:
        snapshot(0, 0.0, u, v)
    if callback is not None:
        callback(0, 0.0, state, v)
    for n in range(n_steps):
        tn = (n + 1) * dt
        # a_{n+1}(u) = c (u − u_n − Δt v_n) − a_n; residual f_int(u) + M a_{n+1}(u) − f_ext
        base = u + dt * v

        def inertia(x, base=base, a=a, u_n=u, v_n=v):
            f = M_full @ (c * (x - base) - a)
            if damping:  # C v_{n+1}, v_{n+1} = 2 (x − u_n)/Δt − v_n
                f = f + damping * (M_full @ (2.0 / dt * (x - u_n) - v_n))
            return f

        u0 = u + dt * v
        u0[disc.fixed] = problem.prescribed(tn)
        res = newton(problem, state, u0, tn, rtol=rtol, maxit=maxit,
                     extra_matrix=(c + 2.0 * damping / dt) * M_ff, extra_rhs=inertia,
                     solver=solver, fixed_matrix=iteration)
        if not res.converged:
            status = f"diverged at t={tn:.4g}: {res.reason}"
            break
        iters.append(res.iterations)
        state = commit(state, res)
        a_new = c * (state.u - base) - a
        v = v + dt / 2 * (a + a_new)
        a = a_new
        u = state.u
        gone = problem.delete_failed(state)
        if len(gone):
            deleted.extend(gone.tolist())
            M_full = problem.mass()
            M_ff = M_full[disc.free][:, disc.free].tocsr()
            a[problem.held] = 0.0
            v[problem.held] = 0.0
            if initial_tangent:
                iteration = effective(state)
        t.append(tn)
        obs.append(observe(u))
        ke.append(0.5 * v @ (M_full @ v))
        se.append(problem.stored_energy(state))
        if snapshot is not None:
            snapshot(n + 1, t[-1], u, v)
        if callback is not None:
            callback(n + 1, tn, state, v)
    return dict(time=np.array(t), observed=np.array(obs), kinetic_energy=np.array(ke),
                strain_energy=np.array(se), status=status, newton_iterations=iters,
                deleted=np.array(deleted, dtype=np.int64))
