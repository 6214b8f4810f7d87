"""The highest eigenfrequency of a particle body and its critical explicit time step.

The explicit loops of every method (:mod:`sph.driver`) are velocity Verlet — the central-difference
scheme — or, for hpm's ``scheme='euler'``, symplectic Euler. Applied to the linearised discrete
system M ü + K u = 0 both are stable exactly when ω_max Δt ≤ 2 (Belytschko, Liu & Moran,
*Nonlinear Finite Elements*, §6.3: the amplification matrix of a mode ω has spectral radius 1 for
ω Δt ≤ 2 and > 1 above), so

    Δt_crit = 2 / ω_max,   ω_max² = λ_max(M⁻¹ K)                                  (1)

with M the lumped particle masses and K = −∂f/∂x the tangent of the method's internal force at the
initial state, restricted to the free DOFs. That is the critical step of each method's own
discretisation; the CFL estimate Δx/c_p of :meth:`sph.method.ParticleBody.time_step` is only a
guess of it (kernel supports of 2.2–2.6Δx make ω_max Δx/c_p differ from 2 by a factor up to two,
and integration-consistent csph on a cell lattice reaches 6.9).

K is applied matrix-free (:func:`stiffness_operator`):

* csph, hpm (a force f(x) of the positions alone, with or without hourglass control or
  stabilisation): K w = −[f(X + εw) − f(X − εw)]/(2ε), a central difference of
  :meth:`~sph.method.ParticleBody.internal_force` (O(ε²) truncation; ε scaled to a strain of
  :data:`FD_STRAIN`, far below any nonlinearity and far above round-off);
* classic SPH (:mod:`sph.classic`), whose stress is a *state* advanced from the velocity gradient:
  Verlet's step sets σ_{n+1} = σ_n + Δt σ̇(L_h(v_{n+1/2})) and then the force from σ_{n+1}, so about
  the stress-free initial state σ(u) = σ̇(L_h(u))·1 — the stress rate of :func:`sph.classic.rates_pass`
  for the "velocity" u over a unit step, with the kernel gradients at the initial positions — and
  K u = −f(σ(u)) by :func:`sph.classic.force_pass` with zero velocity (again as a central
  difference in u, so the hyperelastic stress path linearises too). The artificial viscosity acts
  on velocities, not displacements: it is not in K (it damps; a velocity-dependent force treated
  explicitly lowers the critical step slightly, which the measured critical factor shows).

λ_max of the mass-scaled operator M^{-1/2} K M^{-1/2} is found by Lanczos iterations
(:func:`scipy.sparse.linalg.eigsh`, ARPACK) — or Arnoldi (``eigs``) if the operator turns out
non-symmetric (classic SPH's K is symmetric at any densities: its velocity gradient is the power
conjugate of its forces, :mod:`sph.classic`; it was not while that gradient took m_j/ρ_j).
"""
from __future__ import annotations

import math

import numpy as np

FD_STRAIN = 1e-6
"""Size of the finite-difference perturbation: the largest displacement of εw is FD_STRAIN·Δx."""


def _classic_force(body):
    """f(u) (N, d), N, of a classic-SPH body about its current (initial) state: the force of the
    stress that one unit step of the stress rate with velocity u produces (module docstring)."""
    from .classic import force_pass, rates_pass

    b = body.b
    if b.mirrors:  # the rows would read ghosts (indices >= N) that x does not hold
        raise ValueError("mirror: classic SPH's spectrum is not built with symmetry planes; "
                         "allowed: mirror='none'")
    x = np.ascontiguousarray(b.x.copy())
    b._refresh_neighbours()  # the body's list (its pairs beyond 2h add zeros)
    ip, ix = b.indptr, b.indices
    N, d = x.shape
    zeros_v = np.zeros((N, d))
    a_ext = np.zeros((N, d))
    fixed = np.zeros((N, d), np.uint8)

    def force(u):
        rho = b.rho0.copy()
        rho_new = b.rho0.copy()
        sigma = np.zeros((N, 3, 3))
        F = np.tile(np.eye(3), (N, 1, 1))
        hist = b.table.initial_history(b.mat_id)
        hist_new = hist.copy()
        status = np.zeros(N, np.int64)
        R = np.zeros((N, d, d))
        rates_pass(x, np.ascontiguousarray(u), b.m, rho, rho_new, sigma, F, ip, ix, b.h, 1.0,
                   b.lam, b.mu, b.hyper, b.prm, b.mat_id, hist, hist_new, b.eps_as, status, R)
        acc = np.zeros((N, d))
        force_pass(x, zeros_v, b.m, rho, sigma, R, ip, ix, b.h, b.c, b.alpha, b.beta, b.n_as,
                   b.w_dx, a_ext, acc, fixed, zeros_v, 0.0, 0.0, False)
        return acc * b.m[:, None]

    return force


