"""The results store: one xarray Dataset per study (``../shared/design/contract.md``), provenance
attributes, and atomic NetCDF writes (temporary file in the same folder, then ``os.replace``), so an
interrupted run never leaves a corrupt file."""
from __future__ import annotations

import datetime as _dt
import functools
import json
import os
import platform
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

from . import __version__

ENGINE = "netcdf4"


@functools.lru_cache(maxsize=1)
def git_revision() -> str:
    """The git revision of the checkout this package runs from (``+dirty`` if modified), or
    'unknown' outside a checkout."""
    root = Path(__file__).resolve().parent.parent
    try:
        rev = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=root, capture_output=True,
                             text=True, timeout=5).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                               capture_output=True, text=True, timeout=5).stdout.strip()
        return (rev + ("+dirty" if dirty else "")) if rev else "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def provenance(study: str, scene=None, extra: dict | None = None) -> dict:
    """Attributes every dataset carries: study, version, git revision, date, host CPU count and
    model, and the scene parameters actually used (``param_NAME`` with ``param_NAME_units``)."""
    attrs = {
        "study": study,
        "workbench_version": __version__,
        "git_revision": git_revision(),
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "cpu_count": os.cpu_count() or 1,
        "cpu_model": cpu_model(),
        "python": platform.python_version(),
    }
    if scene is not None:
        attrs["scene"] = scene.name
        attrs.update(scene.attrs())
        mat = getattr(scene, "material", None)
        if mat is not None:
            attrs.update({f"material_{k}" if not k.startswith("material") else k: v
                          for k, v in mat.describe().items()})
    if extra:
        attrs.update(extra)
    return attrs


def _netcdf_safe(value):
    """NetCDF attributes hold numbers, strings and 1-D numeric arrays; everything else becomes JSON."""
    if isinstance(value, (bool, np.bool_)):
        return int(value)
    if isinstance(value, (int, float, str, np.integer, np.floating)):
        return value
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = np.asarray(value)
        if arr.dtype.kind in "if" and arr.ndim == 1:
            return arr
    return json.dumps(value, default=str)


def write(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write ``ds`` to NetCDF atomically. Every data variable must carry ``units``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    missing = [k for k, v in ds.data_vars.items() if "units" not in v.attrs]
    if missing:
        raise ValueError(f"variables without units: {missing}")
    ds = ds.copy()
    ds.attrs = {k: _netcdf_safe(v) for k, v in ds.attrs.items()}
    for v in list(ds.variables.values()):
        v.attrs = {k: _netcdf_safe(a) for k, a in v.attrs.items()}
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        ds.to_netcdf(tmp, engine=ENGINE)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def read(path: str | os.PathLike) -> xr.Dataset:
    """Open a dataset written by :func:`write` (loaded into memory, file closed)."""
    with xr.open_dataset(path, engine=ENGINE) as ds:
        return ds.load()


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write a text file (report, JSON cache entry) atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    os.chmod(tmp, 0o644)
    os.replace(tmp, path)
    return path
