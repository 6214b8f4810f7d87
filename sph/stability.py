"""Drivers of the stability scenes (:mod:`workbench.stability_scenes`: Ring, Slab, Rings) for the
Hamiltonian particle method (:mod:`sph.hpm`, Lagrangian kernel), corrected SPH (:mod:`sph.csph`,
total-Lagrangian corrected kernel gradient, its discretisation and fused Verlet loop) and classic
SPH (:mod:`sph.classic`, Eulerian kernel), with the instability criteria of ``stability.nc``. All
three share the particle generation, the contact of :mod:`sph.contact` and the criteria below.

A run is **unstable** when any of these is seen (the first one met ends it, its status says which):

* ``non-finite``: a NaN/inf position or acceleration, or a material point that failed (J ≤ 0);
* ``energy``: the energy balance E(t) − E(0) − W_ext(t) (kinetic + stored + contact energy minus the
  work of dead loads) *grows* by more than ``ENERGY_TOL`` of the largest energy seen, or is not
  finite (not used for the slab, whose kinematic drive does unmeasured work). The criterion is
  one-sided: a loss of energy (artificial viscosity, damping) is dissipation, not a blow-up. It is
  recorded as ``dissipated`` = max(0, −(balance change)/largest energy) and, above ``ENERGY_TOL``,
  as a ``note`` beside the status 'ok';
* ``disorder``: the particle disorder η₉₅ exceeds ``DISORDER_TOL``. η_i is the non-affine part of
  the motion around particle i relative to the local affine map of the WLS fit (eq. 4 of 004, the
  reference neighbours within r_e = 2.1Δx): η_i² = Σ_j w_ij |x_ij − F_i X_ij|² / Σ_j w_ij |F_i X_ij|²;
  η₉₅ is its 95th percentile over the particles (in the slab, over the particles more than
  2r_e from the driven strips: the strain jump at a strip edge is a boundary artefact, not disorder). A smooth deformation gives η = O((Δx/R)²) (≲ 1e-2
  in these scenes); clumping and particle-scale zig-zag (zero-energy modes) give η = O(0.1–1).

``min_spacing`` (the smallest current distance between particles over Δx) is reported beside it.
"""
from __future__ import annotations

import math
import time

import numpy as np
from numba import njit, prange

from . import hpm
from .contact import contact_forces
from .diagnostics import energy_change
from .integrate import cfl_time_step, check_dt_factor, velocity_verlet
from .kernels import JIT
from .neighbours import neighbour_list

ENERGY_TOL = 0.5
DISORDER_TOL = 0.15
METHODS = ("hpm", "sph", "csph")
CSPH_H_RATIO = 1.3
"""h/Δx of csph in these scenes (support 2.6Δx: enough neighbours for the gradient correction on
the ring's concentric circles)."""


def is_stability_scene(scene) -> bool:
    from workbench.stability_scenes import STABILITY_SCENES

    return isinstance(scene, tuple(STABILITY_SCENES.values()))


# ------------------------------------------------------------------------------------------------
# Particles
# ------------------------------------------------------------------------------------------------

def ring_particles(R_in: float, R_out: float, n_layers: int, centre=(0.0, 0.0)):
    """Particles on ``n_layers`` concentric circles (004's cylindrical arrangement): positions
    (N,2), volumes (N,) m², spacing Δr, and the index of the innermost layer."""
    if not (isinstance(n_layers, (int, np.integer)) and n_layers >= 2):
        raise ValueError(f"resolution: {n_layers!r} is not allowed; particle layers across the ring wall, an integer >= 2")
    dr = (R_out - R_in) / n_layers
    X, V, inner = [], [], []
    for k in range(n_layers):
        r = R_in + (k + 0.5) * dr
        n = max(6, int(round(2 * math.pi * r / dr)))
        th = 2 * math.pi * (np.arange(n) + 0.5 * (k % 2)) / n
        if k == 0:
            inner = np.arange(n)
        X.append(np.stack([centre[0] + r * np.cos(th), centre[1] + r * np.sin(th)], 1))
        V.append(np.full(n, 2 * math.pi * r * dr / n))
    return np.concatenate(X), np.concatenate(V), dr, inner


# ------------------------------------------------------------------------------------------------
# The disorder measure
# ------------------------------------------------------------------------------------------------

