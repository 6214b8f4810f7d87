"""Classic updated-Lagrangian SPH for solids (003 §3.1, eq. 1–4, Fig. 6; Libersky & Petschek 1990;
Gray, Monaghan & Swift 2001), 2-D plane strain and 3-D, a material (a row of the body's
:class:`~workbench.materials.MaterialTable`) per particle: the baseline that shows where
uncorrected SPH fails.

Eulerian kernel: the cubic spline of 003 eq. 4 (:mod:`sph.kernels`, support 2h, h = h_ratio·Δx, in
d = 2 or 3 dimensions) evaluated at the *current* positions, with the neighbours of every step's
positions from the shared cell list (:func:`sph.neighbours.neighbour_list`; searched with a skin,
below). One step follows Fig. 6 of 003 in
kick–drift–kick form (shared :mod:`sph.integrate` rows, optional mass-proportional damping):

1. kick–drift: v ← v + Δt/2 a, x ← x + Δt v;
2. neighbours of the new positions (radius 2h);
3. rates (:func:`rates_pass`): velocity gradient L_i = Σ_j (m_j/ρ_i) (v_j − v_i) ⊗ ∇_i W_ij
   (eq. 3 with the volume m_j/ρ_i; :func:`velocity_gradient_row`), continuity
   ρ̇_i = −ρ_i tr L_i (eq. 2), and the stress update — ``stress="hypoelastic"`` (default):
   Hooke's law on the Jaumann rate with the small-strain λ_i, μ_i of particle i's material,
   σ̇ = λ tr(D) I + 2μ D + Ω σ − σ Ω (D, Ω the symmetric and skew parts of L;
   :func:`jaumann_update`; plane strain: L_zz = 0, σ_zz carried);
   ``stress="hyperelastic"``: Ḟ = L F (F ← (I + Δt L) F) and σ = P Fᵀ/J from the shared material
   library, row ``prm[mat_id[i]]`` (so that the ring's Mooney–Rivlin law of eq. 12 is the same code
   as in HPM and CSPH); the J2 law of the library works through the same path;
4. forces (:func:`force_pass`, eq. 1): a_i = Σ_j m_j (σ_i/ρ_i² + σ_j/ρ_j² + f_ij^n (R_i + R_j)
   − Π_ij I) ∇_i W_ij + a_ext, with Monaghan's artificial viscosity
   Π_ij = (−α c̄_ij μ_ij + β μ_ij²)/ρ̄_ij for v_ij·x_ij < 0, μ_ij = h v_ij·x_ij/(r² + 0.01h²),
   c̄_ij the mean of the two particles' P-wave speeds, and, optionally
   (``artificial_stress`` = ε > 0), the artificial stress of Gray, Monaghan & Swift (2001)
   (:func:`artificial_stress_row`): in the principal frame of σ_i (in 2-D of its in-plane block;
   in 3-D the eigen-decomposition of σ_i),
   R'^a = −ε σ'^a/ρ_i² where σ'^a > 0 (else 0), rotated back; f_ij = W(r_ij)/W(Δx), exponent n = 4;
5. kick: v ← v + Δt/2 a.

Every pair term is antisymmetric (∇_i W_ij = −∇_j W_ji, the bracket symmetric), so linear momentum
is conserved to round-off; the torque of the non-central stress term is not zero (angular momentum
is not conserved exactly). Eq. 3 of 003 writes the derivative with the volumes m_j/ρ_j and leaves
the velocity gradient's form open; we take the volume m_j/ρ_i (the gradient of the continuity
equation ρ̇_i = Σ_j m_j (v_i − v_j)·∇_i W_ij), because that L is the power conjugate of eq. 1's
forces for any densities: Σ_i m_i v_i·a_i = −Σ_i (m_i/ρ_i) σ_i : L_i (swap i and j in the σ_j
half of each pair), so the internal forces do exactly the work that the stress path stores and
the semi-discrete scheme conserves energy across a density jump (tests/test_classic.py). With
m_j/ρ_j the two differ by the density contrast at a material interface: on the RC beam (steel
plate 7850, bars 3580–11 200, mortar 2200 kg/m³) the forces then did work the stored energy did
not see, and the beam under the plate grew unstable from about 0.2 ms (issue 12). Within one
material the two forms differ by the density's variation only.
The pair loops are written out for d = 2 and d = 3 (the sums in registers). Step 2's list is
searched within 2h plus a skin and searched again once a particle has moved half the skin
(:meth:`Body._refresh_neighbours`): every step then sees the pairs of its own positions, as
Fig. 6's search every step gives them (the listed pairs beyond 2h add exact zeros).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from workbench.materials import MaterialTable
from workbench.materials.kernels import material_point
from workbench.materials.tensor import eig_sym3_closed

from .integrate import cfl_time_step, kick_drift, kick_row
from .kernels import JIT, N_CHUNKS, SUPPORT, dw_dr, w as kernel_w
from .method import ParticleBody
from .mirror import on_planes, plane_images, with_images
from .neighbours import max_displacement, neighbour_list

STRESS_LAWS = ("hypoelastic", "hyperelastic")
_NO_KF = np.ones(1)
"""The kernel factors passed when there is no kernel reduction (never read)."""
_NO_AV = np.zeros((1, 1))
"""The viscous accelerations' array passed when they are not tracked (never written)."""
HYPOELASTIC_LAWS = ("svk", "neo_hooke")
"""Laws whose small-strain λ, μ the hypoelastic (Jaumann) path uses."""


# ================================================================================================
# The kernel reduction of 003 §4.2(2)
# ================================================================================================

def kernel_factors(table: MaterialTable, mat_id: np.ndarray, hist: np.ndarray,
                   out: np.ndarray) -> np.ndarray:
    """003 §4.2(2): "the reduction factor φ is multiplied onto the kernel of the particles at a
    crack … applied where a particle's tensile strain is excessive (its stress fully released by
    the tension softening), with the factor's lower bound 0.05". Per particle (N,) into ``out``:
    the mortar's φ_min (0.05 in 003; :meth:`~workbench.materials.Material.mortar`) where its
    history's fully-released flag (:data:`workbench.materials.mortar.H_RELEASED`) is set, 1
    elsewhere (every other law, and virgin or partly released mortar). The pair loops multiply each
    pair's kernel — in the velocity gradient (eq. 3) and in the forces (eq. 1), stress, artificial
    stress and viscosity alike — by min(kf_i, kf_j): the interaction across a fully released
    particle is φ_min times the unreduced one (003 does not say what a pair of two released
    particles gets; we take φ_min, not φ_min²). The factor is symmetric in i, j, so linear
    momentum stays conserved."""
    from workbench.materials.mortar import H_RELEASED

    out[:] = 1.0
    for k, mt in enumerate(table.materials):
        if mt.law != "mortar":
            continue
        sel = (mat_id == k) & (hist[:, H_RELEASED] >= 0.5)
        out[sel] = mt.phi_min
    return out


