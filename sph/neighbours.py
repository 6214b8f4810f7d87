"""The one neighbour search of the particle package: a numba cell list producing CSR arrays.

``indptr`` (N+1,) int64 and ``indices`` (nnz,) int32: the neighbours of particle ``a`` are
``indices[indptr[a]:indptr[a+1]]``, sorted ascending, every ``b ≠ a`` with ``|x_b − x_a| < radius``
(strict, so that a kernel of support ``radius`` is non-zero on every listed pair). The relation is
symmetric (b lists a whenever a lists b).

Usage: once in the reference configuration for total-Lagrangian methods (CSPH, HPM), or every step
(or every few steps with a skin) for an updated-Lagrangian method (classic SPH). Both passes run in
parallel (``prange``) and each particle writes only its own row.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .kernels import JIT


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


@njit(parallel=True, **JIT)
def _search(x, radius, lo, nc, order, cell_start, cid, count_only, indptr, indices):
    N, d = x.shape
    r2max = radius * radius
    n_off = 3 ** d
    counts = np.zeros(N, np.int64)
    for a in prange(N):
        # cell coordinates of a from its linear cell id
        rem = cid[a]
        ca = np.empty(3, np.int64)
        for k in range(d - 1, -1, -1):
            ca[k] = rem % nc[k]
            rem //= nc[k]
        pos = 0
        if not count_only:
            pos = indptr[a]
        n = 0
        for o in range(n_off):
            ok = True
            # decode offset o into (−1, 0, 1)^d, most significant first
            lin = 0
            t = o
            offs = np.empty(3, np.int64)
            for k in range(d - 1, -1, -1):
                offs[k] = t % 3 - 1
                t //= 3
            for k in range(d):
                c = ca[k] + offs[k]
                if c < 0 or c >= nc[k]:
                    ok = False
                    break
                lin = lin * nc[k] + c
            if not ok:
                continue
            for s in range(cell_start[lin], cell_start[lin + 1]):
                b = order[s]
                if b == a:
                    continue
                r2 = 0.0
                for k in range(d):
                    dx = x[b, k] - x[a, k]
                    r2 += dx * dx
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


def neighbour_list(x: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """CSR neighbour list of the points ``x`` (N, d), d = 2 or 3, within ``radius`` (m).

    Returns ``(indptr (N+1,) int64, indices (nnz,) int32)``; self excluded, rows sorted.
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] not in (1, 2, 3):
        raise ValueError(f"x: expected shape (N, d) with d in 1..3, got {x.shape}")
    if not radius > 0:
        raise ValueError(f"radius: {radius} is not allowed; must be > 0")
    N, d = x.shape
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
    np.add.at(cell_start, cid + 1, 1)
    cell_start = np.cumsum(cell_start)
    dummy_p = np.zeros(1, np.int64)
    dummy_i = np.zeros(1, np.int32)
    counts = _search(x, radius, lo, nc, order, cell_start, cid, True, dummy_p, dummy_i)
    indptr = np.zeros(N + 1, np.int64)
    np.cumsum(counts, out=indptr[1:])
    indices = np.empty(int(indptr[-1]), np.int32)
    _search(x, radius, lo, nc, order, cell_start, cid, False, indptr, indices)
    return indptr, indices


def brute_force(x: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The same CSR list by an O(N²) search (tests only)."""
    x = np.asarray(x, dtype=np.float64)
    d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(-1)
    mask = d2 < radius * radius
    np.fill_diagonal(mask, False)
    counts = mask.sum(1)
    indptr = np.zeros(len(x) + 1, np.int64)
    np.cumsum(counts, out=indptr[1:])
    indices = np.nonzero(mask)[1].astype(np.int32)
    return indptr, indices


def drop_cross_body(indptr: np.ndarray, indices: np.ndarray, body: np.ndarray):
    """The CSR list without the pairs whose particles belong to different bodies (``body`` (N,)
    int labels): separate bodies never interact through the kernel, only through contact."""
    N = len(indptr) - 1
    rows = np.repeat(np.arange(N), np.diff(indptr))
    keep = body[rows] == body[indices]
    new_ptr = np.zeros_like(indptr)
    np.cumsum(np.bincount(rows[keep], minlength=N), out=new_ptr[1:])
    return new_ptr, np.ascontiguousarray(indices[keep])


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


def weighted_neighbourhood(X: np.ndarray, re: float, body=None):
    """The reference neighbourhood of the weighted-least-squares fits (004 eq. 4–6): pairs within
    ``re`` (m) of X (N, d), none across the ``body`` (N,) labels, with X_ij = X_j − X_i (P, d) and
    the weight w = 1 − r²/r_e² (P,). Returns (indptr, indices, X_ij, w)."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    indptr, indices = neighbour_list(X, re)
    if body is not None:
        indptr, indices = drop_cross_body(indptr, indices, np.asarray(body))
    rows = np.repeat(np.arange(len(X)), np.diff(indptr))
    X_ij = np.ascontiguousarray(X[indices] - X[rows])
    r2 = np.einsum("pk,pk->p", X_ij, X_ij)
    w = np.ascontiguousarray(np.maximum(1.0 - r2 / (re * re), 0.0))
    return indptr, indices, X_ij, w
