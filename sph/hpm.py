"""Hamiltonian particle method (HPM; Suzuki & Koshizuka 2008, as used in 004 §II), 2-D plane strain,
total Lagrangian.

Everything weight-related is computed once in the reference configuration X (the *Lagrangian
kernel*): neighbours within the influence radius r_e (:mod:`sph.neighbours`), the weights

    w_ij = 1 − |X_ij|²/r_e²  for |X_ij| < r_e, 0 otherwise            (eq. 6, X_ij = X_j − X_i)

and the moment matrices A_i = Σ_j w_ij X_ij ⊗ X_ij (eq. 5, :func:`reference_geometry`). Then per
evaluation:

* the deformation gradient by weighted least squares, F_i = (Σ_j w_ij x_ij ⊗ X_ij) A_i⁻¹ (eq. 4):
  exact for every affine motion on any particle arrangement (F is 3×3, F33 = 1, plane strain);
* P_i = F_i S_i from the shared material library
  (:func:`workbench.materials.kernels.material_point`: SVK eq. 11, Mooney–Rivlin-like eq. 12);
* the force as the exact derivative of the discrete Hamiltonian H = ½ Σ m_i v_i² + Σ_i V_i ψ(F_i):
  since ∂F_i/∂x_k = Σ_j (δ_jk − δ_ik) e ⊗ A_i⁻¹ X_ij w_ij,

      f_i = −∂H/∂x_i = Σ_j w_ij (M_i + M_j) X_ij,   M_i = V_i P_i A_i⁻¹       (eq. 7 times m_i)

  (:func:`internal_force`). The pair term is antisymmetric (X_ji = −X_ij, the bracket symmetric), so
  Σ f = 0 exactly; H is invariant under rigid rotations of x, so the torque vanishes too.

Zero-energy-mode stabilisation (after Kondo, Suzuki & Koshizuka 2010, who add to the Hamiltonian a
potential that penalises the particle motion the affine map F_i does not see): we use

    H_s = Σ_i c_i Σ_j w_ij |x_ij − F_i X_ij|²,   c_i = α G V_i / Σ_j w_ij |X_ij|²

with α = ``stabilisation`` (0: off) and G the small-strain shear modulus. Because F_i minimises
Σ_j w_ij |x_ij − F X_ij|² (that is eq. 4), ∂H_s/∂F_i = 0 and the force is simply
f_i += 2 Σ_j w_ij [c_i (x_ij − F_i X_ij) + c_j (x_ij − F_j X_ij)], antisymmetric, conservative and
objective: energy and both momenta stay conserved. (The exact normalisation of Kondo et al. was not
available here; this is our formulation of the same idea, stated so it can be checked.)

Time integration: the symplectic scheme of eq. 8 (x^{n+1} = x^n + Δt v^n, v^{n+1} = v^n + Δt a^{n+1}).
Its positions are those of the leapfrog; we run it in the kick–drift–kick (velocity Verlet) form of
the shared :mod:`sph.integrate` (``scheme="verlet"``, default) so that velocities — and hence the
reported energies — are synchronous with positions; ``scheme="euler"`` runs eq. 8 literally.

:func:`solve` dispatches on the scene (Plate, Cantilever, and the stability scenes of
:mod:`workbench.scenes.stability`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from numba import njit, prange

from workbench.materials.kernels import material_point, svk_point

from .diagnostics import strain_energy
from .integrate import cfl_time_step, kick_drift_row, kick_row
from .kernels import JIT, N_CHUNKS
from .method import ParticleBody
from .neighbours import drop_cross_body, neighbour_list

RE_RATIO = 2.1
"""Default influence radius r_e over the particle spacing (eq. 6)."""


# ================================================================================================
# Reference configuration (eq. 5, 6)
# ================================================================================================

@njit(parallel=True, **JIT)
def reference_geometry(X, indptr, indices, re, X_ij, w, Ainv, wr2):
    """Fill, per pair p of the CSR list, X_ij[p] = X_j − X_i and w[p] (eq. 6); per particle the
    inverse moment matrix Ainv[i] = A_i⁻¹ (eq. 5) and wr2[i] = Σ_j w_ij |X_ij|². Returns the number
    of particles whose A_i is singular (fewer than two independent neighbour directions)."""
    N = X.shape[0]
    bad = np.zeros(N, np.int64)
    for i in prange(N):
        a00 = 0.0
        a01 = 0.0
        a11 = 0.0
        s = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            dx = X[j, 0] - X[i, 0]
            dy = X[j, 1] - X[i, 1]
            r2 = dx * dx + dy * dy
            wij = 1.0 - r2 / (re * re) if r2 < re * re else 0.0
            X_ij[p, 0] = dx
            X_ij[p, 1] = dy
            w[p] = wij
            a00 += wij * dx * dx
            a01 += wij * dx * dy
            a11 += wij * dy * dy
            s += wij * r2
        det = a00 * a11 - a01 * a01
        wr2[i] = s
        if not det > 1e-12 * (a00 * a11 + 1e-300):
            bad[i] = 1
            Ainv[i, 0, 0] = 0.0
            Ainv[i, 0, 1] = 0.0
            Ainv[i, 1, 0] = 0.0
            Ainv[i, 1, 1] = 0.0
        else:
            Ainv[i, 0, 0] = a11 / det
            Ainv[i, 1, 1] = a00 / det
            Ainv[i, 0, 1] = -a01 / det
            Ainv[i, 1, 0] = -a01 / det
    return bad.sum()


# ================================================================================================
# Per evaluation: F (eq. 4), stress (shared library), force (eq. 7)
# ================================================================================================

@njit(inline="always", **JIT)
def _deformation_gradient_row(i, x, indptr, indices, X_ij, w, Ainv, F):
    """F (3×3, F33 = 1) of particle i by weighted least squares (eq. 4)."""
    b00 = 0.0
    b01 = 0.0
    b10 = 0.0
    b11 = 0.0
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        wij = w[p]
        ux = wij * (x[j, 0] - x[i, 0])
        uy = wij * (x[j, 1] - x[i, 1])
        b00 += ux * X_ij[p, 0]
        b01 += ux * X_ij[p, 1]
        b10 += uy * X_ij[p, 0]
        b11 += uy * X_ij[p, 1]
    F[0, 0] = b00 * Ainv[i, 0, 0] + b01 * Ainv[i, 1, 0]
    F[0, 1] = b00 * Ainv[i, 0, 1] + b01 * Ainv[i, 1, 1]
    F[1, 0] = b10 * Ainv[i, 0, 0] + b11 * Ainv[i, 1, 0]
    F[1, 1] = b10 * Ainv[i, 0, 1] + b11 * Ainv[i, 1, 1]
    F[0, 2] = 0.0
    F[1, 2] = 0.0
    F[2, 0] = 0.0
    F[2, 1] = 0.0
    F[2, 2] = 1.0


@njit(parallel=True, **JIT)
def stress_pass(x, indptr, indices, X_ij, w, Ainv, V, h_old, prm, F_all, M, h_new, status):
    """For every particle: F_i (eq. 4) into F_all (N,3,3), P_i from the shared material library, and
    M_i = V_i P_i A_i⁻¹ (N,2,2) — the per-particle factor of eq. 7. ``status`` (N,) gets the
    material routine's return code (0 ok)."""
    N = x.shape[0]
    chunk = (N + N_CHUNKS - 1) // N_CHUNKS
    svk = prm[0] == 0.0  # SVK: the shared law called directly (no dispatch, no history)
    for c in prange(N_CHUNKS):
        F = np.empty((3, 3))
        P = np.empty((3, 3))
        A = np.empty((3, 3, 3, 3))
        for i in range(c * chunk, min(N, (c + 1) * chunk)):
            _deformation_gradient_row(i, x, indptr, indices, X_ij, w, Ainv, F)
            if svk:
                status[i] = svk_point(F, prm, P, A, False)
            else:
                status[i] = material_point(F, h_old[i], prm, P, h_new[i], A, False)
            for k in range(3):
                for l in range(3):
                    F_all[i, k, l] = F[k, l]
            for k in range(2):
                M[i, k, 0] = V[i] * (P[k, 0] * Ainv[i, 0, 0] + P[k, 1] * Ainv[i, 1, 0])
                M[i, k, 1] = V[i] * (P[k, 0] * Ainv[i, 0, 1] + P[k, 1] * Ainv[i, 1, 1])


