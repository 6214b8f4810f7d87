"""Stop rules as scene data (issue 39 item 2): a :class:`~workbench.scenes.model.Threshold` on an
observable ends a static path at the first load value where it holds and an explicit run
``after`` seconds past the first record where it holds — for the particle methods
(:mod:`sph.stopping`) and the FEM alike. The reference each time is the same run without the rule:
where its recorded observable first crosses the threshold."""
import dataclasses

import numpy as np
import pytest

from fem_reference import solve_model
from sph import driver
from workbench.results import STOPPED
from workbench.scenes import Cantilever, Plate, SceneError
from workbench.scenes import model as M

CANTILEVER = Cantilever(loads=(0.2, 0.4, 0.6, 0.8, 1.0))
PLATE = Plate(periods=1.0)


def solve(method, scene, resolution, drive=None):
    if method == "fem":
        return solve_model(scene, resolution, drive=drive)
    return driver.solve(method, scene, resolution, drive=drive)


@pytest.mark.parametrize("method,resolution", [("csph", 3), ("sph", 3), ("fem", 2)])
def test_a_threshold_ends_a_static_path_at_the_first_value_where_it_holds(method, resolution):
    free = solve(method, CANTILEVER, resolution)
    tip = -np.asarray(free["tip_y"])  # the tip moves down: −u_y grows with the load
    limit = 0.5 * (tip[2] + tip[3])  # crossed between the third and the fourth load value
    drive = dataclasses.replace(CANTILEVER.model().drive, stop=(M.Threshold("tip_y", below=-limit),))
    out = solve(method, CANTILEVER, resolution, drive=drive)
    assert list(out["status"][:4]) == list(free["status"][:4])
    assert list(out["status"][4:]) == [STOPPED]
    assert out["t_threshold"] == pytest.approx(CANTILEVER.loads[3])
    assert out["threshold"] == f"tip_y < {-limit:g}"
    np.testing.assert_allclose(out["tip_y"][:4], free["tip_y"][:4], rtol=1e-9)
    assert np.isnan(out["tip_y"][4])


@pytest.mark.parametrize("method,resolution", [("csph", 4), ("fem", 2)])
@pytest.mark.parametrize("after_records", [0, 3])
def test_a_threshold_ends_an_explicit_run_after_its_delay(method, resolution, after_records):
    drive = PLATE.model().drive
    free = solve(method, PLATE, resolution, drive=dataclasses.replace(drive, n_out=40))
    t, tip = np.asarray(free["time"]), np.asarray(free["tip"])
    limit = 0.5 * float(tip.max())  # the tip swings up to its largest value within the period
    first = int(np.argmax(tip > limit))
    assert 0 < first < len(t) - 5
    after = after_records * float(t[1] - t[0])
    rule = M.Threshold("tip", above=limit, after=after)
    out = solve(method, PLATE, resolution,
                drive=dataclasses.replace(drive, n_out=40, stop=(rule,)))
    assert out["status"] == "ok" and out["criterion"] == "threshold"
    assert out["t_threshold"] == pytest.approx(t[first], rel=1e-9)
    # the run ended at the record ``after`` past the crossing, with the free run's history
    assert out["time"][-1] == pytest.approx(t[first + after_records], rel=1e-9)
    np.testing.assert_allclose(out["tip"], tip[:first + after_records + 1], rtol=1e-9, atol=1e-15)


def test_a_threshold_that_never_holds_changes_nothing():
    drive = dataclasses.replace(PLATE.model().drive, n_out=20)
    free = driver.solve("csph", PLATE, 4, drive=drive)
    out = driver.solve("csph", PLATE, 4, drive=dataclasses.replace(
        drive, stop=(M.Threshold("tip", above=1.0),)))  # a metre: never
    assert out["criterion"] == free["criterion"] == "none"
    assert np.isnan(out["t_threshold"]) and "threshold" not in out
    np.testing.assert_array_equal(out["tip"], free["tip"])


