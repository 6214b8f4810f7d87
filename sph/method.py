"""The interface every particle method gives the driver (:mod:`sph.driver`), over plain state.

A method is a module with ``NAME``, a ``build(particles, **options) -> ParticleBody`` and a short
``OPTIONS`` description; its body holds the reference data and the state — positions ``x``,
velocities ``v``, accelerations ``acc`` (N, d), time ``t``, ``steps`` — in numpy arrays, so that
another back end (a GPU) can implement the same step over the same state. What a body provides:

- :meth:`ParticleBody.time_step` — the CFL step for a time-step factor;
- :meth:`ParticleBody.start` — the initial state (velocities, the loads of t = 0);
- :meth:`ParticleBody.advance` — ``n`` explicit steps with dead forces ``f_ext`` and prescribed
  velocities ``v_fix`` on the ``fixed`` DOFs, in the method's fused compiled loop;
- :meth:`ParticleBody.internal_force` — the internal force at positions x (the generic path used
  with contact, where other forces join each step);
- :meth:`ParticleBody.energies` — kinetic and stored energy;
- :meth:`ParticleBody.gradient_form` — for methods whose F is Σ_b (x_b − x_a) ⊗ G_ab and whose
  force is −∂Π/∂x (csph, hpm): the :class:`sph.total_lagrangian.Body` on which the static Newton
  and the modal solve work; None otherwise (classic SPH: the static drive then relaxes the body
  dynamically through :meth:`advance`, :mod:`sph.relaxation`);
- :meth:`ParticleBody.field_state` — the state a field snapshot writes.

Adding a method: one module implementing this, and one line in :data:`sph.METHODS`.
"""
from __future__ import annotations

import numpy as np

from .integrate import cfl_time_step


class ParticleBody:
    """Base class: the state arrays and the parts every method shares."""

    name = "method"
    impulse_in_loop = False
    """Whether the method's own fused time loop (an override of :meth:`advance`) adds to
    :attr:`impulse`; the generic loop always does. Where neither does, the driver samples the force
    on the fixed DOFs at the end of each chunk instead."""
    normals = None
    """The boundary area vectors (N, d) the method's surface loads must use (an integration-
    consistent method: those it enforced), or None: the particles' own."""

    def __init__(self, particles):
        self.particles = particles
        self.X = particles.X
        self.x = particles.X.copy()
        self.v = np.zeros_like(self.x)
        self.acc = np.zeros_like(self.x)
        self.m = particles.m
        self.t = 0.0
        self.steps = 0
        self.impulse = np.zeros_like(self.x)
        """(N, d): the impulse Σ ½ (f_n + f_n+1) dt of the force (internal plus dead) on each
        fixed DOF, added by :meth:`advance` (the driver zeroes it; the reactions and the work of
        prescribed motion follow from it)."""

    @property
    def n(self) -> int:
        return self.X.shape[0]

    @property
    def dim(self) -> int:
        return self.X.shape[1]

    def wave_speed(self) -> float:
        """Fastest small-strain elastic wave speed of the body's materials, m/s."""
        return self.particles.table.wave_speed("strain")

    def time_step(self, dt_factor: float) -> float:
        """dt = dt_factor · Δx / c_p (the shared CFL estimate), s."""
        return cfl_time_step(self.particles.dx, self.wave_speed(), dt_factor)

    def start(self, v0: np.ndarray, f_ext: np.ndarray, extra=None) -> None:
        """Initial velocities and the accelerations of the reference state under ``f_ext`` (and
        the ``extra`` force, e.g. contact)."""
        self.v[:] = v0
        f = self.internal_force(self.x) + f_ext
        if extra is not None:
            f = f + extra(self.x)
        self.acc[:] = f / self.m[:, None]

    def advance(self, n: int, dt: float, f_ext, fixed, v_fix, damping: float = 0.0,
                extra=None) -> int:
        """``n`` velocity-Verlet steps (:mod:`sph.integrate`) under the dead forces ``f_ext``
        (N, d), the ``fixed`` DOFs (N, d) following ``v_fix``, mass-proportional ``damping`` and an
        optional ``extra(x) -> (N, d)`` force (contact); the impulse on the fixed DOFs is added to
        :attr:`impulse`. Returns the steps completed (fewer when a
        material point failed or the state became non-finite). This generic loop calls
        :meth:`internal_force` per step; methods override it with their fused loop for the case
        without ``extra``."""
        from .integrate import kick, kick_drift

        fx = fixed.astype(bool)
        for s in range(n):
            kick_drift(self.x, self.v, self.acc, fixed, v_fix, dt, damping)
            f_old = self.acc * self.m[:, None]
            f = self.internal_force(self.x) + f_ext
            if extra is not None:
                f = f + extra(self.x)
            if self.impulse is not None:
                self.impulse[fx] += 0.5 * dt * (f_old + f)[fx]
            self.acc[:] = f / self.m[:, None]
            kick(self.v, self.acc, fixed, v_fix, dt, damping)
            self.commit()
            self.t += dt
            self.steps += 1
            if self.failed() or not np.isfinite(self.acc).all():
                return s + 1
        return n

    def internal_force(self, x: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def commit(self) -> None:
        """Accept the history of the last :meth:`internal_force` (the generic step)."""

    def stored_energy(self) -> float:  # pragma: no cover
        raise NotImplementedError

    def energies(self) -> tuple[float, float]:
        """(kinetic, stored) energy, J (J/m in 2-D)."""
        ke = 0.5 * float(np.einsum("a,ak,ak->", self.m, self.v, self.v))
        return ke, self.stored_energy()

    def dissipated(self) -> dict:
        """Energies that left the stored energy for good, J (J/m in 2-D), by name: for J2
        materials ``plastic_work`` Σ V W_p and ``released_energy`` Σ V W_rel (the history columns
        of :mod:`workbench.materials.layout`), so that external work = kinetic + stored + these.
        None by default (a method whose materials keep no such history)."""
        return {}

    def components(self):
        """(N,) int labels of the connected parts of the body — particles joined by the pairs
        through which tension can pass — or None where the method does not say (the default)."""
        return None

    def failed(self) -> bool:
        """Whether a material point failed in the last step (J ≤ 0, no return mapping)."""
        return False

    def diagnostics(self) -> dict:
        """Method-specific scalars recorded beside the energies of an explicit run (e.g. csph's
        spurious-mode measure); none by default."""
        return {}

    def gradient_form(self):
        return None

    def field_state(self) -> dict:  # pragma: no cover
        raise NotImplementedError
