"""Particles from a scene model (:class:`workbench.scenes.model.Model`): one discretisation that
every particle method (csph, hpm, classic SPH) starts from.

At resolution r the spacing is Δx = ``model.length`` / r. Regions with the ``lattice`` arrangement
share one lattice over the bounding box of their union, with a node at its lower corner:

* ``node`` (default): particles on the lattice nodes, faces included;
* ``cell``: one particle at the centre of each cell.

A particle is kept when it lies in the union of the lattice regions (closed, to 1e-6 Δx). Its
volume and its **boundary area vector** n_c = ∮ N dΓ over its share of the body surface come from a
sub-grid of half spacing (:func:`sph.consistency.boundary_normals`): each particle owns the cube of
side Δx around it (its dual cell on the node lattice, its cell on the cell lattice), cut into 2^d
sub-cubes; a sub-cube belongs to the body when its centre does; V_c is (Δx/2)^d times the number
of the particle's sub-cubes in the body, and n_c sums the outward normals times the area
(Δx/2)^(d−1) of the faces between its body sub-cubes and sub-cubes outside the body. For unions of lattice-aligned boxes this is exact: the trapezoid
rule's volumes and face areas (node lattice), Σ V = the body's volume and Σ_c X_c ⊗ n_c = Σ V I (the
discrete divergence theorem the integration-consistent correction needs). Other shapes get a
staircase of half spacing.

Regions with the ``concentric`` arrangement (a 2-D annulus) get 004's cylindrical arrangement:
``round((R_out − R_in)/Δx)`` layers of particles on circles (alternate layers shifted by half a
step), with their own volumes and the boundary area vectors of the inner and outer layers.

Each particle takes the region of highest priority containing it (on a common boundary, the
earlier region of equal priority); regions of equal priority whose interiors share particles are
an error. Its material is its region's (a row of the model's :class:`MaterialTable`), its body
the region's body. Named sets select particles by their shape (a :class:`Plane` on the cell
lattice selects the layer within half a spacing of it); a :class:`Point` set is a **probe**:
multilinear interpolation (or extrapolation, beyond the outermost particles) on the lattice,
weights summing to one, exact for linear fields.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from workbench.materials import MaterialTable
from workbench.materials.brittle import PARTICLE_BAND
from workbench.scenes.model import Model
from workbench.scenes.params import SceneError
from workbench.scenes.shapes import Cylinder, Plane, Point, Union

from .consistency import boundary_normals

TOL = 1e-6
"""Geometric tolerance over the spacing: points within TOL·Δx of a shape's boundary are in it."""


