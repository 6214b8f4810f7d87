"""Shapes of a scene: the geometry of its regions and of its named sets.

A shape answers one question, :meth:`Shape.contains`: which of the points ``X`` (N, d) lie in it.
Shapes are closed: a point on the boundary (within ``tol``, m) is inside, so that the face of a
box selects the particles or nodes lying on it; ``tol < 0`` asks for the interior (used to find
regions whose *interiors* overlap). They combine with ``|`` (union), ``&`` (intersection) and
``-`` (difference).

- :class:`Box` — an axis-aligned box ``lo ≤ X ≤ hi``;
- :class:`Cylinder` — a disc/annulus in 2-D, a (hollow) circular cylinder along a coordinate axis in
  3-D (a rebar, a ring);
- :class:`HalfSpace` — ``(X − point)·normal ≤ 0``;
- :class:`Plane` — the plane ``X[axis] = at`` (a face, a symmetry plane, a clamp face);
- :class:`Point` — one point (a probe, a point load);
- :class:`VoronoiCell` — the points nearer to seed ``index`` than to every other seed (ties go to
  the lower index, so the cells of one seed set partition space; optionally cut by ``within``);
- :class:`Where` — an explicit mask: any vectorised predicate ``fn(X) -> bool (N,)``.

:meth:`Shape.boxes` lists the axis-aligned boxes a shape is the union of (None if it is not one),
so that a structured mesh can follow region boundaries exactly.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from .params import SceneError


class Shape:
    """Base class of the shapes (frozen dataclasses)."""

    dim: int | None = None

    def contains(self, X: np.ndarray, tol: float = 0.0) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def bounds(self):
        """(lo, hi) arrays of an enclosing box, or None when unbounded."""
        return None

    def boxes(self):
        """The axis-aligned boxes whose union is this shape, as a list of (lo, hi), or None."""
        return None

    def __or__(self, other: "Shape") -> "Union":
        return Union((self, other))

    def __and__(self, other: "Shape") -> "Intersection":
        return Intersection((self, other))

    def __sub__(self, other: "Shape") -> "Difference":
        return Difference(self, other)


def _points(X) -> np.ndarray:
    X = np.asarray(X, dtype=np.float64)
    return X[None, :] if X.ndim == 1 else X


@dataclass(frozen=True)
class Box(Shape):
    """``lo ≤ X ≤ hi`` (componentwise), m."""

    lo: tuple
    hi: tuple

    def __post_init__(self):
        lo, hi = tuple(float(v) for v in self.lo), tuple(float(v) for v in self.hi)
        if len(lo) != len(hi) or len(lo) not in (2, 3):
            raise SceneError(f"Box: lo and hi must both have 2 or 3 coordinates (got {lo}, {hi})")
        if not all(h > l for l, h in zip(lo, hi)):
            raise SceneError(f"Box: hi must exceed lo in every coordinate (got {lo}, {hi})")
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "hi", hi)

    @property
    def dim(self) -> int:
        return len(self.lo)

    def contains(self, X, tol=0.0):
        X = _points(X)
        lo, hi = np.asarray(self.lo), np.asarray(self.hi)
        return np.all((X >= lo - tol) & (X <= hi + tol), axis=1)

    def bounds(self):
        return np.asarray(self.lo), np.asarray(self.hi)

    def boxes(self):
        return [(np.asarray(self.lo), np.asarray(self.hi))]


@dataclass(frozen=True)
class Cylinder(Shape):
    """A disc or annulus ``inner ≤ |X − centre| ≤ radius`` in 2-D (``axis`` None); in 3-D a
    circular cylinder along coordinate ``axis`` (0, 1 or 2), its axis through ``centre`` (the
    coordinate along the axis is ignored), between ``extent = (lo, hi)`` along it, hollow when
    ``inner > 0``."""

    centre: tuple
    radius: float
    inner: float = 0.0
    axis: int | None = None
    extent: tuple | None = None

    def __post_init__(self):
        object.__setattr__(self, "centre", tuple(float(c) for c in self.centre))
        if not (self.radius > 0 and 0 <= self.inner < self.radius):
            raise SceneError(f"Cylinder: need 0 <= inner < radius (got inner={self.inner}, "
                             f"radius={self.radius})")
        if len(self.centre) == 3:
            if self.axis not in (0, 1, 2) or self.extent is None:
                raise SceneError("Cylinder: in 3-D give axis (0, 1 or 2) and extent (lo, hi)")
        elif len(self.centre) != 2:
            raise SceneError(f"Cylinder: centre must have 2 or 3 coordinates (got {self.centre})")

    @property
    def dim(self) -> int:
        return len(self.centre)

    def _radial(self, X):
        c = np.asarray(self.centre)
        if self.dim == 2:
            return np.linalg.norm(X - c, axis=1), None
        other = [k for k in range(3) if k != self.axis]
        return np.linalg.norm(X[:, other] - c[other], axis=1), X[:, self.axis]

    def contains(self, X, tol=0.0):
        X = _points(X)
        r, s = self._radial(X)
        ok = (r <= self.radius + tol) & (r >= self.inner - tol)
        if s is not None:
            ok &= (s >= self.extent[0] - tol) & (s <= self.extent[1] + tol)
        return ok

    def bounds(self):
        c = np.asarray(self.centre, dtype=float)
        lo, hi = c - self.radius, c + self.radius
        if self.dim == 3:
            lo[self.axis], hi[self.axis] = self.extent
        return lo, hi


@dataclass(frozen=True)
class HalfSpace(Shape):
    """``(X − point)·normal ≤ 0``: the side of the plane through ``point`` away from ``normal``."""

    point: tuple
    normal: tuple

    def __post_init__(self):
        n = np.asarray(self.normal, dtype=float)
        if not np.linalg.norm(n) > 0 or len(n) != len(self.point):
            raise SceneError("HalfSpace: normal must be a non-zero vector of the point's dimension")
        object.__setattr__(self, "point", tuple(float(v) for v in self.point))
        object.__setattr__(self, "normal", tuple(float(v) for v in n / np.linalg.norm(n)))

    @property
    def dim(self) -> int:
        return len(self.point)

    def contains(self, X, tol=0.0):
        X = _points(X)
        return (X - np.asarray(self.point)) @ np.asarray(self.normal) <= tol


@dataclass(frozen=True)
class Plane(Shape):
    """The plane ``X[axis] = at``, m (a face, a clamp face, a symmetry plane)."""

    axis: int
    at: float

    def __post_init__(self):
        if self.axis not in (0, 1, 2):
            raise SceneError(f"Plane: axis must be 0, 1 or 2 (got {self.axis})")

    def contains(self, X, tol=0.0):
        X = _points(X)
        return np.abs(X[:, self.axis] - self.at) <= max(tol, 0.0)


@dataclass(frozen=True)
class Point(Shape):
    """One point, m: a probe or the point of a point load (the methods interpolate there)."""

    at: tuple

    def __post_init__(self):
        object.__setattr__(self, "at", tuple(float(v) for v in self.at))

    @property
    def dim(self) -> int:
        return len(self.at)

    def contains(self, X, tol=0.0):
        X = _points(X)
        return np.linalg.norm(X - np.asarray(self.at), axis=1) <= max(tol, 0.0)

    def bounds(self):
        p = np.asarray(self.at)
        return p, p


@dataclass(frozen=True)
class VoronoiCell(Shape):
    """The Voronoi cell of ``seeds[index]`` (seeds (k, d), m): the points nearer to it than to
    every other seed, ties to the lower seed index (so the cells of one seed set partition space
    exactly: each point belongs to one cell), cut by ``within`` when given. The assignment to the
    nearest seed is exact for any point set (no polyhedra are built)."""

    seeds: tuple
    index: int
    within: Shape | None = None

    def __post_init__(self):
        s = np.asarray(self.seeds, dtype=float)
        if s.ndim != 2 or s.shape[1] not in (2, 3) or not (0 <= self.index < len(s)):
            raise SceneError(f"VoronoiCell: seeds must be (k, 2 or 3) and 0 <= index < k "
                             f"(got shape {s.shape}, index {self.index})")
        object.__setattr__(self, "seeds", tuple(tuple(float(v) for v in row) for row in s))

    @property
    def dim(self) -> int:
        return len(self.seeds[0])

    def contains(self, X, tol=0.0):
        X = _points(X)
        s = np.asarray(self.seeds)
        d2 = ((X[:, None, :] - s[None, :, :]) ** 2).sum(axis=2)
        ok = np.argmin(d2, axis=1) == self.index
        if self.within is not None:
            ok &= self.within.contains(X, tol)
        return ok

    def bounds(self):
        return self.within.bounds() if self.within is not None else None


@dataclass(frozen=True)
class Where(Shape):
    """An explicit mask: the points where ``fn(X)`` (a vectorised predicate, (N, d) → bool (N,))
    is true. ``label`` names it in messages and attributes."""

    fn: Callable
    label: str = "mask"

    def contains(self, X, tol=0.0):
        return np.asarray(self.fn(_points(X)), dtype=bool)


@dataclass(frozen=True)
class Union(Shape):
    parts: tuple

    def contains(self, X, tol=0.0):
        X = _points(X)
        out = np.zeros(len(X), bool)
        for p in self.parts:
            out |= p.contains(X, tol)
        return out

    def bounds(self):
        b = [p.bounds() for p in self.parts]
        if any(x is None for x in b):
            return None
        return np.min([x[0] for x in b], axis=0), np.max([x[1] for x in b], axis=0)

    def boxes(self):
        out = []
        for p in self.parts:
            bx = p.boxes()
            if bx is None:
                return None
            out += bx
        return out


@dataclass(frozen=True)
class Intersection(Shape):
    parts: tuple

    def contains(self, X, tol=0.0):
        X = _points(X)
        out = np.ones(len(X), bool)
        for p in self.parts:
            out &= p.contains(X, tol)
        return out

    def bounds(self):
        b = [p.bounds() for p in self.parts if p.bounds() is not None]
        if not b:
            return None
        return np.max([x[0] for x in b], axis=0), np.min([x[1] for x in b], axis=0)


@dataclass(frozen=True)
class Difference(Shape):
    """``a`` without the interior of ``b`` (the common boundary stays in: the result is closed)."""

    a: Shape
    b: Shape

    def contains(self, X, tol=0.0):
        X = _points(X)
        return self.a.contains(X, tol) & ~self.b.contains(X, -abs(tol))

    def bounds(self):
        return self.a.bounds()
