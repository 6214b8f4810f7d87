"""The headline scenes (``../shared/design/scenes.md``): the SS curve, the static cantilever and the
oscillating plate, as parameters (``workbench list``, ``--set``) and as models (regions, sets,
loads, drive, observables) that every method runs."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..materials import Material
import workbench.scenes.model as m
from .params import ParameterError, Scene, param
from .shapes import Box, Plane, Point

# ------------------------------------------------------------------------------------------------
# Headline scenes
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class SSCurve(Scene):
    """Uniaxial tension of a block (000, Table 1, Fig. 1): rollers on the three symmetry faces
    X=0, Y=0, Z=0, lateral faces free, the face X=a moved so that the logarithmic axial strain
    grows to ``max_strain`` (optionally unloaded by ``unload_by`` and reloaded). Homogeneous: a
    handful of particles or elements suffices."""

    name: str = field(default="ss_curve", metadata=dict(hidden=True))
    E: float = param(202e9, "Pa", "Young's modulus", lo=0, lo_open=True)
    nu: float = param(0.3, "-", "Poisson's ratio", lo=-1, hi=0.5, lo_open=True, hi_open=True)
    C: float = param(868.8e6, "Pa", "Swift hardening coefficient", lo=0, lo_open=True)
    eps0: float = param(0.0013, "-", "Swift pre-strain", lo=0, lo_open=True)
    n: float = param(0.179, "-", "Swift exponent", lo=0, hi=1, hi_open=True)
    rho: float = param(7974.0, "kg/m^3", "density", lo=0, lo_open=True)
    eps_L: float = param(math.inf, "-", "damage limit plastic strain (inf: no damage)", lo=0, lo_open=True)
    size: float = param(1e-3, "m", "edge of the cubic block (a)", lo=0, lo_open=True)
    max_strain: float = param(0.3, "-", "final logarithmic axial strain", lo=0, hi=2, lo_open=True)
    n_steps: int = param(60, "-", "load steps past twice the yield strain (4 more before)", lo=1, hi=100000)
    unload: bool = param(False, "-", "add an unload-reload cycle at the end")
    unload_by: float = param(0.003, "-", "log strain removed by the unloading (about the elastic "
                                         "strain at yield: a larger value yields in compression)",
                             lo=0, lo_open=True)

    def check(self):
        if self.unload and not self.unload_by <= self.max_strain:
            raise ParameterError(f"unload_by: {self.unload_by:g} is out of range; allowed: "
                                 f"(0, max_strain={self.max_strain:g}]")

    @property
    def material(self) -> Material:
        return Material.j2(E=self.E, nu=self.nu, C=self.C, eps0=self.eps0, n=self.n,
                           rho=self.rho, eps_L=self.eps_L)

    def strain_path(self):
        """The prescribed logarithmic axial strain at each load step (monotonic, then the optional
        unload–reload cycle), starting after 0."""
        import numpy as np

        # four steps through the elastic range (to twice the yield strain), then uniform steps
        e_y = 2 * self.C * self.eps0 ** self.n / self.E
        if e_y < 0.5 * self.max_strain:
            up = np.concatenate([np.linspace(0, e_y, 5)[1:],
                                 np.linspace(e_y, self.max_strain, self.n_steps + 1)[1:]])
        else:
            up = np.linspace(0, self.max_strain, self.n_steps + 1)[1:]
        if not self.unload:
            return up
        k = max(2, self.n_steps // 6)
        low = self.max_strain - self.unload_by
        down = np.linspace(self.max_strain, low, k + 1)[1:]
        back = np.linspace(low, self.max_strain, k + 1)[1:]
        return np.concatenate([up, down, back])

    def model(self, spacing: float | None = None) -> m.Model:
        """The block [0, a]³: rollers on X=0, Y=0, Z=0 (symmetry planes), the face X=a moved to
        x = a exp(ε) along the strain path (the load parameter ε is the logarithmic axial
        strain); observed: the axial reaction on X=a, the mean positions of the faces Y=a and
        Z=a (the current cross-section) and the mean Cauchy stress σ_xx."""
        a = self.size
        faces = [m.Set(f"{ax}{k}", Plane(i, k * a)) for i, ax in enumerate("xyz") for k in (0, 1)]
        return m.Model(
            dim=3, plane=None, length=a, name=self.name,
            regions=(m.Region("block", Box((0, 0, 0), (a, a, a)), self.material),),
            sets=tuple(faces),
            constraints=(m.Roller("x0", 0), m.Roller("y0", 1), m.Roller("z0", 2),
                         m.Prescribed("x1", 0, displacement=Stretch(a))),
            drive=m.Static(tuple(float(e) for e in self.strain_path()), "strain", "-"),
            observables=(m.Reaction("reaction", "x1", 0), m.Position("y1", "y1", 1),
                         m.Position("z1", "z1", 2), m.MeanStress("sigma_xx", 0, 0)))

    def summarise(self, out: dict) -> dict:
        """``stress``: axial reaction on X=a over the current section (mean lateral face
        positions); ``nominal_stress``: reaction / a²; ``stress_particle_average``: Σ V J σ_xx /
        Σ V J."""
        a = self.size
        R = np.asarray(out["reaction"], dtype=float)
        steps = [str(x) for x in np.atleast_1d(out["status"])]
        status = next((x for x in steps if not x.startswith("ok")), "ok")
        return dict(strain=np.asarray(out["parameter"], dtype=float), status=status,
                    step_status=steps,
                    stress=R / (np.asarray(out["y1"]) * np.asarray(out["z1"])),
                    nominal_stress=R / (a * a),
                    stress_particle_average=np.asarray(out["sigma_xx"], dtype=float),
                    wall_time=float(np.nanmax(out["wall_time"])),
                    stress_measure="axial reaction on X=a over the current section (mean lateral "
                                   "face positions)")


@dataclass(frozen=True)
class Stretch:
    """The displacement a (exp(ε) − 1) of a face at X = a for the logarithmic strain ε."""

    a: float

    def __call__(self, eps):
        return self.a * np.expm1(np.asarray(eps, dtype=float))


@dataclass(frozen=True)
class Cantilever(Scene):
    """Static tip-loaded cantilever (004 E), 2-D. The beam occupies 0 ≤ X ≤ L, −H/2 ≤ Y ≤ H/2 and is
    rigidly clamped at X = 0 (particle methods hold a block of particles behind X = 0 fixed); the tip
    load P (per unit thickness) acts downward (−Y) as a uniform shear traction on the tip face X = L.
    ``loads`` are the dimensionless loads P L²/(E I), I = H³/12; the paper's small load
    P = 0.005 N is first."""

    name: str = field(default="cantilever", metadata=dict(hidden=True))
    L: float = param(0.16, "m", "free length", lo=0, lo_open=True)
    H: float = param(0.02, "m", "thickness", lo=0, lo_open=True)
    E: float = param(1.0e5, "Pa", "Young's modulus", lo=0, lo_open=True)
    nu: float = param(0.3, "-", "Poisson's ratio", lo=-1, hi=0.5, lo_open=True, hi_open=True)
    rho: float = param(1000.0, "kg/m^3", "density (not given by 004: our choice)", lo=0, lo_open=True)
    law: str = param("svk", "-", "hyperelastic law", choices=("svk", "neo_hooke"))
    plane: str = param("strain", "-", "2-D idealisation", choices=("strain", "stress"))
    loads: tuple = param((0.0019200000000000003, 1.0, 2.0, 5.0), "-",
                         "dimensionless tip loads P L^2/(E I)", lo=0, hi=50, lo_open=True)
    clamp_layers: int = param(3, "-", "particle layers behind X = 0 held fixed (particle methods)",
                              lo=1, hi=20)

    def check(self):
        if self.H >= self.L:
            raise ParameterError(f"H: {self.H:g} m is out of range; allowed: (0, L={self.L:g}) m")

    @property
    def material(self) -> Material:
        return Material(law=self.law, E=self.E, nu=self.nu, rho=self.rho).validated()

    @property
    def I(self) -> float:
        return self.H ** 3 / 12.0

    def force(self, load: float) -> float:
        """Tip force per unit thickness, N/m, for a dimensionless load P L²/(E I)."""
        return load * self.E * self.I / self.L ** 2

    def model(self, spacing: float | None = None) -> m.Model:
        """The beam [0, L] × [−H/2, H/2] and, behind it, a held block of ``clamp_layers``
        particle spacings (the particle methods' clamp; the FEM clamps X = 0). The tip load is a
        dead uniform shear traction −P/H on X = L, proportional to the load parameter P L²/(E I);
        observed: the displacement of the tip mid-point (L, 0)."""
        L, H = self.L, self.H
        dx = H / 10 if spacing is None else spacing
        back = self.clamp_layers * dx
        return m.Model(
            dim=2, plane=self.plane, length=H, name=self.name,
            regions=(m.Region("clamp", Box((-back, -H / 2), (0.0, H / 2)), self.material,
                              priority=1, held=True),
                     m.Region("beam", Box((0.0, -H / 2), (L, H / 2)), self.material)),
            sets=(m.Set("tip", Plane(0, L)), m.Set("tip_mid", Point((L, 0.0)))),
            loads=(m.Traction("tip", (0.0, -self.force(1.0) / H), scale=m.Proportional(1.0)),),
            drive=m.Static(tuple(float(p) for p in self.loads), "load", "-"),
            observables=(m.Displacement("tip_y", "tip_mid", 1),
                         m.Displacement("tip_x", "tip_mid", 0)))

    def summarise(self, out: dict) -> dict:
        """``tip_deflection`` (m, positive downward) and ``tip_horizontal`` (m, shortening)."""
        return dict(load=np.asarray(out["parameter"], dtype=float),
                    tip_deflection=-np.asarray(out["tip_y"], dtype=float),
                    tip_horizontal=-np.asarray(out["tip_x"], dtype=float))


@dataclass(frozen=True)
class Plate(Scene):
    """Oscillating cantilever plate (004 D, Table I; Gray, Monaghan & Swift 2001), plane strain.
    Free length L from the clamp (X = 0) with a further ``clamp_length`` behind it held rigidly
    fixed (particle methods fix those particles; the FEM clamps X = 0 rigidly: the same clamp).
    Initial velocity v_y(X) = V_f c0 f(X)/f(L) with Gray et al.'s mode shape f (scenes.md)."""

    name: str = field(default="plate", metadata=dict(hidden=True))
    L: float = param(0.2, "m", "free length", lo=0, lo_open=True)
    clamp_length: float = param(0.04, "m", "clamped length behind X = 0", lo=0, lo_open=True)
    H: float = param(0.02, "m", "thickness", lo=0, lo_open=True)
    K: float = param(3.25e6, "Pa", "bulk modulus", lo=0, lo_open=True)
    G: float = param(7.15e5, "Pa", "shear modulus", lo=0, lo_open=True)
    rho: float = param(1000.0, "kg/m^3", "density", lo=0, lo_open=True)
    law: str = param("svk", "-", "hyperelastic law", choices=("svk", "neo_hooke"))
    V_f: float = param(0.01, "-", "tip velocity over c0", lo=0, hi=1, lo_open=True)
    kL: float = param(1.875104068711961, "-", "first root of cos kL cosh kL = -1", lo=0, lo_open=True)
    periods: float = param(2.0, "-", "simulated time in thin-plate periods", lo=0, hi=1000, lo_open=True)
    dt_factor: float = param(0.3, "-", "time step over the CFL estimate", lo=0, hi=10, lo_open=True)

    def check(self):
        if self.H >= self.L:
            raise ParameterError(f"H: {self.H:g} m is out of range; allowed: (0, L={self.L:g}) m")
        if self.K <= 2 * self.G / 3:
            raise ParameterError(f"K: {self.K:g} Pa gives nu <= 0 here; allowed: K > 2G/3")

    @property
    def material(self) -> Material:
        return Material.from_bulk_shear(self.law, K=self.K, G=self.G, rho=self.rho)

    @property
    def c0(self) -> float:
        return math.sqrt(self.K / self.rho)

    def model(self, spacing: float | None = None) -> m.Model:
        """The plate [0, L] × [−H/2, H/2] and the held clamp block behind X = 0 (its length
        rounded to whole spacings, at least one), the initial velocity of eq. 13 in the plate,
        explicit dynamics over ``periods`` thin-plate periods; observed: the vertical
        displacement of the tip mid-point (L, 0) and its period and amplitude."""
        from .. import analytic

        L, H = self.L, self.H
        dx = H / 10 if spacing is None else spacing
        back = max(round(self.clamp_length / dx), 1) * dx
        return m.Model(
            dim=2, plane="strain", length=H, name=self.name,
            regions=(m.Region("clamp", Box((-back, -H / 2), (0.0, H / 2)), self.material,
                              priority=1, held=True),
                     m.Region("plate", Box((0.0, -H / 2), (L, H / 2)), self.material)),
            sets=(m.Set("tip", Point((L, 0.0))),),
            loads=(m.InitialVelocity(PlateVelocity(self), regions=("plate",)),),
            drive=m.Explicit(self.periods * analytic.plate_period(self), self.dt_factor),
            observables=(m.Displacement("tip", "tip", 1), m.Period("period", "tip")))

    def summarise(self, out: dict) -> dict:
        """``period`` (s) and ``amplitude`` (m) of the tip, its history ``tip_displacement``."""
        return dict(period=out.get("period", math.nan), amplitude=out.get("period_amplitude", math.nan),
                    time=np.asarray(out.get("time", ())), tip_displacement=np.asarray(out.get("tip", ())))


@dataclass(frozen=True)
class PlateVelocity:
    """v(X) = (0, V_f c0 f(X)/f(L)) of 004 eq. 13 (zero behind the clamp)."""

    scene: Plate

    def __call__(self, X):
        from .. import analytic

        v = np.zeros_like(X)
        v[:, 1] = analytic.plate_initial_velocity(self.scene, X[:, 0])
        return v



