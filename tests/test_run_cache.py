"""The one run cache (workbench.runcache, issues 38.1, 39.3, 42.4): keyed by the run spec and the
code that decides the result (the solver's package, the core, the scene's own source file, a user's
scene file included; not the studies), every entry verified before it is served, used by the sweep
and the FEM references alike; the test session has its own cache."""
import hashlib
import logging
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np
import pytest

from studies import common, sweep
from workbench import runcache
from app import cli
from workbench.scenes import Plate

ROOT = Path(__file__).resolve().parent.parent

SCENE_FILE = '''
from dataclasses import dataclass, field

from workbench.materials import Material
from workbench.scenes import Scene, param
from workbench.scenes.model import (BodyForce, Clamp, Displacement, Model, Proportional,
                                    Region, Set, Static)
from workbench.scenes.shapes import Box, Plane, Point


@dataclass(frozen=True)
class MyBeam(Scene):
    """A cantilever under its own weight."""

    name: str = field(default="my_beam", metadata=dict(hidden=True))
    H: float = param(0.02, "m", "thickness", lo=0, lo_open=True)

    def model(self, spacing=None):
        return Model(
            dim=2, length=self.H,
            regions=[Region("beam", Box((0.0, -self.H / 2), ({length}, self.H / 2)),
                            Material.svk(E=1e7, nu=0.3, rho=1000.0))],
            sets=[Set("root", Plane(0, 0.0)), Set("tip", Point(({length}, 0.0)))],
            constraints=[Clamp("root")],
            loads=[BodyForce((0.0, {gravity}), scale=Proportional())],
            drive=Static(path=(1.0,), parameter="gravity factor"),
            observables=[Displacement("tip_deflection", "tip", 1)])
'''


def write_scene(path: Path, length=0.16, gravity=-9.81) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(SCENE_FILE.format(length=length, gravity=gravity))
    return path


CALLS = []


def model_solve(scene, resolution, **options):
    """A stand-in solver whose answer is decided by the scene's model (its geometry and load)."""
    CALLS.append(resolution)
    m = scene.model()
    box = m.regions[0].shape
    return {"status": "ok", "length": float(box.hi[0]) if hasattr(box, "hi") else np.nan,
            "gravity": float(getattr(m.loads[0], "acceleration", (np.nan,) * 2)[1]),
            "series": np.arange(4.0) * resolution}


@pytest.fixture
def cache(monkeypatch, tmp_path):
    monkeypatch.setitem(common.SOLVER_ENTRY, "model_fake", f"{__name__}:model_solve")
    monkeypatch.setenv("WORKBENCH_CACHE", str(tmp_path / "cache"))
    CALLS.clear()
    return tmp_path / "cache" / "runs"


def _task(scene, r=1):
    return sweep.Task.make("model_fake", scene, r)


# -- the key ------------------------------------------------------------------------------------

def test_a_user_scene_file_is_part_of_the_key(cache, tmp_path):
    a = cli.load_scene(str(write_scene(tmp_path / "a" / "my_beam.py", length=0.16)))()
    b = cli.load_scene(str(write_scene(tmp_path / "b" / "my_beam.py", length=0.32)))()
    # the same class name and parameters, another geometry: another key, another answer
    assert type(a).__name__ == type(b).__name__ and a == type(a)() and a.H == b.H
    assert _task(a).key() != _task(b).key()
    out_a, out_b = sweep.run_tasks([_task(a), _task(b)], "serial")
    assert (out_a["length"], out_b["length"]) == (0.16, 0.32) and CALLS == [1, 1]
    assert "cached" not in out_b

    # the same file run again: from the cache
    assert sweep.run_tasks([_task(a)], "serial")[0]["cached"] is True and len(CALLS) == 2
    # the sign of gravity changed in model(): a new key, the new answer, not the stale one
    path = write_scene(tmp_path / "a" / "my_beam.py", length=0.16, gravity=+9.81)
    edited = cli.load_scene(str(path))()
    out = sweep.run_tasks([_task(edited)], "serial")[0]
    assert out["gravity"] == pytest.approx(9.81) and "cached" not in out and len(CALLS) == 3


def test_the_fem_reference_and_the_sweep_share_one_key_rule(tmp_path):
    from fem_reference import cache as fem_cache

    a = cli.load_scene(str(write_scene(tmp_path / "a" / "my_beam.py", length=0.16)))()
    b = cli.load_scene(str(write_scene(tmp_path / "b" / "my_beam.py", length=0.32)))()
    assert fem_cache.record_key(a, 2, {})[0] != fem_cache.record_key(b, 2, {})[0]
    # a sweep's FEM run and an FEM reference of the same spec are the same entry
    assert (sweep.Task.make("fem", Plate(), 2, dynamic=False).key()
            == fem_cache.record_key(Plate(), 2, {"dynamic": False})[0])
    # the particle methods hash sph/ (not fem_reference/), the FEM fem_reference/ (not sph/)
    assert sweep.Task.make("csph", Plate(), 2).key() != sweep.Task.make("fem", Plate(), 2).key()


