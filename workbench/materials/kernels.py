"""The material library's dispatch: first Piola–Kirchhoff stress P(F, history), its consistent
tangent A = dP/dF and the stored energy, per point and for N points, for every law of
:mod:`workbench.materials` (law code ``int(prm[0])``; parameter and history layouts in
:mod:`workbench.materials.layout`):

0–2 the hyperelastic laws (:mod:`.elastic`: SVK, neo-Hooke, 004's Mooney–Rivlin-like law);
3 finite-strain J2 (:mod:`.j2`, paper 000); 4 the mortar of paper 003 (:mod:`.mortar`); 5 the brittle
solid with a fracture energy (:mod:`.brittle`).

Entry points: :func:`material_point` (one point, allocation-free for every law, inlined into its
numba callers — callable from other numba code inside its own ``prange``),
:func:`material_points` and :func:`material_points_tangent` (N points; they allocate the outputs
and run the parallel ``prange`` loop :func:`_points_into`, shared so that it compiles once),
:func:`stored_energy_point` and :func:`stored_energies`. The N-point entry points are plain Python
(numba issue #8578: a cached non-parallel function calling a cached parallel one can crash when
both are loaded from the cache).

Status codes: 0 ok, 1 local Newton of J2 not converged (the best iterate is returned),
2 J ≤ 0 or a non-positive trial stretch (P and A set to NaN, history copied), −1 unknown law.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .brittle import N_HISTORY as N_HISTORY_BRITTLE
from .brittle import brittle_energy, brittle_point
from .elastic import elastic_energy, mooney_rivlin_point, neo_hooke_point, svk_point  # noqa: F401
from .j2 import j2_energy, j2_point  # noqa: F401
from .layout import N_HISTORY_J2, N_PARAMS
from .mortar import N_HISTORY as N_HISTORY_MORTAR
from .mortar import mortar_energy, mortar_point
from .tensor import (INVERTED, JIT, JIT_PARALLEL, LOG_SERIES_MAX, NOT_CONVERGED,  # noqa: F401
                     OK, UNKNOWN_LAW, _copy, _fail, eig_sym3_closed, eigh3, exp_sym, log_spd)

# --------------------------------------------------------------------------------------------
# stored energies
# --------------------------------------------------------------------------------------------
@njit(**JIT)
def stored_energy_point(F, h, prm):
    """Stored (elastic) energy per unit reference volume ψ(F, h), J/m³, of one point, in closed
    form; P = ∂ψ/∂F at fixed history (for J2 and the mortar: within an elastic step). The laws:
    :func:`workbench.materials.elastic.elastic_energy`, :func:`workbench.materials.j2.j2_energy`,
    :func:`workbench.materials.mortar.mortar_energy`. F: (3, 3); h: (n_history,) the history of
    the end of the step; prm: (N_PARAMS,) row. NaN for J ≤ 0 or an unknown law code."""
    law = int(prm[0])
    if law <= 2:
        return elastic_energy(F, prm)
    if law == 3:
        return j2_energy(F, h, prm)
    if law == 4:
        return mortar_energy(F, h, prm)
    if law == 5:
        return brittle_energy(F, h, prm)
    return np.nan


@njit(**JIT_PARALLEL)
def _energies_into(F, h, prm, mat_id, out):
    for n in prange(F.shape[0]):
        out[n] = stored_energy_point(F[n], h[n], prm[mat_id[n]])


def stored_energies(F, h, prm, mat_id):
    """Stored energy per unit reference volume of N points, J/m³, in parallel: F (N, 3, 3),
    h (N, n_history) (of the end of the step), prm (n_mat, N_PARAMS), mat_id (N,) → ψ (N,).
    With the J2 history columns W_p and W_rel, ψ + W_p + W_rel is the work done on each point."""
    _check(F, h, prm, mat_id)
    out = np.empty(F.shape[0])
    _energies_into(F, h, prm, mat_id, out)
    return out


# --------------------------------------------------------------------------------------------
# public entry points
# --------------------------------------------------------------------------------------------
@njit(inline="always", **JIT)
def material_point(F, h_old, prm, P, h_new, A, want_tangent):
    """One material point.

    F: (3, 3) deformation gradient; h_old: (n_history,) history at the start of the step;
    prm: (10,) material parameters. Outputs, written in place: P (3, 3) first Piola–Kirchhoff
    stress, Pa; h_new (n_history,); A (3, 3, 3, 3) = ∂P_ij/∂F_kl, Pa, filled only when
    ``want_tangent`` (otherwise untouched: a shared dummy is fine). Returns the status code
    (0 ok, 1 J2 Newton not converged, 2 J ≤ 0 with P = NaN, −1 unknown law).
    From numba code pass ``want_tangent`` as a plain bool (``bool(True)``), not a literal
    ``True``: numba would compile the law kernels again for the literal. Inlined into its numba
    callers (a dispatch of a few lines; as a call of its own it cost about 40 ns per point).
    """
    law = int(prm[0])
    if law != 3:
        _copy(h_old, h_new)  # elastic laws: no history (nothing to copy when n_history = 0)
    if law == 0:
        return svk_point(F, prm, P, A, want_tangent)
    if law == 1:
        return neo_hooke_point(F, prm, P, A, want_tangent)
    if law == 2:
        return mooney_rivlin_point(F, prm, P, A, want_tangent)
    if law == 3:
        return j2_point(F, h_old, prm, P, h_new, A, want_tangent)
    if law == 4:
        return mortar_point(F, h_old, prm, P, h_new, A, want_tangent)
    if law == 5:
        return brittle_point(F, h_old, prm, P, h_new, A, want_tangent)
    _fail(P, A, want_tangent)
    return UNKNOWN_LAW


@njit(**JIT)
def _check(F, h_old, prm, mat_id):
    """Shapes and codes of a batch: F (N, 3, 3), h_old (N, n_history), prm (n_mat, N_PARAMS),
    mat_id (N,) indices into prm; n_history must hold the widest law of the table (the elastic
    laws ignore and keep any history columns)."""
    if prm.shape[1] != N_PARAMS:
        raise ValueError("prm: a parameter table needs N_PARAMS columns (Material.params())")
    for r in range(prm.shape[0]):
        law = int(prm[r, 0])
        if law < 0 or law > 5:
            raise ValueError("prm[:, 0]: unknown material law code")
        if law == 3:
            if h_old.shape[1] < N_HISTORY_J2:
                raise ValueError("h_old: J2 needs N_HISTORY_J2 = 13 history columns")
            if prm[r, 10] != 0.0 and prm[r, 10] != 1.0:
                raise ValueError("prm[:, 10]: J2 hardening kind must be 0 (Swift) or 1 (linear)")
            if prm[r, 11] != 0.0 and prm[r, 11] != 1.0:
                raise ValueError("prm[:, 11]: J2 failure mode must be 0 (literal) or 1 (compression)")
        if law == 4 and h_old.shape[1] < N_HISTORY_MORTAR:
            raise ValueError("h_old: the mortar law needs 23 history columns")
        if law == 5 and h_old.shape[1] < N_HISTORY_BRITTLE:
            raise ValueError("h_old: the brittle law needs 4 history columns")
    if F.shape[1] != 3 or F.shape[2] != 3 or h_old.shape[0] != F.shape[0]:
        raise ValueError("F must be (N, 3, 3) and h_old (N, n_history)")
    if mat_id.shape[0] != F.shape[0]:
        raise ValueError("mat_id must be (N,)")
    for n in range(mat_id.shape[0]):
        if mat_id[n] < 0 or mat_id[n] >= prm.shape[0]:
            raise ValueError("mat_id: a material index outside the parameter table")


@njit(**JIT_PARALLEL)
def _points_into(F, h_old, prm, mat_id, P, h_new, A, status, want_tangent):
    """The parallel loop behind :func:`material_points` and :func:`material_points_tangent`
    (one parallel kernel for both keeps the first compilation short). Point n takes the
    parameter row ``prm[mat_id[n]]``. The law is dispatched per point by a branch the CPU
    predicts; the law kernels are called directly rather than through :func:`material_point`,
    whose non-inlined call halves the speed of the elastic laws. Without ``want_tangent``, A is a
    (1, 3, 3, 3, 3) dummy that is never written."""
    for n in prange(F.shape[0]):
        m = n if want_tangent else n - n  # (n - n: the parfor index type, not int64)
        row = prm[mat_id[n]]
        law = int(row[0])
        if law != 3:
            _copy(h_old[n], h_new[n])
        if law == 0:
            status[n] = svk_point(F[n], row, P[n], A[m], want_tangent)
        elif law == 1:
            status[n] = neo_hooke_point(F[n], row, P[n], A[m], want_tangent)
        elif law == 2:
            status[n] = mooney_rivlin_point(F[n], row, P[n], A[m], want_tangent)
        elif law == 4:
            status[n] = mortar_point(F[n], h_old[n], row, P[n], h_new[n], A[m], want_tangent)
        elif law == 5:
            status[n] = brittle_point(F[n], h_old[n], row, P[n], h_new[n], A[m], want_tangent)
        else:
            status[n] = j2_point(F[n], h_old[n], row, P[n], h_new[n], A[m], want_tangent)


def material_points(F, h_old, prm, mat_id):
    """Stress at N points, in parallel: F (N, 3, 3), h_old (N, n_history), prm (n_mat, N_PARAMS)
    parameter table (:meth:`workbench.materials.MaterialTable.params`), mat_id (N,) int64 rows
    of it → P (N, 3, 3), h_new (N, n_history), status (N,) int64."""
    _check(F, h_old, prm, mat_id)
    N = F.shape[0]
    P = np.empty((N, 3, 3))
    h_new = np.empty((N, h_old.shape[1]))
    status = np.empty(N, dtype=np.int64)
    _points_into(F, h_old, prm, mat_id, P, h_new, np.empty((1, 3, 3, 3, 3)), status, False)
    return P, h_new, status


def material_points_tangent(F, h_old, prm, mat_id):
    """Stress and tangent at N points, in parallel (arguments as :func:`material_points`):
    → P (N, 3, 3), A (N, 3, 3, 3, 3) with A[n, i, j, k, l] = ∂P_ij/∂F_kl, h_new (N, n_history),
    status (N,) int64."""
    _check(F, h_old, prm, mat_id)
    N = F.shape[0]
    P = np.empty((N, 3, 3))
    A = np.empty((N, 3, 3, 3, 3))
    h_new = np.empty((N, h_old.shape[1]))
    status = np.empty(N, dtype=np.int64)
    _points_into(F, h_old, prm, mat_id, P, h_new, A, status, True)
    return P, A, h_new, status