@dataclass
class Particles:
    """The particles of a model at one resolution.

    X (N, d) reference positions, m; V (N,) volumes, m^d (m² per unit thickness in 2-D); dx the
    spacing, m; mat_id (N,) rows of ``table``; region (N,) and body (N,) indices into
    ``region_names`` and ``body_names``; held (N,) particles of held regions; normals (N, d)
    boundary area vectors, m^(d−1); sets: name → particle indices; probes: name → (indices,
    weights); fixed (N, d) the DOFs the constraints hold or move (held particles, clamps, rollers,
    prescribed motion); clamped (N,) the particles held in every DOF at rest (held regions and
    clamps); domain (N,) the particles in the closed union of the non-held regions (the body's
    integration domain: a clamp is a face of it), ``domain_shape`` that union and ``origin`` the
    lattice's first point (None off the lattice); mirrors the symmetry planes ((axis, at, set
    name), ...; :func:`sph.mirror.symmetry_planes`; node lattice only); cracks (K, d, d) the
    facets of the model's pre-cracks and of their mirror images
    (:func:`workbench.crack_geometry.facets`): no pair of particles whose reference segment
    crosses one interacts (:func:`sph.neighbours.cut_pairs`)."""

    X: np.ndarray
    V: np.ndarray
    dx: float
    mat_id: np.ndarray
    table: MaterialTable
    region: np.ndarray
    body: np.ndarray
    held: np.ndarray
    normals: np.ndarray
    region_names: tuple
    body_names: tuple
    lattice: str
    plane: str | None
    sets: dict = field(default_factory=dict)
    probes: dict = field(default_factory=dict)
    set_normal_axis: dict = field(default_factory=dict)
    fixed: np.ndarray | None = None
    clamped: np.ndarray | None = None
    domain: np.ndarray | None = None
    domain_shape: object = None
    origin: np.ndarray | None = None
    mirrors: tuple = ()
    cracks: np.ndarray | None = None
    failed: np.ndarray | None = None

    def initial_history(self) -> np.ndarray:
        """The material history at t = 0 (N, n_history): virgin, but the particles ``failed``
        (the scene's failed regions, :attr:`workbench.scenes.model.Region.failed`) start failed
        (:func:`workbench.materials.failure.set_failed`)."""
        from workbench.materials.failure import set_failed

        h = self.table.initial_history(self.mat_id)
        if self.failed is not None and self.failed.any():
            set_failed(self.table, self.mat_id, h, self.failed)
        return h

    @property
    def n(self) -> int:
        return self.X.shape[0]

    @property
    def dim(self) -> int:
        return self.X.shape[1]

    def cut(self, X=None):
        """The ``cut`` argument of :func:`sph.neighbours.neighbour_list` for these particles (the
        reference positions ``X``, default theirs, and the pre-crack facets), None without
        pre-cracks."""
        if self.cracks is None or len(self.cracks) == 0:
            return None
        return (self.X if X is None else X, self.cracks)

    @property
    def rho(self) -> np.ndarray:
        return self.table.rho(self.mat_id)

    @property
    def m(self) -> np.ndarray:
        """Masses, kg (kg/m in 2-D)."""
        return self.rho * self.V

    def in_regions(self, names) -> np.ndarray:
        """Mask of the particles of the named regions (all when ``names`` is None)."""
        if names is None:
            return np.ones(self.n, bool)
        ids = [self.region_names.index(r) for r in names]
        return np.isin(self.region, ids)

    def surface_area(self, set_name: str, normals=None) -> np.ndarray:
        """Each particle's share (m^(d−1)) of the surface the set lies on: the component of its
        boundary area vector (``normals``, default the particles' own) along the plane normal for
        a :class:`Plane` set, |n_c| otherwise."""
        idx = self.sets[set_name]
        axis = self.set_normal_axis.get(set_name)
        n = (self.normals if normals is None else normals)[idx]
        return np.abs(n[:, axis]) if axis is not None else np.linalg.norm(n, axis=1)


# ------------------------------------------------------------------------------------------------
# Lattice, volumes and boundary area vectors
# ------------------------------------------------------------------------------------------------

def lattice_points(lo, hi, dx: float, mode: str) -> tuple[np.ndarray, np.ndarray]:
    """Points of the lattice of spacing dx anchored at ``lo`` that lie in [lo, hi] (node: the
    nodes; cell: the cell centres) and their integer lattice indices (N, d), first axis slowest."""
    axes, ids = [], []
    for a, b in zip(lo, hi):
        n = int(math.floor((b - a) / dx + TOL))
        if mode == "node":
            k = np.arange(n + 1)
            axes.append(a + k * dx)
        else:
            n = max(int(math.ceil((b - a) / dx - TOL)), 1)
            k = np.arange(n)
            axes.append(a + (k + 0.5) * dx)
        ids.append(k)
    mesh = np.meshgrid(*axes, indexing="ij")
    kmesh = np.meshgrid(*ids, indexing="ij")
    return (np.stack([g.ravel() for g in mesh], axis=1),
            np.stack([g.ravel() for g in kmesh], axis=1))


