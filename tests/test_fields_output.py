"""Field output of the particle drivers and the studies: a plate run writes a ParaView series whose
frames hold the solver's own state (checked against the returned tip history), field output never
changes a result nor is swallowed by the run cache, and ``workbench run --fields`` puts the series
under OUT/fields/ with a snapshot or a note in the report section."""
import numpy as np
import pytest

from workbench.fields import series_frames
from workbench.scenes import Plate, with_overrides

SHORT = {"periods": "0.15"}  # a fraction of a period: a few hundred steps at H/dx = 3


def _plate():
    return with_overrides(Plate(), SHORT)


@pytest.mark.parametrize("solver, lattice_mode", [("csph", "node"), ("hpm", "node"), ("sph", "cell")])
def test_plate_fields_hold_the_solver_state(tmp_path, solver, lattice_mode):
    import pyvista as pv

    from sph import particles
    from studies.common import solver_function

    scene = _plate()
    out = solver_function(solver)(scene, 3, fields=tmp_path, field_frames=4, lattice=lattice_mode)
    assert out["status"] == "ok"
    frames = series_frames(tmp_path / f"plate_{solver}_H3.pvd")
    times = [t for t, _ in frames]
    assert len(frames) >= 3 and times[0] == 0.0 and np.all(np.diff(times) > 0)
    assert times[-1] == pytest.approx(out["time"][-1], rel=1e-12)  # the final state is a frame
    reader = pv.get_reader(str(tmp_path / f"plate_{solver}_H3.pvd"))
    assert reader.time_values == pytest.approx(times)

    ps = particles.discretise(scene.model(scene.H / 3), 3, lattice_mode)
    n = ps.n
    first, last = pv.read(str(frames[0][1])), pv.read(str(frames[-1][1]))
    assert last.n_points == n == out["n_particles"]
    shapes = {k: last.point_data[k].shape for k in last.point_data.keys()}
    assert shapes == {"displacement": (n, 3), "velocity": (n, 3), "stress": (n, 9),
                      "von_mises": (n,), "region": (n,)}  # the plate is elastic: no ε_p, no damage
    u = last.point_data["displacement"][:, :2]
    # points are the deformed positions: x − u is the reference lattice
    assert np.allclose(last.points[:, :2] - u, ps.X, rtol=0, atol=1e-12)
    # the tip probe of the last frame is the solver's last tip displacement
    idx, w = ps.probes["tip"]
    assert w @ u[idx, 1] == pytest.approx(out["tip_displacement"][-1], rel=1e-9, abs=1e-15)
    assert abs(out["tip_displacement"][-1]) > 1e-3  # a real deflection, not a trivial match
    # t = 0: undeformed, unstressed, moving with the initial velocity (zero in the clamp)
    assert np.abs(first.point_data["displacement"]).max() == 0.0
    assert np.abs(first.point_data["stress"]).max() < 1e-6 * np.abs(last.point_data["stress"]).max()
    assert np.abs(first.point_data["velocity"][ps.held]).max() == 0.0
    assert first.point_data["velocity"][:, 1].max() > 0
    # σ_xx carries the bending: tension and compression across the thickness
    sxx = last.point_data["stress"][:, 0]
    assert sxx.max() > 0 > sxx.min()


def test_j2_point_data_has_plastic_strain_and_damage():
    from workbench.fields import particle_point_data
    from workbench.materials import HIST_DAMAGE, HIST_EPS_P, TABLE1_STEEL, evaluate

    mat = TABLE1_STEEL
    F = np.tile(np.diag([1.02, 0.99, 0.99]), (4, 1, 1))
    F[0] = np.eye(3)
    h = evaluate(mat, F, None)["history"]
    data = particle_point_data(mat, np.zeros((4, 2)), np.ones((4, 2)), np.zeros((4, 2)), F=F,
                               history=h)
    assert data["plastic_strain"] == pytest.approx(h[:, HIST_EPS_P])
    assert data["damage"] == pytest.approx(h[:, HIST_DAMAGE])
    assert data["plastic_strain"][0] == 0 and data["plastic_strain"][1] > 0
    assert data["von_mises"][1] > 0.9 * mat.sigma_y0


