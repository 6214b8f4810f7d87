"""scikit-fem total-Lagrangian finite-strain reference solver (the ``fem`` solver of scenes.md).

``solve(scene, resolution, **options) -> dict`` dispatches on the scene type:

- :class:`workbench.scenes.SSCurve` → :func:`fem_reference.drivers.solve_ss_curve`
  (resolution = hexahedra per edge);
- :class:`workbench.scenes.Cantilever` → :func:`fem_reference.drivers.solve_cantilever`
  (resolution = biquadratic quadrilaterals across H);
- :class:`workbench.scenes.Plate` → :func:`fem_reference.drivers.solve_plate`
  (resolution = biquadratic quadrilaterals across H; ``dynamic=False`` for the modal period only).

``reference(scene, quantity)`` returns a converged value from the on-disk cache
(:mod:`fem_reference.cache`), computing it once.

Pipeline: :mod:`.mesh` (structured meshes, element choice) → :mod:`.constitutive` (the shared
material library at the quadrature points; plane strain / plane stress) → :mod:`.assembly`
(total-Lagrangian residual and tangent; scikit-fem bases, forms and quadrature) → :mod:`.static`
(Newton, line search, load stepping), :mod:`.modal` (shift-invert eigenpairs), :mod:`.dynamic`
(Newmark) → :mod:`.drivers` (the scenes) → :mod:`.cache`; :mod:`.bench` times it.

Elements: biquadratic 9-node quadrilaterals (3×3 Gauss) in 2-D, free of shear locking; trilinear
hexahedra (2×2×2 Gauss) for the homogeneous 3-D block, where locking cannot arise. The 2-D scenes
are elastic (SVK or neo-Hooke, ν ≤ 0.4), so nothing here guards against volumetric locking; for a
future 2-D J2 scene the choice is F-bar (de Souza Neto et al. 1996: the element-mean J replaces
det F at the points of a Q2 element), not yet implemented.
"""
from __future__ import annotations

from .cache import reference  # noqa: F401


def solve(scene, resolution: int, **options) -> dict:
    """Run the FEM on ``scene`` at ``resolution``; see the module docstring for the result keys."""
    from workbench.scenes import Cantilever, Plate, SSCurve

    from . import drivers

    if isinstance(scene, SSCurve):
        return drivers.solve_ss_curve(scene, resolution, **options)
    if isinstance(scene, Cantilever):
        return drivers.solve_cantilever(scene, resolution, **options)
    if isinstance(scene, Plate):
        return drivers.solve_plate(scene, resolution, **options)
    raise ValueError(f"scene: {type(scene).__name__} has no FEM driver "
                     "(SSCurve, Cantilever, Plate)")
