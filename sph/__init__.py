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
    "csph": ("sph.csph", {}),
    "csph_quad": ("sph.csph", {"correction": "quadratic", "integration": "nodal"}),
    "csph_bl": ("sph.csph", {"correction": "linear", "integration": "nodal"}),
    "hpm": ("sph.hpm", {}),
    "hpm_vc": ("sph.csph", {"gradient": "wls"}),
    "sph": ("sph.classic", {}),
}
"""Particle method name (the ``solver`` of the datasets) -> (module, default options). ``csph`` is
the integration-consistent corrected SPH (quadratic correction), ``csph_quad`` the same gradient
with nodal integration, ``csph_bl`` paper 000's CSPH as printed (Bonet–Lok correction, nodal
integration); ``hpm`` paper 004's method, ``hpm_vc`` its gradient with the consistent integration
(quadratic basis); ``sph`` classic SPH (paper 003)."""
