"""Field output: a .pvd series that pyvista (as ParaView) reads back with the times and fields."""
import numpy as np
import pytest

from workbench.fields import FieldSeries, can_render, snapshot_png


def test_particle_series_round_trip(tmp_path):
    import pyvista as pv

    s = FieldSeries(tmp_path, "plate")
    x = np.random.default_rng(0).random((50, 2))
    for k, t in enumerate((0.0, 0.5)):
        s.add(t, x + k, u=np.full((50, 2), k), sigma=np.tile(np.eye(2), (50, 1, 1)) * t, eps_p=x[:, 0])
    reader = pv.get_reader(str(s.pvd))
    assert reader.time_values == pytest.approx([0.0, 0.5])
    reader.set_active_time_value(0.5)
    m = reader.read()[0]
    assert m.n_points == 50
    assert np.allclose(m.points[:, :2], x + 1)
    assert np.allclose(m.point_data["u"][:, :2], 1)
    assert m.point_data["sigma"].shape == (50, 9) and np.allclose(m.point_data["sigma"][:, 0], 0.5)


def test_wrong_length_is_refused(tmp_path):
    s = FieldSeries(tmp_path, "x")
    with pytest.raises(ValueError, match="u: 3 values for 4 points"):
        s.add(0.0, np.zeros((4, 2)), u=np.zeros(3))


def test_snapshot_renders_or_says_why(tmp_path):
    s = FieldSeries(tmp_path, "x")
    f = s.add(0.0, np.random.default_rng(1).random((20, 2)), d=np.arange(20.0))
    ok, why = can_render()
    png = snapshot_png(f, tmp_path / "x.png", scalars="d")
    if ok:
        assert png is not None and png.stat().st_size > 1000
    else:
        assert png is None and "unavailable" in why


def test_view_plane_shows_the_two_longest_axes():
    """Snapshots show a 2-D body in its own plane and a 3-D body from the side of its two longest
    axes (the RC beam's quarter model: long in x, deep in z, narrow in y → the x-z plane)."""
    from workbench.fields import view_plane

    assert view_plane((0, 1.0, 0, 0.2, 0, 0)) == (0, 1)
    assert view_plane((0, 0.21, 0, 0.0375, -0.04, 0.16)) == (0, 2)
    assert view_plane((0, 0.01, 0, 0.3, 0, 0.2)) == (1, 2)
