"""Reliability (issue 14): every bad input is refused before any work with one line and exit
status 2; no finished work is lost (run cache, fallback folder, resume after an interrupt or a
kill, fsync before the rename); progress and the solver's own wall time."""
import contextlib
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from studies import common, sweep
from workbench import progress, results
from app import cli
from workbench.scenes import Plate


def _refused(argv, capsys, monkeypatch, needle):
    """cli.main(argv) exits 2 with one line containing ``needle``, no study started."""
    import app.verify as verify

    def no_work(*a, **k):
        raise AssertionError("work started before the input was checked")

    monkeypatch.setattr(verify, "run_study", no_work)
    monkeypatch.setattr(verify, "verify", no_work)
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    return err


@pytest.mark.parametrize("argv,needle", [
    (["run", "cantilever", "--set", "loads="], "loads: the list is empty; allowed: one or more"),
    (["run", "ss_curve", "--set", "E=1e400"], "E: 1e400 overflows to inf"),
    (["run", "ss_curve", "--set", "E=nan"], "E: nan is not a finite number"),
    (["run", "ss_curve", "--set", "eps_L=-inf"], "eps_L: -inf is not a finite number"),
    (["run", "plate", "--set", "V_f=inf"], "V_f: inf"),
    (["run", "ss_curve", "--budget", "inf"], "--budget: inf is out of range"),
    (["run", "ss_curve", "--scheduler", "nonsense"], "--scheduler: 'nonsense' is not allowed"),
])
def test_bad_values_are_refused_before_work(argv, needle, capsys, monkeypatch):
    err = _refused(argv, capsys, monkeypatch, needle)
    name = needle.split(":")[0]
    assert err.removeprefix("workbench: error: ").startswith(name), err  # names the parameter first


def test_unreachable_scheduler_is_one_line(capsys, monkeypatch):
    import socket

    with socket.socket() as s:  # a port nobody listens on (bound, never listening)
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        for argv in (["verify", "--scheduler", f"tcp://127.0.0.1:{port}"],
                     ["run", "ss_curve", "--scheduler", f"127.0.0.1:{port}"]):
            err = _refused(argv, capsys, monkeypatch, f"--scheduler: cannot reach tcp://127.0.0.1:{port}")
            assert "Connection refused" in err or "no answer" in err


@pytest.mark.parametrize("where", ["/proc/forbidden", "a_file"])
def test_unwritable_output_folder_is_refused_before_work(where, tmp_path, capsys, monkeypatch):
    if where == "a_file":
        where = tmp_path / "a_file"
        where.write_text("not a folder")
    for argv in (["run", "ss_curve", "--out", str(where)], ["verify", "--out", str(where)]):
        err = _refused(argv, capsys, monkeypatch, "cannot be written")
        assert err.removeprefix("workbench: error: ").startswith("--out: ") and str(where) in err, err


def test_resolution_beyond_the_machine_memory_is_refused(capsys, monkeypatch):
    err = _refused(["run", "plate", "--resolution", "1000000"], capsys, monkeypatch,
                   "resolution: 1000000 needs about")
    assert "this machine has" in err and "allowed: integers in [1, " in err
    # the largest resolution it names does fit
    r_max = int(err.rsplit("[1, ", 1)[1].split("]")[0])
    need = common.estimate_bytes("csph", Plate(), r_max)[0]
    assert need <= common.machine_memory() < common.estimate_bytes("csph", Plate(), 4 * r_max)[0]


def test_memory_estimate_counts_the_particles():
    # independent count: the particles the discretisation actually makes (node lattice, the held
    # clamp block and the plate share the face X = 0: the estimate counts it twice, ~10/1342)
    from sph.driver import model_at
    from sph.particles import discretise

    for r in (5, 10):
        model, _ = model_at(Plate(), r)
        n = discretise(model, r, None).n
        est, dim = common.estimate_points(Plate(), r, "csph")
        assert dim == 2 and abs(est - n) / n < 0.02


def test_machine_memory_is_read():
    assert 2 ** 26 < common.machine_memory() < 2 ** 62


