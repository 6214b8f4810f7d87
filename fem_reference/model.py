"""The FEM's reader of a scene model (:class:`workbench.scenes.model.Model`): the counterpart of the
particle methods' one driver :func:`sph.driver.solve`, with the same result keys.

``solve_model(scene, resolution, drive=None, element=None, fbar=None, deletion=False, fields=None,
**options)``:

1. **mesh** (:func:`discretise`) — ``scene.model(h)`` at the element size h = ``model.length`` /
   ``resolution``. The body is the union of the regions that are not *held*: a structured grid
   whose lines include every box face of every region (:meth:`Shape.boxes`; a shape that is not a
   union of boxes contributes its bounding box, and its boundary becomes a staircase of elements
   kept by their centroid), clipped to the body's bounding box. Each element takes the region of
   highest priority containing its centroid (ties: the earlier region), as a particle takes its
   region in :mod:`sph.particles`; elements whose region is held are not meshed, and the nodes of
   the body on a held region (its interface with the body) are clamped — a rigid clamp block.
   Elements: 9-node quadrilaterals (3×3 Gauss) in 2-D, plane strain or stress per ``model.plane``;
   27-node hexahedra (3×3×3 Gauss) in 3-D (:mod:`fem_reference.mesh`); ``element`` 'q4' or
   'hex8' for the linear ones (the homogeneous SS-curve block needs no more), or a (scikit-fem
   element, quadrature order) pair.
2. **sets** — nodes (every node of the quadratic elements) in the set's shape (to 1e-6 h), within
   its region when given; boundary facets whose vertices all lie in it (tractions, pressures); a
   :class:`~workbench.scenes.shapes.Point` set is a probe: the shape functions of the element
   containing the point interpolate there (its node set: the node at the point, or else the nodes
   of that element).
3. **constraints and loads** (:mod:`fem_reference.boundary`) — :class:`Clamp`, :class:`Roller`,
   :class:`Prescribed` displacement (a function of the load parameter, or of time; a prescribed
   velocity of an explicit drive is integrated in time to a displacement, exactly for a
   :class:`Table`); :class:`Traction` and :class:`Pressure` on the set's boundary facets
   (consistent nodal forces), :class:`PointLoad` at the probe point (consistent nodal forces; on a
   set of nodes, shared equally), :class:`BodyForce` ρ g on the elements of its regions, each with
   its ``scale`` function; :class:`InitialVelocity` at the nodes of its regions. The option
   ``lumped_mass`` adds rigid masses carried by faces (:func:`lump_mass`: a body pressed on a face,
   e.g. a drop weight while its contact stays compressive), with their initial velocity.
4. **drive** — :class:`Static`: :func:`~fem_reference.static.load_path` along ``drive.path`` (Newton
   with line search, increments halved on failure), observables at each value; :class:`Modal`: the
   lowest ``n_modes`` eigenpairs about the reference state (:mod:`.modal`); :class:`Explicit`:
   Newmark's average-acceleration rule (:mod:`.dynamic`, implicit). Its time step does not follow
   the CFL factor ``dt_factor`` of the particle methods: it is T₁/``steps_per_period`` with T₁
   the lowest modal period, by default :func:`default_steps_per_period` — 100 (the period
   elongation of the trapezoidal rule, (ω₁Δt)²/12, 0.033 %) where the motion starts smoothly, 400
   where a load is applied suddenly (it excites the higher modes, which 100 steps do not resolve:
   the step study of :data:`STEPS_PER_PERIOD_SUDDEN`); n = ⌈t_end/Δt⌉ steps, as the particle driver counts them (the run may
   end up to one step past t_end), at least 20 (then Δt = t_end/20). A body free to move rigidly
   (singular stiffness: ω₁² below :data:`RIGID` times tr K₀/tr M) takes T₁ of its lowest
   deforming mode; when none is found, Δt = t_end/max(n_out, 20). Mass-proportional damping as in
   the drive.
   Observables are recorded about ``n_out`` times, the Displacement histories behind
   :class:`Period` observables at every step. ``initial_tangent``: Newton's iteration matrix is
   the initial effective matrix, factorised once (:func:`fem_reference.dynamic.newmark`): for
   small-displacement runs, one factorisation instead of one or two per step.
5. **observables** — :class:`Displacement` (probe, or the mean over the set's nodes weighted by
   ∫N_a dV), :class:`Position` (the same of the current coordinate), :class:`Reaction` (the force
   the constraints exert on the set, the sum of f_int − f_ext over the set's constrained DOFs of
   that axis, :func:`.observe.reaction`: the particle driver's −Σ(f_int + f_ext) with its
   f_int = −∂Π/∂x, i.e. the same sign — positive along +axis on a face pulled in +axis; NaN in
   explicit runs, as there), :class:`MeanStress` (:func:`.observe.mean_stress`),
   :class:`FailedFraction` (elements deleted or failed at every point), :class:`Period` (the crossings of the
   history's own mean, :func:`workbench.oscillation.measure_period`, the particle methods' one
   definition; NaN with ``<name>_status`` saying why where it does not oscillate; the studies
   carry that reason into the run's status, :func:`workbench.oscillation.with_period_notes`).

Not read: regions with the 'concentric' arrangement (a particle arrangement of a ring: refused with
one line), contact between bodies and models of several bodies (refused), the stability monitor
of an explicit drive (the implicit scheme has no stability limit; a Newton failure ends the run
with status 'diverged').

Result keys (those of :func:`sph.driver.solve`): static — ``parameter``, ``parameter_name``, every
observable by name (an array over the path), ``status`` (one per value), ``wall_time``
(cumulative, s), ``iterations``, ``newton_iterations``, ``residual_history``, ``assembly_time``,
``solve_time``, ``eps_p`` (mean equivalent plastic strain, J2 tables); modal — ``periods``
(longest first), ``period``, ``omega`` (ascending), ``status``, ``wall_time``; explicit — ``time``
(records), the observables, and at each record, as the particle methods report them,
``kinetic_energy``, ``strain_energy``, ``external_work`` (the loads' work, trapezoidal in time)
and ``energy_history`` (their balance, kinetic + stored − external work: zero for an exact
integration), ``status``, ``dt``, ``steps``, ``modal_period``, ``omega``, ``wall_time`` (the
Newmark loop), ``wall_time_modal`` (the modes that set the step), ``loop_time``,
``newton_iterations``, each Period's value, ``<name>_amplitude`` and ``<name>_status``; always
``n_dof``, ``n_elements``, ``element``, ``h``, ``plane``, ``setup_time`` (mesh, discretisation,
loads; explicit: and the modes), ``jit_time`` (:func:`warm_up`) and ``total_time`` (the whole
call) — ``wall_time`` is the solver's own time, without set-up and JIT compilation, as the
particle driver's; then ``scene.summarise(out)`` when the drive is the scene's own kind.

:func:`solve` (``fem_reference.solve``) runs every scene through :func:`solve_model`, with the
plate study's option ``dynamic`` (False: the modal periods only; True: the scene's explicit drive,
and ``period`` stays the modal period, the history's going to ``period_dynamic``).
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from workbench.materials import HIST_EPS_P, MaterialTable
from workbench.oscillation import measure_period, period_amplitude  # noqa: F401 (re-exported)
from workbench.results import error_status as _error_status
from workbench.scenes import model as M
from workbench.scenes.params import SceneError
from workbench.scenes.shapes import Point

from .assembly import Discretisation
from .boundary import Constraints, Loads
from .mesh import grid_lines, mesh_series, mesh_snapshots, tensor_mesh
from .static import Problem

TOL = 1e-6
"""Geometric tolerance over the element size: nodes within TOL·h of a shape are in it."""
STEPS_PER_PERIOD = 100
"""Newmark steps per lowest modal period where the motion starts smoothly (an initial velocity, a
load ramped from zero): period elongation (2π/100)²/12 = 0.033 %."""
STEPS_PER_PERIOD_SUDDEN = 400
"""Newmark steps per lowest modal period where a load is applied suddenly (nonzero at t = 0): it
excites the higher modes (a cantilever's second at ω₂ ≈ 6.3 ω₁), whose phase error (ω_k Δt)²/12
per period accumulates at the top of each swing. Measured (issue 40) on a clamped beam released
under gravity (L/H = 8, Q9 at H/h = 4, 3.3 periods): the tip's overshoot past its start at the
tops of the first two swings, in % of the amplitude, is 0.81 / 1.52 at 100 steps, 0.52 / 1.33 at
200, 0.48 / 1.16 at 400 and 0.47 / 1.17 at 800 (the overshoot itself is the higher modes', the
step's error the difference): 0.35 % at 100, 0.01–0.02 % at 400, where ω₂Δt = 0.1 puts the
second mode's period error at 0.08 %. The energy balance does not tell them apart (the trapezoidal
rule conserves energy: its error is 3e-7 of the energy at 100 steps)."""


def default_steps_per_period(model: "M.Model") -> int:
    """:data:`STEPS_PER_PERIOD_SUDDEN` where a load of ``model`` (a traction, pressure, point or
    body force) is nonzero at t = 0 — applied suddenly —, else :data:`STEPS_PER_PERIOD`."""
    for ld in model.loads:
        if isinstance(ld, M.InitialVelocity):
            continue
        if np.any(np.asarray(M.as_function(ld.scale)(0.0), float) != 0.0):
            return STEPS_PER_PERIOD_SUDDEN
    return STEPS_PER_PERIOD
MIN_STEPS = 20
"""Fewest Newmark steps over an explicit drive's end time."""
N_MODES_EXPLICIT = 3
"""Modal periods computed before a time run (the lowest sets the step; reported as ``omega``)."""
RIGID = 1e-12
"""A mode with ω² below RIGID · tr K₀/tr M is a rigid-body mode. tr K₀/tr M ~ c²/h² is about the
largest ω² of the mesh; a zero eigenvalue comes out at ~1e-17 of it (round-off), the lowest
bending mode of a plate of aspect 10 with 100 elements across at ~1e-8 ((H h/L²)²)."""

ELEMENTS = {"q9": (2, 2), "quad9": (2, 2), "q4": (2, 1), "quad4": (2, 1),
            "hex27": (3, 2), "hex8": (3, 1)}
"""Element names: (dimension, polynomial order)."""

OPTIONS = ("rtol", "maxit", "max_increment", "min_increment", "steps_per_period", "field_frames",
           "lumped_mass", "initial_tangent")


# ------------------------------------------------------------------------------------------------
# The discretised model
# ------------------------------------------------------------------------------------------------

@dataclass
class FemModel:
    """A model on a mesh: the discretisation, the problem and the sets.

    ``region`` (nel,) index into ``model.regions`` of each element; ``nodes``: set name → scalar
    node indices (DOF of component i: node·d + i); ``probes``: set name → (d, N) interpolation
    matrix at the set's point; ``facets``: set name → boundary facets; ``X`` (d, n_nodes) node
    coordinates; ``node_volume`` (n_nodes,) ∫ N_a dV; ``clamped`` the scalar nodes clamped by held
    regions."""

    model: M.Model
    h: float
    disc: Discretisation
    problem: object
    constraints: Constraints
    loads: Loads
    region: np.ndarray
    mat_id: np.ndarray
    table: MaterialTable
    X: np.ndarray
    node_volume: np.ndarray
    nodes: dict = field(default_factory=dict)
    probes: dict = field(default_factory=dict)
    facets: dict = field(default_factory=dict)
    clamped: np.ndarray | None = None
    element: str = ""
    prescribed: list = field(default_factory=list)  # (dofs, displacement fn, velocity fn)
    velocity_holders: list = field(default_factory=list)  # (_Holder, velocity fn)
    nodal_velocity: list = field(default_factory=list)  # (scalar nodes, velocity (d,)): lump_mass

    @property
    def d(self) -> int:
        return self.disc.d

    def dofs(self, set_name: str, axis: int | None = None) -> np.ndarray:
        n = self.nodes[set_name]
        if axis is None:
            return (n[:, None] * self.d + np.arange(self.d)).ravel()
        return n * self.d + axis

    def point_regions(self) -> np.ndarray:
        """(nel·nqp,) index into ``model.regions`` of each quadrature point (element-major, the
        rows of the material history) where the scene's geometry puts the point itself, not its
        element's centroid: a field read per region (a failure strain, say) then sees each
        region's true boundary rather than the mesh's staircase of it. A point outside every
        region takes its element's."""
        at = _assign(self.model, self.disc.Xq.reshape(-1, self.d), TOL * self.h)
        return np.where(at >= 0, at, np.repeat(self.region, self.disc.nqp))

    def elements_of(self, regions) -> np.ndarray:
        """bool (nel,): elements of the named regions (all when None)."""
        if regions is None:
            return np.ones(self.disc.nel, bool)
        ids = [i for i, r in enumerate(self.model.regions) if r.name in set(regions)]
        return np.isin(self.region, ids)


def _element_choice(element, dim: int):
    """(Discretisation keyword arguments, name) of the ``element`` option."""
    if element is None:
        element = "q9" if dim == 2 else "hex27"
    if isinstance(element, str):
        key = element.lower()
        if key not in ELEMENTS or ELEMENTS[key][0] != dim:
            allowed = ", ".join(k for k, v in ELEMENTS.items() if v[0] == dim)
            raise ValueError(f"element: {element!r} is not allowed in {dim}-D; allowed: {allowed}")
        return {"order": ELEMENTS[key][1]}, key
    if isinstance(element, tuple) and len(element) == 2:
        return {"element": element}, f"{type(element[0]).__name__}/intorder {element[1]}"
    raise ValueError(f"element: {element!r} is not an element name or a (scikit-fem element, "
                     "quadrature order) pair")


def _scale(f):
    """A model time function (number, Table, callable) as a float-valued callable."""
    g = M.as_function(f)
    return lambda t: float(g(t))


def _assign(model: M.Model, c: np.ndarray, tol: float) -> np.ndarray:
    """Region index (into model.regions) of each centroid c (n, d): highest priority, then the
    earlier region; -1 outside every region. SceneError when two regions of equal priority share
    interior centroids."""
    best = np.full(len(c), -1, np.int64)
    best_pri = np.full(len(c), -np.inf)
    inner = []
    for k, r in enumerate(model.regions):
        ins = r.shape.contains(c, tol)
        take = ins & (r.priority > best_pri)
        best[take] = k
        best_pri[take] = r.priority
        inner.append((r, r.shape.contains(c, -tol)))
    for i, (a, ia) in enumerate(inner):
        for b, ib in inner[i + 1:]:
            if a.priority == b.priority and np.any(ia & ib):
                raise SceneError(f"regions '{a.name}' and '{b.name}' overlap "
                                 f"({int(np.count_nonzero(ia & ib))} elements inside both) without "
                                 "a stated priority; give one a higher priority")
    return best


def _mesh(model: M.Model, h: float):
    """The tensor mesh of the body and the region of each element (module docstring, step 1)."""
    tol = TOL * h
    boxes = []
    for r in model.regions:
        bx = r.shape.boxes()
        if bx is None:
            b = r.shape.bounds()
            if b is None:
                raise SceneError(f"region '{r.name}': an unbounded shape needs a bounded region "
                                 "(intersect it with a Box)")
            bx = [b]
        boxes += [(np.asarray(lo, float), np.asarray(hi, float)) for lo, hi in bx]
    body_boxes = []
    for r in model.regions:
        if not r.held:
            b = r.shape.bounds()
            if b is None:
                raise SceneError(f"region '{r.name}': an unbounded shape needs a bounded region")
            body_boxes.append(b)
    lo = np.min([b[0] for b in body_boxes], axis=0)
    hi = np.max([b[1] for b in body_boxes], axis=0)
    try:
        lines = grid_lines(boxes, h)
    except ValueError as err:
        raise SceneError(f"regions: {err}") from None
    lines = [ln[(ln >= lo[i] - tol) & (ln <= hi[i] + tol)] for i, ln in enumerate(lines)]
    if any(len(ln) < 2 for ln in lines):
        raise SceneError("regions: the body is thinner than one element along an axis")
    full = tensor_mesh(lines)
    c = full.p[:, full.t].mean(axis=1).T
    reg = _assign(model, c, tol)
    held = np.array([r.held for r in model.regions] + [True])  # -1 (outside): not meshed
    keep = np.flatnonzero(~held[reg])
    if not len(keep):
        raise SceneError(f"regions: no element of size {h:g} m lies in the body")
    mesh = full if len(keep) == full.t.shape[1] else full.restrict(keep)
    return mesh, reg[keep]


def discretise(model: M.Model, resolution: int, element=None, fbar=None,
               deletion=False) -> FemModel:
    """The FEM of ``model`` at ``resolution`` elements across ``model.length`` (module docstring,
    steps 1–3). SceneError (one line) for what the FEM cannot read or a set that selects nothing."""
    if not (isinstance(resolution, (int, np.integer)) and resolution >= 1):
        raise SceneError(f"resolution: {resolution!r} is not allowed; an integer >= 1 "
                         f"(elements across {model.length:g} m)")
    for r in model.regions:
        if r.arrangement == "concentric":
            raise SceneError(f"region '{r.name}': arrangement 'concentric' (a particle arrangement "
                             "of a ring) is not meshed by the FEM; use the particle methods")
    if model.contact:
        raise SceneError("contact: the FEM has no contact between bodies; use the particle methods")
    if model.cracks:
        raise SceneError(f"pre-crack '{model.cracks[0].name}': the FEM does not cut elements along "
                         "a crack; use the particle methods (csph, csph_bl, hpm, sph)")
    if any(isinstance(o, M.CrackTip) for o in model.observables):
        raise SceneError("observable CrackTip: not measured by the FEM; use the particle methods")
    if len({r.body for r in model.regions if not r.held}) > 1:
        raise SceneError("regions: the FEM meshes one body (the model has "
                         f"{', '.join(model.bodies)})")
    h = model.length / int(resolution)
    tol = TOL * h
    d = model.dim
    kw, ename = _element_choice(element, d)
    mesh, region = _mesh(model, h)
    disc = Discretisation(mesh, fbar=fbar, **kw)
    # materials of the meshed regions, in region order
    mats, rows = [], {}
    for r in model.regions:
        if not r.held:
            if r.material not in mats:
                mats.append(r.material)
            rows[r.name] = mats.index(r.material)
    table = MaterialTable(tuple(mats)).with_band(h)  # brittle law: a band of one element
    mat_id = np.array([rows.get(r.name, -1) for r in model.regions], np.int64)[region]
    X = np.ascontiguousarray(disc.basis.doflocs[:, ::d])
    n_nodes = X.shape[1]
    vol = np.bincount(disc.sdofs.ravel(),
                      weights=np.einsum("eq,eqa->ea", disc.dV0, disc.Nq).ravel(),
                      minlength=n_nodes)
    fm = FemModel(model, h, disc, None, Constraints(disc), Loads(disc), region, mat_id, table, X,
                  vol, element=ename)
    _sets(fm, tol)
    _constraints(fm, tol)
    if not len(fm.constraints.dofs) and not isinstance(model.drive, M.Explicit):
        raise SceneError("constraints: the body has no support (no clamp, roller, prescribed "
                         "motion or held region): its static and modal problems are singular")
    fm.constraints.apply()
    _loads(fm)
    try:
        fm.problem = Problem(disc, table, model.plane if d == 2 else None, fm.constraints.values,
                             fm.loads, mat_id=mat_id, deletion=deletion)
    except ValueError as err:
        raise SceneError(str(err)) from None
    failed = np.array([r.failed for r in model.regions], bool)
    if failed.any():  # the scene's failed regions: their elements' points start failed
        fm.problem.failed_elements0 = failed[region]
    return fm


def _nodes_of(fm: FemModel, region_name: str) -> np.ndarray:
    """bool (n_nodes,): nodes of the elements of the named region."""
    k = [r.name for r in fm.model.regions].index(region_name)
    mask = np.zeros(fm.X.shape[1], bool)
    mask[fm.disc.sdofs[fm.region == k].ravel()] = True
    return mask


def _sets(fm: FemModel, tol: float) -> None:
    disc, mesh = fm.disc, fm.disc.mesh
    verts = mesh.p.T
    bf = mesh.boundary_facets()
    for s in fm.model.sets:
        if isinstance(s.shape, Point):
            p = np.asarray(s.shape.at, float)
            if p.shape != (fm.d,):
                raise SceneError(f"set '{s.name}': the point {tuple(p)} has {len(p)} coordinates "
                                 f"in a {fm.d}-D model")
            try:
                P = disc.probe(p[None, :])
            except ValueError:
                raise SceneError(f"set '{s.name}': the point {tuple(p)} lies outside the meshed "
                                 "body") from None
            fm.probes[s.name] = P
            at = np.flatnonzero(np.linalg.norm(fm.X.T - p, axis=1) <= tol)
            if not len(at):
                at = np.unique(P.indices // fm.d)
            fm.nodes[s.name] = at
            fm.facets[s.name] = np.zeros(0, np.int64)
            continue
        mask = s.shape.contains(fm.X.T, tol)
        vmask = s.shape.contains(verts, tol)
        if s.region is not None:
            mask &= _nodes_of(fm, s.region)
            k = [r.name for r in fm.model.regions].index(s.region)
            vin = np.zeros(mesh.p.shape[1], bool)
            vin[mesh.t[:, fm.region == k].ravel()] = True
            vmask &= vin
        if not mask.any():
            raise SceneError(f"set '{s.name}': selects no node at element size {fm.h:g} m")
        fm.nodes[s.name] = np.flatnonzero(mask)
        fm.facets[s.name] = bf[np.all(vmask[mesh.facets[:, bf]], axis=0)]


def integral(f, t_end: float, breaks=()) -> callable:
    """u(t) = ∫₀ᵗ f(s) ds for 0 ≤ t ≤ t_end: f is interpolated linearly on 4000 intervals refined
    at ``breaks`` and at a :class:`Table`'s points, and that interpolant is integrated exactly
    (exact for a Table, piecewise linear; second order for any other function). Beyond t_end
    f is held at f(t_end)."""
    g = M.as_function(f)
    grid = np.linspace(0.0, t_end, 4001)
    pts = list(breaks) + list(getattr(g, "times", ()))
    grid = np.union1d(grid, [p for p in pts if 0.0 < p < t_end])
    try:
        v = np.asarray(g(grid), float) * np.ones_like(grid)
    except (TypeError, ValueError):  # a callable of one number at a time
        v = np.array([float(g(t)) for t in grid])
    dg = np.diff(grid)
    U = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dg)])
    slope = np.diff(v) / dg

    def disp(t):
        t = float(t)
        if t >= t_end:
            return float(U[-1] + v[-1] * (t - t_end))
        if t <= 0.0:
            return float(v[0] * t)
        k = min(int(np.searchsorted(grid, t, side="right")) - 1, len(dg) - 1)
        tau = t - grid[k]
        return float(U[k] + v[k] * tau + 0.5 * slope[k] * tau * tau)

    return disp


