"""Fixtures shared across test modules."""
import os
import subprocess
import sys

import pytest


@pytest.fixture(scope="session")
def quick_verify(tmp_path_factory):
    """`workbench verify --quick` run once per session (the main job, minutes): its output folder
    and the finished process. test_verify checks the job itself; other modules (e.g.
    test_stability_theory) assert on the datasets it wrote rather than recomputing them."""
    out = tmp_path_factory.mktemp("verify")
    env = dict(os.environ, WORKBENCH_CACHE=str(out / "cache"))
    proc = subprocess.run([sys.executable, "-m", "workbench.app.cli", "verify", "--quick", "--out", str(out)],
                          capture_output=True, text=True, env=env, timeout=900)
    return out, proc
