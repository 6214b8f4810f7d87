"""The on-disk cache of FEM reference values (runs of the one run cache, workbench.runcache)."""
import dataclasses

import numpy as np
import pytest

import fem_reference
from fem_reference import cache
from workbench.scenes import Cantilever, Plate


@pytest.fixture
def tmp_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("WORKBENCH_CACHE", str(tmp_path))
    return tmp_path


def test_reference_is_computed_once_then_read(tmp_cache, monkeypatch):
    sc = Plate()
    T = fem_reference.reference(sc, "period", resolution=2)
    assert T == pytest.approx(fem_reference.solve(sc, 2, dynamic=False)["period"], rel=1e-12)
    files = list((tmp_cache / "runs").glob("*.pkl"))
    assert len(files) == 1
    rec = cache.record(sc, 2, dynamic=False)
    assert files[0].stem == rec["key"] and rec["resolution"] == 2 and rec["solver"] == "fem"

    def boom(*a, **k):
        raise AssertionError("solve called although the value is cached")

    monkeypatch.setattr(fem_reference.model, "solve", boom)
    assert fem_reference.reference(sc, "period", resolution=2) == T


def test_key_depends_on_parameters_resolution_and_options():
    sc = Plate()
    k0, _ = cache.record_key(sc, 2, {})
    assert cache.record_key(dataclasses.replace(sc, H=0.021), 2, {})[0] != k0
    assert cache.record_key(sc, 4, {})[0] != k0
    assert cache.record_key(sc, 2, {"dynamic": True})[0] != k0
    assert cache.record_key(Plate(), 2, {})[0] == k0


def test_array_quantity_and_unknown_quantity(tmp_cache):
    sc = dataclasses.replace(Cantilever(), loads=(0.00192, 0.5))
    v = fem_reference.reference(sc, "tip_deflection", resolution=1)
    assert isinstance(v, np.ndarray) and v.shape == (2,) and np.all(v > 0)
    with pytest.raises(ValueError, match="quantity"):
        fem_reference.reference(sc, "period")
