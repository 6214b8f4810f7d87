"""numba's on-disk cache, kept honest across files.

``cache=True`` keys each compiled function on its own source file only: a function that calls
code from another file (a law of the material library from the particle loops, the mortar law from
the material dispatch) keeps its old machine code after that other file changes. A package that
compiles such callers calls :func:`guard` at import: when any of the given sources changed since
the cache was written, the package's cached machine code is dropped (numba compiles again, once).
"""
from __future__ import annotations

import hashlib
from pathlib import Path


def guard(cache_dir: Path, sources) -> None:
    """Drop the ``.nbi``/``.nbc`` files of ``cache_dir`` unless the hash of ``sources`` (paths)
    matches the one stored there. A read-only install is left alone (numba then compiles in
    memory)."""
    h = hashlib.sha1()
    for p in sorted(Path(s) for s in sources):
        if p.exists():
            h.update(p.name.encode())
            h.update(p.read_bytes())
    digest = h.hexdigest()
    stamp = cache_dir / "numba_sources.sha1"
    try:
        if stamp.exists() and stamp.read_text().strip() == digest:
            return
        cache_dir.mkdir(exist_ok=True)
        for f in list(cache_dir.glob("*.nbi")) + list(cache_dir.glob("*.nbc")):
            f.unlink(missing_ok=True)
        stamp.write_text(digest)
    except OSError:  # pragma: no cover - read-only install
        pass


def sources_of(*dirs) -> list[Path]:
    """The ``.py`` files of the given package directories."""
    return [p for d in dirs for p in sorted(Path(d).glob("*.py"))]
