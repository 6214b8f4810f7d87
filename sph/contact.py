"""Contact between separate bodies: a pairwise penalty between particles of different bodies
(the "repulsive particle" contact of Monaghan 1994 / Gray et al. 2001 in its simplest, linear form),
weighted on mirror-symmetry planes.

Two particles a, b of different bodies closer than the contact distance r_c interact through the
potential Φ_ab = ½ w_ab k (r_c − r_ab)² (2-D: k in Pa = N/m per unit thickness per metre of
overlap; 3-D: k r_c in N/m), i.e. the repulsive force f_a = w_ab k (r_c − r_ab) (x_a − x_b)/r_ab =
−f_b. The pair force is equal and opposite and central, so linear and angular momentum are
conserved exactly, and the contact is conservative (its energy Φ is part of the Hamiltonian; w_ab
is constant in time).

**Symmetry weight** w_ab (:func:`pair_weight`). A model cut by mirror-symmetry planes (rollers
on a plane with its normal held: the quarter model of a beam) stands for the whole body, its
mirrored copies included; a particle on a plane is shared with its mirror image (it carries half
the mass, on two planes a quarter). The whole body's contact energy is a sum over the orbits of
its pairs under the mirrors, and the model holds one pair of each orbit. An orbit has as many
pairs as there are copies, except that a pair whose two particles both lie on a plane is its own
image in that plane. So w_ab = (pairs in the orbit)/n = Π, over the planes on which both a and b
lie, of ½ (n the number of copies, 4 for a quarter model): w = 1 off the
planes and for a pair with one particle on a plane (its image, with the mirrored partner, is
another pair of the whole body: the shared particle feels both with its whole mass, one with its
half), ½ for two particles on one plane, ¼ on two. For every symmetric configuration the model's
contact energy is then the whole body's over n, and the force on a
particle along the planes it lies on is the whole body's on it times its share (its number of
images over n: the share of its mass, so the accelerations are the whole body's); the normal
component, zero in the whole by symmetry, is the roller's. Neither the product nor the minimum
or maximum of per-particle area factors does this (they halve or quarter a pair with one or both
particles on a plane, or keep two particles on different planes at ½). Without planes every
w_ab is 1 and the forces are the unweighted ones, bit for bit.

Pairs are found with the shared cell list (:func:`sph.neighbours.neighbour_list`) on the current
positions, every call.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .kernels import JIT
from .neighbours import neighbour_list


@njit(**JIT)
def pair_weight(pa, pb):
    """Symmetry weight w_ab of a contact pair (module docstring): ½ for each mirror plane both
    particles lie on. ``pa``, ``pb`` the particles' plane bit masks (bit i: on plane i)."""
    common = pa & pb
    w = 1.0
    while common:
        w *= 0.5
        common &= common - 1
    return w


@njit(parallel=True, **JIT)
def _contact(x, body, planes, indptr, indices, rc, k):
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
            kw = k * pair_weight(planes[a], planes[b])
            s = kw * (rc - r) / r
            for i in range(d):
                f[a, i] += s * (x[a, i] - x[b, i])
            e[a] += 0.25 * kw * (rc - r) * (rc - r)  # half of Φ_ab: each pair is visited twice
    return f, e.sum()


