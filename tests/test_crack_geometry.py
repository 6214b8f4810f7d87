"""The crack path of failed particles (workbench.crack_geometry.crack_path) on constructed cracks
of known geometry: straight and kinked, 2-D and 3-D, lattice staircases and noisy positions."""
from __future__ import annotations

import math

import numpy as np
import pytest

from workbench.crack_geometry import crack_path

DX = 0.01


def band(origin, direction, length, half_width, dx=DX, dim=2):
    """The lattice points (spacing dx) within ``half_width`` of the segment from ``origin`` along
    ``direction`` of ``length``: a crack band as a lattice staircase."""
    o = np.asarray(origin, float)
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    n = int(math.ceil((length + 2 * half_width) / dx)) + 2
    axes = [np.arange(-n, n + 1) * dx + o[k] for k in range(dim)]
    P = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], 1)
    s = (P - o) @ u
    perp = np.linalg.norm(P - o - np.outer(s, u), axis=1)
    return P[(s > 0) & (s <= length) & (perp <= half_width)]


@pytest.mark.parametrize("theta", [0.0, 30.0, -70.5, 115.0])
def test_straight_band_2d(theta):
    """A straight band two spacings wide at angle θ from the x axis, from the origin to
    L = 40 Δx: the tip within one spacing of the band's end (a staircase resolves the end to a
    spacing), the length within 1.5 spacings, the angle from +x within atan(1/20) (one spacing of
    staircase over the half of the path the direction is fitted on) — ~3°."""
    o = np.array([0.013, -0.02])
    u = np.array([math.cos(math.radians(theta)), math.sin(math.radians(theta))])
    L = 40 * DX
    p = crack_path(band(o, u, L, DX), o, 2 * DX, reference=(1.0, 0.0))
    assert np.linalg.norm(p.tip - (o + L * u)) < DX
    assert abs(p.length - L) < 1.5 * DX
    assert abs(p.angle - theta) < math.degrees(math.atan(1 / 20))


def test_kinked_crack_2d():
    """A pre-crack along +x ends at the origin; the crack kinks there by 70.5° (Erdogan–Sih) and
    runs 30 Δx: the kink angle is 70.5° within 3°, the tip at the end, the path's points on the
    kinked line within a spacing; isolated failed points far away (spurious damage at an edge)
    do not belong to the crack."""
    o = np.zeros(2)
    th = math.radians(70.5)
    u = np.array([math.cos(th), math.sin(th)])
    L = 30 * DX
    pts = band(o, u, L, 0.8 * DX)
    stray = np.array([[0.5, -0.3], [0.51, -0.3], [-0.4, 0.2]])
    p = crack_path(np.vstack([pts, stray]), o, 2 * DX, reference=(1.0, 0.0))
    assert abs(p.angle - 70.5) < 3.0
    assert np.linalg.norm(p.tip - L * u) < DX
    perp = np.abs(p.path[:, 0] * u[1] - p.path[:, 1] * u[0])
    assert perp.max() < DX
    assert len(p.members) == len(pts)  # the stray points left out


def test_kinked_at_a_later_point_keeps_the_initial_direction():
    """A crack growing straight ahead 20 Δx and then turning by 45° for 20 Δx: the direction of
    growth (the first half of the path) is straight ahead within 3°, the length is the sum of the
    legs within two spacings, the tip at the second leg's end within a spacing."""
    o = np.zeros(2)
    L1, L2 = 20 * DX, 20 * DX
    u2 = np.array([math.cos(math.pi / 4), math.sin(math.pi / 4)])
    knee = np.array([L1, 0.0])
    pts = np.vstack([band(o, (1, 0), L1, DX), band(knee, u2, L2, DX)])
    pts = np.unique(np.round(pts / DX).astype(int), axis=0) * DX
    p = crack_path(pts, o, 2 * DX, reference=(1.0, 0.0))
    assert abs(p.angle) < 3.0
    assert abs(p.length - (L1 + L2)) < 2 * DX
    assert np.linalg.norm(p.tip - (knee + L2 * u2)) < DX


