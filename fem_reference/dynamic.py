"""Implicit dynamics: Newmark's average-acceleration rule (β = 1/4, γ = 1/2, the trapezoidal
rule), unconditionally stable and energy-conserving for linear problems, second-order accurate.

    M a_{n+1} + f_int(u_{n+1}) = f_ext,
    u_{n+1} = u_n + Δt v_n + Δt²/4 (a_n + a_{n+1}),    v_{n+1} = v_n + Δt/2 (a_n + a_{n+1}),

solved for u_{n+1} by Newton with the effective tangent K + 4/Δt² M (Hughes, *The finite element
method*, §9.1). Kinetic energy ½ vᵀMv and strain energy ∫ W(F) dV are recorded every step.
"""
from __future__ import annotations


import numpy as np

from .constitutive import strain_energy_density
from .static import Problem, TangentSolver, commit, newton


def newmark(problem: Problem, v0: np.ndarray, dt: float, n_steps: int, observe,
            rtol: float = 1e-10, maxit: int = 20, snapshot=None):
    """Advance from rest at u = 0 with initial velocity v0 (N,) for ``n_steps`` steps of ``dt``.

    ``observe(u)`` returns the scalar recorded each step (e.g. a tip displacement);
    ``snapshot(step, t, u, v)`` (optional) is called at the start and after every step (field
    output; it decides which steps it writes).
    Returns dict(time, observed, kinetic_energy, strain_energy, status, newton_iterations).
    """
    disc = problem.disc
    free = disc.free
    M_full = disc.mass(problem.material.rho)
    M_ff = M_full[free][:, free].tocsr()
    state = problem.initial_state()
    u = state.u.copy()
    v = v0.copy()
    v[disc.fixed] = 0.0
    a = np.zeros(disc.N)  # f_int(0) = 0, f_ext = 0: the initial acceleration is zero
    c = 4.0 / dt ** 2

    def energy(st):
        if problem.material.law != "svk":
            return np.nan
        H = disc.displacement_gradient(st.u)
        return disc.integrate(strain_energy_density(problem.material, H, st.F33))

    t = [0.0]
    obs = [observe(u)]
    ke = [0.5 * v @ (M_full @ v)]
    se = [energy(state)]
    iters = []
    status = "ok"
    solver = TangentSolver()
    if snapshot is not None:
        snapshot(0, 0.0, u, v)
    for n in range(n_steps):
        # a_{n+1}(u) = c (u − u_n − Δt v_n) − a_n; residual f_int(u) + M a_{n+1}(u)
        base = u + dt * v

        def inertia(x, base=base, a=a):
            return M_full @ (c * (x - base) - a)

        res = newton(problem, state, u + dt * v, 0.0, rtol=rtol, maxit=maxit,
                     extra_matrix=c * M_ff, extra_rhs=inertia, solver=solver)
        if not res.converged:
            status = f"diverged at t={t[-1] + dt:.4g}: {res.reason}"
            break
        iters.append(res.iterations)
        state = commit(state, res)
        a_new = c * (state.u - base) - a
        v = v + dt / 2 * (a + a_new)
        a = a_new
        u = state.u
        t.append((n + 1) * dt)
        obs.append(observe(u))
        ke.append(0.5 * v @ (M_full @ v))
        se.append(energy(state))
        if snapshot is not None:
            snapshot(n + 1, t[-1], u, v)
    return dict(time=np.array(t), observed=np.array(obs), kinetic_energy=np.array(ke),
                strain_energy=np.array(se), status=status, newton_iterations=iters)
