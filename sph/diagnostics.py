"""Energy and momentum diagnostics of a particle system.

The stored energy of a hyperelastic point is taken from the shared material routine alone (no
private copy of any law): ψ(F) = ∫₀¹ P(F(s)) : (F − I) ds along the straight path
F(s) = I + s (F − I), which is exact for a hyperelastic law because P = ∂ψ/∂F and ψ(I) = 0. The
integral is by Gauss–Legendre quadrature with ``N_GAUSS`` points: exact for Saint Venant–Kirchhoff
(the integrand is a cubic in s) and converged to round-off for the neo-Hookean law at the strains of
the scenes. For an elastoplastic law ψ is not defined by this path and the routine is not used.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from workbench.materials.kernels import material_point
# the observables of a history (period, amplitude): one definition for every method, in the core
from workbench.oscillation import MIN_CROSSINGS, measure_period, peak, period_amplitude  # noqa: F401

from .kernels import JIT, N_CHUNKS

N_GAUSS = 6
_GX, _GW = np.polynomial.legendre.leggauss(N_GAUSS)
GAUSS_S = 0.5 * (_GX + 1.0)
GAUSS_W = 0.5 * _GW


@njit(parallel=True, **JIT)
def _strain_energy(F, V, prm, mat_id, gs, gw, nthreads_chunks):
    N = F.shape[0]
    out = np.zeros(N)
    nh = 0
    chunk = (N + nthreads_chunks - 1) // nthreads_chunks
    for c in prange(nthreads_chunks):
        Fs = np.empty((3, 3))
        P = np.empty((3, 3))
        A = np.empty((3, 3, 3, 3))
        h0 = np.zeros(nh)
        h1 = np.zeros(nh)
        for a in range(c * chunk, min(N, (c + 1) * chunk)):
            psi = 0.0
            for g in range(gs.shape[0]):
                for i in range(3):
                    for j in range(3):
                        Fs[i, j] = (1.0 if i == j else 0.0) + gs[g] * (F[a, i, j] - (1.0 if i == j else 0.0))
                material_point(Fs, h0, prm[mat_id[a]], P, h1, A, False)
                s = 0.0
                for i in range(3):
                    for j in range(3):
                        s += P[i, j] * (F[a, i, j] - (1.0 if i == j else 0.0))
                psi += gw[g] * s
            out[a] = V[a] * psi
    return out


def strain_energy(F: np.ndarray, V: np.ndarray, prm: np.ndarray, mat_id=None,
                  per_particle: bool = False, history=None):
    """Stored energy Σ V_a ψ(F_a), J (J/m in 2-D), of hyperelastic materials, or with
    ``history`` (N, n_history) of any law, Σ V_a ψ(F_a, h_a) in closed form
    (:func:`workbench.materials.kernels.stored_energies`; a law with a history — J2, mortar —
    needs it: ValueError without).

    F: (N, 3, 3) deformation gradients; V: (N,) reference volumes; prm: a parameter row
    (``Material.params()``) or a table (n_mat, N_PARAMS) with ``mat_id`` (N,) its rows.
    """
    from workbench.materials import LAW_CODES

    prm = np.atleast_2d(prm)
    mat_id = (np.zeros(len(V), np.int64) if mat_id is None
              else np.ascontiguousarray(mat_id, dtype=np.int64))
    if history is not None and np.shape(history)[1] > 0:
        from workbench.materials.kernels import stored_energies

        e = np.asarray(V, dtype=np.float64) * stored_energies(
            np.ascontiguousarray(F), np.ascontiguousarray(history, dtype=np.float64), prm, mat_id)
        return e if per_particle else float(e.sum())
    with_history = (LAW_CODES["j2"], LAW_CODES["mortar"])
    if np.isin(prm[np.unique(mat_id), 0].astype(int), with_history).any():
        raise ValueError("history: a law with a history (j2, mortar) needs it; give history=(N, n_history)")
    e = _strain_energy(np.ascontiguousarray(F), np.ascontiguousarray(V, dtype=np.float64), prm,
                       mat_id, GAUSS_S, GAUSS_W, N_CHUNKS)
    return e if per_particle else float(e.sum())


def kinetic_energy(m: np.ndarray, v: np.ndarray) -> float:
    """½ Σ m_a |v_a|², J."""
    return 0.5 * float(np.einsum("a,ak,ak->", m, v, v))


def linear_momentum(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Σ m_a v_a, (d,)."""
    return np.einsum("a,ak->k", m, v)


