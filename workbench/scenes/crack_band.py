"""A mortar bar pulled apart: the crack-band regularisation of 003 eq. 5 (issue 12 gate 6).

Softening with a fixed release strain ε_0 is mesh-dependent (Bažant & Oh 1983; Bažant &
Belytschko 1985): the crack localises into a band a fixed number of particles wide, so the energy
released per unit crack area is g_F · (band width) = ½ f_t ε_0 · n Δx and goes to zero with the
spacing Δx. 003 eq. 5 ties the release strain to the particle size, ε_0(Δx) = 2 G_F/(f_t Δx)
(:func:`workbench.materials.mortar.release_strain`; :meth:`RCBeam.release_strain` scales the
paper's 17 000 µ at 5 mm by 5 mm/Δx), and then the energy per crack area is n G_F whatever the
spacing. This scene measures it (tests/test_crack_band.py).

The bar (2-D, plane strain, or 3-D with ``dim`` = 3: |Z| ≤ B/2 too): −L/2 ≤ X ≤ L/2, |Y| ≤ B/2, of
the mortar of :class:`RCBeam` (E, f_t,
f_c of 003 Table 1; the release strain ``eps_release`` at 5 mm, scaled to the spacing with
``scale_release``) with ν = 0 by default, so that every particle of the band follows the law's
uniaxial curve σ = f_t(ε_0 − ε)/(ε_0 − ε_cr), of area g_F = ½ f_t ε_0, whatever the band's lateral
constraint. (With ν > 0 the band, held laterally by the bulk, lies between uniaxial stress and
uniaxial strain: its area between g_F and (1 − ν)/((1 + ν)(1 − 2ν)) g_F, +14 % at ν = 0.22;
measured +5.6 % with csph.) Where the crack forms:

* a **weak section**: ``weak_columns`` lattice columns from the node nearest to the middle have the
  tensile strength ``weak`` · f_t and the same fracture energy G_F(Δx) (so every released layer
  releases G_F(Δx)): the crack localises there;
* **grips**: the bar's ends, |X| ≥ L/2 − ``grip``, are the same material without softening (Saint
  Venant–Kirchhoff, same E and ν), so the loaded ends do not crack.

Loading: the end faces move apart along X at ``rate`` (m/s, the opening rate: ±rate/2 each, held
along Y), from the velocity field of uniform stretching at that rate (v_x = rate · X/L at t = 0):
the elastic phase is then exactly quasi-static (a linear velocity field at constant stretch rate
has no acceleration: no wave is sent in), whatever the rate; after the peak the bulk unloads and
the halves move apart. The run ends at the opening ``opening`` · ε_0(Δx) Δx past the elastic
stretch ε_cr L. The rate 0.05 m/s is quasi-static for the softening branch too (half of it gives
the same released energy to 1e-4, csph 2.5 mm); at 0.1 m/s the band's last stage releases fast
enough to crack a second section.

What a particle method makes of it (measured, csph and classic SPH): **the band is two lattice
columns wide**, whatever the spacing and whether the weak section is one column or two. A
particle's deformation gradient is formed from its neighbours' positions, not its own (on a lattice
Σ_b G_ab = 0 and the stencil is central-difference-like), so a displacement jump between two
columns is seen by both, each with a strain of about the jump over 2 Δx; they release together at
the opening 2 ε_0 Δx. So the energy released per crack area is 2 G_F(Δx), not eq. 5's G_F (which
assumes a band one particle wide): spacing-independent with ``scale_release``, but twice the
G_F that 003's 17 000 µ at 5 mm intends (68.4 J/m²). To release G_F per crack area a particle
method would take eq. 5 with the band width 2 Δx, ε_0 = G_F/(f_t Δx).

Measured at 5, 3.33 and 2.5 mm (B = 20 mm; energy released per crack area at the opening 3 ε_0 Δx
(csph) or 5 ε_0 Δx (classic SPH), over G_F): csph with nodal integration (as the RC beam study runs
it) 1.9997 at all three, in 2-D and in 3-D (``dim`` = 3, 5 and 3.33 mm: 1.9996, 1.9997) — exactly
the two columns, nothing beside them; the integration-consistent csph 2.061 / 2.045 / 2.036 (the
columns beside the band keep 2–4 % partial damage); classic SPH (hyperelastic stress) 2.132 /
2.101 / 2.073 (its Eulerian kernel, support 2.6 Δx, partly damages the free-surface particles
beside the band, while the band's own free-surface particles stop at damage ~0.99). Without
``scale_release`` the same multiples of G_F(Δx) ∝ Δx: csph 136.8 / 91.2 / 68.4 J/m².

The released energy is path-independent: the mortar's released energy per unit volume is a
function of its damage alone (the stiffness lost), g_F for a fully released particle in uniaxial
stress (:mod:`workbench.materials.mortar`; plus the midpoint rule's E Δε²/8 for Δε the strain
increment of one time step). So the energy released per crack area B (per unit thickness) over
G_F(Δx) counts the particle layers the crack consumed (:func:`crack_band`).

The same bar of the **brittle law** (``law='brittle'``, :meth:`Material.brittle`, issue 41): the
fracture energy ``G_c`` is a material constant and the law spreads it over the method's band,
2 Δx (:data:`workbench.materials.brittle.PARTICLE_BAND`), so the energy released per crack area
should be G_c itself at every spacing (tests/test_crack_band.py, docs/fracture.md).

Observed: ``force`` (N/m, the reaction on the right end, the time mean over each record
interval), ``opening`` (m, the right end's displacement; the left end's is its negative).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

import workbench.scenes.model as m

from ..materials import Material
from ..materials.brittle import PARTICLE_BAND, band_constants
from ..materials.mortar import fracture_energy
from ..materials.mortar_constants import PAPER_SPACING
from .params import ParameterError, Scene, param
from .shapes import Box, Plane


@dataclass(frozen=True)
class MortarBar(Scene):
    """A 2-D mortar bar with a weak section, pulled apart to full separation (module docstring).
    Resolution r: r particles across B (spacing B/r)."""

    name: str = field(default="mortar_bar", metadata=dict(hidden=True))
    dim: int = param(2, "-", "2 (plane strain, B high) or 3 (a square section B x B)",
                     choices=(2, 3))
    law: str = param("mortar", "-", "the softening law: 003's mortar (release strain by eq. 5) or "
                     "the brittle law (Material.brittle, G_c over the method's band)",
                     choices=("mortar", "brittle"))
    G_c: float = param(68.4, "J/m^2", "fracture energy of the brittle law (68.4: 003's mortar, "
                       "1.61 MPa x 17 000 µ x 5 mm / 2)", lo=0, lo_open=True)
    L: float = param(0.05, "m", "length (grips included)", lo=0, lo_open=True, hi=10)
    B: float = param(0.02, "m", "height (and width in 3-D): the crack's area is B (per unit "
                     "thickness) or B^2", lo=0, lo_open=True, hi=10)
    grip: float = param(0.005, "m", "length of each elastic grip at the ends", lo=0, hi=5)
    E: float = param(11.9e9, "Pa", "Young's modulus (003 Table 1)", lo=0, lo_open=True)
    nu: float = param(0.0, "-", "Poisson's ratio (0: uniaxial softening curve in the band)",
                      lo=-1, hi=0.5, lo_open=True, hi_open=True)
    f_t: float = param(1.61e6, "Pa", "tensile strength (003 Table 1)", lo=0, lo_open=True)
    f_c: float = param(16.1e6, "Pa", "compressive strength (003 Table 1)", lo=0, lo_open=True)
    rho: float = param(2200.0, "kg/m^3", "density", lo=0, lo_open=True)
    eps_release: float = param(0.017, "-", "release strain at 5 mm spacing (003 4.1)", lo=0,
                               lo_open=True)
    scale_release: bool = param(True, "-", "release strain x 5 mm/spacing (eq. 5, G_F fixed)")
    weak: float = param(0.9, "-", "tensile strength of the weak section over f_t", lo=0,
                        hi=1, lo_open=True)
    weak_columns: int = param(2, "-", "lattice columns of the weak section (the particle methods' "
                              "narrowest crack band is two: see the module docstring)", lo=1, hi=10)
    rate: float = param(0.05, "m/s", "opening rate of the ends", lo=0, lo_open=True, hi=10)
    opening: float = param(3.0, "-", "final opening past the elastic stretch, over eps_0(dx) dx",
                           lo=0, lo_open=True, hi=1000)
    dt_factor: float = param(0.5, "-", "time step over the CFL estimate", lo=0, hi=10,
                             lo_open=True)
    n_out: int = param(100, "-", "records over the run", lo=1)

    def check(self):
        if not 2 * self.grip < self.L:
            raise ParameterError(f"grip: {self.grip:g} m is out of range; allowed: [0, L/2="
                                 f"{self.L / 2:g}) m")
        self.mortar(self.B / 2)  # the strengths and the release strain (ParameterError)

    # -- the law at a spacing -----------------------------------------------------------------
    def release_strain(self, dx: float) -> float:
        """ε_0 at spacing dx: ``eps_release`` · 5 mm/dx with ``scale_release`` (eq. 5), else
        ``eps_release`` (as :meth:`RCBeam.release_strain`); the brittle law: its ε_f at the
        particle methods' band 2 dx (:func:`workbench.materials.brittle.band_constants`)."""
        if self.law == "brittle":
            return band_constants(self.E, self.f_t, self.G_c, PARTICLE_BAND * dx)[2]
        return self.eps_release * (PAPER_SPACING / dx if self.scale_release else 1.0)

    def fracture_energy(self, dx: float) -> float:
        """G_F(dx) = ½ f_t ε_0(dx) dx, J/m² (:func:`workbench.materials.mortar.fracture_energy`):
        the energy per crack area of a band one particle wide. With ``scale_release`` the same at
        every spacing (68.4 J/m² for 003's mortar). The brittle law: ``G_c``, the energy per
        crack area it is built to release (whatever the band)."""
        if self.law == "brittle":
            return self.G_c
        return fracture_energy(self.f_t, self.release_strain(dx), dx)

    def mortar(self, dx: float, strength: float = 1.0) -> Material:
        """The mortar at spacing dx with the tensile strength ``strength`` · f_t and the fracture
        energy G_F(dx) (:meth:`fracture_energy`; ε_0 = 2 G_F(dx)/(strength f_t dx), eq. 5): the
        weak section differs in strength only, so every released layer releases G_F(dx). With
        ``law='brittle'``: the brittle law of that strength and ``G_c`` (its band is the
        method's)."""
        f_t = strength * self.f_t
        if self.law == "brittle":
            try:
                return Material.brittle(E=self.E, nu=self.nu, f_t=f_t, G_c=self.G_c, rho=self.rho)
            except ValueError as err:
                raise ParameterError(str(err)) from None
        eps0 = 2.0 * self.fracture_energy(dx) / (f_t * dx)
        try:
            return Material.mortar(E=self.E, nu=self.nu, f_t=f_t, f_c=self.f_c, eps_release=eps0,
                                   rho=self.rho)
        except ValueError as err:
            raise ParameterError(str(err)) from None

    def weak_section(self, dx: float) -> float:
        """X of the weak section's first lattice column, m: the lattice node nearest to the middle
        (the lattice is anchored at X = −L/2)."""
        return -0.5 * self.L + dx * math.floor(0.5 * self.L / dx + 1e-9)

    def duration(self, dx: float) -> float:
        """The run's end time, s: the elastic stretch ε_cr L plus ``opening`` ε_0(dx) dx, at
        ``rate``."""
        u0 = self.release_strain(dx) * dx
        return (self.f_t / self.E * self.L + self.opening * u0) / self.rate

    # -- the model ----------------------------------------------------------------------------
    @property
    def area(self) -> float:
        """The crack's area, the section: B (m² per m of thickness) in 2-D, B² in 3-D."""
        return self.B if self.dim == 2 else self.B * self.B

    def model(self, spacing: float | None = None) -> m.Model:
        dx = self.B / 4 if spacing is None else spacing
        L2, B2, d = self.L / 2, self.B / 2, self.dim
        cross = (B2,) * (d - 1)

        def box(x0, x1):  # the bar between X = x0 and x1
            return Box((x0,) + tuple(-c for c in cross), (x1,) + cross)

        grip = Material.svk(E=self.E, nu=self.nu, rho=self.rho)
        x0 = self.weak_section(dx)
        x1 = x0 + (self.weak_columns - 0.75) * dx
        regions = [m.Region("weak", box(x0 - 0.25 * dx, x1), self.mortar(dx, self.weak),
                            priority=2),
                   m.Region("bar", box(-L2, L2), self.mortar(dx))]
        if self.grip > 0:
            g = L2 - self.grip
            regions += [m.Region("grip_left", box(-L2, -g), grip, priority=1),
                        m.Region("grip_right", box(g, L2), grip, priority=1)]
        rate, L = self.rate, self.L

        def stretching(X):  # uniform stretching at the opening rate
            v = np.zeros((len(X), d))
            v[:, 0] = rate * X[:, 0] / L
            return v

        held = tuple(m.Roller(end, k) for end in ("left", "right") for k in range(1, d))
        return m.Model(
            dim=d, plane="strain" if d == 2 else None, length=self.B, name=self.name,
            regions=tuple(regions),
            sets=(m.Set("left", Plane(0, -L2)), m.Set("right", Plane(0, L2))),
            constraints=(m.Prescribed("left", 0, velocity=-0.5 * rate),
                         m.Prescribed("right", 0, velocity=0.5 * rate)) + held,
            loads=(m.InitialVelocity(stretching),),
            drive=m.Explicit(self.duration(dx), self.dt_factor, n_out=self.n_out),
            observables=(m.Reaction("force", "right", 0), m.Displacement("opening", "right", 0)),
            notes=("mortar bar pulled apart: a weak section in the middle, elastic grips, ends "
                   "moving apart at the opening rate from uniform stretching",))
