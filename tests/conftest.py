"""Fixtures shared across test modules."""
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

SESSION_CACHE = "WORKBENCH_TEST_SESSION_CACHE"
"""Set to the session's own run cache, so that pytest-xdist workers (and subprocesses) share it."""


def pytest_configure(config):
    """The test session uses its own temporary run cache (``WORKBENCH_CACHE``), never the user's:
    a test then computes every run and FEM reference it reads from the code it tests."""
    own = os.environ.get(SESSION_CACHE)
    if not own:
        own = tempfile.mkdtemp(prefix="workbench-test-cache-")
        os.environ[SESSION_CACHE] = own
        config._workbench_session_cache = own  # removed by this process at the end
    os.environ["WORKBENCH_CACHE"] = own
    os.environ.pop("WORKBENCH_NO_CACHE", None)


VERIFY = pytest.StashKey[dict]()
"""The session's `workbench verify --quick`: started when collection finds a test that needs it,
so that it runs beside the tests that do not (the main job is a few minutes, mostly one core)."""


def _start_verify(config) -> dict:
    out = tempfile.mkdtemp(prefix="workbench-verify-")
    env = dict(os.environ, WORKBENCH_CACHE=os.path.join(out, "cache"))
    logs = [open(os.path.join(out, name), "w+") for name in ("stdout.txt", "stderr.txt")]
    proc = subprocess.Popen([sys.executable, "-m", "app.cli", "verify", "--quick",
                             "--out", out], stdout=logs[0], stderr=logs[1], text=True, env=env)
    config.stash[VERIFY] = job = dict(out=out, proc=proc, logs=logs)
    return job


@pytest.hookimpl(trylast=True)  # after -k / -m have deselected
def pytest_collection_modifyitems(session, config, items):
    """Start the session's verify when a test needs it, and run the modules that read it last (in
    their order, each module whole, so that its module fixtures are set up once): the verify runs
    beside every other test instead of the test process waiting for it at the first that reads it."""
    needs = {item.module.__name__ for item in items
             if "quick_verify" in getattr(item, "fixturenames", ())}
    if needs:
        _start_verify(config)
        items[:] = ([i for i in items if i.module.__name__ not in needs]
                    + [i for i in items if i.module.__name__ in needs])


def pytest_unconfigure(config):
    own = getattr(config, "_workbench_session_cache", None)
    if own is not None:
        shutil.rmtree(own, ignore_errors=True)
        os.environ.pop(SESSION_CACHE, None)
    job = config.stash.get(VERIFY, None)
    if job is not None:
        if job["proc"].poll() is None:
            job["proc"].kill()
            job["proc"].wait()
        for f in job["logs"]:
            f.close()
        shutil.rmtree(job["out"], ignore_errors=True)


@pytest.fixture(scope="session")
def quick_verify(pytestconfig):
    """`workbench verify --quick` run once per session (the main job, minutes): its output folder
    and the finished process. test_verify checks the job itself; other modules (e.g.
    test_stability_theory) assert on the datasets it wrote rather than recomputing them."""
    job = pytestconfig.stash.get(VERIFY, None) or _start_verify(pytestconfig)
    proc = job["proc"]
    rc = proc.wait(timeout=900)
    for f in job["logs"]:
        f.seek(0)
    stdout, stderr = (f.read() for f in job["logs"])
    return Path(job["out"]), subprocess.CompletedProcess(proc.args, rc, stdout, stderr)