def concentric_particles(cyl: Cylinder, dx: float):
    """004's cylindrical arrangement of an annulus: ``round((R_out − R_in)/dx)`` layers on circles
    (at least 2: SceneError otherwise), n = max(6, round(2πr/Δr)) particles per circle, alternate layers shifted by half
    a step. Returns X (N, 2), V (N,), the layer spacing Δr, and the boundary area vectors (the
    inner layer: −e_r 2πR_in/n; the outer layer: +e_r 2πR_out/n)."""
    if len(cyl.centre) != 2:
        raise SceneError("arrangement 'concentric': only a 2-D annulus (Cylinder in 2-D)")
    R_in, R_out = cyl.inner, cyl.radius
    layers = int(round((R_out - R_in) / dx))
    if layers < 2:
        raise SceneError(f"resolution: {layers} particle layer(s) across the annulus wall; "
                         "allowed: at least 2")
    dr = (R_out - R_in) / layers
    X, V, nrm = [], [], []
    for k in range(layers):
        r = R_in + (k + 0.5) * dr
        n = max(6, int(round(2 * math.pi * r / dr)))
        th = 2 * math.pi * (np.arange(n) + 0.5 * (k % 2)) / n
        er = np.stack([np.cos(th), np.sin(th)], 1)
        X.append(np.asarray(cyl.centre) + r * er)
        V.append(np.full(n, 2 * math.pi * r * dr / n))
        a = np.zeros((n, 2))
        if k == 0:
            a -= er * 2 * math.pi * R_in / n
        if k == layers - 1:
            a += er * 2 * math.pi * R_out / n
        nrm.append(a)
    return np.concatenate(X), np.concatenate(V), dr, np.concatenate(nrm)


def box(lo, hi, dx: float, mode: str = "cell") -> tuple[np.ndarray, np.ndarray]:
    """Positions (N, d) and volumes (N,) of the lattice particles of the box [lo, hi] (the
    lattice anchored at ``lo``; node or cell), as :func:`discretise` makes them."""
    from workbench.scenes.shapes import Box

    b = Box(tuple(lo), tuple(hi))
    X, _ = lattice_points(np.asarray(lo, float), np.asarray(hi, float), dx, mode)
    X = np.ascontiguousarray(X[b.contains(X, TOL * dx)])
    origin = np.asarray(lo, float) + (0.5 * dx if mode == "cell" else 0.0)
    V, _ = boundary_normals(X, dx, lambda q: b.contains(q, 0.0), origin=origin)
    return X, V


