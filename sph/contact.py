"""Contact between separate bodies: a pairwise penalty between particles of different bodies
(the "repulsive particle" contact of Monaghan 1994 / Gray et al. 2001 in its simplest, linear form).

Two particles a, b of different bodies closer than the contact distance r_c interact through the
potential Φ_ab = ½ k (r_c − r_ab)² (k in Pa = N/m per unit thickness per metre of overlap), i.e. the
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
    N = x.shape[0]
    f = np.zeros((N, 2))
    e = np.zeros(N)
    for a in prange(N):
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            if body[b] == body[a]:
                continue
            d0 = x[a, 0] - x[b, 0]
            d1 = x[a, 1] - x[b, 1]
            r = math.sqrt(d0 * d0 + d1 * d1)
            if r >= rc or r <= 0.0:
                continue
            s = k * (rc - r) / r
            f[a, 0] += s * d0
            f[a, 1] += s * d1
            e[a] += 0.25 * k * (rc - r) * (rc - r)  # half of Φ_ab: each pair is visited twice
    return f, e.sum()


def contact_forces(x: np.ndarray, body: np.ndarray, rc: float, k: float):
    """Contact forces (N,2), N per unit thickness, and the contact energy Σ Φ, J per unit thickness.
    ``body`` (N,) int labels; ``rc`` contact distance (m); ``k`` penalty stiffness (Pa)."""
    if not rc > 0 or not k >= 0:
        raise ValueError(f"rc, k: must be > 0 and >= 0 (got {rc}, {k})")
    x = np.ascontiguousarray(x, dtype=np.float64)
    indptr, indices = neighbour_list(x, rc)
    return _contact(x, np.ascontiguousarray(body, dtype=np.int64), indptr, indices, rc, k)