@njit(inline="always", **JIT)
def _force_row(i, x, indptr, indices, X_ij, w, M, F_all, cs, stab):
    """f_i = Σ_j w_ij (M_i + M_j) X_ij (eq. 7) plus, where ``stab`` and cs ≠ 0, the stabilisation
    force."""
    fx = 0.0
    fy = 0.0
    mi00 = M[i, 0, 0]
    mi01 = M[i, 0, 1]
    mi10 = M[i, 1, 0]
    mi11 = M[i, 1, 1]
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        wij = w[p]
        X0 = X_ij[p, 0]
        X1 = X_ij[p, 1]
        fx += wij * ((mi00 + M[j, 0, 0]) * X0 + (mi01 + M[j, 0, 1]) * X1)
        fy += wij * ((mi10 + M[j, 1, 0]) * X0 + (mi11 + M[j, 1, 1]) * X1)
        if stab and (cs[i] != 0.0 or cs[j] != 0.0):
            x0 = x[j, 0] - x[i, 0]
            x1 = x[j, 1] - x[i, 1]
            di0 = x0 - (F_all[i, 0, 0] * X0 + F_all[i, 0, 1] * X1)
            di1 = x1 - (F_all[i, 1, 0] * X0 + F_all[i, 1, 1] * X1)
            dj0 = x0 - (F_all[j, 0, 0] * X0 + F_all[j, 0, 1] * X1)
            dj1 = x1 - (F_all[j, 1, 0] * X0 + F_all[j, 1, 1] * X1)
            fx += 2.0 * wij * (cs[i] * di0 + cs[j] * dj0)
            fy += 2.0 * wij * (cs[i] * di1 + cs[j] * dj1)
    return fx, fy


