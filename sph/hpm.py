"""Hamiltonian particle method (HPM; Suzuki & Koshizuka 2008, as used in 004 §II), total Lagrangian,
2-D plane strain and 3-D, a material (a row of the body's
:class:`~workbench.materials.MaterialTable`) per particle.

Everything weight-related is computed once in the reference configuration X (the *Lagrangian
kernel*): neighbours within the influence radius r_e (:mod:`sph.neighbours`), the weights

    w_ij = 1 − |X_ij|²/r_e²  for |X_ij| < r_e, 0 otherwise            (eq. 6, X_ij = X_j − X_i)

and the moment matrices A_i = Σ_j w_ij X_ij ⊗ X_ij (eq. 5, d × d, :func:`reference_geometry`).
Then per evaluation:

* the deformation gradient by weighted least squares, F_i = (Σ_j w_ij x_ij ⊗ X_ij) A_i⁻¹ (eq. 4,
  :func:`deformation_gradient_row`): exact for every affine motion on any particle arrangement (F is
  3×3; in 2-D F33 = 1, plane strain);
* P_i = F_i S_i from the shared material library, row ``prm[mat_id[i]]`` of the table
  (:func:`workbench.materials.kernels.material_point`; a body of Saint Venant–Kirchhoff materials,
  eq. 11, calls that law directly; Mooney–Rivlin-like eq. 12, J2, … through the dispatch);
* the force as the exact derivative of the discrete Hamiltonian H = ½ Σ m_i v_i² + Σ_i V_i ψ(F_i):
  since ∂F_i/∂x_k = Σ_j (δ_jk − δ_ik) e ⊗ A_i⁻¹ X_ij w_ij,

      f_i = −∂H/∂x_i = Σ_j w_ij (M_i + M_j) X_ij,   M_i = V_i P_i A_i⁻¹       (eq. 7 times m_i)

  (:func:`stress_pass` gives M, :func:`internal_force` the sum). The pair term is antisymmetric
  (X_ji = −X_ij, the bracket symmetric), so Σ f = 0 exactly; H is invariant under rigid rotations of
  x, so the torque vanishes too.

Zero-energy-mode stabilisation (after Kondo, Suzuki & Koshizuka 2010, who add to the Hamiltonian a
potential that penalises the particle motion the affine map F_i does not see): we use

    H_s = Σ_i c_i Σ_j w_ij |x_ij − F_i X_ij|²,   c_i = α G_i V_i / Σ_j w_ij |X_ij|²
    (:func:`stabilisation_energy`)

with α = ``stabilisation`` (0: off) and G_i the small-strain shear modulus of particle i's material.
Because F_i minimises Σ_j w_ij |x_ij − F X_ij|² (that is eq. 4), ∂H_s/∂F_i = 0 and the force is
simply f_i += 2 Σ_j w_ij [c_i (x_ij − F_i X_ij) + c_j (x_ij − F_j X_ij)], antisymmetric,
conservative and objective: energy and both momenta stay conserved. This is
``stabilisation_form="energy"`` (the default).

``stabilisation_form="kondo"``: the per-bond ("spring") normalisation that we read in Kondo, Suzuki
& Koshizuka (2010): each bond's non-affine stretch is measured against its own length and the
bonds of a particle are averaged with normalised weights,

    H_K = ½ α Σ_i G_i V_i Σ_j ŵ_ij |x_ij − F_i X_ij|² / |X_ij|²,  ŵ_ij = V_j w_ij / Σ_k V_k w_ik
    (:func:`kondo_stiffness`),

i.e. the hourglass energy of :mod:`sph.hourglass` on HPM's weights and gradient. Unlike H_s, the
bond weights ŵ_ij/|X_ij|² are not the least-squares weights of eq. 4, so ∂H_K/∂F_i ≠ 0; H_K is a
quadratic form ½ Σ_k x_kᵀ K x_k of the positions (F_i is linear in x), and its exact force −K x
(through F_i included) keeps energy and both momenta conserved. The paper's own text was not
available here (only its bibliographic record and 004's one-line description): the per-bond
normalisation by |X_ij|², the normalised weights, the ½ and the shear modulus as the scale are
our reading, not a transcription; G_i and α play the role of the paper's stiffness coefficient.
On a uniform lattice, with ŵ_ij/|X_ij|² ≈ w_ij/Σ_k w_ik|X_ik|² and ½ against 1, H_K ≈ ½ H_s at
the same α for the nearest bonds; bonds shorter or longer than the mean weigh more or less.

Time integration (:func:`advance`): the symplectic scheme of eq. 8 (x^{n+1} = x^n + Δt v^n,
v^{n+1} = v^n + Δt a^{n+1}). Its positions are those of the leapfrog; we run it in the
kick–drift–kick (velocity Verlet) form of the shared :mod:`sph.integrate` (``scheme="verlet"``,
default) so that velocities — and hence the reported energies — are synchronous with positions;
``scheme="euler"`` runs eq. 8 literally.

The compiled kernels are written for any d (loops over the d components) with 2-D
specialisations (scalar accumulation) on the hot path of the plane-strain time loop. The body of
the driver is :class:`HPM` (:func:`build`); :func:`wls_discretisation` gives its gradient form
(static Newton, modal solve).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from workbench.materials import MaterialTable
from workbench.materials.kernels import material_point, svk_point

from .diagnostics import strain_energy
from .integrate import cfl_time_step, kick_drift_row, kick_row
from .kernels import JIT, N_CHUNKS
from .method import ParticleBody
from .neighbours import neighbour_list
from .total_lagrangian import FASTMATH

RE_RATIO = 2.1
"""Default influence radius r_e over the particle spacing (eq. 6)."""
SINGULAR = 1e-12
"""A_i is singular (fewer than d independent neighbour directions) when det A_i is below this
fraction of the product of its diagonal."""


# ================================================================================================
# Reference configuration (eq. 5, 6)
# ================================================================================================

@njit(inline="always", **JIT)
def _invert_moment(a00, a01, a02, a11, a12, a22, d, Ainv):
    """A⁻¹ of the symmetric moment matrix of eq. 5 (entries a_kl, k ≤ l; the a_k2 unused in 2-D)
    into Ainv (d, d). Returns 1 (and Ainv = 0) when A is singular, else 0."""
    if d == 2:
        det = a00 * a11 - a01 * a01
        if not det > SINGULAR * (a00 * a11 + 1e-300):
            for k in range(2):
                for l in range(2):
                    Ainv[k, l] = 0.0
            return 1
        Ainv[0, 0] = a11 / det
        Ainv[1, 1] = a00 / det
        Ainv[0, 1] = -a01 / det
        Ainv[1, 0] = -a01 / det
        return 0
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    if not det > SINGULAR * (a00 * a11 * a22 + 1e-300):
        for k in range(3):
            for l in range(3):
                Ainv[k, l] = 0.0
        return 1
    Ainv[0, 0] = c00 / det
    Ainv[1, 1] = c11 / det
    Ainv[2, 2] = c22 / det
    Ainv[0, 1] = Ainv[1, 0] = c01 / det
    Ainv[0, 2] = Ainv[2, 0] = c02 / det
    Ainv[1, 2] = Ainv[2, 1] = c12 / det
    return 0


@njit(parallel=True, **JIT)
def reference_geometry(X, indptr, indices, re, X_ij, w, Ainv, wr2):
    """Fill, per pair p of the CSR list, X_ij[p] = X_j − X_i (nnz, d) and the weight w[p] of eq. 6;
    per particle the inverse moment matrix Ainv[i] = A_i⁻¹ (N, d, d) of eq. 5 and
    wr2[i] = Σ_j w_ij |X_ij|² (m²). X (N, d), m; re the influence radius r_e, m. Returns the number
    of particles whose A_i is singular (fewer than d independent neighbour directions)."""
    N, d = X.shape
    re2 = re * re
    bad = np.zeros(N, np.int64)
    for i in prange(N):
        a00 = 0.0
        a01 = 0.0
        a02 = 0.0
        a11 = 0.0
        a12 = 0.0
        a22 = 0.0
        s = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            r2 = 0.0
            for k in range(d):
                e = X[j, k] - X[i, k]
                X_ij[p, k] = e
                r2 += e * e
            wij = 1.0 - r2 / re2 if r2 < re2 else 0.0
            w[p] = wij
            e0 = X_ij[p, 0]
            e1 = X_ij[p, 1]
            e2 = X_ij[p, 2] if d == 3 else 0.0
            a00 += wij * e0 * e0
            a01 += wij * e0 * e1
            a02 += wij * e0 * e2
            a11 += wij * e1 * e1
            a12 += wij * e1 * e2
            a22 += wij * e2 * e2
            s += wij * r2
        wr2[i] = s
        bad[i] = _invert_moment(a00, a01, a02, a11, a12, a22, d, Ainv[i])
    return bad.sum()


# ================================================================================================
# Per evaluation: F (eq. 4), stress (shared library), force (eq. 7)
# ================================================================================================

@njit(inline="always", **JIT)
def _deformation_gradient_row_2d(i, x, indptr, indices, X_ij, w, Ainv, F):
    """2-D specialisation of :func:`deformation_gradient_row` (scalar accumulation, F33 = 1)."""
    b00 = 0.0
    b01 = 0.0
    b10 = 0.0
    b11 = 0.0
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        wij = w[p]
        ux = wij * (x[j, 0] - x[i, 0])
        uy = wij * (x[j, 1] - x[i, 1])
        b00 += ux * X_ij[p, 0]
        b01 += ux * X_ij[p, 1]
        b10 += uy * X_ij[p, 0]
        b11 += uy * X_ij[p, 1]
    F[0, 0] = b00 * Ainv[i, 0, 0] + b01 * Ainv[i, 1, 0]
    F[0, 1] = b00 * Ainv[i, 0, 1] + b01 * Ainv[i, 1, 1]
    F[1, 0] = b10 * Ainv[i, 0, 0] + b11 * Ainv[i, 1, 0]
    F[1, 1] = b10 * Ainv[i, 0, 1] + b11 * Ainv[i, 1, 1]
    F[0, 2] = 0.0
    F[1, 2] = 0.0
    F[2, 0] = 0.0
    F[2, 1] = 0.0
    F[2, 2] = 1.0


@njit(inline="always", **JIT)
def deformation_gradient_row(i, x, indptr, indices, X_ij, w, Ainv, B, F):
    """Eq. 4 for particle i, any d: F_i = (Σ_j w_ij x_ij ⊗ X_ij) A_i⁻¹ into the 3×3 F (F33 = 1 in
    2-D); B (3, 3) scratch."""
    d = x.shape[1]
    for k in range(3):
        for l in range(3):
            B[k, l] = 0.0
            F[k, l] = 0.0
    if d == 2:
        F[2, 2] = 1.0
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        wij = w[p]
        for k in range(d):
            u = wij * (x[j, k] - x[i, k])
            for l in range(d):
                B[k, l] += u * X_ij[p, l]
    for k in range(d):
        for l in range(d):
            s = 0.0
            for m in range(d):
                s += B[k, m] * Ainv[i, m, l]
            F[k, l] = s


@njit(inline="always", **JIT)
def _count_failed(status):
    """Number of non-zero material status codes (counted after the parallel loop: a reduction
    inside it costs the 2-D plate a few per cent)."""
    n = 0
    for i in range(status.shape[0]):
        if status[i] != 0:
            n += 1
    return n


@njit(parallel=True, fastmath=FASTMATH, **JIT)
def stress_pass(x, indptr, indices, X_ij, w, Ainv, V, h_old, prm, mat_id, all_svk, F_all, M,
                h_new, status):
    """For every particle, any d: F_i (eq. 4, :func:`deformation_gradient_row`) into F_all
    (N, 3, 3); P_i from the shared material library with the parameter row prm[mat_id[i]] (prm
    (n_mat, N_PARAMS) the material table; ``all_svk``: every row is Saint Venant–Kirchhoff, whose
    law is called directly, without dispatch or history); M_i = V_i P_i A_i⁻¹ into M (N, d, d),
    Pa·m^(d−2) — the per-particle factor of eq. 7. History h_old → h_new (N, n_history);
    ``status`` (N,) gets the material routine's return code (0 ok). Returns the number of failed
    points (status ≠ 0). :func:`_stress_pass_2d` is its plane-strain specialisation (the time
    loop's hot path)."""
    N, d = x.shape
    chunk = (N + N_CHUNKS - 1) // N_CHUNKS
    for c in prange(N_CHUNKS):
        F = np.empty((3, 3))
        B = np.empty((3, 3))
        P = np.empty((3, 3))
        A = np.empty((3, 3, 3, 3))
        cur = mat_id[c * chunk] if c * chunk < N else 0
        row = prm[cur]  # the material row, switched only where mat_id changes (regions are runs)
        for i in range(c * chunk, min(N, (c + 1) * chunk)):
            if mat_id[i] != cur:
                cur = mat_id[i]
                row = prm[cur]
            deformation_gradient_row(i, x, indptr, indices, X_ij, w, Ainv, B, F)
            if all_svk:
                status[i] = svk_point(F, row, P, A, False)
            else:
                status[i] = material_point(F, h_old[i], row, P, h_new[i], A, False)
            for k in range(3):
                for l in range(3):
                    F_all[i, k, l] = F[k, l]
            vi = V[i]
            for k in range(d):
                for l in range(d):
                    s = 0.0
                    for q in range(d):
                        s += P[k, q] * Ainv[i, q, l]
                    M[i, k, l] = vi * s
    return _count_failed(status)


@njit(parallel=True, **JIT)
def _stress_pass_2d(x, indptr, indices, X_ij, w, Ainv, V, h_old, prm, mat_id, all_svk, F_all, M,
                    h_new, status):
    """:func:`stress_pass` in plane strain (d = 2), written out with scalar accumulation; the
    same arguments and result."""
    N = x.shape[0]
    chunk = (N + N_CHUNKS - 1) // N_CHUNKS
    for c in prange(N_CHUNKS):
        F = np.empty((3, 3))
        P = np.empty((3, 3))
        A = np.empty((3, 3, 3, 3))
        cur = mat_id[c * chunk] if c * chunk < N else 0
        row = prm[cur]
        for i in range(c * chunk, min(N, (c + 1) * chunk)):
            if mat_id[i] != cur:
                cur = mat_id[i]
                row = prm[cur]
            _deformation_gradient_row_2d(i, x, indptr, indices, X_ij, w, Ainv, F)
            if all_svk:
                status[i] = svk_point(F, row, P, A, False)
            else:
                status[i] = material_point(F, h_old[i], row, P, h_new[i], A, False)
            for k in range(3):
                for l in range(3):
                    F_all[i, k, l] = F[k, l]
            for k in range(2):
                M[i, k, 0] = V[i] * (P[k, 0] * Ainv[i, 0, 0] + P[k, 1] * Ainv[i, 1, 0])
                M[i, k, 1] = V[i] * (P[k, 0] * Ainv[i, 0, 1] + P[k, 1] * Ainv[i, 1, 1])
    return _count_failed(status)


@njit(inline="always", **JIT)
def _force_row_2d(i, x, indptr, indices, X_ij, w, M, F_all, cs, stab):
    """2-D specialisation of :func:`force_row`, returning (f_x, f_y)."""
    fx = 0.0
    fy = 0.0
    mi00 = M[i, 0, 0]
    mi01 = M[i, 0, 1]
    mi10 = M[i, 1, 0]
    mi11 = M[i, 1, 1]
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        wij = w[p]
        X0 = X_ij[p, 0]
        X1 = X_ij[p, 1]
        fx += wij * ((mi00 + M[j, 0, 0]) * X0 + (mi01 + M[j, 0, 1]) * X1)
        fy += wij * ((mi10 + M[j, 1, 0]) * X0 + (mi11 + M[j, 1, 1]) * X1)
        if stab and (cs[i] != 0.0 or cs[j] != 0.0):
            x0 = x[j, 0] - x[i, 0]
            x1 = x[j, 1] - x[i, 1]
            di0 = x0 - (F_all[i, 0, 0] * X0 + F_all[i, 0, 1] * X1)
            di1 = x1 - (F_all[i, 1, 0] * X0 + F_all[i, 1, 1] * X1)
            dj0 = x0 - (F_all[j, 0, 0] * X0 + F_all[j, 0, 1] * X1)
            dj1 = x1 - (F_all[j, 1, 0] * X0 + F_all[j, 1, 1] * X1)
            fx += 2.0 * wij * (cs[i] * di0 + cs[j] * dj0)
            fy += 2.0 * wij * (cs[i] * di1 + cs[j] * dj1)
    return fx, fy


@njit(inline="always", **JIT)
def force_row(i, x, indptr, indices, X_ij, w, M, F_all, cs, stab, out):
    """Eq. 7 for particle i, any d: f_i = Σ_j w_ij (M_i + M_j) X_ij plus, where ``stab`` and
    c_i or c_j ≠ 0, the stabilisation force
    2 Σ_j w_ij [c_i (x_ij − F_i X_ij) + c_j (x_ij − F_j X_ij)];
    written into out[i] (d,), N (N/m in 2-D)."""
    d = x.shape[1]
    for k in range(d):
        out[i, k] = 0.0
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        wij = w[p]
        for k in range(d):
            s = 0.0
            for l in range(d):
                s += (M[i, k, l] + M[j, k, l]) * X_ij[p, l]
            out[i, k] += wij * s
        if stab and (cs[i] != 0.0 or cs[j] != 0.0):
            for k in range(d):
                xk = x[j, k] - x[i, k]
                di = xk
                dj = xk
                for l in range(d):
                    di -= F_all[i, k, l] * X_ij[p, l]
                    dj -= F_all[j, k, l] * X_ij[p, l]
                out[i, k] += 2.0 * wij * (cs[i] * di + cs[j] * dj)


@njit(parallel=True, **JIT)
def internal_force(x, indptr, indices, X_ij, w, M, F_all, cs):
    """Internal forces (N, d), N (N per unit thickness in 2-D): −∂(Σ V ψ + H_s)/∂x, from the M and
    F of :func:`stress_pass` at the same x."""
    N, d = x.shape
    f = np.empty((N, d))
    stab = np.any(cs != 0.0)
    for i in prange(N):
        if d == 2:
            fx, fy = _force_row_2d(i, x, indptr, indices, X_ij, w, M, F_all, cs, stab)
            f[i, 0] = fx
            f[i, 1] = fy
        else:
            force_row(i, x, indptr, indices, X_ij, w, M, F_all, cs, stab, f)
    return f


@njit(parallel=True, **JIT)
def stabilisation_energy(x, indptr, indices, X_ij, w, F_all, cs):
    """H_s = Σ_i c_i Σ_j w_ij |x_ij − F_i X_ij|², J (J per unit thickness in 2-D), any d."""
    N, d = x.shape
    e = np.zeros(N)
    for i in prange(N):
        if cs[i] == 0.0:
            continue
        s = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            for k in range(d):
                r = x[j, k] - x[i, k]
                for l in range(d):
                    r -= F_all[i, k, l] * X_ij[p, l]
                s += w[p] * r * r
        e[i] = cs[i] * s
    return e.sum()


@njit(inline="always", **JIT)
def _end_step_row(i, euler, v, acc, fixed, v_fix, dt, damping):
    """The velocity update closing a step for particle i: eq. 8's v += Δt a (``euler``) or the
    closing half kick of velocity Verlet."""
    if euler:
        for k in range(v.shape[1]):
            if fixed[i, k]:
                v[i, k] = v_fix[i, k]
            else:
                v[i, k] = (v[i, k] + dt * acc[i, k]) / (1.0 + damping * dt)
    else:
        kick_row(i, v, acc, fixed, v_fix, dt, damping)


@njit(parallel=True, fastmath=FASTMATH, **JIT)
def _advance(n_steps, euler, x, v, acc, m, a_ext, fixed, v_fix, dt, damping, indptr, indices,
             X_ij, w, Ainv, V, h_old, prm, mat_id, all_svk, cs, F_all, M, h_new, status):
    """``n_steps`` steps of eq. 8 (``euler``) or its kick–drift–kick form, in place, any d, from the
    synchronised state (x, v, acc); the history h_old is committed (from h_new) after every step.
    Returns the number of steps completed (fewer if a material point failed or an acceleration
    became non-finite)."""
    N, d = x.shape
    nh = h_old.shape[1]
    stab = np.any(cs != 0.0)
    for s in range(n_steps):
        for i in prange(N):
            if euler:
                for k in range(d):
                    if fixed[i, k]:
                        v[i, k] = v_fix[i, k]
                    x[i, k] += dt * v[i, k]
            else:
                kick_drift_row(i, x, v, acc, fixed, v_fix, dt, damping)
        if d == 2:
            nfail = _stress_pass_2d(x, indptr, indices, X_ij, w, Ainv, V, h_old, prm, mat_id,
                                    all_svk, F_all, M, h_new, status)
        else:
            nfail = stress_pass(x, indptr, indices, X_ij, w, Ainv, V, h_old, prm, mat_id, all_svk,
                                F_all, M, h_new, status)
        bad = 0
        if d == 2:  # the plane-strain loop on its own: a lean body for the hot path
            for i in prange(N):
                fx, fy = _force_row_2d(i, x, indptr, indices, X_ij, w, M, F_all, cs, stab)
                acc[i, 0] = fx / m[i] + a_ext[i, 0]
                acc[i, 1] = fy / m[i] + a_ext[i, 1]
                _end_step_row(i, euler, v, acc, fixed, v_fix, dt, damping)
                if not (math.isfinite(acc[i, 0]) and math.isfinite(acc[i, 1])):
                    bad += 1
        else:
            for i in prange(N):
                force_row(i, x, indptr, indices, X_ij, w, M, F_all, cs, stab, acc)
                for k in range(d):
                    acc[i, k] = acc[i, k] / m[i] + a_ext[i, k]
                _end_step_row(i, euler, v, acc, fixed, v_fix, dt, damping)
                for k in range(d):
                    if not math.isfinite(acc[i, k]):
                        bad += 1
        if nh > 0:
            for i in prange(N):
                for k in range(nh):
                    h_old[i, k] = h_new[i, k]
        if bad > 0 or nfail > 0:
            return s + 1
    return n_steps


# ================================================================================================
# A body and its dynamics
# ================================================================================================

@dataclass
class Model:
    """An HPM body: reference geometry and the constant arrays of the loops.

    X (N, d) m, V (N,) m^d (m² per unit thickness in 2-D), m (N,) kg (kg/m in 2-D), CSR neighbours
    (indptr, indices) within r_e, per pair X_ij (nnz, d) and w (nnz,), Ainv (N, d, d), 1/m²,
    stabilisation coefficients cs (N,); the materials: ``table`` (a MaterialTable), its parameter
    rows ``prm`` (n_mat, N_PARAMS), ``mat_id`` (N,) a row per particle, ``all_svk`` (every row
    Saint Venant–Kirchhoff: the direct call)."""

    X: np.ndarray
    V: np.ndarray
    m: np.ndarray
    dx: float
    re: float
    indptr: np.ndarray
    indices: np.ndarray
    X_ij: np.ndarray
    w: np.ndarray
    Ainv: np.ndarray
    cs: np.ndarray
    prm: np.ndarray
    table: MaterialTable
    mat_id: np.ndarray
    all_svk: bool
    n_singular: int = 0

    @property
    def n(self) -> int:
        return self.X.shape[0]

    @property
    def dim(self) -> int:
        return self.X.shape[1]

    @property
    def n_history(self) -> int:
        return self.table.n_history


STABILISATION_FORMS = ("energy", "kondo")


def kondo_stiffness(model: "Model", alpha: float) -> "sp.csr_matrix":
    """K (N × N) of H_K = ½ α Σ_i G_i V_i Σ_j ŵ_ij |x_ij − F_i X_ij|²/|X_ij|² (module docstring,
    ``stabilisation_form="kondo"``) = ½ Σ_k x_kᵀ K x_k, each coordinate column k; the shared
    hourglass operator of :func:`sph.hourglass.hourglass_stiffness` on HPM's weight (eq. 6) and
    gradient (eq. 4), with each particle's own shear modulus G_i, Pa. ``alpha`` dimensionless."""
    from .hourglass import hourglass_stiffness

    mu = np.array([mt.mu for mt in model.table.materials])[model.mat_id]
    return hourglass_stiffness(wls_discretisation(model), alpha, mu)


def build_model(X, V, material, dx: float, re_ratio: float = RE_RATIO, stabilisation: float = 0.0,
                body=None, mat_id=None, cracks=None) -> Model:
    """Reference configuration of an HPM body (eq. 5–6): X (N, d) m, d = 2 or 3; V (N,) volumes;
    ``material`` a :class:`~workbench.materials.Material` or a
    :class:`~workbench.materials.MaterialTable` with ``mat_id`` (N,) its row per particle (default
    all 0); dx the spacing, m; r_e = re_ratio·dx. ``body`` (N,) int, optional: particles of
    different bodies never interact through the weights (separate bodies, e.g. two rings).
    ``cracks`` (K, d, d) or None: pre-crack facets, no pair across one
    (:func:`sph.neighbours.cut_pairs`)."""
    if not (isinstance(re_ratio, (int, float)) and 1.0 < re_ratio <= 6.0):
        raise ValueError(f"re_ratio: {re_ratio!r} is not allowed; r_e/Δx must lie in (1, 6]")
    if not (isinstance(stabilisation, (int, float)) and 0.0 <= stabilisation <= 10.0):
        raise ValueError(f"stabilisation: {stabilisation!r} is not allowed; must lie in [0, 10]")
    X = np.ascontiguousarray(X, dtype=np.float64)
    N, d = X.shape
    if d not in (2, 3):
        raise ValueError(f"X: {d}-D positions are not allowed; 2-D (plane strain) or 3-D")
    V = np.ascontiguousarray(V, dtype=np.float64)
    table = MaterialTable.of(material)
    mat_id = (np.zeros(N, np.int64) if mat_id is None
              else np.ascontiguousarray(mat_id, dtype=np.int64))
    if mat_id.shape != (N,) or (N and not (0 <= mat_id.min() and mat_id.max() < len(table))):
        raise ValueError(f"mat_id: not allowed; must be ({N},) integers in [0, {len(table)}) "
                         "(rows of the material table)")
    re = re_ratio * dx
    indptr, indices = neighbour_list(X, re, body,
                                     None if cracks is None or not len(cracks) else (X, cracks))
    nnz = len(indices)
    X_ij = np.empty((nnz, d))
    w = np.empty(nnz)
    Ainv = np.empty((N, d, d))
    wr2 = np.empty(N)
    bad = reference_geometry(X, indptr, indices, re, X_ij, w, Ainv, wr2)
    cs = np.zeros(N)
    if stabilisation > 0:
        mu = np.array([mt.mu for mt in table.materials])[mat_id]
        cs = stabilisation * mu * V / np.maximum(wr2, 1e-300)
    return Model(X, V, table.rho(mat_id) * V, dx, re, indptr, indices, X_ij, w, Ainv, cs,
                 table.params(), table, mat_id, table.all_svk, int(bad))


@dataclass
class State:
    """Synchronous state: positions x (N, d), velocities v (N, d), accelerations acc (N, d), time t;
    the last F (N, 3, 3), M (N, d, d), material status (N,) and history (N, n_history)."""

    x: np.ndarray
    v: np.ndarray
    acc: np.ndarray
    t: float
    F: np.ndarray
    M: np.ndarray
    status: np.ndarray
    h: np.ndarray
    h_new: np.ndarray
    steps: int = 0


def _evaluate(model: Model, x: np.ndarray, h: np.ndarray):
    """stress_pass at x from the history h: (F, M, h_new, status)."""
    N, d = model.n, model.dim
    F = np.empty((N, 3, 3))
    M = np.empty((N, d, d))
    status = np.zeros(N, np.int64)
    h_new = h.copy()
    sp = _stress_pass_2d if d == 2 else stress_pass
    sp(x, model.indptr, model.indices, model.X_ij, model.w, model.Ainv, model.V, h, model.prm,
       model.mat_id, model.all_svk, F, M, h_new, status)
    return F, M, h_new, status


def forces(model: Model, x: np.ndarray, state: State | None = None) -> np.ndarray:
    """Internal forces (N, d) at positions x (eq. 7 plus the optional stabilisation), from the
    committed history of ``state`` (virgin without one); fills the state's F, M, status and
    trial history h_new."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    h = model.table.initial_history(model.mat_id) if state is None else state.h
    F, M, h_new, status = _evaluate(model, x, h)
    if state is not None:
        state.F[:] = F
        state.M[:] = M
        state.status[:] = status
        state.h_new[:] = h_new
    return internal_force(x, model.indptr, model.indices, model.X_ij, model.w, M, F, model.cs)


def potential_energy(model: Model, x: np.ndarray, history: np.ndarray | None = None) -> float:
    """The potential part of the discrete Hamiltonian, Σ V_i ψ(F_i, h_i) + H_s, J (J per unit
    thickness in 2-D) (:func:`sph.diagnostics.strain_energy`); ``history`` the committed material
    history (None: virgin), which a law with a history (J2, mortar, brittle) needs."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    h = model.table.initial_history(model.mat_id) if history is None else history
    F, _, _, _ = _evaluate(model, x, h)
    e = strain_energy(F, model.V, model.prm, model.mat_id,
                      history=h if model.n_history else None)
    if model.cs.any():
        e += stabilisation_energy(x, model.indptr, model.indices, model.X_ij, model.w, F, model.cs)
    return float(e)


def init(model: Model, v0: np.ndarray | None = None, x0: np.ndarray | None = None) -> State:
    """State at t = 0 with the accelerations of the initial configuration."""
    N, d = model.n, model.dim
    x = np.array(model.X if x0 is None else x0, dtype=np.float64)
    v = np.zeros((N, d)) if v0 is None else np.array(v0, dtype=np.float64)
    h = model.table.initial_history(model.mat_id)
    st = State(x, v, np.zeros((N, d)), 0.0, np.empty((N, 3, 3)), np.empty((N, d, d)),
               np.zeros(N, np.int64), h, h.copy())
    st.acc[:] = forces(model, x, st) / model.m[:, None]
    return st


def advance(model: Model, st: State, dt: float, n_steps: int, fixed=None, v_fix=None,
            a_ext=None, damping: float = 0.0, scheme: str = "verlet") -> int:
    """Advance ``st`` by ``n_steps`` steps of size dt (s). ``fixed`` (N, d) uint8 DOFs follow
    ``v_fix`` (m/s); ``a_ext`` (N, d) m/s² external acceleration; ``damping`` mass-proportional,
    1/s. Returns the steps completed."""
    if scheme not in ("verlet", "euler"):
        raise ValueError(f"scheme: {scheme!r} is not one of 'verlet', 'euler'")
    N, d = model.n, model.dim
    fixed = np.zeros((N, d), np.uint8) if fixed is None else fixed
    v_fix = np.zeros((N, d)) if v_fix is None else v_fix
    a_ext = np.zeros((N, d)) if a_ext is None else a_ext
    done = _advance(n_steps, scheme == "euler", st.x, st.v, st.acc, model.m, a_ext, fixed, v_fix,
                    dt, damping, model.indptr, model.indices, model.X_ij, model.w, model.Ainv,
                    model.V, st.h, model.prm, model.mat_id, model.all_svk, model.cs, st.F, st.M,
                    st.h_new, st.status)
    st.t += done * dt
    st.steps += done
    return done


def energies(model: Model, st: State) -> tuple[float, float]:
    """(kinetic, potential) energy of the state, J (J per unit thickness in 2-D)."""
    ke = 0.5 * float(np.sum(model.m[:, None] * st.v * st.v))
    return ke, potential_energy(model, st.x)


def time_step(model: Model, dt_factor: float) -> float:
    """dt = dt_factor · Δx / c_p (shared CFL estimate; c_p the fastest P-wave speed of the
    table)."""
    return cfl_time_step(model.dx, model.table.wave_speed("strain"), dt_factor)


# ================================================================================================
# The method's body for the driver
# ================================================================================================

def wls_discretisation(model: Model):
    """The HPM body as a :class:`sph.total_lagrangian.Discretisation` (2-D or 3-D): eq. 4 is
    F_i = Σ_j (x_j − x_i) ⊗ G_ij with G_ij = w_ij A_i⁻¹ X_ij (A_i symmetric), and the force of
    eq. 7 is −∂(Σ V ψ)/∂x — the gradient form of CSPH's eq. 35, so the static Newton and the modal
    solve (tangent K = ∂²Π/∂x∂x) apply unchanged. Without the stabilisation potential only."""
    from .correction import reverse_gradients
    from .total_lagrangian import Discretisation

    N, d = model.n, model.dim
    rows = np.repeat(np.arange(N), np.diff(model.indptr))
    G = np.ascontiguousarray(model.w[:, None]
                             * np.einsum("pkl,pl->pk", model.Ainv[rows], model.X_ij))
    GT = reverse_gradients(model.indptr, model.indices, G)
    return Discretisation(model.X, model.V, model.m, model.re, "wls", model.indptr,
                          model.indices, G, GT, np.broadcast_to(np.eye(d), (N, d, d)).copy(),
                          np.ones(N, bool))


NAME = "hpm"
OPTIONS = dict(re_ratio=f"r_e/Δx (default {RE_RATIO})",
               stabilisation="zero-energy-mode stabilisation α in [0, 10] (default 0)",
               stabilisation_form="'energy' (default: H_s, normalised by the neighbourhood) | "
                                  "'kondo' (per-bond normalisation, our reading of Kondo et al. 2010)",
               scheme="'verlet' (default) | 'euler' (eq. 8 literally)")


class HPM(ParticleBody):
    """An HPM body built from :class:`sph.particles.Particles`: 2-D plane strain or 3-D, a row of
    the particles' material table per particle."""

    name = NAME

    def __init__(self, particles, re_ratio: float = RE_RATIO, stabilisation: float = 0.0,
                 scheme: str = "verlet", stabilisation_form: str = "energy"):
        super().__init__(particles)
        ps = particles
        if ps.plane == "stress":
            raise ValueError("plane: 'stress' is not modelled by hpm (F33 = 1: plane strain); "
                             "allowed: 'strain' or a 3-D model")
        if scheme not in ("verlet", "euler"):
            raise ValueError(f"scheme: {scheme!r} is not one of 'verlet', 'euler'")
        if stabilisation_form not in STABILISATION_FORMS:
            raise ValueError(f"stabilisation_form: {stabilisation_form!r} is not one of "
                             f"{', '.join(map(repr, STABILISATION_FORMS))}")
        self.scheme = scheme
        self.stabilisation = float(stabilisation)
        self.stabilisation_form = stabilisation_form
        kondo = stabilisation_form == "kondo"
        self.model = build_model(ps.X, ps.V, ps.table, ps.dx, re_ratio,
                                 0.0 if kondo else stabilisation,
                                 body=ps.body if len(ps.body_names) > 1 else None,
                                 mat_id=ps.mat_id, cracks=ps.cracks)
        self.K_kondo = (kondo_stiffness(self.model, self.stabilisation)
                        if kondo and self.stabilisation > 0 else None)
        self.m = self.model.m
        self.st = init(self.model)
        if ps.failed is not None and ps.failed.any():  # the scene's failed regions (unstressed
            self.st.h[:] = ps.initial_history()      # at t = 0: the acceleration is the same)
            self.st.h_new[:] = self.st.h
        if self.K_kondo is not None:
            self.st.acc -= (self.K_kondo @ self.st.x) / self.m[:, None]
        self.x, self.v, self.acc = self.st.x, self.st.v, self.st.acc

    def internal_force(self, x):
        f = forces(self.model, x, self.st)
        if self.K_kondo is not None:
            f -= self.K_kondo @ x
        return f

    def commit(self) -> None:
        if self.model.n_history:
            self.st.h[:] = self.st.h_new

    def failed(self) -> bool:
        return bool(self.st.status.any())

    def dissipated(self) -> dict:
        """``plastic_work`` and ``released_energy``, J: the history's work columns times the
        reference volumes (:func:`sph.diagnostics.dissipated_work`); none for elastic laws."""
        from .diagnostics import dissipated_work

        return dissipated_work(self.model.table, self.model.mat_id, self.st.h, self.model.V)

    def advance(self, n, dt, f_ext, fixed, v_fix, damping=0.0, extra=None) -> int:
        if extra is not None or self.K_kondo is not None:
            # the generic velocity Verlet: the Kondo force −K x is not in the fused loop
            return super().advance(n, dt, f_ext, fixed, v_fix, damping, extra)
        self.st.t, self.st.steps = self.t, self.steps
        done = advance(self.model, self.st, dt, n, fixed=fixed, v_fix=v_fix,
                       a_ext=f_ext / self.m[:, None], damping=damping, scheme=self.scheme)
        self.t, self.steps = self.st.t, self.st.steps
        return done

    def stored_energy(self) -> float:
        e = potential_energy(self.model, self.x, self.st.h)
        if self.K_kondo is not None:
            e += 0.5 * float(np.sum(self.x * (self.K_kondo @ self.x)))
        return e

    def gradient_form(self):
        from .total_lagrangian import Body

        if self.stabilisation != 0.0:
            return None
        return Body(wls_discretisation(self.model), self.particles.table, self.particles.mat_id)

    def field_state(self) -> dict:
        return dict(t=self.t, x=self.x, v=self.v, F=self.st.F, history=self.st.h,
                    mat_id=self.particles.mat_id, region=self.particles.region)


def build(particles, **options) -> HPM:
    """An HPM body of ``particles`` (:func:`sph.particles.discretise`); options: ``OPTIONS``."""
    return HPM(particles, **options)