# ================================================================================================
# Rates (eq. 2, 3) and the stress update
# ================================================================================================

@njit(inline="always", **JIT)
def velocity_gradient_row(i, x, v, m, rho, indptr, indices, h, L, kf, reduce):
    """Eq. 3: L_i = Σ_j (m_j/ρ_i) (v_j − v_i) ⊗ ∇_i W_ij (the cubic spline in d = 2 or 3; the
    volume m_j/ρ_i makes L the power conjugate of eq. 1's forces, module docstring) into the 3×3 L
    (zero third row and column in 2-D), 1/s. With ``reduce``, each pair's kernel
    times min(kf_i, kf_j) (:func:`kernel_factors`, the kernel reduction of 003 §4.2(2))."""
    d = x.shape[1]
    for k in range(3):
        for l in range(3):
            L[k, l] = 0.0
    inv_rho = 1.0 / rho[i]
    if d == 2:
        L00 = 0.0
        L01 = 0.0
        L10 = 0.0
        L11 = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            dx0 = x[i, 0] - x[j, 0]
            dx1 = x[i, 1] - x[j, 1]
            r = math.sqrt(dx0 * dx0 + dx1 * dx1)
            if r <= 0.0:
                continue
            g = dw_dr(r, h, 0, 2) / r * m[j] * inv_rho
            if reduce:
                g *= min(kf[i], kf[j])
            dv0 = v[j, 0] - v[i, 0]
            dv1 = v[j, 1] - v[i, 1]
            L00 += dv0 * g * dx0
            L01 += dv0 * g * dx1
            L10 += dv1 * g * dx0
            L11 += dv1 * g * dx1
        L[0, 0] = L00
        L[0, 1] = L01
        L[1, 0] = L10
        L[1, 1] = L11
        return
    # 3-D: the nine components in registers (the same sums, term by term, as a loop over k, l)
    L00 = L01 = L02 = L10 = L11 = L12 = L20 = L21 = L22 = 0.0
    xi0, xi1, xi2 = x[i, 0], x[i, 1], x[i, 2]
    vi0, vi1, vi2 = v[i, 0], v[i, 1], v[i, 2]
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        d0 = xi0 - x[j, 0]
        d1 = xi1 - x[j, 1]
        d2 = xi2 - x[j, 2]
        r = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if r <= 0.0:
            continue
        g = dw_dr(r, h, 0, 3) / r * m[j] * inv_rho
        if reduce:
            g *= min(kf[i], kf[j])
        a0 = (v[j, 0] - vi0) * g
        a1 = (v[j, 1] - vi1) * g
        a2 = (v[j, 2] - vi2) * g
        L00 += a0 * d0
        L01 += a0 * d1
        L02 += a0 * d2
        L10 += a1 * d0
        L11 += a1 * d1
        L12 += a1 * d2
        L20 += a2 * d0
        L21 += a2 * d1
        L22 += a2 * d2
    L[0, 0], L[0, 1], L[0, 2] = L00, L01, L02
    L[1, 0], L[1, 1], L[1, 2] = L10, L11, L12
    L[2, 0], L[2, 1], L[2, 2] = L20, L21, L22


@njit(inline="always", **JIT)
def jaumann_update(s, L, lam, mu, dt, T):
    """Hooke's law on the Jaumann rate, one explicit step in place on the 3×3 Cauchy stress s, Pa:
    s ← s + Δt (λ tr(D) I + 2μ D + Ω s − s Ω), D = ½(L + Lᵀ), Ω = ½(L − Lᵀ) (L 3×3, 1/s);
    λ, μ the small-strain Lamé constants, Pa; T (3, 3) scratch."""
    trD = L[0, 0] + L[1, 1] + L[2, 2]
    for k in range(3):
        for l in range(3):
            rot = 0.0
            for q in range(3):
                rot += 0.5 * ((L[k, q] - L[q, k]) * s[q, l] - s[k, q] * (L[q, l] - L[l, q]))
            T[k, l] = mu * (L[k, l] + L[l, k]) + rot
        T[k, k] += lam * trD
    for k in range(3):
        for l in range(3):
            s[k, l] += dt * T[k, l]


@njit(inline="always", **JIT)
def _jaumann_update_2d(s, L, lam, mu, dt):
    """2-D (plane strain) specialisation of :func:`jaumann_update`: the in-plane block, and σ_zz
    += Δt λ tr D (L_zz = 0, no rotation out of the plane)."""
    trD = L[0, 0] + L[1, 1]
    D01 = 0.5 * (L[0, 1] + L[1, 0])
    W01 = 0.5 * (L[0, 1] - L[1, 0])  # Ω = [[0, W01], [−W01, 0]]
    s00 = s[0, 0]
    s01 = s[0, 1]
    s11 = s[1, 1]
    # Ω σ − σ Ω for the in-plane block
    j00 = 2.0 * W01 * s01
    j11 = -2.0 * W01 * s01
    j01 = W01 * (s11 - s00)
    s[0, 0] = s00 + dt * (lam * trD + 2.0 * mu * L[0, 0] + j00)
    s[1, 1] = s11 + dt * (lam * trD + 2.0 * mu * L[1, 1] + j11)
    s[0, 1] = s01 + dt * (2.0 * mu * D01 + j01)
    s[1, 0] = s[0, 1]
    s[2, 2] = s[2, 2] + dt * lam * trD


