"""Issue 9's verification scenes run by the particle driver: the bi-material bar (two regions of
different stiffness in one body, exact answer the series spring) and the 3-D cantilever of
rectangular section (against Timoshenko beam theory), written only with the scene API."""
import numpy as np
import pytest

from sph import driver
from workbench.scenes import BiMaterialBar, Cantilever3D


@pytest.mark.parametrize("dim", [2, 3])
def test_bimaterial_bar_reaction_converges_to_the_series_spring(dim):
    """csph (per-particle materials: a material row per region). The strain jumps at the
    interface; the kernel's support smears it over about one spacing on either side, so the
    compliance of that band is in error by O(Δx/L): the reaction within Δx/(2L) of the series
    spring (5 % at 2 and 2.5 % at 4 particles across H; measured +3.6 % and +1.7 %), falling at
    first order (ratio > 1.6 from 2 to 4 across H; measured 2.1)."""
    sc = BiMaterialBar(dim=dim)
    err = []
    for res in (2, 4):
        r = driver.solve("csph", sc, res)
        assert r["status"] == ["ok"]
        err.append(r["reaction"][-1] / sc.exact_reaction() - 1)
        dx = sc.H / res
        assert abs(err[-1]) < dx / (2 * sc.L), (res, err)
    assert abs(err[0] / err[1]) > 1.6, err


def test_cantilever_3d_against_timoshenko():
    """csph at 4 particles across H and B: the 3-D continuum sits 0.9 % below Timoshenko theory
    (the FEM's converged hex27 value: clamp warping restraint and the shear coefficient), and the
    method's second-order error is (Δx/H)²/4 = 1.6 % at H/Δx = 4: 2.5 % in all (measured +0.58 %;
    at 2 across H, +38 %, outside it)."""
    sc = Cantilever3D()
    r = driver.solve("csph", sc, 4)
    assert r["status"] == ["ok"]
    err = r["tip_deflection"][-1] / sc.timoshenko(sc.loads[-1]) - 1
    assert abs(err) < 0.025, err
    coarse = driver.solve("csph", sc, 2)
    assert abs(coarse["tip_deflection"][-1] / sc.timoshenko(sc.loads[-1]) - 1) > 0.025
