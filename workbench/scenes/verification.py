"""Verification scenes written only with the scene API (:mod:`workbench.scenes.model`): each has an
exact or classical answer every method is checked against (tests/test_scene_api.py), and each runs
with ``workbench run`` through the generic scene study.

- :class:`Cantilever3D` — a 3-D cantilever of rectangular section under a tip shear load: at small
  load, Timoshenko beam theory δ = P L³/(3 E I) + P L/(κ G A);
- :class:`BiMaterialBar` — two materials in series, stretched between rollers (uniaxial strain):
  the reaction is the series spring's, F = A u / (L₁/M₁ + L₂/M₂), M = λ + 2μ the P-wave modulus.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

import workbench.scenes.model as m

from ..materials import Material
from .params import ParameterError, Scene, param
from .shapes import Box, Plane, Point


@dataclass(frozen=True)
class Cantilever3D(Scene):
    """A 3-D cantilever 0 ≤ X ≤ L, |Y| ≤ B/2, |Z| ≤ H/2, clamped at X = 0 (the particle methods hold
    ``clamp_layers`` particle layers behind it, the FEM clamps the face), under a dead uniform
    shear traction −P/(B H) e_z on the tip face X = L, P proportional to the load parameter
    P L²/(E I), I = B H³/12; SVK. Observed: the vertical displacement of the tip centre."""

    name: str = field(default="cantilever3d", metadata=dict(hidden=True))
    L: float = param(0.16, "m", "length", lo=0, lo_open=True)
    B: float = param(0.02, "m", "width", lo=0, lo_open=True)
    H: float = param(0.02, "m", "height", lo=0, lo_open=True)
    E: float = param(1.0e5, "Pa", "Young's modulus", lo=0, lo_open=True)
    nu: float = param(0.3, "-", "Poisson's ratio", lo=-1, hi=0.5, lo_open=True, hi_open=True)
    rho: float = param(1000.0, "kg/m^3", "density", lo=0, lo_open=True)
    loads: tuple = param((0.01,), "-", "dimensionless tip loads P L^2/(E I)", lo=0, hi=50, lo_open=True)
    clamp_layers: int = param(3, "-", "particle layers behind X = 0 held (particle methods)", lo=1, hi=20)

    def check(self):
        if not (self.H < self.L and self.B < self.L):
            raise ParameterError(f"H, B: {self.H:g}, {self.B:g} m are out of range; allowed: (0, L={self.L:g}) m")

    @property
    def material(self) -> Material:
        return Material.svk(E=self.E, nu=self.nu, rho=self.rho)

    @property
    def I(self) -> float:
        return self.B * self.H ** 3 / 12.0

    def force(self, load: float) -> float:
        """Tip force, N, for a dimensionless load P L²/(E I)."""
        return load * self.E * self.I / self.L ** 2

    def timoshenko(self, load: float) -> float:
        """δ = P L³/(3 E I) + P L/(κ G A), κ = 10(1+ν)/(12+11ν) (Cowper 1966, rectangular section)."""
        P = self.force(load)
        G = self.E / (2 * (1 + self.nu))
        kappa = 10 * (1 + self.nu) / (12 + 11 * self.nu)
        return P * self.L ** 3 / (3 * self.E * self.I) + P * self.L / (kappa * G * self.B * self.H)

    def model(self, spacing: float | None = None) -> m.Model:
        L, B, H = self.L, self.B, self.H
        dx = H / 4 if spacing is None else spacing
        back = self.clamp_layers * dx
        return m.Model(
            dim=3, plane=None, length=H, name=self.name,
            regions=(m.Region("clamp", Box((-back, -B / 2, -H / 2), (0.0, B / 2, H / 2)),
                              self.material, priority=1, held=True),
                     m.Region("beam", Box((0.0, -B / 2, -H / 2), (L, B / 2, H / 2)), self.material)),
            sets=(m.Set("tip", Plane(0, L)), m.Set("tip_centre", Point((L, 0.0, 0.0)))),
            loads=(m.Traction("tip", (0.0, 0.0, -self.force(1.0) / (B * H)), scale=m.Proportional()),),
            drive=m.Static(tuple(float(p) for p in self.loads), "load", "-"),
            observables=(m.Displacement("tip_w", "tip_centre", 2),))

    def summarise(self, out: dict) -> dict:
        """``tip_deflection`` (m, positive downward) and ``timoshenko`` (m) at each load."""
        loads = np.asarray(out["parameter"], float)
        return dict(tip_deflection=-np.asarray(out["tip_w"], float),
                    timoshenko=np.array([self.timoshenko(p) for p in loads]))


@dataclass(frozen=True)
class BiMaterialBar(Scene):
    """A bar [0, L] × [0, H] (× [0, H] in 3-D) of two materials in series — E1 for X < ``split`` L,
    E2 beyond — with rollers on X = 0 and on the lateral faces (uniaxial strain), the face X = L
    moved by ``strain`` L. The exact reaction is the series spring's:
    F = A u / (L₁/M₁ + L₂/M₂), M = E(1−ν)/((1+ν)(1−2ν)), at small strain (SVK)."""

    name: str = field(default="bimaterial_bar", metadata=dict(hidden=True))
    dim: int = param(2, "-", "dimension (2: plane strain, or 3)", choices=(2, 3))
    L: float = param(0.1, "m", "length", lo=0, lo_open=True)
    H: float = param(0.02, "m", "height (and width in 3-D)", lo=0, lo_open=True)
    E1: float = param(2.0e5, "Pa", "Young's modulus of the first part", lo=0, lo_open=True)
    E2: float = param(1.0e5, "Pa", "Young's modulus of the second part", lo=0, lo_open=True)
    nu: float = param(0.3, "-", "Poisson's ratio of both", lo=-1, hi=0.5, lo_open=True, hi_open=True)
    split: float = param(0.5, "-", "position of the interface over L", lo=0, hi=1, lo_open=True, hi_open=True)
    strain: float = param(1e-6, "-", "imposed mean axial strain", lo=0, hi=0.1, lo_open=True)

    def materials(self) -> tuple[Material, Material]:
        return (Material.svk(E=self.E1, nu=self.nu), Material.svk(E=self.E2, nu=self.nu))

    def exact_reaction(self) -> float:
        """The series spring's reaction on X = L, N (N/m in 2-D), at small strain."""
        M = [mt.lam + 2 * mt.mu for mt in self.materials()]
        L1, L2 = self.split * self.L, (1 - self.split) * self.L
        area = self.H ** (self.dim - 1)
        return area * self.strain * self.L / (L1 / M[0] + L2 / M[1])

    def model(self, spacing: float | None = None) -> m.Model:
        L, H, d = self.L, self.H, self.dim
        hi = (L,) + (H,) * (d - 1)
        xs = self.split * L
        m1, m2 = self.materials()
        lateral = [m.Set(f"{ax}{k}", Plane(i, k * H)) for i, ax in list(enumerate("xyz"))[1:d] for k in (0, 1)]
        return m.Model(
            dim=d, plane="strain" if d == 2 else None, length=H, name=self.name,
            regions=(m.Region("part1", Box((0.0,) * d, (xs,) + hi[1:]), m1, priority=1),
                     m.Region("part2", Box((xs,) + (0.0,) * (d - 1), hi), m2)),
            sets=(m.Set("x0", Plane(0, 0.0)), m.Set("x1", Plane(0, L)), *lateral),
            constraints=(m.Roller("x0", 0),
                         *[m.Roller(s.name, "xyz".index(s.name[0])) for s in lateral],
                         m.Prescribed("x1", 0, displacement=m.Proportional(self.strain * L))),
            drive=m.Static((1.0,), "load factor", "-"),
            observables=(m.Reaction("reaction", "x1", 0),))

    def summarise(self, out: dict) -> dict:
        """``reaction`` (N) against ``exact_reaction`` (N)."""
        return dict(exact_reaction=self.exact_reaction())