def angular_momentum(m: np.ndarray, x: np.ndarray, v: np.ndarray):
    """Σ m_a x_a × v_a about the origin: a scalar in 2-D, (3,) in 3-D."""
    if x.shape[1] == 2:
        return float(np.sum(m * (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0])))
    return np.einsum("a,ak->k", m, np.cross(x, v))


def total_force(f: np.ndarray) -> np.ndarray:
    """Σ_a f_a, (d,)."""
    return f.sum(axis=0)


def total_torque(x: np.ndarray, f: np.ndarray):
    """Σ_a x_a × f_a: a scalar in 2-D, (3,) in 3-D."""
    if x.shape[1] == 2:
        return float(np.sum(x[:, 0] * f[:, 1] - x[:, 1] * f[:, 0]))
    return np.cross(x, f).sum(axis=0)


# ------------------------------------------------------------------------------------------------
# Energies that left the stored energy for good (every law with such a history)
# ------------------------------------------------------------------------------------------------

def work_columns(table) -> tuple[np.ndarray, np.ndarray]:
    """History columns of the plastic work and of the released (failure, cracking) energy of each
    material of ``table``, J/m³ of reference volume: (n_mat,) int arrays, −1 where the law keeps
    none. J2 (:mod:`workbench.materials.j2`): W_p in ``HIST_W_P``, W_rel in ``HIST_W_REL``; the
    mortar of 003 (:mod:`workbench.materials.mortar`): W_p in ``H_W_PLASTIC``, W_r in
    ``H_W_RELEASED``; the brittle law (:mod:`workbench.materials.brittle`): W_rel in its
    ``H_W_RELEASED``, no plastic work; elastic laws: none."""
    from workbench.materials import HIST_W_P, HIST_W_REL
    from workbench.materials import brittle
    from workbench.materials.mortar import H_W_PLASTIC, H_W_RELEASED

    cols = {"j2": (HIST_W_P, HIST_W_REL), "mortar": (H_W_PLASTIC, H_W_RELEASED),
            "brittle": (-1, brittle.H_W_RELEASED)}
    wp = np.array([cols.get(m.law, (-1, -1))[0] for m in table.materials], np.int64)
    wr = np.array([cols.get(m.law, (-1, -1))[1] for m in table.materials], np.int64)
    return wp, wr


def dissipated_work(table, mat_id: np.ndarray, history: np.ndarray, V: np.ndarray) -> dict:
    """``plastic_work`` Σ V_a W_p,a and ``released_energy`` Σ V_a W_rel,a, J (J/m in 2-D), over the
    points of every law that keeps them (:func:`work_columns`; other points add nothing).
    mat_id (N,) rows of ``table``; history (N, n_history); V (N,) the volumes the stored energy is
    integrated with, m³. Empty dict when no material keeps such a history."""
    wp, wr = work_columns(table)
    if history is None or not ((wp >= 0).any() or (wr >= 0).any()) or np.shape(history)[1] == 0:
        return {}
    mat_id = np.asarray(mat_id, np.int64)
    h = np.asarray(history)
    n = np.arange(len(mat_id))
    cp, cr = wp[mat_id], wr[mat_id]
    Wp = np.where(cp >= 0, h[n, np.maximum(cp, 0)], 0.0)
    Wr = np.where(cr >= 0, h[n, np.maximum(cr, 0)], 0.0)
    V = np.asarray(V, float)
    return dict(plastic_work=float(V @ Wp), released_energy=float(V @ Wr))
