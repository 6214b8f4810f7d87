"""Static equilibrium for a particle method without a gradient form (classic SPH, :mod:`sph.classic`):
dynamic relaxation through the method's own explicit step with kinetic damping (Cundall 1976;
Underwood 1983, "Dynamic relaxation", in *Computational Methods for Transient Analysis*, ch. 5;
Topping & Khan 1994).

A static drive asks for the equilibrium f_int(x) + f_ext(λ) = 0 at each value λ of its load path.
A method whose force is not −∂Π/∂x of its positions (classic SPH integrates a rate form: the stress
is a state advanced by the velocity gradient, the kernel is evaluated at the current positions)
has no tangent for Newton; the one thing it does have is its time step. So each load value is
reached by running that step (:meth:`sph.method.ParticleBody.advance`, velocity Verlet with the
method's own forces, artificial viscosity included) from the previous equilibrium under the new
dead loads, with the prescribed DOFs moved to their new positions, until the motion dies out.

Damping: **kinetic damping** (:func:`relax`) — the global kinetic energy ½ Σ m v² is followed and,
whenever it has passed a maximum, every velocity is set to zero. Along the lowest mode the body
starts at rest a distance u₀ from equilibrium and passes through it at the first kinetic-energy
peak, a quarter period later; zeroing the velocities there leaves it at rest near the equilibrium,
and the restart repeats this on what is left in the higher modes. Chosen over mass-proportional
viscous damping c = 2 ω₁ because that needs the lowest frequency ω₁ of each scene, resolution and
load (the cantilever's bending mode and the bar's axial mode differ by an order of magnitude, and
a wrong ω₁ makes the run either under-damped or a slow creep), while kinetic damping has no
parameter beyond the sampling interval; and it is what :func:`sph.static.dynamic_relaxation` does
for the gradient-form methods, so the two relaxations are comparable in cost. The velocities are
zeroed after the peak has been passed, within :data:`CHECK_EVERY` steps of it (the energy then
lies within O((ω₁ Δt·CHECK_EVERY)²) of its peak: the restart point differs from the equilibrium by
that fraction, removed by the following cycles). Rate-form stresses are a state of the body and
are kept through the restarts.

Prescribed motion: the held DOFs move from their present to their target positions at a constant
velocity over :func:`ramp_steps` steps (a rate-form method cannot jump: its stress follows from
velocities), the increment of strain per step in the particles next to them at most
:data:`RAMP_STRAIN`, then stay.

Converged when the out-of-balance force on the free DOFs, ‖m a‖₂, is at most ``tol`` times the
force scale — ‖f_ext‖₂, the applied dead loads, or, where there are none (a body loaded by
prescribed motion), ‖f_fixed‖₂, the forces the constraints carry — at a kinetic-energy restart (the
velocities zero: a state of rest). :data:`TOL` = 1e-4: a residual r left along the lowest mode, the
slowest to relax, displaces the body by r/k₁ against the load's f/k₁, a relative error of about
tol in the observed displacement (what is left in higher modes moves it less), two orders below
the discretisation error of any resolution the workbench runs classic SPH at.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from workbench.results import STOPPED

TOL = 1e-4
"""Out-of-balance force over the force scale at which the relaxation stops (module docstring)."""
CHECK_EVERY = 4
"""Steps between samples of the kinetic energy (one compiled call of the method's step each)."""
DT_FACTOR = 0.5
"""Time step over the CFL estimate Δx/c_p. The relaxation stays near the reference configuration at
small load, where the linear limit ω_max Δt < 2 is what counts: for classic SPH (cubic spline,
h = 1.3 Δx) ω_max of the assembled linearised stiffness puts it at a factor of 2.6–4.1 on the 3-D
cantilever and the bi-material bars; Monaghan's viscosity (α = β = 1), an explicit damper of
rate ~ α c/h, lowers it to O(1). 0.5 halves the steps of the explicit drives' 0.3 and was stable
in every run; an unstable step ends as 'diverged', never as a wrong equilibrium."""
MAX_STEPS = 200_000
"""Steps per load value after which the relaxation gives up ('not converged')."""
RAMP_STRAIN = 1e-4
"""Largest increment of strain per step (|Δu| per step over Δx) while prescribed DOFs move."""


@dataclass
class Relaxed:
    """Outcome of one relaxation: ``converged``, ``steps`` taken, ``restarts`` (kinetic-energy
    peaks at which the velocities were zeroed), ``residual`` ‖m a‖ on the free DOFs over the force
    scale at the end, ``failed`` (non-finite state or a failed material point)."""

    converged: bool
    steps: int
    restarts: int
    residual: float
    failed: bool = False


def ramp_steps(dx_fixed: np.ndarray, spacing: float, ramp_strain: float = RAMP_STRAIN) -> int:
    """Steps over which the prescribed DOFs move by ``dx_fixed`` (any shape, m): the largest
    |Δu|/Δx over ``ramp_strain``, at least one. ``spacing`` Δx, m."""
    if not (ramp_strain > 0):
        raise ValueError(f"ramp_strain: {ramp_strain!r} is not allowed; must be > 0")
    top = float(np.abs(dx_fixed).max()) if np.size(dx_fixed) else 0.0
    return max(1, int(math.ceil(top / (ramp_strain * spacing))))


def residual(body, fixed: np.ndarray) -> tuple[float, float]:
    """(‖m a‖₂ over the free DOFs, ‖m a‖₂ over the ``fixed`` (N, d) DOFs), N: the out-of-balance
    force and the forces the constraints must carry, from the body's accelerations (which include
    its dead loads)."""
    f = body.acc * body.m[:, None]
    return float(np.linalg.norm(f[~fixed])), float(np.linalg.norm(f[fixed]))


def relax(body, f_ext: np.ndarray, fixed: np.ndarray, x_target: np.ndarray, dt: float,
          spacing: float, tol: float = TOL, check_every: int = CHECK_EVERY,
          max_steps: int = MAX_STEPS) -> Relaxed:
    """Relax ``body`` (a :class:`sph.method.ParticleBody`, from its present state) to equilibrium
    under the dead forces ``f_ext`` (N, d), N, with the ``fixed`` (N, d) bool DOFs brought to
    ``x_target`` (N, d), m (only its fixed entries are read) by a ramp (:func:`ramp_steps`) and
    held there; kinetic damping sampled every ``check_every`` steps of size ``dt`` (s); converged
    at ‖R_free‖ ≤ ``tol`` · ‖f_ext‖ (‖R_fixed‖ where f_ext = 0) at a restart (module docstring), or given up
    after ``max_steps``. The body's state (positions, velocities zero at convergence, its
    rate-form stresses) is left at the last step."""
    if not (tol > 0):
        raise ValueError(f"tol: {tol!r} is not allowed; must be > 0")
    if not (isinstance(check_every, (int, np.integer)) and check_every >= 1):
        raise ValueError(f"check_every: {check_every!r} is not allowed; an integer >= 1")
    fixed = np.asarray(fixed, bool)
    fixed_u8 = np.ascontiguousarray(fixed, dtype=np.uint8)
    f_ext = np.ascontiguousarray(f_ext, dtype=np.float64)
    f_scale = float(np.linalg.norm(f_ext))
    zero = np.zeros_like(body.x)
    body.start(zero, f_ext)
    steps = restarts = 0
    # the ramp of the prescribed DOFs
    du = np.where(fixed, x_target - body.x, 0.0)
    n_ramp = ramp_steps(du, spacing) if np.any(du != 0) else 0
    if n_ramp:
        v_fix = du / (n_ramp * dt)
        done = body.advance(n_ramp, dt, f_ext, fixed_u8, v_fix)
        steps += done
        if done < n_ramp or not np.isfinite(body.x).all():
            return Relaxed(False, steps, restarts, math.nan, True)
    ke_old = 0.0
    res = math.inf
    while steps < max_steps:
        k = min(check_every, max_steps - steps)
        done = body.advance(k, dt, f_ext, fixed_u8, zero)
        steps += done
        if done < k or not np.isfinite(body.x).all():
            return Relaxed(False, steps, restarts, math.nan, True)
        ke = float(np.einsum("a,ak,ak->", body.m, body.v, body.v))
        if ke < ke_old:  # past a peak: stop
            body.v[:] = 0.0
            restarts += 1
            ke = 0.0
            r_free, r_fixed = residual(body, fixed)
            res = r_free / max(f_scale or r_fixed, 1e-300)
            if res <= tol:
                return Relaxed(True, steps, restarts, res)
        ke_old = ke
    r_free, r_fixed = residual(body, fixed)
    return Relaxed(False, steps, restarts, r_free / max(f_scale or r_fixed, 1e-300))


def relax_path(body, path, constraints_at, on_equilibrium=None, dt_factor: float = DT_FACTOR,
               tol: float = TOL, check_every: int = CHECK_EVERY,
               max_steps: int = MAX_STEPS) -> list[str]:
    """Equilibria along the load parameter ``path`` by :func:`relax` at each value, from the
    body's present state (the reference configuration at λ = 0), with the method's time step at
    ``dt_factor``. ``constraints_at(λ) -> (Constraints, x_target (N, d))`` as
    :func:`sph.static.solve_path` (its ``fixed`` and ``f_ext``); after each value
    ``on_equilibrium(k, λ, x, steps, force)`` with the force m a (N, d) on each particle (internal
    plus dead: its negative is what the constraints exert); a true return value stops the path
    there. Returns one status per value: 'ok', 'not converged: …' (the later values 'not run: an
    earlier load failed'), 'diverged: …', :data:`workbench.results.STOPPED`."""
    dt = body.time_step(dt_factor)
    spacing = body.particles.dx
    statuses = []
    failed = stopped = False
    for k, lam in enumerate(path):
        if failed or stopped:
            statuses.append("not run: an earlier load failed" if failed else STOPPED)
            continue
        cons, x_target = constraints_at(float(lam))
        out = relax(body, cons.f_ext, cons.fixed, x_target, dt, spacing, tol, check_every,
                    max_steps)
        if out.failed:
            statuses.append(f"diverged: dynamic relaxation, non-finite state after {out.steps} steps")
            failed = True
            continue
        if not out.converged:
            statuses.append(f"not converged: dynamic relaxation, residual {out.residual:.3g} of "
                            f"the load after {out.steps} steps")
            failed = True
            continue
        statuses.append("ok")
        if on_equilibrium is not None:
            stopped = bool(on_equilibrium(k, float(lam), body.x, out.steps,
                                          body.acc * body.m[:, None]))
    return statuses