@njit(inline="always", **JIT)
def hyperelastic_update(Fi, L, dt, hist_i, prm_row, hist_new_i, s, Fn, P, A):
    """F ← (I + Δt L) F (Ḟ = L F) in place on Fi (3, 3), then σ = P Fᵀ/J from the shared material
    routine with the parameter row ``prm_row`` into s (3, 3), Pa; Fn, P (3, 3), A (3, 3, 3, 3)
    scratch. Returns the material status (99 when J ≤ 0)."""
    for k in range(3):
        for l in range(3):
            Fn[k, l] = Fi[k, l]
    for k in range(3):
        for l in range(3):
            t = 0.0
            for q in range(3):
                t += L[k, q] * Fn[q, l]
            Fi[k, l] = Fn[k, l] + dt * t
    for k in range(3):
        for l in range(3):
            Fn[k, l] = Fi[k, l]
    st = material_point(Fn, hist_i, prm_row, P, hist_new_i, A, False)
    J = (Fn[0, 0] * (Fn[1, 1] * Fn[2, 2] - Fn[1, 2] * Fn[2, 1])
         - Fn[0, 1] * (Fn[1, 0] * Fn[2, 2] - Fn[1, 2] * Fn[2, 0])
         + Fn[0, 2] * (Fn[1, 0] * Fn[2, 1] - Fn[1, 1] * Fn[2, 0]))
    if not J > 0.0:
        st = 99
        J = 1.0
    for k in range(3):
        for l in range(3):
            t = 0.0
            for q in range(3):
                t += P[k, q] * Fn[l, q]
            s[k, l] = t / J
    return st


@njit(inline="always", **JIT)
def artificial_stress_row(i, sigma, rho_i, eps_as, d, R, a, V):
    """Gray, Monaghan & Swift (2001): R_i = Σ_a r_a e_a ⊗ e_a over the principal directions e_a of
    σ_i (2-D: of its in-plane block; 3-D: :func:`workbench.materials.tensor.eig_sym3_closed`), with
    r_a = −ε σ_a/ρ_i² where σ_a > 0, else 0; into R[i] (d, d), Pa·m⁶/kg². a, V (3, 3) scratch."""
    ri2 = 1.0 / (rho_i * rho_i)
    if d == 2:
        p = sigma[i, 0, 0]
        q = sigma[i, 1, 1]
        s = sigma[i, 0, 1]
        th = 0.5 * math.atan2(2.0 * s, p - q)
        cs = math.cos(th)
        sn = math.sin(th)
        p1 = p * cs * cs + 2.0 * s * cs * sn + q * sn * sn
        p2 = p * sn * sn - 2.0 * s * cs * sn + q * cs * cs
        r1 = -eps_as * p1 * ri2 if p1 > 0.0 else 0.0
        r2 = -eps_as * p2 * ri2 if p2 > 0.0 else 0.0
        R[i, 0, 0] = r1 * cs * cs + r2 * sn * sn
        R[i, 1, 1] = r1 * sn * sn + r2 * cs * cs
        R[i, 0, 1] = (r1 - r2) * cs * sn
        R[i, 1, 0] = R[i, 0, 1]
        return
    for k in range(3):
        for l in range(3):
            a[k, l] = sigma[i, k, l]
    eig_sym3_closed(a, V)
    for k in range(3):
        for l in range(3):
            R[i, k, l] = 0.0
    for e in range(3):
        pe = a[e, e]
        if pe > 0.0:
            r = -eps_as * pe * ri2
            for k in range(3):
                for l in range(3):
                    R[i, k, l] += r * V[k, e] * V[l, e]


def rates_pass(x, v, m, rho, rho_new, sigma, F, indptr, indices, h, dt, lam, mu, hyper, prm,
               mat_id, hist, hist_new, eps_as, status, R, kf=None):
    """Step 3 (:func:`rates_kernel`); ``kf`` (N,) or None: the kernel factors of the kernel
    reduction (:func:`kernel_factors`), None: none (the unreduced pair loop)."""
    reduce = kf is not None
    rates_kernel(x, v, m, rho, rho_new, sigma, F, indptr, indices, h, dt, lam, mu, hyper, prm,
                 mat_id, hist, hist_new, eps_as, status, R, kf if reduce else _NO_KF, reduce)


@njit(parallel=True, **JIT)
def rates_kernel(x, v, m, rho, rho_new, sigma, F, indptr, indices, h, dt, lam, mu, hyper, prm,
                 mat_id, hist, hist_new, eps_as, status, R, kf, reduce):
    """Step 3 of the module docstring for every particle, in place: the velocity gradient (eq. 3),
    the new density into ``rho_new`` (eq. 2; ``rho`` is read by the neighbours, so it is not
    overwritten), the stress — hypoelastic (Jaumann, λ (N,), μ (N,) per particle, Pa) or, with
    ``hyper``, hyperelastic through F (N, 3, 3) and the material row prm[mat_id[i]] with history
    hist → hist_new (N, n_history) — into ``sigma`` (N, 3, 3) Cauchy, Pa, and, where ε = eps_as > 0,
    the artificial-stress tensor into R (N, d, d). ``status`` (N,) the material status (0 ok).
    The rows are those of ``indptr``; x, v, m, rho (and kf) may also hold ghosts (:mod:`sph.mirror`)."""
    N, d = indptr.shape[0] - 1, x.shape[1]
    chunk = (N + N_CHUNKS - 1) // N_CHUNKS
    for c in prange(N_CHUNKS):
        L = np.empty((3, 3))
        T = np.empty((3, 3))
        Fn = np.empty((3, 3))
        P = np.empty((3, 3))
        A = np.empty((3, 3, 3, 3))
        for i in range(c * chunk, min(N, (c + 1) * chunk)):
            velocity_gradient_row(i, x, v, m, rho, indptr, indices, h, L, kf, reduce)
            rho_new[i] = rho[i] * (1.0 - dt * (L[0, 0] + L[1, 1] + L[2, 2]))
            if hyper:
                status[i] = hyperelastic_update(F[i], L, dt, hist[i], prm[mat_id[i]], hist_new[i],
                                                sigma[i], Fn, P, A)
            elif d == 2:
                _jaumann_update_2d(sigma[i], L, lam[i], mu[i], dt)
            else:
                jaumann_update(sigma[i], L, lam[i], mu[i], dt, T)
            if eps_as > 0.0:
                artificial_stress_row(i, sigma, rho_new[i], eps_as, d, R, Fn, T)


# ================================================================================================
# Forces (eq. 1)
# ================================================================================================

