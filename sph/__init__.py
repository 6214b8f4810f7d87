"""Particle methods of the workbench: the shared particle core (kernels, neighbour search,
lattices, time integration, diagnostics) and one module per method (``csph``, …).

numba's on-disk cache (``cache=True``) keys each compiled function on its own source file only: a
function that calls code from another file (the material library, or a row routine of this
package) keeps the old callee after that file changes. :func:`_guard_numba_cache` therefore drops
this package's cached machine code whenever any of its sources or the material kernels change.
"""
from __future__ import annotations

import hashlib
from pathlib import Path


def _guard_numba_cache() -> None:
    here = Path(__file__).parent
    sources = sorted(here.glob("*.py"))
    try:
        import workbench.materials as _m

        sources.append(Path(_m.__file__).parent / "kernels.py")
    except Exception:  # pragma: no cover - material library missing: nothing to guard
        return
    h = hashlib.sha1()
    for p in sources:
        if p.exists():
            h.update(p.name.encode())
            h.update(p.read_bytes())
    digest = h.hexdigest()
    cache = here / "__pycache__"
    stamp = cache / "numba_sources.sha1"
    try:
        if stamp.exists() and stamp.read_text().strip() == digest:
            return
        cache.mkdir(exist_ok=True)
        for f in list(cache.glob("*.nbi")) + list(cache.glob("*.nbc")):
            f.unlink(missing_ok=True)
        stamp.write_text(digest)
    except OSError:  # read-only install: numba falls back to compiling in memory
        pass


_guard_numba_cache()