class _Holder:
    """A prescribed displacement u(t) whose function is set later (a prescribed velocity is
    integrated once the time step, hence the run's end, is known)."""

    def __init__(self, fn):
        self.fn = fn

    def __call__(self, t):
        return float(self.fn(t))


def _constraints(fm: FemModel, tol: float) -> None:
    model, bc, d = fm.model, fm.constraints, fm.d
    clamped = np.zeros(fm.X.shape[1], bool)
    for r in model.regions:
        if r.held:
            on = r.shape.contains(fm.X.T, tol)
            if not on.any():
                raise SceneError(f"region '{r.name}': a held region that touches no node of the "
                                 "body clamps nothing")
            clamped |= on
    fm.clamped = np.flatnonzero(clamped)
    if len(fm.clamped):
        bc.prescribe_dofs((fm.clamped[:, None] * d + np.arange(d)).ravel(), 0.0)
    for c in model.constraints:
        if isinstance(c, M.Clamp):
            bc.prescribe_dofs(fm.dofs(c.set), 0.0)
            continue
        dofs = fm.dofs(c.set, c.axis)
        if isinstance(c, M.Roller):
            bc.prescribe_dofs(dofs, 0.0)
            continue
        # Prescribed
        if isinstance(model.drive, M.Modal):
            bc.prescribe_dofs(dofs, 0.0)  # the modes about the reference state: held
            continue
        if c.displacement is not None:
            disp = _scale(c.displacement)
            vel = None
        else:
            vel = M.as_function(c.velocity)
            disp = None  # integrated once the time step is known (explicit drives only)
        fm.prescribed.append((dofs, disp, vel))
        holder = _Holder(disp if disp is not None else (lambda t: 0.0))
        bc.prescribe_dofs(dofs, holder)
        if vel is not None:
            fm.velocity_holders.append((holder, vel))