@njit(inline="always", **JIT)
def _force_row_2d(i, x, v, m, rho, sigma, R, indptr, indices, h, c, alpha, beta, n_as, w_dx, kf,
                  reduce):
    """2-D specialisation of :func:`force_row`, returning (a_x, a_y, a^Π_x, a^Π_y)."""
    ax = 0.0
    ay = 0.0
    px = 0.0
    py = 0.0
    ri2 = 1.0 / (rho[i] * rho[i])
    si00 = sigma[i, 0, 0] * ri2
    si01 = sigma[i, 0, 1] * ri2
    si10 = sigma[i, 1, 0] * ri2
    si11 = sigma[i, 1, 1] * ri2
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        dx0 = x[i, 0] - x[j, 0]
        dx1 = x[i, 1] - x[j, 1]
        r2 = dx0 * dx0 + dx1 * dx1
        r = math.sqrt(r2)
        if r <= 0.0:
            continue
        g = dw_dr(r, h, 0, 2) / r
        if reduce:
            g *= min(kf[i], kf[j])
        gx = g * dx0
        gy = g * dx1
        rj2 = 1.0 / (rho[j] * rho[j])
        t00 = si00 + sigma[j, 0, 0] * rj2
        t01 = si01 + sigma[j, 0, 1] * rj2
        t10 = si10 + sigma[j, 1, 0] * rj2
        t11 = si11 + sigma[j, 1, 1] * rj2
        if n_as > 0:
            f = (kernel_w(r, h, 0, 2) / w_dx) ** n_as
            t00 += f * (R[i, 0, 0] + R[j, 0, 0])
            t01 += f * (R[i, 0, 1] + R[j, 0, 1])
            t10 += f * (R[i, 1, 0] + R[j, 1, 0])
            t11 += f * (R[i, 1, 1] + R[j, 1, 1])
        vr = (v[i, 0] - v[j, 0]) * dx0 + (v[i, 1] - v[j, 1]) * dx1
        if vr < 0.0 and (alpha > 0.0 or beta > 0.0):
            mu_ij = h * vr / (r2 + 0.01 * h * h)
            pi_ij = ((-alpha * 0.5 * (c[i] + c[j]) * mu_ij + beta * mu_ij * mu_ij)
                     / (0.5 * (rho[i] + rho[j])))
            t00 -= pi_ij
            t11 -= pi_ij
            px -= m[j] * pi_ij * gx
            py -= m[j] * pi_ij * gy
        ax += m[j] * (t00 * gx + t01 * gy)
        ay += m[j] * (t10 * gx + t11 * gy)
    return ax, ay, px, py


@njit(inline="always", **JIT)
def force_row(i, x, v, m, rho, sigma, R, indptr, indices, h, c, alpha, beta, n_as, w_dx, kf,
              reduce):
    """Eq. 1 for particle i in 3-D, returning (a_x, a_y, a_z) and its viscous part
    (a^Π_x, a^Π_y, a^Π_z) = −Σ_j m_j Π_ij ∇_i W_ij, m/s²:
    Σ_j m_j (σ_i/ρ_i² + σ_j/ρ_j² + f^n (R_i + R_j) − Π_ij I) ∇_i W_ij; with ``reduce`` each pair's
    kernel times min(kf_i, kf_j) (:func:`kernel_factors`). The sums are in registers, term by term
    as a loop over the components would add them."""
    ax = 0.0
    ay = 0.0
    az = 0.0
    px = 0.0
    py = 0.0
    pz = 0.0
    ri2 = 1.0 / (rho[i] * rho[i])
    s00, s01, s02 = sigma[i, 0, 0] * ri2, sigma[i, 0, 1] * ri2, sigma[i, 0, 2] * ri2
    s10, s11, s12 = sigma[i, 1, 0] * ri2, sigma[i, 1, 1] * ri2, sigma[i, 1, 2] * ri2
    s20, s21, s22 = sigma[i, 2, 0] * ri2, sigma[i, 2, 1] * ri2, sigma[i, 2, 2] * ri2
    xi0, xi1, xi2 = x[i, 0], x[i, 1], x[i, 2]
    vi0, vi1, vi2 = v[i, 0], v[i, 1], v[i, 2]
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        d0 = xi0 - x[j, 0]
        d1 = xi1 - x[j, 1]
        d2 = xi2 - x[j, 2]
        r2 = d0 * d0 + d1 * d1 + d2 * d2
        vr = (vi0 - v[j, 0]) * d0 + (vi1 - v[j, 1]) * d1 + (vi2 - v[j, 2]) * d2
        r = math.sqrt(r2)
        if r <= 0.0:
            continue
        g = m[j] * dw_dr(r, h, 0, 3) / r
        if reduce:
            g *= min(kf[i], kf[j])
        rj2 = 1.0 / (rho[j] * rho[j])
        t00 = s00 + sigma[j, 0, 0] * rj2
        t01 = s01 + sigma[j, 0, 1] * rj2
        t02 = s02 + sigma[j, 0, 2] * rj2
        t10 = s10 + sigma[j, 1, 0] * rj2
        t11 = s11 + sigma[j, 1, 1] * rj2
        t12 = s12 + sigma[j, 1, 2] * rj2
        t20 = s20 + sigma[j, 2, 0] * rj2
        t21 = s21 + sigma[j, 2, 1] * rj2
        t22 = s22 + sigma[j, 2, 2] * rj2
        if n_as > 0:
            f = (kernel_w(r, h, 0, 3) / w_dx) ** n_as
            t00 += f * (R[i, 0, 0] + R[j, 0, 0])
            t01 += f * (R[i, 0, 1] + R[j, 0, 1])
            t02 += f * (R[i, 0, 2] + R[j, 0, 2])
            t10 += f * (R[i, 1, 0] + R[j, 1, 0])
            t11 += f * (R[i, 1, 1] + R[j, 1, 1])
            t12 += f * (R[i, 1, 2] + R[j, 1, 2])
            t20 += f * (R[i, 2, 0] + R[j, 2, 0])
            t21 += f * (R[i, 2, 1] + R[j, 2, 1])
            t22 += f * (R[i, 2, 2] + R[j, 2, 2])
        pi_ij = 0.0
        if vr < 0.0 and (alpha > 0.0 or beta > 0.0):
            mu_ij = h * vr / (r2 + 0.01 * h * h)
            pi_ij = ((-alpha * 0.5 * (c[i] + c[j]) * mu_ij + beta * mu_ij * mu_ij)
                     / (0.5 * (rho[i] + rho[j])))
        ax += g * (t00 * d0 + t01 * d1 + t02 * d2 - pi_ij * d0)
        ay += g * (t10 * d0 + t11 * d1 + t12 * d2 - pi_ij * d1)
        az += g * (t20 * d0 + t21 * d1 + t22 * d2 - pi_ij * d2)
        px -= g * pi_ij * d0
        py -= g * pi_ij * d1
        pz -= g * pi_ij * d2
    return ax, ay, az, px, py, pz


