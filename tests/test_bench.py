"""``workbench bench`` (contract: ``bench.nc``): schema, units and sane values of a small sweep, and
bad input as one line with exit status 2. Speed is reported, never gated here."""
import math

import numpy as np
import pytest

from workbench import results
from app import cli


@pytest.fixture(scope="module")
def bench_ds(tmp_path_factory):
    from studies import bench

    out = tmp_path_factory.mktemp("bench")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(bench.REPEATS_ENV, "1")  # one run per cell is enough for the schema
        rc = cli.main(["bench", "--particles", "2000", "--threads", "1", "--solver", "csph",
                       "--out", str(out)])
    assert rc == 0
    assert (out / "bench.png").stat().st_size > 0
    return results.read(out / "bench.nc")


def test_schema_and_units(bench_ds):
    ds = bench_ds
    assert list(ds.solver.values) == ["csph"]
    assert list(ds.particles.values) == [2000] and list(ds.threads.values) == [1]
    expect = {"particle_steps_per_second": (("solver", "particles", "threads"), "1/s"),
              "status": (("solver", "particles", "threads"), "-"),
              "bytes_per_particle": (("solver", "particles"), "B"),
              "n_particles_actual": (("solver", "particles"), "-"),
              "startup_time": (("solver",), "s")}
    for name, (dims, units) in expect.items():
        assert ds[name].dims == dims, name
        assert ds[name].attrs["units"] == units, name
    for v in ds.data_vars.values():
        assert "units" in v.attrs
    for key in ("cpu_model", "cpu_count", "numba_version", "numba_threading_layer", "study",
                "git_revision", "bench_scene", "bench_laws"):
        assert key in ds.attrs, key
    assert ds.attrs["study"] == "bench"
    assert ds.attrs["bench_scene"] == "plate" and ds.attrs["bench_laws"] == "svk"
    assert ds["resolution"].dims == ("solver", "particles")


def test_values_are_sane(bench_ds):
    ds = bench_ds
    assert (ds.status.values == "ok").all(), ds.status.values
    psps = ds.particle_steps_per_second.values
    assert np.isfinite(psps).all() and (psps > 0).all()
    bpp = ds.bytes_per_particle.values
    assert ((bpp > 100) & (bpp < 1e6)).all(), bpp
    n = ds.n_particles_actual.values
    assert ((n > 1000) & (n < 4000)).all(), n  # "about N" particles
    st = ds.startup_time.values
    assert np.isfinite(st).all() and (st > 0).all(), st


@pytest.mark.parametrize("argv,needle", [
    (["bench", "--particles", "0"], "--particles: 0 is out of range"),
    (["bench", "--solver", "magic"], "--solver: 'magic' is not benchmarked"),
    (["bench", "--threads", "0"], "--threads: 0 is out of range"),
    (["bench", "--scene", "magic"], "--scene: 'magic' is not benchmarked"),
    (["bench", "--scene", "rc_beam", "--solver", "hpm"],
     "--solver: 'hpm' is not benchmarked on rc_beam"),
])
def test_bad_input_is_one_line_exit_2(argv, needle, capsys, tmp_path):
    assert cli.main(argv + ["--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "bench.nc").exists()


def test_a_failed_measurement_is_a_status_not_a_crash():
    from studies import bench

    r = bench.measure("csph", 2000, 1, timeout=0.01)
    assert r["status"].startswith("error: timed out")
    assert math.isnan(bench.startup_time("hpm", 2000, timeout=0.01)["startup_time"])


@pytest.mark.parametrize("scene,solver", [("microcantilever3d", "csph"), ("rc_beam", "csph"),
                                          ("rc_beam", "sph")])
def test_scene_harness_runs_the_scene(scene, solver):
    """The 3-D scenes' harness (in process, one timed step at ~1000 particles): the scene's own
    materials and options, about the requested particle count, a finite rate."""
    from studies import bench

    r = bench.particle_steps_per_second(solver, 1000, 1, steps=1, scene=scene)
    assert r["status"] == "ok" and r["scene"] == scene and r["steps"] == 1
    assert r["law"] == {"microcantilever3d": "j2", "rc_beam": "j2+mortar+svk"}[scene]
    assert 500 <= r["n_particles"] <= 2000, r["n_particles"]  # "about N" from the probe's scaling
    assert math.isfinite(r["particle_steps_per_second"]) and r["particle_steps_per_second"] > 0
    sb = bench.scene_body(scene, solver, 1000)
    assert sb.body.x.shape[1] == 3 and (sb.extra is not None) == (scene == "rc_beam")  # contact
    with pytest.raises(ValueError, match="law"):
        bench.scene_body(scene, solver, 1000, law="j2")


def test_every_step_variant_is_classic_sph_searching_every_step():
    """``sph_every_step`` (issue 12's classic-SPH step with its neighbours rebuilt every step) is
    the study's sph with ``skin`` 0: a search in every step, where the study's body searches
    again only after a move of half its skin."""
    from studies import bench

    every = bench.scene_body("rc_beam", "sph_every_step", 1000)
    study = bench.scene_body("rc_beam", "sph", 1000)
    assert every.body.b.skin == 0.0 and study.body.b.skin > 0.0
    searches = []
    for sb in (every, study):
        before = sb.body.b.searches
        assert sb.body.advance(5, sb.dt, sb.f_ext, sb.fixed, sb.v_fix, sb.damping, sb.extra) == 5
        searches.append(sb.body.b.searches - before)
    assert searches[0] == 5 and searches[1] < 5
