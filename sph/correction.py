"""Kernel-gradient corrections of CSPH, computed once in the reference configuration X
(paper 000 §2(5); Bonet & Lok 1999):

* :func:`correction_matrices` — eq. 31, L_a = (Σ_b V_b ∇W_b(X_a) ⊗ (X_b − X_a))⁻¹;
* :func:`corrected_gradients` — eq. 29 and 34, G_ab = V_b L_a ∇W_b(X_a), so that
  Σ_b (X_b − X_a) ⊗ G_ab = I (eq. 30: F of eq. 35 exact for linear fields);
* :func:`quadratic_gradients` — a second-order option: the moving-least-squares derivative with a
  quadratic basis, exact for quadratic fields (bending at free surfaces);
* :func:`reverse_gradients` — G_ba stored beside G_ab in a's row, for the force loop.

The gradients are per CSR pair (``indptr``, ``indices`` from :func:`sph.neighbours.neighbour_list`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .kernels import JIT, dw_dr, w


@njit(inline="always", **JIT)
def _inverse(M, d, out):
    """Inverse of the d×d (d = 1, 2, 3) block of M into out; returns the determinant."""
    if d == 1:
        det = M[0, 0]
        if det != 0.0:
            out[0, 0] = 1.0 / det
        return det
    if d == 2:
        det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
        if det != 0.0:
            out[0, 0] = M[1, 1] / det
            out[1, 1] = M[0, 0] / det
            out[0, 1] = -M[0, 1] / det
            out[1, 0] = -M[1, 0] / det
        return det
    c00 = M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1]
    c01 = M[1, 2] * M[2, 0] - M[1, 0] * M[2, 2]
    c02 = M[1, 0] * M[2, 1] - M[1, 1] * M[2, 0]
    det = M[0, 0] * c00 + M[0, 1] * c01 + M[0, 2] * c02
    if det != 0.0:
        out[0, 0] = c00 / det
        out[1, 0] = c01 / det
        out[2, 0] = c02 / det
        out[0, 1] = (M[0, 2] * M[2, 1] - M[0, 1] * M[2, 2]) / det
        out[1, 1] = (M[0, 0] * M[2, 2] - M[0, 2] * M[2, 0]) / det
        out[2, 1] = (M[0, 1] * M[2, 0] - M[0, 0] * M[2, 1]) / det
        out[0, 2] = (M[0, 1] * M[1, 2] - M[0, 2] * M[1, 1]) / det
        out[1, 2] = (M[0, 2] * M[1, 0] - M[0, 0] * M[1, 2]) / det
        out[2, 2] = (M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]) / det
    return det


@njit(parallel=True, **JIT)
def correction_matrices(X, V, indptr, indices, h, kind):
    """Eq. 31: L_a = (Σ_b V_b ∇W_b(X_a) ⊗ (X_b − X_a))⁻¹, shape (N, d, d).

    Returns (L, ok): ``ok[a]`` is False where the moment matrix is singular (too few or
    collinear neighbours); L_a is then the identity (uncorrected gradient)."""
    N, d = X.shape
    L = np.zeros((N, d, d))
    ok = np.ones(N, np.bool_)
    for a in prange(N):
        M = np.zeros((d, d))
        scale = 0.0
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            r2 = 0.0
            for k in range(d):
                r2 += (X[a, k] - X[b, k]) ** 2
            r = math.sqrt(r2)
            c = V[b] * dw_dr(r, h, kind, d) / r
            for i in range(d):
                for j in range(d):
                    # ∇W_b(X_a) ⊗ (X_b − X_a), ∇W_b(X_a) = W'(r) (X_a − X_b)/r
                    M[i, j] += c * (X[a, i] - X[b, i]) * (X[b, j] - X[a, j])
            scale += abs(c) * r2
        inv = np.zeros((d, d))
        det = _inverse(M, d, inv)
        if not (abs(det) > 1e-10 * max(scale, 1e-300) ** d):
            ok[a] = False
            for i in range(d):
                inv[i, i] = 1.0
        for i in range(d):
            for j in range(d):
                L[a, i, j] = inv[i, j]
    return L, ok


@njit(parallel=True, **JIT)
def corrected_gradients(X, V, indptr, indices, h, kind, L):
    """Eq. 29 and 34: G_ab = V_b L_a ∇W_b(X_a), stored per CSR pair, shape (nnz, d), 1/m."""
    N, d = X.shape
    G = np.empty((indices.shape[0], d))
    for a in prange(N):
        for p in range(indptr[a], indptr[a + 1]):
            b = indices[p]
            r2 = 0.0
            for k in range(d):
                r2 += (X[a, k] - X[b, k]) ** 2
            r = math.sqrt(r2)
            c = V[b] * dw_dr(r, h, kind, d) / r
            for i in range(d):
                s = 0.0
                for j in range(d):
                    s += L[a, i, j] * (X[a, j] - X[b, j])
                G[p, i] = c * s
    return G


@njit(parallel=True, **JIT)
def quadratic_gradients(X, V, indptr, indices, h, kind):
    """Second-order corrected gradients (an option beside eq. 31/34): the moving-least-squares
    derivative with the quadratic basis p(Δ) = (Δ, Δ⊗Δ upper triangle)/h, weights V_b W_ab:
    G_ab = [M_a⁻¹ p(Δ_ab) V_b W_ab]_(first d), M_a = Σ_b V_b W_ab p p^T, Δ_ab = X_b − X_a.
    Then Σ_b Δ_ab ⊗ G_ab = I (eq. 30, linear completeness) and Σ_b (Δ_ab)_i (Δ_ab)_j G_ab = 0, so
    F (eq. 35) is exact for quadratic fields too — bending included — also at free surfaces where
    the first-order gradient is one-sided. Returns (G (nnz, d), ok (N,))."""
    N, d = X.shape
    m = d + d * (d + 1) // 2
    G = np.zeros((indices.shape[0], d))
    ok = np.ones(N, np.bool_)
    for a in prange(N):
        n = indptr[a + 1] - indptr[a]
        Pm = np.zeros((n, m))
        wv = np.zeros(n)
        for q in range(n):
            b = indices[indptr[a] + q]
            r2 = 0.0
            for k in range(d):
                r2 += (X[b, k] - X[a, k]) ** 2
            wv[q] = V[b] * w(math.sqrt(r2), h, kind, d)
            c = d
            for i in range(d):
                Pm[q, i] = (X[b, i] - X[a, i]) / h
                for j in range(i, d):
                    Pm[q, c] = (X[b, i] - X[a, i]) * (X[b, j] - X[a, j]) / (h * h)
                    c += 1
        M = np.zeros((m, m))
        for q in range(n):
            for i in range(m):
                for j in range(m):
                    M[i, j] += wv[q] * Pm[q, i] * Pm[q, j]
        if n < m or abs(np.linalg.det(M)) < 1e-12 * np.abs(M).max() ** m:
            ok[a] = False
            continue
        Minv = np.linalg.inv(M)
        for q in range(n):
            for i in range(d):
                s = 0.0
                for j in range(m):
                    s += Minv[i, j] * Pm[q, j]
                G[indptr[a] + q, i] = s * wv[q] / h
    return G, ok


def reverse_gradients(indptr, indices, G):
    """G_ba for every pair (a, b) of a's row (:func:`sph.neighbours.reverse_pairs`), stored
    contiguously beside G_ab (shape (nnz, d)) for the force loop."""
    from .neighbours import reverse_pairs

    return np.ascontiguousarray(G[reverse_pairs(indptr, indices)])