def test_cache_does_not_swallow_a_field_request(tmp_path, monkeypatch):
    from studies.sweep import Task, run_tasks

    monkeypatch.setenv("WORKBENCH_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("WORKBENCH_NO_CACHE", raising=False)
    scene = with_overrides(Plate(), {"periods": "0.05"})
    plain = Task.make("csph", scene, 3)
    with_fields = Task.make("csph", scene, 3, fields=str(tmp_path / "f"))
    assert with_fields.key() == plain.key() and with_fields.writes_fields
    (a,) = run_tasks([plain], "serial")  # now cached
    (b,) = run_tasks([with_fields], "serial")  # must run anyway and write the series
    assert (tmp_path / "f" / "plate_csph_H3.pvd").exists()
    assert np.array_equal(a["tip_displacement"], b["tip_displacement"])  # fields change nothing


def test_cli_run_fields_and_report_note(tmp_path, monkeypatch, capsys):
    import xarray as xr

    from studies import plate
    from workbench import fields
    from app import cli, verify

    monkeypatch.setenv("WORKBENCH_NO_CACHE", "1")
    out = tmp_path / "out"
    rc = cli.main(["run", "plate", "--solver", "csph", "--resolution", "3", "--quick", "--fields",
                   "--set", "periods=0.05", "--out", str(out)])
    assert rc == 0
    assert "fields/plate_csph_H3.pvd" in capsys.readouterr().out
    assert len(series_frames(out / "fields" / "plate_csph_H3.pvd")) >= 2
    with xr.open_dataset(out / "plate.nc") as ds:  # the FEM's dynamic rung (4 in quick) too
        assert {n.strip() for n in ds.attrs["field_series"].split(",")} == {"plate_csph_H3.pvd", "plate_fem_H4.pvd"}
    # a machine that cannot render gets a note: where the fields are and why there is no picture
    monkeypatch.setattr(fields, "can_render", lambda: (False, "off-screen rendering unavailable (test)"))
    figures = []
    notes = verify.field_section(plate, "plate_csph_H3.pvd", out / "fields", out, figures)
    assert figures == []
    text = " ".join(notes)
    assert "fields/plate_csph_H3.pvd" in text and "ParaView" in text
    assert "off-screen rendering unavailable (test)" in text


def test_fem_plate_mesh_fields_hold_the_newmark_state(tmp_path):
    """The FEM plate's dynamic run writes its mesh (.vtu, vertex displacement and velocity); the
    tip vertex's vertical displacement in every frame is the tip history the driver returns at
    that time (so the test fails if the DOF-to-vertex map or the frame times are wrong)."""
    import pyvista as pv

    from fem_reference import drivers

    sc = Plate(periods=0.3)
    out = drivers.solve_plate(sc, 2, fields=str(tmp_path), field_frames=5)
    assert out["status"] == "ok"
    frames = series_frames(tmp_path / "plate_fem_H2.pvd")
    assert len(frames) >= 5 and frames[-1][0] == pytest.approx(out["time"][-1])
    for t, f in frames:
        grid = pv.read(str(f))
        assert isinstance(grid, pv.UnstructuredGrid) and grid.n_cells == 40  # 20 x 2 quads (L/H = 10)
        tip = int(np.argmin(np.hypot(grid.points[:, 0] - sc.L, grid.points[:, 1])))
        k = int(np.argmin(np.abs(out["time"] - t)))
        assert grid.point_data["displacement"][tip, 1] == pytest.approx(out["tip_displacement"][k], abs=1e-15)
        assert grid.point_data["velocity"].shape == (grid.n_points, 3)