def _loads(fm: FemModel) -> None:
    model, loads, disc = fm.model, fm.loads, fm.disc
    for ld in model.loads:
        if isinstance(ld, M.InitialVelocity):
            continue
        s = _scale(ld.scale)
        if isinstance(ld, (M.Traction, M.Pressure)):
            fac = fm.facets[ld.set]
            if not len(fac):
                raise SceneError(f"{type(ld).__name__} on set '{ld.set}': the set holds no "
                                 f"boundary facet at element size {fm.h:g} m")
            if isinstance(ld, M.Traction):
                loads.vector(disc.traction_load(fac, np.asarray(ld.traction, float)), s)
            else:
                loads.vector(disc.pressure_load(fac, float(ld.pressure)), s)
        elif isinstance(ld, M.PointLoad):
            force = np.asarray(ld.force, float)
            if ld.set in fm.probes:
                loads.vector(fm.probes[ld.set].T @ force, s)
            else:
                f = np.zeros(disc.N)
                n = fm.nodes[ld.set]
                for i in range(fm.d):
                    f[n * fm.d + i] = force[i] / len(n)
                loads.vector(f, s)
        elif isinstance(ld, M.BodyForce):
            rho_e = np.where(fm.elements_of(ld.regions), fm.table.rho(fm.mat_id), 0.0)
            loads.body(rho_e, np.asarray(ld.acceleration, float), s)


