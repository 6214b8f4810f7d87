# notched_plate.py
from dataclasses import dataclass, field

from workbench.materials import Material
from workbench.scenes import Scene, param
from workbench.scenes.model import (CrackTip, Explicit, Model, PreCrack, Prescribed, Reaction,
                                    Region, Set, Table, Threshold)
from workbench.scenes.shapes import Box, Plane


@dataclass(frozen=True)
class NotchedPlate(Scene):
    """A square brittle plate (plane strain) with an edge pre-crack, pulled apart by grips."""

    name: str = field(default="notched_plate", metadata=dict(hidden=True))
    L: float = param(0.1, "m", "side", lo=0, lo_open=True)
    a: float = param(0.05, "m", "pre-crack length", lo=0, lo_open=True)
    f_t: float = param(5.0e6, "Pa", "tensile strength", lo=0, lo_open=True)
    G_c: float = param(50.0, "J/m^2", "fracture energy", lo=0, lo_open=True)
    rate: float = param(0.025, "m/s", "grip speed", lo=0, lo_open=True)

    def model(self, spacing=None):
        L = self.L
        glass = Material.brittle(E=1.0e10, nu=0.3, f_t=self.f_t, G_c=self.G_c, rho=2000.0)
        tab = Material.svk(E=1.0e10, nu=0.3, rho=2000.0)  # gripped bands: elastic, never crack
        up, down = (Table((0.0, 1e-4), (0.0, s * self.rate)) for s in (1, -1))  # speed ramp
        return Model(
            dim=2, length=L,  # resolution r: r intervals across L (odd r: no row on the crack)
            regions=[Region("plate", Box((0.0, -L / 2), (L, L / 2)), glass),
                     Region("top_tab", Box((0.0, L / 2 - 0.01), (L, L / 2)), tab, priority=1),
                     Region("bottom_tab", Box((0.0, -L / 2), (L, 0.01 - L / 2)), tab, priority=1)],
            cracks=[PreCrack("notch", ((0.0, 0.0), (self.a, 0.0)))],  # zero width, any spacing
            sets=[Set("top", Plane(1, L / 2)), Set("bottom", Plane(1, -L / 2))],
            constraints=[Prescribed("top", 1, velocity=up), Prescribed("bottom", 1, velocity=down)],
            drive=Explicit(t_end=0.005, damping=8000.0,  # 5 % of critical at the first period
                           stop=[Threshold("tip_length", above=0.01)]),  # grown 10 mm: stop
            observables=[CrackTip("tip", "notch"), Reaction("grip", "top", 1)])
