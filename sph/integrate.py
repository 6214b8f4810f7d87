"""Explicit time integration shared by the particle methods: velocity Verlet (kick–drift–kick
leapfrog, symplectic), with fixed or prescribed-velocity degrees of freedom and optional
mass-proportional damping, and the CFL time step.

A step from the synchronised state (x_n, v_n, a_n):

1. kick–drift: v ← v + dt/2 a_n, x ← x + dt v;
2. the method computes a_{n+1} = f(x_{n+1})/m;
3. kick: v ← v + dt/2 a_{n+1}.

Degrees of freedom flagged in ``fixed`` (N, d) uint8 follow their prescribed velocity ``v_fix``
(zero for a clamp) instead. Mass-proportional damping a = f/m − c v is applied semi-implicitly in
the kicks (v ← (v + dt/2 f/m)/(1 + c dt/2) after the force, v ← (1 − c dt/2) v + dt/2 f/m before),
which is second order and exactly the undamped scheme for c = 0.

The row routines (:func:`kick_drift_row`, :func:`kick_row`) are what a method's fused force loop
calls per particle; :func:`kick_drift` and :func:`kick` are their parallel loops over all particles.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .kernels import JIT


def check_dt_factor(factor) -> None:
    """``factor`` (time step over the CFL estimate) must lie in (0, 10]; anything else is a
    ``ValueError`` naming it."""
    if not (isinstance(factor, (int, float)) and math.isfinite(factor) and 0 < factor <= 10):
        raise ValueError(f"dt_factor: {factor!r} is not allowed; the time step over the CFL "
                         f"estimate must lie in (0, 10]")


def cfl_time_step(dx: float, wave_speed: float, factor: float) -> float:
    """dt = factor · Δx / c, s, with c the fastest elastic wave speed (m/s) and Δx the particle
    spacing (m). ``factor`` as :func:`check_dt_factor`."""
    check_dt_factor(factor)
    if not (dx > 0 and wave_speed > 0):
        raise ValueError(f"dx, wave_speed: must be > 0 (got {dx}, {wave_speed})")
    return factor * dx / wave_speed


@njit(inline="always", **JIT)
def kick_drift_row(a, x, v, acc, fixed, v_fix, dt, damping):
    """First half of velocity Verlet for particle ``a``: v += dt/2 acc (damped), x += dt v."""
    for k in range(x.shape[1]):
        if fixed[a, k]:
            v[a, k] = v_fix[a, k]
        else:
            v[a, k] = (1.0 - 0.5 * damping * dt) * v[a, k] + 0.5 * dt * acc[a, k]
        x[a, k] += dt * v[a, k]


@njit(inline="always", **JIT)
def kick_row(a, v, acc, fixed, v_fix, dt, damping):
    """Second half of velocity Verlet for particle ``a``: v = (v + dt/2 acc)/(1 + c dt/2)."""
    for k in range(v.shape[1]):
        if fixed[a, k]:
            v[a, k] = v_fix[a, k]
        else:
            v[a, k] = (v[a, k] + 0.5 * dt * acc[a, k]) / (1.0 + 0.5 * damping * dt)


@njit(parallel=True, **JIT)
def kick_drift(x, v, acc, fixed, v_fix, dt, damping):
    """:func:`kick_drift_row` over all particles."""
    for a in prange(x.shape[0]):
        kick_drift_row(a, x, v, acc, fixed, v_fix, dt, damping)


@njit(parallel=True, **JIT)
def kick(v, acc, fixed, v_fix, dt, damping):
    """:func:`kick_row` over all particles."""
    for a in prange(v.shape[0]):
        kick_row(a, v, acc, fixed, v_fix, dt, damping)


def velocity_verlet(x, v, acc, accel_fn, dt: float, n_steps: int, fixed=None, v_fix=None,
                    damping: float = 0.0, callback=None):
    """Generic driver for a method without a fused loop: ``accel_fn(x) -> acc`` (N, d).

    Advances the synchronised state (x, v, acc) in place by ``n_steps`` steps; ``callback(step, x,
    v, acc)`` after each (return True to stop early). Returns the number of steps taken.
    """
    N, d = x.shape
    fixed = np.zeros((N, d), np.uint8) if fixed is None else np.ascontiguousarray(fixed, np.uint8)
    v_fix = np.zeros((N, d)) if v_fix is None else v_fix
    for s in range(n_steps):
        kick_drift(x, v, acc, fixed, v_fix, dt, damping)
        acc[:] = accel_fn(x)
        kick(v, acc, fixed, v_fix, dt, damping)
        if callback is not None and callback(s + 1, x, v, acc):
            return s + 1
    return n_steps


def monitor_chunk(n_steps: int, n_out: int) -> int:
    """Steps per chunk of :func:`run_monitored`."""
    return max(1, n_steps // n_out)


def run_monitored(step, energies, observe, failed, state, n_steps: int, n_out: int,
                  energy_growth: float, snapshot=None) -> dict:
    """The monitored time loop of the plate drivers (hpm, classic SPH): ``n_steps`` steps in about
    ``n_out`` chunks; after each chunk the energies and the observed quantity are recorded.

    ``step(k) -> steps done``; ``energies() -> (kinetic, stored)``; ``observe() -> float`` (the tip
    displacement); ``failed() -> bool`` (a material point failed); ``state`` has ``x`` and ``t``.
    Unstable (status 'unstable: <reason> at t=…', the run ends) on a short step, a non-finite state,
    or total energy *grown* by more than ``energy_growth`` of the initial energy
    (:func:`sph.diagnostics.energy_change`, one-sided). A loss of energy is recorded as
    ``dissipated`` (fraction of the initial energy lost at the end, ≥ 0) with a ``note`` when it
    exceeds ``energy_growth``; the status stays 'ok'. ``period`` and ``amplitude`` come from the
    observed history by :func:`sph.diagnostics.period_amplitude` (NaN for an unstable run).

    ``snapshot`` (optional, a :class:`workbench.fields.Snapshots` built with ``chunk`` =
    :func:`monitor_chunk`): called with the steps done before the loop, after every chunk and,
    ``final=True``, at the end — field output between chunks, outside the compiled steps."""
    import time

    from .diagnostics import energy_change, period_amplitude

    per = monitor_chunk(n_steps, n_out)
    if snapshot is not None:
        snapshot(0)
    times, obs = [0.0], [0.0]
    ke, pe = energies()
    kes, pes = [ke], [pe]
    e0 = ke + pe
    status = "ok"
    wall = 0.0
    done_total = 0
    while done_total < n_steps:
        k = min(per, n_steps - done_total)
        t0 = time.perf_counter()
        done = step(k)
        wall += time.perf_counter() - t0
        done_total += done
        if done < k or not np.isfinite(state.x).all():
            reason = "material point failed (J <= 0 or no convergence)" if failed() else "non-finite state"
            status = f"unstable: {reason} at t={state.t:.4g} s"
            break
        ke, pe = energies()
        times.append(state.t)
        obs.append(observe())
        kes.append(ke)
        pes.append(pe)
        grew, change = energy_change(e0, ke + pe, e0, energy_growth)
        if grew:
            status = f"unstable: total energy grew by {change:+.3g} at t={state.t:.4g} s"
            break
        if snapshot is not None:
            snapshot(done_total)
    if snapshot is not None:
        snapshot(done_total, final=True)
    t, u = np.asarray(times), np.asarray(obs)
    T, A = period_amplitude(t, u) if status == "ok" else (math.nan, math.nan)
    ke_a, pe_a = np.asarray(kes), np.asarray(pes)
    e = ke_a + pe_a
    drift = float((e[-1] - e[0]) / e[0]) if e[0] else math.nan
    dissipated = max(0.0, -drift) if math.isfinite(drift) else math.nan
    note = (f"dissipated {100 * dissipated:.3g} % of the initial energy"
            if status == "ok" and dissipated > energy_growth else "")
    return dict(period=T, amplitude=A, time=t, tip_displacement=u, kinetic_energy=ke_a,
                strain_energy=pe_a, energy_drift=drift, dissipated=dissipated, note=note,
                status=status, wall_time=wall)
