"""Static equilibrium of a gradient-form body (:class:`sph.total_lagrangian.Body`): Newton on the
force balance f(x) + f_ext = 0 with the assembled symmetric tangent K = ∂²Π/∂x∂x, load stepping
along a path of the load parameter with the increment halved on failure, and dynamic relaxation
(explicit dynamics with kinetic damping) as the fallback and for the cost comparison.

A static scene is solved as such: Newton converges quadratically from the previous equilibrium in
a few iterations where dynamic relaxation needs tens of thousands of steps (README: cantilever
H/Δx = 4, 0.5 s against 2 s).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.linear_systems import (RTOL, KeptHierarchy, forcing_term, rigid_body_modes,
                                      solve_symmetric)
from workbench.results import STOPPED

from .integrate import cfl_time_step
from .total_lagrangian import Body, advance


@dataclass
class Constraints:
    """Kinematic boundary conditions on DOFs: ``fixed`` (N, d) bool, the DOFs whose position is
    prescribed (clamps, rollers, prescribed displacement); ``f_ext`` (N, d) applied dead loads, N."""

    fixed: np.ndarray
    f_ext: np.ndarray


DR_TOL = 1e-4
"""Residual over the load at which dynamic relaxation stops (its residual stagnates near 1e-5 of
the load: explicit round-off and the kinetic damping's restarts)."""
ROUND_OFF = 1e-13
"""A Newton correction below this fraction of the body's size is round-off: converged."""


def newton(body: Body, x: np.ndarray, cons: Constraints, x_target_fixed: np.ndarray,
           tol: float = 1e-8, max_iter: int = 30, force_scale: float | None = None,
           kept: KeptHierarchy | None = None):
    """Equilibrium f(x) + f_ext = 0 on the free DOFs with the fixed DOFs moved to
    ``x_target_fixed`` (N, d) (only its fixed entries are read), from the equilibrium ``x``.

    First iteration: the consistent predictor (old tangent, prescribed increment through K_fp).
    Converged when ‖R_free‖ ≤ tol · scale, with ``force_scale`` or, by default, the larger of the
    applied load ‖f_ext‖ and the reaction ‖f_fixed‖ (so the criterion is relative whether the body
    is loaded by forces or by prescribed motion), or when the last correction was round-off
    (below :data:`ROUND_OFF` of the body's size; quadratic convergence has then run out of
    digits). ``kept``: an AMG hierarchy kept across the systems of a path (:func:`solve_linear`).
    Returns (x_new, converged, iterations); the body's trial history belongs to x_new (call
    ``body.commit()`` to accept)."""
    fixed = cons.fixed.ravel()
    free = ~fixed
    x = x.copy()
    dxp = (x_target_fixed - x).ravel()[fixed]
    f_norm = float(np.linalg.norm(cons.f_ext))
    size = float(np.abs(body.disc.X).max()) or 1.0
    last_step = np.inf
    for it in range(max_iter + 1):
        f, A = body.evaluate(x, tangent=True)
        if np.any(body.status != 0):
            return x, False, it
        R = -(f + cons.f_ext).ravel()
        Rf = R[free]
        scale = (force_scale if force_scale is not None
                 else max(f_norm, float(np.linalg.norm(R[fixed]))))
        if it > 0 and (np.linalg.norm(Rf) <= tol * scale or last_step <= ROUND_OFF * size):
            return x, True, it
        K = body.tangent(A)
        Kff = K[free][:, free]
        rhs = -Rf
        if it == 0 and np.any(dxp != 0):
            Kfp = K[free][:, fixed]
            rhs = rhs - Kfp @ dxp
        # inexact Newton: the system to the forcing term of the residual it corrects
        rtol = forcing_term(np.linalg.norm(rhs) / scale) if scale > 0 else RTOL
        try:
            du = solve_linear(Kff, rhs, near_null=lambda: rigid_body_modes(x, free),
                              dim=x.shape[1], kept=kept, rtol=rtol)
        except Exception:  # singular tangent
            return x, False, it
        if not np.all(np.isfinite(du)):
            return x, False, it
        step = np.zeros(x.size)
        step[free] = du
        if it == 0:
            step[fixed] = dxp
        last_step = float(np.abs(du).max()) if du.size else 0.0
        x = x + step.reshape(x.shape)
    return x, False, max_iter


DENSE_BELOW = {2: 400, 3: 1200}
"""Free DOFs, by dimension, under which the Newton system is solved dense (LAPACK) rather than by
SuperLU: measured on csph tangents of a clamped beam (min of 3, one BLAS thread, 2 cores; dense
ms / sparse ms) — 2-D: 320 unknowns 1.4 / 1.7, 480: 8.0 / 6.4, 672: 11.5 / 5.6, 1760: 937 /
24, 2496: 1433 / 44, 3360: 2390 / 113; 3-D: 216: 0.8 / 2.5, 576: 16 / 40, 1200: 116 / 117, 2160:
1005 / 330. The particle tangent couples second neighbours, so a tiny body's sparse LU fills in
and loses; above the crossover the dense solve's n³ loses by far (issue 40: 4.68 s against
0.35 s at 2 538 unknowns with threaded BLAS on a busy machine)."""


def solve_linear(K, rhs, near_null=None, dim: int = 3, kept: KeptHierarchy | None = None,
                 rtol: float = RTOL) -> np.ndarray:
    """K⁻¹ rhs for the Newton step: dense LU below :data:`DENSE_BELOW` unknowns (of ``dim``), above that
    :func:`workbench.linear_systems.solve_symmetric` (SuperLU, or in 3-D above
    :data:`~workbench.linear_systems.AMG_ABOVE` unknowns CG with an AMG hierarchy built on
    ``near_null``, the rigid-body modes of the free DOFs, point-major, or a callable giving
    them, and kept in ``kept`` for the next systems, to the relative residual ``rtol``;
    ``dim``: the body's dimension)."""
    import scipy.linalg as sla

    if K.shape[0] < DENSE_BELOW[3 if dim >= 3 else 2]:
        return sla.solve(K.toarray(), rhs, check_finite=False)
    return solve_symmetric(K.tocsr(), rhs, near_null=near_null, dim=dim, kept=kept, rtol=rtol)


def spacing(body: Body) -> float:
    """Smallest neighbour distance of the reference configuration (the particle spacing), m."""
    d = body.disc
    a = np.repeat(np.arange(d.n), np.diff(d.indptr))
    return float(np.linalg.norm(d.extend(d.X)[d.indices] - d.X[a], axis=1).min())


def dynamic_relaxation(body: Body, x: np.ndarray, cons: Constraints, x_target_fixed: np.ndarray,
                       tol: float = DR_TOL, max_steps: int = 2_000_000, force_scale: float | None = None,
                       dt_factor: float = 0.5, check_every: int = 10):
    """Equilibrium by explicit dynamics (the fused loop of :func:`sph.total_lagrangian.advance`)
    with kinetic damping: the velocities are zeroed whenever the kinetic energy, sampled every
    ``check_every`` steps, has passed a peak. Converged when ‖f + f_ext‖ on the free DOFs ≤
    tol · force_scale (default: the total applied load Σ|f_ext|). Returns (x, converged, steps);
    the body's history is committed along the way."""
    disc = body.disc
    dt = cfl_time_step(spacing(body), body.table.wave_speed("strain"), dt_factor)
    if force_scale is None:
        force_scale = max(float(np.abs(cons.f_ext).sum()), 1e-300)
    x = np.ascontiguousarray(x, dtype=np.float64).copy()
    x[cons.fixed] = x_target_fixed[cons.fixed]
    fixed = np.ascontiguousarray(cons.fixed, dtype=np.uint8)
    v = np.zeros_like(x)
    v_fix = np.zeros_like(x)
    f_ext = np.ascontiguousarray(cons.f_ext, dtype=np.float64)
    acc = (body.evaluate(x) + f_ext) / disc.m[:, None]
    body.commit()
    h_scratch = body.history.copy()
    ke_old = 0.0
    steps = 0
    free = ~cons.fixed
    while steps < max_steps:
        done = advance(body, x, v, acc, f_ext, fixed, v_fix, dt, 0.0, check_every, h_scratch)
        steps += done
        if done < check_every or not np.isfinite(v).all():
            return x, False, steps
        ke = float(np.sum(disc.m[:, None] * v * v))
        if ke < ke_old:
            v[:] = 0.0
            ke = 0.0
        ke_old = ke
        if steps % (10 * check_every) == 0:
            R = acc * disc.m[:, None]
            if np.linalg.norm(R[free]) <= tol * force_scale:
                return x, True, steps
    return x, False, steps


def solve_path(body: Body, x: np.ndarray, path, constraints_at, on_equilibrium=None,
               tol: float = 1e-8, max_cuts: int = 6, fallback: str | None = "dr",
               method: str = "newton") -> list[str]:
    """Equilibria along the load parameter ``path`` (increasing or not), from the equilibrium
    ``x`` at the parameter 0. ``constraints_at(λ) -> (Constraints, x_target (N, d))`` gives the
    loads and prescribed positions at λ. Each value is reached by Newton from the last
    equilibrium; a failed increment is halved (at most 2^``max_cuts`` sub-steps, each committed);
    when that is exhausted, dynamic relaxation (``fallback='dr'``) or failure. ``method='dr'``
    uses dynamic relaxation alone (the cost comparison). After each value of the path
    ``on_equilibrium(k, λ, x, iterations)`` is called; a true return value stops the path there.
    Returns one status per value ('ok', 'ok (dynamic relaxation fallback)', 'diverged: …',
    'not run: an earlier load failed', :data:`workbench.results.STOPPED`)."""
    if method not in ("newton", "dr"):
        raise ValueError(f"static: {method!r} is not one of 'newton', 'dr'")
    statuses = []
    current = 0.0
    kept = KeptHierarchy()  # one AMG hierarchy for the path's systems, rebuilt where it misses
    failed = stopped = False
    for k, lam in enumerate(path):
        if failed or stopped:
            statuses.append("not run: an earlier load failed" if failed else STOPPED)
            continue
        steps = [float(lam)]
        status = "ok"
        total_it = 0
        while steps:
            target = steps[0]
            cons, x_target = constraints_at(target)
            if method == "dr":
                xn, conv, it = dynamic_relaxation(body, x, cons, x_target, tol=DR_TOL)
                total_it += it
                if not conv:
                    status = "diverged: dynamic relaxation"
                    failed = True
                    break
                x, current = xn, target
                steps.pop(0)
                continue
            xn, conv, it = newton(body, x, cons, x_target, tol=tol, kept=kept)
            total_it += it
            if not conv and len(steps) < 2 ** max_cuts and abs(target - current) > 1e-6 * max(abs(lam), 1e-300):
                steps.insert(0, current + 0.5 * (target - current))
                continue
            if not conv and fallback == "dr":
                xn, conv, it = dynamic_relaxation(body, x, cons, x_target, tol=DR_TOL)
                total_it += it
                status = "ok (dynamic relaxation fallback)" if conv else "diverged: dynamic relaxation"
            elif not conv:
                status = f"diverged: Newton at {target:.4g}"
            if not conv:
                failed = True
                break
            body.commit()
            x = xn
            current = target
            steps.pop(0)
        statuses.append(status)
        if not failed and on_equilibrium is not None:
            stopped = bool(on_equilibrium(k, float(lam), x, total_it))
    return statuses
