"""A brittle plate with an edge pre-crack loaded slowly in pure mode I or pure mode II: the
verification of the crack *path* (issue 41 item 5) against the maximum-hoop-stress criterion.

The plate 0 ≤ X ≤ L, |Y| ≤ L/2 (plane strain, :meth:`Material.brittle`) has a zero-width
pre-crack from (0, 0) to (a, 0). Its top and bottom faces are moved, at a constant rate reached
after a smooth start, by grips (explicit dynamics):

* mode I: u_y = ±δ(t) on Y = ±L/2 (u_x free): symmetric about the crack's line, K_II = 0; the
  crack grows straight ahead, kink angle θ = 0.
* mode II: u_x = ±δ(t) on Y = ±L/2, u_y = 0 there: antisymmetric, the upper face slides towards
  the tip, K_II > 0 (the upper crack face moves +x, Williams' mode-II field) and K_I ≈ 0 (by the
  antisymmetry; not measured here); the
  maximum-hoop-stress criterion (Erdogan & Sih 1963), K_I sin θ + K_II (3 cos θ − 1) = 0 with
  K_I = 0, gives cos θ = 1/3, θ = −arccos(1/3) = −70.53°
  (:func:`kink_angle`), clockwise from the crack's direction.

Quasi-static: the grips' speed makes the loading time to the crack's onset many times the plate's
first period T₁ (:meth:`CrackPathPlate.period`), and a mass-proportional damping of a few per cent
of critical at T₁ removes the grips' start-up wave; the run stops (:class:`~.model.Threshold`) once
the crack has grown ``grow`` from its tip, its kink angle recorded by :class:`~.model.CrackTip`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

import workbench.scenes.model as m

from ..materials import Material
from .params import ParameterError, Scene, param
from .shapes import Box, HalfSpace, Intersection, Plane


def kink_angle(K_I: float, K_II: float) -> float:
    """θ, degrees: the direction of largest hoop stress at a crack tip with stress intensity
    factors K_I ≥ 0, K_II (Erdogan & Sih 1963): the root in (−180°, 180°) of
    K_I sin θ + K_II (3 cos θ − 1) = 0, θ = 2 arctan[(K_I − √(K_I² + 8 K_II²)) / (4 K_II)]."""
    if K_II == 0:
        return 0.0
    return math.degrees(2 * math.atan((K_I - math.sqrt(K_I ** 2 + 8 * K_II ** 2)) / (4 * K_II)))


def smooth_ramp(t, t_ramp: float, rate: float):
    """δ(t), m: a grip displacement whose speed rises as sin² from 0 to ``rate`` over ``t_ramp``
    and stays there (no step in velocity: no start-up shock)."""
    t = np.asarray(t, dtype=float)
    ramp = rate * (0.5 * t - t_ramp / (2 * math.pi) * np.sin(math.pi * t / t_ramp))
    after = rate * (t - 0.5 * t_ramp)
    return np.where(t < t_ramp, ramp, after)


@dataclass(frozen=True)
class _Ramp:
    """The grip displacement ``sign`` · δ(t) (:func:`smooth_ramp`) as a picklable callable."""

    t_ramp: float
    rate: float
    sign: float = 1.0

    def __call__(self, t):
        return self.sign * smooth_ramp(t, self.t_ramp, self.rate)


@dataclass(frozen=True)
class CrackPathPlate(Scene):
    """The plate of the module docstring: side L, pre-crack length a, brittle (E, ν, ρ, f_t, G_c),
    ``mode`` 1 or 2, grip speed ``rate``; observed the crack's tip (``tip_*``: position, length,
    kink angle) and the grip's reaction."""

    name: str = field(default="crack_path", metadata=dict(hidden=True))
    mode: int = param(1, "-", "loading mode: 1 (opening) or 2 (in-plane shear)", lo=1, hi=2)
    L: float = param(0.1, "m", "side of the square plate", lo=0, lo_open=True)
    a: float = param(0.05, "m", "pre-crack length", lo=0, lo_open=True)
    E: float = param(1.0e10, "Pa", "Young's modulus", lo=0, lo_open=True)
    nu: float = param(0.3, "-", "Poisson's ratio", lo=-1, hi=0.5, lo_open=True, hi_open=True)
    rho: float = param(2000.0, "kg/m^3", "density", lo=0, lo_open=True)
    f_t: float = param(5.0e6, "Pa", "tensile strength", lo=0, lo_open=True)
    G_c: float = param(50.0, "J/m^2", "fracture energy", lo=0, lo_open=True)
    rate: float = param(0.025, "m/s", "grip speed (each grip)", lo=0, lo_open=True)
    grow: float = param(0.02, "m", "crack growth at which the run stops", lo=0, lo_open=True)
    damping: float = param(0.0, "1/s", "mass-proportional damping (0: 5 % of critical at T1)", lo=0)
    tab: float = param(0.01, "m", "depth of the gripped bands at Y = ±L/2, elastic (0: none)", lo=0)

    def check(self):
        if self.mode not in (1, 2):
            raise ParameterError(f"mode: {self.mode!r} is out of range; allowed: 1 or 2")
        if not self.a <= 0.7 * self.L:
            raise ParameterError(f"a: {self.a:g} m is out of range; allowed: (0, 0.7 L = {0.7 * self.L:g}] m")
        if not self.tab < 0.25 * self.L:
            raise ParameterError(f"tab: {self.tab:g} m is out of range; allowed: [0, 0.25 L = "
                                 f"{0.25 * self.L:g}) m")
        if not self.grow < self.L - self.a:
            raise ParameterError(f"grow: {self.grow:g} m is out of range; allowed: (0, L - a = "
                                 f"{self.L - self.a:g}) m")

    @property
    def c_p(self) -> float:
        """The plane-strain dilatational wave speed, m/s."""
        E, nu = self.E, self.nu
        return math.sqrt(E * (1 - nu) / (self.rho * (1 + nu) * (1 - 2 * nu)))

    @property
    def c_s(self) -> float:
        """The shear wave speed, m/s."""
        return math.sqrt(self.E / (2 * (1 + self.nu) * self.rho))

    def period(self) -> float:
        """T₁, s: the first period of the gripped plate in its loading's mode — the uncracked
        layer of height L between the grips, in thickness stretch (mode I: 2L/c_p) or thickness
        shear (mode II: 2L/c_s), the one-dimensional standing half wave between the grips — a
        lower bound: the cracked plate is softer and its period longer, so the onset measured in
        T₁ overstates how slow the loading is by that factor."""
        return 2 * self.L / (self.c_p if self.mode == 1 else self.c_s)

    def reference(self) -> dict:
        """``angle``: the kink angle of the maximum-hoop-stress criterion, degrees."""
        return dict(angle=kink_angle(1.0, 0.0) if self.mode == 1 else kink_angle(0.0, 1.0))

    def model(self, spacing: float | None = None) -> m.Model:
        """The plate at the particle spacing ``spacing`` (default L/20)."""
        L, a = self.L, self.a
        dx = L / 20 if spacing is None else spacing
        T1 = self.period()
        damping = self.damping or 2 * 0.05 * (2 * math.pi / T1)
        top, bottom = _Ramp(T1, self.rate, 1.0), _Ramp(T1, self.rate, -1.0)
        axis = 1 if self.mode == 1 else 0
        grips = [m.Prescribed("top", axis, displacement=top),
                 m.Prescribed("bottom", axis, displacement=bottom)]
        rollers = [] if self.mode == 1 else [m.Roller("top", 1), m.Roller("bottom", 1)]
        # the time for the nominal strain 2δ/L to reach 5 f_t/E (the crack starts well before)
        t_end = 5 * self.f_t / self.E * L / (2 * self.rate) + T1
        regions = [m.Region("plate", Box((0.0, -L / 2), (L, L / 2)),
                            Material.brittle(E=self.E, nu=self.nu, f_t=self.f_t, G_c=self.G_c,
                                             rho=self.rho))]
        if self.tab > 0:  # the gripped bands: the same elastic constants, unbreakable
            grip = Material.svk(E=self.E, nu=self.nu, rho=self.rho)
            regions += [m.Region(f"{side}_tab", Box((0.0, lo), (L, lo + self.tab)), grip, priority=1)
                        for side, lo in (("bottom", -L / 2), ("top", L / 2 - self.tab))]
        return m.Model(
            dim=2, plane="strain", length=L, name=self.name,
            regions=tuple(regions),
            cracks=(m.PreCrack("crack", ((-dx, 0.0), (a, 0.0))),),
            sets=(m.Set("top", Plane(1, L / 2)), m.Set("bottom", Plane(1, -L / 2))),
            constraints=tuple(grips + rollers),
            drive=m.Explicit(t_end=t_end, damping=damping, n_out=400,
                             stop=(m.Threshold("tip_length", above=self.grow),)),
            observables=(m.CrackTip("tip", "crack"),
                         m.Reaction("grip", "top", axis)))

    def critical_energy_release(self) -> float:
        """G at the crack's onset by LEFM, J/m²: G_c in mode I; in mode II the maximum-hoop-stress
        criterion's K_IIc = (√3/2) K_Ic, so G_IIc = K_IIc²/E' = ¾ G_c."""
        return self.G_c if self.mode == 1 else 0.75 * self.G_c

    def elastic_half(self, a: float, grip: float = 1e-6) -> m.Model:
        """The elastic plate above the crack's line (0 ≤ Y ≤ L/2), crack length ``a``, with the top
        grip moved by ``grip`` (m) in the loading's direction: the LEFM reference of the onset
        (``studies.crack_path.lefm_onset``) by the FEM, which cuts no elements. Mode I is symmetric
        about Y = 0: the ligament X ≥ a on a roller in y, the crack face free. Mode II is
        antisymmetric (u_x odd, u_y even in Y): the ligament held in x, the crack face free, the
        grip's u_y = 0. One static step; ``grip`` small (geometrically linear)."""
        L, axis = self.L, (1 if self.mode == 1 else 0)
        ligament = Intersection((Plane(1, 0.0), HalfSpace((a, 0.0), (-1.0, 0.0))))
        constraints = [m.Roller("ligament", axis),
                       m.Prescribed("top", axis, displacement=m.Proportional(grip))]
        if self.mode == 2:
            constraints.append(m.Roller("top", 1))
        return m.Model(
            dim=2, plane="strain", length=L, name=f"{self.name}_half",
            regions=(m.Region("plate", Box((0.0, 0.0), (L, L / 2)),
                              Material.svk(E=self.E, nu=self.nu, rho=self.rho)),),
            sets=(m.Set("top", Plane(1, L / 2)), m.Set("ligament", ligament)),
            constraints=tuple(constraints), drive=m.Static(path=(1.0,)),
            observables=(m.Reaction("grip", "top", axis),))

    def summarise(self, out: dict) -> dict:
        return {}
