"""Contact between separate bodies: a pairwise penalty between particles of different bodies
(the "repulsive particle" contact of Monaghan 1994 / Gray et al. 2001 in its simplest, linear form).

Two particles a, b of different bodies closer than the contact distance r_c interact through the
potential Φ_ab = ½ k (r_c − r_ab)² (2-D: k in Pa = N/m per unit thickness per metre of overlap;
3-D: k r_c in N/m), i.e. the
repulsive force f_a = k (r_c − r_ab) (x_a − x_b)/r_ab = −f_b. The pair force is equal and opposite
and central, so linear and angular momentum are conserved exactly, and the contact is conservative
(its energy Φ is part of the Hamiltonian). Pairs are found with the shared cell list
(:func:`sph.neighbours.neighbour_list`) on the current positions, every call.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .kernels import JIT
from .neighbours import neighbour_list


@njit(parallel=True, **JIT)
def _contact(x, body, indptr, indices, rc, k):
    N, d = x.shape
    f = np.zeros((N, d))
    e = np.zeros(N)
    for a in prange(N):
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            if body[b] == body[a]:
                continue
            r2 = 0.0
            for i in range(d):
                r2 += (x[a, i] - x[b, i]) ** 2
            r = math.sqrt(r2)
            if r >= rc or r <= 0.0:
                continue
            s = k * (rc - r) / r
            for i in range(d):
                f[a, i] += s * (x[a, i] - x[b, i])
            e[a] += 0.25 * k * (rc - r) * (rc - r)  # half of Φ_ab: each pair is visited twice
    return f, e.sum()


def contact_forces(x: np.ndarray, body: np.ndarray, rc: float, k: float):
    """Contact forces (N, d), N (N/m in 2-D), and the contact energy Σ Φ, J (J/m in 2-D), in 2-D
    or 3-D. ``body`` (N,) int labels; ``rc`` contact distance (m); ``k`` penalty stiffness (Pa: N/m
    per unit thickness per metre of overlap in 2-D; in 3-D the force per metre of overlap is k·rc,
    the stiffness of a particle of section ~rc²/rc)."""
    if not rc > 0 or not k >= 0:
        raise ValueError(f"rc, k: must be > 0 and >= 0 (got {rc}, {k})")
    x = np.ascontiguousarray(x, dtype=np.float64)
    body = np.ascontiguousarray(body, dtype=np.int64)
    kk = k if x.shape[1] == 2 else k * rc
    sel = candidates(x, body, rc)
    if sel is None:
        indptr, indices = neighbour_list(x, rc)
        return _contact(x, body, indptr, indices, rc, kk)
    f = np.zeros_like(x)
    if sel.size == 0:
        return f, 0.0
    xs = np.ascontiguousarray(x[sel])
    indptr, indices = neighbour_list(xs, rc)
    fs, e = _contact(xs, np.ascontiguousarray(body[sel]), indptr, indices, rc, kk)
    f[sel] = fs
    return f, e


def candidates(x: np.ndarray, body: np.ndarray, rc: float):
    """Indices of the particles that can touch another body: those within ``rc`` of another
    body's bounding box (the pair search then runs on them only; a large body touched on a small
    part of its surface costs that part). None when that is every particle."""
    labels = np.unique(body)
    near = np.zeros(len(x), bool)
    for b in labels:
        mb = body == b
        lo, hi = x[mb].min(axis=0) - rc, x[mb].max(axis=0) + rc
        near |= ~mb & np.all((x >= lo) & (x <= hi), axis=1)
    if near.all():
        return None
    return np.nonzero(near)[0]
