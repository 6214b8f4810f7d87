"""The FEM's rigid mass on a face (fem_reference.model.lump_mass, the ``lumped_mass`` option) and
its modified-Newton Newmark (``initial_tangent``), on a rod with a tip mass.

The rod: a square bar of side a and length L along z, ν = 0 and rollers on its four sides (so the
3-D bar is exactly the 1-D rod of modulus E, and it cannot bend), clamped at z = 0, a mass M_t
lumped on its top face.
Its modes u = sin(k z) with the tip condition E A u'(L) = M_t ω² u(L): β tan β = m_rod/M_t with
β = kL, ω = β c/L, c = √(E/ρ) (a rod with a tip mass, e.g. Meirovitch, *Elements of vibration
analysis*, §5). With the tip mass starting at v₀ and the rod at rest, the tip moves as the modal
series u(L, t) = Σ_n v̇_n/ω_n φ_n(L) sin ω_n t, v̇_n = M_t v₀ φ_n(L)/m_n,
m_n = ρA ∫₀ᴸ φ_n² dz + M_t φ_n(L)².
"""
import math

from dataclasses import dataclass, field

import numpy as np
import pytest
from scipy.optimize import brentq

import workbench.scenes.model as M
from fem_reference.model import solve_model
from workbench.materials import Material
from workbench.scenes.shapes import Box, Plane

A_SIDE, L, E, RHO = 0.1, 1.0, 2.0e9, 1000.0
M_ROD = RHO * A_SIDE * A_SIDE * L


@dataclass(frozen=True)
class Rod:
    """A scene for the FEM: the clamped rod, ``n`` elements along it (resolution r: elements of
    L/r), its top face the set 'top'."""

    t_end: float = 1e-3
    n_out: int = 10000
    name: str = field(default="rod")

    def model(self, spacing=None):
        return M.Model(
            dim=3, plane=None, length=L,
            regions=(M.Region("rod", Box((0, 0, 0), (A_SIDE, A_SIDE, L)),
                              Material.svk(E=E, nu=0.0, rho=RHO)),),
            sets=(M.Set("base", Plane(2, 0.0)), M.Set("top", Plane(2, L)),
                  M.Set("x0", Plane(0, 0.0)), M.Set("x1", Plane(0, A_SIDE)),
                  M.Set("y0", Plane(1, 0.0)), M.Set("y1", Plane(1, A_SIDE))),
            constraints=(M.Clamp("base"), M.Roller("x0", 0), M.Roller("x1", 0),
                         M.Roller("y0", 1), M.Roller("y1", 1)),
            drive=M.Explicit(self.t_end, n_out=self.n_out),
            observables=(M.Displacement("tip", "top", 2),))

    def summarise(self, out):
        return {}


def modes(ratio: float, n: int) -> np.ndarray:
    """The lowest n roots β of β tan β = ratio (one in each (kπ, kπ + π/2))."""
    f = lambda b: b * math.tan(b) - ratio  # noqa: E731
    return np.array([brentq(f, k * math.pi + 1e-12, k * math.pi + math.pi / 2 - 1e-12,
                            xtol=1e-15) for k in range(n)])


# Quadratic elements with a consistent mass over-estimate a rod's frequency by about (k h)⁴/1440
# (the acoustic branch's dispersion, h the element length; tests/test_fem_dynamics.py); four
# elements and β ≤ 0.87 give k h ≤ 0.22: (kh)⁴/720 = 3e-6 bounds it. A mass lumped wrongly (on
# the corner nodes only, counted per component twice, or not at all) moves ω by its share,
# orders of magnitude more.
@pytest.mark.parametrize("ratio", [0.1, 1.0])
def test_tip_mass_frequency(ratio):
    c = math.sqrt(E / RHO)
    beta = modes(ratio, 1)[0]
    out = solve_model(Rod(), 4, drive=M.Modal(1), lumped_mass=(("top", M_ROD / ratio, None),))
    omega = 2 * math.pi / out["periods"][0]
    assert omega / (beta * c / L) - 1 == pytest.approx(0.0, abs=(beta / 4) ** 4 / 720)


def test_tip_mass_released_at_a_speed():
    """Newmark from the tip mass at v₀ (M_t = 10 m_rod), its history against the modal series of
    the continuum (five modes) over a quarter period. Tolerance 1 % of the amplitude: the top
    element layer's nodes start at v₀ with the tip mass, a momentum excess of at most
    m_rod/(4 M_t) · (1/6) ≈ 0.4 % (their consistent-mass share of one element of four);
    Newmark's period error (ω Δt)²/12 at 200 steps a period is 1e-4; the series beyond five
    modes, below 1e-4. The modified Newton (``initial_tangent``) gives the same history as the full
    one to the Newton tolerance (1e-9 of the forces)."""
    ratio, v0 = 0.1, 0.01
    Mt = M_ROD / ratio
    c = math.sqrt(E / RHO)
    beta = modes(ratio, 5)
    w = beta * c / L
    T = 2 * math.pi / w[0]
    z = np.linspace(0, L, 20001)
    vel = []
    for b in beta:
        phi_L = math.sin(b)
        m_n = RHO * A_SIDE ** 2 * np.trapezoid(np.sin(b * z / L) ** 2, z) + Mt * phi_L ** 2
        vel.append(Mt * v0 * phi_L / m_n * phi_L)
    runs = {}
    for modified in (False, True):
        runs[modified] = solve_model(Rod(t_end=T / 4, n_out=1000), 4,
                                     lumped_mass=(("top", Mt, (0.0, 0.0, v0)),),
                                     steps_per_period=200, initial_tangent=modified)
    t = runs[True]["time"]
    ref = sum(vn / wn * np.sin(wn * t) for vn, wn in zip(vel, w))
    amp = v0 / w[0]
    assert np.max(np.abs(runs[True]["tip"] - ref)) <= 0.01 * amp
    assert np.max(np.abs(runs[True]["tip"] - runs[False]["tip"])) <= 1e-7 * amp


def test_lumped_mass_bad_input():
    with pytest.raises(ValueError, match=r"^lumped_mass: mass -1"):
        solve_model(Rod(), 2, drive=M.Modal(1), lumped_mass=(("top", -1.0, None),))
