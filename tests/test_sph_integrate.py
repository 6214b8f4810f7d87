"""The shared velocity-Verlet integrator (the generic step of sph.method.ParticleBody, built on
the rows of sph.integrate): second-order accurate and energy-conserving on a harmonic chain,
fixed DOFs held, damping dissipates; the CFL step guard."""
from types import SimpleNamespace

import numpy as np
import pytest

from sph.integrate import cfl_time_step
from sph.method import ParticleBody


class Chain(ParticleBody):
    """Unit masses on a line joined by springs of stiffness k and rest length 1."""

    def __init__(self, n, k):
        X = np.c_[np.arange(n, dtype=float), np.zeros(n)]
        super().__init__(SimpleNamespace(X=X, m=np.ones(n)))
        self.k = k

    def internal_force(self, x):
        f = np.zeros_like(x)
        s = np.diff(x[:, 0]) - 1.0
        f[:-1, 0] += self.k * s
        f[1:, 0] -= self.k * s
        return f


def velocity_verlet(x, v, acc, accel, dt, n, fixed=None, damping=0.0, callback=None):
    """n steps of the generic velocity Verlet on the chain whose state is (x, v, acc)."""
    b = accel.body
    b.x, b.v, b.acc = x, v, acc
    fixed = np.zeros_like(x, dtype=np.uint8) if fixed is None else fixed
    zero = np.zeros_like(x)
    for s in range(n):
        assert b.advance(1, dt, zero, fixed, zero, damping) == 1
        if callback is not None:
            callback(s, b.x, b.v, b.acc)


def chain(n=6, k=100.0):
    body = Chain(n, k)

    def accel(x):
        return body.internal_force(x) / body.m[:, None]
    accel.body = body
    return body.X.copy(), accel


def energy(x, v, k=100.0):
    return 0.5 * np.sum(v * v) + 0.5 * k * np.sum((np.diff(x[:, 0]) - 1.0) ** 2)


@pytest.mark.parametrize("damping", [0.0, 2.0])
def test_chain_energy_and_fixed_dofs(damping):
    x, accel = chain()
    v = np.zeros_like(x)
    v[-1, 0] = 1.0
    fixed = np.zeros_like(x, dtype=np.uint8)
    fixed[0, :] = 1
    acc = accel(x)
    e0 = energy(x, v)
    es = []
    velocity_verlet(x, v, acc, accel, 0.01, 3000, fixed=fixed, damping=damping,
                    callback=lambda s, x_, v_, a_: es.append(energy(x_, v_)) and False)
    assert x[0, 0] == 0.0 and v[0, 0] == 0.0  # the clamp holds
    if damping == 0.0:
        assert max(abs(e / e0 - 1) for e in es) < 1e-2  # bounded O(dt²) oscillation, no drift
    else:
        assert es[-1] < 1e-3 * e0


def test_second_order():
    errs = []
    for dt in (0.02, 0.01):
        x, accel = chain(n=2)
        v = np.zeros_like(x)
        x[1, 0] += 0.1
        velocity_verlet(x, v, accel(x), accel, dt, int(round(1.0 / dt)))
        w = np.sqrt(200.0)
        exact = 1.0 + 0.1 * np.cos(w * 1.0)  # the separation oscillates about its rest length
        errs.append(abs(x[1, 0] - x[0, 0] - exact))
    assert 3.0 < errs[0] / errs[1] < 5.0, errs


def test_cfl():
    assert cfl_time_step(0.01, 100.0, 0.5) == pytest.approx(5e-5)
    with pytest.raises(ValueError, match="dt_factor"):
        cfl_time_step(0.01, 100.0, 0)
