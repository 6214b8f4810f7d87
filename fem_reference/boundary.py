"""Boundary conditions and loads by node sets, for any drive: each value or load is scaled by a
function of the load parameter — the load factor λ of a static run, the time t of a dynamic run
(:func:`fem_reference.dynamic.newmark` passes t as the parameter).

A node set is a predicate ``where(x) -> bool (n,)`` on node coordinates x (d, n) in the reference
configuration (scikit-fem's convention), e.g. ``lambda x: x[0] < 1e-9`` or a scene shape's
``contains``. Every node of the discretisation is tested (vertices, mid-side, face and centre
nodes of the quadratic elements).

- :class:`Constraints` — Dirichlet conditions: :meth:`~Constraints.clamp` (all components zero),
  :meth:`~Constraints.roller` (one component zero: a roller or symmetry plane),
  :meth:`~Constraints.prescribe` (one component, a value or a function of the parameter).
- :class:`Loads` — Neumann data and body forces: dead traction on the boundary facets of a node
  set (:meth:`~Loads.traction`), dead pressure (:meth:`~Loads.pressure`), point forces
  (:meth:`~Loads.point`), body force ρ g with each element's density (:meth:`~Loads.body`).

Both are callables of the parameter, so that ``Problem(disc, table, plane, constraints.values,
loads, mat_id=...)`` takes them directly after ``constraints.apply()``.
"""
from __future__ import annotations

from typing import Callable

import numpy as np


def _scale_fn(scale) -> Callable[[float], float]:
    """The parameter function: None → proportional (s(λ) = λ), a number c → constant c, or a
    callable."""
    if scale is None:
        return lambda lam: lam
    if callable(scale):
        return scale
    c = float(scale)
    return lambda lam: c


class Constraints:
    """Dirichlet conditions of a :class:`~fem_reference.assembly.Discretisation`.

    Later conditions override earlier ones on a shared DOF. ``dofs`` (sorted) and
    ``values(λ)`` (aligned with it) are what :class:`~fem_reference.static.Problem` reads;
    :meth:`apply` sets them as the discretisation's fixed DOFs.
    """

    def __init__(self, disc):
        self.disc = disc
        self._items: list[tuple[np.ndarray, Callable]] = []

    def _add(self, dofs, value):
        dofs = np.asarray(dofs, dtype=np.int64)
        if callable(value):
            fn = value
        else:
            v = np.asarray(value, dtype=float)
            fn = lambda lam: v  # noqa: E731
        self._items.append((dofs, fn))
        return dofs

    def _nodes(self, where, component):
        dofs = self.disc.dofs_where(where, component)
        if not len(dofs):
            raise ValueError("where: the node set selects no node of the mesh")
        return dofs

    def clamp(self, where) -> np.ndarray:
        """All displacement components zero on the nodes of ``where``; returns the DOFs."""
        return self._add(self._nodes(where, None), 0.0)

    def roller(self, where, component: int) -> np.ndarray:
        """Displacement ``component`` zero on the nodes of ``where`` (a roller, or a symmetry
        plane with that normal); returns the DOFs."""
        return self._add(self._nodes(where, component), 0.0)

    def prescribe(self, where, component: int, value) -> np.ndarray:
        """Displacement ``component`` on the nodes of ``where`` equal to ``value`` (m): a number
        (times the parameter: u = value·λ) or a function of the parameter returning a number or
        one value per selected DOF. Returns the DOFs."""
        dofs = self._nodes(where, component)
        if not callable(value):
            c = float(value)
            value = lambda lam: c * lam  # noqa: E731
        return self._add(dofs, value)

    def prescribe_dofs(self, dofs, value) -> np.ndarray:
        """The same on explicit DOFs: ``value(λ)`` a number or an array (len(dofs),)."""
        return self._add(dofs, value)

    @property
    def dofs(self) -> np.ndarray:
        if not self._items:
            return np.zeros(0, dtype=np.int64)
        return np.unique(np.concatenate([d for d, _ in self._items]))

    def values(self, lam: float) -> np.ndarray:
        """Prescribed values (len(dofs),) at the parameter λ."""
        g = np.zeros(self.disc.N)
        for dofs, fn in self._items:
            g[dofs] = fn(lam)
        return g[self.dofs]

    def apply(self) -> "Constraints":
        """Make these the discretisation's fixed DOFs."""
        self.disc.set_fixed(self.dofs)
        return self


