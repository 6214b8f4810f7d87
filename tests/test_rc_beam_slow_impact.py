"""Gate 2, second half (studies/rc_beam/slow_impact.py): an impact too slow to crack
anything, csph's mid-span history against the FEM's (studies.rc_beam.SlowImpactFem: the weight a
mass on the plate's top face, hinges at the support blocks' inner columns)."""
import dataclasses
import math

import numpy as np
import pytest

from studies.rc_beam import RCBeam


# -- the FEM's model is the particles' geometry ---------------------------------------------------
@pytest.mark.parametrize("resolution", [8, 10])
def test_fem_regions_are_the_particles_cells(resolution):
    """SlowImpactFem meshes each region as the particles fill it at their spacing: the volume of
    every region (the plate rounded to the beam's top lattice layers, the bar, the mortar, the
    whole beam) equals the sum of its particles' volumes (sph.particles, exact for lattice boxes),
    to round-off; the hinge nodes lie on the support block's inner column, x = span/2 − Δx, z = 0,
    and the weight's face on the plate's top under the weight's columns. Specimen B (no stirrups,
    whose scene boxes are not on the 12.5 mm lattice), FEM at 2 elements across H: the grid runs
    through every region face, so the volumes do not depend on it."""
    from fem_reference.model import build
    from sph.particles import discretise
    from studies.rc_beam.slow_impact import SlowImpactFem, slow_impact_scene

    sc = dataclasses.replace(slow_impact_scene(), specimen="B")
    dx = sc.H / resolution
    ps = discretise(sc.model(dx), resolution)
    fem = SlowImpactFem(sc, resolution)
    fm = build(fem, 2)
    vol = np.bincount(fm.region, weights=fm.disc.dV0.sum(axis=1), minlength=len(fm.model.regions))
    names = [r.name for r in fm.model.regions]
    for n in ("mortar", "plate", "bar"):
        assert vol[names.index(n)] == pytest.approx(
            ps.V[ps.region == ps.region_names.index(n)].sum(), rel=1e-12)
    assert vol.sum() == pytest.approx(ps.V[ps.body == ps.body_names.index("beam")].sum(), rel=1e-12)
    X = fm.X
    hinge = X[:, fm.nodes["hinge"]]
    assert np.allclose(hinge[0], sc.span / 2 - dx) and np.allclose(hinge[2], 0.0)
    face = X[:, fm.nodes["weight_face"]]
    weight = ps.X[ps.region == ps.region_names.index("weight")]
    assert np.allclose(face[2], ps.X[ps.region == ps.region_names.index("plate"), 2].max())
    assert face[0].max() == pytest.approx(weight[:, 0].max()) and face[0].min() == 0.0


def test_velocity_estimate_is_the_timoshenko_beam_under_the_weight():
    """studies.rc_beam.slow_impact_stress against the same estimate written out for A at 1 m/s:
    the transformed section (E_s/E_m = 17.3, both D10 bars 20 mm up), a hinged beam of 800 mm
    under a central load (bending + shear, κ = 5/6), the 100 kg weight meeting its static
    stiffness; and SLOW_VELOCITY keeps the bottom stress under a third of the mortar's tensile
    strength (room for the contact's force peaks, 2-3 times its smooth value)."""
    from studies.rc_beam.slow_impact import SLOW_VELOCITY, slow_impact_scene, slow_impact_stress
    from studies.rc_beam.scene import D10_AREA

    b, h, L, n, As = 0.075, 0.1, 0.8, 206e9 / 11.9e9, 2 * D10_AREA
    zc = (b * h * h / 2 + (n - 1) * As * 0.02) / (b * h + (n - 1) * As)
    I = b * h ** 3 / 12 + b * h * (h / 2 - zc) ** 2 + (n - 1) * As * (zc - 0.02) ** 2
    G = 11.9e9 / (2 * 1.22)
    k = 1 / (L ** 3 / (48 * 11.9e9 * I) + L / (4 * 5 / 6 * G * b * h))
    sigma = math.sqrt(k * 100.0) * L / 4 * zc / I
    sc = slow_impact_scene()
    assert slow_impact_stress(sc, 1.0) == pytest.approx(sigma, rel=1e-12)
    assert slow_impact_stress(sc, SLOW_VELOCITY) < sc.f_t / 3


