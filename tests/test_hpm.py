"""Hamiltonian particle method (sph.hpm, 004 §II): the force is the exact derivative of the discrete
Hamiltonian, momentum is conserved, F is exact for affine motions, and the plate gates of issue 5."""
import math

import numpy as np
import pytest

import dataclasses
from types import SimpleNamespace

from sph import driver, hpm, particles
from workbench.materials import RING_RUBBER, RUBBER
from workbench.scenes import Plate

# Central finite differences with step 1e-6 Δx: truncation ~ (1e-6)² relative, round-off
# ~ 1e-16 E / (1e-6 Δx f) ~ 1e-9 relative; observed ~1e-8. 1e-6 leaves margin yet catches any
# missing or mis-signed term (those are O(1)).
TOL_FD = 1e-6
# Σ f and Σ x × f vanish by construction: round-off only, relative to the largest force.
TOL_MOMENTUM = 1e-12
# Issue 5: the HPM plate period within 3 % of the FEM modal period at H/Δx = 10 (004's model is
# 2.7 % from thin-plate theory, i.e. ~2.2 % from the FEM).
TOL_PLATE_PERIOD = 0.03
# Issue 5: energy drift over two periods below 0.1 % (a symplectic scheme at dt_factor 0.3: the
# energy error oscillates at O((ω dt)²) ~ 1e-7 and does not drift).
TOL_PLATE_DRIFT = 1e-3


def block(size, n, mode):
    """Lattice particles of the box [0, size] with n cells along its first edge."""
    dx = size[0] / n
    X, V = particles.box((0.0,) * len(size), size, dx, mode)
    return SimpleNamespace(X=X, V=V, dx=dx)


def _deformed(ps, seed=0, jitter=0.1):
    rng = np.random.default_rng(seed)
    Fm = np.array([[1.1, 0.2], [-0.1, 0.95]])
    return ps.X @ Fm.T + jitter * ps.dx * rng.standard_normal(ps.X.shape)


@pytest.mark.parametrize("material", [RUBBER, RING_RUBBER], ids=["svk", "mooney_rivlin"])
@pytest.mark.parametrize("stab", [0.0, 0.5], ids=["plain", "stabilised"])
def test_force_is_minus_gradient_of_hamiltonian(material, stab):
    ps = block((0.008, 0.006), 4, mode="cell")
    model = hpm.build_model(ps.X, ps.V, material, ps.dx, 2.5, stab)
    x = _deformed(ps)
    f = hpm.forces(model, x)
    h = 1e-6 * ps.dx
    fd = np.zeros_like(f)
    for i in range(len(x)):
        for k in range(2):
            xp = x.copy()
            xp[i, k] += h
            xm = x.copy()
            xm[i, k] -= h
            fd[i, k] = -(hpm.potential_energy(model, xp) - hpm.potential_energy(model, xm)) / (2 * h)
    err = np.abs(f - fd).max() / np.abs(f).max()
    assert err < TOL_FD, f"force vs -dH/dx: relative error {err:.3g}"


@pytest.mark.parametrize("stab", [0.0, 0.5])
def test_momentum_conserved_by_the_forces(stab):
    ps = block((0.02, 0.01), 10, mode="node")
    model = hpm.build_model(ps.X, ps.V, RUBBER, ps.dx, 2.1, stab)
    x = _deformed(ps, seed=1)
    f = hpm.forces(model, x)
    scale = np.abs(f).max()
    assert np.abs(f.sum(0)).max() < TOL_MOMENTUM * scale * len(x)
    torque = np.sum(x[:, 0] * f[:, 1] - x[:, 1] * f[:, 0])
    assert abs(torque) < TOL_MOMENTUM * scale * len(x) * 0.02


def test_deformation_gradient_exact_for_affine_motion():
    ps = block((0.01, 0.01), 6, mode="node")
    rng = np.random.default_rng(3)
    X = ps.X + 0.2 * ps.dx * rng.standard_normal(ps.X.shape)
    model = hpm.build_model(X, ps.V, RUBBER, ps.dx, 2.1)
    Fm = np.array([[1.3, -0.4], [0.25, 0.8]])
    st = hpm.init(model, x0=X @ Fm.T + 0.01)
    assert np.abs(st.F[:, :2, :2] - Fm).max() < 1e-12
    assert np.all(st.F[:, 2, 2] == 1.0)


def test_free_body_conserves_momentum_and_energy():
    ps = block((0.02, 0.01), 8, mode="node")
    model = hpm.build_model(ps.X, ps.V, RUBBER, ps.dx, 2.1, 0.0)
    rng = np.random.default_rng(4)
    v0 = 0.5 * rng.standard_normal(ps.X.shape)
    st = hpm.init(model, v0)
    p0 = model.m @ st.v
    L0 = np.sum(model.m * (st.x[:, 0] * st.v[:, 1] - st.x[:, 1] * st.v[:, 0]))
    e0 = sum(hpm.energies(model, st))
    dt = hpm.time_step(model, 0.3)
    assert hpm.advance(model, st, dt, 2000) == 2000
    p1 = model.m @ st.v
    L1 = np.sum(model.m * (st.x[:, 0] * st.v[:, 1] - st.x[:, 1] * st.v[:, 0]))
    e1 = sum(hpm.energies(model, st))
    pscale = np.sum(model.m * np.abs(v0).max())
    assert np.abs(p1 - p0).max() < 1e-12 * pscale
    assert abs(L1 - L0) < 1e-10 * pscale * 0.02
    # symplectic: bounded energy error O((c dt/dx)^2 ...) — 1 % is loose for dt_factor 0.3
    assert abs(e1 - e0) / e0 < 1e-2, f"energy error {(e1 - e0) / e0:.3g}"


