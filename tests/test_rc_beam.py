"""The reinforced mortar beam of 003 (workbench/scenes/rc_beam.py): bad input, the quarter model's
particles against closed forms, and a short coarse impact through the particle driver (momentum
through the first contact, contact forces equal and opposite, no NaN)."""
import dataclasses
import math

import numpy as np
import pytest

from sph import driver
from sph.contact import contact_forces
from sph.particles import discretise
from workbench.scenes import ParameterError, RCBeam
from workbench.scenes.rc_beam import D10_AREA, bar_lines, staircase


# -- bad input: one line naming the parameter and its range ---------------------------------------
@pytest.mark.parametrize("kw, name", [
    (dict(f_t=0.0), "f_t"), (dict(f_c=-1e6), "f_c"), (dict(f_y=0.0), "f_y"),
    (dict(eps_release=1.0e-4), "eps_release"),  # f_t/E = 1.35e-4: no softening branch
    (dict(velocity=-1.0), "velocity"), (dict(velocity=0.0), "velocity"),
    (dict(structure="frame"), "structure"),
    (dict(spacing=0.025), "spacing"),  # above the 20 mm cover
    (dict(specimen="C"), "specimen"),
])
def test_bad_input(kw, name):
    with pytest.raises(ParameterError) as err:
        RCBeam(**kw)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(name)


def test_spacing_of_a_resolution_above_the_cover_is_refused():
    with pytest.raises(ParameterError, match="^spacing"):
        driver.model_at(RCBeam(), 4)  # 100 mm / 4 = 25 mm > 20 mm cover


def test_specimens():
    a, b = RCBeam(), RCBeam(specimen="B")
    assert (a.span, a.impact_velocity, len(a.stirrup_positions)) == (0.8, 2.2, 4)
    assert (b.span, b.impact_velocity, b.stirrup_positions) == (0.4, 1.4, ())
    assert RCBeam(velocity=3.0).impact_velocity == 3.0


# -- the quarter model at the paper's 5 mm ------------------------------------------------------
@pytest.fixture(scope="module")
def quarter_a():
    s = RCBeam()
    return s, discretise(s.model(), s.resolution)


def test_quarter_model_regions_and_counts(quarter_a):
    """Counts of lattice nodes in each box at 5 mm (the lattice has a node at the origin): the
    beam 420 × 37.5 × 100 mm holds 85 × 8 × 21 nodes (37.5 mm is not a node: the last is 35), the
    plate's layers z = 100, 105, 110 over 11 × 8 (it takes the beam's top layer), the weight
    11 × 8 × 11 (50 mm high), the support strip 3 × 8 × 3."""
    s, ps = quarter_a
    count = {n: int(np.count_nonzero(ps.region == i)) for i, n in enumerate(ps.region_names)}
    beam = sum(v for k, v in count.items() if k in ("mortar", "bar") or k.startswith("stirrup"))
    assert beam + count["plate"] == 85 * 8 * 21 + 11 * 8 * 2
    assert count["plate"] == 11 * 8 * 3
    assert count["weight"] == 11 * 8 * 11
    assert count["support"] == 3 * 8 * 3
    assert ps.n == 85 * 8 * 21 + 11 * 8 * 2 + 11 * 8 * 11 + 3 * 8 * 3
    assert sum(k.startswith("stirrup") for k in ps.region_names) == 3 * 4
    assert ps.body_names == ("beam", "weight", "support")
    assert ps.held[ps.in_regions(["support"])].all() and not ps.held[~ps.in_regions(["support"])].any()
    # volumes: the beam's box and the plate's exactly (lattice-aligned halves), the weight's mass
    V_beam = ps.V[ps.body == 0].sum()
    assert V_beam == pytest.approx(0.42 * 0.0375 * 0.1 + 0.05 * 0.0375 * 0.01, rel=1e-12)
    assert ps.m[ps.in_regions(["weight"])].sum() == pytest.approx(100.0 / 4, rel=1e-12)


def test_rebar_carries_the_d10_section(quarter_a):
    """The main bar on lattice lines with its equivalent steel: Σ V_a E_a / L over its particles
    is E_s A_D10 (A = 71.33 mm², JIS nominal), i.e. the quarter section's steel fraction is
    A/(B/2 · H) = 1.902 %; its mass per length is ρ_s A. Closed forms; tolerance round-off."""
    s, ps = quarter_a
    sel = ps.in_regions(["bar"])
    E = np.array([mt.E for mt in ps.table.materials])[ps.mat_id]
    rho = ps.rho
    L = s.span / 2 + s.overhang
    assert float(np.sum(ps.V[sel] * E[sel]) / L) == pytest.approx(206e9 * D10_AREA, rel=1e-12)
    assert float(np.sum(ps.V[sel] * rho[sel]) / L) == pytest.approx(7850.0 * D10_AREA, rel=1e-12)
    frac = float(np.sum(ps.V[sel] * E[sel] / 206e9) / (L * 0.0375 * 0.1))
    assert frac == pytest.approx(71.33 / (37.5 * 100.0), rel=1e-12)
    # at 5 mm the bar (side 8.45 mm about y = 17.5, z = 20 mm) is the lattice lines y = 15, 20
    ys, zs = np.unique(ps.X[sel, 1]), np.unique(ps.X[sel, 2])
    assert np.allclose(ys, [0.015, 0.020]) and np.allclose(zs, [0.020])