@njit(parallel=True, **JIT)
def internal_force(x, indptr, indices, X_ij, w, M, F_all, cs):
    """Internal forces (N,2), N (per unit thickness): −∂(Σ V ψ + H_s)/∂x."""
    N = x.shape[0]
    f = np.empty((N, 2))
    stab = np.any(cs != 0.0)
    for i in prange(N):
        fx, fy = _force_row(i, x, indptr, indices, X_ij, w, M, F_all, cs, stab)
        f[i, 0] = fx
        f[i, 1] = fy
    return f


@njit(parallel=True, **JIT)
def stabilisation_energy(x, indptr, indices, X_ij, w, F_all, cs):
    """H_s = Σ_i c_i Σ_j w_ij |x_ij − F_i X_ij|², J per unit thickness."""
    N = x.shape[0]
    e = np.zeros(N)
    for i in prange(N):
        if cs[i] == 0.0:
            continue
        s = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            d0 = x[j, 0] - x[i, 0] - (F_all[i, 0, 0] * X_ij[p, 0] + F_all[i, 0, 1] * X_ij[p, 1])
            d1 = x[j, 1] - x[i, 1] - (F_all[i, 1, 0] * X_ij[p, 0] + F_all[i, 1, 1] * X_ij[p, 1])
            s += w[p] * (d0 * d0 + d1 * d1)
        e[i] = cs[i] * s
    return e.sum()