def test_tiny_tip_velocity_does_not_crash(tmp_path, capsys, monkeypatch):
    # V_f = 1e-300: the energies are round-off; the stability criterion itself is issue 13's
    # (sph/monitor.py). Here only: no traceback, a status per run, exit 0 or 1.
    monkeypatch.setenv("WORKBENCH_CACHE", str(tmp_path / "cache"))
    code = cli.main(["run", "plate", "--set", "V_f=1e-300", "--set", "periods=0.05", "--solver",
                     "csph", "--resolution", "3", "--quick", "--out", str(tmp_path)])
    out = capsys.readouterr()
    assert code in (0, 1) and "Traceback" not in out.err and out.err.count("\n") <= 1
    ds = results.read(tmp_path / "plate.nc")
    status = str(ds.status.sel(solver="csph", resolution=3).values)
    assert status.startswith(("ok", "unstable"))
    assert code == (0 if status.startswith("ok") else 1)


# -- no lost work ------------------------------------------------------------------------------

CALLS = []


def fake_solve(scene, resolution, **options):
    CALLS.append(resolution)
    if options.get("interrupt_at") == resolution:
        raise KeyboardInterrupt
    if options.get("exit_at") == resolution:
        os._exit(137)  # a kill: no clean-up of any kind
    return {"period": scene.L * resolution, "status": "ok"}


@pytest.fixture
def fake_solver(monkeypatch, tmp_path):
    monkeypatch.setitem(common.SOLVER_ENTRY, "fake", f"{__name__}:fake_solve")
    monkeypatch.setenv("WORKBENCH_CACHE", str(tmp_path / "cache"))
    CALLS.clear()
    return tmp_path / "cache"


def test_interrupted_sweep_resumes_from_the_cache(fake_solver):
    tasks = [sweep.Task.make("fake", Plate(), r, interrupt_at=2) for r in (1, 2, 3)]
    with pytest.raises(KeyboardInterrupt):
        sweep.run_tasks(tasks, "serial")
    assert CALLS == [1, 2]
    # the same sweep, not interrupted this time (its key must not change: a task option that
    # never fires again stands for "the user pressed Ctrl-C")
    import studies.sweep as sw

    CALLS.clear()
    with sw.recording() as rec:
        out = sw.run_tasks(tasks[:1] + [sweep.Task.make("fake", Plate(), r) for r in (2, 3)], "serial")
    assert CALLS == [2, 3]  # the finished run was not recomputed
    assert out[0]["cached"] is True and out[0]["period"] == pytest.approx(0.2)
    assert [r["cached"] for r in rec] == [True, False, False]


def test_killed_sweep_resumes_from_the_cache(fake_solver, tmp_path):
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {os.path.dirname(os.path.dirname(os.path.abspath(__file__)))!r})
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        from studies import common, sweep
        from workbench.scenes import Plate
        common.SOLVER_ENTRY["fake"] = "test_reliability:fake_solve"
        sweep.run_tasks([sweep.Task.make("fake", Plate(), r, exit_at=9) for r in (1, 9)], "serial")
    """)
    env = dict(os.environ, WORKBENCH_CACHE=str(fake_solver))
    p = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True)
    assert p.returncode == 137, p.stderr
    assert len(list((fake_solver / "runs").glob("*.pkl"))) == 1  # the finished run, whole
    assert not list((fake_solver / "runs").glob("*.tmp"))
    tasks = [sweep.Task.make("fake", Plate(), r, exit_at=9) for r in (1,)]
    out = sweep.run_tasks(tasks, "serial")
    assert CALLS == [] and out[0]["cached"] is True


def interrupt_solve(scene, resolution, **options):
    """A solver in which the user presses Ctrl-C at ``resolution == options['at']``, and which
    then does what compiled code or a careless solver does with it: ``wrap`` turns it into a
    SystemError (numba: 'returned a result with an exception set'), ``swallow`` into an error
    status."""
    CALLS.append(resolution)
    if resolution == options["at"]:
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)  # the handler runs here
        except KeyboardInterrupt as err:
            if options["how"] == "wrap":
                raise SystemError("<numba dispatcher> returned a result with an exception set") from err
            return {"status": "error: SystemError: returned a result with an exception set"}
    return {"period": float(resolution), "status": "ok"}


@pytest.mark.parametrize("how", ["wrap", "swallow"])
def test_ctrl_c_turned_into_an_error_still_stops_the_sweep(how, fake_solver, monkeypatch):
    monkeypatch.setitem(common.SOLVER_ENTRY, "interrupt", f"{__name__}:interrupt_solve")
    tasks = [sweep.Task.make("interrupt", Plate(), r, at=2, how=how) for r in (1, 2, 3)]
    with pytest.raises(KeyboardInterrupt):
        sweep.run_tasks(tasks, "serial")
    assert CALLS == [1, 2]  # stopped: the third run never started
    assert len(list((fake_solver / "runs").glob("*.pkl"))) == 1  # the finished run is kept
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # handler restored
    assert not common.interrupted()


def test_interrupted_recognises_a_wrapped_keyboard_interrupt():
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as ki:
            raise SystemError("returned a result with an exception set") from ki
    except SystemError as err:
        assert common.interrupted(err)
    assert not common.interrupted(SystemError("another cause"))


SPIN_SCRIPT = """
import sys, time
sys.path.insert(0, {root!r})
import numba
from studies import common, sweep
import app.verify as verify
from app import cli
from workbench.scenes import Plate


