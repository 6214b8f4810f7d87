"""The command line: bad input gets one line naming the parameter and its range, exit status 2."""
import subprocess
import sys

import pytest

from app import cli
from workbench.scenes import Cantilever, ParameterError, SSCurve, with_overrides


@pytest.mark.parametrize("argv,needle", [
    (["run", "ss_curve", "--set", "nu=0.5"], "nu: 0.5 is out of range; allowed: (-1, 0.5)"),
    (["run", "ss_curve", "--set", "E=-1"], "E: -1 Pa is out of range"),
    (["run", "ss_curve", "--set", "eps_L=-0.1"], "eps_L: -0.1 is out of range"),
    (["run", "ss_curve", "--set", "bogus=1"], "bogus: unknown parameter"),
    (["run", "nosuch"], "study: 'nosuch' is unknown"),
    (["run", "ss_curve", "--solver", "magic"], "--solver: 'magic' is not supported"),
    (["run", "ss_curve", "--resolution", "0"], "resolution: 0 is out of range"),
    (["run", "cantilever", "--set", "H=0.5"], "H: 0.5 m is out of range"),
])
def test_bad_input_is_one_line_exit_2(argv, needle, capsys):
    if argv[1] == "cantilever" and "cantilever" not in __import__("studies").STUDIES:
        pytest.skip("cantilever study not registered")
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err
    assert len(err.splitlines()) == 1 and "Traceback" not in err


def test_overrides_are_typed_and_validated():
    s = with_overrides(SSCurve(), {"n_steps": "10", "unload": "true", "nu": "0.25"})
    assert s.n_steps == 10 and s.unload is True and s.nu == 0.25
    c = with_overrides(Cantilever(), {"loads": "1,2"})
    assert c.loads == (1.0, 2.0)
    with pytest.raises(ParameterError, match="n_steps"):
        with_overrides(SSCurve(), {"n_steps": "ten"})


def test_console_script_runs_analytic_study(tmp_path):
    out = subprocess.run([sys.executable, "-m", "app.cli", "run", "ss_curve", "--solver",
                          "analytic", "--out", str(tmp_path)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "ss_curve.nc").exists() and (tmp_path / "ss_curve.png").exists()
    import xarray as xr

    with xr.open_dataset(tmp_path / "ss_curve.nc") as ds:
        assert ds.stress.sel(solver="analytic").max() > 6e8  # Swift curve reaches ~700 MPa
        assert ds.attrs["param_max_strain"] == 0.3


def test_printed_table_says_which_runs_came_from_the_cache(tmp_path, capsys, monkeypatch):
    # the same command twice: the second serves the csph run from the run cache and says so; the
    # first shows the run's set-up and JIT apart from the solver's own wall time
    monkeypatch.setenv("WORKBENCH_CACHE", str(tmp_path / "cache"))
    argv = ["run", "ss_curve", "--solver", "csph", "--resolution", "1", "--set", "n_steps=4",
            "--out", str(tmp_path)]
    assert cli.main(argv) == 0
    first = [ln for ln in capsys.readouterr().out.splitlines() if ln.strip().startswith("csph")]
    assert len(first) == 1 and "(set-up " in first[0] and "JIT " in first[0]
    assert "(cached)" not in first[0]
    assert cli.main(argv) == 0
    again = [ln for ln in capsys.readouterr().out.splitlines() if ln.strip().startswith("csph")]
    assert len(again) == 1 and again[0].endswith("(cached)")