def test_lattice_helpers():
    assert bar_lines(0.0175, math.sqrt(D10_AREA), 0.005) == (3, 4)
    assert bar_lines(0.0175, 0.001, 0.0125) == (1, 1)  # none within: the nearest line
    assert staircase(0.0375, 0.005) == pytest.approx(0.0375)
    assert staircase(0.0375, 0.02) == pytest.approx(0.03)  # nodes 0, 20 mm; 20 owns up to 30


# -- a short coarse impact ------------------------------------------------------------------------
def test_contact_forces_equal_and_opposite(quarter_a):
    """With the weight pushed into the plate by a third of a spacing, the contact force on the
    weight is minus that on the beam, and the total is zero to round-off."""
    s, ps = quarter_a
    x = ps.X.copy()
    w = ps.in_regions(["weight"])
    x[w, 2] -= ps.dx / 3
    f, e = contact_forces(x, ps.body, ps.dx, s.contact_stiffness * s.E_s)
    Fw, Fb = f[w].sum(axis=0), f[ps.body == 0].sum(axis=0)
    assert Fw[2] > 0 and e > 0
    assert np.allclose(Fw, -Fb, rtol=1e-12, atol=1e-9 * abs(Fw[2]))


@pytest.mark.parametrize("method, options", [("sph", dict(stress="hyperelastic")), ("csph", {})])
def test_short_impact_conserves_momentum(method, options):
    """Specimen A at 20 mm spacing for 40 µs: the weight strikes the plate (the impact force
    rises), and until the stress wave reaches the support 400 mm away (the steel's P wave,
    5.96 km/s, needs 67 µs) no external force acts along z: the z momentum of weight + beam stays
    −(100 kg/4)·2.2 m/s. Tolerance 1e-6 of it: the support's kernel-smeared precursor (< 1e-2 N
    over 4e-5 s) and round-off; a contact force not equal and opposite would change it by a
    fraction of the impact's impulse (~1 N s, 2 %)."""
    s = RCBeam(t_end=4e-5, n_out=10, dt_factor=0.1)
    out = driver.solve(method, s, 5, **options)
    assert out["status"] == "ok"
    p = np.asarray(out["linear_momentum"])
    p0 = -25.0 * 2.2
    assert np.all(np.isfinite(p)) and np.all(np.isfinite(out["midspan_displacement"]))
    assert np.allclose(p[:, 2], p0, rtol=0, atol=1e-6 * abs(p0))
    assert np.max(out["impact_force"]) > 1e4  # the weight struck the plate
    assert out["midspan_displacement"][-1] > 0  # the beam moves down
    for k in ("impact_force", "support_reaction", "time"):
        assert np.all(np.isfinite(out[k]))


@pytest.fixture(scope="module")
def consistent_a():
    """Integration-consistent csph (the default) on specimen A at 12.5 mm for 0.1 ms with the time
    step a factor times its own critical step 2/ω_max (``dt_reference='spectrum'``,
    :mod:`sph.spectrum`): 0.9 and 1.2. Also the CFL estimate Δx/c_p of the same body."""
    from sph.driver import method_entry, model_at

    s = RCBeam(t_end=1e-4, n_out=10, dt_reference="spectrum")
    runs = {f: driver.solve("csph", dataclasses.replace(s, dt_factor=f), 8) for f in (0.9, 1.2)}
    mod, defaults = method_entry("csph")
    model, _ = model_at(s, 8)
    dt_cfl = mod.build(discretise(model, 8), **defaults).time_step(1.0)
    return runs, dt_cfl


def test_consistent_csph_is_stable_below_its_critical_step(consistent_a):
    """The failure of integration-consistent csph at the CFL step (dt_factor 0.3) on this scene is
    the CFL estimate's, not the method's: its critical step 2/ω_max is 0.20 Δx/c_p here (the bars'
    and stirrups' stiff equivalent steel on lattice lines next to the mortar; nodal integration:
    0.57), below 0.3. At 0.9 Δt_crit it runs the impact (~260 steps: the weight strikes the plate,
    the beam bends) with the energy balance within the study's 2 % (studies.rc_beam.TOL_ENERGY);
    at 1.2 Δt_crit it grows exponentially within a few tens of steps (the central-difference
    amplification of the highest mode above ω Δt = 2: measured 38 steps), so the step that
    separates the two is the spectrum's, within (0.9, 1.2)."""
    from studies.rc_beam import TOL_ENERGY, energy_error

    runs, dt_cfl = consistent_a
    ok, bad = runs[0.9], runs[1.2]
    dt_crit = ok["dt"] / 0.9
    assert dt_crit < 0.3 * dt_cfl  # the CFL step of the old default lies above the critical step
    assert ok["status"] == "ok"
    assert ok["steps"] >= 0.9 * 1e-4 / ok["dt"]
    assert np.max(ok["impact_force"]) > 1e4 and -ok["midspan_w"][-1] > 0
    assert np.max(np.abs(energy_error(ok))) <= TOL_ENERGY
    assert bad["status"].startswith("unstable")
    assert bad["dt"] == pytest.approx(1.2 * dt_crit, rel=1e-12)
