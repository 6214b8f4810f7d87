"""Modal analysis: the lowest eigenpairs of K₀ φ = ω² M φ, the problem linearised about the
reference state (K₀ the tangent at F = I, M the consistent mass with each element's density), by
scipy's shift-invert Lanczos with the shift σ = 0 given explicitly."""
from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from .static import Problem


def lowest_modes(problem: Problem, k: int = 3):
    """ω (k,) rad/s ascending and the mode shapes (N, k) (zero on the fixed DOFs)."""
    disc = problem.disc
    st = problem.initial_state()
    pt = problem.evaluate(st.u, st, tangent=True)
    K0 = problem.tangent(pt).tocsc()
    M = problem.mass()[disc.free][:, disc.free].tocsc()
    lam, phi = spla.eigsh(K0, k=k, M=M, sigma=0.0, which="LM")
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    shapes = np.zeros((disc.N, k))
    shapes[disc.free] = phi
    return np.sqrt(lam), shapes
