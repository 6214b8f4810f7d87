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
hexahedra (2×2×2 Gauss) for the homogeneous 3-D block, where locking cannot arise. Against
volumetric locking under nearly incompressible (plastic) flow the 2-D plane-strain element has an
F-bar option (``Discretisation(..., fbar=True)``; de Souza Neto et al. 1996): at each Gauss point
F̄ = (J̄/J)^{1/2} F with J̄ the L² projection of J onto linear polynomials over the element — the
small-strain equivalent of the inf–sup-stable Q2–P1 (9/3) mixed element, so neither volumetric
locking nor spurious modes — and the consistent (non-symmetric) tangent, see
:mod:`.assembly`. It is off by default (the elastic scenes, ν ≤ 0.4, keep the standard element and
their results); plane stress does not need it and does not take it.
tests/test_fem_locking.py shows it on the plane-strain thick-walled cylinder: Lamé's bore
displacement at ν = 0.4999 within 1e-4 (full integration 9 % short on 4 × 8 elements) and the von
Mises limit pressure within 0.1 % (full integration, ν = 0.4999: no limit).

Loads: dead surface tractions and pressures (:meth:`.assembly.Discretisation.traction_load`,
:meth:`~.assembly.Discretisation.pressure_load`) through ``Problem.f_ext``, and point forces on
nodes (``Problem(..., point_loads=((x, force), ...))``), all scaled by the load factor.
"""
from __future__ import annotations

from .cache import reference  # noqa: F401


def solve(scene, resolution: int, **options) -> dict:
    """Run the FEM on ``scene`` at ``resolution``; see the module docstring for the result keys."""
    from workbench.scenes import Cantilever, Plate, SSCurve

    from . import drivers

    if not isinstance(scene, Plate):  # only the plate's dynamic run writes mesh fields
        options.pop("fields", None)
        options.pop("field_frames", None)
    if isinstance(scene, SSCurve):
        return drivers.solve_ss_curve(scene, resolution, **options)
    if isinstance(scene, Cantilever):
        return drivers.solve_cantilever(scene, resolution, **options)
    if isinstance(scene, Plate):
        return drivers.solve_plate(scene, resolution, **options)
    raise ValueError(f"scene: {type(scene).__name__} has no FEM driver "
                     "(SSCurve, Cantilever, Plate)")
