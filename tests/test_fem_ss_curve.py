"""The FEM SS curve (000, Table 1): a homogeneous 3-D block in uniaxial stress with J2, against the
exact curve of workbench.analytic (computed independently by a scalar return mapping)."""
import dataclasses

import numpy as np
import pytest

from fem_reference import solve
from studies.ss_curve import TOL_REL
from workbench import analytic
from workbench.scenes import SSCurve

# The state is homogeneous and trilinear hexahedra represent it exactly (a patch test): only the
# Newton tolerance (1e-9 relative residual) and the return mapping's tolerance remain. The study's
# gate (studies.ss_curve.TOL_REL, was 0.5 % there).
TOL_PATCH = TOL_REL


@pytest.mark.parametrize("resolution", [1, 2])
def test_ss_curve_matches_exact_uniaxial_curve(resolution):
    sc = SSCurve()
    r = solve(sc, resolution, element="hex8")
    assert r["status"] == "ok", r["status"]
    assert r["strain"][-1] == pytest.approx(0.3)
    ref = analytic.uniaxial_curve(sc.material, r["strain"])
    err = np.abs(r["stress"] / ref["sigma"] - 1)
    err_nom = np.abs(r["nominal_stress"] / ref["nominal"] - 1)
    assert err.max() < TOL_PATCH, f"Cauchy stress off by {err.max():.2e}"
    assert err_nom.max() < TOL_PATCH, f"nominal stress off by {err_nom.max():.2e}"
    assert np.abs(r["stress_particle_average"] / ref["sigma"] - 1).max() < TOL_PATCH
    assert np.abs(r["eps_p"] - ref["eps_p"]).max() < TOL_PATCH * 0.3
    # a few Newton iterations per step, each load step converged
    assert all(len(h) == 1 and h[0][-1] < 1e-9 for h in r["residual_history"])


def test_unload_reload_cycle_is_elastic_with_slope_E():
    sc = dataclasses.replace(SSCurve(), max_strain=0.1, n_steps=20, unload=True, unload_by=0.002)
    r = solve(sc, 1, element="hex8")
    assert r["status"] == "ok", r["status"]
    ref = analytic.uniaxial_curve(sc.material, r["strain"])
    tau = r["stress"] * np.exp((1 - 2 * sc.nu) * ref["tau"] / sc.E)  # Kirchhoff = J σ
    assert np.abs(r["stress"] / ref["sigma"] - 1).max() < TOL_PATCH
    k = np.argmax(r["strain"])  # the unloading branch follows
    slope = (tau[k + 1] - tau[k]) / (r["strain"][k + 1] - r["strain"][k])
    assert slope == pytest.approx(sc.E, rel=1e-6)
    # no plastic flow during unloading
    assert r["eps_p"][k + 1] == pytest.approx(r["eps_p"][k], abs=1e-12)