def test_pure_bending_energy_node_lattice():
    """The WLS gradient is first order at a free surface; on the node lattice the pure-bending
    energy at H/Δx = 10, r_e = 2.1Δx is within 2 % (measured 1.4 %); on the cell lattice it is
    7 % low (which is why the plate uses the node lattice)."""
    mat = RUBBER
    k = 1e-3
    nu_p = mat.nu / (1 - mat.nu)
    Ep = mat.E / (1 - mat.nu ** 2)
    exact = 0.5 * Ep * k ** 2 * 0.02 ** 3 / 12 * 0.2
    errs = {}
    for mode in ("node", "cell"):
        ps = block((0.2, 0.02), 100, mode=mode)
        X = ps.X - np.array([0.0, 0.01])
        u = np.stack([-k * X[:, 0] * X[:, 1], 0.5 * k * X[:, 0] ** 2 + 0.5 * nu_p * k * X[:, 1] ** 2], 1)
        model = hpm.build_model(X, ps.V, mat, ps.dx, 2.1)
        errs[mode] = hpm.potential_energy(model, X + u) / exact - 1
    assert abs(errs["node"]) < 0.02, errs
    assert errs["cell"] < -0.05, errs  # the known surface error must show on the cell lattice


def test_invalid_dt_factor_names_the_parameter():
    from workbench.scenes import with_overrides

    for bad in ("0.0", "-1.0", "nan"):
        with pytest.raises(ValueError, match="dt_factor"):
            with_overrides(Plate(), {"dt_factor": bad})


def test_blow_up_is_a_status_not_an_exception():
    out = driver.solve("hpm", Plate(periods=0.05, dt_factor=4.0), 4)
    assert out["status"].startswith("unstable:") and "t=" in out["status"]
    assert math.isnan(out["period"])


# The plate at H/Δx = 10 (period within TOL_PLATE_PERIOD of the FEM's modal period, amplitude within
# 5 % of the FEM's dynamic run, energy drift below TOL_PLATE_DRIFT) is a gate of the plate study that
# `workbench verify --quick` applies to the same run; tests/test_verify.py fails on any failed gate.


def test_cantilever_small_load_against_timoshenko():
    """The static tip deflection of 004 E at the paper's load and spacing (H/Δx = 10), by the
    default static Newton. Tolerance 6 %: the WLS surface error softens bending by ~1.4 % (see
    test_pure_bending_energy_node_lattice), and the 2-D clamp and shear add a few per cent to the
    Timoshenko beam (measured: +3.4 %)."""
    from workbench import analytic
    from workbench.scenes import Cantilever

    sc = Cantilever(loads=(0.00192,))
    out = driver.solve("hpm", sc, 10)
    assert out["status"] == ["ok"], out["status"]
    ref = analytic.cantilever_tip(sc, 0.00192)
    err = abs(out["tip_deflection"][0] - ref) / ref
    assert err < 0.06, f"tip {out['tip_deflection'][0]:.4g} m vs Timoshenko {ref:.4g} m: {err:.2%}"


def test_wls_discretisation_gives_the_hpm_force():
    """HPM's F (eq. 4) and force (eq. 7) are CSPH's eq. 35 and −∂Π/∂x with the gradient
    G_ij = w_ij A_i⁻¹ X_ij: the CSPH body built on it must give HPM's force to round-off at an
    arbitrary deformed state (this is what lets HPM use CSPH's static Newton); both return the
    force on the particles, −∂Π/∂x."""
    from sph import total_lagrangian
    from workbench.scenes import Cantilever

    sc = Cantilever()
    ps = particles.discretise(sc.model(sc.H / 4), 4, "node")
    m = hpm.build_model(ps.X, ps.V, sc.material, ps.dx)
    rng = np.random.default_rng(0)
    x = ps.X + 1e-3 * rng.standard_normal(ps.X.shape)
    x[:, 1] += 0.05 * ps.X[:, 0] ** 2
    f_hpm = hpm.forces(m, x)
    f_csph = total_lagrangian.Body(hpm.wls_discretisation(m), sc.material).evaluate(np.ascontiguousarray(x))
    assert np.abs(f_hpm - f_csph).max() < 1e-12 * np.abs(f_hpm).max()


def test_static_newton_agrees_with_dynamic_relaxation():
    """The two static paths of the driver reach the same equilibrium of the HPM body: Newton to
    1e-8 of the load or reaction, dynamic relaxation stopped at a residual of 1e-4 of the load —
    agreement to 1e-3 covers the DR stopping error. (The stabilised body has no gradient form: its
    static drive is sph.relaxation's, tested with classic SPH in tests/test_scene_methods.py.)"""
    from workbench.scenes import Cantilever

    sc = Cantilever(loads=(1.0,))
    newton = driver.solve("hpm", sc, 3)
    dr = driver.solve("hpm", sc, 3, static="dr")
    assert newton["status"] == ["ok"] and dr["status"] == ["ok"]
    assert np.allclose(newton["tip_deflection"], dr["tip_deflection"], rtol=1e-3)


def test_plane_stress_is_refused_naming_the_parameter():
    """HPM's 2-D F has F33 = 1 (plane strain); a plane-stress model is refused, 3-D is built."""
    ps = block((0.01, 0.005), 4, mode="node")
    with pytest.raises(ValueError, match="plane"):
        hpm.build(particles.of_arrays(ps.X, ps.V, ps.dx, RUBBER, plane="stress"))
    X, V = particles.box((0, 0, 0), (0.01, 0.005, 0.005), 0.0025, "node")
    assert hpm.build(particles.of_arrays(X, V, 0.0025, RUBBER, plane=None)).dim == 3
