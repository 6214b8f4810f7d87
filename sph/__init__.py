"""Particle methods of the workbench: the shared particle core (kernels, neighbour search,
particles from scene models, time integration, diagnostics, the driver) and one module per method.

:data:`METHODS` is the registry: a method is a module with ``NAME``, ``OPTIONS`` and
``build(particles, **options)`` returning a :class:`sph.method.ParticleBody`; adding one is a
module and a line here.

numba's on-disk cache keys each compiled function on its own source file only; the package drops
its cached machine code whenever any of its sources or the material library's change
(:func:`workbench.jitcache.guard`).
"""
from __future__ import annotations

from pathlib import Path

from workbench import jitcache as _jitcache
from workbench import materials as _materials

_here = Path(__file__).parent
_jitcache.guard(_here / "__pycache__",
                _jitcache.sources_of(_here, Path(_materials.__file__).parent))

METHODS = {
    "csph": "sph.csph",
    "hpm": "sph.hpm",
    "sph": "sph.classic",
}
"""Particle method name (the ``solver`` of the datasets) -> module."""
