"""The micro-cantilever study (studies/microcantilever.py) at its quick setting and the scene's bad
input: one line naming the parameter and its allowed range, exit status 2 from the command line."""
import time

import numpy as np
import pytest

from sph import driver
from workbench.scenes.fracture import MicroCantilever
from workbench.scenes.params import ParameterError, SceneError


@pytest.mark.parametrize("kw,name", [
    (dict(eps_L_low=0.0), "eps_L_low"), (dict(eps_L_high=-1.0), "eps_L_high"),
    (dict(gb_thickness=5e-6), "gb_thickness"), (dict(gb_thickness=0.0), "gb_thickness"),
    (dict(n_grains=2.5), "n_grains"), (dict(n_grains=0), "n_grains"),
    (dict(velocity=0.0), "velocity"), (dict(velocity=-1.0), "velocity")])
def test_bad_parameters(kw, name):
    with pytest.raises(ParameterError) as err:
        MicroCantilever(**kw)
    msg = str(err.value)
    assert msg.startswith(f"{name}:") and "allowed" in msg and "\n" not in msg


def test_grain_boundary_thinner_than_the_spacing():
    with pytest.raises(SceneError) as err:
        driver.model_at(MicroCantilever(gb_thickness=0.5e-6), 5)
    msg = str(err.value)
    assert msg.startswith("gb_thickness:") and "spacing" in msg and "\n" not in msg


def test_cli_bad_input_exit_status(tmp_path, capsys):
    from workbench.app.cli import main

    assert main(["run", "microcantilever", "--quick", "--out", str(tmp_path),
                 "--set", "gb_thickness=2e-7"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "gb_thickness" in err
    assert main(["run", "microcantilever", "--quick", "--out", str(tmp_path),
                 "--set", "velocity=0"]) == 2


# ------------------------------------------------------------------------------------------------
# The study at its quick setting
# ------------------------------------------------------------------------------------------------

def test_microcantilever_quick_study(tmp_path, monkeypatch):
    """``workbench run microcantilever --quick``: both cases (2-D, H/Δx = 5, the default rule)
    pass every gate; the dataset holds the load–deflection curves, failed fractions and energies
    with units; the figures are written."""
    import studies
    from workbench.app.verify import run_study

    monkeypatch.setenv("WORKBENCH_NO_CACHE", "1")
    t0 = time.perf_counter()
    section = run_study("microcantilever", tmp_path, quick=True, study=studies.get("microcantilever"))
    wall = time.perf_counter() - t0
    ds = section["dataset"]
    bad = [g.line() for g in section["gates"] if not g.passed]
    assert not bad, bad
    assert len(section["gates"]) == 8
    for v in ("load", "deflection", "failed_fraction", "external_work", "kinetic_energy",
              "elastic_energy", "plastic_work", "released_energy"):
        assert ds[v].attrs["units"] and np.isfinite(ds[v].values).any(), v
    assert ds.attrs["plane"] == "strain"
    assert (tmp_path / "microcantilever.nc").exists()
    assert (tmp_path / "microcantilever_cracks.png").exists()
    print(f"quick study: {wall:.1f} s")
