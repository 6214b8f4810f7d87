"""The reinforced mortar beam under drop-weight impact of paper 003 (§2, §4.1, Fig. 1–2, 12–14,
Table 1), as parameters and a model: a quarter model by the two symmetry planes, 3-D.

What we read from 003 (the figures are labels only; approximate):

* section 75 mm wide × 100 mm high; two D10 bars with their centres 20 mm from the bottom and from
  the sides (Fig. 1–2: "20 … 35 … 20" across the width, "20" above the bottom);
* specimen **A**: span 800 mm, 20 mm overhang past each support, D6 stirrups at x = 50, 130, 210,
  290 mm from mid-span (Fig. 1: "50 80 80 80 110 20"), 60 mm high between the bar levels
  (Fig. 1: "60"), a 100 kg weight at 2.2 m/s; specimen **B**: span 400 mm, no stirrups, 1.4 m/s;
* a steel plate bonded on the top at mid-span takes the impact (§2); we read its length along the
  span as 100 mm (Fig. 1–2: "50" either side of C.L.) over the full width; its thickness is not
  given (``plate_thickness``, 10 mm; rounded down to whole spacings above the beam's top lattice
  layer, so that the weight's bottom layer, one spacing above the plate's top layer, is a free
  surface of its own);
* hinge supports without anti-rebound fixtures (§2, Fig. 4);
* materials (Table 1, Fig. 14): mortar E = 11.9 GPa, ν = 0.22, f_c = 16.1 MPa, f_t = 1.61 MPa,
  stress fully released at 17 000 µ strain for 5 mm particles (§4.1); steel E = 206 GPa, ν = 0.3,
  f_y = 394 MPa; post-yield slope E/100 in both;
* quarter model by two symmetry planes, 5 mm particles (§4.1).

Our choices (all parameters below; ``workbench list`` shows them):

* coordinates: x along the span from mid-span (x = 0, a symmetry plane: roller on x), y across
  from mid-width (y = 0, a symmetry plane: roller on y), z up from the beam's bottom;
* **bars as lattice lines with an equivalent material**: a D10 bar (71.33 mm², JIS nominal) is a
  square bar of the same area in the geometry, but at 5 mm spacing a 8.4 mm square holds 1 × 2
  lattice lines. Each bar (and each stirrup leg, D6: 31.67 mm²) is the lattice lines within half
  its side of its centre line (at least the nearest one), whose particle area is A_p = n dx², and
  its steel is scaled by s = A_bar/A_p (E, σ_y, the hardening modulus and ρ all × s): the bar's
  axial stiffness E A, yield force and mass are the real bar's, its wave speed the steel's
  (:func:`bar_lines`);
* the **weight** is a separate body, a steel-stiff block over the plate's footprint,
  ``weight_height`` high, whose density makes its discretised mass the quarter mass (100 kg/4:
  its volume is the half-spacing staircase of the particle discretisation, :func:`staircase`),
  starting one spacing above the plate (just touching at the contact distance) with the impact
  velocity; it meets the plate through the particle contact of :mod:`sph.contact`;
* the **supports** are held steel blocks (a strip of three lattice columns centred at x = span/2,
  three layers deep — fewer leave CSPH's gradient correction of the block singular —, one
  spacing below the beam's bottom) meeting the beam through the same contact: a one-sided hinge
  (the beam may lift off: no anti-rebound fixture). One penalty acts between all bodies
  (``contact_stiffness`` × the steel's E);
* the release strain is tied to the spacing by eq. 5 (G_F fixed): ε_r(Δx) = ε_r · 5 mm / Δx
  (``scale_release``), so the energy released per crack area does not depend on the spacing;
* no gravity (the weight's speed is the impact speed); the kernel reduction of §4.2(2) belongs to
  the particle method: classic SPH's ``kernel_reduction`` option (:func:`sph.classic.kernel_factors`);
* ``symmetry=False``: the full beam (each box of the quarter model mirrored in x = 0 and y = 0, the
  lattice anchored so that it is the quarter model's mirrored: :meth:`RCBeam.mortar_shape`), no
  rollers, forces not scaled (:attr:`RCBeam.copies`) — for issue 12's symmetry gate. The quarter
  model's contact is weighted on its symmetry planes (:mod:`sph.contact`: a pair of particles
  both on a plane carries half its force, the planes read from the rollers), so that its contact
  forces and energy are exactly a quarter of the mirrored full beam's (A, 12.5 mm, nodal csph:
  peak impact force 584.0 kN against the full beam's 584.2 kN; 625.8 kN unweighted). CSPH
  builds the quarter's discretisation on the full body and keeps mirror images of the neighbours
  across the planes (:mod:`sph.mirror`), so the quarter moves as the full beam does, to
  round-off (tests/test_mirror.py: mid-span displacement over 0.5 ms at 20 mm 1e-8 of the peak
  apart); classic SPH finds its ghosts with its neighbours (1e-12 at 12.5 mm). With one-sided
  stencils (``mirror='none'``) csph is 11 % off at 20 mm (partly because the quarter's half
  width there is too narrow for the quadratic correction), 12 % at 12.5 mm, classic SPH 24 % at
  12.5 mm (specimen B, 0.5 ms);
* ``velocity`` defaults to None, the specimen's speed; a given speed must lie in (0, 50] m/s;
* ``structure='beam'``: the beam with its rebar alone (no plate, weight, support blocks or
  contact) on hinges — the line x = span/2, z = 0 held along z — with a modal drive: the elastic
  check against the FEM (which meshes one body without contact). A bar's box reaches half a
  spacing beyond its lattice lines, so that its section is the particles' n dx² (the FEM meshes the
  box with the same equivalent steel) and no other lattice node lies in it.

Running: ``driver.solve("sph", RCBeam(), 20, stress="hyperelastic")`` (the mortar and the J2 steel
need classic SPH's hyperelastic stress) and ``driver.solve("csph", RCBeam(), 20,
integration="nodal")``. The integration-consistent CSPH (the default) fails at the CFL step
(``dt_factor`` 0.3): its critical step 2/ω_max (:mod:`sph.spectrum`) is only 0.20 Δx/c_p on
specimen A at 12.5 mm (0.40 on B; 0.94 at 20 mm; nodal integration 0.57 at 12.5 mm) — the stiff
equivalent steel of the bars on lattice lines next to the mortar. With ``dt_reference='spectrum'``
and ``dt_factor`` 0.9 it runs (stable at 0.9 Δt_crit, exponential growth at 1.2 Δt_crit:
tests/test_rc_beam.py).

Observed (quarter model; :meth:`RCBeam.summarise` gives the full beam's): the mid-span bottom
displacement (probe at x = y = z = 0), the weight's mean displacement, the contact force on the
weight (the impact force) and on the supports (minus the support reaction), and the force that holds
the support blocks (``support_hold``, the driver's time mean over each record interval), and
the weight's z momentum (``weight_momentum``: its change is the impulse of the impact force, the
weight carrying no other force along z).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import workbench.scenes.model as m

from workbench.materials import Material, linear_hardening_modulus
from workbench.materials.mortar_constants import PAPER_SPACING
from workbench.scenes.params import ParameterError, Scene, SceneError, param
from workbench.scenes.shapes import Box, Difference, Plane, Point, Union

D10_AREA = 71.33e-6
"""JIS G 3112 nominal section of a D10 deformed bar, m²."""
D6_AREA = 31.67e-6
"""JIS G 3112 nominal section of a D6 deformed bar, m²."""
SPECIMENS = {
    "A": dict(span=0.8, velocity=2.2, stirrups=(0.05, 0.13, 0.21, 0.29)),
    "B": dict(span=0.4, velocity=1.4, stirrups=()),
}
"""003 §2, Fig. 1–2: span (m), impact velocity (m/s), stirrup positions from mid-span (m)."""
TOL = 1e-9


def bar_lines(centre: float, side: float, dx: float) -> tuple[int, int]:
    """Lattice lines (node indices k, positions k·dx, lattice anchored at 0) of a bar of square
    side ``side`` (m) centred at ``centre`` (m) along one cross axis: the k with
    |k dx − centre| ≤ side/2, or the nearest one when none is. Returns (k_lo, k_hi)."""
    lo = math.ceil((centre - 0.5 * side) / dx - TOL)
    hi = math.floor((centre + 0.5 * side) / dx + TOL)
    if hi < lo:
        lo = hi = int(round(centre / dx))
    return int(lo), int(hi)


def staircase(a: float, dx: float) -> float:
    """Discretised length (m) of an interval [k dx, k dx + a] starting on a lattice node: the
    particle volumes come from sub-cells of half spacing whose centres lie inside
    (:mod:`sph.particles`): the nodes in the interval own dx/2 on either side, the first node's
    lower half and the last node's upper half only where the sub-cell centre (a quarter spacing
    away) lies inside. So: the last node's offset, plus dx/2 when its upper sub-cell's centre is
    inside."""
    last = dx * math.floor(a / dx + TOL)
    return last + (0.5 * dx if last + 0.25 * dx <= a + TOL * dx else 0.0)


@dataclass(frozen=True)
class RCBeam(Scene):
    """Reinforced mortar beam of 003 under a drop weight: quarter model, 3-D (module docstring).
    Resolution r: spacing ``H / r`` (default r = H/``spacing`` = 20, 5 mm)."""

    name: str = field(default="rc_beam", metadata=dict(hidden=True))
    specimen: str = param("A", "-", "specimen of 003: A (800 mm span, D6 stirrups, 2.2 m/s) or B "
                          "(400 mm, 1.4 m/s)", choices=("A", "B"))
    velocity: float | None = param(None, "m/s", "impact velocity; default (none): the specimen's "
                                   "(A 2.2, B 1.4)", lo=0, lo_open=True, hi=50)
    mass: float = param(100.0, "kg", "mass of the weight (the full weight)", lo=0, lo_open=True)
    overhang: float = param(0.02, "m", "beam length past each support", lo=0, lo_open=True, hi=0.5)
    B: float = param(0.075, "m", "section width", lo=0, lo_open=True, hi=1)
    H: float = param(0.1, "m", "section height", lo=0, lo_open=True, hi=1)
    cover: float = param(0.02, "m", "bar centres from the bottom and from the sides", lo=0,
                         lo_open=True)
    bar_area: float = param(D10_AREA, "m^2", "section of one main bar (D10: 71.33 mm^2)", lo=0,
                            lo_open=True)
    stirrup_area: float = param(D6_AREA, "m^2", "section of a stirrup leg (D6: 31.67 mm^2)",
                                lo=0, lo_open=True)
    stirrup_height: float = param(0.06, "m", "stirrup height between the bar levels", lo=0,
                                  lo_open=True)
    stirrups: bool = param(True, "-", "D6 stirrups of specimen A (B has none)")
    rebar: bool = param(True, "-", "the main bars and stirrups; false: a plain mortar beam (the "
                        "bars' lattice lines are mortar; a diagnostic of issue 35)")
    plate_length: float = param(0.1, "m", "loading plate length along the span", lo=0,
                                lo_open=True)
    plate_thickness: float = param(0.01, "m", "loading plate thickness", lo=0, lo_open=True)
    weight_height: float = param(0.05, "m", "height of the weight block (its density gives the "
                                 "mass)", lo=0, lo_open=True)
    E_m: float = param(11.9e9, "Pa", "mortar Young's modulus", lo=0, lo_open=True)
    nu_m: float = param(0.22, "-", "mortar Poisson's ratio", lo=-1, hi=0.5, lo_open=True,
                        hi_open=True)
    f_c: float = param(16.1e6, "Pa", "mortar compressive strength", lo=0, lo_open=True)
    f_t: float = param(1.61e6, "Pa", "mortar tensile strength", lo=0, lo_open=True)
    rho_m: float = param(2200.0, "kg/m^3", "mortar density (003 gives none)", lo=0, lo_open=True)
    eps_release: float = param(0.017, "-", "strain of full stress release at 5 mm spacing "
                               "(must exceed f_t/E_m)", lo=0, lo_open=True)
    scale_release: bool = param(True, "-", "release strain x 5 mm/spacing (eq. 5, G_F fixed)")
    phi_min: float = param(0.05, "-", "floor of the mortar's shear reduction factors (003 eq. 6: "
                           "0.05); near 1 the crack keeps its shear stiffness", lo=0, hi=1,
                           hi_open=True)
    shear_retention: float = param(0.05, "-", "the mortar's constant shear rate of a cracked pair "
                                   "of axes (a fixed smeared crack: a sliding crack releases its "
                                   "normal G_F only); 0: 003's eq. 7 as printed (rates falling "
                                   "with the opening, floored by phi_min)", lo=0, hi=1)
    E_s: float = param(206e9, "Pa", "steel Young's modulus", lo=0, lo_open=True)
    nu_s: float = param(0.3, "-", "steel Poisson's ratio", lo=-1, hi=0.5, lo_open=True,
                        hi_open=True)
    f_y: float = param(394e6, "Pa", "steel yield strength", lo=0, lo_open=True)
    rho_s: float = param(7850.0, "kg/m^3", "steel density", lo=0, lo_open=True)
    contact_stiffness: float = param(1.0, "-", "contact penalty over the steel's E", lo=0,
                                     lo_open=True, hi=100)
    spacing: float = param(0.005, "m", "particle spacing (at most the cover)", lo=0, lo_open=True)
    t_end: float = param(0.01, "s", "simulated time", lo=0, lo_open=True)
    dt_factor: float = param(0.3, "-", "time step over the CFL estimate", lo=0, hi=10,
                             lo_open=True)
    dt_reference: str = param("cfl", "-", "what dt_factor multiplies: cfl (the CFL estimate "
                              "dx/c_p) or spectrum (the method's critical step 2/omega_max at the "
                              "initial state, sph.spectrum)", choices=("cfl", "spectrum"))
    n_out: int = param(200, "-", "records over the run", lo=1)
    symmetry: bool = param(True, "-", "quarter model by the symmetry planes x = 0 and y = 0 "
                           "(rollers); false: the full beam (every box mirrored, no rollers; "
                           "forces not scaled), for the symmetry check")
    structure: str = param("impact", "-", "impact: the weight strikes the plate, supports by "
                           "contact; beam: the beam with its rebar alone on hinges (a line "
                           "x = span/2, z = 0 held along z), no plate, weight or contact, lowest "
                           "modes (the elastic check against the FEM)", choices=("impact", "beam"))

    # -- parameters ---------------------------------------------------------------------------
    def check(self):
        if self.velocity is not None:
            try:  # ``--set velocity=3`` arrives as text (the default is None)
                v = float(self.velocity)
            except (TypeError, ValueError):
                raise ParameterError(f"velocity: cannot read {self.velocity!r} as a number; "
                                     "allowed: (0, 50] m/s") from None
            if not 0 < v <= 50:
                raise ParameterError(f"velocity: {v:g} m/s is out of range; allowed: (0, 50] m/s")
            object.__setattr__(self, "velocity", v)
        if self.spacing > self.cover * (1 + 1e-9):
            raise ParameterError(f"spacing: {self.spacing:g} m is out of range; allowed: "
                                 f"(0, cover={self.cover:g}] m")
        if not 2 * self.cover < min(self.B, self.H):
            raise ParameterError(f"cover: {self.cover:g} m is out of range; allowed: "
                                 f"(0, {0.5 * min(self.B, self.H):g}) m")
        if not self.cover + self.stirrup_height < self.H:
            raise ParameterError(f"stirrup_height: {self.stirrup_height:g} m is out of range; "
                                 f"allowed: (0, H - cover={self.H - self.cover:g}) m")
        if not self.plate_length / 2 < self.span / 2:
            raise ParameterError(f"plate_length: {self.plate_length:g} m is out of range; allowed: "
                                 f"(0, span={self.span:g}) m")
        self.mortar(self.spacing)  # strengths and the release strain (ParameterError)

    @property
    def span(self) -> float:
        """Distance between the supports, m."""
        return SPECIMENS[self.specimen]["span"]

    @property
    def impact_velocity(self) -> float:
        """The weight's speed at impact, m/s."""
        return self.velocity if self.velocity is not None else SPECIMENS[self.specimen]["velocity"]

    @property
    def stirrup_positions(self) -> tuple:
        """x of the stirrups from mid-span, m (none for B or ``stirrups`` false)."""
        return SPECIMENS[self.specimen]["stirrups"] if self.stirrups else ()

    @property
    def resolution(self) -> int:
        """The resolution of ``spacing``: particles across H."""
        return max(1, int(round(self.H / self.spacing)))

    # -- materials ----------------------------------------------------------------------------
    def release_strain(self, dx: float) -> float:
        """ε_r at spacing dx: ``eps_release`` · 5 mm/dx with ``scale_release`` (eq. 5: the
        released energy per crack area G_F = g_F h fixed), else ``eps_release``."""
        return self.eps_release * (PAPER_SPACING / dx if self.scale_release else 1.0)

    def mortar(self, dx: float) -> Material:
        """The mortar of 003 (Table 1, eq. 5–8) at spacing dx."""
        try:
            return Material.mortar(E=self.E_m, nu=self.nu_m, f_t=self.f_t, f_c=self.f_c,
                                   eps_release=self.release_strain(dx), rho=self.rho_m,
                                   phi_min=self.phi_min, shear_retention=self.shear_retention)
        except ValueError as err:
            raise ParameterError(str(err)) from None

    def steel(self, scale: float = 1.0) -> Material:
        """The bilinear steel of 003 (Fig. 14, post-yield slope E/100), every constant and the
        density times ``scale`` (the equivalent material of a bar on lattice lines)."""
        H = linear_hardening_modulus(self.E_s, self.E_s / 100)
        return Material.j2_linear(E=scale * self.E_s, nu=self.nu_s, sigma_y0=scale * self.f_y,
                                  H=scale * H, rho=scale * self.rho_s)

    def weight_density(self, dx: float) -> float:
        """ρ of the weight block that makes its discretised quarter volume carry mass/4, kg/m³."""
        V = (staircase(self.plate_length / 2, dx) * staircase(self.B / 2, dx)
             * staircase(self.weight_height, dx))
        return 0.25 * self.mass / V

    # -- the model ----------------------------------------------------------------------------
    @property
    def copies(self) -> int:
        """How many copies of the model make the full beam: 4 (quarter model) or 1."""
        return 4 if self.symmetry else 1

    def whole(self, box: Box):
        """A box of the quarter model (x ≥ 0, y ≥ 0) as the model's shape: itself with
        ``symmetry``, else the full beam's: the box and its mirror images in x = 0 and y = 0, as
        one box across a plane the box starts on, two apart otherwise (no overlap: the
        discretisation's volumes would count an overlap twice)."""
        if self.symmetry:
            return box
        (x0, y0, z0), (x1, y1, z1) = box.lo, box.hi

        def spans(a0, a1):
            return ((-a1, a1),) if abs(a0) < TOL else ((a0, a1), (-a1, -a0))

        parts = tuple(Box((a0, b0, z0), (a1, b1, z1))
                      for a0, a1 in spans(x0, x1) for b0, b1 in spans(y0, y1))
        return parts[0] if len(parts) == 1 else Union(parts)

    def mortar_shape(self, dx: float):
        """The mortar's box, x ∈ [0, x_e], y ∈ [0, B/2], z ∈ [0, H] (quarter model) or the full
        beam's, x ∈ [−x_e, x_e], y ∈ [−B/2, B/2]. The particle lattice is anchored at the lowest
        corner of the regions' bounds, so in the full beam the mortar's bounds reach down to the
        lattice nodes −⌈x_e/Δx⌉Δx, −⌈B/(2Δx)⌉Δx (a box minus the slabs beyond −x_e and −B/2):
        the full beam's lattice is then the quarter model's, mirrored (a node on x = 0, y = 0)."""
        xe, B2, H = self.span / 2 + self.overhang, self.B / 2, self.H
        box = Box((0.0, 0.0, 0.0), (xe, B2, H))
        if self.symmetry:
            return box
        ax = -math.ceil(xe / dx - TOL) * dx
        ay = -math.ceil(B2 / dx - TOL) * dx
        big = (xe + dx, B2 + dx, H + dx)
        beyond = Union((Box((ax - dx, ay - dx, -dx), (-xe, big[1], big[2])),
                        Box((ax - dx, ay - dx, -dx), (big[0], -B2, big[2]))))
        return Difference(Box((ax, ay, 0.0), (xe, B2, H)), beyond)

    def bars(self, dx: float) -> list:
        """The steel on lattice lines at spacing dx: a list of (name, Box, scale, priority) — the
        main bar (quarter model: one), and three legs per stirrup (vertical at the bar's y, bottom
        and top horizontal from the symmetry plane to it)."""
        yb, zb = self.B / 2 - self.cover, self.cover
        zt = zb + self.stirrup_height
        xe = self.span / 2 + self.overhang
        q = 0.5 * dx  # a box edge half a spacing beyond the outer lattice lines: the box's
        # section is the particles' area n dx² (what the FEM meshes), no other node inside
        out = []
        side = math.sqrt(self.bar_area)
        ky, kz = bar_lines(yb, side, dx), bar_lines(zb, side, dx)
        n = (ky[1] - ky[0] + 1) * (kz[1] - kz[0] + 1)
        out.append(("bar", Box((0.0, ky[0] * dx - q, kz[0] * dx - q), (xe, ky[1] * dx + q, kz[1] * dx + q)),
                    self.bar_area / (n * dx * dx), 3))
        s = math.sqrt(self.stirrup_area)
        for i, xs in enumerate(self.stirrup_positions):
            kx = bar_lines(xs, s, dx)
            x0, x1 = kx[0] * dx - q, kx[1] * dx + q
            ky, kb, kt = bar_lines(yb, s, dx), bar_lines(zb, s, dx), bar_lines(zt, s, dx)
            nx = kx[1] - kx[0] + 1
            out.append((f"stirrup{i}_side", Box((x0, ky[0] * dx - q, zb), (x1, ky[1] * dx + q, zt)),
                        self.stirrup_area / (nx * (ky[1] - ky[0] + 1) * dx * dx), 2))
            for leg, kk in (("bottom", kb), ("top", kt)):
                out.append((f"stirrup{i}_{leg}", Box((x0, 0.0, kk[0] * dx - q), (x1, yb, kk[1] * dx + q)),
                            self.stirrup_area / (nx * (kk[1] - kk[0] + 1) * dx * dx), 1))
        return out

    def model(self, spacing: float | None = None) -> m.Model:
        dx = self.spacing if spacing is None else spacing
        if dx > self.cover * (1 + 1e-9):
            raise SceneError(f"spacing: {dx:g} m is out of range; allowed: (0, cover={self.cover:g}] m")
        L2, B2, H = self.span / 2, self.B / 2, self.H
        xe = L2 + self.overhang
        xp = self.plate_length / 2
        z_top = math.floor((H + self.plate_thickness) / dx + TOL) * dx  # the plate's top layer
        top = z_top + 0.2 * dx  # the plate's box: its top layer's upper sub-cells outside
        zw = z_top + dx  # the weight's bottom layer: one spacing (the contact distance) above
        if self.structure == "beam":
            return self._beam_model(dx)
        steel = self.steel()
        weight = Material.svk(E=self.E_s, nu=self.nu_s, rho=self.weight_density(dx))
        W = self.whole
        regions = [m.Region("mortar", self.mortar_shape(dx), self.mortar(dx), body="beam"),
                   m.Region("plate", W(Box((0.0, 0.0, H), (xp, B2, top))), steel, priority=1, body="beam")]
        for name, box, scale, pri in (self.bars(dx) if self.rebar else ()):
            regions.append(m.Region(name, W(box), self.steel(scale), priority=pri, body="beam"))
        regions.append(m.Region("weight", W(Box((0.0, 0.0, zw), (xp, B2, zw + self.weight_height))),
                                weight, body="weight"))
        support = W(Box((L2 - dx, 0.0, -3 * dx), (L2 + dx, B2, -dx)))
        regions.append(m.Region("support", support, steel, held=True, body="support"))
        k = self.contact_stiffness * self.E_s
        sym = ((m.Set("sym_x", Plane(0, 0.0)), m.Set("sym_y", Plane(1, 0.0))) if self.symmetry
               else ())
        return m.Model(
            dim=3, plane=None, length=H, name=self.name, regions=tuple(regions),
            sets=sym + (m.Set("midspan_bottom", Point((0.0, 0.0, 0.0))),
                        m.Set("weight_all", regions[-2].shape, region="weight"),
                        m.Set("support_all", support, region="support")),
            constraints=((m.Roller("sym_x", 0), m.Roller("sym_y", 1)) if self.symmetry else ()),
            loads=(m.InitialVelocity((0.0, 0.0, -self.impact_velocity), regions=("weight",)),),
            contact=(m.Contact(("weight", "beam"), k, dx), m.Contact(("beam", "support"), k, dx)),
            drive=m.Explicit(self.t_end, self.dt_factor, n_out=self.n_out,
                             dt_reference=self.dt_reference),
            observables=(m.Displacement("midspan_w", "midspan_bottom", 2),
                         m.Displacement("weight_w", "weight_all", 2),
                         m.ContactForce("weight_force", "weight", 2),
                         m.ContactForce("support_force", "support", 2),
                         m.Momentum("weight_momentum", "weight", 2),
                         m.Reaction("support_hold", "support_all", 2)),
            notes=(f"003 specimen {self.specimen}: "
                   + ("quarter model (symmetry rollers on x = 0 and y = 0)" if self.symmetry
                      else "the full beam (no symmetry planes)") + "; bars on lattice lines with an equivalent steel (E, sigma_y, H, rho x "
                   "A_bar/A_particles); one-sided supports by contact with held blocks; weight a "
                   "separate body of density mass/(4 V_discretised).",))

    def _beam_model(self, dx: float) -> m.Model:
        """The beam with its rebar alone (mortar, main bar, stirrups; no plate, weight, support
        blocks or contact), hinged along the line x = span/2, z = 0 (held along z: the line of
        contact of a hinge support), symmetry rollers on x = 0 and y = 0; its lowest modes."""
        L2, B2, H = self.span / 2, self.B / 2, self.H
        xe = L2 + self.overhang
        W = self.whole
        regions = [m.Region("mortar", self.mortar_shape(dx), self.mortar(dx), body="beam")]
        for name, box, scale, pri in self.bars(dx):
            regions.append(m.Region(name, W(box), self.steel(scale), priority=pri, body="beam"))
        q = 0.25 * dx
        hinge = W(Box((L2 - q, 0.0, -q), (L2 + q, B2, q)))
        sym = ((m.Set("sym_x", Plane(0, 0.0)), m.Set("sym_y", Plane(1, 0.0))) if self.symmetry
               else ())
        rollers = (m.Roller("sym_x", 0), m.Roller("sym_y", 1)) if self.symmetry else ()
        return m.Model(
            dim=3, plane=None, length=H, name=self.name, regions=tuple(regions),
            sets=sym + (m.Set("hinge", hinge), m.Set("midspan_bottom", Point((0.0, 0.0, 0.0)))),
            constraints=rollers + (m.Roller("hinge", 2),),
            drive=m.Modal(3),
            observables=(m.Displacement("midspan_w", "midspan_bottom", 2),),
            notes=(f"003 specimen {self.specimen}, the beam with its rebar alone on hinges: quarter "
                   "model, lowest modes about the reference state.",))

    def summarise(self, out: dict) -> dict:
        """The full beam's histories (the quarter model's forces × 4, :attr:`copies`): ``midspan_displacement``
        (m, positive downward), ``impact_force`` (N, the plate's push on the weight, at the
        record), ``support_reaction`` (N, both supports together, at the record),
        ``support_reaction_mean`` (N, the force holding the support blocks, its time mean over the
        interval since the previous record: Σ R_k Δt_k is the impulse the supports gave, exactly
        the change of the momentum of weight plus beam along z), ``impact_impulse`` (N s, the
        impulse of the plate's push on the weight since t = 0: the change of the weight's z
        momentum, which carries no other force — exact at any record interval, so that a time
        mean of the impact force over any window is too), and their peaks."""
        import numpy as np

        if "time" not in out or "midspan_w" not in out:
            return {}  # the modal check: periods only
        c = float(self.copies)
        w = -np.asarray(out["midspan_w"], float)
        F = c * np.asarray(out["weight_force"], float)
        R = -c * np.asarray(out["support_force"], float)
        extra = {}
        if "support_hold" in out:
            extra["support_reaction_mean"] = c * np.asarray(out["support_hold"], float)
        if "weight_momentum" in out:
            p = np.asarray(out["weight_momentum"], float)
            extra["impact_impulse"] = c * (p - p[0])
        return dict(midspan_displacement=w, impact_force=F, support_reaction=R, **extra,
                    max_displacement=float(np.nanmax(w)) if w.size else math.nan,
                    max_impact_force=float(np.nanmax(F)) if F.size else math.nan,
                    max_support_reaction=float(np.nanmax(R)) if R.size else math.nan)