@njit(parallel=True, **JIT)
def _disorder(x, indptr, indices, X_ij, w, Ainv):
    N = x.shape[0]
    eta = np.zeros(N)
    for i in prange(N):
        F = np.empty((3, 3))
        hpm._deformation_gradient_row(i, x, indptr, indices, X_ij, w, Ainv, F)
        num = 0.0
        den = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            y0 = F[0, 0] * X_ij[p, 0] + F[0, 1] * X_ij[p, 1]
            y1 = F[1, 0] * X_ij[p, 0] + F[1, 1] * X_ij[p, 1]
            d0 = x[j, 0] - x[i, 0] - y0
            d1 = x[j, 1] - x[i, 1] - y1
            num += w[p] * (d0 * d0 + d1 * d1)
            den += w[p] * (y0 * y0 + y1 * y1)
        eta[i] = math.sqrt(num / den) if den > 0.0 else 0.0
    return eta


class Disorder:
    """η of the module docstring for a particle set with reference positions X (N,2)."""

    def __init__(self, X, V, material, dx, body=None, mask=None):
        self.geo = hpm.build(X, V, material, dx, 2.1, 0.0, body=body)
        self.dx = dx
        self.mask = np.ones(len(X), bool) if mask is None else mask

    def __call__(self, x) -> tuple[float, float]:
        g = self.geo
        eta = _disorder(np.ascontiguousarray(x), g.indptr, g.indices, g.X_ij, g.w, g.Ainv)[self.mask]
        return float(np.percentile(eta, 95)), float(eta.max())

    def min_spacing(self, x) -> float:
        ip, ix = neighbour_list(np.ascontiguousarray(x), 2.0 * self.dx)
        if len(ix) == 0:
            return float("inf")
        rows = np.repeat(np.arange(len(x)), np.diff(ip))
        return float(np.min(np.linalg.norm(x[rows] - x[ix], axis=1)) / self.dx)


# ------------------------------------------------------------------------------------------------
# One run
# ------------------------------------------------------------------------------------------------

class _Sim:
    """A method-agnostic view of one body set: step(dt, n), x, v, m, steps, energy(), status_any.

    hpm and csph without contact run their own fused loops (:func:`sph.hpm.advance`,
    :class:`sph.csph.Dynamics`); with contact both take the shared velocity Verlet of
    :func:`sph.integrate.velocity_verlet` with the method's force plus :func:`contact_forces`.
    Classic SPH adds the contact force through its ``extra_force`` hook."""

    def __init__(self, method, X, V, material, dx, body, fixed, v0, a_ext, contact, dt, options):
        self.method = method
        self.contact = contact  # (rc, k) or None
        self.body = body
        self.a_ext = a_ext
        self.fixed = fixed
        self.v_fix = np.zeros_like(X)
        self.dt = dt
        if method == "hpm":
            self.model = hpm.build(X, V, material, dx, options.get("re_ratio", hpm.RE_RATIO),
                                   options.get("stabilisation", 0.0), body=body)
            self.st = hpm.init(self.model, v0)
            self.m = self.model.m
            self.st.acc[:] = self._acc(self.st.x) if contact is not None else self.st.acc + a_ext
        elif method == "csph":
            from . import csph

            disc = csph.discretise(X, V, material.rho, dx, options.get("h_ratio", CSPH_H_RATIO),
                                   options.get("kernel", "cubic_spline"),
                                   options.get("correction", csph.DEFAULT_CORRECTION), body=body)
            self.cb = csph.Body(disc, material, hourglass=options.get("hourglass", 0.0))
            self.m = disc.m
            self.dyn = csph.Dynamics(self.cb, v0, fixed, dt, f_ext=a_ext * self.m[:, None], v_fix=self.v_fix)
            if contact is not None:
                self.dyn.acc[:] = self._acc(self.dyn.x)
        else:
            from .classic import Body

            b = Body(X, V, material, dx, options.get("h_ratio", 1.3), options.get("stress", "hyperelastic"),
                     options.get("alpha", 1.0), options.get("beta", 1.0),
                     options.get("artificial_stress", 0.0), fixed=fixed, v0=v0, body=body)
            b.a_ext = a_ext
            b.v_fix = self.v_fix
            if contact is not None:
                b.extra_force = lambda bb: contact_forces(bb.x, body, *contact)[0]
            b._accelerations(0.0, kick=False)
            self.b = b
            self.m = b.m

    @property
    def _state(self):
        return {"hpm": getattr(self, "st", None), "csph": getattr(self, "dyn", None),
                "sph": getattr(self, "b", None)}[self.method]

    @property
    def x(self):
        return self._state.x

    @property
    def v(self):
        return self._state.v

    @property
    def steps(self) -> int:
        return self._state.steps

    @property
    def status_any(self) -> bool:
        st = {"hpm": lambda: self.st.status, "csph": lambda: self.cb.status, "sph": lambda: self.b.status}
        return bool(st[self.method]().any())

    def _acc(self, x):
        """Internal + contact + external acceleration at x (the contact path of hpm and csph)."""
        if self.method == "hpm":
            f = hpm.forces(self.model, x, self.st)
        else:
            f = self.cb.evaluate(x)
        f = f + contact_forces(x, self.body, *self.contact)[0]
        return f / self.m[:, None] + self.a_ext

    def step(self, dt, n) -> int:
        if self.method == "sph":
            return self.b.step(dt, n)
        if self.contact is None:
            if self.method == "hpm":
                return hpm.advance(self.model, self.st, dt, n, fixed=self.fixed, v_fix=self.v_fix, a_ext=self.a_ext)
            _, bad = self.dyn.advance(n)
            return n if bad < 0 else bad + 1
        s = self._state

        def check(k, x, v, acc):
            if self.method == "csph":
                self.cb.commit()
            return self.status_any or not np.isfinite(acc).all()

        done = velocity_verlet(s.x, s.v, s.acc, self._acc, dt, n, self.fixed, self.v_fix, callback=check)
        s.t += done * dt
        s.steps += done
        return done

    def energy(self) -> float:
        """Kinetic + stored (+ contact) energy, J per unit thickness."""
        if self.method == "hpm":
            ke, pe = hpm.energies(self.model, self.st)
        elif self.method == "csph":
            ke, pe = self.dyn.energies()
        else:
            ke, pe = self.b.energies()
        ce = contact_forces(self.x, self.body, *self.contact)[1] if self.contact is not None else 0.0
        return ke + pe + ce


