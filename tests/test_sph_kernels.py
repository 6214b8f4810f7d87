"""Kernel checks: normalisation, derivative, discrete moments on a lattice (partition of unity,
zero gradient sum, first moment = identity)."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from sph import kernels, particles
from sph.neighbours import neighbour_list

KERNELS = ["cubic_spline", "wendland_c2"]


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("dim", [2, 3])
def test_normalised(kernel, dim):
    # ∫ W dV = 1: radial quadrature to 1e-10 (the integrand is a piecewise polynomial)
    k, h = kernels.kernel_code(kernel), 0.7
    shell = (lambda r: 2 * math.pi * r) if dim == 2 else (lambda r: 4 * math.pi * r * r)
    val, _ = quad(lambda r: shell(r) * kernels.w(r, h, k, dim), 0, 2 * h, points=[h], epsabs=1e-13)
    assert abs(val - 1) < 1e-10, val


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("dim", [2, 3])
def test_derivative_matches_finite_difference(kernel, dim):
    k, h, e = kernels.kernel_code(kernel), 1.3, 1e-6
    for r in np.linspace(0.05, 2.55, 23):
        fd = (kernels.w(r + e, h, k, dim) - kernels.w(r - e, h, k, dim)) / (2 * e)
        assert abs(kernels.dw_dr(r, h, k, dim) - fd) < 1e-7 * kernels.sigma(k, dim, h) / h
    assert kernels.w(2 * h, h, k, dim) == 0.0 and kernels.dw_dr(2 * h, h, k, dim) == 0.0


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("dim", [2, 3])
def test_discrete_moments_on_lattice(kernel, dim):
    """Interior particle of a unit lattice with h/Δx = 1.3: Σ V W ≈ 1 (partition of unity, to the
    lattice quadrature error: up to 1 % at this h/Δx), Σ V ∇W = 0 by symmetry (round-off),
    Σ V (X_b − X_a) ⊗ ∇W_b(X_a) ≈ I (first moment, the quantity eq. 31 corrects; the uncorrected lattice sum is off by up to 2.6 %, hence 3 %)."""
    k, n = kernels.kernel_code(kernel), 8
    X, V = particles.box((0,) * dim, (n,) * dim, 1.0, "cell")
    h = 1.3
    indptr, indices = neighbour_list(X, 2 * h)
    a = int(np.argmin(np.linalg.norm(X - n / 2 + 0.5, axis=1)))
    nb = indices[indptr[a]:indptr[a + 1]]
    r = np.linalg.norm(X[nb] - X[a], axis=1)
    s0 = V[a] * kernels.w(0.0, h, k, dim) + sum(V[b] * kernels.w(q, h, k, dim) for b, q in zip(nb, r))
    g = np.array([kernels.dw_dr(q, h, k, dim) / q * (X[a] - X[b]) for b, q in zip(nb, r)])
    assert abs(s0 - 1) < 1.5e-2, s0
    assert np.abs((V[nb, None] * g).sum(0)).max() < 1e-12
    M = np.einsum("b,bi,bj->ij", V[nb], X[nb] - X[a], g)
    assert np.allclose(M, np.eye(dim), atol=3e-2), M


def test_unknown_kernel_is_a_clear_error():
    with pytest.raises(ValueError, match="kernel"):
        kernels.kernel_code("gaussian")