def contact_forces(x: np.ndarray, body: np.ndarray, rc: float, k: float, planes=None):
    """Contact forces (N, d), N (N/m in 2-D), and the contact energy Σ Φ, J (J/m in 2-D), in 2-D
    or 3-D. ``body`` (N,) int labels; ``rc`` contact distance (m); ``k`` penalty stiffness (Pa: N/m
    per unit thickness per metre of overlap in 2-D; in 3-D the force per metre of overlap is k·rc,
    the stiffness of a particle of section ~rc²/rc); ``planes`` (N,) int bit masks of the mirror
    planes each particle lies on (bit i: plane i; None: no planes, every pair weight 1), for the
    symmetry weight of the module docstring (:func:`mirror_planes`)."""
    if not rc > 0 or not k >= 0:
        raise ValueError(f"rc, k: must be > 0 and >= 0 (got {rc}, {k})")
    x = np.ascontiguousarray(x, dtype=np.float64)
    body = np.ascontiguousarray(body, dtype=np.int64)
    if planes is None:
        planes = np.zeros(len(x), np.int64)
    planes = np.ascontiguousarray(planes, dtype=np.int64)
    if planes.shape != body.shape:
        raise ValueError(f"planes: shape {planes.shape} must be that of body {body.shape}")
    kk = k if x.shape[1] == 2 else k * rc
    sel = candidates(x, body, rc)
    if sel is None:
        indptr, indices = neighbour_list(x, rc)
        return _contact(x, body, planes, indptr, indices, rc, kk)
    f = np.zeros_like(x)
    if sel.size == 0:
        return f, 0.0
    xs = np.ascontiguousarray(x[sel])
    indptr, indices = neighbour_list(xs, rc)
    fs, e = _contact(xs, np.ascontiguousarray(body[sel]), np.ascontiguousarray(planes[sel]),
                     indptr, indices, rc, kk)
    f[sel] = fs
    return f, e


def mirror_planes(X: np.ndarray, planes, tol: float):
    """The plane bit masks of :func:`contact_forces`: ``planes`` a sequence of (axis, at, idx) —
    a mirror plane X[axis] = at (m) and the indices of the particles it constrains —; bit i of
    particle a is set where a is among plane i's particles and lies on it (|X_a[axis] − at| ≤
    ``tol``, m: a particle half a spacing off the plane, on a cell lattice, is a whole particle
    with a distinct image); entries on the same plane share its bit. Returns (N,) int64, or None
    when no particle lies on a plane."""
    X = np.asarray(X, dtype=np.float64)
    merged = {}  # one bit per plane: constraints on the same plane (e.g. per region) share it
    for axis, at, idx in planes:
        merged.setdefault((int(axis), float(at)), []).append(np.asarray(idx, dtype=np.int64))
    if len(merged) > 62:
        raise ValueError(f"planes: {len(merged)} mirror planes; allowed: at most 62")
    mask = np.zeros(len(X), np.int64)
    for i, ((axis, at), parts) in enumerate(merged.items()):
        idx = np.unique(np.concatenate(parts))
        on = idx[np.abs(X[idx, axis] - at) <= tol]
        mask[on] |= np.int64(1) << np.int64(i)
    return mask if mask.any() else None


@njit(**JIT)
def _near_other_body(x, body, rc):
    """(N,) bool: within ``rc`` of another body's bounding box (every coordinate inside it
    widened by ``rc``). ``body`` labels are non-negative ints; one pass for the boxes, one for
    the test."""
    N, d = x.shape
    nb = 0
    for a in range(N):
        if body[a] < 0:
            raise ValueError("body: labels must be >= 0")
        nb = max(nb, body[a] + 1)
    lo = np.full((nb, d), np.inf)
    hi = np.full((nb, d), -np.inf)
    for a in range(N):
        b = body[a]
        for i in range(d):
            lo[b, i] = min(lo[b, i], x[a, i])
            hi[b, i] = max(hi[b, i], x[a, i])
    near = np.zeros(N, np.bool_)
    for a in range(N):
        for b in range(nb):
            if b == body[a] or lo[b, 0] > hi[b, 0]:  # own body, or a label no particle has
                continue
            inside = True
            for i in range(d):
                if x[a, i] < lo[b, i] - rc or x[a, i] > hi[b, i] + rc:
                    inside = False
                    break
            if inside:
                near[a] = True
                break
    return near


def candidates(x: np.ndarray, body: np.ndarray, rc: float):
    """Indices of the particles that can touch another body: those within ``rc`` of another
    body's bounding box (the pair search then runs on them only; a large body touched on a small
    part of its surface costs that part). None when that is every particle. ``x`` and ``body``
    as :func:`contact_forces` passes them (float64 and int64, contiguous; labels ≥ 0)."""
    near = _near_other_body(x, body, rc)
    if near.all():
        return None
    return np.flatnonzero(near)
