"""What every study shares: the solver registry, one guarded call per (scene, solver, resolution)
run, gate records, and the observed order of convergence.

A solver is a function ``solve(scene, resolution, **options) -> dict`` (see the study modules for
the keys each scene returns). A run that raises is a result, not a crash: :func:`run_solver` turns
the exception into ``status = 'error: …'`` and the sweep goes on.
"""
from __future__ import annotations

import functools
import importlib
import logging
import time
import traceback
from dataclasses import dataclass

import numpy as np

log = logging.getLogger("workbench")

# 'analytic' is handled by each study itself; 'fem' is the reference; every particle method of
# :data:`sph.METHODS` runs through the one particle driver.
SOLVER_ENTRY = {"fem": "fem_reference:solve"}
"""Solvers other than the particle methods: name -> "module:function"."""


def _particle_methods() -> tuple:
    from sph import METHODS

    return tuple(METHODS)


ALL_SOLVERS = ("analytic", "fem") + _particle_methods()


def solver_function(name: str):
    """``solve(scene, resolution, **options) -> dict`` of the solver ``name``."""
    if name in SOLVER_ENTRY:
        mod, fn = SOLVER_ENTRY[name].split(":")
        return getattr(importlib.import_module(mod), fn)
    if name not in _particle_methods():
        raise ValueError(f"solver: {name!r} is unknown; allowed: {', '.join(ALL_SOLVERS)}")
    from sph import driver

    return functools.partial(driver.solve, name)


def run_solver(name: str, scene, resolution: int, **options) -> dict:
    """Call one solver once; never raises for a failed run. Adds ``wall_time`` if the solver did not
    and a ``status`` (``ok``, ``unstable: …``, ``diverged``, ``error: …``)."""
    t0 = time.perf_counter()
    try:
        out = dict(solver_function(name)(scene, resolution, **options))
    except Exception as err:  # a failed run is a result
        log.debug("%s", traceback.format_exc())
        out = {"status": f"error: {type(err).__name__}: {err}"}
    wall = time.perf_counter() - t0
    out.setdefault("wall_time", wall)
    out.setdefault("status", "ok")
    out["run_wall_time"] = wall  # the whole call, set-up included
    status = summary_status(out["status"])
    log.info("run %-10s %-6s resolution=%-4s %7.2f s  %s", scene.name, name, resolution, wall, status)
    return out


def summary_status(status) -> str:
    """One status for a run whose solver reports one per load: 'ok' or the first that is not."""
    if isinstance(status, str):
        return status
    status = [str(s) for s in status]
    return "ok" if all(s == "ok" for s in status) else next(s for s in status if s != "ok")


@dataclass
class Gate:
    """One accuracy gate: what was compared, the observed value, the tolerance and why."""

    name: str
    observed: float
    tolerance: float
    reason: str
    passed: bool
    shown: str = ""  # how a yes/no gate reads in the report (see :meth:`expect`)

    @classmethod
    def at_most(cls, name: str, observed: float, tolerance: float, reason: str) -> "Gate":
        ok = bool(np.isfinite(observed) and observed <= tolerance)
        return cls(name, float(observed), float(tolerance), reason, ok)

    @classmethod
    def at_least(cls, name: str, observed: float, bound: float, reason: str) -> "Gate":
        """A lower bound (an observed order of convergence, say)."""
        ok = bool(np.isfinite(observed) and observed >= bound)
        return cls(name, float(observed), float(bound), reason, ok,
                   shown=f"{observed:.4g} (at least {bound:.4g})")

    @classmethod
    def expect(cls, name: str, observed: str, expected: str, reason: str) -> "Gate":
        """A qualitative gate: an observed outcome (e.g. 'stable', 'unstable') against the one the
        literature predicts; ``observed`` is 1 where they differ, 0 where they agree."""
        ok = observed == expected
        return cls(name, 0.0 if ok else 1.0, 0.0, reason, ok,
                   shown=f"{observed} (expected {expected})")

    def line(self) -> str:
        mark = "PASS" if self.passed else "FAIL"
        value = self.shown or f"{self.observed:.4g} (tolerance {self.tolerance:.4g})"
        return f"{mark}  {self.name}: {value} — {self.reason}"


def observed_order(h, err) -> float:
    """Least-squares slope of log(err) against log(h) over the finite, positive points (NaN if fewer
    than three)."""
    h = np.asarray(h, float)
    err = np.abs(np.asarray(err, float))
    ok = np.isfinite(err) & (err > 0) & np.isfinite(h) & (h > 0)
    if ok.sum() < 3:
        return float("nan")
    slope, _ = np.polyfit(np.log(h[ok]), np.log(err[ok]), 1)
    return float(slope)


def check_resolutions(resolutions) -> list[int]:
    out = []
    for r in resolutions:
        r = int(r)
        if r < 1:
            raise ValueError(f"resolution: {r} is out of range; allowed: integers >= 1 "
                             "(particles or elements across the body; a spacing larger than the "
                             "body is not a discretisation)")
        out.append(r)
    return out


def ladders(solvers, resolutions, study, quick: bool) -> tuple[list, dict]:
    """The solvers that run and each one's :func:`ladder`: a solver whose ladder is empty (a
    variant the quick ladder leaves out) is dropped; 'analytic' is kept (it has no ladder)."""
    lads = {s: ladder(s, resolutions, study, quick) for s in solvers if s != "analytic"}
    kept = [s for s in solvers if s == "analytic" or lads[s]]
    return kept, {s: lads[s] for s in kept if s != "analytic"}


def ladder(solver: str, resolutions, study, quick: bool) -> list[int]:
    """The resolutions ``solver`` runs at: ``resolutions`` may be None (the study's ladder, or its
    quick ladder), a list (every discrete solver but the FEM reference, which keeps its own), or a
    dict solver -> list."""
    default = list((study.QUICK_RESOLUTIONS if quick else study.RESOLUTIONS).get(solver, ()))
    if resolutions is None:
        return default
    if isinstance(resolutions, dict):
        return check_resolutions(resolutions.get(solver, default))
    if solver == "fem" and study.NAME != "ss_curve":
        return default
    return check_resolutions(resolutions)


FIELD_SOLVERS = ("fem", "csph", "hpm", "sph")
"""The solvers that write fields (``fields=<folder>``): the particle methods their particles, the
FEM its mesh (the plate's dynamic run only)."""


def field_options(solver: str, resolution: int, fields, field_runs=None) -> dict:
    """The solver options asking one run for field output: ``{"fields": folder}`` when ``fields``
    (a folder) is given, ``solver`` writes fields, and (solver, resolution) is in ``field_runs``
    (None: every run); else ``{}``."""
    if fields is None or solver not in FIELD_SOLVERS:
        return {}
    if field_runs is not None and (solver, int(resolution)) not in set(field_runs):
        return {}
    return {"fields": str(fields)}


def field_series(scene, tasks) -> str:
    """The ``.pvd`` file names the ``tasks`` that asked for fields have written (those that exist),
    comma-separated, for the dataset's ``field_series`` attribute."""
    from pathlib import Path

    from workbench.fields import series_name

    names = []
    for t in tasks:
        folder = dict(t.options).get("fields")
        if folder is None:
            continue
        pvd = Path(folder) / f"{series_name(scene.name, t.solver, t.resolution)}.pvd"
        if pvd.exists():
            names.append(pvd.name)
    return ", ".join(names)
