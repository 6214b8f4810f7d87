"""A plate with a centre pre-crack under tension: the verification of :class:`~.model.PreCrack`.

A plate |X| ≤ W, |Y| ≤ H (plane strain) with a zero-width crack |X| ≤ a on Y = 0, pulled by a
uniform dead traction σ on Y = H and held by a roller (u_y = 0) on Y = −H, u_x = 0 on the centre
line X = 0 (symmetry). The crack adds to the plate's stretch δ = u_y(Y = H) the crack's
compliance,

    Δδ = δ − 2Hσ/E' = (2πσ / (E' W)) ∫₀^a s F(s/W)² ds,

from the energy release rate G = K²/E' of each tip, K = σ √(π a) F(a/W), by Castigliano
(Tada, Paris & Irwin, *The Stress Analysis of Cracks Handbook*, 3rd ed. 2000, p. 5.1 and 5.3):
F(α) = (1 − 0.025 α² + 0.06 α⁴) √sec(πα/2) (Feddersen–Tada, 0.1 % for any α, an infinitely
long strip), E' = E/(1 − ν²). For a small crack it is π σ a² / (E' W), the load-point image of
the crack-opening displacement 4σ/E' √(a² − x²). The finite height checked with the FEM on a
quarter of the plate (symmetry planes, the crack face free, the ligament on a roller; Q9 at 16,
32, 64 elements across W, a = W/2): Δδ/Δδ_Tada − 1 = −2.2, −1.1, −0.5 % at H = 2W (first order,
to ≈ 0 %), +0.6, +1.2 % at 32, 64 at H = 1.5W (to ≈ +2 %): H ≥ 2W keeps the strip's closed
form within a few tenths of a per cent.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

import workbench.scenes.model as m

from ..materials import Material
from .params import ParameterError, Scene, param
from .shapes import Box, Plane


def tada_factor(alpha):
    """F(α) = (1 − 0.025 α² + 0.06 α⁴) √sec(πα/2): K / (σ √(π a)) of a centre crack of length 2a
    in a strip of width 2W, α = a/W (Tada et al. 2000, p. 5.1; 0.1 % for α < 1)."""
    alpha = np.asarray(alpha, float)
    return (1 - 0.025 * alpha ** 2 + 0.06 * alpha ** 4) * np.sqrt(1.0 / np.cos(0.5 * np.pi * alpha))


def crack_compliance(sigma: float, a: float, W: float, E_prime: float) -> float:
    """Δδ, m: the extra stretch of the strip under σ from its centre crack (module docstring),
    ∫ by Gauss–Legendre quadrature of 40 points (the integrand is smooth for a/W < 1)."""
    s, w = np.polynomial.legendre.leggauss(40)
    s = 0.5 * a * (s + 1)
    integral = 0.5 * a * float(np.sum(w * s * tada_factor(s / W) ** 2))
    return 2 * math.pi * sigma * integral / (E_prime * W)


@dataclass(frozen=True)
class CentreCrackPlate(Scene):
    """The plate of the module docstring: half-width W, half-height H, crack half-length a, SVK
    (E, ν), traction σ; observed: the stretch of the top face (mean u_y) and the crack opening
    at its centre (u_y above minus below)."""

    name: str = field(default="centre_crack", metadata=dict(hidden=True))
    W: float = param(1.0, "m", "half-width", lo=0, lo_open=True)
    H: float = param(2.0, "m", "half-height (>= 2 W: the strip of the closed form)", lo=0, lo_open=True)
    a: float = param(0.5, "m", "crack half-length", lo=0, lo_open=True)
    E: float = param(1.0e9, "Pa", "Young's modulus", lo=0, lo_open=True)
    nu: float = param(0.3, "-", "Poisson's ratio", lo=-1, hi=0.5, lo_open=True, hi_open=True)
    sigma: float = param(1.0e5, "Pa", "traction on the top face", lo=0, lo_open=True)

    def check(self):
        if not self.a < 0.8 * self.W:
            raise ParameterError(f"a: {self.a:g} m is out of range; allowed: (0, 0.8 W = {0.8 * self.W:g}) m")
        if not self.H >= 2 * self.W:
            raise ParameterError(f"H: {self.H:g} m is out of range; allowed: [2 W = {2 * self.W:g}, inf) m")

    @property
    def E_prime(self) -> float:
        return self.E / (1 - self.nu ** 2)

    def reference(self) -> dict:
        """``stretch`` δ (m) of the cracked plate and ``crack_stretch`` Δδ (m), closed form."""
        d_crack = crack_compliance(self.sigma, self.a, self.W, self.E_prime)
        return dict(stretch=2 * self.H * self.sigma / self.E_prime + d_crack, crack_stretch=d_crack)

    def model(self, spacing: float | None = None) -> m.Model:
        """The plate at the particle spacing ``spacing`` (the crack-opening sets are the particle
        on the crack's centre, Y = 0 — on the crack's line: its upper side —, and the one a
        spacing below)."""
        W, H, a = self.W, self.H, self.a
        dx = 2 * W / 10 if spacing is None else spacing
        e = 1e-3 * dx
        return m.Model(
            dim=2, plane="strain", length=2 * W, name=self.name,
            regions=(m.Region("plate", Box((-W, -H), (W, H)),
                              Material.svk(E=self.E, nu=self.nu, rho=1000.0)),),
            cracks=(m.PreCrack("crack", ((-a, 0.0), (a, 0.0))),),
            sets=(m.Set("top", Plane(1, H)), m.Set("bottom", Plane(1, -H)),
                  m.Set("centre_line", Plane(0, 0.0)),
                  m.Set("above", Box((-e, -e), (e, e))), m.Set("below", Box((-e, -dx - e), (e, -dx + e)))),
            constraints=(m.Roller("bottom", 1), m.Roller("centre_line", 0)),
            loads=(m.Traction("top", (0.0, self.sigma), scale=m.Proportional()),),
            drive=m.Static((1.0,), "load", "-"),
            observables=(m.Displacement("stretch", "top", 1), m.Displacement("u_above", "above", 1),
                         m.Displacement("u_below", "below", 1)))

    def summarise(self, out: dict) -> dict:
        """``opening``: the crack opening at its centre (u_y above minus below), m, at each load."""
        return dict(opening=np.asarray(out["u_above"], float) - np.asarray(out["u_below"], float))
