"""Static cantilever (004 E) with CSPH: tip deflection within 3 % of the FEM at H/Δx = 10 for the
paper's small load and the large loads (issue 4 item 6); dynamic relaxation agrees with Newton;
the small-load result against beam theory."""
import numpy as np
import pytest

import fem_reference as fem
from sph import driver
from studies.cantilever import TOL_CONSISTENT_FEM
from workbench.analytic import cantilever_tip
from workbench.scenes import Cantilever

# Integration-consistent CSPH (issue 10), second order: the study's gate at H/Δx = 10 (was 2.5e-3
# here; studies/cantilever.py says why; the nodal quadratic CSPH is −0.23 … +0.35 % off, Bonet–Lok
# +1.3 … +4.6 %).
TIP_GATE = TOL_CONSISTENT_FEM


def csph(scene, resolution, **options):
    return driver.solve("csph", scene, resolution, **options)


def test_cantilever_tip_gate_h10():
    scene = Cantilever()
    r = csph(scene, 10)
    assert r["status"] == ["ok"] * len(scene.loads)
    ref = fem.reference(scene, "tip_deflection")
    err = r["tip_deflection"] / ref - 1
    assert np.abs(err).max() < TIP_GATE, err  # measured +0.05 … +0.10 %
    ref_h = fem.reference(scene, "tip_horizontal")
    # the shortening is second order in the deflection: 1 % at the large loads, 1 % at the small
    assert np.abs(r["tip_horizontal"][1:] / ref_h[1:] - 1).max() < 0.03
    assert np.all(np.diff(r["wall_time"]) >= 0)
    # small load: Timoshenko beam theory within 3 % (the clamp and 2-D effects are below that)
    assert abs(r["tip_deflection"][0] / cantilever_tip(scene, scene.loads[0]) - 1) < 0.03


def test_dynamic_relaxation_agrees_with_newton():
    scene = Cantilever(loads=(1.0,))
    newton = csph(scene, 4)
    dr = csph(scene, 4, static="dr")  # DR stops at a residual of 1e-4 of the load
    assert newton["status"] == ["ok"] and dr["status"] == ["ok"]
    # measured agreement 3e-6 (71 000 DR steps, 2 s, against 0.5 s for Newton)
    assert abs(dr["tip_deflection"][0] / newton["tip_deflection"][0] - 1) < 1e-3


def test_plane_stress_is_refused_clearly():
    with pytest.raises(ValueError, match="plane"):
        csph(Cantilever(plane="stress"), 4)