def force_pass(x, v, m, rho, sigma, R, indptr, indices, h, c, alpha, beta, n_as, w_dx, a_ext,
               acc, fixed, v_fix, dt, damping, do_kick, kf=None, a_visc=None):
    """Step 4–5 (:func:`force_kernel`); ``kf`` (N,) or None as in :func:`rates_pass`; ``a_visc``
    (N, d) or None: where given, the viscous part of the accelerations, −Σ_j m_j Π_ij ∇_i W_ij,
    m/s², is written there. Returns the number of non-finite accelerations."""
    reduce = kf is not None
    track = a_visc is not None
    return force_kernel(x, v, m, rho, sigma, R, indptr, indices, h, c, alpha, beta, n_as, w_dx,
                        a_ext, acc, fixed, v_fix, dt, damping, do_kick,
                        kf if reduce else _NO_KF, reduce, a_visc if track else _NO_AV, track)


@njit(parallel=True, **JIT)
def force_kernel(x, v, m, rho, sigma, R, indptr, indices, h, c, alpha, beta, n_as, w_dx, a_ext,
                 acc, fixed, v_fix, dt, damping, do_kick, kf, reduce, a_visc, track):
    """Accelerations (N, d) into ``acc`` (eq. 1 plus a_ext (N, d), m/s²; c (N,) the particles'
    P-wave speeds, m/s), with ``track`` their viscous part into ``a_visc`` (N, d), and, with
    ``do_kick``, the closing half kick (step 4–5). The kick is a
    separate loop: the viscosity reads the neighbours' velocities, which must not be kicked while
    they are read. Returns the number of non-finite accelerations. The rows are those of
    ``indptr``; the neighbours' arrays may also hold ghosts (:mod:`sph.mirror`)."""
    N, d = indptr.shape[0] - 1, x.shape[1]
    bad = 0
    for i in prange(N):
        if d == 2:
            ax, ay, px, py = _force_row_2d(i, x, v, m, rho, sigma, R, indptr, indices, h, c,
                                           alpha, beta, n_as, w_dx, kf, reduce)
            acc[i, 0] = ax + a_ext[i, 0]
            acc[i, 1] = ay + a_ext[i, 1]
            if track:
                a_visc[i, 0] = px
                a_visc[i, 1] = py
        else:
            ax, ay, az, px, py, pz = force_row(i, x, v, m, rho, sigma, R, indptr, indices, h, c,
                                               alpha, beta, n_as, w_dx, kf, reduce)
            acc[i, 0] = ax + a_ext[i, 0]
            acc[i, 1] = ay + a_ext[i, 1]
            acc[i, 2] = az + a_ext[i, 2]
            if track:
                a_visc[i, 0] = px
                a_visc[i, 1] = py
                a_visc[i, 2] = pz
        ok = True
        for k in range(d):
            ok = ok and math.isfinite(acc[i, k])
        if not ok:
            bad += 1
    if do_kick:
        for i in prange(N):
            kick_row(i, v, acc, fixed, v_fix, dt, damping)
    return bad


def viscous_step_work(m, a_old, a_new, v_n, v_half, v_new, dt):
    """The work of the artificial viscosity's forces over one velocity-Verlet step, J (J/m in 2-D):
    each half kick changes the velocity by Δt/2 times the acceleration, so a force's part of the
    kinetic-energy change over it is Δt/2 · m a · (the mean of the velocities before and after):
    Δt/2 Σ m_i [a^Π_n · (v_n + v_n+½)/2 + a^Π_n+1 · (v_n+½ + v_n+1)/2] with the viscous parts
    a^Π = −Σ_j m_j Π_ij ∇_i W_ij of the force passes that made the two kicks. Without damping
    or held DOFs the kinetic energy changes by exactly the sum of these works over all forces. It is
    dissipative (Π_ij > 0 only for approaching pairs: Σ_i m_i a^Π_i · v_i ≤ 0 at the velocities Π
    was evaluated with) up to the change of the velocities within a half kick."""
    return 0.25 * dt * (float(np.einsum("i,ik,ik->", m, a_old, v_n + v_half))
                        + float(np.einsum("i,ik,ik->", m, a_new, v_half + v_new)))


# ================================================================================================
# A body
# ================================================================================================