@njit(parallel=True, **JIT)
def _advance(n_steps, euler, x, v, acc, m, a_ext, fixed, v_fix, dt, damping,
             indptr, indices, X_ij, w, Ainv, V, h_old, prm, cs, F_all, M, h_new, status):
    """``n_steps`` steps of eq. 8 (``euler``) or its kick–drift–kick form, in place. Returns the
    number of steps completed (fewer if a material point failed or a position became non-finite)."""
    N = x.shape[0]
    stab = np.any(cs != 0.0)
    for s in range(n_steps):
        if euler:
            for i in prange(N):
                for k in range(2):
                    if fixed[i, k]:
                        v[i, k] = v_fix[i, k]
                    x[i, k] += dt * v[i, k]
        else:
            for i in prange(N):
                kick_drift_row(i, x, v, acc, fixed, v_fix, dt, damping)
        stress_pass(x, indptr, indices, X_ij, w, Ainv, V, h_old, prm, F_all, M, h_new, status)
        bad = 0
        for i in prange(N):
            fx, fy = _force_row(i, x, indptr, indices, X_ij, w, M, F_all, cs, stab)
            acc[i, 0] = fx / m[i] + a_ext[i, 0]
            acc[i, 1] = fy / m[i] + a_ext[i, 1]
            if euler:
                for k in range(2):
                    if fixed[i, k]:
                        v[i, k] = v_fix[i, k]
                    else:
                        v[i, k] = (v[i, k] + dt * acc[i, k]) / (1.0 + damping * dt)
            else:
                kick_row(i, v, acc, fixed, v_fix, dt, damping)
            if status[i] != 0 or not (math.isfinite(acc[i, 0]) and math.isfinite(acc[i, 1])):
                bad += 1
        if bad > 0:
            return s + 1
    return n_steps


# ================================================================================================
# A body and its dynamics
# ================================================================================================

@dataclass
class Model:
    """An HPM body: reference geometry and the constant arrays of the loops.

    X (N,2) m, V (N,) m², m (N,) kg/m, CSR neighbours (indptr, indices) within r_e, per pair X_ij
    (nnz,2) and w (nnz,), Ainv (N,2,2), stabilisation coefficients cs (N,), material ``prm``."""

    X: np.ndarray
    V: np.ndarray
    m: np.ndarray
    dx: float
    re: float
    indptr: np.ndarray
    indices: np.ndarray
    X_ij: np.ndarray
    w: np.ndarray
    Ainv: np.ndarray
    cs: np.ndarray
    prm: np.ndarray
    material: object
    n_singular: int = 0

    @property
    def n(self) -> int:
        return self.X.shape[0]


def build_model(X, V, material, dx: float, re_ratio: float = RE_RATIO, stabilisation: float = 0.0,
          body=None) -> Model:
    """Reference configuration of an HPM body (eq. 5–6). ``body`` (N,) int, optional: particles
    of different bodies never interact through the weights (separate bodies, e.g. two rings)."""
    if not (isinstance(re_ratio, (int, float)) and 1.0 < re_ratio <= 6.0):
        raise ValueError(f"re_ratio: {re_ratio!r} is not allowed; r_e/Δx must lie in (1, 6]")
    if not (isinstance(stabilisation, (int, float)) and 0.0 <= stabilisation <= 10.0):
        raise ValueError(f"stabilisation: {stabilisation!r} is not allowed; must lie in [0, 10]")
    X = np.ascontiguousarray(X, dtype=np.float64)
    V = np.ascontiguousarray(V, dtype=np.float64)
    re = re_ratio * dx
    indptr, indices = neighbour_list(X, re)
    if body is not None:
        indptr, indices = drop_cross_body(indptr, indices, np.asarray(body))
    nnz = len(indices)
    X_ij = np.empty((nnz, 2))
    w = np.empty(nnz)
    Ainv = np.empty((X.shape[0], 2, 2))
    wr2 = np.empty(X.shape[0])
    bad = reference_geometry(X, indptr, indices, re, X_ij, w, Ainv, wr2)
    cs = np.zeros(X.shape[0])
    if stabilisation > 0:
        cs = stabilisation * material.mu * V / np.maximum(wr2, 1e-300)
    return Model(X, V, material.rho * V, dx, re, indptr, indices, X_ij, w, Ainv, cs,
                 material.params(), material, int(bad))


@dataclass
class State:
    """Synchronous state: positions x (N,2), velocities v (N,2), accelerations acc (N,2), time t;
    the last F (N,3,3), M (N,2,2), material status (N,) and history."""

    x: np.ndarray
    v: np.ndarray
    acc: np.ndarray
    t: float
    F: np.ndarray
    M: np.ndarray
    status: np.ndarray
    h: np.ndarray
    h_new: np.ndarray
    steps: int = 0


