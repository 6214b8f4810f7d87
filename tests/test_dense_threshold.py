"""The Newton system of a particle body is solved dense only where that is faster (issue 40.5):
the threshold :data:`sph.static.DENSE_BELOW` was measured on csph tangents (its docstring has the
table: the dense LU loses from ~400 unknowns in 2-D and ~1200 in 3-D; at 3000, 13x slower)."""
import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp

from sph import static


def tangent_like(n: int, band: int = 30) -> sp.csr_matrix:
    """A symmetric positive definite banded matrix of n unknowns (a particle tangent's pattern)."""
    rng = np.random.default_rng(0)
    A = sp.random(n, n, density=min(1.0, band / n), random_state=rng)
    return (A + A.T + sp.identity(n) * (2 * band + 1)).tocsr()


@pytest.mark.parametrize("dim,n", [(2, 1000), (2, 2538), (3, 2000)])
def test_above_the_measured_crossover_the_solve_is_sparse(dim, n, monkeypatch):
    def dense(*a, **k):
        raise AssertionError("dense LU above the measured crossover")

    monkeypatch.setattr(scipy.linalg, "solve", dense)
    K = tangent_like(n)
    b = np.ones(n)
    x = static.solve_linear(K, b, dim=dim)
    assert np.linalg.norm(K @ x - b) <= 1e-10 * np.linalg.norm(b)


@pytest.mark.parametrize("dim,n", [(2, 200), (3, 600)])
def test_below_it_dense(dim, n, monkeypatch):
    called = []
    real = scipy.linalg.solve
    monkeypatch.setattr(scipy.linalg, "solve", lambda *a, **k: called.append(1) or real(*a, **k))
    K = tangent_like(n)
    x = static.solve_linear(K, np.ones(n), dim=dim)
    assert called and np.allclose(K @ x, 1.0)