# -- the comparison on histories with known answers ------------------------------------------------
def _runs(T=0.01, amp=3e-5, delta=0.02, mesh=0.004, step=0.001):
    """Synthetic runs: the finest FEM w = A sin(πt/T) (records every 50 µs, on past T), the next
    mesh A(1 + mesh) sin, half the steps A sin(πt/(T(1 + step))), csph A(1 + δ) sin(πt/T) with
    its impact force zero at every third record and a constant support reaction, no damage."""
    t = np.arange(0.0, 1.2 * T, 5e-5)
    s = np.sin(np.pi * t / T)
    fem = {("fem", 8, 200): amp * s, ("fem", 6, 200): amp * (1 + mesh) * s,
           ("fem", 8, 100): amp * np.sin(np.pi * t / (T * (1 + step)))}
    runs = {k: dict(time=t, midspan_displacement=w, status="ok") for k, w in fem.items()}
    F = np.where(np.arange(len(t)) % 3 == 0, 0.0, 300.0) * (t < T)
    runs[("csph", 8, 0)] = dict(time=t, midspan_displacement=amp * (1 + delta) * s, status="ok",
                                impact_force=F, support_reaction_mean=np.full(len(t), 100.0),
                                history=np.zeros((3, 23)), region=np.array([0, 1, 2]),
                                region_names=["mortar", "plate", "weight"])
    return runs


def test_slow_comparison_of_known_histories():
    """studies.rc_beam.slow_comparison on sines: the window ends at the FEM's zero crossing T (to
    the linear interpolation's O(Δt³) at a zero of a sine), the difference is δ of the peak, the
    FEM's mesh error its rung's 0.4 %, its time error max |sin(πt/T(1 + ε)) − sin(πt/T)| over the
    window; a third of the records without force, and the force's 1 ms means equal to its mean
    over the window to the trapezoid's end effects (a 1 ms mean spans 20 records, nearly whole
    periods of the every-third-record chatter); a constant support reaction's means equal it; no
    history of damage. The quarter window ends at the peak's record (T/2 to a record)."""
    from studies.rc_beam.slow_impact import slow_comparison

    T, delta, eps = 0.01, 0.02, 0.001
    c = slow_comparison(_runs(T=T, delta=delta, step=eps))
    assert c["window_end"] == pytest.approx(T, rel=1e-9)
    assert c["error"] == pytest.approx(delta, rel=1e-6)
    assert c["fem_mesh_error"] == pytest.approx(0.004, rel=1e-6)
    tt = np.linspace(0, T, 2001)
    ref = np.max(np.abs(np.sin(np.pi * tt / (T * (1 + eps))) - np.sin(np.pi * tt / T)))
    assert c["fem_time_error"] == pytest.approx(ref, rel=1e-3)
    assert c["zero_force_fraction"] == pytest.approx(1 / 3, abs=0.01)
    assert c["min_mean_force"] == pytest.approx(1.0, abs=0.05)
    assert c["min_mean_support"] == pytest.approx(1.0, rel=1e-12)
    assert c["max_damage"] == 0.0 and c["max_plastic_strain"] == 0.0
    assert len(c["time"]) == len(c["csph"]) == len(c["fem"])
    q = slow_comparison(_runs(T=T, delta=delta), window="quarter")
    assert q["window_end"] == pytest.approx(T / 2, abs=5e-5)
    assert q["error"] == pytest.approx(delta, rel=1e-6)


