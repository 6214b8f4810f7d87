"""The one neighbour search of the particle package: a numba cell list producing CSR arrays.

``indptr`` (N+1,) int64 and ``indices`` (nnz,) int32: the neighbours of particle ``a`` are
``indices[indptr[a]:indptr[a+1]]``, sorted ascending, every ``b ≠ a`` with
``|x_b − x_a| < radius·(1 − EDGE)`` (strict, so that a kernel of support ``radius`` is non-zero on
every listed pair). The relation is symmetric (b lists a whenever a lists b).

A pair at the support's edge to round-off is no neighbour (:data:`EDGE`): on a lattice whose
support radius is itself a lattice distance (h/Δx = 1.5: 2h = 3Δx; 2.0: 4Δx) such pairs would
otherwise fall inside or outside by the last bit of their coordinates, so that the same body
discretised from mirrored (or shifted) coordinates got other pairs; their kernel value and
gradient vanish there, but the consistent correction's uniform pair weights do not, and it
corrected other gradients (csph, h/Δx = 1.5: the half plate with its mirror images 2.5 % off the
full plate's gradients, 19 % of the peak displacement after a few periods).

Usage: once in the reference configuration for total-Lagrangian methods (CSPH, HPM), or every step
(or every few steps with a skin) for an updated-Lagrangian method (classic SPH). Both passes run in
parallel (``prange``) and each particle writes only its own row.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .kernels import JIT

EDGE = 1e-9
"""Relative band at the support's edge whose pairs are not neighbours (module docstring): far above
the round-off of coordinates (1e-16 relative) and far below any lattice's distinct distances; a
compact kernel's value there is O(EDGE³) of its peak."""


@njit(**JIT)
def _cell_coords(x, lo, cell, nc):
    N, d = x.shape
    cid = np.empty(N, np.int64)
    for a in range(N):
        lin = 0
        for k in range(d):
            c = int(math.floor((x[a, k] - lo[k]) / cell))
            if c < 0:
                c = 0
            if c >= nc[k]:
                c = nc[k] - 1
            lin = lin * nc[k] + c
        cid[a] = lin
    return cid


@njit(inline="always", **JIT)
def _cell_range(cid, nc, k, d):
    """The range [lo, hi] of the coordinates along axis k of the linear cell ``cid`` and its
    neighbouring cells, clipped to the grid ([0, 0] for k ≥ d)."""
    if k >= d:
        return 0, 0
    rem = cid
    for j in range(d - 1, k, -1):
        rem //= nc[j]
    c = rem % nc[k]
    return max(c - 1, 0), min(c + 1, nc[k] - 1)


@njit(parallel=True, **JIT)
def _search(x, radius, nc, order, cell_start, cid, body, count_only, indptr, indices):
    """Pass over the 3^d blocks of cells: with ``count_only`` the row lengths, else the rows into
    ``indices`` at ``indptr``, each sorted ascending. ``body`` (N,) labels, or an empty array:
    pairs of different labels are not neighbours."""
    N, d = x.shape
    r2max = radius * radius
    by_body = body.shape[0] == N
    n1 = nc[1] if d > 1 else 1
    n2 = nc[2] if d > 2 else 1
    counts = np.zeros(N, np.int64)
    for a in prange(N):
        l0, h0 = _cell_range(cid[a], nc, 0, d)
        l1, h1 = _cell_range(cid[a], nc, 1, d)
        l2, h2 = _cell_range(cid[a], nc, 2, d)
        pos = 0 if count_only else indptr[a]
        n = 0
        for c0 in range(l0, h0 + 1):
            for c1 in range(l1, h1 + 1):
                # the cells c2 = l2..h2 are consecutive in the linear order
                first = (c0 * n1 + c1) * n2
                for s in range(cell_start[first + l2], cell_start[first + h2 + 1]):
                    b = order[s]
                    if b == a or (by_body and body[b] != body[a]):
                        continue
                    r2 = 0.0
                    for k in range(d):
                        e = x[b, k] - x[a, k]
                        r2 += e * e
                    if r2 < r2max:
                        if not count_only:
                            indices[pos + n] = b
                        n += 1
        counts[a] = n
        if not count_only:
            # insertion sort of the row: rows are short (tens of entries)
            for i in range(pos + 1, pos + n):
                v = indices[i]
                j = i - 1
                while j >= pos and indices[j] > v:
                    indices[j + 1] = indices[j]
                    j -= 1
                indices[j + 1] = v
    return counts