class Body:
    """Particles, materials and options of a classic-SPH body; ``step`` advances it (Fig. 6 of 003).

    X (N, d) reference positions, m (d = 2: plane strain, or 3); V (N,) volumes, m^d; ``material``
    a :class:`~workbench.materials.Material` or a :class:`~workbench.materials.MaterialTable` with
    ``mat_id`` (N,) its row per particle (the particle's density ρ0, wave speed, λ and μ or law);
    dx spacing, m; options: ``h_ratio`` (h/Δx), ``stress`` ('hypoelastic' | 'hyperelastic'),
    ``alpha``, ``beta`` (artificial viscosity), ``artificial_stress`` (ε of Gray et al., 0 = off),
    ``n_as`` (exponent, 4); ``damping`` mass-proportional, 1/s; ``kernel_reduction``: the kernel
    reduction of 003 §4.2(2) across fully released mortar particles (:func:`kernel_factors`;
    needs ``stress='hyperelastic'``, the mortar's path); ``viscous_work``: the viscosity's
    dissipation into :attr:`viscous_work` (:func:`viscous_step_work`); ``skin``: the neighbour
    list's skin, × Δx (:meth:`_refresh_neighbours`; 0: searched every step); ``cracks`` (K, d, d)
    or None: pre-crack facets — no pair whose *reference* segment X_a–X_b crosses one
    interacts, at every search (:func:`sph.neighbours.cut_pairs`)."""

    def __init__(self, X, V, material, dx, h_ratio=1.3, stress="hypoelastic", alpha=1.0, beta=1.0,
                 artificial_stress=0.0, n_as=4, fixed=None, v0=None, body=None, mat_id=None,
                 viscous_work=False, kernel_reduction=False, mirrors=(), skin=0.1, cracks=None):
        if stress not in STRESS_LAWS:
            raise ValueError(f"stress: {stress!r} is not one of {STRESS_LAWS}")
        if not (isinstance(h_ratio, (int, float)) and 0.5 <= h_ratio <= 3.0):
            raise ValueError(f"h_ratio: {h_ratio!r} is not allowed; h/Δx must lie in [0.5, 3]")
        if not (alpha >= 0 and beta >= 0):
            raise ValueError("alpha, beta: artificial-viscosity coefficients must be >= 0")
        if not (isinstance(skin, (int, float)) and 0 <= skin <= 1):
            raise ValueError(f"skin: {skin!r} is not allowed; the neighbour list's skin must lie in "
                             "[0, 1] (× Δx; 0: rebuilt every step)")
        if not (0 <= artificial_stress <= 1):
            raise ValueError(f"artificial_stress: {artificial_stress!r} is not allowed; ε must lie "
                             "in [0, 1]")
        table = MaterialTable.of(material)
        if kernel_reduction and stress != "hyperelastic":
            raise ValueError("kernel_reduction: True needs stress='hyperelastic' (the mortar's "
                             "history); allowed: False, or True with the hyperelastic stress")
        if stress == "hypoelastic":
            for mt in table.materials:
                if mt.law not in HYPOELASTIC_LAWS:
                    raise ValueError(f"stress: 'hypoelastic' uses the small-strain λ, μ of an "
                                     f"elastic law; law {mt.law!r} needs stress='hyperelastic'")
        self.X = np.ascontiguousarray(X, dtype=np.float64)
        N, d = self.X.shape
        if d not in (2, 3):
            raise ValueError(f"X: {d}-D positions are not allowed; 2-D (plane strain) or 3-D")
        self.table = table
        self.mat_id = (np.zeros(N, np.int64) if mat_id is None
                       else np.ascontiguousarray(mat_id, dtype=np.int64))
        mid = self.mat_id
        if mid.shape != (N,) or (N and not (0 <= mid.min() and mid.max() < len(table))):
            raise ValueError(f"mat_id: not allowed; must be ({N},) integers in [0, {len(table)}) "
                             "(rows of the material table)")
        mats = table.materials
        row = self.mat_id
        self.dx = float(dx)
        self.h = h_ratio * dx
        self.rho0 = np.array([mt.rho for mt in mats])[row]
        self.lam = np.ascontiguousarray(np.array([mt.lam for mt in mats])[row])
        self.mu = np.ascontiguousarray(np.array([mt.mu for mt in mats])[row])
        self.c = np.ascontiguousarray(np.array([mt.wave_speed("strain") for mt in mats])[row])
        self.V0 = np.asarray(V, dtype=np.float64)
        self.m = self.rho0 * self.V0
        self.hyper = stress == "hyperelastic"
        self.alpha, self.beta = float(alpha), float(beta)
        self.eps_as = float(artificial_stress)
        self.n_as = int(n_as) if artificial_stress > 0 else 0
        self.w_dx = kernel_w(self.dx, self.h, 0, d)
        self.c0 = float(self.c.max())
        self.prm = table.params()
        self.x = self.X.copy()
        self.v = np.zeros((N, d)) if v0 is None else np.array(v0, dtype=np.float64)
        self.acc = np.zeros((N, d))
        self.rho = self.rho0.copy()
        self.rho_new = self.rho0.copy()
        self.sigma = np.zeros((N, 3, 3))
        self.F = np.tile(np.eye(3), (N, 1, 1))
        self.hist = table.initial_history(self.mat_id)
        self.hist_new = self.hist.copy()
        self.status = np.zeros(N, np.int64)
        self.fixed = (np.zeros((N, d), np.uint8) if fixed is None
                      else np.ascontiguousarray(fixed, np.uint8))
        self.v_fix = np.zeros((N, d))
        self.a_ext = np.zeros((N, d))
        self.damping = 0.0
        self.t = 0.0
        self.steps = 0
        self.R = np.zeros((N, d, d))
        self.extra_force = None  # callable(body) -> (N, d) forces, e.g. contact between bodies
        self.track_viscous = bool(viscous_work) and (self.alpha > 0 or self.beta > 0)
        self.viscous_work = 0.0  # energy dissipated by the artificial viscosity so far, J
        # the viscous part of the accelerations (the force pass's; swapped every step)
        self.a_visc = np.zeros((N, d)) if self.track_viscous else None
        self._a_visc_new = np.zeros((N, d)) if self.track_viscous else None
        self.impulse = None  # (N, d) or None: the impulse of the force on each fixed DOF is added
        self.body = None if body is None else np.asarray(body, dtype=np.int64)
        self.kf = np.ones(N) if kernel_reduction else None  # the kernel factors, or None: off
        self.mirrors = tuple((int(a), float(at)) for a, at, *_ in mirrors)
        self._on = on_planes(self.X, self.mirrors, 1e-6 * self.dx)
        self.m_full = self.m / 0.5 ** self._on.sum(axis=1)  # a plane particle's whole mass
        self._ghosts = None
        self.skin = float(skin) * self.dx
        self.cracks = None if cracks is None or not len(cracks) else np.ascontiguousarray(cracks)
        self._x_listed = None  # positions at the last neighbour search
        self.searches = 0  # neighbour searches so far
        self._accelerations(0.0, kick=False)

    @property
    def n(self) -> int:
        return self.X.shape[0]

    @property
    def dim(self) -> int:
        return self.X.shape[1]

    def _neighbours(self, x, reach):
        """The shared cell list at the positions x within ``reach`` (m); particles of different
        bodies (``body`` labels) do not interact through the kernel (they meet through contact
        only). With symmetry planes the ghosts of :meth:`_find_ghosts` are among the neighbours
        (their indices ≥ N; the rows are the particles')."""
        N = self.n
        body = self.body
        if self.mirrors:
            self._find_ghosts(x, reach)
            src = self._ghosts[0]
            x = np.concatenate([x, self._ghosts[1] * x[src] + self._ghosts[2]])
            if body is not None:
                body = np.concatenate([body, body[src]])
        cut = None
        if self.cracks is not None:  # the pairs' reference segments (ghosts: mirrored)
            X = self.X
            if self.mirrors:
                X = np.concatenate([X, self._ghosts[1] * X[src] + self._ghosts[2]])
            cut = (X, self.cracks)
        indptr, indices = neighbour_list(x, reach, body, cut)
        if self.mirrors:
            indptr, indices = indptr[:N + 1], indices[:indptr[N]]
        return indptr, indices

    def _refresh_neighbours(self):
        """Step 2: the neighbour list (``indptr``, ``indices``) of the current positions. It is
        searched within 2h + ``skin`` and searched again only once a particle has moved more than
        half the skin since: until then no pair outside the list can have come within 2h (each of
        the two moved at most skin/2), and the listed pairs beyond 2h add exact zeros (the kernel
        vanishes there), so every step sees the pairs of Fig. 6's search of its own positions
        (``skin`` 0: searched every step)."""
        if (self._x_listed is None or self.skin == 0.0
                or max_displacement(self.x, self._x_listed) > 0.5 * self.skin):
            self.indptr, self.indices = self._neighbours(self.x, SUPPORT * self.h + self.skin)
            self._x_listed = self.x.copy()
            self.searches += 1

    def _find_ghosts(self, x, reach):
        """Mirror images (:mod:`sph.mirror`) of the particles within ``reach`` (the kernel support
        2h and the list's skin) of every plane of a combination of the symmetry planes, at the
        positions x (a plane particle is its own image in its plane): (src, sign, offset) into
        ``_ghosts``."""
        near = np.abs(x[:, [a for a, _ in self.mirrors]] - [at for _, at in self.mirrors]) <= reach
        self._ghosts = plane_images(x, self.mirrors, self._on, near)
        src = self._ghosts[0]  # what does not change until the next search
        self._ghost_m = with_images(self.m_full, src)
        self._ghost_c = with_images(self.c, src)

    def _extended(self, x, v, rho, sigma, R):
        """The arrays the neighbours are read from: the particles' (masses the full body's, for a
        plane particle its whole mass) and their ghosts' (mirrored: x, v by sign and offset, σ and
        R by R = diag(sign) on both sides). Without symmetry planes, the particles' own."""
        if not self.mirrors:
            return x, v, self.m, rho, sigma, R, self.c, self.kf
        src, sg, of = self._ghosts
        kf = None if self.kf is None else with_images(self.kf, src)
        return (with_images(x, src, sg, of), with_images(v, src, sg), self._ghost_m,
                with_images(rho, src), with_images(sigma, src, sg), with_images(R, src, sg),
                self._ghost_c, kf)

    def _a_ext(self):
        if self.extra_force is None:
            return self.a_ext
        return self.a_ext + self.extra_force(self) / self.m[:, None]

    def _accelerations(self, dt, kick):
        self._refresh_neighbours()
        if self.kf is not None:
            kernel_factors(self.table, self.mat_id, self.hist, self.kf)
        return self._force_pass(self._a_ext(), self.acc, dt, kick, self.a_visc)

    def _force_pass(self, a_ext, acc, dt, kick, a_visc=None):
        """:func:`force_pass` at the current state, the ghosts of the symmetry planes included
        (their velocities are a copy: the kick is carried back to the particles); ``a_visc``
        (N, d) or None: the viscous part of the accelerations into it."""
        x, v, m, rho, sigma, R, c, kf = self._extended(self.x, self.v, self.rho, self.sigma, self.R)
        bad = force_pass(x, v, m, rho, sigma, R, self.indptr, self.indices, self.h, c, self.alpha,
                         self.beta, self.n_as, self.w_dx, a_ext, acc, self.fixed, self.v_fix, dt,
                         self.damping, kick, kf, a_visc)
        if kick and v is not self.v:
            self.v[:] = v[:self.n]
        return bad

    def step(self, dt: float, n: int = 1) -> int:
        """``n`` steps of size dt; returns the steps completed (fewer if the state became
        non-finite or a material point failed). With ``impulse`` (N, d) set, the trapezoid impulse
        ½ (f_n + f_n+1) dt of the force on each fixed DOF is added to it; with ``viscous_work``,
        the energy the artificial viscosity dissipates, minus the work of its forces over the step
        (:func:`viscous_step_work`), is added to :attr:`viscous_work`."""
        fx = np.flatnonzero(self.fixed.ravel()) if self.impulse is not None else None
        if fx is not None and fx.size == 0:
            fx = None
        if fx is not None:
            m_fx = self.m[fx // self.acc.shape[1]]
        track = self.track_viscous
        for s in range(n):
            f_old = self.acc.ravel()[fx] * m_fx if fx is not None else None
            v_n = self.v.copy() if track else None
            kick_drift(self.x, self.v, self.acc, self.fixed, self.v_fix, dt, self.damping)
            v_h = self.v.copy() if track else None
            self._refresh_neighbours()
            x, v, m, rho, _, _, _, kf = self._extended(self.x, self.v, self.rho, self.sigma,
                                                       self.R)
            rates_pass(x, v, m, rho, self.rho_new, self.sigma, self.F,
                       self.indptr, self.indices, self.h, dt, self.lam, self.mu, self.hyper,
                       self.prm, self.mat_id, self.hist, self.hist_new, self.eps_as, self.status,
                       self.R, kf)
            self.rho, self.rho_new = self.rho_new, self.rho
            if self.hist.shape[1]:
                self.hist, self.hist_new = self.hist_new, self.hist
            if self.kf is not None:  # the particles released by this step's history
                kernel_factors(self.table, self.mat_id, self.hist, self.kf)
            bad = self._force_pass(self._a_ext(), self.acc, dt, True,
                                   self._a_visc_new if track else None)
            if fx is not None:
                self.impulse.ravel()[fx] += 0.5 * dt * (f_old + self.acc.ravel()[fx] * m_fx)
            if track:
                self.viscous_work -= viscous_step_work(self.m, self.a_visc, self._a_visc_new,
                                                       v_n, v_h, self.v, dt)
                self.a_visc, self._a_visc_new = self._a_visc_new, self.a_visc
            self.t += dt
            self.steps += 1
            if bad or self.status.any() or not np.isfinite(self.x).all():
                return s + 1
        return n

    def forces(self) -> np.ndarray:
        """Particle forces m a (N, d) of the current state (no external load), N."""
        acc = np.zeros_like(self.acc)
        self._refresh_neighbours()
        self._force_pass(np.zeros_like(self.acc), acc, 0.0, False)
        return acc * self.m[:, None]

    def energies(self) -> tuple[float, float]:
        """(kinetic, stored) energy, J (J per unit thickness in 2-D). Stored energy: hyperelastic,
        Σ V0 ψ(F) by the shared diagnostics; hypoelastic, the linear-elastic complementary energy
        Σ (m/ρ) ½ σ : C⁻¹ : σ = Σ (m/ρ) [σ:σ − λ/(3λ + 2μ) (tr σ)²]/(4μ) with each particle's λ, μ
        (plane strain: σ_zz included)."""
        ke = 0.5 * float(np.sum(self.m[:, None] * self.v * self.v))
        if self.hyper:
            from .diagnostics import strain_energy

            return ke, strain_energy(np.ascontiguousarray(self.F), self.V0, self.prm, self.mat_id,
                                   history=self.hist)
        s = self.sigma
        tr = s[:, 0, 0] + s[:, 1, 1] + s[:, 2, 2]
        ss = np.einsum("nij,nij->n", s, s)
        lam, mu = self.lam, self.mu
        w = (ss - lam / (3 * lam + 2 * mu) * tr * tr) / (4 * mu)
        return ke, float(np.sum(self.m / self.rho * w))

    def time_step(self, dt_factor: float) -> float:
        """dt = dt_factor · Δx / c, c the fastest P-wave speed of the body's materials, s."""
        return cfl_time_step(self.dx, self.c0, dt_factor)


NAME = "sph"
DISORDER = 0.15
"""The η₉₅ limit (:mod:`sph.monitor`) every explicit run of classic SPH on elastic materials is
monitored with unless its drive sets one (``disorder``; ``math.inf``: off). The method's known
failure — particle disorder: the kink that folds a clamped beam at its root, rows pairing under
tension or compression — keeps the energy balance, so the energy criterion does not see it. 0.15
is the stability scenes' limit (:data:`workbench.scenes.stability.DISORDER_TOL`). Measured (issue
40): a smooth bending gives η₉₅ ≲ 0.02 (the swinging beam of L/H = 8 at H/Δx = 8: ≤ 0.017, the
plate at H/Δx = 5: 0.044); the swinging beam of L/H = 20 at H/Δx = 8 folds at its root and passes
0.15 at t ≈ 0.14 s, reaching 0.5; the plate at H/Δx = 10 (cell lattice) pairs its second row
from the lower surface (η ≈ 0.2 along it, lasting) and stops at t = 0.061 s. A material that
yields or fails (a history: J2, mortar) disorders by fracturing, which is its result: not
monitored by default."""
OPTIONS = dict(h_ratio="h/Δx (default 1.3)", stress="'hypoelastic' (default) | 'hyperelastic'",
               alpha="Monaghan viscosity α (default 1)", beta="Monaghan viscosity β (default 1)",
               artificial_stress="Gray et al.'s ε in [0, 1] (default 0: off)",
               viscous_work="track the energy the artificial viscosity dissipates, the work of "
                            "its forces over each step (default False)",
               kernel_reduction="003 4.2(2): kernels across fully released mortar particles x "
                                "phi_min (default False; needs stress='hyperelastic')",
               mirror="'auto' (default: the scene's symmetry planes by mirror images found "
                      "with the neighbours, sph.mirror) | 'none' (a one-sided stencil at a symmetry plane)",
               skin="the neighbour list's skin in [0, 1] x dx (default 0.1: searched again once a "
                    "particle has moved skin/2, the same pairs as every step's search; 0: "
                    "searched every step)")


class Classic(ParticleBody):
    """A classic-SPH body built from :class:`sph.particles.Particles`: 2-D plane strain or 3-D, a
    row of the particles' material table per particle."""

    name = NAME
    impulse_in_loop = True

    def __init__(self, particles, h_ratio: float = 1.3, stress: str = "hypoelastic",
                 alpha: float = 1.0, beta: float = 1.0, artificial_stress: float = 0.0,
                 n_as: int = 4, viscous_work: bool = False, kernel_reduction: bool = False,
                 mirror: str = "auto", skin: float = 0.1):
        super().__init__(particles)
        ps = particles
        if mirror not in ("auto", "none"):
            raise ValueError(f"mirror: {mirror!r} is not one of 'auto', 'none'")
        if ps.plane == "stress":
            raise ValueError("plane: 'stress' is not modelled by sph (plane strain: L_zz = 0); "
                             "allowed: 'strain' or a 3-D model")
        self.b = Body(ps.X, ps.V, ps.table, ps.dx, h_ratio, stress, alpha, beta,
                      artificial_stress, n_as, body=ps.body if len(ps.body_names) > 1 else None,
                      mat_id=ps.mat_id, viscous_work=viscous_work,
                      kernel_reduction=kernel_reduction,
                      mirrors=ps.mirrors if mirror == "auto" else (), skin=skin,
                      cracks=ps.cracks)
        self.b.impulse = self.impulse
        if ps.failed is not None and ps.failed.any():  # the scene's failed regions
            self.b.hist[:] = ps.initial_history()
            self.b.hist_new[:] = self.b.hist
        self.m = self.b.m
        self.x, self.v, self.acc = self.b.x, self.b.v, self.b.acc

    def _set_loads(self, f_ext, fixed=None, v_fix=None, extra=None, damping=0.0):
        b = self.b
        b.a_ext = f_ext / self.m[:, None]
        if fixed is not None:
            b.fixed[:] = fixed
            b.v_fix[:] = v_fix
        b.damping = float(damping)
        b.extra_force = None if extra is None else (lambda bb: extra(bb.x))

    def start(self, v0, f_ext, extra=None) -> None:
        self.v[:] = v0
        self._set_loads(f_ext, extra=extra)
        self.b._accelerations(0.0, kick=False)

    def advance(self, n, dt, f_ext, fixed, v_fix, damping=0.0, extra=None) -> int:
        if not (damping >= 0 and math.isfinite(damping)):
            raise ValueError(f"damping: {damping!r} is not allowed; mass damping must be >= 0 "
                             "(1/s)")
        self._set_loads(f_ext, fixed, v_fix, extra, damping)
        done = self.b.step(dt, n)
        self.t, self.steps = self.b.t, self.b.steps
        self.x, self.v, self.acc = self.b.x, self.b.v, self.b.acc
        return done

    def time_step(self, dt_factor: float) -> float:
        return self.b.time_step(dt_factor)

    def energies(self) -> tuple[float, float]:
        return self.b.energies()

    def failed(self) -> bool:
        return bool(self.b.status.any())

    def dissipated(self) -> dict:
        """``plastic_work`` and ``released_energy``, J (the history columns of J2 and the mortar,
        :func:`sph.diagnostics.dissipated_work`, times the reference volumes, the volumes of the
        stored energy), and with the option ``viscous_work`` the energy dissipated by the
        artificial viscosity under the same name, ``viscous_work``, J."""
        from .diagnostics import dissipated_work

        b = self.b
        out = dissipated_work(b.table, b.mat_id, b.hist, b.V0) if self.b.hyper else {}
        if b.track_viscous:
            out["viscous_work"] = b.viscous_work
        return out

    def field_state(self) -> dict:
        b = self.b
        return dict(t=b.t, x=b.x, v=b.v, sigma=b.sigma, history=b.hist, J=b.rho0 / b.rho,
                    mat_id=self.particles.mat_id, region=self.particles.region)


def build(particles, **options) -> Classic:
    """A classic-SPH body of ``particles``; options: ``OPTIONS``."""
    return Classic(particles, **options)
