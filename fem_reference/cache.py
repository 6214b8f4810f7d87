"""Converged FEM reference values cached on disk, so that particle studies compare against the
FEM without recomputing it.

A record is keyed by the scene type and all its parameters, the resolution, the solver options and
a hash of the FEM and material source code (:func:`code_version`): a change to any of them gives a
new key. Records are JSON files ``<key>.json`` in ``$WORKBENCH_CACHE`` (default
``~/.cache/particle-workbench``)/``fem``, written atomically (temporary file, then rename).

    >>> from fem_reference import reference
    >>> reference(Plate(), "period")            # modal period at the default fine resolution, s
    >>> reference(Cantilever(), "tip_deflection")  # (len(scene.loads),) m
"""
from __future__ import annotations

import dataclasses
import datetime
import hashlib
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

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


def cache_dir() -> Path:
    root = os.environ.get("WORKBENCH_CACHE") or os.path.join(
        os.path.expanduser("~"), ".cache", "particle-workbench")
    return Path(root) / "fem"


def code_version() -> str:
    """sha256 (16 hex digits) of the FEM and material-library sources and the scikit-fem version."""
    import skfem

    import workbench.materials as wm

    h = hashlib.sha256()
    here = Path(__file__).parent
    files = sorted(p for p in here.glob("*.py") if p.name not in ("bench.py",))
    files += sorted(Path(wm.__file__).parent.glob("*.py"))
    for p in files:
        h.update(p.name.encode())
        h.update(p.read_bytes())
    h.update(skfem.__version__.encode())
    return h.hexdigest()[:16]


def _jsonable(x):
    if isinstance(x, np.ndarray):
        return [_jsonable(v) for v in x.tolist()] if x.ndim else _jsonable(x.item())
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else None  # JSON has no NaN: null
    if isinstance(x, (np.integer, int, bool, str)) or x is None:
        return x.item() if isinstance(x, np.generic) else x
    return str(x)


def record_key(scene, resolution: int, options: dict) -> tuple[str, dict]:
    """The cache key and the description it hashes."""
    desc = dict(scene=type(scene).__name__, params=_jsonable(dataclasses.asdict(scene)),
                resolution=int(resolution), options=_jsonable(options), code=code_version())
    text = json.dumps(desc, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24], desc


def _write_atomic(path: Path, data: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=".json")
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(data, f)
        os.chmod(tmp, 0o644)  # mkstemp makes it private; the cache is shared
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def record(scene, resolution: int | None = None, refresh: bool = False, **options) -> dict:
    """The cached FEM result of ``scene`` at ``resolution`` (default: the fine one), computing and
    storing it when absent (or with ``refresh``). Returns the stored dict: ``result`` (the
    solver's output, arrays as lists, NaN as None), ``scene``, ``params``, ``resolution``,
    ``options``, ``code``, ``created``, ``key``."""
    from .model import solve

    name = type(scene).__name__
    options = {**DEFAULT_OPTIONS.get(name, {}), **options}
    if resolution is None:
        resolution = DEFAULT_RESOLUTION[name + ("/dynamic" if options.get("dynamic") else "")]
    key, desc = record_key(scene, resolution, options)
    path = cache_dir() / f"{key}.json"
    if path.exists() and not refresh:
        with open(path) as f:
            return json.load(f)
    result = solve(scene, resolution, **options)
    keep = {k: v for k, v in result.items() if k != "residual_history"}
    data = dict(desc, key=key, created=datetime.datetime.now().isoformat(timespec="seconds"),
                result=_jsonable(keep))
    _write_atomic(path, data)
    return data


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
    if isinstance(value, list):
        return np.array([np.nan if v is None else v for v in value], dtype=float)
    return float("nan") if value is None else value