def neighbour_list(x: np.ndarray, radius: float, body=None, cut=None) -> tuple[np.ndarray, np.ndarray]:
    """CSR neighbour list of the points ``x`` (N, d), d = 1, 2 or 3, within ``radius`` (m);
    ``body`` (N,) int labels or None: particles of different bodies are never neighbours (they
    meet through contact only, :mod:`sph.contact`); ``cut``: None, or (X (N, d) reference
    positions, facets (K, d, d) of the pre-cracks, :func:`workbench.crack_geometry.facets`) —
    pairs whose reference segment X_a–X_b crosses a facet are no neighbours
    (:func:`cut_pairs`).

    Returns ``(indptr (N+1,) int64, indices (nnz,) int32)``; self excluded, rows sorted.
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] not in (1, 2, 3):
        raise ValueError(f"x: expected shape (N, d) with d in 1..3, got {x.shape}")
    if not radius > 0:
        raise ValueError(f"radius: {radius} is not allowed; must be > 0")
    N, d = x.shape
    if body is None:
        body = np.zeros(0, np.int64)
    else:
        body = np.ascontiguousarray(body, dtype=np.int64)
        if body.shape != (N,):
            raise ValueError(f"body: shape {body.shape} must be (N,) = ({N},)")
    if N == 0:
        return np.zeros(1, np.int64), np.zeros(0, np.int32)
    lo = x.min(axis=0) - 1e-12 * max(1.0, radius)
    hi = x.max(axis=0)
    nc = np.maximum(1, np.floor((hi - lo) / radius).astype(np.int64) + 1)
    if np.prod(nc.astype(np.float64)) > 8 * N + 1000:  # sparse cloud: coarsen the grid
        f = (np.prod(nc.astype(np.float64)) / (8 * N + 1000)) ** (1.0 / d)
        cell = radius * f
        nc = np.maximum(1, np.floor((hi - lo) / cell).astype(np.int64) + 1)
        # a cell larger than the radius still finds every pair in the 3^d block
    else:
        cell = radius
    cid = _cell_coords(x, lo, cell, nc)
    order = np.argsort(cid, kind="stable")
    ncell = int(np.prod(nc))
    cell_start = np.zeros(ncell + 1, np.int64)
    np.cumsum(np.bincount(cid, minlength=ncell), out=cell_start[1:])
    dummy_p = np.zeros(1, np.int64)
    dummy_i = np.zeros(1, np.int32)
    reach = radius * (1.0 - EDGE)
    counts = _search(x, reach, nc, order, cell_start, cid, body, True, dummy_p, dummy_i)
    indptr = np.zeros(N + 1, np.int64)
    np.cumsum(counts, out=indptr[1:])
    indices = np.empty(int(indptr[-1]), np.int32)
    _search(x, reach, nc, order, cell_start, cid, body, False, indptr, indices)
    if cut is not None and len(cut[1]):
        indptr, indices = cut_pairs(indptr, indices, *cut)
    return indptr, indices


@njit(inline="always", **JIT)
def _crosses(X, a, b, F, f):
    """Whether the segment X_a–X_b crosses the facet F[f] (a segment in 2-D, a triangle in 3-D;
    :mod:`workbench.crack_geometry`: different sides, the positive one closed, and the crossing
    point in the closed facet)."""
    d = X.shape[1]
    pq = 0.0
    for k in range(d):
        pq += (X[b, k] - X[a, k]) ** 2
    if d == 2:
        t0 = F[f, 1, 0] - F[f, 0, 0]
        t1 = F[f, 1, 1] - F[f, 0, 1]
        sp = t0 * (X[a, 1] - F[f, 0, 1]) - t1 * (X[a, 0] - F[f, 0, 0])
        sq = t0 * (X[b, 1] - F[f, 0, 1]) - t1 * (X[b, 0] - F[f, 0, 0])
        tol = 1e-12 * math.sqrt(pq * (t0 * t0 + t1 * t1))
    else:
        e1 = F[f, 1] - F[f, 0]
        e2 = F[f, 2] - F[f, 0]
        n0 = e1[1] * e2[2] - e1[2] * e2[1]
        n1 = e1[2] * e2[0] - e1[0] * e2[2]
        n2 = e1[0] * e2[1] - e1[1] * e2[0]
        sp = (n0 * (X[a, 0] - F[f, 0, 0]) + n1 * (X[a, 1] - F[f, 0, 1])
              + n2 * (X[a, 2] - F[f, 0, 2]))
        sq = (n0 * (X[b, 0] - F[f, 0, 0]) + n1 * (X[b, 1] - F[f, 0, 1])
              + n2 * (X[b, 2] - F[f, 0, 2]))
        tol = 1e-12 * math.sqrt(pq) * (e1[0] ** 2 + e1[1] ** 2 + e1[2] ** 2)
    if abs(sp) <= tol:
        sp = 0.0
    if abs(sq) <= tol:
        sq = 0.0
    if (sp >= 0.0) == (sq >= 0.0):
        return False
    lam = sp / (sp - sq)
    if d == 2:
        u = 0.0
        for k in range(2):
            u += (X[a, k] + lam * (X[b, k] - X[a, k]) - F[f, 0, k]) * (F[f, 1, k] - F[f, 0, k])
        u /= t0 * t0 + t1 * t1
        return -1e-12 <= u <= 1.0 + 1e-12
    p = np.empty(3)
    for k in range(3):
        p[k] = X[a, k] + lam * (X[b, k] - X[a, k])
    nn = n0 * n0 + n1 * n1 + n2 * n2
    for i in range(3):
        j = (i + 1) % 3
        e0 = F[f, j, 0] - F[f, i, 0]
        e1_ = F[f, j, 1] - F[f, i, 1]
        e2_ = F[f, j, 2] - F[f, i, 2]
        r0 = p[0] - F[f, i, 0]
        r1 = p[1] - F[f, i, 1]
        r2 = p[2] - F[f, i, 2]
        c = (n0 * (e1_ * r2 - e2_ * r1) + n1 * (e2_ * r0 - e0 * r2) + n2 * (e0 * r1 - e1_ * r0))
        if c < -1e-12 * nn:
            return False
    return True


@njit(parallel=True, **JIT)
def _keep_pairs(indptr, indices, X, F, lo, hi, keep):
    """keep[p] = False for the pairs p = (a, b) whose segment X_a–X_b crosses a facet of F (whose
    bounding box, ``lo``/``hi`` (K, d), the segment's meets)."""
    N, d = X.shape
    for a in prange(N):
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            for f in range(F.shape[0]):
                near = True
                for k in range(d):
                    if (max(X[a, k], X[b, k]) < lo[f, k] or min(X[a, k], X[b, k]) > hi[f, k]):
                        near = False
                        break
                if near and _crosses(X, a, b, F, f):
                    keep[p] = False
                    break


def cut_pairs(indptr, indices, X, F) -> tuple[np.ndarray, np.ndarray]:
    """The CSR list (``indptr``, ``indices``) less the pairs (a, b) whose reference segment
    X_a–X_b (X (N, d) m) crosses a pre-crack facet of F (K, d, d)
    (:func:`workbench.crack_geometry.facets`), whatever their length: the relation stays symmetric
    (the test is symmetric in a and b) and the rows sorted. Once per list: the methods compute
    their corrections on the cut lists."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.float64)
    tol = 1e-12 * max(1.0, float(np.abs(F).max()))
    lo = np.ascontiguousarray(F.min(axis=1) - tol)
    hi = np.ascontiguousarray(F.max(axis=1) + tol)
    keep = np.ones(indices.shape[0], np.bool_)
    _keep_pairs(indptr, indices, X, F, lo, hi, keep)
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    counts = np.bincount(rows[keep], minlength=len(indptr) - 1)
    new_ptr = np.zeros(len(indptr), np.int64)
    np.cumsum(counts, out=new_ptr[1:])
    return new_ptr, np.ascontiguousarray(indices[keep])


@njit(parallel=True, **JIT)
def max_displacement(x, x0):
    """The largest distance |x_a − x0_a| over the points (N, d), m: how far a point has moved
    since a neighbour list was built at x0 (a list searched within radius + skin holds every pair
    within radius while this stays at most skin/2)."""
    N, d = x.shape
    out = 0.0
    for a in prange(N):
        r2 = 0.0
        for k in range(d):
            e = x[a, k] - x0[a, k]
            r2 += e * e
        out = max(out, r2)
    return math.sqrt(out)


def brute_force(x: np.ndarray, radius: float, body=None):
    """The same CSR list by an O(N²) search (tests only)."""
    x = np.asarray(x, dtype=np.float64)
    d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(-1)
    mask = d2 < (radius * (1.0 - EDGE)) ** 2
    if body is not None:
        mask &= np.equal.outer(body, body)
    np.fill_diagonal(mask, False)
    counts = mask.sum(1)
    indptr = np.zeros(len(x) + 1, np.int64)
    np.cumsum(counts, out=indptr[1:])
    indices = np.nonzero(mask)[1].astype(np.int32)
    return indptr, indices


@njit(inline="always", **JIT)
def sorted_position(keys, lo, hi, e):
    """The first index in keys[lo:hi] (sorted ascending) whose key is not below e (binary search):
    where e sits in a sorted CSR row."""
    while lo < hi:
        mid = (lo + hi) // 2
        if keys[mid] < e:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(parallel=True, **JIT)
def reverse_pairs(indptr, indices):
    """rev[p] for the pair p = (a, b) of a's row: the index of (b, a) in b's sorted row (binary
    search; the list is symmetric), shape (nnz,)."""
    N = indptr.shape[0] - 1
    rev = np.empty(indices.shape[0], np.int64)
    for a in prange(N):
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            rev[p] = sorted_position(indices, indptr[b], indptr[b + 1], a)
    return rev


def weighted_neighbourhood(X: np.ndarray, re: float, body=None, cracks=None):
    """The reference neighbourhood of the weighted-least-squares fits (004 eq. 4–6): pairs within
    ``re`` (m) of X (N, d), none across the ``body`` (N,) labels nor the pre-crack facets
    ``cracks`` (K, d, d) or None, with X_ij = X_j − X_i (P, d) and the weight w = 1 − r²/r_e² (P,).
    Returns (indptr, indices, X_ij, w)."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    indptr, indices = neighbour_list(X, re, body, None if cracks is None else (X, cracks))
    rows = np.repeat(np.arange(len(X)), np.diff(indptr))
    X_ij = np.ascontiguousarray(X[indices] - X[rows])
    r2 = np.einsum("pk,pk->p", X_ij, X_ij)
    w = np.ascontiguousarray(np.maximum(1.0 - r2 / (re * re), 0.0))
    return indptr, indices, X_ij, w
