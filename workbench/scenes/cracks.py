"""Cracks in the scene vocabulary: :class:`PreCrack` (a zero-width crack the particle methods
cut their pairs along) and :class:`CrackTip` (the observable of a growing crack), with the checks
:class:`~workbench.scenes.model.Model` makes of them. Both are part of
:mod:`workbench.scenes.model` (imported there); the geometry is
:mod:`workbench.crack_geometry`."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..crack_geometry import polygon_problem
from .params import SceneError


@dataclass(frozen=True)
class PreCrack:
    """A zero-width crack in the reference configuration: no particle interacts with a particle
    on its other side. ``points``: in 2-D the two end points (a segment, m); in 3-D three or more
    coplanar points, the vertices of a convex polygon in order (:meth:`rectangle` makes one).

    The particle methods cut every neighbour pair whose reference segment X_a–X_b crosses the
    crack (closed: a pair through an end point or an edge is cut), whatever the kernel's reach
    (:func:`sph.neighbours.cut_pairs`), before the gradient correction is computed: each side is
    then a body with a free face along the crack, and the notch has no width at any spacing. A
    particle exactly on the crack's line (plane) belongs to the side its normal points to
    (:func:`workbench.crack_geometry.facets`); place a crack between lattice planes to keep the
    crack faces where they are drawn (on a lattice plane they lie half a spacing towards the other
    side). The FEM does not cut elements: it refuses a model with a pre-crack."""

    name: str
    points: tuple

    def __post_init__(self):
        pts = np.asarray(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] not in (2, 3) or not np.all(np.isfinite(pts)):
            raise SceneError(f"pre-crack '{self.name}': points must be finite (x, y) or (x, y, z) "
                             f"points, got {self.points!r}")
        object.__setattr__(self, "points", tuple(tuple(float(c) for c in p) for p in pts))

    @property
    def dim(self) -> int:
        return len(self.points[0])

    @classmethod
    def rectangle(cls, name: str, corner, edge1, edge2) -> "PreCrack":
        """A 3-D rectangular (or parallelogram) crack: the corner, m, and its two edges from it
        (vectors, m): vertices corner, corner + edge1, corner + edge1 + edge2, corner + edge2."""
        c, e1, e2 = (np.asarray(v, dtype=float) for v in (corner, edge1, edge2))
        return cls(name, (tuple(c), tuple(c + e1), tuple(c + e1 + e2), tuple(c + e2)))


@dataclass(frozen=True)
class CrackTip:
    """The growing crack that starts at ``origin``: its failed particles of the named ``regions``
    (all when None; the driver's failed-particle mask) ordered into a path from ``origin``
    (:func:`workbench.crack_geometry.crack_path`). ``origin``: a point (d,), m, or the name of a
    :class:`PreCrack` — its last point is then the origin (the tip the crack grows from; in 3-D
    the last vertex).

    Recorded with every observable (explicit drives at each record, static ones at each load
    value), as ``<name>_x``, ``<name>_y`` (, ``<name>_z``) the tip, m (the origin while nothing
    has failed), ``<name>_length`` the path's length from the origin, m, ``<name>_angle`` the
    kink angle, degrees, between the pre-crack's direction (``direction``, or the PreCrack's
    last segment; in 3-D None: the path's first leg) and the path's direction near the tip
    (counter-clockwise positive in 2-D, 0..180 in 3-D), and ``<name>_speed`` the tip speed, m/s
    (the difference quotient of the length between records; per unit load parameter in a static
    drive). ``spacing``: the bin width along the path in units of the particle spacing (default
    2: a crack band two particles wide makes one point per bin). The run's result also holds
    ``<name>_path`` (K, d), m: the path (origin, centroids, tip) at the last record — in the
    generic study's dataset a NaN-padded variable over (``<name>_point``,
    ``<name>_coordinate``)."""

    name: str
    origin: object
    regions: tuple | None = None
    direction: tuple | None = None
    spacing: float = 2.0

    def outputs(self, dim: int) -> tuple:
        """The quantities the observable records: ((name, units), ...)."""
        xyz = tuple((f"{self.name}_{c}", "m") for c in "xyz"[:dim])
        return xyz + ((f"{self.name}_length", "m"), (f"{self.name}_angle", "deg"),
                      (f"{self.name}_speed", "m/s"))


def check_cracks(model) -> None:
    """The pre-cracks of ``model`` (SceneError, one line, otherwise): unique names, and each a
    segment of two distinct points in 2-D, in 3-D a planar, convex polygon of at least three
    vertices with a non-zero area."""
    names = [c.name for c in model.cracks]
    if len(set(names)) != len(names):
        raise SceneError(f"pre-crack: a name is used twice ({', '.join(names)})")
    for c in model.cracks:
        if not isinstance(c, PreCrack):
            raise SceneError(f"cracks: {c!r} is not a PreCrack")
        if c.dim != model.dim:
            raise SceneError(f"pre-crack '{c.name}': {c.dim}-D points in a {model.dim}-D model")
        pts = np.asarray(c.points)
        if model.dim == 2:
            if len(pts) != 2 or not np.linalg.norm(pts[1] - pts[0]) > 0:
                raise SceneError(f"pre-crack '{c.name}': a 2-D crack is a segment; allowed: "
                                 f"two distinct points (got {len(pts)} points)")
        else:
            why = polygon_problem(pts)
            if why:
                raise SceneError(f"pre-crack '{c.name}': {why}; allowed: three or more "
                                 "coplanar vertices of a convex polygon, in order")


def check_tip(model, o) -> None:
    """The :class:`CrackTip` ``o`` of ``model`` (SceneError, one line, otherwise): its origin (a
    point in the model's dimension or one of its pre-cracks), direction and spacing."""
    if isinstance(o.origin, str):
        if o.origin not in {c.name for c in model.cracks}:
            known = ", ".join(c.name for c in model.cracks) or "none"
            raise SceneError(f"observable '{o.name}': origin '{o.origin}' is not a PreCrack of "
                             f"this model (pre-cracks: {known})")
    elif np.shape(o.origin) != (model.dim,) or not np.all(np.isfinite(np.asarray(o.origin, float))):
        raise SceneError(f"observable '{o.name}': origin {o.origin!r} is not allowed; a "
                         f"{model.dim}-D point or the name of a PreCrack")
    if o.direction is not None and (np.shape(o.direction) != (model.dim,)
                                    or not np.linalg.norm(np.asarray(o.direction, float)) > 0):
        raise SceneError(f"observable '{o.name}': direction {o.direction!r} is not allowed; a "
                         f"non-zero {model.dim}-D vector or None")
    if not (isinstance(o.spacing, (int, float)) and 0.5 <= o.spacing <= 20):
        raise SceneError(f"observable '{o.name}': spacing {o.spacing!r} is out of range; "
                         "allowed: [0.5, 20] particle spacings")