def lump_mass(fm: FemModel, set_name: str, mass: float, velocity=None) -> np.ndarray:
    """A rigid mass carried by a face: ``mass`` (kg) lumped onto the nodes of the set ``set_name``
    in proportion to ∫_Γ N_a dA over its boundary facets (the consistent shares of a uniform
    surface density; positive for the Lagrange elements used here), or in equal shares where the
    set holds no boundary facet (a line, a point); every component of a node carries its share
    (``fm.problem.nodal_mass``, added to the consistent mass: :meth:`Problem.mass`). Those nodes
    start with ``velocity`` (d,), m/s (None: at rest; the constrained DOFs at their prescribed
    rate). What it models: a body of that mass moving with the face — e.g. a weight pressed on a
    loading plate while their contact stays compressive — as a distributed inertia that does not
    stiffen the face. Returns the lumped mass per scalar node (n_nodes,), kg."""
    if not (math.isfinite(mass) and mass > 0):
        raise ValueError(f"lumped_mass: mass {mass!r} is out of range; allowed: (0, inf) kg")
    disc, d = fm.disc, fm.d
    if set_name not in fm.nodes:
        raise ValueError(f"lumped_mass: set {set_name!r} is not a set of the model; allowed: "
                         f"{', '.join(fm.nodes)}")
    nodes = fm.nodes[set_name]
    fac = fm.facets[set_name]
    share = np.zeros(fm.X.shape[1])
    if len(fac):
        e0 = np.zeros(d)
        e0[0] = 1.0
        share = disc.traction_load(fac, e0)[::d].copy()
        share[np.setdiff1d(np.arange(len(share)), nodes)] = 0.0
    if not share.sum() > 0:
        share = np.zeros(fm.X.shape[1])
        share[nodes] = 1.0
    lumped = mass * share / share.sum()
    extra = np.repeat(lumped, d)
    p = fm.problem
    p.nodal_mass = extra if p.nodal_mass is None else p.nodal_mass + extra
    if velocity is not None:
        vel = np.asarray(velocity, float)
        if vel.shape != (d,):
            raise ValueError(f"lumped_mass: velocity {tuple(vel)} needs {d} components")
        fm.nodal_velocity.append((np.flatnonzero(share > 0), vel))
    return lumped