def stiffness_operator(body):
    """(apply, dx): ``apply(w) -> K w`` (N, d) → (N, d), N/m, the tangent of ``body``'s internal
    force at its current (initial) state by the rule of the module docstring, and the spacing Δx."""
    from .classic import Classic

    dx = float(body.particles.dx)
    if isinstance(body, Classic):
        force = _classic_force(body)
    else:
        X0 = body.x.copy()

        def force(u):
            return np.asarray(body.internal_force(np.ascontiguousarray(X0 + u)))

    def apply(w):
        scale = float(np.max(np.abs(w)))
        if scale == 0.0:
            return np.zeros_like(w)
        eps = FD_STRAIN * dx / scale
        return -(force(eps * w) - force(-eps * w)) / (2.0 * eps)

    return apply, dx


def max_frequency(body, fixed=None, tol: float = 1e-6, seed: int = 0) -> float:
    """ω_max (rad/s) of eq. (1): the largest eigenfrequency of the linearised discrete system of
    ``body`` (a :class:`sph.method.ParticleBody`, at its initial state: call before
    :meth:`~sph.method.ParticleBody.start`, which refreshes the state the force evaluations
    leave behind) with the DOFs ``fixed`` ((N, d) bool, or None: none) held. ``tol``: the relative
    accuracy of ω_max² asked of ARPACK."""
    import scipy.sparse.linalg as spla

    N, d = body.x.shape
    free = np.ones((N, d), bool) if fixed is None else ~np.asarray(fixed, bool)
    if free.shape != (N, d):
        raise ValueError(f"fixed: shape {free.shape} is not allowed; must be ({N}, {d})")
    m = np.broadcast_to(np.asarray(body.m, float)[:, None], (N, d))[free]
    if not (m > 0).all():
        free &= np.broadcast_to(np.asarray(body.m, float)[:, None] > 0, (N, d))
        m = np.broadcast_to(np.asarray(body.m, float)[:, None], (N, d))[free]
    n = int(free.sum())
    if n == 0:
        raise ValueError("fixed: every DOF is fixed; nothing can vibrate")
    apply, _ = stiffness_operator(body)
    s = 1.0 / np.sqrt(m)

    def matvec(y):
        w = np.zeros((N, d))
        w[free] = s * np.ravel(y)
        return s * apply(w)[free]

    A = spla.LinearOperator((n, n), matvec=matvec, dtype=np.float64)
    rng = np.random.default_rng(seed)
    p, q = rng.standard_normal(n), rng.standard_normal(n)
    Ap, Aq = matvec(p), matvec(q)
    asym = abs(q @ Ap - p @ Aq) / (np.linalg.norm(Ap) * np.linalg.norm(q) + 1e-300)
    v0 = rng.standard_normal(n)
    if n <= 3:
        Kd = np.column_stack([matvec(e) for e in np.eye(n)])
        lam = float(np.max(np.abs(np.linalg.eigvals(Kd))))
    elif asym < 1e-6:
        lam = float(spla.eigsh(A, k=1, which="LA", tol=tol, v0=v0, return_eigenvectors=False,
                               ncv=min(n, 30))[0])
    else:
        lam = float(np.abs(spla.eigs(A, k=1, which="LM", tol=tol, v0=v0, return_eigenvectors=False,
                                     ncv=min(n, 30))[0]))
    return math.sqrt(max(lam, 0.0))


def critical_time_step(body, fixed=None, tol: float = 1e-6) -> float:
    """Δt_crit = 2/ω_max (s), eq. (1), of ``body`` with the DOFs ``fixed`` held (see
    :func:`max_frequency`)."""
    w = max_frequency(body, fixed, tol)
    return 2.0 / w if w > 0 else math.inf
