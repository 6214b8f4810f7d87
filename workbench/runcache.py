"""The one run cache: finished runs on disk, keyed by what decides their result, verified before
they are served.

**Key** (:func:`key`): the run spec — solver, scene class and every scene parameter, resolution,
solver options — and a hash (:func:`code_hash`) of the code that decides the result: the solver's
own package (``sph/`` for the particle methods, ``fem_reference/`` for the FEM), the core
(``workbench/``; the application, ``app/``, decides no result and is not part of it), the source file of the scene's class
and of each of its base classes outside those packages (a user's scene file: its bytes, so two files
with the same class name and parameters but another geometry get different keys, and an edit of
``model()`` gives a new key), and the versions of numpy, scipy, numba and scikit-fem. The studies'
own source (captions, gates, figures) is not part of it: editing a study keeps its cached runs.
Not covered: another file of the user's own that the scene file imports (only the files of the
scene's classes are hashed).

**Entry** (:func:`store`): ``<key>.pkl`` in ``$WORKBENCH_CACHE/runs`` (default
``~/.cache/particle-workbench/runs``), a header line, the SHA-256 of the payload and the payload
(a pickle of the key and the run's result dict), written to a temporary file, synced
and renamed, so a kill leaves the whole entry or none. Only runs whose status is ``ok`` are stored
(a failure is retried).

**Verified** (:func:`load`): an entry is served only when its header and checksum match, its key
is the one asked for and its result is a dict whose status is ``ok``; anything else (a flipped
bit, a truncated file, an entry of another shape) is discarded with a one-line warning and the run
is recomputed. ``WORKBENCH_NO_CACHE=1`` disables the cache.

The sweep (:mod:`studies.sweep`) and the FEM references (:mod:`fem_reference.cache`) both use it.
"""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import importlib.util
import inspect
import json
import logging
import os
import pickle
import sys
import tempfile
from pathlib import Path

log = logging.getLogger("workbench")

MAGIC = b"workbench-run-cache 1\n"
"""The first line of every entry (the format's version)."""
LIBRARIES = ("numpy", "scipy", "numba", "scikit-fem")
"""Libraries whose version is part of the code hash."""
_CORE = Path(__file__).resolve().parent


def cache_dir() -> Path | None:
    """``$WORKBENCH_CACHE/runs`` (default ``$XDG_CACHE_HOME`` or ``~/.cache``, then
    ``particle-workbench/runs``); None when ``WORKBENCH_NO_CACHE=1``."""
    if os.environ.get("WORKBENCH_NO_CACHE") == "1":
        return None
    base = os.environ.get("WORKBENCH_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")), "particle-workbench")
    return Path(base) / "runs"


def _package_files(root: Path) -> list[Path]:
    if root.is_file():
        return [root]
    return sorted(root.rglob("*.py"))