@pytest.mark.parametrize("rule,words", [
    (M.Threshold("nowhere", above=1.0), "stop rule on 'nowhere': no such observable"),
    (M.Threshold("period", above=1.0), "stop rule on 'period': no such observable"),
    (M.Threshold("tip", above=1.0, below=0.0), "give one finite threshold"),
    (M.Threshold("tip"), "give one finite threshold"),
    (M.Threshold("tip", above=float("nan")), "give one finite threshold"),
    (M.Threshold("tip", above=1.0, after=-1.0), "after = -1.0 s is out of range"),
    ("tip > 1", "is not a Threshold"),
])
def test_a_bad_stop_rule_is_one_line_naming_it(rule, words):
    model = PLATE.model()
    with pytest.raises(SceneError, match=words.replace("(", r"\(")):
        dataclasses.replace(model, drive=dataclasses.replace(model.drive, stop=(rule,)))


def test_a_static_stop_rule_has_no_delay():
    model = CANTILEVER.model()
    with pytest.raises(SceneError, match="allowed: 0 on a static path"):
        dataclasses.replace(model, drive=dataclasses.replace(
            model.drive, stop=(M.Threshold("tip_y", below=-1.0, after=1.0),)))


def test_the_explicit_loop_and_its_stop_rules_live_apart():
    """Issue 39 item 2: ``Run.explicit`` is the loop; the records (sph.records) and each stop rule
    (sph.stopping) are their own classes — the loop stays short enough to read whole."""
    import inspect

    src = inspect.getsource(driver.Run.explicit)
    assert len(src.splitlines()) <= 125, len(src.splitlines())
    for name in ("EnergyGrowth", "Disorder(", "separated(", "linear_momentum"):
        assert name not in src, name


SCENE_WITH_A_STOP = '''
from dataclasses import dataclass, field

from workbench.materials import Material
from workbench.scenes import Scene, param
from workbench.scenes.model import (BodyForce, Clamp, Displacement, Explicit, Model, Region, Set,
                                    Threshold)
from workbench.scenes.shapes import Box, Plane, Point


@dataclass(frozen=True)
class Dropping(Scene):
    name: str = field(default="dropping", metadata=dict(hidden=True))
    drop: float = param(2e-3, "m", "tip deflection that ends the run", lo=0, lo_open=True)

    def model(self, spacing=None):
        L, H = 0.16, 0.02
        return Model(
            dim=2, length=H,
            regions=[Region("beam", Box((0.0, -H / 2), (L, H / 2)), Material.svk(1e7, 0.3, 1000.0))],
            sets=[Set("root", Plane(0, 0.0)), Set("tip", Point((L, 0.0)))],
            constraints=[Clamp("root")], loads=[BodyForce((0.0, -9.81))],
            drive=Explicit(t_end=0.25, n_out=50, stop=[Threshold("tip", below=-self.drop)]),
            observables=[Displacement("tip", "tip", 1)])
'''


def test_a_users_scene_stops_on_its_rule_from_the_command_line(tmp_path):
    """The rule reaches the dataset: the run ends early (status ok), ``t_threshold`` says when
    the tip passed 2 mm, and the history stops there (NaN on the dataset's time grid beyond it).
    The static deflection under the weight is q L⁴/(8 E' I) = 2.2 mm (plane strain), the swing
    overshoots to about twice it within half a period (0.04 s): the crossing lies in between."""
    from app import cli
    from workbench import results

    path = tmp_path / "dropping.py"
    path.write_text(SCENE_WITH_A_STOP)
    argv = ["run", str(path), "--solver", "csph", "--resolution", "3", "--out", str(tmp_path)]
    assert cli.main(argv) == 0
    ds = results.read(tmp_path / "dropping.nc")
    run = dict(solver="csph", resolution=3)
    assert str(ds.status.sel(**run).values) == "ok"
    t_stop = float(ds.t_threshold.sel(**run))
    assert 0.0 < t_stop < 0.04
    tip = ds.tip.sel(**run)
    assert np.all(np.isnan(tip.sel(time=slice(t_stop * 1.001, None))))  # the run ended there
    before = tip.sel(time=slice(None, t_stop * 0.999))
    assert np.all(before > -2e-3) and before.size > 3