def test_dataset_variables_and_gates_of_the_slow_impact():
    """studies.rc_beam.dataset with the slow runs: both histories on one time axis with units,
    the four gates (history, elastic, weight and supports pressed) passing at δ = 2 % < 5 %,
    the history's failing at δ = 6 %; a separated weight fails its gate."""
    from studies import rc_beam
    from studies.rc_beam.dataset import dataset
    from studies.rc_beam.slow_impact import slow_gates

    scene = RCBeam(t_end=2.5e-4, n_out=50)
    for delta, ok in ((0.02, True), (0.06, False)):
        ds = dataset(scene, {}, ["csph"], [8], quick=False, slow=_runs(delta=delta))
        for v in ("slow_csph_displacement", "slow_fem_displacement", "slow_fem_rungs"):
            assert "slow_time" in ds[v].dims and "units" in ds[v].attrs
        g = slow_gates(ds)
        assert len(g) == 4 and g[0].passed == ok and all(x.passed for x in g[1:])
        assert any("slow impact" in gate.name for gate in rc_beam.gates(ds))
        assert any("slow impact" in n for n in rc_beam.report_notes(ds))
    runs = _runs()
    runs[("csph", 8, 0)]["impact_force"] = np.where(runs[("csph", 8, 0)]["time"] < 0.005, 300.0, 0.0)
    ds = dataset(scene, {}, ["csph"], [8], quick=False, slow=runs)
    assert not slow_gates(ds)[2].passed


# -- the check itself, cheaply ---------------------------------------------------------------------
def test_slow_impact_follows_the_fem_to_the_peak():
    """Gate 2's slow impact at a fraction of its cost: specimen A without its stirrups (an FEM of
    8e3 unknowns instead of 5e4: the stirrups' boxes put grid lines everywhere) at SLOW_VELOCITY,
    csph at 12.5 mm (the study's options) to just past the peak of the FEM's response (the first
    quarter period, ~5 ms; 8e3 steps), against SlowImpactFem at 4 elements across H and 200
    Newmark steps a period. csph's mid-span displacement stays within studies.rc_beam.TOL_SLOW
    (5 %) of the FEM's peak over the window; nothing cracks or yields; the weight stays pressed on
    the plate on average (the smallest 1 ms mean of the impact force positive) while the contact
    chatters (some records without force).

    Tolerance: the gate's budget (studies/rc_beam/slow_impact.py, TOL_SLOW) over a quarter period: the
    FEM's own error at this mesh and step (with the stirrups, against the gate's reference, 8
    elements and 400 steps: 1.0 % of the peak over this window, mostly the step), csph's
    stiffness (A's first frequency 0.9 % high at 12.5 mm: a phase error at a quarter period of
    π/2 · 0.9 % ≈ 1.5 %), the contact the FEM idealises (csph's weight bounces off the plate at
    its first impact, the FEM's sticks: 3.5 % of the peak at 0.7 ms, the largest difference of the
    window; with the FEM's own error there, 4.4 %). csph's present difference is 3.7 % of the
    peak: a threefold error fails."""
    from studies.common import run_solver
    from studies.rc_beam.slow_impact import (TOL_SLOW, slow_comparison, slow_impact_scene,
                                             slow_impact_tasks)

    sc = dataclasses.replace(slow_impact_scene(), stirrups=False, t_end=5.3e-3)
    tasks = slow_impact_tasks(sc, fem_resolutions=(4,), steps=(200,))
    runs = {k: run_solver(t.solver, t.scene, t.resolution, **dict(t.options))  # no run cache
            for k, t in tasks.items()}
    assert all(r["status"] == "ok" for r in runs.values())
    c = slow_comparison(runs, window="quarter")
    assert 4e-3 < c["window_end"] < 5.3e-3
    assert c["error"] <= TOL_SLOW
    assert c["max_damage"] == 0.0 and c["max_plastic_strain"] == 0.0
    assert c["min_mean_force"] > 0 and 0 < c["zero_force_fraction"] < 0.5
