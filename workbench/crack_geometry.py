"""The geometry of cracks, as pure functions of points: pre-cracks as facets (what the particle
methods cut their neighbour pairs with) and the path of a growing crack from its failed particles
(what :class:`~workbench.scenes.model.CrackTip` records).

**Facets.** A 2-D pre-crack is one segment [A, B]; a 3-D one a planar convex polygon, split into
the triangles of a fan from its first vertex (all with the polygon's orientation). A point P is on
the *positive* side of a facet when (B − A) × (P − A) ≥ 0 (2-D: the left of A → B) or
((B − A) × (C − A)) · (P − A) ≥ 0 (3-D: the side the polygon's right-handed normal points to);
a point on the facet's line or plane is on the positive side, so that every particle belongs to
exactly one side. A pair (P, Q) crosses the facet when P and Q lie on different sides and the
point where the segment P–Q meets the line (plane) lies in the closed facet.

**Crack path** (:func:`crack_path`). The failed particles linked to the origin by chains of
failed particles no farther apart than the bin width w (a crack band is a few particles wide;
isolated failures elsewhere do not belong to this crack) are ordered by their distance from the
origin along those chains (Dijkstra on the graph of links). Binned in slices of width w of that
distance, the centroids of the slices are the crack's centreline (a band of any width, a lattice
staircase, collapses onto its middle). The tip is the farthest failed particle projected onto the
centreline's last leg (exact for a straight band, whatever its width); the length is that of the
polyline origin → centroids → tip; the direction of growth is the line through the origin that
best fits (least squares) the centroids of the first half of the path (at least two slices), and
the kink angle is the angle from a reference direction (the pre-crack's) to it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

FLAT_TOL = 1e-9
"""A 3-D pre-crack's vertices may lie this far (times the polygon's size) off its plane."""


def polygon_problem(points) -> str:
    """What is wrong with ``points`` (K, 3) as the vertices of a planar convex polygon in order
    ('' when nothing): fewer than three, zero area, off one plane, or not convex."""
    P = np.asarray(points, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) < 3:
        return f"{len(P)} point(s) do not make a polygon"
    size = float(np.ptp(P, axis=0).max())
    n = np.zeros(3)
    for k in range(1, len(P) - 1):
        n += np.cross(P[k] - P[0], P[k + 1] - P[0])
    if not np.linalg.norm(n) > FLAT_TOL * size * size:
        return "the polygon has no area"
    n /= np.linalg.norm(n)
    if np.abs((P - P[0]) @ n).max() > FLAT_TOL * size:
        return "the vertices do not lie in one plane"
    K = len(P)
    turns = [np.dot(np.cross(P[(k + 1) % K] - P[k], P[(k + 2) % K] - P[(k + 1) % K]), n)
             for k in range(K)]
    if min(turns) < -FLAT_TOL * size * size:
        return "the polygon is not convex (or its vertices are not in order)"
    return ""


def facets(cracks, dim: int, mirrors=()) -> np.ndarray:
    """The facets of the pre-cracks ``cracks`` (objects with ``points``; module docstring):
    (K, d, d) float64, K segments [A, B] in 2-D, K triangles [A, B, C] in 3-D. ``mirrors``:
    symmetry planes ((axis, at), ...): the facets' mirror images across every combination of them
    are added (a body computed as its full mirror image sees the whole crack)."""
    out = []
    for c in cracks:
        P = np.asarray(c.points, dtype=float)
        if dim == 2:
            out.append(P[:2])
        else:
            out.extend(np.stack([P[0], P[k], P[k + 1]]) for k in range(1, len(P) - 1))
    F = np.asarray(out, dtype=float).reshape(-1, dim, dim)
    planes = [(int(a), float(at)) for a, at, *_ in mirrors]
    for a, at in planes:
        img = F.copy()
        img[:, :, a] = 2.0 * at - img[:, :, a]
        img = img[:, ::-1] if dim == 2 else img[:, [0, 2, 1]]  # keep the positive side's image
        F = np.concatenate([F, img])
    return np.ascontiguousarray(F)


def crosses(P, Q, F) -> np.ndarray:
    """(M,) bool: whether the segment P_m–Q_m (P, Q (M, d)) crosses a facet of F (K, d, d) (module
    docstring; vectorised numpy, the reference of :func:`sph.neighbours.cut_pairs`)."""
    P = np.atleast_2d(np.asarray(P, float))
    Q = np.atleast_2d(np.asarray(Q, float))
    out = np.zeros(len(P), bool)
    d = P.shape[1]
    for f in np.asarray(F, float):
        A = f[0]
        if d == 2:
            t = f[1] - A
            sP = t[0] * (P[:, 1] - A[1]) - t[1] * (P[:, 0] - A[0])
            sQ = t[0] * (Q[:, 1] - A[1]) - t[1] * (Q[:, 0] - A[0])
        else:
            nrm = np.cross(f[1] - A, f[2] - A)
            sP = (P - A) @ nrm
            sQ = (Q - A) @ nrm
        tol = 1e-12 * np.linalg.norm(Q - P, axis=1) * np.linalg.norm(f[1] - A) ** (d - 1)
        sP = np.where(np.abs(sP) <= tol, 0.0, sP)
        sQ = np.where(np.abs(sQ) <= tol, 0.0, sQ)
        split = (sP >= 0) != (sQ >= 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            lam = np.where(split, sP / (sP - sQ), 0.0)
        X = P + lam[:, None] * (Q - P)
        if d == 2:
            t = f[1] - A
            u = (X - A) @ t / (t @ t)
            inside = (u >= -1e-12) & (u <= 1 + 1e-12)
        else:
            inside = np.ones(len(P), bool)
            for k in range(3):
                e = f[(k + 1) % 3] - f[k]
                inside &= (np.cross(e, X - f[k]) @ nrm) >= -1e-12 * (nrm @ nrm)
        out |= split & inside
    return out


@dataclass(frozen=True)
class CrackPath:
    """A crack's path from its origin (:func:`crack_path`): ``path`` (K, d) the origin, the
    centroids of the slices and the tip, m; ``tip`` (d,), m; ``length``, m; ``direction`` (d,)
    the unit direction of growth (NaN without failed particles); ``angle`` the kink angle, degrees
    (NaN without a reference or a path); ``members`` the indices of the points on the crack."""

    path: np.ndarray
    tip: np.ndarray
    length: float
    direction: np.ndarray
    angle: float
    members: np.ndarray


def crack_path(points, origin, width: float, reference=None) -> CrackPath:
    """The path of the crack through the failed ``points`` (n, d), m, that grows from ``origin``
    (d,), m, with slices (and links) of ``width`` w, m (module docstring). ``reference`` (d,) or
    None: the direction the kink angle is measured from (2-D: signed, counter-clockwise positive,
    in (−180, 180]; 3-D: 0..180)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra
    from scipy.spatial import cKDTree

    P = np.asarray(points, dtype=float).reshape(-1, len(origin))
    o = np.asarray(origin, dtype=float)
    d = o.size
    if not width > 0:
        raise ValueError(f"width: {width!r} is not allowed; must be > 0 m")
    empty = CrackPath(o[None, :].copy(), o.copy(), 0.0, np.full(d, np.nan), math.nan,
                      np.zeros(0, np.int64))
    if len(P) == 0:
        return empty
    # the graph: node 0 the origin, node i + 1 the point i; links no longer than the width
    pairs = cKDTree(P).query_pairs(width * (1 + 1e-9), output_type="ndarray")
    r0 = np.linalg.norm(P - o, axis=1)
    start = np.nonzero(r0 <= width * (1 + 1e-9))[0]
    if start.size == 0:
        return empty
    i = np.concatenate([pairs[:, 0] + 1, np.zeros(start.size, np.int64)])
    j = np.concatenate([pairs[:, 1] + 1, start + 1])
    w = np.concatenate([np.linalg.norm(P[pairs[:, 0]] - P[pairs[:, 1]], axis=1), r0[start]])
    w = np.maximum(w, 1e-300 * width)  # a zero length would read as no link
    g = coo_matrix((w, (i, j)), shape=(len(P) + 1, len(P) + 1)).tocsr()
    s = dijkstra(g, directed=False, indices=0)[1:]
    members = np.nonzero(np.isfinite(s))[0]
    s = s[members]
    Pm = P[members]
    k = np.floor(s / width).astype(np.int64)
    bins = np.unique(k)
    cent = np.stack([Pm[k == b].mean(axis=0) for b in bins])
    far = Pm[np.argmax(s)]
    prev = cent[-2] if len(cent) > 1 else o
    leg = cent[-1] - prev
    nl = np.linalg.norm(leg)
    tip = cent[-1] + (leg / nl) * max(0.0, float((far - cent[-1]) @ leg) / nl) if nl > 0 else far
    path = np.vstack([o, cent, tip])
    length = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
    # the direction of growth: the line through the origin fitting the first half's centroids
    half = bins * width <= max(0.5 * float(s.max()), 2 * width)
    R = cent[half] - o
    M = R.T @ R
    u = np.linalg.eigh(M)[1][:, -1]
    if u @ R.sum(axis=0) < 0:
        u = -u
    angle = math.nan
    if reference is not None:
        r = np.asarray(reference, float) / np.linalg.norm(reference)
        if d == 2:
            angle = math.degrees(math.atan2(r[0] * u[1] - r[1] * u[0], float(r @ u)))
        else:
            angle = math.degrees(math.acos(float(np.clip(r @ u, -1.0, 1.0))))
    return CrackPath(path, tip, length, u, angle, members)