# ------------------------------------------------------------------------------------------------
# Observables
# ------------------------------------------------------------------------------------------------

def _displacement(fm: FemModel, o, u: np.ndarray) -> float:
    if o.set in fm.probes:
        return float((fm.probes[o.set] @ u)[o.axis])
    n = fm.nodes[o.set]
    w = fm.node_volume[n]
    return float(w @ u[n * fm.d + o.axis] / w.sum())


def observe(fm: FemModel, state, lam: float | None = None, need_force: bool = True) -> dict:
    """The model's observables at the committed ``state``; ``lam`` the load parameter of f_ext
    for reactions (None: no reaction, NaN — explicit drives)."""
    from .observe import failed_elements, mean_stress, reaction

    u = state.u
    out = {}
    f_int = None
    for o in fm.model.observables:
        if isinstance(o, M.Displacement):
            out[o.name] = _displacement(fm, o, u)
        elif isinstance(o, M.Position):
            if o.set in fm.probes:
                X = np.asarray(fm.model.set(o.set).shape.at, float)[o.axis]
                out[o.name] = float(X + (fm.probes[o.set] @ u)[o.axis])
            else:
                n = fm.nodes[o.set]
                w = fm.node_volume[n]
                out[o.name] = float(w @ (fm.X[o.axis, n] + u[n * fm.d + o.axis]) / w.sum())
        elif isinstance(o, M.Reaction):
            if lam is None or not need_force:
                out[o.name] = math.nan
                continue
            if f_int is None:
                f_int = fm.problem.evaluate(u, state, tangent=False)["f_int"]
            out[o.name] = float(reaction(fm.problem, state, dofs=fm.dofs(o.set, o.axis), lam=lam,
                                         f_int=f_int)[o.axis]) if f_int is not None else math.nan
        elif isinstance(o, M.MeanStress):
            sel = fm.elements_of(o.regions)
            out[o.name] = float(mean_stress(fm.problem, state, elements=sel)[o.i, o.j]) \
                if (sel & fm.disc.active).any() else math.nan
        elif isinstance(o, M.FailedFraction):
            sel = fm.elements_of(o.regions)
            failed = failed_elements(fm.problem, state)
            out[o.name] = float(np.count_nonzero(failed & sel) / max(1, np.count_nonzero(sel)))
    return out


