"""The stability scenes of scenes.md (004 A–C): where particle methods fail. Frozen dataclasses on
the pattern of :mod:`workbench.scenes` (``param`` fields with units and allowed ranges).

Choices where the papers are silent are ours and are stated in each docstring.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..materials import Material
import workbench.scenes.model as m
from .params import ParameterError, Scene, param
from .shapes import Box, Cylinder


@dataclass(frozen=True)
class Ring(Scene):
    """Rubber ring under internal pressure (004 A; Rabczuk, Belytschko & Xiao 2004), plane strain.

    Ring rubber: the Mooney–Rivlin-like law of 004 eq. 12. A dead radial pressure ``pressure`` acts
    on the inner circumference from t = 0 (applied as equal radial forces p·2πR_in/n on the innermost
    particle layer, in the reference radial direction). The papers give no radii: we take
    R_in = 0.1 m, R_out = 0.2 m (about 2100 particles at 15 across the wall, 004 has 2201). A
    thinner ring (R_out = 0.15 m) inflates without bound under the suddenly applied pressure (the
    dynamic overshoot passes the inflation limit point), which tests nothing about the kernels.
    Particles lie on concentric circles (the "cylindrical arrangement" of 004).
    """

    name: str = field(default="ring", metadata=dict(hidden=True))
    R_in: float = param(0.10, "m", "inner radius", lo=0, lo_open=True)
    R_out: float = param(0.20, "m", "outer radius", lo=0, lo_open=True)
    pressure: float = param(6.2e4, "Pa", "radial pressure on the inner circumference", lo=0)
    c1: float = param(1.265e5, "Pa", "Mooney-Rivlin c1 (004 eq. 12)", lo=0)
    c2: float = param(1.012e4, "Pa", "Mooney-Rivlin c2 (004 eq. 12)", lo=0)
    lam: float = param(1.012e7, "Pa", "lambda of 004 eq. 12", lo=0, lo_open=True)
    rho: float = param(125.4, "kg/m^3", "density", lo=0, lo_open=True)
    t_end: float = param(5.0, "s", "simulated time", lo=0, lo_open=True)
    dt_factor: float = param(0.3, "-", "time step over the CFL estimate", lo=0, hi=10, lo_open=True)

    def check(self):
        if not self.R_out > self.R_in:
            raise ParameterError(f"R_out: {self.R_out:g} m is out of range; allowed: (R_in={self.R_in:g}, inf) m")
        if not self.c1 + self.c2 > 0:
            raise ParameterError("c1, c2: must be >= 0 with c1 + c2 > 0")

    @property
    def material(self) -> Material:
        return Material.mooney_rivlin(c1=self.c1, c2=self.c2, lam=self.lam, rho=self.rho)

    def model(self, spacing: float | None = None) -> m.Model:
        """The ring on concentric circles; the pressure on its inner surface acts on the innermost
        layer (its boundary area vectors); explicit dynamics with the stability monitor."""
        dr = (self.R_out - self.R_in) / 15 if spacing is None else spacing
        ring = Cylinder((0.0, 0.0), self.R_out, inner=self.R_in)
        return m.Model(
            dim=2, plane="strain", length=self.R_out - self.R_in, name=self.name,
            regions=(m.Region("ring", ring, self.material, arrangement="concentric"),),
            sets=(m.Set("inner", Cylinder((0.0, 0.0), self.R_in + dr, inner=self.R_in)),),
            loads=(m.Pressure("inner", self.pressure),),
            drive=_monitored(self))


@dataclass(frozen=True)
class Slab(Scene):
    """Slab in pure tension (004 B), plane strain, SVK rubber (K, G, ρ = 1000).

    ``length`` × ``height`` (3 cm × 1 cm). The particles in the end strips of width ``strip``
    (0.2 cm) are driven apart kinematically: their x velocity is ±``accel``·min(t, ``t_load``). We
    read 004's "acceleration of 0.5 m/s² to the particles within 0.2 cm strips for 1 s" this way
    because as a body force it would stress the slab by about 1 Pa (ρ·strip·a), nothing that could
    be seen; kinematically the free part is stretched by ~1.3 at the default t_end = 0.15 s and by
    ~5 at 004's t = 0.5 s. Beyond a stretch of ~1.6 the SVK law itself fails in the necking strip
    corners (J → 0 under lateral compression: SVK softens in compression), whatever the
    discretisation, so the default end time stays below it.
    """

    name: str = field(default="slab", metadata=dict(hidden=True))
    length: float = param(0.03, "m", "slab length", lo=0, lo_open=True)
    height: float = param(0.01, "m", "slab height", lo=0, lo_open=True)
    strip: float = param(0.002, "m", "width of the driven end strips", lo=0, lo_open=True)
    accel: float = param(0.5, "m/s^2", "acceleration of the end strips (each outward)", lo=0)
    t_load: float = param(1.0, "s", "duration of the acceleration", lo=0)
    K: float = param(3.25e6, "Pa", "bulk modulus", lo=0, lo_open=True)
    G: float = param(7.15e5, "Pa", "shear modulus", lo=0, lo_open=True)
    rho: float = param(1000.0, "kg/m^3", "density", lo=0, lo_open=True)
    t_end: float = param(0.15, "s", "simulated time (004 Fig. 2 shows t = 0.5 s; see the docstring)", lo=0, lo_open=True)
    dt_factor: float = param(0.3, "-", "time step over the CFL estimate", lo=0, hi=10, lo_open=True)

    def check(self):
        if not 2 * self.strip < self.length:
            raise ParameterError(f"strip: {self.strip:g} m is out of range; allowed: (0, length/2) m")

    @property
    def material(self) -> Material:
        return Material.from_bulk_shear("svk", K=self.K, G=self.G, rho=self.rho)

    def model(self, spacing: float | None = None) -> m.Model:
        """The slab on a cell lattice; the end strips move outward at ±accel·min(t, t_load)
        (prescribed x velocity); the disorder is measured away from the strips (more than
        2 r_e = 4.2 spacings from them: the strain jump at a strip edge is not disorder). The
        energy criterion is off: the kinematic drive does work the balance does not count."""
        dx = self.height / 10 if spacing is None else spacing
        L, Hs, w = self.length, self.height, self.strip
        v = m.Table((0.0, self.t_load), (0.0, self.accel * self.t_load))
        vneg = m.Table((0.0, self.t_load), (0.0, -self.accel * self.t_load))
        lo, hi = w + 4.2 * dx, L - w - 4.2 * dx
        return m.Model(
            dim=2, plane="strain", length=Hs, lattice="cell", name=self.name,
            regions=(m.Region("slab", Box((0.0, 0.0), (L, Hs)), self.material),),
            sets=(m.Set("left", Box((0.0, 0.0), (w, Hs))), m.Set("right", Box((L - w, 0.0), (L, Hs))),
                  m.Set("interior", Box((lo, 0.0), (max(hi, lo + dx), Hs)))),
            constraints=(m.Prescribed("left", 0, velocity=vneg), m.Prescribed("right", 0, velocity=v)),
            drive=_monitored(self, energy=False, disorder_set="interior"))


@dataclass(frozen=True)
class Rings(Scene):
    """Two colliding rubber rings (004 C; Gray, Monaghan & Swift 2001), plane strain, SVK rubber.

    Inner and outer radii 0.03 m and 0.04 m (scenes.md; 004 prints cm), each ring moving towards
    the other at ``speed``; initial gap ``gap`` between the outer surfaces. The bodies meet only
    through the particle contact of :mod:`sph.contact` (a pairwise penalty, momentum conserving).
    """

    name: str = field(default="rings", metadata=dict(hidden=True))
    R_in: float = param(0.03, "m", "inner radius", lo=0, lo_open=True)
    R_out: float = param(0.04, "m", "outer radius", lo=0, lo_open=True)
    speed: float = param(0.2, "m/s", "speed of each ring towards the other", lo=0)
    gap: float = param(0.002, "m", "initial gap between the rings", lo=0, lo_open=True)
    K: float = param(3.25e6, "Pa", "bulk modulus", lo=0, lo_open=True)
    G: float = param(7.15e5, "Pa", "shear modulus", lo=0, lo_open=True)
    rho: float = param(1000.0, "kg/m^3", "density", lo=0, lo_open=True)
    contact_stiffness: float = param(1.0, "-", "penalty stiffness over the P-wave modulus", lo=0, lo_open=True, hi=100)
    t_end: float = param(0.1, "s", "simulated time", lo=0, lo_open=True)
    dt_factor: float = param(0.3, "-", "time step over the CFL estimate", lo=0, hi=10, lo_open=True)

    def check(self):
        if not self.R_out > self.R_in:
            raise ParameterError(f"R_out: {self.R_out:g} m is out of range; allowed: (R_in={self.R_in:g}, inf) m")

    @property
    def material(self) -> Material:
        return Material.from_bulk_shear("svk", K=self.K, G=self.G, rho=self.rho)

    def model(self, spacing: float | None = None) -> m.Model:
        """Two rings (bodies 'left' and 'right') on concentric circles, each moving towards the
        other; contact between them at the particle spacing with the penalty stiffness
        ``contact_stiffness`` × (λ + 2μ); observed: the mean x displacement of the left ring."""
        dr = (self.R_out - self.R_in) / 10 if spacing is None else spacing
        c = self.R_out + self.gap / 2
        mat = self.material
        rings = []
        for name, x, u in (("left", -c, self.speed), ("right", c, -self.speed)):
            rings.append(m.Region(name, Cylinder((x, 0.0), self.R_out, inner=self.R_in), mat,
                                  body=name, arrangement="concentric"))
        return m.Model(
            dim=2, plane="strain", length=self.R_out - self.R_in, name=self.name,
            regions=tuple(rings),
            sets=(m.Set("left_ring", rings[0].shape, region="left"),),
            observables=(m.Displacement("left_u", "left_ring", 0),),
            loads=(m.InitialVelocity((self.speed, 0.0), regions=("left",)),
                   m.InitialVelocity((-self.speed, 0.0), regions=("right",))),
            contact=(m.Contact(("left", "right"), self.contact_stiffness * (mat.lam + 2 * mat.mu), dr),),
            drive=_monitored(self))


ENERGY_TOL = 0.5
"""Energy criterion of the stability scenes: the balance grown by more than half the largest
energy seen."""
DISORDER_TOL = 0.15
"""Disorder criterion: η₉₅ above 0.15 (see :mod:`sph.monitor`)."""
N_OUT = 100


def _monitored(scene, energy: bool = True, disorder_set=None) -> m.Explicit:
    """The explicit drive of a stability scene: its end time and time-step factor, the energy
    criterion (unless off) and the disorder criterion."""
    return m.Explicit(scene.t_end, scene.dt_factor, n_out=N_OUT,
                      energy_growth=ENERGY_TOL if energy else None, disorder=DISORDER_TOL,
                      disorder_set=disorder_set)



