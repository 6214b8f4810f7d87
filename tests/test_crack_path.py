"""The crack-path study (issue 41 item 5): Erdogan & Sih's kink angle, the scene's input checks,
and `workbench run crack_path --quick`'s gates (they pass, and fail a regression or a NaN)."""
import math

import numpy as np
import pytest

from workbench.scenes.crack_path import CrackPathPlate, kink_angle, smooth_ramp
from workbench.scenes.params import ParameterError


def test_kink_angle_closed_form():
    """Pure mode II: cos θ = 1/3 (θ = −70.53°, Erdogan & Sih 1963); pure mode I: 0; mixed: the
    root makes the hoop stress's derivative K_I sin θ + K_II (3 cos θ − 1) vanish."""
    assert kink_angle(0.0, 1.0) == pytest.approx(-math.degrees(math.acos(1 / 3)), abs=1e-12)
    assert kink_angle(1.0, 0.0) == 0.0
    th = math.radians(kink_angle(1.0, 0.5))
    assert math.sin(th) + 0.5 * (3 * math.cos(th) - 1) == pytest.approx(0.0, abs=1e-12)
    assert -90 < math.degrees(th) < 0


def test_smooth_ramp_has_no_velocity_step():
    """δ(0) = 0 with zero speed, the speed ``rate`` from t_ramp on, δ continuous there."""
    t = np.array([0.0, 1e-9, 1.0 - 1e-9, 1.0, 2.0])
    d = smooth_ramp(t, 1.0, 3.0)
    assert d[0] == 0.0 and d[1] / 1e-9 < 1e-6
    assert d[3] == pytest.approx(1.5) and d[2] == pytest.approx(1.5, abs=1e-8)
    assert d[4] - d[3] == pytest.approx(3.0)


@pytest.mark.parametrize("kw, word", [(dict(mode=3), "mode"), (dict(a=0.09), "a"),
                                      (dict(grow=0.06), "grow")])
def test_bad_parameters_name_themselves(kw, word):
    with pytest.raises(ParameterError, match=f"^{word}: "):
        CrackPathPlate(**kw).check()


def test_crack_path_quick_gates():
    """`workbench run crack_path --quick` (mode I, csph and sph at 15, 21, 31 spacings): the crack
    grows straight ahead (θ = 0 to round-off) at every spacing, each gate passes, names its
    reference and fails a regression (an exact gate: a third of the smallest lattice kink), and a
    run that grew no crack (NaN) fails its gate; the crack starts after several periods T₁."""
    from studies import crack_path as study

    ds = study.run(quick=True)
    gates = study.gates(ds)
    assert len(gates) == study.N_GATES[True]
    for g in gates:
        assert g.passed and g.reference, g.line()
        assert not g.regressed(3.0).passed, g.line()
    assert float(ds["onset_periods"].min()) > 5.0
    # the onset load: the grip reaction at the first record with a grown crack, against LEFM's
    # (the elastic FEM's compliance, G = G_c); a strength-based onset with l_ch = E'G_c/f_t² =
    # 0.44 a lies below LEFM's (the size effect: LEFM is the large-size limit, from above)
    for s in ds.solver.values:
        for r in ds.resolution.values:
            run = ds.sel(solver=s, resolution=r)
            first = int(np.argmax(run["tip_length"].fillna(0).values > 0))
            assert float(run["onset_load"]) == float(run["grip"][first])
            assert float(run["onset_ratio"]) == float(run["onset_load"] / run["onset_load_lefm"])
            assert 0 < float(run["onset_ratio"]) < 1, (s, r, float(run["onset_ratio"]))
    ds["error"][0, -1] = np.nan
    assert not study.gates(ds)[len(study.QUICK_RESOLUTIONS["csph"]) - 1].passed
    assert ds["kink_angle"].attrs["units"] == "deg"


def test_mode_i_gate_fails_a_broken_symmetry():
    """A real defect, not a scaled one: at 20 spacings the crack's line is a lattice row, which
    belongs to the upper side, so the mirror symmetry is broken and sph's mode-I crack kinks
    (−14°: one spacing off the line over the grown 20 mm): its exact gate fails."""
    from studies import crack_path as study

    ds = study.run(solvers=["sph"], resolutions={"sph": [20]})
    (gate,) = study.gates(ds)
    assert float(ds["error"].sel(solver="sph", resolution=20)) > 1.0
    assert not gate.passed, gate.line()


def test_classic_sph_grows_a_mode_ii_crack():
    """Classic SPH in mode II at 15 spacings: the crack grows from the pre-crack's tip on the side
    Erdogan & Sih's criterion gives (θ < 0, the lower half) until the Threshold stops the run, and
    no particle of the gripped bands fails. With brittle grips (``tab=0``, the scene before) the
    uncorrected kernel's prescribed rows failed first — 18 of the 25 failed particles on Y = ±L/2 —
    and no crack grew by t_end."""
    from sph import driver

    scene = CrackPathPlate(mode=2)
    out = driver.solve("sph", scene, 15, stress="hyperelastic")
    assert out["status"] == "ok" and np.isfinite(out["t_threshold"]), out["status"]
    failed, X = out["failed_particles"], out["X"]
    assert failed.any() and not (np.abs(X[failed, 1]) > scene.L / 2 - scene.tab).any()
    tip_y = np.asarray(out["tip_y"])
    assert np.nanmin(tip_y) < -scene.L / 15  # grown more than a spacing below the crack's line
