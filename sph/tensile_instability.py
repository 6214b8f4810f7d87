"""The tensile instability predicted per particle: Swegle, Hicks & Attaway (1995) for the Eulerian
kernel of classic SPH (:mod:`sph.classic`), and the same stress term for a total-Lagrangian body.

**Eulerian kernel (classic SPH, 003 eq. 1).** a_i = Σ_j m_j S_ij ∇_i W(x_i − x_j),
S_ij = σ_i/ρ_i² + σ_j/ρ_j². Perturb the positions by a particle-scale wave and hold the stresses
(the zig-zag leaves SPH's velocity gradient, eq. 3, unchanged at the nearest neighbours: the
constitutive response does not see it, which is Swegle's point); the acceleration changes by

    δa_i = Σ_j m_j S_ij H(x_ij) (δx_i − δx_j),   H(r) = W''(r) n⊗n + (W'(r)/r)(I − n⊗n),

H the Hessian of the kernel, n = x_ij/r. For the longitudinal wave δx_j = cos(k·(x_j − x_i)) e
along a unit direction e with k = (π/Δx) e (the shortest wave of the lattice), δa_i = λ_i(e) δx_i,

    λ_i(e) = e · [Σ_j m_j S_ij H(x_ij) (1 − cos(k·x_ij))] e    (1/s², :func:`swegle_rate`),

and the wave grows as exp(√λ t) where λ > 0: the particle is **predicted unstable**. In 1-D with
the nearest neighbours at r = Δx (1 − cos π = 2) this is λ = 4 m (2σ/ρ²) W''(Δx), i.e.
Swegle's condition σ·W''(r) > 0 (σ > 0 tension): tension beyond the kernel's inflection point
(for the cubic spline W'' > 0 for q = r/h > 2/3, so h = 1.3Δx puts the nearest neighbours at
q = 0.77: unstable in tension), compression inside it. We take e along each principal direction of
σ_i (in-plane in 2-D) and report the largest λ (:func:`swegle_rates`).

**Total Lagrangian (csph, hpm).** The kernel is evaluated at the reference positions, so its
Hessian never enters: the stress term of the force is the geometric stiffness of the stored energy
Π = Σ_a V_a ψ(F_a), F_a = Σ_b (x_b − x_a) ⊗ G_ab, whose second variation along a mode u is
Σ_a V_a tr(δF_a S_a δF_aᵀ) (S the second Piola–Kirchhoff stress). For the same wave centred at
particle a (u_b = cos(k·X_ab) e), −V_a tr(δF_a S_a δF_aᵀ)/m_a (:func:`lagrangian_rates`) is the
counterpart of λ: it is ≤ 0 wherever S_a is positive semi-definite (tension), so no tensile
instability is predicted — the stress term stabilises, as in the continuum.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .kernels import JIT, dw_dr, kernel_code
from .kernels import sigma as kernel_sigma


@njit(**JIT)
def d2w_dr2(r: float, h: float, kind: int, dim: int) -> float:
    """Second radial derivative W''(r) of the kernel ``kind`` (:mod:`sph.kernels`), 1/m^(dim+2):
    cubic spline σ_d/h² (−3 + 9/2 q) for q < 1, σ_d/h² · 3/2 (2 − q) for 1 ≤ q < 2; Wendland C2
    σ_d/h² (1 − q/2)² (10q − 5) (2-D, 3-D). Zero beyond 2h."""
    q = r / h
    if q >= 2.0:
        return 0.0
    s = kernel_sigma(kind, dim, h) / (h * h)
    if kind == 0:
        if q < 1.0:
            return s * (-3.0 + 4.5 * q)
        return s * 1.5 * (2.0 - q)
    t = 1.0 - 0.5 * q
    return s * t * t * (10.0 * q - 5.0)


@njit(inline="always", **JIT)
def swegle_rate(i, e, kwave, x, sigma, rho, m, h, kind, indptr, indices):
    """λ_i(e) of the module docstring for particle i and unit direction e (d,), wave number
    ``kwave`` = π/Δx, 1/m; x (N, d) m, sigma (N, 3, 3) Pa, rho (N,) kg/m³ (kg/m^d), m (N,) kg
    (kg/m in 2-D). Returns 1/s²."""
    d = x.shape[1]
    lam = 0.0
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        r2 = 0.0
        kx = 0.0
        ne = 0.0
        for k in range(d):
            xij = x[i, k] - x[j, k]
            r2 += xij * xij
            kx += kwave * e[k] * xij
        r = math.sqrt(r2)
        if r <= 0.0:
            continue
        for k in range(d):
            ne += e[k] * (x[i, k] - x[j, k]) / r
        w2 = d2w_dr2(r, h, kind, d)
        w1r = dw_dr(r, h, kind, d) / r
        # e · S H e, H e = W'' (n·e) n + W'/r (e − (n·e) n)
        he = np.empty(d)
        for k in range(d):
            nk = (x[i, k] - x[j, k]) / r
            he[k] = w2 * ne * nk + w1r * (e[k] - ne * nk)
        s = 0.0
        ri = 1.0 / (rho[i] * rho[i])
        rj = 1.0 / (rho[j] * rho[j])
        for k in range(d):
            for l in range(d):
                s += e[k] * (sigma[i, k, l] * ri + sigma[j, k, l] * rj) * he[l]
        lam += m[j] * s * (1.0 - math.cos(kx))
    return lam


@njit(parallel=True, **JIT)
def _swegle_rates(x, sigma, rho, m, h, kind, dx, indptr, indices, lam, direction):
    N, d = x.shape
    kwave = math.pi / dx
    for i in prange(N):
        S = np.empty((d, d))
        for k in range(d):
            for l in range(d):
                S[k, l] = 0.5 * (sigma[i, k, l] + sigma[i, l, k])
        _, vecs = np.linalg.eigh(S)
        best = -np.inf
        for c in range(d):
            e = np.ascontiguousarray(vecs[:, c])
            val = swegle_rate(i, e, kwave, x, sigma, rho, m, h, kind, indptr, indices)
            if val > best:
                best = val
                for k in range(d):
                    direction[i, k] = e[k]
        lam[i] = best


def swegle_rates(x, sigma, rho, m, h: float, dx: float, indptr, indices,
                 kernel: str = "cubic_spline") -> tuple[np.ndarray, np.ndarray]:
    """Swegle's tensile-instability indicator of the module docstring for every particle of a
    classic-SPH state: (λ (N,) 1/s², the largest λ_i(e) over the principal directions e of σ_i;
    e (N, d) that direction). x (N, d) current positions, m; sigma (N, 3, 3) Cauchy stress, Pa
    (tension positive); rho (N,) current densities; m (N,) masses; h the smoothing length, dx the
    spacing, m; CSR neighbours (indptr, indices) of x within the support 2h. λ > 0: predicted
    unstable, growth rate √λ (1/s)."""
    if not (h > 0 and dx > 0):
        raise ValueError(f"h, dx: must be > 0 (got {h}, {dx})")
    x = np.ascontiguousarray(x, dtype=np.float64)
    N, d = x.shape
    lam = np.zeros(N)
    direction = np.zeros((N, d))
    _swegle_rates(x, np.ascontiguousarray(sigma, dtype=np.float64),
                  np.ascontiguousarray(rho, dtype=np.float64),
                  np.ascontiguousarray(m, dtype=np.float64), float(h), kernel_code(kernel),
                  float(dx), indptr, indices, lam, direction)
    return lam, direction


def classic_rates(body) -> tuple[np.ndarray, np.ndarray]:
    """:func:`swegle_rates` of a classic-SPH body (:class:`sph.classic.Classic` or its
    :class:`sph.classic.Body`) in its current state."""
    b = getattr(body, "b", body)
    return swegle_rates(b.x, b.sigma, b.rho, b.m, b.h, b.dx, b.indptr, b.indices)


@njit(parallel=True, **JIT)
def _lagrangian_rates(X, indptr, indices, G, V, m, S, dx, lam):
    N, d = X.shape
    kwave = math.pi / dx
    for a in prange(N):
        Sa = np.empty((d, d))
        for k in range(d):
            for l in range(d):
                Sa[k, l] = 0.5 * (S[a, k, l] + S[a, l, k])
        _, vecs = np.linalg.eigh(Sa)
        best = -np.inf
        for c in range(d):
            e = vecs[:, c]
            # δF = Σ_b (u_b − u_a) ⊗ G_ab = e ⊗ g, g = Σ_b (cos(k·X_ab) − 1) G_ab
            g = np.zeros(d)
            for p in range(indptr[a], indptr[a + 1]):
                b = indices[p]
                kx = 0.0
                for k in range(d):
                    kx += kwave * e[k] * (X[b, k] - X[a, k])
                f = math.cos(kx) - 1.0
                for k in range(d):
                    g[k] += f * G[p, k]
            # tr(δF S δFᵀ) = |e|² gᵀ S g
            q = 0.0
            for k in range(d):
                for l in range(d):
                    q += g[k] * Sa[k, l] * g[l]
            val = -V[a] * q / m[a] if m[a] > 0 else 0.0
            if val > best:
                best = val
        lam[a] = best


def lagrangian_rates(disc, S, dx: float) -> np.ndarray:
    """The total-Lagrangian counterpart of :func:`swegle_rates` (module docstring), (N,) 1/s²:
    −V_a tr(δF_a S_a δF_aᵀ)/m_a for the wave u_b = cos(k·X_ab) e, k = π/Δx e, e the principal
    directions of S_a, the largest. ``disc`` a :class:`sph.total_lagrangian.Discretisation` (X, V,
    m, CSR pairs, gradients G); S (N, 3, 3) the second Piola–Kirchhoff stress, Pa. ≤ 0 wherever S
    is positive semi-definite: no tensile instability. dx the spacing, m."""
    if not dx > 0:
        raise ValueError(f"dx: {dx!r} is not allowed; the spacing must be > 0")
    if disc.n_ghost:
        raise ValueError("disc: mirror images (symmetry planes) are not allowed here; build the "
                         "body with mirror='none'")
    N, d = disc.X.shape
    S = np.ascontiguousarray(np.asarray(S, dtype=np.float64)[:, :d, :d])
    X = np.ascontiguousarray(disc.X)
    lam = np.zeros(N)
    _lagrangian_rates(X, disc.indptr, disc.indices, np.ascontiguousarray(disc.G),
                      np.ascontiguousarray(disc.V), np.ascontiguousarray(disc.m), S, float(dx), lam)
    return lam
