"""The one stability criterion of every explicit run (:mod:`sph.driver`), for every method.

A run is **unstable** when the first of these is seen (its status says which and when):

* ``non-finite``: a NaN/inf position, or a material point that failed (J ≤ 0, no return mapping);
* ``energy`` — exponential growth of the energy gain (:class:`EnergyGrowth`). The gain
  e_n = B_n − min_{k≤n} B_k is how far the energy balance B = E_kin + E_stored + E_contact +
  E_dissipated − W_ext has risen above the lowest value it has had (a balance that only falls —
  artificial viscosity, damping — has e = 0: dissipation, recorded as ``dissipated``, never
  instability: the criterion is one-sided). Unstable at a record when all three hold:

  1. e_n > ``E_floor`` = ½ M c_p² ε_f² with ε_f = :data:`FLOOR_STRAIN`: the kinetic energy of the
     whole body (mass M) moving at ε_f c_p, i.e. of a strain ε_f — an **absolute** floor far above
     the round-off of a resting or tiny state (positions carry 1e-16 relative error, strains
     ≲ 1e-13 from it, energies ~1e-26 of the floor's scale); a run with a 1e-300 initial velocity
     never reaches it unless something grows;
  2. e_n > ``tol``·S (the drive's ``energy_growth``), S the largest total energy seen so far (the
     initial and the current one included) — so that the O(Δt²) energy error of a symplectic
     scheme while a load sets a body in motion is not taken for growth;
  3. the growth rate γ = d ln e / d(step), fitted by least squares over the last :data:`WINDOW`
     records (a record whose gain is ≤ 0 enters at 1e-16 S), is ≥ :data:`GROWTH_RATE` per step.
     An explicit integration beyond its critical step multiplies the energy of the offending mode
     by |λ|² per step, |λ| ≈ 1 + 4δ + √(8δ) at Δt = (1 + δ) Δt_crit (central difference; see
     :mod:`sph.spectrum`), i.e. ln|λ|² ≥ 0.01 for δ ≥ 3e-6 (0.1–2 per step in the runs
     beyond the critical step); a bounded energy error, a slow drift or the energy exchanged by
     the physical motion (time scales of hundreds of steps or more: e ∝ t^p gives γ = p/n at step
     n) stays below it once condition 2 holds. A gain that passes conditions 1–2 within one
     record interval, from below, counts as growth at ≥ ln(gain/(1e-16 S))/(steps between them);

  a non-finite energy is always unstable;
* ``disorder`` (where the drive asks for it): the particle disorder η₉₅ exceeds the drive's limit.
  η_i is the non-affine part of the motion around particle i relative to the local affine map of
  the weighted-least-squares fit (004 eq. 4 with the reference neighbours within r_e = 2.1Δx):
  η_i² = Σ_j w_ij |x_ij − F_i X_ij|² / Σ_j w_ij |F_i X_ij|²; η₉₅ is its 95th percentile over the
  monitored particles. A smooth deformation gives η = O((Δx/R)²) (≲ 1e-2 in the scenes);
  clumping and particle-scale zig-zag (zero-energy modes) give η = O(0.1–1). This is a level, not
  a rate: it flags the physical instabilities of a discretisation (clumping, the tensile
  instability, zero-energy modes), which keep the energy balance.

``min_spacing`` (the smallest current distance between particles over Δx) is reported beside it.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .kernels import JIT
from .neighbours import neighbour_list

DISORDER_RE = 2.1
"""Influence radius of the disorder measure over the spacing (004's r_e)."""


FLOOR_STRAIN = 1e-5
"""ε_f of the absolute energy floor ½ M (ε_f c_p)² (module docstring, condition 1)."""
GROWTH_RATE = 1e-2
"""Smallest growth rate of the energy gain, per time step, that counts as instability (condition 3)."""
WINDOW = 3
"""Records over which the growth rate is fitted (the current one and the two before)."""


def energy_floor(mass: float, wave_speed: float) -> float:
    """E_floor = ½ M (ε_f c_p)², J (J/m in 2-D): condition 1 of the module docstring for a body of
    total mass ``mass`` (kg, kg/m in 2-D) and fastest wave speed ``wave_speed`` (m/s)."""
    if not (mass >= 0 and wave_speed >= 0):
        raise ValueError(f"mass, wave_speed: must be >= 0 (got {mass}, {wave_speed})")
    return 0.5 * mass * (FLOOR_STRAIN * wave_speed) ** 2


def growth_rate(steps, gains, scale: float) -> float:
    """γ of condition 3: the least-squares slope of ln e over ``steps`` (per step), the gains
    ``gains`` clipped below at 1e-16·``scale``; NaN with fewer than two records."""
    n = np.asarray(steps, float)
    if len(n) < 2 or not np.ptp(n) > 0:
        return math.nan
    y = np.log(np.maximum(np.asarray(gains, float), 1e-16 * scale))
    nc = n - n.mean()
    return float(nc @ (y - y.mean()) / (nc @ nc))


class EnergyGrowth:
    """The energy criterion of the module docstring, fed one record at a time.

    ``floor``: E_floor (:func:`energy_floor`), J; ``tol``: the relative level of condition 2;
    ``scale``: the initial energy scale (|E_kin + E_stored| at t = 0), J."""

    def __init__(self, floor: float, tol: float, scale: float = 0.0):
        if not (floor >= 0 and tol >= 0):
            raise ValueError(f"floor, tol: must be >= 0 (got {floor}, {tol})")
        self.floor, self.tol = float(floor), float(tol)
        self.scale = abs(float(scale))
        self.lowest = math.inf
        self.steps, self.gains = [], []

    def update(self, step: int, balance: float, total: float) -> tuple[bool, float, float]:
        """Add the record at ``step`` with energy balance ``balance`` and total energy ``total``
        (J). Returns (unstable, gain e_n / S, growth rate per step); a non-finite balance is
        unstable with gain inf."""
        if not (math.isfinite(balance) and math.isfinite(total)):
            return True, math.inf, math.inf
        self.scale = max(self.scale, abs(total))
        self.lowest = min(self.lowest, balance)
        e = balance - self.lowest
        self.steps.append(step)
        self.gains.append(e)
        rel = e / self.scale if self.scale > 0 else (math.inf if e > 0 else 0.0)
        if not (e > self.floor and e > self.tol * self.scale):
            return False, rel, math.nan
        rate = growth_rate(self.steps[-WINDOW:], self.gains[-WINDOW:], max(self.scale, self.floor))
        return bool(rate >= GROWTH_RATE), rel, rate


@njit(parallel=True, **JIT)
def _disorder(x, indptr, indices, X_ij, w, Ainv):
    N, d = x.shape
    eta = np.zeros(N)
    for i in prange(N):
        B = np.zeros((d, d))
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            for k in range(d):
                for l in range(d):
                    B[k, l] += w[p] * (x[j, k] - x[i, k]) * X_ij[p, l]
        F = B @ Ainv[i]
        num = 0.0
        den = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            for k in range(d):
                y = 0.0
                for l in range(d):
                    y += F[k, l] * X_ij[p, l]
                r = x[j, k] - x[i, k] - y
                num += w[p] * r * r
                den += w[p] * y * y
        eta[i] = math.sqrt(num / den) if den > 0.0 else 0.0
    return eta


class Disorder:
    """η of the module docstring for particles with reference positions X (N, d), spacing dx;
    ``body`` (N,) labels (no weights across bodies), ``mask`` the monitored particles, ``cracks``
    (K, d, d) pre-crack facets or None (no weights across them: a pre-crack that opens is not
    disorder)."""

    def __init__(self, X, dx, body=None, mask=None, cracks=None):
        from .neighbours import weighted_neighbourhood

        X = np.ascontiguousarray(X, dtype=np.float64)
        indptr, indices, X_ij, w = weighted_neighbourhood(
            X, DISORDER_RE * dx, body, None if cracks is None or not len(cracks) else cracks)
        rows = np.repeat(np.arange(len(X)), np.diff(indptr))
        A = np.zeros((len(X), X.shape[1], X.shape[1]))
        np.add.at(A, rows, w[:, None, None] * X_ij[:, :, None] * X_ij[:, None, :])
        self.geo = (indptr, indices, X_ij, w, np.linalg.pinv(A))
        self.dx = dx
        self.mask = np.ones(len(X), bool) if mask is None else mask

    def __call__(self, x) -> tuple[float, float]:
        eta = _disorder(np.ascontiguousarray(x), *self.geo)[self.mask]
        return float(np.percentile(eta, 95)), float(eta.max())

    def min_spacing(self, x) -> float:
        ip, ix = neighbour_list(np.ascontiguousarray(x), 2.0 * self.dx)
        if len(ix) == 0:
            return float("inf")
        rows = np.repeat(np.arange(len(x)), np.diff(ip))
        return float(np.min(np.linalg.norm(x[rows] - x[ix], axis=1)) / self.dx)