class Loads:
    """External force f_ext(λ) = Σ_k s_k(λ) f_k of dead loads, each with its parameter function
    s_k (``scale``: None → s = λ, a number → constant, a callable).

    Tractions and pressures act on the boundary facets whose vertices all lie in the node set;
    body forces use the elements' densities and are recomputed after element deletion (a deleted
    element carries no weight); the other loads are fixed vectors.
    """

    def __init__(self, disc):
        self.disc = disc
        self._items: list[tuple[np.ndarray, Callable]] = []
        self._body: list[tuple[np.ndarray, np.ndarray, Callable]] = []

    def vector(self, f: np.ndarray, scale=None) -> np.ndarray:
        """Any nodal force vector (N,), N (N/m in 2-D)."""
        f = np.asarray(f, dtype=float)
        if f.shape != (self.disc.N,):
            raise ValueError(f"f: shape {f.shape} is not ({self.disc.N},)")
        self._items.append((f, _scale_fn(scale)))
        return f

    def _facets(self, where):
        facets = self.disc.facets_where(where)
        if not len(facets):
            raise ValueError("where: the node set contains no boundary facet")
        return facets

    def traction(self, where, t, scale=None) -> np.ndarray:
        """Dead traction t (d,) (force per reference area, Pa) on the boundary facets of the
        node set ``where``."""
        t = np.asarray(t, dtype=float)
        if t.shape != (self.disc.d,):
            raise ValueError(f"t: a traction has {self.disc.d} components, got shape {t.shape}")
        return self.vector(self.disc.traction_load(self._facets(where), t), scale)

    def pressure(self, where, p: float, scale=None) -> np.ndarray:
        """Dead pressure p (Pa, positive pushing inwards) on the boundary facets of ``where``:
        the nominal traction −p N with N the reference outward normal."""
        return self.vector(self.disc.pressure_load(self._facets(where), float(p)), scale)

    def point(self, x, force, scale=None) -> np.ndarray:
        """Point force ``force`` (d,) (N; N/m in 2-D) at the point x (d,) of the reference
        configuration: the consistent nodal forces N_a(x) force of the element containing x (on
        a node, the force on that node alone)."""
        x = np.asarray(x, dtype=float).reshape(1, -1)
        force = np.asarray(force, dtype=float)
        if force.shape != (self.disc.d,):
            raise ValueError(f"force: a force has {self.disc.d} components, got {force.shape}")
        # probe (d·1, N): row i interpolates component i; its transpose spreads a force
        return self.vector(self.disc.probe(x).T @ force, scale)

    def body(self, rho, g, scale=None) -> None:
        """Body force ρ g per unit reference volume; ``rho`` (kg/m³) a number or one per element
        (nel,), g (d,) m/s²."""
        rho = np.broadcast_to(np.asarray(rho, dtype=float), (self.disc.nel,)).copy()
        g = np.asarray(g, dtype=float)
        if g.shape != (self.disc.d,):
            raise ValueError(f"g: an acceleration has {self.disc.d} components, got {g.shape}")
        self._body.append((rho, g, _scale_fn(scale)))

    def __call__(self, lam: float) -> np.ndarray:
        f = np.zeros(self.disc.N)
        for vec, fn in self._items:
            f += fn(lam) * vec
        for rho, g, fn in self._body:
            s = fn(lam)
            if s != 0.0:
                f += s * self.disc.body_load(rho, g)
        return f
