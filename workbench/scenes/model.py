"""A scene as data: the :class:`Model` every method reads (particle methods through
:mod:`sph.driver`, the FEM through :mod:`fem_reference.model`).

A model holds

- the geometry and a resolution rule: ``dim``, ``length`` (the spacing of a run at resolution r is
  ``length / r``: r intervals across that length — r + 1 particles on the node lattice, r on the
  cell lattice, r elements), the lattice of the particle methods;
- **regions** (:class:`Region`): a shape (:mod:`workbench.scenes.shapes`) with its own material; a
  region may be *held* (a rigid clamp block: its particles are fixed, the FEM does not mesh it and
  clamps its interface), belong to a separate *body* (bodies meet only through :class:`Contact`),
  and take a *priority* where regions overlap (a rebar inside the mortar);
- **named sets** (:class:`Set`): particles or nodes selected by a shape (a face, a plane, a probe
  point), optionally within one region;
- **constraints** (:class:`Clamp`, :class:`Roller` — a symmetry plane —, :class:`Prescribed`
  motion) and **loads** (:class:`Traction`, :class:`Pressure`, :class:`PointLoad`,
  :class:`BodyForce`, :class:`InitialVelocity`), each on a named set and scaled by a function of
  time (explicit drive) or of the load parameter (static drive);
- a **drive**: :class:`Static` (load steps along a path of the load parameter), :class:`Modal`,
  :class:`Explicit` (to an end time with a time-step factor), with **stop rules**
  (:class:`Threshold` on an observable; the explicit drive's own energy, disorder and separation
  rules);
- **pre-cracks** (:class:`PreCrack`): a zero-width crack — a segment in 2-D, a planar convex
  polygon (e.g. :meth:`PreCrack.rectangle`) in 3-D — that no particle interaction crosses, whatever
  the kernel's reach;
- **observables**: :class:`Displacement` of a probe or a set, :class:`Position`,
  :class:`Reaction` on a set, :class:`MeanStress`, :class:`FailedFraction` per region,
  :class:`Period` of a displacement history, :class:`CrackTip` (tip position, length, kink angle
  and speed of a growing crack); explicit runs always record the energies (kinetic,
  stored, plastic work, external work, released by failure).

Everything is a frozen dataclass; :meth:`Model.validate` checks the references between the parts
and raises :class:`SceneError` with one line naming the region, set or load and what is wrong.
Checks that need the discretisation (a set that selects no particle, overlapping regions without a
stated priority) are made where the model is discretised, with the same error.

Time functions (:class:`Table`, :func:`ramp`, a number, or a Python callable) give the scale of a
load: a :class:`Table` is piecewise linear and held constant beyond its ends; a callable is
evaluated at each load parameter of a static drive and tabulated finely for an explicit one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..materials import Material, MaterialTable
from .cracks import CrackTip, PreCrack, check_cracks, check_tip
from .params import SceneError
from .shapes import Point, Shape

POINT_TOL = 1e-9
"""A point set may lie this far (times the model's ``length``) outside its region: round-off of a
point placed on the boundary (a tip probe at X = L)."""


# ------------------------------------------------------------------------------------------------
# Time functions
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Table:
    """A piecewise-linear function through (``times[k]``, ``values[k]``) (times increasing), held
    constant before the first and after the last point. The argument is the time, s, in an
    explicit drive and the load parameter in a static one."""

    times: tuple
    values: tuple

    def __post_init__(self):
        t = tuple(float(v) for v in np.atleast_1d(self.times))
        v = tuple(float(x) for x in np.atleast_1d(self.values))
        if len(t) != len(v) or not t:
            raise SceneError(f"Table: times and values must have the same, non-zero length "
                             f"(got {len(t)} and {len(v)})")
        if any(b <= a for a, b in zip(t, t[1:])) or not all(map(math.isfinite, t + v)):
            raise SceneError("Table: times must be finite and strictly increasing, values finite")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "values", v)

    def __call__(self, t):
        return np.interp(t, self.times, self.values)


def constant(value: float = 1.0) -> Table:
    return Table((0.0,), (float(value),))


def ramp(t_ramp: float, value: float = 1.0) -> Table:
    """0 at t = 0, rising linearly to ``value`` at ``t_ramp``, then held."""
    if not t_ramp > 0:
        raise SceneError(f"ramp: t_ramp = {t_ramp!r} is out of range; allowed: (0, inf)")
    return Table((0.0, float(t_ramp)), (0.0, float(value)))


@dataclass(frozen=True)
class Proportional:
    """f(t) = ``factor`` · t: a load proportional to the load parameter (or to time)."""

    factor: float = 1.0

    def __call__(self, t):
        return self.factor * np.asarray(t, dtype=float)


def as_function(f) -> Callable:
    """A number, a :class:`Table` or a callable as a callable of one argument."""
    if isinstance(f, (int, float)):
        return constant(float(f))
    if callable(f):
        return f
    raise SceneError(f"scale: {f!r} is not a number, a Table or a callable")


# ------------------------------------------------------------------------------------------------
# Regions and sets
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Region:
    """Part of the body occupied by ``shape`` with ``material``.

    ``priority``: where the interiors of two regions overlap, the higher priority wins (a rebar
    inside the mortar); equal priorities over a common interior are an error. On a common
    *boundary* the higher priority, then the earlier region, takes the particles or nodes.
    ``held``: a rigid, fixed block (a clamp): its particles are held, the FEM leaves it out and
    clamps its interface with the body. ``body``: the name of the body the region belongs to;
    particles of different bodies interact only through :class:`Contact`. ``arrangement``:
    ``'lattice'`` (the model's lattice, the default) or ``'concentric'`` (2-D annulus only:
    particles on concentric circles, 004's cylindrical arrangement). ``failed``: the region's
    particles start already failed (cracked: a notch of any width, a damaged zone), as their law
    leaves a failed point (:func:`workbench.materials.failure.set_failed`); the material must be
    one with a failed state (J2, the mortar, the brittle law)."""

    name: str
    shape: Shape
    material: Material | None = None
    priority: int = 0
    held: bool = False
    body: str = "body"
    arrangement: str = "lattice"
    failed: bool = False


@dataclass(frozen=True)
class Set:
    """The particles or nodes in ``shape`` (closed; a :class:`~.shapes.Point` is a probe point:
    methods interpolate there), restricted to ``region`` when given."""

    name: str
    shape: Shape
    region: str | None = None


# ------------------------------------------------------------------------------------------------
# Constraints
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Clamp:
    """Every component of the set held at its reference position."""

    set: str


@dataclass(frozen=True)
class Roller:
    """Component ``axis`` of the set held (a roller, or a symmetry plane with normal e_axis)."""

    set: str
    axis: int


@dataclass(frozen=True)
class Prescribed:
    """Component ``axis`` of the set moved: ``displacement`` (m, a function of the load parameter
    in a static drive or of time in an explicit one) or ``velocity`` (m/s, explicit drives)."""

    set: str
    axis: int
    displacement: object = None
    velocity: object = None


# ------------------------------------------------------------------------------------------------
# Loads
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Traction:
    """A dead traction ``traction`` (d,), Pa (N/m per unit thickness in 2-D), on the surface of the
    set, times ``scale``. A particle's share is its boundary area on that surface (for a
    :class:`~.shapes.Plane` set the component of its boundary area vector along the plane normal)."""

    set: str
    traction: tuple
    scale: object = 1.0


@dataclass(frozen=True)
class Pressure:
    """A dead pressure, Pa, on the surface of the set, along the inward reference normal, times
    ``scale``."""

    set: str
    pressure: float
    scale: object = 1.0


@dataclass(frozen=True)
class PointLoad:
    """A dead force ``force`` (d,), N (N/m in 2-D), at the probe point of the set, times
    ``scale`` (spread over the particles by the probe's interpolation weights)."""

    set: str
    force: tuple
    scale: object = 1.0


@dataclass(frozen=True)
class BodyForce:
    """A body force per unit mass ``acceleration`` (d,), m/s² (gravity), times ``scale``, on the
    named ``regions`` (all when None)."""

    acceleration: tuple
    scale: object = 1.0
    regions: tuple | None = None


@dataclass(frozen=True)
class InitialVelocity:
    """The velocity at t = 0: a vector (d,), m/s, or a function ``fn(X) -> (N, d)`` of the
    reference positions, on the named ``regions`` (all when None; held particles stay at rest)."""

    velocity: object
    regions: tuple | None = None


@dataclass(frozen=True)
class Contact:
    """Contact between the bodies ``bodies = (a, b)``: a penalty ``stiffness`` (Pa) acting between
    particles of the two bodies closer than ``distance`` (m; None: the particle spacing)."""

    bodies: tuple
    stiffness: float
    distance: float | None = None


# ------------------------------------------------------------------------------------------------
# Drives
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Static:
    """Equilibrium at each value of the load parameter along ``path`` (loads and prescribed
    displacements are functions of it), reached by Newton from the previous one, the increment
    halved on failure. ``parameter`` and ``units`` name it in the results (e.g. the
    dimensionless load, or the logarithmic strain). ``stop``: :class:`Threshold` rules; the path
    ends at the first value where one holds (the later values are not run)."""

    path: tuple
    parameter: str = "load"
    units: str = "-"
    stop: tuple = ()


@dataclass(frozen=True)
class Modal:
    """The lowest ``n_modes`` small-amplitude vibration modes about the reference configuration."""

    n_modes: int = 3


@dataclass(frozen=True)
class Explicit:
    """Explicit dynamics to ``t_end`` (s) with the time step ``dt_factor`` times the method's CFL
    estimate, mass-proportional ``damping`` (1/s), observables and energies recorded about
    ``n_out`` times. Stability monitor (one criterion for every method): a non-finite state or a
    failed material point; the energy balance's gain growing exponentially beyond an absolute
    floor and beyond ``energy_growth`` of the largest energy seen (:mod:`sph.monitor`; one-sided:
    dissipation is recorded, not flagged); with ``disorder`` (η₉₅ limit),
    particle disorder measured on the set ``disorder_set`` (all particles when None) — None: the
    method's own default (classic SPH monitors its known failure, disorder, at
    :data:`sph.classic.DISORDER` on elastic materials; the other methods none), ``math.inf``: off.
    ``dt_reference``: what ``dt_factor`` multiplies — 'cfl' (the default: the CFL estimate
    Δx/c_p) or 'spectrum' (the method's critical step 2/ω_max at the initial state,
    :mod:`sph.spectrum`). ``separate`` (two set names) with ``after`` (s): the run stops ``after``
    seconds past the first record at which no chain of intact particles joins the two sets (a
    crack has cut the body between them; the method's ``components``), ``t_end`` then the
    longest it may run (``after`` = inf: to ``t_end``, the time and state of the cut recorded).
    ``stop``: :class:`Threshold` rules on the observables; the run ends ``after`` seconds past
    the first record at which one holds."""

    t_end: float
    dt_factor: float = 0.3
    damping: float = 0.0
    n_out: int = 400
    energy_growth: float = 0.5
    disorder: float | None = None
    disorder_set: str | None = None
    dt_reference: str = "cfl"
    separate: tuple[str, str] | None = None
    after: float = 0.0
    stop: tuple = ()


@dataclass(frozen=True)
class Threshold:
    """A stop rule of a drive (``Explicit(stop=...)``, ``Static(stop=...)``): the run ends when
    the observable named ``of`` is above ``above`` or below ``below`` (give one) — at the first
    such value of a static path, ``after`` seconds past the first such record of an explicit
    run (``after`` = inf: to ``t_end``, the time of the crossing recorded). Every method reads
    it the same way (:mod:`sph.stopping`, :mod:`fem_reference.model`): status ``ok``, criterion
    ``threshold``, the time (or load parameter) of the crossing in ``t_threshold``. For
    example ``Threshold("tip", below=-1e-3)`` ends a run once the tip has moved 1 mm down."""

    of: str
    above: float | None = None
    below: float | None = None
    after: float = 0.0

    def holds(self, value: float) -> bool:
        """Whether ``value`` has crossed the threshold (a NaN never has)."""
        if self.above is not None and value > self.above:
            return True
        return self.below is not None and value < self.below

    def describe(self) -> str:
        return (f"{self.of} > {self.above:g}" if self.above is not None
                else f"{self.of} < {self.below:g}")


# ------------------------------------------------------------------------------------------------
# Observables
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Displacement:
    """Displacement component ``axis`` (m) at the probe point of the set (interpolated), or the
    volume-weighted mean over the set's particles."""

    name: str
    set: str
    axis: int


@dataclass(frozen=True)
class Position:
    """Mean current coordinate ``axis`` (m) of the set's particles or nodes."""

    name: str
    set: str
    axis: int


@dataclass(frozen=True)
class Reaction:
    """Total force (N; N/m in 2-D) the constraints exert on the set along ``axis``: at each load
    value of a static drive; in an explicit drive its time mean over the interval since the
    previous record (the constraint impulse over the interval's length, :mod:`sph.driver`)."""

    name: str
    set: str
    axis: int


@dataclass(frozen=True)
class MeanStress:
    """Volume-weighted mean Cauchy stress component σ_ij (Pa), Σ V J σ_ij / Σ V J, over the
    named ``regions`` (all when None)."""

    name: str
    i: int
    j: int
    regions: tuple | None = None


@dataclass(frozen=True)
class FailedFraction:
    """Fraction of the particles (elements) of the named ``regions`` (all when None) whose damage
    has reached 1, whatever their law (:func:`workbench.materials.failure.failed`: J2, the
    mortar, the brittle law)."""

    name: str
    regions: tuple | None = None


@dataclass(frozen=True)
class Period:
    """Period (s) and amplitude (m) of the history of the :class:`Displacement` named ``of``
    (explicit drives): twice the least-squares slope of its zero-crossing times, and max |u|."""

    name: str
    of: str


@dataclass(frozen=True)
class ContactForce:
    """Total contact force (N; N/m in 2-D) on the particles of ``body`` along ``axis``, from
    every :class:`Contact` (explicit drives; an impact force, or the reaction of a held support
    body)."""

    name: str
    body: str
    axis: int


@dataclass(frozen=True)
class Momentum:
    """Linear momentum Σ m v (kg m/s; per unit thickness in 2-D) of the particles of ``body``
    along ``axis`` (explicit drives). Its change over an interval is the impulse of every force
    on the body; for a body that carries no load and no constraint along ``axis`` (a drop weight)
    that is the impulse of its :class:`ContactForce`, exactly (velocity Verlet changes Σ m v by
    the trapezoid impulse of the net force, and internal forces cancel), whatever the interval
    between records: a time mean of the contact force over any window is then exact, where the
    force itself is only sampled at the records."""

    name: str
    body: str
    axis: int


OBSERVABLES = (Displacement, Position, Reaction, MeanStress, FailedFraction, Period, ContactForce,
               Momentum, CrackTip)
def record_names(o, dim: int) -> tuple:
    """The names under which the observable ``o`` is recorded: its own name, or for a
    :class:`CrackTip` each of its quantities (:meth:`CrackTip.outputs`)."""
    return tuple(n for n, _ in o.outputs(dim)) if isinstance(o, CrackTip) else (o.name,)


CONSTRAINTS = (Clamp, Roller, Prescribed)
LOADS = (Traction, Pressure, PointLoad, BodyForce, InitialVelocity)
DRIVES = (Static, Modal, Explicit)


# ------------------------------------------------------------------------------------------------
# The model
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Model:
    """A scene as data (module docstring). ``length``: the resolution rule, spacing = length /
    resolution. ``plane``: the 2-D idealisation ('strain' or 'stress'; None in 3-D). ``lattice``:
    'node' (particles on the lattice nodes, faces included, volumes by the trapezoid rule) or
    'cell' (one particle per cell centre) for the particle methods. ``cracks``: the
    :class:`PreCrack` s of the body."""

    dim: int
    length: float
    regions: tuple
    drive: object
    sets: tuple = ()
    constraints: tuple = ()
    loads: tuple = ()
    observables: tuple = ()
    plane: str | None = "strain"
    lattice: str = "node"
    contact: tuple = ()
    name: str = "model"
    notes: tuple = field(default=())
    cracks: tuple = ()

    def __post_init__(self):
        for k in ("regions", "sets", "constraints", "loads", "observables", "contact", "notes",
                  "cracks"):
            object.__setattr__(self, k, tuple(getattr(self, k)))
        self.validate()

    def _check_point(self, s) -> None:
        """A point set (a probe, a point load) must lie in the body — inside or on the boundary
        of a region (of its own region, if it names one), to round-off
        (:data:`POINT_TOL` · ``length``): every method then reads the same place, where the FEM
        refuses a point outside its mesh and a particle method would read its nearest
        particle."""
        p = np.asarray(s.shape.at, float)
        if p.shape != (self.dim,):
            raise SceneError(f"set '{s.name}': the point {tuple(p)} has {p.size} coordinates in a "
                             f"{self.dim}-D model")
        regions = [r for r in self.regions if s.region is None or r.name == s.region]
        if not any(bool(r.shape.contains(p[None, :], POINT_TOL * self.length)[0]) for r in regions):
            where = f"region '{s.region}'" if s.region is not None else "the body (every region)"
            raise SceneError(f"set '{s.name}': the point {tuple(p.tolist())} m lies outside "
                             f"{where}; allowed: a point inside or on the boundary of "
                             f"{'it' if s.region is not None else 'a region'}")

    # -- lookups -----------------------------------------------------------------------------
    def region(self, name: str) -> Region:
        for r in self.regions:
            if r.name == name:
                return r
        raise SceneError(f"region '{name}': no such region (regions: {_names(self.regions)})")

    def set(self, name: str) -> Set:
        for s in self.sets:
            if s.name == name:
                return s
        raise SceneError(f"set '{name}': no such set (sets: {_names(self.sets)})")

    @property
    def bodies(self) -> tuple:
        """The body names, in order of first appearance."""
        return tuple(dict.fromkeys(r.body for r in self.regions))

    def materials(self) -> tuple[MaterialTable, dict]:
        """The material table of the model (distinct materials in region order) and the row of
        each region: (table, {region name: row})."""
        mats, rows = [], {}
        for r in self.regions:
            if r.material not in mats:
                mats.append(r.material)
            rows[r.name] = mats.index(r.material)
        return MaterialTable(tuple(mats)), rows

    def observable(self, name: str):
        for o in self.observables:
            if o.name == name:
                return o
        raise SceneError(f"observable '{name}': no such observable")

    # -- checks ------------------------------------------------------------------------------
    def validate(self) -> "Model":
        if self.dim not in (2, 3):
            raise SceneError(f"dim: {self.dim!r} is not allowed; 2 or 3")
        if not (isinstance(self.length, (int, float)) and self.length > 0 and math.isfinite(self.length)):
            raise SceneError(f"length: {self.length!r} m is out of range; allowed: (0, inf) m")
        if self.plane not in (("strain", "stress") if self.dim == 2 else (None,)):
            raise SceneError(f"plane: {self.plane!r} is not allowed; 'strain' or 'stress' in 2-D, "
                             f"None in 3-D")
        if self.lattice not in ("node", "cell"):
            raise SceneError(f"lattice: {self.lattice!r} is not one of 'node', 'cell'")
        if not self.regions:
            raise SceneError("regions: a model needs at least one region")
        _unique("region", self.regions)
        _unique("set", self.sets)
        _unique("observable", self.observables)
        for r in self.regions:
            if not isinstance(r, Region):
                raise SceneError(f"regions: {r!r} is not a Region")
            if r.material is None:
                raise SceneError(f"region '{r.name}': no material (give one of workbench.materials, "
                                 "e.g. Material.svk(E, nu, rho))")
            if not isinstance(r.material, Material):
                raise SceneError(f"region '{r.name}': material {r.material!r} is not a Material")
            if not isinstance(r.shape, Shape):
                raise SceneError(f"region '{r.name}': shape {r.shape!r} is not a Shape")
            sd = getattr(r.shape, "dim", None)
            if sd is not None and sd != self.dim:
                raise SceneError(f"region '{r.name}': a {sd}-D shape in a {self.dim}-D model")
            if r.arrangement not in ("lattice", "concentric"):
                raise SceneError(f"region '{r.name}': arrangement {r.arrangement!r} is not one of "
                                 "'lattice', 'concentric'")
            if r.failed:
                from ..materials.failure import damage_column

                if r.held:
                    raise SceneError(f"region '{r.name}': failed=True is not allowed on a held "
                                     "region (a rigid block cannot crack)")
                if damage_column(r.material) < 0:
                    raise SceneError(f"region '{r.name}': failed=True needs a material that can "
                                     f"fail (j2, mortar, brittle); its law is "
                                     f"{r.material.law!r}")
        region_names = {r.name for r in self.regions}
        set_names = {s.name for s in self.sets}
        for s in self.sets:
            if not isinstance(s.shape, Shape):
                raise SceneError(f"set '{s.name}': shape {s.shape!r} is not a Shape")
            if s.region is not None and s.region not in region_names:
                raise SceneError(f"set '{s.name}': region '{s.region}' does not exist "
                                 f"(regions: {_names(self.regions)})")
            if isinstance(s.shape, Point):
                self._check_point(s)
        for item in self.constraints + self.loads:
            if not isinstance(item, CONSTRAINTS + LOADS):
                raise SceneError(f"constraints/loads: {item!r} is not a constraint or a load")
            what = type(item).__name__
            name = getattr(item, "set", None)
            if name is not None and name not in set_names:
                raise SceneError(f"{what} on set '{name}': no such set (sets: {_names(self.sets)})")
            axis = getattr(item, "axis", None)
            if axis is not None and axis not in range(self.dim):
                raise SceneError(f"{what} on set '{name}': axis {axis!r} is out of range; "
                                 f"allowed: 0..{self.dim - 1}")
            for vec in ("traction", "force", "acceleration"):
                v = getattr(item, vec, None)
                if v is not None and len(tuple(v)) != self.dim:
                    raise SceneError(f"{what}: {vec} {v!r} must have {self.dim} components")
            for rn in getattr(item, "regions", None) or ():
                if rn not in region_names:
                    raise SceneError(f"{what}: region '{rn}' does not exist "
                                     f"(regions: {_names(self.regions)})")
            if isinstance(item, Prescribed):
                if item.displacement is None and item.velocity is None:
                    raise SceneError(f"Prescribed on set '{name}': give a displacement or a velocity")
                if isinstance(self.drive, Static) and item.displacement is None:
                    raise SceneError(f"Prescribed on set '{name}': a static drive needs a displacement")
            scale = getattr(item, "scale", None)
            if scale is not None:
                as_function(scale)
        check_cracks(self)
        obs_names = {o.name for o in self.observables}
        for o in self.observables:
            if not isinstance(o, OBSERVABLES):
                raise SceneError(f"observables: {o!r} is not an observable")
            sname = getattr(o, "set", None)
            if sname is not None and sname not in set_names:
                raise SceneError(f"observable '{o.name}': set '{sname}' does not exist "
                                 f"(sets: {_names(self.sets)})")
            for rn in getattr(o, "regions", None) or ():
                if rn not in region_names:
                    raise SceneError(f"observable '{o.name}': region '{rn}' does not exist")
            if isinstance(o, (ContactForce, Momentum)) and o.body not in self.bodies:
                raise SceneError(f"observable '{o.name}': body '{o.body}' does not exist "
                                 f"(bodies: {', '.join(self.bodies)})")
            if isinstance(o, CrackTip):
                check_tip(self, o)
            if isinstance(o, Period):
                if o.of not in obs_names or not isinstance(self.observable(o.of), Displacement):
                    raise SceneError(f"observable '{o.name}': '{o.of}' is not a Displacement "
                                     "observable of this model")
            axis = getattr(o, "axis", None)
            if axis is not None and axis not in range(self.dim):
                raise SceneError(f"observable '{o.name}': axis {axis!r} is out of range; "
                                 f"allowed: 0..{self.dim - 1}")
        bodies = set(self.bodies)
        for c in self.contact:
            if not isinstance(c, Contact) or len(tuple(c.bodies)) != 2:
                raise SceneError(f"contact: {c!r} is not a Contact between two bodies")
            for b in c.bodies:
                if b not in bodies:
                    raise SceneError(f"contact: body '{b}' does not exist (bodies: {', '.join(self.bodies)})")
            if not c.stiffness > 0:
                raise SceneError(f"contact: stiffness {c.stiffness!r} Pa is out of range; allowed: (0, inf)")
        d = self.drive
        if not isinstance(d, DRIVES):
            raise SceneError(f"drive: {d!r} is not Static, Modal or Explicit")
        if isinstance(d, Static):
            p = np.asarray(d.path, dtype=float)
            if p.size == 0 or not np.all(np.isfinite(p)):
                raise SceneError("drive: a static path needs at least one finite value")
        if isinstance(d, Explicit):
            if not (d.t_end > 0 and math.isfinite(d.t_end)):
                raise SceneError(f"drive: t_end = {d.t_end!r} s is out of range; allowed: (0, inf) s")
            if not 0 < d.dt_factor <= 10:
                raise SceneError(f"dt_factor: {d.dt_factor!r} is out of range; allowed: (0, 10]")
            if d.dt_reference not in ("cfl", "spectrum"):
                raise SceneError(f"dt_reference: {d.dt_reference!r} is not allowed; 'cfl' or 'spectrum'")
            if d.disorder is not None and not d.disorder > 0:
                raise SceneError(f"disorder: {d.disorder!r} is out of range; allowed: (0, inf] or None")
            if d.disorder_set is not None and d.disorder_set not in set_names:
                raise SceneError(f"drive: disorder set '{d.disorder_set}' does not exist")
        for rule in getattr(d, "stop", ()):
            self._check_stop(rule)
        if isinstance(d, Modal) and not (isinstance(d.n_modes, int) and d.n_modes >= 1):
            raise SceneError(f"drive: n_modes = {d.n_modes!r} is out of range; allowed: integers >= 1")
        return self

    def _check_stop(self, rule) -> None:
        """A stop rule names an observable of the model that has a value at every record, and
        one finite threshold; ``after`` ≥ 0 (0 on a static path: it ends where the rule holds)."""
        if not isinstance(rule, Threshold):
            raise SceneError(f"drive: stop rule {rule!r} is not a Threshold")
        recorded = [n for o in self.observables if not isinstance(o, Period)
                    for n in record_names(o, self.dim)]
        if rule.of not in recorded:
            raise SceneError(f"stop rule on '{rule.of}': no such observable with a value at every "
                             f"record (recorded: {', '.join(recorded) or 'none'})")
        bounds = [b for b in (rule.above, rule.below) if b is not None]
        if len(bounds) != 1 or not math.isfinite(bounds[0]):
            raise SceneError(f"stop rule on '{rule.of}': give one finite threshold, above or below")
        limit = (0.0, 0.0) if isinstance(self.drive, Static) else (0.0, math.inf)
        if not (isinstance(rule.after, (int, float)) and limit[0] <= rule.after <= limit[1]):
            raise SceneError(f"stop rule on '{rule.of}': after = {rule.after!r} s is out of range; "
                             f"allowed: " + ("0 on a static path" if limit[1] == 0 else "[0, inf] s"))

    def crack(self, name: str) -> PreCrack:
        for c in self.cracks:
            if c.name == name:
                return c
        raise SceneError(f"pre-crack '{name}': no such pre-crack (pre-cracks: {_names(self.cracks)})")

    def tip_origin(self, o) -> tuple[np.ndarray, np.ndarray | None]:
        """The origin (d,) of the :class:`CrackTip` ``o`` and the reference direction of its kink
        angle ((d,) unit, or None: the path's first leg)."""
        if isinstance(o.origin, str):
            pts = np.asarray(self.crack(o.origin).points)
            origin = pts[-1]
            ref = pts[-1] - pts[-2] if self.dim == 2 else None
        else:
            origin, ref = np.asarray(o.origin, float), None
        if o.direction is not None:
            ref = np.asarray(o.direction, float)
        return origin, (None if ref is None else ref / np.linalg.norm(ref))

    def describe(self) -> dict:
        """Dataset attributes: regions with their materials, sets, constraints, loads, drive."""
        out = {"model_dim": self.dim, "model_plane": str(self.plane), "model_lattice": self.lattice,
               "model_regions": "; ".join(f"{r.name}: {r.material.law} E={r.material.E:g} Pa"
                                          f"{' (held)' if r.held else ''}" for r in self.regions),
               "model_drive": repr(self.drive)}
        if self.cracks:
            out["model_cracks"] = "; ".join(f"{c.name}: {c.points}" for c in self.cracks)
        if self.notes:
            out["model_notes"] = " ".join(self.notes)
        return out


def _names(items) -> str:
    return ", ".join(i.name for i in items) or "none"


def _unique(kind: str, items) -> None:
    seen = set()
    for i in items:
        if i.name in seen:
            raise SceneError(f"{kind} '{i.name}': the name is used twice")
        seen.add(i.name)