KEY_SCRIPT = """
from studies import sweep
from workbench.scenes import Plate
print(sweep.Task.make("csph", Plate(), 3).key(), sweep.Task.make("fem", Plate(), 3).key())
"""


def _keys(root: Path) -> tuple[str, str]:
    env = dict(os.environ, PYTHONPATH=str(root), NUMBA_DISABLE_JIT="1")
    p = subprocess.run([sys.executable, "-c", KEY_SCRIPT], cwd=root, env=env, capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return tuple(p.stdout.split())


def test_the_key_covers_the_solver_and_the_core_not_the_studies(tmp_path):
    """Edits in a copy of the packages: a study's caption keeps every key; an edit in sph/ changes
    the particle methods' keys only, one in the core (workbench/) every key, one in the
    application none."""
    root = tmp_path / "copy"
    for pkg in ("workbench", "sph", "fem_reference", "studies", "app"):
        shutil.copytree(ROOT / pkg, root / pkg, ignore=shutil.ignore_patterns("__pycache__"))

    def edit(rel):
        with open(root / rel, "a") as fh:
            fh.write("\n# an edit\n")

    k0 = _keys(root)
    edit("studies/plate.py")
    edit("app/report.py")
    assert _keys(root) == k0
    edit("sph/csph.py")
    k1 = _keys(root)
    assert k1[0] != k0[0] and k1[1] == k0[1]
    edit("workbench/results.py")
    k2 = _keys(root)
    assert k2[0] != k1[0] and k2[1] != k1[1]


# -- every entry verified before it is served ------------------------------------------------------

def _entry(cache) -> Path:
    files = list(cache.glob("*.pkl"))
    assert len(files) == 1, files
    return files[0]


def _flip_bit(p: Path) -> None:
    blob = bytearray(p.read_bytes())
    blob[-20] ^= 0x04  # a bit inside the pickled result (a number of the series)
    p.write_bytes(bytes(blob))


def _truncate(p: Path) -> None:
    p.write_bytes(p.read_bytes()[:-30])


def _wrong_shape(p: Path) -> None:
    # a well-formed entry whose result is not a run's result dict (an empty list)
    key = p.stem
    payload = pickle.dumps((key, []))
    p.write_bytes(runcache.MAGIC + hashlib.sha256(payload).hexdigest().encode() + b"\n" + payload)


def _empty_dict(p: Path) -> None:
    payload = pickle.dumps((p.stem, {}))
    p.write_bytes(runcache.MAGIC + hashlib.sha256(payload).hexdigest().encode() + b"\n" + payload)


def _old_plain_pickle(p: Path) -> None:
    p.write_bytes(pickle.dumps({"status": "ok"}))  # the old format: an unverified dict


@pytest.mark.parametrize("damage", [_flip_bit, _truncate, _wrong_shape, _empty_dict,
                                    _old_plain_pickle])
def test_a_damaged_entry_is_discarded_and_recomputed(damage, cache, caplog):
    task = _task(Plate(), 3)
    good = sweep.run_tasks([task], "serial")[0]
    damage(_entry(cache))
    with caplog.at_level(logging.WARNING, logger="workbench"):
        out = sweep.run_tasks([task], "serial")[0]
    assert CALLS == [3, 3]  # recomputed, not served
    assert "cached" not in out and np.array_equal(out["series"], good["series"])
    warned = [r.getMessage() for r in caplog.records if "run cache" in r.getMessage()]
    assert len(warned) == 1 and "discarded" in warned[0] and "\n" not in warned[0]
    # the recomputed run is stored whole again, and served from now on
    again = sweep.run_tasks([task], "serial")[0]
    assert again["cached"] is True and np.array_equal(again["series"], good["series"])
    assert CALLS == [3, 3]


def test_an_fem_reference_is_verified_before_it_is_read(monkeypatch, tmp_path):
    import fem_reference
    from fem_reference import cache as fem_cache

    monkeypatch.setenv("WORKBENCH_CACHE", str(tmp_path))
    sc = Plate()
    T = fem_reference.reference(sc, "period", resolution=2)
    entry = tmp_path / "runs" / f"{fem_cache.record_key(sc, 2, {'dynamic': False})[0]}.pkl"
    assert entry.exists()
    _truncate(entry)
    calls = []
    real = fem_reference.model.solve
    monkeypatch.setattr(fem_reference.model, "solve",
                        lambda *a, **k: calls.append(1) or real(*a, **k))
    assert fem_reference.reference(sc, "period", resolution=2) == pytest.approx(T, rel=1e-12)
    assert calls == [1]


# -- the test session's own cache ---------------------------------------------------------------

def test_the_test_session_has_its_own_cache():
    from workbench import results

    where = os.environ.get("WORKBENCH_CACHE")
    user = os.path.join(os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")),
                        "particle-workbench")
    assert where and Path(where).resolve() != Path(user).resolve()
    assert Path(where).resolve().is_relative_to(Path(tempfile.gettempdir()).resolve())
    assert runcache.cache_dir() == Path(where) / "runs"
    assert results.fallback_dir() == Path(where) / "unsaved" or os.environ.get("WORKBENCH_FALLBACK")