def forces(model: Model, x: np.ndarray, state: State | None = None) -> np.ndarray:
    """Internal forces (N,2) at positions x (eq. 7 plus the optional stabilisation)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    N = model.n
    F = np.empty((N, 3, 3))
    M = np.empty((N, 2, 2))
    status = np.zeros(N, np.int64)
    nh = model.material.n_history
    h = np.zeros((N, nh)) if state is None else state.h
    h_new = np.zeros((N, nh))
    stress_pass(x, model.indptr, model.indices, model.X_ij, model.w, model.Ainv, model.V, h,
                model.prm, F, M, h_new, status)
    if state is not None:
        state.F[:] = F
        state.M[:] = M
        state.status[:] = status
    return internal_force(x, model.indptr, model.indices, model.X_ij, model.w, M, F, model.cs)


def potential_energy(model: Model, x: np.ndarray) -> float:
    """The potential part of the discrete Hamiltonian, Σ V_i ψ(F_i) + H_s, J per unit thickness."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    N = model.n
    F = np.empty((N, 3, 3))
    M = np.empty((N, 2, 2))
    status = np.zeros(N, np.int64)
    nh = model.material.n_history
    stress_pass(x, model.indptr, model.indices, model.X_ij, model.w, model.Ainv, model.V,
                np.zeros((N, nh)), model.prm, F, M, np.zeros((N, nh)), status)
    e = strain_energy(F, model.V, model.prm)
    if model.cs.any():
        e += stabilisation_energy(x, model.indptr, model.indices, model.X_ij, model.w, F, model.cs)
    return float(e)


def init(model: Model, v0: np.ndarray | None = None, x0: np.ndarray | None = None) -> State:
    """State at t = 0 with the accelerations of the initial configuration."""
    N = model.n
    x = np.array(model.X if x0 is None else x0, dtype=np.float64)
    v = np.zeros((N, 2)) if v0 is None else np.array(v0, dtype=np.float64)
    nh = model.material.n_history
    st = State(x, v, np.zeros((N, 2)), 0.0, np.empty((N, 3, 3)), np.empty((N, 2, 2)),
               np.zeros(N, np.int64), model.material.initial_history(N), np.zeros((N, nh)))
    st.acc[:] = forces(model, x, st) / model.m[:, None]
    return st


def advance(model: Model, st: State, dt: float, n_steps: int, fixed=None, v_fix=None,
            a_ext=None, damping: float = 0.0, scheme: str = "verlet") -> int:
    """Advance ``st`` by ``n_steps`` steps of size dt (s). ``fixed`` (N,2) uint8 dofs follow
    ``v_fix``; ``a_ext`` (N,2) m/s² external acceleration. Returns the steps completed."""
    if scheme not in ("verlet", "euler"):
        raise ValueError(f"scheme: {scheme!r} is not one of 'verlet', 'euler'")
    N = model.n
    fixed = np.zeros((N, 2), np.uint8) if fixed is None else fixed
    v_fix = np.zeros((N, 2)) if v_fix is None else v_fix
    a_ext = np.zeros((N, 2)) if a_ext is None else a_ext
    done = _advance(n_steps, scheme == "euler", st.x, st.v, st.acc, model.m, a_ext, fixed, v_fix,
                    dt, damping, model.indptr, model.indices, model.X_ij, model.w, model.Ainv,
                    model.V, st.h, model.prm, model.cs, st.F, st.M, st.h_new, st.status)
    if model.material.n_history:
        st.h[:] = st.h_new
    st.t += done * dt
    st.steps += done
    return done


def energies(model: Model, st: State) -> tuple[float, float]:
    """(kinetic, potential) energy of the state, J per unit thickness."""
    ke = 0.5 * float(np.sum(model.m[:, None] * st.v * st.v))
    return ke, potential_energy(model, st.x)


def time_step(model: Model, dt_factor: float) -> float:
    """dt = dt_factor · Δx / c_p (shared CFL estimate; c_p the P-wave speed, plane strain)."""
    return cfl_time_step(model.dx, model.material.wave_speed("strain"), dt_factor)


# ================================================================================================
# The method's body for the driver
# ================================================================================================