@numba.njit
def spin(n):
    s = 0.0
    for i in range(n):
        s += (i % 7) * 1e-9
    return s


def spin_solve(scene, resolution, **options):
    print("run", resolution, flush=True)
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < (0.2 if resolution == 1 else 60.0):
        spin(20_000_000)  # ~20 ms of compiled loop per call
    return {{"status": "ok", "period": 1.0}}


spin(10)  # compiled before the sweep
common.SOLVER_ENTRY["spin"] = "__main__:spin_solve"
verify.run_study = lambda *a, **k: sweep.run_tasks(
    [sweep.Task.make("spin", Plate(), r) for r in (1, 2, 3)], "serial")
sys.exit(cli.main(["run", "ss_curve", "--solver", "analytic", "--out", {out!r}]))
"""


def test_ctrl_c_during_a_compiled_loop_exits_130(tmp_path):
    """A real SIGINT to a process running a numba loop inside a sweep: the sweep stops, the
    finished run is kept, exit status 130 and one 'interrupted' line."""
    script = tmp_path / "spin.py"
    script.write_text(SPIN_SCRIPT.format(root=str(Path(__file__).resolve().parent.parent),
                                         out=str(tmp_path / "out")))
    env = dict(os.environ, WORKBENCH_CACHE=str(tmp_path / "cache"))
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    try:
        lines = []
        for line in p.stdout:
            lines.append(line.strip())
            if line.strip() == "run 2":
                break
        time.sleep(0.5)  # inside the compiled loop of the second run
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert lines == ["run 1", "run 2"] and "run 3" not in out, (lines, out)
    assert p.returncode == 130, err
    assert err.strip().count("\n") == 0 and "interrupted" in err and "Traceback" not in err, err
    assert len(list((tmp_path / "cache" / "runs").glob("*.pkl"))) == 1


def test_ctrl_c_in_the_cli_says_how_to_resume(tmp_path, capsys, monkeypatch):
    import app.verify as verify

    monkeypatch.setenv("WORKBENCH_CACHE", str(tmp_path / "cache"))

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(verify, "run_study", interrupted)
    assert cli.main(["run", "ss_curve", "--solver", "analytic", "--out", str(tmp_path)]) == 130
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "run the same command again to resume" in err
    assert str(tmp_path / "cache") in err


def test_failed_write_saves_the_dataset_elsewhere(tmp_path, capsys, monkeypatch):
    out_dir = tmp_path / "out"
    monkeypatch.setenv("WORKBENCH_FALLBACK", str(tmp_path / "fallback"))
    real = results._write_atomic

    def disk_full(ds, path):
        if path.parent == out_dir:
            raise OSError(28, "No space left on device")
        return real(ds, path)

    monkeypatch.setattr(results, "_write_atomic", disk_full)
    code = cli.main(["run", "ss_curve", "--solver", "analytic", "--out", str(out_dir)])
    err = capsys.readouterr().err.strip()
    assert code == 1 and len(err.splitlines()) == 1 and "Traceback" not in err
    saved = list((tmp_path / "fallback").glob("ss_curve-*.nc"))
    assert len(saved) == 1 and str(saved[0]) in err and "No space left" in err
    ds = results.read(saved[0])
    assert ds.stress.sel(solver="analytic").max() > 6e8  # the whole dataset (Swift curve ~700 MPa)
    assert not list(out_dir.glob("*.nc")) and not list(out_dir.glob(".*.tmp"))


@contextlib.contextmanager
def small_filesystem(where):
    """A real 200 kB file system (tmpfs) mounted at ``where``; yields None where this machine
    does not permit mounting (the caller then injects the libraries' own exceptions). Unmounted
    at the end."""
    where.mkdir(parents=True, exist_ok=True)
    try:
        p = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(where)],
                           capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        p = None
    if p is None or p.returncode != 0:
        yield None
        return
    try:
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], capture_output=True, timeout=30)


def fill(folder, leave=0):
    """Fill ``folder``'s file system up to ENOSPC, then free ``leave`` bytes."""
    filler = folder / "filler"
    with open(filler, "wb", buffering=0) as fh:
        try:
            while True:
                fh.write(b"\0" * 4096)
        except OSError:
            pass
    size = filler.stat().st_size
    with open(filler, "r+b") as fh:
        fh.truncate(max(size - leave, 0))


def _disk_full_error(kind, out_dir, monkeypatch, what):
    """Make every write of ``what`` ('dataset' or 'figure') into ``out_dir`` fail as the library
    does on a full disk: netCDF4's RuntimeError('NetCDF: HDF error'), or an OSError (ENOSPC)."""
    import errno

    import matplotlib.figure
    import xarray as xr

    def boom():
        if kind == "RuntimeError":
            return RuntimeError("NetCDF: HDF error")
        return OSError(errno.ENOSPC, "No space left on device")

    if what == "dataset":
        real = xr.Dataset.to_netcdf

        def to_netcdf(self, path=None, *a, **k):
            if path is not None and Path(path).parent == out_dir:
                raise boom()
            return real(self, path, *a, **k)

        monkeypatch.setattr(xr.Dataset, "to_netcdf", to_netcdf)
    else:
        real_save = matplotlib.figure.Figure.savefig

        def savefig(self, fname, *a, **k):
            if Path(fname).parent == out_dir:
                raise boom()
            return real_save(self, fname, *a, **k)

        monkeypatch.setattr(matplotlib.figure.Figure, "savefig", savefig)


@pytest.mark.parametrize("kind", ["tmpfs", "RuntimeError", "OSError"])
def test_full_disk_saves_the_dataset_elsewhere(kind, tmp_path, capsys, monkeypatch):
    """A dataset that cannot be written on a full disk reaches the fallback (netCDF raises
    RuntimeError there, not OSError): one line naming where the data went, exit 1."""
    monkeypatch.setenv("WORKBENCH_FALLBACK", str(tmp_path / "fallback"))
    with small_filesystem(tmp_path / "small") as small:
        if kind == "tmpfs":
            if small is None:
                pytest.skip("mounting a tmpfs is not permitted here (the injected cases run)")
            out_dir = small / "out"
            out_dir.mkdir()
            fill(small, leave=8192)  # room for the probe file, not for the ~23 kB dataset
        else:
            out_dir = tmp_path / "out"
            _disk_full_error(kind, out_dir, monkeypatch, "dataset")
        code = cli.main(["run", "ss_curve", "--solver", "analytic", "--out", str(out_dir)])
        err = capsys.readouterr().err.strip()
        assert code == 1 and len(err.splitlines()) == 1 and "Traceback" not in err, err
        saved = list((tmp_path / "fallback").glob("ss_curve-*.nc"))
        assert len(saved) == 1 and str(saved[0]) in err, err
        assert ("HDF error" in err or "No space left" in err), err
        ds = results.read(saved[0])
        assert ds.stress.sel(solver="analytic").max() > 6e8  # the whole dataset (Swift ~700 MPa)
        assert not list(out_dir.glob("*.nc")) and not list(out_dir.glob(".*.tmp"))


@pytest.mark.parametrize("kind", ["tmpfs", "RuntimeError", "OSError"])
def test_full_disk_for_the_figures_names_the_dataset(kind, tmp_path, capsys, monkeypatch):
    """The dataset was written, then the disk filled up: the figure's failure is one line that
    says where the dataset is, exit 1, no traceback."""
    with small_filesystem(tmp_path / "small") as small:
        if kind == "tmpfs":
            if small is None:
                pytest.skip("mounting a tmpfs is not permitted here (the injected cases run)")
            out_dir = small / "out"
            real_write = results.write

            def write_then_fill(ds, path, *a, **k):
                where = real_write(ds, path, *a, **k)
                fill(small)
                return where

            monkeypatch.setattr(results, "write", write_then_fill)
        else:
            out_dir = tmp_path / "out"
            _disk_full_error(kind, out_dir, monkeypatch, "figure")
        code = cli.main(["run", "ss_curve", "--solver", "analytic", "--out", str(out_dir)])
        err = capsys.readouterr().err.strip()
        assert code == 1 and len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert "figures of ss_curve could not be written" in err
        assert f"the dataset was saved to {out_dir / 'ss_curve.nc'}" in err
        assert results.read(out_dir / "ss_curve.nc").stress.sel(solver="analytic").max() > 6e8


def test_files_are_synced_before_the_rename(tmp_path, monkeypatch):
    import xarray as xr

    events = []
    real_fsync, real_replace = os.fsync, os.replace
    monkeypatch.setattr(os, "fsync", lambda fd: (events.append("fsync"), real_fsync(fd))[1])
    monkeypatch.setattr(os, "replace", lambda a, b: (events.append("replace"), real_replace(a, b))[1])
    ds = xr.Dataset({"x": (("i",), np.arange(3.0), {"units": "m"})})
    results.write(ds, tmp_path / "x.nc")
    assert events[:2] == ["fsync", "replace"]
    events.clear()
    results.atomic_write_text(tmp_path / "r.md", "text")
    assert events[:2] == ["fsync", "replace"]


# -- progress and wall time ----------------------------------------------------------------------

def test_sweep_progress_bar_only_on_a_terminal(fake_solver, capsys, monkeypatch):
    tasks = [sweep.Task.make("fake", Plate(), r) for r in (1, 2)]
    monkeypatch.delenv("WORKBENCH_PROGRESS", raising=False)
    sweep.run_tasks(tasks, "serial", title="quiet")
    assert "quiet" not in capsys.readouterr().err  # pytest's stderr is not a terminal
    monkeypatch.setenv("WORKBENCH_PROGRESS", "1")
    sweep.run_tasks(tasks, "serial", title="shown")
    err = capsys.readouterr().err
    assert "shown" in err and "2/2" in err and "run" in err


def test_jit_estimate_subtracts_the_first_chunk_overhead():
    # first chunk: 10 steps in 5 s; later: 100 steps in 1 s (0.01 s a step) -> 5 - 0.1 s of JIT
    from sph.driver import jit_estimate

    assert jit_estimate(5.0, 10, 1.0, 100) == pytest.approx(4.9)
    assert jit_estimate(0.05, 10, 1.0, 100) == 0.0  # never negative
    assert jit_estimate(5.0, 10, 0.0, 0) == 0.0  # no later chunk: nothing to measure against


def test_driver_reports_its_own_time_apart_from_setup_and_jit():
    from sph import driver

    out = driver.solve("csph", Plate(periods=0.05), 3)
    assert out["status"] == "ok"
    assert 0 <= out["jit_time"] <= out["loop_time"]
    assert out["wall_time"] == pytest.approx(out["loop_time"] - out["jit_time"])
    assert out["total_time"] >= out["setup_time"] + out["loop_time"]


# -- errors inside a user's scene file -----------------------------------------------------------

@pytest.mark.parametrize("edit,cause", [
    (("length=self.H,", "length=self.H + undefined_name,"), "NameError: name 'undefined_name'"),
    (("rho=1000.0", "rho=-1000.0"), "ValueError: rho: -1000.0 kg/m^3 is not allowed"),
    (("nu=0.3", "nu=0.5"), "ValueError: nu: 0.5 is not allowed"),
    (("def model(self, spacing=None):", "def model(self, spacing=None):\n        1 / 0"),
     "ZeroDivisionError"),
])
@pytest.mark.parametrize("command", ["list", "run"])
def test_an_error_in_a_users_model_is_one_line(command, edit, cause, tmp_path, capsys, monkeypatch):
    """An exception inside model() of a user's scene file (the material library's own refusals
    included) under `list` and `run`: one line naming the file, the line and the cause, exit 2,
    before any work."""
    from test_run_cache import SCENE_FILE

    text = SCENE_FILE.format(length=0.16, gravity=-9.81)
    assert edit[0] in text
    text = text.replace(edit[0], edit[1])
    path = tmp_path / "my_beam.py"
    path.write_text(text)
    line = next(i for i, t in enumerate(text.splitlines(), 1)
                if edit[1].splitlines()[-1].strip() in t)
    argv = ["list", str(path)] if command == "list" else [
        "run", str(path), "--solver", "csph", "--resolution", "3", "--out", str(tmp_path / "out")]
    err = _refused(argv, capsys, monkeypatch, cause)
    assert f"scene file: {path} line {line}: model() failed" in err, err


def test_an_error_in_a_users_scene_class_names_its_line(tmp_path, capsys, monkeypatch):
    from test_run_cache import SCENE_FILE

    text = SCENE_FILE.format(length=0.16, gravity=-9.81).replace(
        "    def model(self, spacing=None):",
        "    def __post_init__(self):\n        raise RuntimeError('refused')\n\n"
        "    def model(self, spacing=None):")
    path = tmp_path / "my_beam.py"
    path.write_text(text)
    line = next(i for i, t in enumerate(text.splitlines(), 1) if "refused" in t)
    err = _refused(["list", str(path)], capsys, monkeypatch, "RuntimeError: refused")
    assert f"scene file: {path} line {line}: MyBeam() failed" in err, err
    # an error at import names its line too
    path.write_text("import math\n\nx = undefined_at_import\n")
    err = _refused(["list", str(path)], capsys, monkeypatch, "NameError")
    assert f"scene file: {path} line 3 could not be loaded" in err, err


# -- a probe point outside the body --------------------------------------------------------------

@pytest.mark.parametrize("solver", ["csph", "hpm", "fem"])
def test_a_probe_outside_the_body_is_refused_up_front(solver, tmp_path, capsys, monkeypatch):
    """A Point set beyond the beam's end (X = 0.2 m on a 0.16 m beam): refused before any run,
    one line naming the set and the point, exit 2 — for the particle methods as for the FEM
    (which read the nearest particle before)."""
    from test_run_cache import SCENE_FILE

    text = SCENE_FILE.format(length=0.16, gravity=-9.81).replace(
        'Set("tip", Point((0.16, 0.0)))', 'Set("tip", Point((0.2, 0.0)))')
    assert "Point((0.2, 0.0))" in text
    path = tmp_path / "my_beam.py"
    path.write_text(text)
    err = _refused(["run", str(path), "--solver", solver, "--resolution", "3", "--out",
                    str(tmp_path / "out")], capsys, monkeypatch,
                   "set 'tip': the point (0.2, 0.0) m lies outside the body")
    assert "allowed: a point inside or on the boundary" in err
    line = next(i for i, t in enumerate(text.splitlines(), 1) if "return Model(" in t)
    assert err.startswith(f"workbench: error: scene file: {path} line {line}: model() set 'tip'"), err


def test_a_probe_on_the_boundary_or_in_its_region_is_accepted():
    from workbench.materials import Material
    from workbench.scenes import SceneError
    from workbench.scenes import model as M
    from workbench.scenes.shapes import Box, Point

    mat = Material.svk(E=1e7, nu=0.3, rho=1000.0)
    regions = [M.Region("a", Box((0, 0), (1.0, 0.1)), mat), M.Region("b", Box((1, 0), (2.0, 0.1)), mat)]

    def model(p, region=None):
        return M.Model(dim=2, length=0.1, regions=regions, sets=[M.Set("p", Point(p), region=region)],
                       drive=M.Static((1.0,)), observables=[M.Displacement("u", "p", 0)])

    model((1.0 + 0.1 - 0.1, 0.1))  # on the boundary, placed with round-off
    model((1.5, 0.05))
    with pytest.raises(SceneError, match="set 'p': the point .* lies outside region 'a'"):
        model((1.5, 0.05), region="a")
    with pytest.raises(SceneError, match="has 3 coordinates in a 2-D model"):
        model((1.5, 0.05, 0.0))


# -- the stability study's exit status ------------------------------------------------------------

def _stability_section(status, gate_passed=True):
    """A stability dataset of the study's shape (solver x scene x dt_factor) with the given
    statuses (every other run ok), as run_study returns it: the CLI's verdict alone is tested
    (the study itself is long)."""
    import xarray as xr

    from studies import stability

    solvers, scenes, factors = ["hpm", "sph"], ["ring", "slab"], [0.5, 0.9, 1.1]
    st = np.full((2, 2, 3), "ok", dtype=object)
    for (s, sc, f), v in status.items():
        st[solvers.index(s), scenes.index(sc), factors.index(f)] = v
    ds = xr.Dataset({"status": (("solver", "scene", "dt_factor"), st.astype(str), {"units": "-"})},
                    coords={"solver": solvers, "scene": scenes, "dt_factor": factors})
    gate = common.Gate.expect("stability: sph ring at dt factor 0.5", "unstable",
                              "unstable" if gate_passed else "stable", "clumping")
    return dict(name="stability", dataset=ds, rows=[], gates=[gate], written="stability.nc"), stability


@pytest.mark.parametrize("status,gate_passed,code", [
    # blown up on purpose above dt_crit, and where the literature predicts it: results, exit 0
    ({("hpm", "ring", 1.1): "unstable: energy growth at t=0.01", ("sph", "ring", 0.5):
      "unstable: disorder at t=0.002", ("sph", "slab", 0.9): "unstable: disorder at t=0.01"}, True, 0),
    # the same runs, a gate failed: exit 1
    ({("hpm", "ring", 1.1): "unstable: energy growth at t=0.01"}, False, 1),
    # a run that crashed is a failed run whatever the gates say
    ({("hpm", "ring", 1.1): "unstable: energy growth at t=0.01",
      ("hpm", "slab", 0.5): "error: FloatingPointError: boom"}, True, 1),
])
def test_stability_exit_status_follows_its_gates(status, gate_passed, code, tmp_path, capsys,
                                                monkeypatch):
    import app.verify as verify

    section, stability = _stability_section(status, gate_passed)
    monkeypatch.setattr(verify, "run_study", lambda *a, **k: section)
    assert cli.main(["run", "stability", "--quick", "--out", str(tmp_path)]) == code
    out = capsys.readouterr().out
    assert f"runs that did not end ok ({len(status)})" in out
    if ("hpm", "ring", 1.1) in status:
        assert "hpm ring dt factor 1.1" in out and "expected: above dt_crit (dt factor 1.1 > 1)" in out
    if ("sph", "ring", 0.5) in status:
        assert "expected: Eulerian kernel: particle clumping" in out
    if ("hpm", "slab", 0.5) in status:
        assert "[FAILED]" in out and "failed runs: ['hpm slab dt factor 0.5']" in out
    else:
        assert "failed runs" not in out
    assert stability.expected_instability("hpm", "ring", 0.9) == ""  # not predicted at 0.9


@pytest.mark.parametrize("kind", ["tmpfs", "OSError"])
def test_full_disk_for_the_report_names_the_datasets(kind, tmp_path, capsys, monkeypatch):
    """`workbench verify` on a disk that fills up after the datasets: the report's failure is one
    line naming where the datasets are, exit 1, no traceback."""
    import errno

    import app.verify as verify

    def section(name, outdir, *a, **k):
        return dict(name=name, gates=[], rows=[], figures=[], error_label="-", verdict="PASS",
                    dataset=None, written=Path(outdir) / f"{name}.nc", notes=[])

    monkeypatch.setattr(verify, "run_study", section)
    with small_filesystem(tmp_path / "small") as small:
        if kind == "tmpfs":
            if small is None:
                pytest.skip("mounting a tmpfs is not permitted here (the OSError case runs)")
            out_dir = small / "out"
            real = verify.run_study

            def then_fill(name, outdir, *a, **k):
                got = real(name, outdir, *a, **k)
                fill(small)
                return got

            monkeypatch.setattr(verify, "run_study", then_fill)
        else:
            out_dir = tmp_path / "out"
            real_open = open

            def no_space(file, mode="r", *a, **k):
                if "w" in mode and Path(file).parent == out_dir:
                    raise OSError(errno.ENOSPC, "No space left on device")
                return real_open(file, mode, *a, **k)

            monkeypatch.setattr("builtins.open", no_space)
        code = cli.main(["verify", "--quick", "--out", str(out_dir)])
        err = capsys.readouterr().err.strip()
        assert code == 1 and len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert f"the report could not be written in {out_dir}" in err and "No space left" in err
        assert "the datasets were saved to " in err and str(out_dir / "plate.nc") in err
