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
calls per particle; :func:`kick_drift` and :func:`kick` are their parallel loops over all particles
(the generic step of :meth:`sph.method.ParticleBody.advance`).
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
