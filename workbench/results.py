"""The results store: one xarray Dataset per study (``../shared/design/contract.md``), provenance
attributes, and atomic NetCDF writes (temporary file in the same folder, flushed to disk with
``fsync``, then ``os.replace``), so an interrupted run never leaves a corrupt file.

No lost work: :func:`check_writable` proves an output folder writable (a probe file) before a
study starts, and a write that still fails (the disk filled up, the folder vanished) saves the
dataset in a fallback folder (:func:`fallback_dir`) and raises :class:`SavedElsewhere` naming it."""
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
from .materials import Material

ENGINE = "netcdf4"

STOPPED = "stopped: the caller's criterion was met"
"""Status of the load values of a static path after its caller asked to stop (not run, and not a
failure): both static solvers (``fem_reference.static.load_path``, ``sph.static.solve_path``)."""


def error_status(err: BaseException) -> str:
    """The status of a run that raised ``err``: ``error: <type>: <message>`` on one line (a failed
    run is a result, not a crash)."""
    return f"error: {type(err).__name__}: {err}".replace("\n", " ")


def path_ok(status: str) -> bool:
    """Whether a static path value's status is a success: ``ok`` (possibly qualified, ``ok (…)``)
    or :data:`STOPPED`."""
    return status.startswith("ok") or status == STOPPED


class OutputError(ValueError):
    """An output folder that cannot be written (one line: the folder and what failed)."""


class WriteFailed(OSError):
    """A dataset could be written neither where asked nor in a fallback folder."""


class SavedElsewhere(OSError):
    """A dataset could not be written where asked; it was saved at ``fallback`` instead."""

    def __init__(self, message: str, fallback: Path):
        super().__init__(message)
        self.fallback = fallback


class PartlyWritten(OSError):
    """A study's dataset was written (at ``saved``) but its figures or the report could not be;
    the one-line message names where the data is."""

    def __init__(self, message: str, saved: Path):
        super().__init__(message)
        self.saved = saved


WRITE_ERRORS = (OSError, RuntimeError, ValueError, TypeError)
"""What a failed write raises: ``OSError`` (no space, no folder, no permission), and the
libraries' own types for the same causes — netCDF4 raises ``RuntimeError: NetCDF: HDF error`` on a
full disk, and xarray/matplotlib a ``ValueError`` or ``TypeError`` for what a backend refuses."""


def why(err: BaseException) -> str:
    """One line: the exception's type and cause (the OS's words for an ``OSError``)."""
    text = (getattr(err, "strerror", None) or str(err) or "no message").strip()
    return f"{type(err).__name__}: {' '.join(text.split())}"


def _fsync_dir(folder: Path) -> None:
    """Make a rename in ``folder`` durable (best effort: not every file system allows it)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def check_writable(folder: str | os.PathLike) -> Path:
    """Create ``folder`` (and its parents) and prove it writable by writing, syncing and removing
    a probe file; :class:`OutputError` (one line naming the folder and the failure) otherwise."""
    folder = Path(folder)
    try:
        if folder.exists() and not folder.is_dir():
            raise NotADirectoryError(f"{folder} is a file, not a folder")
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".workbench-probe.", dir=folder)
        try:
            os.write(fd, b"probe")
            os.fsync(fd)
        finally:
            os.close(fd)
            os.unlink(probe)
    except OSError as err:
        why = err.strerror or str(err)
        raise OutputError(f"{folder} cannot be written ({type(err).__name__}: {why}); allowed: a "
                          "folder this user can create and write") from None
    return folder


def fallback_dir() -> Path:
    """Where a dataset goes when its own folder fails: ``WORKBENCH_FALLBACK`` if set, else
    ``unsaved/`` beside the run cache (``WORKBENCH_CACHE`` or ``~/.cache/particle-workbench``),
    else the system's temporary folder."""
    env = os.environ.get("WORKBENCH_FALLBACK")
    if env:
        return Path(env)
    base = os.environ.get("WORKBENCH_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")), "particle-workbench")
    return Path(base) / "unsaved"


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
        if isinstance(mat, Material):  # a scene's one material (not a method of that name)
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


def write(ds: xr.Dataset, path: str | os.PathLike, fallback: bool = True) -> Path:
    """Write ``ds`` to NetCDF atomically (flushed with ``fsync`` before the rename). Every data
    variable must carry ``units``. If the file cannot be written (any of :data:`WRITE_ERRORS`:
    an ``OSError``, or netCDF's ``RuntimeError`` on a full disk) and ``fallback``, the dataset is
    written to :func:`fallback_dir` (else the system's temporary folder) and
    :class:`SavedElsewhere` names where; :class:`WriteFailed` when neither could be written."""
    path = Path(path)
    missing = [k for k, v in ds.data_vars.items() if "units" not in v.attrs]
    if missing:
        raise ValueError(f"variables without units: {missing}")
    ds = ds.copy()
    ds.attrs = {k: _netcdf_safe(v) for k, v in ds.attrs.items()}
    for v in list(ds.variables.values()):
        v.attrs = {k: _netcdf_safe(a) for k, a in v.attrs.items()}
    try:
        return _write_atomic(ds, path)
    except WRITE_ERRORS as err:
        if not fallback:
            raise
        stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
        tried = []
        for folder in (fallback_dir(), Path(tempfile.gettempdir()) / "workbench-unsaved"):
            try:
                where = _write_atomic(ds, folder / f"{path.stem}-{stamp}{path.suffix}")
            except WRITE_ERRORS as again:
                tried.append(f"{folder} ({why(again)})")
                continue
            raise SavedElsewhere(f"{path} could not be written ({why(err)}); the dataset was "
                                 f"saved to {where}", where) from None
        raise WriteFailed(f"{path} could not be written ({why(err)}), nor in "
                          f"{' or '.join(tried)}") from None


def _replace_atomically(path: Path, fill) -> Path:
    """The one atomic write: ``fill(tmp)`` writes a temporary file beside ``path``, which is
    fsync'ed (on disk before the rename makes it the file), made world-readable and renamed over
    ``path``; the folder is fsync'ed after. On any failure the temporary file is removed."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        fill(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    _fsync_dir(path.parent)
    return path


def _write_atomic(ds: xr.Dataset, path: Path) -> Path:
    return _replace_atomically(path, lambda tmp: ds.to_netcdf(tmp, engine=ENGINE))


def read(path: str | os.PathLike) -> xr.Dataset:
    """Open a dataset written by :func:`write` (loaded into memory, file closed)."""
    with xr.open_dataset(path, engine=ENGINE) as ds:
        return ds.load()


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write a text file (report, JSON cache entry) atomically."""

    def fill(tmp):
        with open(tmp, "w") as fh:
            fh.write(text)

    return _replace_atomically(Path(path), fill)