def test_noisy_positions():
    """Positions jittered by ±0.3 Δx (a disordered arrangement): the same tolerances as a clean
    straight band."""
    rng = np.random.default_rng(0)
    o = np.zeros(2)
    th = math.radians(25.0)
    u = np.array([math.cos(th), math.sin(th)])
    L = 40 * DX
    pts = band(o, u, L, DX)
    pts = pts + rng.uniform(-0.3 * DX, 0.3 * DX, pts.shape)
    p = crack_path(pts, o, 2 * DX, reference=(1.0, 0.0))
    assert np.linalg.norm(p.tip - (o + L * u)) < 1.3 * DX
    assert abs(p.length - L) < 2 * DX
    assert abs(p.angle - 25.0) < 3.0


def test_tube_3d():
    """3-D: a crack band (a tube of radius Δx on the lattice) leaving the origin at 60° from a
    reference direction, 30 Δx long: the tip, the length and the (unsigned) angle."""
    o = np.array([0.1, 0.2, 0.3])
    ref = np.array([1.0, 0.0, 0.0])
    u = np.array([0.5, math.sqrt(3) / 2 * 0.6, math.sqrt(3) / 2 * 0.8])  # 60° from ref
    L = 30 * DX
    p = crack_path(band(o, u, L, DX, dim=3), o, 2 * DX, reference=ref)
    assert np.linalg.norm(p.tip - (o + L * u)) < 1.5 * DX
    assert abs(p.length - L) < 1.5 * DX
    assert abs(p.angle - 60.0) < 3.0


def test_planar_front_3d():
    """3-D: a planar crack grown from a straight front through the origin (failed particles of a
    slab 8 Δx across the front, one spacing thick, 20 Δx ahead, kinked 30° out of the
    pre-crack's plane): the centreline runs along the middle of the front, the tip 20 Δx ahead."""
    o = np.zeros(3)
    th = math.radians(30.0)
    ahead = np.array([math.cos(th), 0.0, math.sin(th)])
    n = 40
    g = np.arange(-n, n + 1) * DX
    P = np.stack([c.ravel() for c in np.meshgrid(g, g, g, indexing="ij")], 1)
    s = P @ ahead
    normal = np.cross(ahead, (0.0, 1.0, 0.0))
    sel = (s > 0) & (s <= 20 * DX) & (np.abs(P[:, 1]) <= 4 * DX) & (np.abs(P @ normal) <= 0.5 * DX)
    p = crack_path(P[sel], o, 2 * DX, reference=(1.0, 0.0, 0.0))
    assert abs(p.angle - 30.0) < 3.0
    assert np.linalg.norm(p.tip - 20 * DX * ahead) < 1.5 * DX
    assert np.abs(p.path[:, 1]).max() < 0.5 * DX


def test_nothing_failed():
    """No failed particle (or none linked to the origin): the tip is the origin, length 0, no
    angle."""
    o = np.array([0.2, 0.1])
    for pts in (np.zeros((0, 2)), np.array([[0.9, 0.9]])):
        p = crack_path(pts, o, 2 * DX, reference=(1.0, 0.0))
        assert np.array_equal(p.tip, o) and p.length == 0.0 and math.isnan(p.angle)


# ------------------------------------------------------------------------------------------------
# The CrackTip observable end to end
# ------------------------------------------------------------------------------------------------

def _notched_scene():
    from dataclasses import dataclass, field

    from workbench.materials import Material
    from workbench.scenes import model as M
    from workbench.scenes import shapes as S
    from workbench.scenes.params import Scene

    @dataclass(frozen=True)
    class Notched(Scene):
        """A 1 cm J2-damage plate with an edge pre-crack to 3 mm, pulled apart at 10 m/s."""

        name: str = field(default="notched", metadata=dict(hidden=True))

        def model(self, spacing=None):
            L = 0.01
            dx = L / 20 if spacing is None else spacing
            mat = Material.j2_linear(200e9, 0.3, 400e6, 1e9, 7850.0, eps_L=0.05)
            y = 0.5 * L + 0.25 * dx  # between two lattice rows
            return M.Model(
                dim=2, length=L, regions=(M.Region("plate", S.Box((0, 0), (L, L)), mat),),
                cracks=(M.PreCrack("notch", ((-0.001, y), (0.3 * L, y))),),
                sets=(M.Set("top", S.Plane(1, L)), M.Set("bottom", S.Plane(1, 0.0))),
                constraints=(M.Prescribed("top", 1, velocity=10.0),
                             M.Prescribed("bottom", 1, velocity=-10.0)),
                drive=M.Explicit(t_end=1.6e-5, n_out=16),
                observables=(M.CrackTip("tip", "notch"),))

    return Notched()


