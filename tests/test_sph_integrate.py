"""The shared velocity-Verlet integrator: second-order accurate and energy-conserving on a
harmonic chain, fixed DOFs held, damping dissipates; the CFL step guard."""
import numpy as np
import pytest

from sph.integrate import cfl_time_step, velocity_verlet


def chain(n=6, k=100.0):
    def accel(x):
        a = np.zeros_like(x)
        s = np.diff(x[:, 0]) - 1.0
        a[:-1, 0] += k * s
        a[1:, 0] -= k * s
        return a
    x = np.c_[np.arange(n, dtype=float), np.zeros(n)]
    return x, accel


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
