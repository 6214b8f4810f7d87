# swinging_cantilever.py
from dataclasses import dataclass, field

from workbench.materials import Material
from workbench.scenes import Scene, param
from workbench.scenes.model import (BodyForce, Clamp, Displacement, Explicit, Model, Period,
                                    Region, Set)
from workbench.scenes.shapes import Box, Plane, Point


@dataclass(frozen=True)
class SwingingCantilever(Scene):
    """A 2-D cantilever (plane strain) released from rest under its own weight, clamped at X = 0."""

    name: str = field(default="swinging_cantilever", metadata=dict(hidden=True))
    L: float = param(0.16, "m", "length", lo=0, lo_open=True)
    H: float = param(0.02, "m", "thickness", lo=0, lo_open=True)
    E: float = param(1.0e7, "Pa", "Young's modulus", lo=0, lo_open=True)
    g: float = param(9.81, "m/s^2", "gravity", lo=0)
    t_end: float = param(0.25, "s", "simulated time (about three periods)", lo=0, lo_open=True)

    def model(self, spacing=None):
        beam = Material.svk(E=self.E, nu=0.3, rho=1000.0)
        return Model(
            dim=2, length=self.H,  # resolution r: r intervals across H, spacing H/r (r + 1 particles)
            regions=[Region("beam", Box((0.0, -self.H / 2), (self.L, self.H / 2)), beam)],
            sets=[Set("root", Plane(0, 0.0)), Set("tip", Point((self.L, 0.0)))],
            constraints=[Clamp("root")],
            loads=[BodyForce((0.0, -self.g))],  # constant: applied at t = 0
            drive=Explicit(t_end=self.t_end),
            observables=[Displacement("tip_deflection", "tip", 1),
                         Period("period", "tip_deflection")])
