"""The results store: provenance, units required, atomic writes that leave no partial file."""
import numpy as np
import pytest
import xarray as xr

from workbench import results
from workbench.scenes import Plate


def _ds():
    return xr.Dataset({"period": (("solver",), np.array([0.25, np.nan]), {"units": "s"}),
                       "status": (("solver",), np.array(["ok", "unstable: NaN at t=0.1"]),
                                  {"units": "-"})},
                      coords={"solver": ["fem", "csph"]})


def test_round_trip_with_provenance(tmp_path):
    ds = _ds()
    ds.attrs = results.provenance("plate", Plate())
    path = results.write(ds, tmp_path / "plate.nc")
    back = results.read(path)
    assert back.period.attrs["units"] == "s"
    assert list(back.status.values) == ["ok", "unstable: NaN at t=0.1"]
    for key in ("study", "workbench_version", "git_revision", "date", "cpu_count", "param_L",
                "param_L_units", "material_E"):
        assert key in back.attrs, key
    assert back.attrs["param_L"] == Plate().L
    assert back.attrs["param_L_units"] == "m"


def test_variables_need_units(tmp_path):
    ds = _ds()
    ds["x"] = (("solver",), np.zeros(2))
    with pytest.raises(ValueError, match="units"):
        results.write(ds, tmp_path / "x.nc")


def test_interrupted_write_leaves_old_file_intact(tmp_path, monkeypatch):
    path = tmp_path / "plate.nc"
    results.write(_ds(), path)
    before = path.read_bytes()

    def boom(self, *a, **k):
        open(a[0], "wb").write(b"partial")
        raise KeyboardInterrupt

    monkeypatch.setattr(xr.Dataset, "to_netcdf", boom)
    with pytest.raises(KeyboardInterrupt):
        results.write(_ds(), path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["plate.nc"]