# ------------------------------------------------------------------------------------------------
# Drives
# ------------------------------------------------------------------------------------------------

def _static(fm: FemModel, t0: float, options: dict, series) -> dict:
    from .observe import plastic_strain
    from .static import TangentSolver, load_path

    drive = fm.model.drive
    path = np.asarray(drive.path, dtype=float)
    n = len(path)
    names = [o.name for o in fm.model.observables if not isinstance(o, M.Period)]
    out = dict(parameter=path, parameter_name=drive.parameter, wall_time=np.full(n, np.nan),
               iterations=np.zeros(n, int), status=["error: not run"] * n,
               residual_history=[[] for _ in range(n)], newton_iterations=[[] for _ in range(n)],
               assembly_time=np.full(n, np.nan), solve_time=np.full(n, np.nan),
               **{k: np.full(n, np.nan) for k in names})
    j2 = fm.table.n_history > HIST_EPS_P
    if j2:
        out["eps_p"] = np.full(n, np.nan)

    if drive.stop:
        out["t_threshold"] = math.nan  # the load parameter at which a stop rule held

    def measure(k, lam, state):
        for key, v in observe(fm, state, lam).items():
            out[key][k] = v
        if j2:
            out["eps_p"][k] = plastic_strain(fm.problem, state, "mean")
        if series is not None:
            series(lam, state.u)
        held = [r for r in drive.stop if r.holds(out[r.of][k])]
        if held and not math.isfinite(out["t_threshold"]):
            out["t_threshold"], out["threshold"] = float(lam), held[0].describe()
        return bool(held)  # the path ends there (the drive's stop rules)

    solver = TangentSolver()
    kw = {k: options[k] for k in ("max_increment", "min_increment", "rtol", "maxit")
          if k in options}
    try:
        setup = time.perf_counter() - t0
        recs, _ = load_path(fm.problem, path, callback=measure, solver=solver, **kw)
        for k, r in enumerate(recs):
            out["status"][k] = r["status"]
            out["residual_history"][k] = r["residual_history"]
            out["newton_iterations"][k] = r["newton_iterations"]
            out["iterations"][k] = r["iterations"]
            out["wall_time"][k] = r["wall_time"] + setup
            out["assembly_time"][k] = r["assembly_time"]
            out["solve_time"][k] = r["solve_time"]
    except Exception as err:  # a failed run is a result (contract.md)
        out["status"] = [_error_status(err)] * n
    out["factorisations"] = solver.factorisations
    out["krylov_iterations"] = solver.krylov_iterations
    return out


def _modes(fm: FemModel, k: int):
    """ω (k,) ascending, rad/s, of the lowest modes (fewer when the free DOFs are fewer)."""
    from .modal import lowest_modes

    k = max(1, min(k, len(fm.disc.free) - 1))
    omega, _ = lowest_modes(fm.problem, k=k)
    return omega


def _operators(fm: FemModel):
    """The tangent K₀ about the reference state and the mass, on the free DOFs (CSC)."""
    problem, disc = fm.problem, fm.disc
    st = problem.initial_state()
    K = problem.tangent(problem.evaluate(st.u, st, tangent=True)).tocsc()
    return K, problem.mass()[disc.free][:, disc.free].tocsc()


def _stiffness_scale(fm: FemModel) -> float:
    """tr K₀ / tr M on the free DOFs, 1/s²: about the largest ω² of the mesh."""
    K, Mf = _operators(fm)
    return float(K.diagonal().sum() / Mf.diagonal().sum())


