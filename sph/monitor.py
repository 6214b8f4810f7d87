"""The one stability criterion of every explicit run (:mod:`sph.driver`), for every method.

A run is **unstable** when the first of these is seen (its status says which and when):

* ``non-finite``: a NaN/inf position, or a material point that failed (J ≤ 0, no return mapping);
* ``energy``: the energy balance E(t) − E(0) − W_ext(t) (kinetic + stored + contact energy minus
  the work of the dead loads) *grows* by more than ``energy_growth`` of the energy scale S, or is
  not finite. S is the largest total energy seen so far, the initial and the current one included
  (a plate set swinging: its initial energy; a body at rest that a load sets in motion: what the
  load has put in). One-sided: a loss of energy (artificial viscosity, damping) is dissipation,
  recorded as ``dissipated``, not a blow-up;
* ``disorder`` (where the drive asks for it): the particle disorder η₉₅ exceeds the drive's limit.
  η_i is the non-affine part of the motion around particle i relative to the local affine map of
  the weighted-least-squares fit (004 eq. 4 with the reference neighbours within r_e = 2.1Δx):
  η_i² = Σ_j w_ij |x_ij − F_i X_ij|² / Σ_j w_ij |F_i X_ij|²; η₉₅ is its 95th percentile over the
  monitored particles. A smooth deformation gives η = O((Δx/R)²) (≲ 1e-2 in the scenes);
  clumping and particle-scale zig-zag (zero-energy modes) give η = O(0.1–1).

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


def energy_change(e0: float, e: float, scale: float, tol: float) -> tuple[bool, float]:
    """The one-sided energy criterion: (grew, change) with change = (e − e0)/scale. ``grew`` is
    True when the energy rose by more than ``tol``·scale or is not finite (a blow-up); a loss of
    energy (dissipation by artificial viscosity, damping) never counts as instability."""
    if not math.isfinite(e):
        return True, math.inf
    if not scale > 0:  # nothing to compare with (a body at rest and unloaded)
        return False, math.nan
    change = (e - e0) / scale
    return change > tol, change


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
    ``body`` (N,) labels (no weights across bodies), ``mask`` the monitored particles."""

    def __init__(self, X, dx, body=None, mask=None):
        from .neighbours import drop_cross_body

        X = np.ascontiguousarray(X, dtype=np.float64)
        re = DISORDER_RE * dx
        indptr, indices = neighbour_list(X, re)
        if body is not None:
            indptr, indices = drop_cross_body(indptr, indices, np.asarray(body))
        rows = np.repeat(np.arange(len(X)), np.diff(indptr))
        X_ij = X[indices] - X[rows]
        r2 = np.einsum("pk,pk->p", X_ij, X_ij)
        w = np.where(r2 < re * re, 1.0 - r2 / (re * re), 0.0)
        A = np.zeros((len(X), X.shape[1], X.shape[1]))
        np.add.at(A, rows, w[:, None, None] * X_ij[:, :, None] * X_ij[:, None, :])
        self.geo = (indptr, indices, np.ascontiguousarray(X_ij), w, np.linalg.pinv(A))
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
