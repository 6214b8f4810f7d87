"""Converged FEM reference values cached on disk, so that particle studies compare against the
FEM without recomputing it.

A record is a run of the one run cache (:mod:`workbench.runcache`): keyed by the scene type and
all its parameters, the resolution, the solver options and a hash of the code that decides the
result (``fem_reference/``, the core ``workbench/`` without the application, the scene's own
source file, the library versions), each entry checksummed and verified before it is read. A FEM
run of a sweep (:mod:`studies.sweep`) with the same spec is the same entry. Only a run whose status
is ``ok`` is stored; a failed one is recomputed next time (and :func:`reference` raises).

    >>> from fem_reference import reference
    >>> reference(Plate(), "period")            # modal period at the default fine resolution, s
    >>> reference(Cantilever(), "tip_deflection")  # (len(scene.loads),) m
"""
from __future__ import annotations

import numpy as np

from workbench import runcache

# Fine resolutions (elements across H, or per edge): each within ~0.01–0.05 % of its extrapolated
# limit (tests/test_fem_cantilever.py and test_fem_plate.py measure the convergence).
# The plate's dynamic run is ~600 Newton iterations: 8 across H (period within 0.05 % of its limit).
DEFAULT_RESOLUTION = {"SSCurve": 2, "Cantilever": 16, "Plate": 32, "Plate/dynamic": 8}
# The quantities a record can answer, per scene type; the plate's dynamic ones need a time run.
QUANTITIES = {
    "SSCurve": ("strain", "stress", "nominal_stress", "eps_p"),
    "Cantilever": ("load", "tip_deflection", "tip_horizontal"),
    "Plate": ("period", "omega", "period_dynamic", "amplitude", "time", "tip_displacement"),
}
# Options of a scene type's references: the SS-curve block's homogeneous state needs no more than
# trilinear hexahedra (the study's choice too).
DEFAULT_OPTIONS = {"SSCurve": {"element": "hex8"}}
DYNAMIC_QUANTITIES = ("period_dynamic", "amplitude", "time", "tip_displacement")


SOLVER_MODULES = ("fem_reference",)
"""The package whose code decides an FEM run (hashed into the key, with the core and the scene)."""


def cache_dir():
    """Where the records are: the run cache's folder (None when it is off)."""
    return runcache.cache_dir()


def record_key(scene, resolution: int, options: dict) -> tuple[str, dict]:
    """The cache key and the description it hashes (:func:`workbench.runcache.describe`)."""
    options = dict(options)
    return (runcache.key("fem", scene, int(resolution), options, SOLVER_MODULES),
            runcache.describe("fem", scene, int(resolution), options, SOLVER_MODULES))


def record(scene, resolution: int | None = None, refresh: bool = False, **options) -> dict:
    """The cached FEM result of ``scene`` at ``resolution`` (default: the fine one), computing and
    storing it when absent (or with ``refresh``). Returns the key's description (``scene``,
    ``params``, ``resolution``, ``options``, ``code``), ``key`` and ``result`` (the solver's output
    dict)."""
    from .model import solve

    name = type(scene).__name__
    options = {**DEFAULT_OPTIONS.get(name, {}), **options}
    if resolution is None:
        resolution = DEFAULT_RESOLUTION[name + ("/dynamic" if options.get("dynamic") else "")]
    key, desc = record_key(scene, resolution, options)
    result = None if refresh else runcache.load(key)
    if result is None:
        result = dict(solve(scene, resolution, **options))
        result.setdefault("status", "ok")
        runcache.store(key, result)
    return dict(desc, key=key, result=result)


def _ok(status) -> bool:
    if isinstance(status, list):
        return all(s == "ok" for s in status)
    return status == "ok"


def reference(scene, quantity: str, resolution: int | None = None, refresh: bool = False,
              **options):
    """A converged FEM value of ``quantity`` for ``scene`` (float or array, SI units), from the
    cache when present. Raises ``ValueError`` for an unknown quantity and ``RuntimeError`` when the
    FEM run itself failed (its status is in the message)."""
    name = type(scene).__name__
    if name not in QUANTITIES or quantity not in QUANTITIES[name]:
        raise ValueError(f"quantity: {quantity!r} is not one of {QUANTITIES.get(name, ())} "
                         f"for {name}")
    if name == "Plate":
        options.setdefault("dynamic", quantity in DYNAMIC_QUANTITIES)
    rec = record(scene, resolution, refresh=refresh, **options)
    res = rec["result"]
    if not _ok(res["status"]):
        raise RuntimeError(f"FEM reference of {name} at resolution {rec['resolution']} failed: "
                           f"{res['status']}")
    value = res[quantity]
    if np.ndim(value):
        return np.array([np.nan if v is None else v for v in np.ravel(value)], dtype=float)
    return float("nan") if value is None else float(value)
