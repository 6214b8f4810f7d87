"""scikit-fem total-Lagrangian finite-strain reference solver (the ``fem`` solver of scenes.md).

``solve_model(scene, resolution, drive=None, element=None, fbar=None, deletion=False, fields=None,
**options) -> dict`` (:mod:`fem_reference.model`) reads any scene model
(:class:`workbench.scenes.model.Model`: regions, sets, constraints, loads, drive, observables) —
the FEM's counterpart of the particle methods' :func:`sph.driver.solve`, with the same result keys;
``resolution`` is the number of elements across ``model.length``.

``solve(scene, resolution, **options) -> dict`` runs every scene, the headline ones included,
through it (:func:`fem_reference.model.solve`; the plate study's ``dynamic`` option: False for
the modal periods only, True for the Newmark run with ``period`` the modal one).

``reference(scene, quantity)`` returns a converged value from the on-disk cache
(:mod:`fem_reference.cache`), computing it once.

Pipeline: :mod:`.mesh` (structured meshes — rectangles, rings, tubes, unions of boxes with the
element size from a resolution — and the element choice) → :mod:`.constitutive` (the shared
material library at the quadrature points, a material id per element; plane strain / plane
stress) → :mod:`.assembly` (total-Lagrangian residual and tangent, consistent mass and body force
with a density per element, F-bar, element deletion; scikit-fem bases, forms and quadrature) →
:mod:`.boundary` (Dirichlet conditions and loads on node sets, scaled by functions of the load
parameter or time) → :mod:`.static` (the :class:`~.static.Problem`: materials per element,
Newton, line search, load stepping, deletion of failed elements), :mod:`.modal` (shift-invert
eigenpairs), :mod:`.dynamic` (Newmark) → :mod:`.observe` (reactions, displacement at any point,
energies, mean stress, failed fraction) → :mod:`.model` (the reader of scene models: mesh, sets,
constraints, loads, drive, observables) → :mod:`.cache`; :mod:`.drivers` holds the problems that are
not scenes (the thick tube with its curved mesh, the micro-cantilever with its loaded patch);
:mod:`.bench` times it.

Elements: biquadratic 9-node quadrilaterals (3×3 Gauss) in 2-D, free of shear locking; trilinear
hexahedra (2×2×2 Gauss) for homogeneous 3-D states (the ss-curve block), triquadratic 27-node
hexahedra (3×3×3 Gauss, ``order=2``) for 3-D bodies that bend (the 8-node element shear-locks:
tests/test_fem_3d.py). Against volumetric locking under nearly incompressible (plastic) flow the
quadratic elements have an F-bar option in 2-D plane strain and in 3-D
(``Discretisation(..., fbar=True)``; de Souza Neto et al. 1996): at each Gauss point
F̄ = (J̄/J)^{1/d} F with J̄ the L² projection of J onto linear polynomials over the element — the
small-strain equivalent of the inf–sup-stable Q2–P1 element, so neither volumetric locking nor
spurious modes — and the consistent (non-symmetric) tangent, see :mod:`.assembly`. It is off by
default (the elastic scenes, ν ≤ 0.4, keep the standard element and their results); plane stress
does not need it and does not take it. tests/test_fem_locking.py and tests/test_fem_3d.py show it
on the plane-strain thick-walled cylinder (2-D, and a 3-D slice with plane-strain ends): Lamé's
bore displacement at ν = 0.4999 within 1e-4 (full integration 9 % short on 4 × 8 elements) and the
von Mises limit pressure within 0.1 % (full integration, ν = 0.4999: no limit).

Bodies of several materials: ``Problem(disc, MaterialTable((m0, m1, …)), plane, fixed_values,
f_ext, mat_id=…)`` with a row per element. Fracture: ``Problem(..., deletion=True)`` deletes an
element once a point reaches the damage D ≥ 1 of the J2 law (:mod:`.static`).

Loads: dead surface tractions and pressures, point loads (at any point: consistent nodal forces),
body forces ρ g (:class:`.boundary.Loads`; also :meth:`.assembly.Discretisation.traction_load`,
:meth:`~.assembly.Discretisation.pressure_load` through ``Problem.f_ext``, and
``Problem(..., point_loads=((x, force), ...))`` on nodes), all scaled by the load factor or a
function of it.
"""
from __future__ import annotations

from .cache import reference  # noqa: F401
from .model import solve, solve_model  # noqa: F401