@functools.lru_cache(maxsize=None)
def _tree_hash(root: str) -> str:
    """SHA-256 of the ``.py`` files under ``root`` (or of the file ``root``), names included."""
    root_p = Path(root)
    h = hashlib.sha256()
    for p in _package_files(root_p):
        h.update((p.relative_to(root_p.parent).as_posix() if root_p.is_dir() else p.name).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def _module_root(module: str) -> Path | None:
    """The directory of the top-level package of ``module`` (or its file, for a plain module);
    None where it has no source (a solver entry that does not import: its run fails, uncached)."""
    top = module.split(".")[0]
    loaded = sys.modules.get(top)
    if getattr(loaded, "__file__", None):  # imported already (``__main__`` included)
        origin = Path(loaded.__file__).resolve()
        return origin.parent if hasattr(loaded, "__path__") else origin
    try:
        spec = importlib.util.find_spec(top)
    except (ImportError, ValueError):
        spec = None
    if spec is None or spec.origin in (None, "built-in", "frozen"):
        return None
    origin = Path(spec.origin).resolve()
    return origin.parent if spec.submodule_search_locations else origin


def scene_sources(scene) -> list[Path]:
    """The source files of the scene's class and its base classes (a user's scene file among
    them); classes without a source file (builtins) are skipped."""
    out = []
    for cls in type(scene).__mro__:
        mod = sys.modules.get(cls.__module__)
        f = getattr(mod, "__file__", None)
        if f is None:
            try:
                f = inspect.getsourcefile(cls)
            except TypeError:
                f = None
        if f is not None and Path(f).is_file():
            p = Path(f).resolve()
            if p not in out:
                out.append(p)
    return out


def _version(lib: str) -> str:
    from importlib import metadata

    try:
        return metadata.version(lib)
    except metadata.PackageNotFoundError:
        return "absent"


def code_hash(solver_modules, scene) -> str:
    """SHA-256 (24 hex digits) of the code that decides a run's result (module doc): the packages
    of ``solver_modules`` (module names, e.g. ``("sph",)``), the core without the application, the
    scene's own source files (their bytes, wherever they lie) and the library versions."""
    found = {m: _module_root(m) for m in solver_modules}
    roots = {_CORE} | {r for r in found.values() if r is not None}
    h = hashlib.sha256()
    h.update(" ".join(sorted(m for m, r in found.items() if r is None)).encode())
    for root in sorted(roots):
        h.update(_tree_hash(str(root)).encode())
    for p in scene_sources(scene):
        if not any(r == p or r in p.parents for r in roots):
            h.update(b"scene source\n")
            h.update(p.read_bytes())  # read now: an edit of the file is a new key
    for lib in LIBRARIES:
        h.update(f"{lib}={_version(lib)}".encode())
    return h.hexdigest()[:24]


def _params(scene) -> dict:
    return dataclasses.asdict(scene) if dataclasses.is_dataclass(scene) else dict(vars(scene))


def describe(solver: str, scene, resolution, options: dict, solver_modules) -> dict:
    """What a key hashes: the run spec and the code hash (module doc)."""
    return dict(solver=solver, scene=type(scene).__qualname__, params=_params(scene),
                resolution=resolution, options=sorted([str(k), v] for k, v in options.items()),
                code=code_hash(solver_modules, scene))


def key(solver: str, scene, resolution, options: dict, solver_modules) -> str:
    """The cache key (24 hex digits) of one run (module doc)."""
    desc = describe(solver, scene, resolution, options, solver_modules)
    text = json.dumps(desc, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _path(k: str) -> Path | None:
    d = cache_dir()
    return None if d is None else d / f"{k}.pkl"


def _discard(path: Path, why: str) -> None:
    log.warning("run cache: entry %s discarded (%s); the run is recomputed", path, why)
    try:
        path.unlink()
    except OSError:
        pass


def _status_ok(status) -> bool:
    if isinstance(status, str):
        return status.startswith("ok")
    try:
        return len(status) > 0 and all(str(s).startswith("ok") for s in status)
    except TypeError:
        return False


def load(k: str) -> dict | None:
    """The result stored under key ``k``, verified (module doc); None when absent or discarded."""
    path = _path(k)
    if path is None or not path.exists():
        return None
    try:
        blob = path.read_bytes()
    except OSError as err:
        log.warning("run cache: entry %s cannot be read (%s); the run is recomputed", path, err)
        return None
    head, digest = len(MAGIC), blob[len(MAGIC):len(MAGIC) + 64]
    payload = blob[head + 65:]
    if not blob.startswith(MAGIC) or blob[head + 64:head + 65] != b"\n":
        return _discard(path, "not a run-cache entry")
    if hashlib.sha256(payload).hexdigest().encode() != digest:
        return _discard(path, "checksum mismatch: damaged or truncated")
    try:
        stored_key, out = pickle.loads(payload)
    except Exception as err:  # noqa: BLE001 - any unreadable payload is discarded
        return _discard(path, f"unreadable payload: {type(err).__name__}")
    if stored_key != k:
        return _discard(path, "stored under another key")
    if not isinstance(out, dict) or not _status_ok(out.get("status")):
        return _discard(path, "not a finished run's result")
    return out


def store(k: str, out: dict) -> None:
    """Store a finished run under key ``k`` (only a status ``ok``; synced to disk, then renamed
    into place: a kill leaves the whole entry or none). A cache that cannot be written is a
    warning, never a lost run."""
    path = _path(k)
    if path is None or not _status_ok(out.get("status", "")):
        return  # failures are not cached: they are re-tried
    out = {n: v for n, v in out.items() if n != "cached"}
    tmp = None
    try:
        payload = pickle.dumps((k, out), protocol=pickle.HIGHEST_PROTOCOL)
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            fh.write(MAGIC + hashlib.sha256(payload).hexdigest().encode() + b"\n" + payload)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)  # mkstemp makes it private; the cache may be shared
        os.replace(tmp, path)
    except (OSError, pickle.PicklingError, TypeError, AttributeError) as err:
        log.warning("run cache %s not written (%s: %s): this run will be recomputed next time",
                    path.parent, type(err).__name__, err)
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