def of_arrays(X, V, dx: float, material, plane: str | None = "strain", body=None,
              normals=None) -> Particles:
    """Particles of one region (one material) from given positions X (N, d) and volumes V (N,):
    hand-made arrangements and tests. ``body`` (N,) int labels separate bodies."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    N, d = X.shape
    body = np.zeros(N, np.int64) if body is None else np.asarray(body, np.int64)
    names = tuple(f"body{k}" for k in range(int(body.max()) + 1))
    return Particles(X, np.asarray(V, dtype=np.float64), float(dx), np.zeros(N, np.int64),
                     MaterialTable.of(material), np.zeros(N, np.int64), body, np.zeros(N, bool),
                     np.zeros((N, d)) if normals is None else np.asarray(normals, float),
                     ("body",), names, "given", plane if d == 2 else None)


# ------------------------------------------------------------------------------------------------
# Probes
# ------------------------------------------------------------------------------------------------

def _probe_lattice(p, lo, dx, mode, index_of, kmax):
    """Multilinear weights at p on the lattice (None if a corner particle is missing)."""
    idx_axes, w_axes = [], []
    off = 0.0 if mode == "node" else 0.5
    for k in range(len(p)):
        s = (p[k] - lo[k]) / dx - off  # lattice coordinate
        r = round(s)
        if abs(s - r) <= TOL and 0 <= r <= kmax[k]:
            idx_axes.append((int(r),))
            w_axes.append((1.0,))
            continue
        i0 = int(min(max(math.floor(s), 0), kmax[k] - 1))
        t = s - i0
        idx_axes.append((i0, i0 + 1))
        w_axes.append((1.0 - t, t))
    idx, wts = [], []
    for combo in itertools.product(*[range(len(a)) for a in idx_axes]):
        key = tuple(idx_axes[k][c] for k, c in enumerate(combo))
        w = float(np.prod([w_axes[k][c] for k, c in enumerate(combo)]))
        if w == 0.0:
            continue
        j = index_of.get(key)
        if j is None:
            return None
        idx.append(j)
        wts.append(w)
    return np.asarray(idx, np.int64), np.asarray(wts)


# ------------------------------------------------------------------------------------------------
# The discretisation
# ------------------------------------------------------------------------------------------------

def discretise(model: Model, resolution: int, lattice: str | None = None) -> Particles:
    """The particles of ``model`` at ``resolution`` (spacing ``model.length / resolution``);
    ``lattice`` overrides the model's ('node' or 'cell'). SceneError (one line) for a set that
    selects no particle or regions whose interiors overlap without a stated priority."""
    if not (isinstance(resolution, (int, np.integer)) and resolution >= 1):
        raise SceneError(f"resolution: {resolution!r} is not allowed; an integer >= 1 "
                         f"(particles across {model.length:g} m)")
    mode = model.lattice if lattice is None else lattice
    if mode not in ("node", "cell"):
        raise SceneError(f"lattice: {mode!r} is not one of 'node', 'cell'")
    dx = model.length / resolution
    tol = TOL * dx
    d = model.dim
    lat = [r for r in model.regions if r.arrangement == "lattice"]
    conc = [r for r in model.regions if r.arrangement == "concentric"]
    table, rows = model.materials()
    table = table.with_band(PARTICLE_BAND * dx)  # the brittle law's crack band: two columns
    Xs, Vs, Ns, regs = [], [], [], []
    lo = kmax = None
    index_of = {}
    n_lat = 0
    if lat:
        bnds = [r.shape.bounds() for r in lat]
        for r, b in zip(lat, bnds):
            if b is None:
                raise SceneError(f"region '{r.name}': an unbounded shape needs a bounded region "
                                 "(intersect it with a Box)")
        lo = np.min([b[0] for b in bnds], axis=0)
        hi = np.max([b[1] for b in bnds], axis=0)
        body = Union(tuple(r.shape for r in lat))
        P, K = lattice_points(lo, hi, dx, mode)
        keep = body.contains(P, tol)
        X, K = P[keep], K[keep]
        if len(X) == 0:
            raise SceneError(f"regions: no lattice point at spacing {dx:g} m lies in the body")
        first = lo + (0.5 * dx if mode == "cell" else 0.0)  # the lattice's first point
        V, nrm = boundary_normals(X, dx, lambda q: body.contains(q, 0.0), origin=first)
        reg = _assign_regions(model, lat, X, tol)
        Xs.append(X); Vs.append(V); Ns.append(nrm); regs.append(reg)
        kmax = K.max(axis=0)
        index_of = {tuple(k): i for i, k in enumerate(K.tolist())}
        n_lat = len(X)
    for r in conc:
        if not isinstance(r.shape, Cylinder):
            raise SceneError(f"region '{r.name}': arrangement 'concentric' needs a Cylinder (annulus)")
        X, V, _, nrm = concentric_particles(r.shape, dx)
        Xs.append(X); Vs.append(V); Ns.append(nrm)
        regs.append(np.full(len(X), model.regions.index(r), np.int64))
    X = np.ascontiguousarray(np.concatenate(Xs))
    V = np.concatenate(Vs)
    region = np.concatenate(regs)
    region_names = tuple(r.name for r in model.regions)
    mat_id = np.array([rows[r.name] for r in model.regions], np.int64)[region]
    body_names = model.bodies
    body = np.array([body_names.index(r.body) for r in model.regions], np.int64)[region]
    held = np.array([r.held for r in model.regions], bool)[region]
    ps = Particles(X, V, dx, mat_id, table, region, body, held, np.concatenate(Ns),
                   region_names, body_names, mode if lat else "concentric", model.plane,
                   failed=np.array([r.failed for r in model.regions], bool)[region])
    for s in model.sets:
        if isinstance(s.shape, Point):
            pr = None
            p = np.asarray(s.shape.at, dtype=float)
            if lat:
                pr = _probe_lattice(p, lo, dx, mode, index_of, kmax)
            if pr is None:  # off the lattice: the nearest particle
                j = int(np.argmin(np.linalg.norm(X - p, axis=1)))
                pr = (np.array([j], np.int64), np.array([1.0]))
            ps.probes[s.name] = pr
            ps.sets[s.name] = pr[0]
            continue
        ptol = 0.5 * dx * (1 + TOL) if (mode == "cell" and isinstance(s.shape, Plane)) else tol
        sel = s.shape.contains(X, ptol)
        if s.region is not None:
            sel &= region == region_names.index(s.region)
        if not sel.any():
            raise SceneError(f"set '{s.name}': selects no particle at spacing {dx:g} m")
        ps.sets[s.name] = np.nonzero(sel)[0]
        if isinstance(s.shape, Plane):
            ps.set_normal_axis[s.name] = s.shape.axis
    del n_lat
    _constraints(model, ps, lat, tol, lo)
    if mode == "node" and not conc:
        from .mirror import symmetry_planes

        ps.mirrors = symmetry_planes(model, ps, tol)
    if model.cracks:
        from workbench.crack_geometry import facets

        ps.cracks = facets(model.cracks, d, ps.mirrors)
    return ps


def _constraints(model: Model, ps: Particles, lat, tol: float, lo) -> None:
    """``fixed``, ``clamped``, ``domain``, ``domain_shape`` and ``origin`` of the particles."""
    from workbench.scenes import model as M

    fixed = np.zeros((ps.n, ps.dim), bool)
    fixed[ps.held] = True
    clamped = ps.held.copy()
    for c in model.constraints:
        idx = ps.sets[c.set]
        if isinstance(c, M.Clamp):
            fixed[idx] = True
            clamped[idx] = True
        else:
            fixed[idx, c.axis] = True
    free_regions = [r for r in lat if not r.held]
    domain = np.zeros(ps.n, bool)
    if free_regions:
        shape = Union(tuple(r.shape for r in free_regions))
        domain = shape.contains(ps.X, tol)
        ps.domain_shape = shape
    conc = [model.regions.index(r) for r in model.regions if r.arrangement == "concentric" and not r.held]
    domain |= np.isin(ps.region, conc)
    ps.fixed, ps.clamped, ps.domain = fixed, clamped, domain
    ps.origin = (None if lo is None else np.asarray(lo, dtype=float)
                 + (0.5 * ps.dx if ps.lattice == "cell" else 0.0))


def _assign_regions(model: Model, lat, X, tol) -> np.ndarray:
    """The region of every lattice particle: highest priority, then the earlier region; interiors
    of equal priority that share particles are an error."""
    best = np.full(len(X), -1, np.int64)
    best_pri = np.full(len(X), -np.inf)
    inner = []
    for r in lat:
        ins = r.shape.contains(X, tol)
        k = model.regions.index(r)
        take = ins & (r.priority > best_pri)
        best[take] = k
        best_pri[take] = r.priority
        inner.append((r, r.shape.contains(X, -tol)))
    for (a, ia), (b, ib) in itertools.combinations(inner, 2):
        if a.priority == b.priority:
            both = int(np.count_nonzero(ia & ib))
            if both:
                raise SceneError(f"regions '{a.name}' and '{b.name}' overlap ({both} particles inside "
                                 "both) without a stated priority; give one a higher priority")
    return best