def solve(method: str, scene, resolution: int, dt_factor: float | None = None, n_out: int = 100,
          t_end: float | None = None, **options) -> dict:
    """Run ``method`` ('hpm', 'csph' or 'sph') on a stability scene; ``resolution`` = particles across the
    ring wall / slab height. Returns dict(stable (bool), status, criterion, energy_drift,
    note, dissipated, disorder (η₉₅ at the end), disorder_max, min_spacing (end, over Δx), time, disorder_history,
    energy_history, linear_momentum (time, 2), dt, steps, wall_time, n_particles)."""
    from workbench.stability_scenes import Ring, Rings, Slab

    if method not in METHODS:
        raise ValueError(f"method: {method!r} is not one of {METHODS}")
    dt_factor = scene.dt_factor if dt_factor is None else dt_factor
    check_dt_factor(dt_factor)
    mat = scene.material
    contact = None
    drive = None
    dmask = None
    if isinstance(scene, Ring):
        X, V, dx, inner = ring_particles(scene.R_in, scene.R_out, resolution)
        body = np.zeros(len(X), np.int64)
        f_ext = np.zeros_like(X)
        er = X[inner] / np.linalg.norm(X[inner], axis=1)[:, None]
        f_ext[inner] = scene.pressure * 2 * math.pi * scene.R_in / len(inner) * er
        a_ext = f_ext / (mat.rho * V)[:, None]
        fixed = np.zeros(X.shape, np.uint8)
        v0 = np.zeros_like(X)
    elif isinstance(scene, Rings):
        X1, V1, dx, _ = ring_particles(scene.R_in, scene.R_out, resolution, (-(scene.R_out + scene.gap / 2), 0.0))
        X2, V2, _, _ = ring_particles(scene.R_in, scene.R_out, resolution, (scene.R_out + scene.gap / 2, 0.0))
        X, V = np.concatenate([X1, X2]), np.concatenate([V1, V2])
        body = np.concatenate([np.zeros(len(X1), np.int64), np.ones(len(X2), np.int64)])
        v0 = np.zeros_like(X)
        v0[:, 0] = np.where(body == 0, scene.speed, -scene.speed)
        f_ext = np.zeros_like(X)
        a_ext = np.zeros_like(X)
        fixed = np.zeros(X.shape, np.uint8)
        contact = (dx, scene.contact_stiffness * (mat.lam + 2 * mat.mu))
    elif isinstance(scene, Slab):
        from .lattice import grid

        if not (isinstance(resolution, (int, np.integer)) and resolution >= 2):
            raise ValueError(f"resolution: {resolution!r} is not allowed; particles across the slab height, an integer >= 2")
        dx = scene.height / resolution
        X, V = grid((0.0, 0.0), (scene.length, scene.height), dx, "cell")
        body = np.zeros(len(X), np.int64)
        f_ext = np.zeros_like(X)
        a_ext = np.zeros_like(X)
        fixed = np.zeros(X.shape, np.uint8)
        left = X[:, 0] < scene.strip
        right = X[:, 0] > scene.length - scene.strip
        fixed[left | right, 0] = 1
        v0 = np.zeros_like(X)
        sign = np.where(left, -1.0, np.where(right, 1.0, 0.0))
        drive = lambda t: sign * scene.accel * min(t, scene.t_load)  # noqa: E731
        dmask = (X[:, 0] > scene.strip + 4.2 * dx) & (X[:, 0] < scene.length - scene.strip - 4.2 * dx)
    else:
        raise ValueError(f"scene: {type(scene).__name__} is not a stability scene")
    t0w = time.perf_counter()
    dt = cfl_time_step(dx, mat.wave_speed("strain"), dt_factor)
    sim = _Sim(method, X, V, mat, dx, body, fixed, v0, a_ext, contact, dt, options)
    dis = Disorder(X, V, mat, dx, body=body, mask=dmask)
    t_end = scene.t_end if t_end is None else t_end
    n_steps = int(math.ceil(t_end / dt))
    per = max(1, n_steps // n_out)
    if drive is not None:
        per = min(per, 20)  # the kinematic drive is updated between chunks
    m = sim.m

    def balance():
        return sim.energy() - float(np.sum(f_ext * (sim.x - X)))

    e0 = balance()
    times, dh, eh, mom = [0.0], [dis(sim.x)[0]], [e0], [m @ sim.v]
    e_scale = max(abs(e0), 1e-300)
    status, criterion = "ok", "none"
    wall = 0.0
    t = 0.0
    while sim.steps < n_steps:
        k = min(per, n_steps - sim.steps)
        if drive is not None:
            sim.v_fix[:, 0] = drive(t + 0.5 * k * dt)
        tw = time.perf_counter()
        done = sim.step(dt, k)
        wall += time.perf_counter() - tw
        t = sim.steps * dt
        if done < k or not np.isfinite(sim.x).all():
            criterion = "non-finite"
            status = f"unstable: {'material point failed' if sim.status_any else 'non-finite state'} at t={t:.4g} s"
            break
        if len(times) % max(1, n_out // 50) == 0 or sim.steps >= n_steps:
            d95, _ = dis(sim.x)
        else:
            d95 = dh[-1]
        e = balance() if drive is None else float("nan")
        times.append(t)
        dh.append(d95)
        eh.append(e)
        mom.append(m @ sim.v)
        if drive is None:
            e_scale = max(e_scale, abs(sim.energy()))
            grew, change = energy_change(e0, e, e_scale, ENERGY_TOL)
            if grew:
                criterion = "energy"
                status = f"unstable: energy balance grew by {change:+.3g} at t={t:.4g} s"
                break
        if d95 > DISORDER_TOL:
            criterion = "disorder"
            status = f"unstable: particle disorder eta95 = {d95:.3g} > {DISORDER_TOL} at t={t:.4g} s"
            break
    ok_x = np.isfinite(sim.x).all()
    d95, dmax = dis(sim.x) if ok_x else (float("nan"), float("nan"))
    drift = float((eh[-1] - e0) / e_scale) if drive is None else float("nan")
    dissipated = max(0.0, -drift) if math.isfinite(drift) else float("nan")
    note = (f"dissipated {100 * dissipated:.3g} % of the largest energy seen"
            if status == "ok" and dissipated > ENERGY_TOL else "")
    return dict(stable=status == "ok", status=status, criterion=criterion, note=note,
                energy_drift=drift, dissipated=dissipated,
                disorder=d95, disorder_max=dmax, min_spacing=dis.min_spacing(sim.x) if ok_x else float("nan"),
                time=np.asarray(times), disorder_history=np.asarray(dh), energy_history=np.asarray(eh),
                linear_momentum=np.asarray(mom), dt=dt, steps=int(sim.steps), wall_time=wall,
                total_wall_time=time.perf_counter() - t0w, n_particles=int(len(X)), x=sim.x.copy(), X=X)
