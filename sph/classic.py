"""Classic updated-Lagrangian SPH for solids (003 §3.1, eq. 1–4, Fig. 6; Libersky & Petschek 1990;
Gray, Monaghan & Swift 2001), 2-D plane strain: the baseline that shows where uncorrected SPH fails.

Eulerian kernel: the cubic spline of 003 eq. 4 (:mod:`sph.kernels`, support 2h, h = h_ratio·Δx)
evaluated at the *current* positions, with the neighbours rebuilt every step by the shared cell
list (:func:`sph.neighbours.neighbour_list`). One step follows Fig. 6 of 003 in kick–drift–kick
form (shared :mod:`sph.integrate` rows):

1. kick–drift: v ← v + Δt/2 a, x ← x + Δt v;
2. neighbours of the new positions (radius 2h);
3. rates (:func:`rates_pass`): velocity gradient L_i = Σ_j V_j (v_j − v_i) ⊗ ∇_i W_ij (eq. 3,
   V_j = m_j/ρ_j), continuity ρ̇_i = −ρ_i tr L_i, and the stress update —
   ``stress="hypoelastic"`` (default): Hooke's law on the Jaumann rate,
   σ̇ = λ tr(D) I + 2μ D + Ω σ − σ Ω (D, Ω the symmetric and skew parts of L; plane strain: L_zz = 0,
   σ_zz carried); ``stress="hyperelastic"``: Ḟ = L F (F ← (I + Δt L) F) and σ = P Fᵀ/J from the
   shared material library (so that the ring's Mooney–Rivlin law of eq. 12 is the same code as in
   HPM and CSPH); the J2 law of the library works through the same path;
4. forces (:func:`force_pass`): a_i = Σ_j m_j (σ_i/ρ_i² + σ_j/ρ_j² + f_ij^n (R_i + R_j) − Π_ij I) ∇_i W_ij
   + a_ext, with Monaghan's artificial viscosity Π_ij = (−α c̄ μ_ij + β μ_ij²)/ρ̄_ij for
   v_ij·x_ij < 0, μ_ij = h v_ij·x_ij/(r² + 0.01h²), and, optionally (``artificial_stress`` = ε > 0),
   the artificial stress of Gray, Monaghan & Swift (2001): in the principal frame of σ_i,
   R'^a = −ε σ'^a/ρ_i² where σ'^a > 0 (else 0), rotated back; f_ij = W(r_ij)/W(Δx), exponent n = 4;
5. kick: v ← v + Δt/2 a.

Every pair term is antisymmetric (∇_i W_ij = −∇_j W_ji, the bracket symmetric), so linear momentum
is conserved to round-off.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from workbench.materials.kernels import material_point

from .integrate import cfl_time_step, kick_drift, kick_row
from .kernels import JIT, N_CHUNKS, SUPPORT, dw_dr, w as kernel_w
from .method import ParticleBody
from .neighbours import drop_cross_body, neighbour_list

STRESS_LAWS = ("hypoelastic", "hyperelastic")


@njit(parallel=True, **JIT)
def rates_pass(x, v, m, rho, rho_new, sigma, F, indptr, indices, h, dt, lam, mu, hyper, prm, hist,
               hist_new, eps_as, status):
    """Velocity gradient, density, stress (hypoelastic Jaumann or hyperelastic via F) and the
    artificial-stress tensor R of every particle, in place (steps 3 of the module docstring).
    ``sigma`` (N,3,3) Cauchy stress, ``F`` (N,3,3), the new density into ``rho_new`` (``rho`` is
    read by the neighbours, so it is not overwritten), returns R (N,2,2)."""
    N = x.shape[0]
    R = np.zeros((N, 2, 2))
    chunk = (N + N_CHUNKS - 1) // N_CHUNKS
    for c in prange(N_CHUNKS):
        Fn = np.empty((3, 3))
        P = np.empty((3, 3))
        A = np.empty((3, 3, 3, 3))
        for i in range(c * chunk, min(N, (c + 1) * chunk)):
            L00 = 0.0
            L01 = 0.0
            L10 = 0.0
            L11 = 0.0
            for p in range(indptr[i], indptr[i + 1]):
                j = indices[p]
                dx0 = x[i, 0] - x[j, 0]
                dx1 = x[i, 1] - x[j, 1]
                r = math.sqrt(dx0 * dx0 + dx1 * dx1)
                if r <= 0.0:
                    continue
                g = dw_dr(r, h, 0, 2) / r
                Vj = m[j] / rho[j]
                dv0 = v[j, 0] - v[i, 0]
                dv1 = v[j, 1] - v[i, 1]
                L00 += Vj * dv0 * g * dx0
                L01 += Vj * dv0 * g * dx1
                L10 += Vj * dv1 * g * dx0
                L11 += Vj * dv1 * g * dx1
            trD = L00 + L11
            rho_new[i] = rho[i] * (1.0 - dt * trD)
            if hyper:
                for k in range(3):
                    for l in range(3):
                        Fn[k, l] = F[i, k, l]
                for l in range(3):
                    F[i, 0, l] = Fn[0, l] + dt * (L00 * Fn[0, l] + L01 * Fn[1, l])
                    F[i, 1, l] = Fn[1, l] + dt * (L10 * Fn[0, l] + L11 * Fn[1, l])
                for k in range(3):
                    for l in range(3):
                        Fn[k, l] = F[i, k, l]
                status[i] = material_point(Fn, hist[i], prm, P, hist_new[i], A, False)
                J = Fn[0, 0] * (Fn[1, 1] * Fn[2, 2] - Fn[1, 2] * Fn[2, 1]) \
                    - Fn[0, 1] * (Fn[1, 0] * Fn[2, 2] - Fn[1, 2] * Fn[2, 0]) \
                    + Fn[0, 2] * (Fn[1, 0] * Fn[2, 1] - Fn[1, 1] * Fn[2, 0])
                if not J > 0.0:
                    status[i] = 99
                    J = 1.0
                for k in range(3):
                    for l in range(3):
                        s = 0.0
                        for q in range(3):
                            s += P[k, q] * Fn[l, q]
                        sigma[i, k, l] = s / J
            else:
                D01 = 0.5 * (L01 + L10)
                W01 = 0.5 * (L01 - L10)  # Ω = [[0, W01], [−W01, 0]]
                s00 = sigma[i, 0, 0]
                s01 = sigma[i, 0, 1]
                s11 = sigma[i, 1, 1]
                # Ω σ − σ Ω for the in-plane block
                j00 = 2.0 * W01 * s01
                j11 = -2.0 * W01 * s01
                j01 = W01 * (s11 - s00)
                sigma[i, 0, 0] = s00 + dt * (lam * trD + 2.0 * mu * L00 + j00)
                sigma[i, 1, 1] = s11 + dt * (lam * trD + 2.0 * mu * L11 + j11)
                sigma[i, 0, 1] = s01 + dt * (2.0 * mu * D01 + j01)
                sigma[i, 1, 0] = sigma[i, 0, 1]
                sigma[i, 2, 2] = sigma[i, 2, 2] + dt * lam * trD
            if eps_as > 0.0:
                # principal stresses of the in-plane block
                a = sigma[i, 0, 0]
                b = sigma[i, 1, 1]
                s = sigma[i, 0, 1]
                th = 0.5 * math.atan2(2.0 * s, a - b)
                cs = math.cos(th)
                sn = math.sin(th)
                p1 = a * cs * cs + 2.0 * s * cs * sn + b * sn * sn
                p2 = a * sn * sn - 2.0 * s * cs * sn + b * cs * cs
                ri2 = 1.0 / (rho_new[i] * rho_new[i])
                r1 = -eps_as * p1 * ri2 if p1 > 0.0 else 0.0
                r2 = -eps_as * p2 * ri2 if p2 > 0.0 else 0.0
                R[i, 0, 0] = r1 * cs * cs + r2 * sn * sn
                R[i, 1, 1] = r1 * sn * sn + r2 * cs * cs
                R[i, 0, 1] = (r1 - r2) * cs * sn
                R[i, 1, 0] = R[i, 0, 1]
    return R


@njit(inline="always", **JIT)
def _force_row(i, x, v, m, rho, sigma, R, indptr, indices, h, c0, alpha, beta, n_as, w_dx):
    """Acceleration of particle i: Σ_j m_j (σ_i/ρ_i² + σ_j/ρ_j² + f^n (R_i + R_j) − Π_ij) ∇_i W_ij."""
    ax = 0.0
    ay = 0.0
    ri2 = 1.0 / (rho[i] * rho[i])
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        dx0 = x[i, 0] - x[j, 0]
        dx1 = x[i, 1] - x[j, 1]
        r2 = dx0 * dx0 + dx1 * dx1
        r = math.sqrt(r2)
        if r <= 0.0:
            continue
        g = dw_dr(r, h, 0, 2) / r
        gx = g * dx0
        gy = g * dx1
        rj2 = 1.0 / (rho[j] * rho[j])
        t00 = sigma[i, 0, 0] * ri2 + sigma[j, 0, 0] * rj2
        t01 = sigma[i, 0, 1] * ri2 + sigma[j, 0, 1] * rj2
        t10 = sigma[i, 1, 0] * ri2 + sigma[j, 1, 0] * rj2
        t11 = sigma[i, 1, 1] * ri2 + sigma[j, 1, 1] * rj2
        if n_as > 0:
            f = (kernel_w(r, h, 0, 2) / w_dx) ** n_as
            t00 += f * (R[i, 0, 0] + R[j, 0, 0])
            t01 += f * (R[i, 0, 1] + R[j, 0, 1])
            t10 += f * (R[i, 1, 0] + R[j, 1, 0])
            t11 += f * (R[i, 1, 1] + R[j, 1, 1])
        vr = (v[i, 0] - v[j, 0]) * dx0 + (v[i, 1] - v[j, 1]) * dx1
        if vr < 0.0 and (alpha > 0.0 or beta > 0.0):
            mu_ij = h * vr / (r2 + 0.01 * h * h)
            pi_ij = (-alpha * c0 * mu_ij + beta * mu_ij * mu_ij) / (0.5 * (rho[i] + rho[j]))
            t00 -= pi_ij
            t11 -= pi_ij
        ax += m[j] * (t00 * gx + t01 * gy)
        ay += m[j] * (t10 * gx + t11 * gy)
    return ax, ay


@njit(parallel=True, **JIT)
def force_pass(x, v, m, rho, sigma, R, indptr, indices, h, c0, alpha, beta, n_as, w_dx, a_ext,
               acc, fixed, v_fix, dt, damping, do_kick):
    """Accelerations (N,2) into ``acc`` and, with ``do_kick``, the closing half kick (step 4–5).
    The kick is a separate loop: the viscosity reads the neighbours' velocities, which must not be
    kicked while they are read. Returns the number of non-finite accelerations."""
    N = x.shape[0]
    bad = 0
    for i in prange(N):
        ax, ay = _force_row(i, x, v, m, rho, sigma, R, indptr, indices, h, c0, alpha, beta, n_as, w_dx)
        acc[i, 0] = ax + a_ext[i, 0]
        acc[i, 1] = ay + a_ext[i, 1]
        if not (math.isfinite(acc[i, 0]) and math.isfinite(acc[i, 1])):
            bad += 1
    if do_kick:
        for i in prange(N):
            kick_row(i, v, acc, fixed, v_fix, dt, damping)
    return bad


class Body:
    """Particles, material and options of a classic-SPH body; ``step`` advances it (Fig. 6 of 003).

    X (N,2) reference positions, V (N,) volumes (m²), dx spacing; options: ``h_ratio`` (h/Δx),
    ``stress`` ('hypoelastic' | 'hyperelastic'), ``alpha``, ``beta`` (artificial viscosity),
    ``artificial_stress`` (ε of Gray et al., 0 = off), ``n_as`` (exponent, 4)."""

    def __init__(self, X, V, material, dx, h_ratio=1.3, stress="hypoelastic", alpha=1.0, beta=1.0,
                 artificial_stress=0.0, n_as=4, fixed=None, v0=None, body=None):
        if stress not in STRESS_LAWS:
            raise ValueError(f"stress: {stress!r} is not one of {STRESS_LAWS}")
        if not (isinstance(h_ratio, (int, float)) and 0.5 <= h_ratio <= 3.0):
            raise ValueError(f"h_ratio: {h_ratio!r} is not allowed; h/Δx must lie in [0.5, 3]")
        if not (alpha >= 0 and beta >= 0):
            raise ValueError("alpha, beta: artificial-viscosity coefficients must be >= 0")
        if not (0 <= artificial_stress <= 1):
            raise ValueError(f"artificial_stress: {artificial_stress!r} is not allowed; ε must lie in [0, 1]")
        if stress == "hypoelastic" and material.law not in ("svk", "neo_hooke"):
            raise ValueError(f"stress: 'hypoelastic' uses the small-strain λ, μ of an elastic law; "
                             f"law {material.law!r} needs stress='hyperelastic'")
        self.material = material
        self.X = np.ascontiguousarray(X, dtype=np.float64)
        N = self.X.shape[0]
        self.dx = float(dx)
        self.h = h_ratio * dx
        self.rho0 = material.rho
        self.m = material.rho * np.asarray(V, dtype=np.float64)
        self.V0 = np.asarray(V, dtype=np.float64)
        self.hyper = stress == "hyperelastic"
        self.alpha, self.beta = float(alpha), float(beta)
        self.eps_as = float(artificial_stress)
        self.n_as = int(n_as) if artificial_stress > 0 else 0
        self.w_dx = kernel_w(self.dx, self.h, 0, 2)
        self.c0 = material.wave_speed("strain")
        self.prm = material.params()
        self.x = self.X.copy()
        self.v = np.zeros((N, 2)) if v0 is None else np.array(v0, dtype=np.float64)
        self.acc = np.zeros((N, 2))
        self.rho = np.full(N, material.rho)
        self.rho_new = np.full(N, material.rho)
        self.sigma = np.zeros((N, 3, 3))
        self.F = np.tile(np.eye(3), (N, 1, 1))
        self.hist = material.initial_history(N)
        self.hist_new = material.initial_history(N)
        self.status = np.zeros(N, np.int64)
        self.fixed = np.zeros((N, 2), np.uint8) if fixed is None else np.ascontiguousarray(fixed, np.uint8)
        self.v_fix = np.zeros((N, 2))
        self.a_ext = np.zeros((N, 2))
        self.t = 0.0
        self.steps = 0
        self.R = np.zeros((N, 2, 2))
        self.extra_force = None  # callable(body) -> (N,2) forces, e.g. contact between bodies
        self.body = None if body is None else np.asarray(body, dtype=np.int64)
        self._accelerations(0.0, kick=False)

    @property
    def n(self) -> int:
        return self.X.shape[0]

    def _neighbours(self, x):
        """The shared cell list at the current positions; particles of different bodies
        (``body`` labels) do not interact through the kernel (they meet through contact only)."""
        indptr, indices = neighbour_list(x, SUPPORT * self.h)
        if self.body is not None:
            indptr, indices = drop_cross_body(indptr, indices, self.body)
        return indptr, indices

    def _accelerations(self, dt, kick):
        self.indptr, self.indices = self._neighbours(self.x)
        a_ext = self.a_ext
        if self.extra_force is not None:
            a_ext = a_ext + self.extra_force(self) / self.m[:, None]
        return force_pass(self.x, self.v, self.m, self.rho, self.sigma, self.R, self.indptr,
                          self.indices, self.h, self.c0, self.alpha, self.beta, self.n_as,
                          self.w_dx, a_ext, self.acc, self.fixed, self.v_fix, dt, 0.0, kick)

    def step(self, dt: float, n: int = 1) -> int:
        """``n`` steps of size dt; returns the steps completed (fewer if the state became
        non-finite or a material point failed)."""
        lam, mu = self.material.lam, self.material.mu
        for s in range(n):
            kick_drift(self.x, self.v, self.acc, self.fixed, self.v_fix, dt, 0.0)
            self.indptr, self.indices = self._neighbours(self.x)
            self.R = rates_pass(self.x, self.v, self.m, self.rho, self.rho_new, self.sigma, self.F,
                                self.indptr, self.indices, self.h, dt, lam, mu, self.hyper, self.prm,
                                self.hist, self.hist_new, self.eps_as, self.status)
            self.rho, self.rho_new = self.rho_new, self.rho
            if self.material.n_history:
                self.hist, self.hist_new = self.hist_new, self.hist
            a_ext = self.a_ext
            if self.extra_force is not None:
                a_ext = a_ext + self.extra_force(self) / self.m[:, None]
            bad = force_pass(self.x, self.v, self.m, self.rho, self.sigma, self.R, self.indptr,
                             self.indices, self.h, self.c0, self.alpha, self.beta, self.n_as,
                             self.w_dx, a_ext, self.acc, self.fixed, self.v_fix, dt, 0.0, True)
            self.t += dt
            self.steps += 1
            if bad or self.status.any() or not np.isfinite(self.x).all():
                return s + 1
        return n

    def forces(self) -> np.ndarray:
        """Particle forces m a (N,2) of the current state (no external load)."""
        acc = np.zeros_like(self.acc)
        indptr, indices = self._neighbours(self.x)
        force_pass(self.x, self.v, self.m, self.rho, self.sigma, self.R, indptr, indices, self.h,
                   self.c0, self.alpha, self.beta, self.n_as, self.w_dx, np.zeros_like(self.acc),
                   acc, self.fixed, self.v_fix, 0.0, 0.0, False)
        return acc * self.m[:, None]

    def energies(self) -> tuple[float, float]:
        """(kinetic, stored) energy, J per unit thickness. Stored energy: hyperelastic, Σ V0 ψ(F)
        by the shared diagnostics; hypoelastic, the linear-elastic complementary energy
        Σ (m/ρ) ½ σ : C⁻¹ : σ (plane strain, σ_zz included)."""
        ke = 0.5 * float(np.sum(self.m[:, None] * self.v * self.v))
        if self.hyper:
            from .diagnostics import strain_energy

            return ke, strain_energy(np.ascontiguousarray(self.F), self.V0, self.prm)
        E, nu = self.material.E, self.material.nu
        s = self.sigma
        tr = s[:, 0, 0] + s[:, 1, 1] + s[:, 2, 2]
        ss = np.einsum("nij,nij->n", s, s)
        w = ((1 + nu) * ss - nu * tr * tr) / (2 * E)
        return ke, float(np.sum(self.m / self.rho * w))

    def time_step(self, dt_factor: float) -> float:
        return cfl_time_step(self.dx, self.c0, dt_factor)


NAME = "sph"
OPTIONS = dict(h_ratio="h/Δx (default 1.3)", stress="'hypoelastic' (default) | 'hyperelastic'",
               alpha="Monaghan viscosity α (default 1)", beta="Monaghan viscosity β (default 1)",
               artificial_stress="Gray et al.'s ε in [0, 1] (default 0: off)")


class Classic(ParticleBody):
    """A classic-SPH body built from :class:`sph.particles.Particles` (2-D, one material)."""

    name = NAME

    def __init__(self, particles, h_ratio: float = 1.3, stress: str = "hypoelastic",
                 alpha: float = 1.0, beta: float = 1.0, artificial_stress: float = 0.0,
                 n_as: int = 4):
        super().__init__(particles)
        ps = particles
        if ps.dim != 2 or ps.plane == "stress":
            raise ValueError("sph: plane strain (2-D) only in this version; the model is "
                             f"{ps.dim}-D{' plane stress' if ps.plane == 'stress' else ''}")
        if len(ps.table) != 1:
            raise ValueError(f"sph: one material per body in this version (the model has {len(ps.table)})")
        self.b = Body(ps.X, ps.V, ps.table[0], ps.dx, h_ratio, stress, alpha, beta,
                      artificial_stress, n_as, body=ps.body if len(ps.body_names) > 1 else None)
        self.m = self.b.m
        self.x, self.v, self.acc = self.b.x, self.b.v, self.b.acc

    def _set_loads(self, f_ext, fixed=None, v_fix=None, extra=None):
        b = self.b
        b.a_ext = f_ext / self.m[:, None]
        if fixed is not None:
            b.fixed[:] = fixed
            b.v_fix[:] = v_fix
        b.extra_force = None if extra is None else (lambda bb: extra(bb.x))

    def start(self, v0, f_ext, extra=None) -> None:
        self.v[:] = v0
        self._set_loads(f_ext, extra=extra)
        self.b._accelerations(0.0, kick=False)

    def advance(self, n, dt, f_ext, fixed, v_fix, damping=0.0, extra=None) -> int:
        if damping:
            raise ValueError("damping: classic SPH dissipates through its artificial viscosity; "
                             "mass damping is not supported (allowed: 0)")
        self._set_loads(f_ext, fixed, v_fix, extra)
        done = self.b.step(dt, n)
        self.t, self.steps = self.b.t, self.b.steps
        self.x, self.v, self.acc = self.b.x, self.b.v, self.b.acc
        return done

    def energies(self) -> tuple[float, float]:
        return self.b.energies()

    def failed(self) -> bool:
        return bool(self.b.status.any())

    def field_state(self) -> dict:
        b = self.b
        return dict(t=b.t, x=b.x, v=b.v, sigma=b.sigma, history=b.hist, J=b.rho0 / b.rho,
                    mat_id=self.particles.mat_id, region=self.particles.region)


def build(particles, **options) -> Classic:
    """A classic-SPH body of ``particles``; options: ``OPTIONS``."""
    return Classic(particles, **options)