def test_crack_tip_observable_end_to_end():
    """A short csph run of a notched J2-damage plate pulled apart: the CrackTip records start at
    the pre-crack's tip (nothing failed), the crack grows from it, the last record is the path of
    the run's final failed particles (the returned state, measured again here), and the speed is
    the length's difference quotient."""
    from sph.driver import solve

    sc = _notched_scene()
    out = solve("csph", sc, 20)
    assert out["status"] == "ok"
    dx = 0.01 / 20
    y = 0.005 + 0.25 * dx
    assert out["tip_x"][0] == pytest.approx(0.003) and out["tip_y"][0] == pytest.approx(y)
    assert out["tip_length"][0] == 0.0 and math.isnan(out["tip_angle"][0])
    failed = out["failed_particles"]
    assert failed.any()
    p = crack_path(out["X"][failed], (0.003, y), 2 * dx, reference=(1.0, 0.0))
    assert p.length >= 2 * dx and p.tip[0] > 0.003 + dx  # grown ahead of the pre-crack
    last = [out[f"tip_{k}"][-1] for k in ("x", "y", "length", "angle")]
    assert last == pytest.approx([*p.tip, p.length, p.angle], rel=1e-12)
    v = np.diff(out["tip_length"]) / np.diff(out["time"])
    assert np.allclose(out["tip_speed"][1:], v) and out["tip_speed"][0] == 0.0


def test_crack_tip_checks():
    from workbench.materials import Material
    from workbench.scenes import model as M
    from workbench.scenes import shapes as S
    from workbench.scenes.params import SceneError

    def mk(o):
        return M.Model(dim=2, length=1.0,
                       regions=(M.Region("p", S.Box((0, 0), (1, 1)), Material.svk(1e9, 0.3)),),
                       drive=M.Explicit(1e-3), observables=(o,))

    with pytest.raises(SceneError, match="origin 'nope' is not a PreCrack"):
        mk(M.CrackTip("tip", "nope"))
    with pytest.raises(SceneError, match="origin .* is not allowed"):
        mk(M.CrackTip("tip", (0.1, 0.2, 0.3)))
    with pytest.raises(SceneError, match="spacing"):
        mk(M.CrackTip("tip", (0.1, 0.2), spacing=0.0))
    assert [n for n, _ in M.CrackTip("t", (0, 0)).outputs(2)] == [
        "t_x", "t_y", "t_length", "t_angle", "t_speed"]


def test_crack_tip_in_the_scene_dataset():
    """The generic scene study stores a CrackTip's histories as variables of the run's dataset,
    each with its units, on the drive's common time grid (the driver's records: n_out = 16 over
    t_end, so the grid is the records' times)."""
    from sph.driver import solve
    from studies import scene as study

    sc = _notched_scene()
    ds = study.run(sc, solvers=["csph"], resolutions=[20])
    units = {"tip_x": "m", "tip_y": "m", "tip_length": "m", "tip_angle": "deg", "tip_speed": "m/s"}
    for n, u in units.items():
        assert ds[n].attrs["units"] == u
    out = solve("csph", sc, 20)
    got = ds["tip_length"].sel(solver="csph", resolution=20).values
    assert np.allclose(got, np.interp(ds["time"].values, out["time"], out["tip_length"]))


def test_crack_path_in_the_result_and_the_dataset():
    """The path at the last record: in the driver's result (origin first, tip last) and, padded,
    in the generic study's dataset."""
    from sph.driver import solve
    from studies import scene as study

    sc = _notched_scene()
    out = solve("csph", sc, 20)
    path = out["tip_path"]
    assert np.allclose(path[-1], [out["tip_x"][-1], out["tip_y"][-1]])
    assert np.allclose(path[0], [0.003, 0.005 + 0.25 * 0.01 / 20])
    ds = study.run(sc, solvers=["csph"], resolutions=[20])
    p = ds["tip_path"].sel(solver="csph", resolution=20).values
    assert np.allclose(p[:len(path)], path) and np.isnan(p[len(path):]).all()
