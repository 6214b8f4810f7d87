"""The constants of a mortar material (003), in Python: the release strain of eq. 5 from the
fracture energy and the particle size, its inverse, the checks of a :class:`Material`'s mortar
constants and their slots in the parameter row. The point routine that uses them is
:mod:`workbench.materials.mortar`."""
from __future__ import annotations

import math

import numpy as np

PAPER_SPACING = 0.005
"""003 §4.1: the particle size at which the release strain is 17 000 µ, m (the RC beam's
mortar and the crack-band bar scale their release strain from it)."""


def release_strain(E: float, f_t: float, G_f: float, particle_size: float) -> float:
    """003 eq. 5 with the linear release of Fig. 8: g_F = G_F/h is the area ½ f_t ε_0 under the
    uniaxial stress–strain curve, so ε_0 = 2 G_F/(f_t h). E, f_t in Pa, G_f in J/m² (N/m), h in m.
    Raises ValueError (one line) unless ε_0 > ε_cr = f_t/E (no snap-back)."""
    if not E > 0:
        raise ValueError(f"E: {E} Pa is not allowed; E must be > 0")
    if not f_t > 0:
        raise ValueError(f"f_t: {f_t} Pa is not allowed; the tensile strength must be > 0")
    if not particle_size > 0:
        raise ValueError(f"particle_size: {particle_size} m is not allowed; it must be > 0")
    g_min = f_t * f_t * particle_size / (2.0 * E)
    if not (G_f > g_min and math.isfinite(G_f)):
        raise ValueError(f"G_f: {G_f} J/m^2 is not allowed; it must be finite and > f_t^2 h/(2E) "
                         f"= {g_min:.4g} J/m^2 (release strain above the cracking strain f_t/E)")
    return 2.0 * G_f / (f_t * particle_size)


def fracture_energy(f_t: float, eps_release: float, particle_size: float) -> float:
    """The fracture energy implied by a release strain (inverse of :func:`release_strain`):
    G_F = ½ f_t ε_0 h, J/m². 003: f_t = 1.61 MPa, ε_0 = 0.017, h = 5 mm give 68.4 N/m."""
    return 0.5 * f_t * eps_release * particle_size


def check_material(m) -> None:
    """The mortar constants of a :class:`Material` (E, ν, ρ are checked by ``validated``)."""
    if not (m.f_t > 0 and math.isfinite(m.f_t)):
        raise ValueError(f"f_t: {m.f_t} Pa is not allowed; the tensile strength must be > 0")
    if not (m.f_c > 0 and math.isfinite(m.f_c)):
        raise ValueError(f"f_c: {m.f_c} Pa is not allowed; the compressive strength must be > 0")
    eps_cr = m.f_t / m.E
    if not (m.eps_release > eps_cr and math.isfinite(m.eps_release)):
        raise ValueError(f"eps_release: {m.eps_release} is not allowed; the release strain must be "
                         f"finite and > the cracking strain f_t/E = {eps_cr:.4g}")
    if not (m.H_c >= 0 and math.isfinite(m.H_c)):
        raise ValueError(f"H_c: {m.H_c} Pa is not allowed; the hardening modulus must be >= 0")
    if not (0.0 <= m.phi_min < 1.0):
        raise ValueError(f"phi_min: {m.phi_min} is not allowed; the floor of φ must lie in [0, 1)")
    if not (0.0 <= m.shear_retention <= 1.0):
        raise ValueError(f"shear_retention: {m.shear_retention} is not allowed; the shear retention "
                         "of a crack must lie in [0, 1] (0: 003's eq. 7 as printed)")
    if not m.tol > 0:
        raise ValueError(f"tol: {m.tol} is not allowed; the tolerance must be > 0")


def pack_params(m, p: np.ndarray) -> None:
    """Slots 3–9 of the parameter row of a mortar (slots 0–2 are the common ones; slot 8 the shear
    retention β, 0 for eq. 7 as printed)."""
    p[3] = m.f_t
    p[4] = m.eps_release
    p[5] = m.f_c
    p[6] = m.H_c
    p[7] = m.phi_min
    p[8] = m.shear_retention
    p[9] = m.tol