def wls_discretisation(model: Model):
    """The HPM body as a :class:`sph.total_lagrangian.Discretisation`: eq. 4 is
    F_i = Σ_j (x_j − x_i) ⊗ G_ij with G_ij = w_ij A_i⁻¹ X_ij (A_i symmetric), and the force of
    eq. 7 is −∂(Σ V ψ)/∂x — the gradient form of CSPH's eq. 35, so the static Newton and the modal
    solve (tangent K = ∂²Π/∂x∂x) apply unchanged. Without the stabilisation potential only."""
    from .correction import reverse_gradients
    from .total_lagrangian import Discretisation

    rows = np.repeat(np.arange(model.n), np.diff(model.indptr))
    G = model.w[:, None] * np.einsum("pkl,pl->pk", model.Ainv[rows], model.X_ij)
    GT = reverse_gradients(model.indptr, model.indices, G)
    N = model.n
    return Discretisation(model.X, model.V, model.m, model.re, "wls", model.indptr,
                          model.indices, G, GT, np.broadcast_to(np.eye(2), (N, 2, 2)).copy(),
                          np.ones(N, bool))


NAME = "hpm"
OPTIONS = dict(re_ratio=f"r_e/Δx (default {RE_RATIO})",
               stabilisation="zero-energy-mode stabilisation α in [0, 10] (default 0)",
               scheme="'verlet' (default) | 'euler' (eq. 8 literally)")


class HPM(ParticleBody):
    """An HPM body built from :class:`sph.particles.Particles` (2-D, one material)."""

    name = NAME

    def __init__(self, particles, re_ratio: float = RE_RATIO, stabilisation: float = 0.0,
                 scheme: str = "verlet"):
        super().__init__(particles)
        ps = particles
        if ps.dim != 2 or ps.plane == "stress":
            raise ValueError("hpm: plane strain (2-D) only in this version; the model is "
                             f"{ps.dim}-D{' plane stress' if ps.plane == 'stress' else ''}")
        if len(ps.table) != 1:
            raise ValueError("hpm: one material per body in this version (the model has "
                             f"{len(ps.table)})")
        if scheme not in ("verlet", "euler"):
            raise ValueError(f"scheme: {scheme!r} is not one of 'verlet', 'euler'")
        self.scheme = scheme
        self.stabilisation = float(stabilisation)
        self.model = build_model(ps.X, ps.V, ps.table[0], ps.dx, re_ratio, stabilisation,
                           body=ps.body if len(ps.body_names) > 1 else None)
        self.m = self.model.m
        self.st = init(self.model)
        self.x, self.v, self.acc = self.st.x, self.st.v, self.st.acc

    def start(self, v0, f_ext, extra=None) -> None:
        super().start(v0, f_ext, extra)

    def internal_force(self, x):
        return forces(self.model, x, self.st)

    def commit(self) -> None:
        if self.model.material.n_history:
            self.st.h[:] = self.st.h_new

    def failed(self) -> bool:
        return bool(self.st.status.any())

    def advance(self, n, dt, f_ext, fixed, v_fix, damping=0.0, extra=None) -> int:
        if extra is not None:
            return super().advance(n, dt, f_ext, fixed, v_fix, damping, extra)
        self.st.t, self.st.steps = self.t, self.steps
        done = advance(self.model, self.st, dt, n, fixed=fixed, v_fix=v_fix,
                       a_ext=f_ext / self.m[:, None], damping=damping, scheme=self.scheme)
        self.t, self.steps = self.st.t, self.st.steps
        return done

    def stored_energy(self) -> float:
        return potential_energy(self.model, self.x)

    def gradient_form(self):
        from .total_lagrangian import Body

        if self.stabilisation != 0.0:
            return None
        return Body(wls_discretisation(self.model), self.particles.table, self.particles.mat_id)

    def field_state(self) -> dict:
        return dict(t=self.t, x=self.x, v=self.v, F=self.st.F, history=self.st.h,
                    mat_id=self.particles.mat_id, region=self.particles.region)


def build(particles, **options) -> HPM:
    """An HPM body of ``particles`` (:func:`sph.particles.discretise`); options: ``OPTIONS``."""
    return HPM(particles, **options)
