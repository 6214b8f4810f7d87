"""SS-curve gate (issue 2 item 7): CSPH on the exact uniaxial curve at every strain up to 0.3 (the
study's tolerance, studies.ss_curve.TOL_CONSISTENT: the homogeneous state is the discrete
equilibrium), with the equilibrium of every free particle solved by Newton at each load step."""
import numpy as np
import pytest

from sph import driver
from workbench.analytic import uniaxial_curve
from studies.ss_curve import TOL_CONSISTENT
from workbench.scenes import SSCurve

GATE = TOL_CONSISTENT  # the study's gate (was 0.5 %, issue 2's bound, here)


def csph(scene, resolution, **options):
    return driver.solve("csph", scene, resolution, h_ratio=1.3, **options)


@pytest.mark.parametrize("correction", ["linear", "quadratic"])
def test_ss_curve_gate(correction):
    scene = SSCurve()
    r = csph(scene, 2, correction=correction)  # 3 particles per edge, 27 particles
    assert r["status"] == "ok"
    exact = uniaxial_curve(scene.material, r["strain"])
    assert r["strain"][-1] == pytest.approx(0.3)
    err = np.abs(r["stress"] / exact["sigma"] - 1).max()
    err_nom = np.abs(r["nominal_stress"] / exact["nominal"] - 1).max()
    err_avg = np.abs(r["stress_particle_average"] / exact["sigma"] - 1).max()
    assert err < GATE and err_nom < GATE and err_avg < GATE, (err, err_nom, err_avg)
    assert r["n_particles"] == 27 and r["wall_time"] > 0


def test_unload_reload_cycle():
    """Elastic unloading with slope E and reloading back onto the curve (return mapping check)."""
    scene = SSCurve(unload=True, n_steps=30)
    r = csph(scene, 2)
    exact = uniaxial_curve(scene.material, r["strain"])
    assert np.abs(r["stress"] / exact["sigma"] - 1).max() < GATE


# The integration-consistent CSPH keeps the homogeneous state as its discrete equilibrium at any
# resolution: Newton's tolerance (1e-8 of the reaction) and the return mapping's round-off remain.
EXACT = TOL_CONSISTENT


@pytest.mark.parametrize("resolution", [3, 5])
def test_ss_curve_finer_block_is_exact(resolution):
    """4 and 6 particles per edge, into the plastic range: csph on the exact curve; paper 000's CSPH
    as printed (csph_bl: Bonet–Lok gradient, nodal integration) relaxes into a non-homogeneous
    state that is more than 5 % soft (the contrast shows the gate can fail)."""
    scene = SSCurve(n_steps=3, max_strain=0.003)
    r = csph(scene, resolution)
    exact = uniaxial_curve(scene.material, r["strain"])
    assert np.abs(r["stress"] / exact["sigma"] - 1).max() < EXACT
    if resolution == 3:
        bl = driver.solve("csph_bl", scene, resolution, h_ratio=1.3)
        assert (bl["stress"] / exact["sigma"] - 1).min() < -0.05
