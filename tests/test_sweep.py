"""Sweeps: a failed run is a status and the sweep goes on; finished runs come from the cache keyed by
parameters and code version; results come back in task order."""
import dataclasses

import numpy as np
import pytest

from studies import common, sweep
from workbench.scenes import Plate

CALLS = []


def fake_solve(scene, resolution, **options):
    CALLS.append((resolution, options))
    if resolution == 3:
        raise FloatingPointError("blew up")
    return {"period": scene.L * resolution, "status": "ok"}


@pytest.fixture
def fake_solver(monkeypatch, tmp_path):
    monkeypatch.setitem(common.SOLVER_ENTRY, "fake", f"{__name__}:fake_solve")
    monkeypatch.setenv("WORKBENCH_CACHE", str(tmp_path))
    CALLS.clear()


def test_failed_run_is_a_status_and_sweep_goes_on(fake_solver):
    tasks = [sweep.Task.make("fake", Plate(), r) for r in (1, 3, 2)]
    out = sweep.run_tasks(tasks, "serial")
    assert [o["status"][:5] for o in out] == ["ok", "error", "ok"]
    assert "FloatingPointError: blew up" in out[1]["status"]
    assert out[2]["period"] == pytest.approx(0.4)


def test_cache_reuses_finished_runs_only(fake_solver):
    tasks = [sweep.Task.make("fake", Plate(), r, flag=True) for r in (1, 3)]
    sweep.run_tasks(tasks, "serial")
    assert len(CALLS) == 2
    again = sweep.run_tasks(tasks, "serial")
    # the ok run came from the cache; the failed one was retried
    assert len(CALLS) == 3 and CALLS[-1][0] == 3
    assert again[0]["period"] == pytest.approx(0.2)
    # another parameter set is another key
    other = sweep.Task.make("fake", dataclasses.replace(Plate(), L=0.3), 1, flag=True)
    assert other.key() != tasks[0].key()
    assert sweep.run_tasks([other], "serial")[0]["period"] == pytest.approx(0.3)
    assert len(CALLS) == 4


def test_code_hash_is_part_of_the_key(fake_solver, monkeypatch):
    from workbench import runcache

    t = sweep.Task.make("fake", Plate(), 1)
    k1 = t.key()
    monkeypatch.setattr(runcache, "code_hash", lambda *a: "another")
    assert t.key() != k1


def test_observed_order_least_squares():
    h = np.array([0.1, 0.05, 0.025, 0.0125])
    assert common.observed_order(h, 3 * h ** 2) == pytest.approx(2.0, abs=1e-12)
    assert np.isnan(common.observed_order(h[:2], h[:2]))


def test_local_dask_cluster_runs_sweep_and_keeps_failures(tmp_path, monkeypatch):
    # two real FEM runs of the homogeneous block and one that fails (an unknown solver entry):
    # all three come back, in order, the failure as a status
    from workbench.scenes import SSCurve

    monkeypatch.setenv("WORKBENCH_NO_CACHE", "1")
    monkeypatch.setitem(common.SOLVER_ENTRY, "broken", "no_such_module:solve")
    scene = SSCurve(n_steps=4, max_strain=0.02)
    tasks = [sweep.Task.make("fem", scene, 1), sweep.Task.make("broken", scene, 1),
             sweep.Task.make("fem", scene, 2)]
    serial = sweep.run_tasks([tasks[0]], "serial")[0]
    out = sweep.run_tasks(tasks, "local")
    assert out[0]["status"] == "ok" and out[2]["status"] == "ok"
    assert out[1]["status"].startswith("error:")
    assert np.allclose(out[0]["stress"], serial["stress"], rtol=1e-12)
