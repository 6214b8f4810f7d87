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

from .static import Problem, TangentSolver, commit, newton
from workbench.linear_systems import direct_factor


MAX_CUTS = 6
"""Most halvings of a step whose Newton fails (a step of Δt/2⁶ at the deepest): a material point
that reaches failure (D ≥ 1) within a step is refused by the line search (:func:`newton`), so
the step is cut until the point fails at a step's end, where it is committed and its element
deleted — as the static load stepping does with its increments."""


def newmark(problem: Problem, v0: np.ndarray, dt: float, n_steps: int, observe,
            rtol: float = 1e-10, maxit: int = 20, snapshot=None, callback=None,
            damping: float = 0.0, initial_tangent: bool = False, max_cuts: int = MAX_CUTS,
            on_step=None):
    """Advance from u = 0 (the prescribed values of the fixed DOFs at t = 0) with initial velocity
    v0 (N,) for ``n_steps`` steps of ``dt``. On the fixed DOFs v0 must be the rate of the
    prescribed motion at t = 0 (zero on a clamp): the consistent mass couples their acceleration
    into the free DOFs.

    ``observe(u)`` returns the scalar (or array) recorded each step (e.g. a tip displacement);
    ``snapshot(step, t, u, v)`` (optional) is called at the start and after every step (field
    output; it decides which steps it writes); ``callback(step, t, state, v)`` (optional) too, with
    the committed :class:`~fem_reference.static.State`; a true return value of ``callback``
    ends the run there (status ok, ``stopped`` True: a stop rule of the drive).
    The initial acceleration solves M a₀ = f_ext(0) − f_int(u₀) − c M v₀ on the free DOFs
    (``damping`` c, 1/s: mass-proportional damping, module docstring). ``initial_tangent``:
    modified Newton with the initial effective matrix (module docstring). A step whose Newton
    fails is cut in two halves, each cut again if it fails, down to Δt/2^``max_cuts``
    (:data:`MAX_CUTS`); the run stops ("diverged") only below that. Recorded are the ends of
    the full steps. ``on_step(t, h, r)`` (optional) is called after every converged step or
    part of one, of length h ending at t, with r (N,) = M a + f_int − f_ext at the new state: on
    the fixed DOFs the force of the supports on the body (dynamic equilibrium), whose impulse
    over the step is h/2 (r_n + r_n+1) by the trapezoidal rule of the scheme.
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
        a[disc.free] = direct_factor(M_ff)(r0[disc.free])
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

    def effective(st, M_ff):
        """b ↦ (K₀ + (c + 2 damping/Δt) M_ff)⁻¹ b with the tangent at ``st``, factorised once."""
        K0 = problem.tangent(problem.evaluate(st.u, st, tangent=True))
        return direct_factor((K0 + (c + 2.0 * damping / dt) * M_ff).tocsr())

    iteration = effective(state, M_ff) if initial_tangent else None
    if snapshot is not None:
        snapshot(0, 0.0, u, v)
    stopped = callback is not None and bool(callback(0, 0.0, state, v))
    run = dict(state=state, u=u, v=v, a=a, M_full=M_full, M_ff=M_ff, iteration=iteration)

    def advance(t0, h, depth):
        """One step of h from t0 on ``run``, cut in halves where Newton fails; None, or the
        reason it could not be done."""
        st, u_n, v_n, a_n = run["state"], run["u"], run["v"], run["a"]
        ch = 4.0 / h ** 2
        base = u_n + h * v_n
        M_full = run["M_full"]

        def inertia(x):  # a_{n+1}(x) = ch (x − u_n − h v_n) − a_n; C v_{n+1}, v = 2(x − u_n)/h − v_n
            f = M_full @ (ch * (x - base) - a_n)
            if damping:
                f = f + damping * (M_full @ (2.0 / h * (x - u_n) - v_n))
            return f

        u0 = u_n + h * v_n
        u0[disc.fixed] = problem.prescribed(t0 + h)
        res = newton(problem, st, u0, t0 + h, rtol=rtol, maxit=maxit,
                     extra_matrix=(ch + 2.0 * damping / h) * run["M_ff"], extra_rhs=inertia,
                     solver=solver, fixed_matrix=run["iteration"] if depth == 0 else None)
        if not res.converged:
            if depth >= max_cuts:
                return res.reason
            return advance(t0, h / 2, depth + 1) or advance(t0 + h / 2, h / 2, depth + 1)
        iters.append(res.iterations)
        if on_step is not None:
            on_step(t0 + h, h, res.residual)
        st = commit(st, res)
        a_new = ch * (st.u - base) - a_n
        v_new = v_n + h / 2 * (a_n + a_new)
        gone = problem.delete_failed(st)
        if len(gone):
            deleted.extend(gone.tolist())
            run["M_full"] = problem.mass()
            run["M_ff"] = run["M_full"][disc.free][:, disc.free].tocsr()
            a_new[problem.held] = 0.0
            v_new[problem.held] = 0.0
            if initial_tangent:
                run["iteration"] = effective(st, run["M_ff"])
        run.update(state=st, u=st.u, v=v_new, a=a_new)
        return None

    for n in range(0 if stopped else n_steps):
        tn = (n + 1) * dt
        why = advance(n * dt, dt, 0)
        if why is not None:
            status = f"diverged at t={tn:.4g}: {why}"
            break
        state, u, v, M_full = run["state"], run["u"], run["v"], run["M_full"]
        t.append(tn)
        obs.append(observe(u))
        ke.append(0.5 * v @ (M_full @ v))
        se.append(problem.stored_energy(state))
        if snapshot is not None:
            snapshot(n + 1, t[-1], u, v)
        if callback is not None and callback(n + 1, tn, state, v):
            stopped = True
            break
    return dict(time=np.array(t), observed=np.array(obs), kinetic_energy=np.array(ke),
                strain_energy=np.array(se), status=status, newton_iterations=iters,
                deleted=np.array(deleted, dtype=np.int64), stopped=stopped)