def _deforming_period(fm: FemModel) -> float:
    """The lowest period of the deforming modes of a body free to move rigidly (singular K₀):
    shift-invert about a small negative shift −s (K₀ + s M is regular), the rigid modes (ω² below
    :data:`RIGID` times tr K₀/tr M) skipped; NaN if none is found."""
    import scipy.sparse.linalg as spla

    K, Mf = _operators(fm)
    scale = float(K.diagonal().sum() / Mf.diagonal().sum())
    k = min(fm.d * (fm.d + 1) // 2 + N_MODES_EXPLICIT, K.shape[0] - 2)
    try:
        lam = spla.eigsh(K, k=k, M=Mf, sigma=-1e-6 * scale, which="LM", return_eigenvectors=False)
    except Exception:
        return math.nan
    lam = np.sort(lam[lam > RIGID * scale])
    return float(2 * np.pi / np.sqrt(lam[0])) if len(lam) else math.nan


def _modal(fm: FemModel, t0: float) -> dict:
    n = fm.model.drive.n_modes
    try:
        omega = _modes(fm, n)
        periods = 2 * np.pi / omega  # longest first: ω ascends
        out = dict(omega=omega, periods=periods, period=float(periods[0]), status="ok")
    except Exception as err:  # a failed run is a result
        out = dict(omega=np.full(n, np.nan), periods=np.full(n, np.nan), period=math.nan,
                   status=_error_status(err))
    out["wall_time"] = time.perf_counter() - t0
    out["wall_time_modal"] = out["wall_time"]
    return out


def _initial_velocity(fm: FemModel, dt: float) -> np.ndarray:
    """v₀ (N,): the model's initial velocities at the nodes of their regions; on the constrained
    DOFs the rate of the prescribed motion at t = 0 (zero on clamps and rollers)."""
    d, disc = fm.d, fm.disc
    v = np.zeros((fm.X.shape[1], d))
    for ld in fm.model.loads:
        if isinstance(ld, M.InitialVelocity):
            nodes = np.zeros(fm.X.shape[1], bool)
            nodes[disc.sdofs[fm.elements_of(ld.regions)].ravel()] = True
            idx = np.flatnonzero(nodes)
            vel = ld.velocity
            v[idx] = vel(fm.X[:, idx].T) if callable(vel) else np.asarray(vel, float)
    for idx, vel in fm.nodal_velocity:
        v[idx] = vel
    v = v.ravel()
    v[disc.fixed] = 0.0
    for dofs, disp, vel in fm.prescribed:
        v[dofs] = (float(np.asarray(vel(0.0))) if vel is not None
                   else (disp(0.5 * dt) - disp(-0.5 * dt)) / dt)
    return v


def _explicit(fm: FemModel, t0: float, options: dict, fields, name: str) -> dict:
    from .dynamic import newmark

    drive = fm.model.drive
    d = fm.d
    omega = np.full(N_MODES_EXPLICIT, np.nan)
    try:
        with np.errstate(invalid="ignore"):
            omega = _modes(fm, N_MODES_EXPLICIT)
        if not (np.isfinite(omega[0]) and omega[0] ** 2 > RIGID * _stiffness_scale(fm)):
            raise ValueError("a rigid mode: the stiffness is singular")
        T1 = float(2 * np.pi / omega[0])
    except Exception:  # a body free to move rigidly: the lowest period of the deforming modes
        omega = np.full(N_MODES_EXPLICIT, np.nan)
        T1 = _deforming_period(fm)
    if math.isfinite(T1):
        dt = T1 / options.get("steps_per_period", default_steps_per_period(fm.model))
        n_steps = int(math.ceil(drive.t_end / dt))
    else:
        n_steps = max(drive.n_out, MIN_STEPS)
        dt = drive.t_end / n_steps
    if n_steps < MIN_STEPS:
        n_steps = MIN_STEPS
        dt = drive.t_end / n_steps
    t_modal = time.perf_counter() - t0
    for holder, vel in fm.velocity_holders:
        holder.fn = integral(vel, (n_steps + 1) * dt)
    v0 = _initial_velocity(fm, dt)
    every = max(1, n_steps // max(1, drive.n_out))
    periods = [o for o in fm.model.observables if isinstance(o, M.Period)]
    sources = [fm.model.observable(p.of) for p in periods]
    names = [o.name for o in fm.model.observables if not isinstance(o, M.Period)]
    rec = {k: [] for k in names}
    steps_rec = []
    work = dict(w=0.0, u=None, f=None)
    w_rec = []

    # reactions: the time mean over each output interval of the supports' force on the body,
    # M a + f_int − f_ext on the set's fixed DOFs (newmark's on_step), by the trapezoidal rule
    reactions = {o.name: np.intersect1d(fm.dofs(o.set, o.axis), fm.disc.fixed)
                 for o in fm.model.observables if isinstance(o, M.Reaction)}
    impulse = dict(t=0.0, prev={}, sum={k: 0.0 for k in reactions})

    def on_step(t, h, r):
        for k, dofs in reactions.items():
            now = float(r[dofs].sum())
            impulse["sum"][k] += 0.5 * h * (impulse["prev"].get(k, now) + now)
            impulse["prev"][k] = now

    stops = dict(t=math.nan, rule=None)

    def callback(step, t, state, v):
        f = fm.problem.external(t)
        if work["u"] is not None:
            work["w"] += 0.5 * float((f + work["f"]) @ (state.u - work["u"]))
        work["u"], work["f"] = state.u.copy(), f
        if step % every == 0 or step == n_steps:
            for k, val in observe(fm, state, None).items():
                if k in reactions:
                    span = t - impulse["t"]
                    val = impulse["sum"][k] / span if span > 0 else math.nan
                    impulse["sum"][k] = 0.0
                rec[k].append(val)
            impulse["t"] = t
            steps_rec.append(step)
            w_rec.append(work["w"])
            # the drive's stop rules: ``after`` seconds past the first record where one holds
            held = [r for r in drive.stop if r.holds(rec[r.of][-1])]
            if held and stops["rule"] is None:
                stops.update(t=t, rule=held[0])
            return stops["rule"] is not None and t >= stops["t"] + stops["rule"].after * (1 - 1e-9)
        return False

    def history(u):
        return np.array([_displacement(fm, o, u) for o in sources])

    snap = None
    if fields is not None:
        snap = mesh_snapshots(fields, name, fm.disc, n_steps, options.get("field_frames", 20))
    t_setup = time.perf_counter() - t0
    tl = time.perf_counter()
    try:
        run = newmark(fm.problem, v0, dt, n_steps, observe=history, rtol=options.get("rtol", 1e-9),
                      maxit=options.get("maxit", 20), snapshot=snap, callback=callback,
                      damping=drive.damping, initial_tangent=options.get("initial_tangent", False),
                      on_step=on_step if reactions else None)
        status = run["status"]
    except Exception as err:  # a failed run is a result
        run = None
        status = _error_status(err)
    loop = time.perf_counter() - tl
    idx = np.asarray(steps_rec, int)
    out = dict(status=status, dt=dt, steps=n_steps if run is None else len(run["time"]) - 1,
               modal_period=T1, omega=omega, wall_time_modal=t_modal, setup_time=t_setup,
               loop_time=loop, wall_time=loop, time=idx * dt, external_work=np.asarray(w_rec, float),
               **{k: np.asarray(v, float) for k, v in rec.items()})
    if run is not None:
        ke, se = run["kinetic_energy"][idx], run["strain_energy"][idx]
        out.update(kinetic_energy=ke, strain_energy=se,
                   energy_history=ke + se - np.asarray(w_rec),
                   newton_iterations=run["newton_iterations"],
                   deleted=run["deleted"])
        out["time"] = run["time"][idx]
    size = float(np.abs(fm.X).max())  # the coordinates' size: the round-off test's scale
    for j, p in enumerate(periods):
        m = dict(period=math.nan, amplitude=math.nan, status=f"no oscillation: the run is {status}")
        if run is not None and status == "ok":
            m = measure_period(run["time"], run["observed"][:, j], size)
        out[p.name] = m["period"]
        out[f"{p.name}_amplitude"] = m["amplitude"]
        out[f"{p.name}_status"] = m["status"]
    if drive.stop:
        out["t_threshold"] = stops["t"]
        out["criterion"] = "threshold" if stops["rule"] is not None and run is not None \
            and run["stopped"] else "none"
        if stops["rule"] is not None:
            out["threshold"] = stops["rule"].describe()
    return out



# ------------------------------------------------------------------------------------------------
# The reader
# ------------------------------------------------------------------------------------------------

def model_at(scene, resolution: int):
    """The scene's model at the element size of ``resolution`` (its geometry may depend on it)."""
    if not (isinstance(resolution, (int, np.integer)) and resolution >= 1):
        raise SceneError(f"resolution: {resolution!r} is not allowed; an integer >= 1")
    h = scene.model().length / int(resolution)
    return scene.model(h)


def build(scene, resolution: int, drive=None, element=None, fbar=None, deletion=False) -> FemModel:
    """:func:`discretise` of ``scene.model(h)`` at ``resolution`` (``drive`` replaces the
    model's)."""
    model = model_at(scene, resolution)
    if drive is not None:
        model = dataclasses.replace(model, drive=drive)
    return discretise(model, int(resolution), element, fbar, deletion)


def solve_model(scene, resolution: int, drive=None, element=None, fbar=None, deletion=False,
                fields=None, **options) -> dict:
    """Run the FEM on ``scene`` at ``resolution`` elements across ``model.length`` (module
    docstring). ``drive`` replaces the model's (e.g. ``Modal()``); ``element``: None (Q9 / hex27),
    'q9', 'q4', 'hex27', 'hex8' or a (scikit-fem element, quadrature order) pair; ``fbar``: the
    F-bar option of :class:`~fem_reference.assembly.Discretisation`; ``deletion``: delete failed
    elements (:class:`~fem_reference.static.Problem`); ``fields`` (a folder, or None): the mesh
    (vertex displacement, and velocity in time runs) as the ParaView series
    ``<scene>_fem_H<resolution>.pvd`` — one frame per load value of a static drive, about
    ``field_frames`` frames of an explicit one, none of a modal one. ``options``: ``rtol``,
    ``maxit``, ``max_increment``, ``min_increment`` (Newton and load stepping),
    ``steps_per_period`` (Newmark), ``field_frames``, ``lumped_mass`` (a sequence of (set name,
    mass kg, initial velocity (d,) or None): rigid masses carried by faces, :func:`lump_mass`),
    ``initial_tangent`` (Newmark by modified Newton with the initial effective matrix factorised
    once, :func:`fem_reference.dynamic.newmark`)."""
    bad = sorted(set(options) - set(OPTIONS))
    if bad:
        raise ValueError(f"{bad[0]}: not an option of the FEM; allowed: {', '.join(OPTIONS)}, "
                         "drive, element, fbar, deletion, fields")
    t0 = time.perf_counter()
    lumped = options.pop("lumped_mass", ())
    fm = build(scene, resolution, drive, element, fbar, deletion)
    for spec in lumped:
        lump_mass(fm, *spec)
    setup = time.perf_counter() - t0
    jit = warm_up(fm)
    t1 = time.perf_counter()  # the solver's own time starts here
    model = fm.model
    name = None
    if fields is not None:
        from workbench.fields import series_name

        name = series_name(scene.name, "fem", resolution)
    if isinstance(model.drive, M.Static):
        series = mesh_series(fields, name, fm.disc) if fields is not None else None
        out = _static(fm, t1, options, series)
    elif isinstance(model.drive, M.Modal):
        out = _modal(fm, t1)
    else:
        out = _explicit(fm, t1, options, fields, name)
    if "wall_time" not in out:
        out["wall_time"] = time.perf_counter() - t1
    out.update(n_dof=int(fm.disc.N), n_elements=int(fm.disc.nel), element=fm.element, h=fm.h,
               plane=model.plane, setup_time=setup + out.get("setup_time", 0.0), jit_time=jit,
               total_time=time.perf_counter() - t0)
    if isinstance(model.drive, type(scene.model().drive)):
        out.update(scene.summarise(out))
    return out


def warm_up(fm: FemModel) -> float:
    """The JIT compilation (and numba cache loading) of the FEM's kernels, s: one evaluation of
    the internal force and the tangent at the reference state, timed twice — the first includes
    the compilation, the second is the warm cost, the difference the compilation. So that the
    solver times (``wall_time``) exclude it, as the particle driver's do."""
    p = fm.problem
    times = []
    try:
        for _ in range(2):
            tw = time.perf_counter()
            state = p.initial_state()
            p.tangent(p.evaluate(state.u, state, tangent=True))
            times.append(time.perf_counter() - tw)
    except Exception:  # a model the solver itself will report on
        return 0.0
    return max(0.0, times[0] - times[1])


def solve(scene, resolution: int, dynamic: bool | None = None, **options) -> dict:
    """``fem_reference.solve``: every scene through :func:`solve_model`. ``dynamic`` (the plate
    study's contract): None — the scene's own drive; False — the lowest three modal periods
    (``drive=Modal(3)``); True — the scene's explicit drive (Newmark), with ``period`` the modal
    period (the plate study's reference on every rung) and the period of the history as
    ``period_dynamic``."""
    if dynamic is not None:
        own = scene.model().drive
        if dynamic and not isinstance(own, M.Explicit):
            raise ValueError(f"dynamic: True needs an explicit drive; {scene.name} has "
                             f"{type(own).__name__}")
        if not dynamic:
            options.setdefault("drive", M.Modal(3))
    out = solve_model(scene, resolution, **options)
    if dynamic:
        for o in scene.model().observables:
            if isinstance(o, M.Period):
                out[f"{o.name}_dynamic"] = out.get(o.name, math.nan)
                out[f"{o.name}_dynamic_status"] = out.pop(f"{o.name}_status", "ok")
                out[o.name] = out["modal_period"]
    return out
