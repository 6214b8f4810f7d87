"""Functions of symmetric 3×3 matrices in the J2 kernel against numpy.linalg.eigh (LAPACK): the
closed-form eigen-decomposition :func:`kernels.eigh3` on random matrices and the hard cases (exactly
and nearly repeated eigenvalues, pairs and triples, diagonal matrices, extreme scales, the
near-identity elastic b_e of metals); the matrix logarithm and exponential (series near I, spectral
beyond) on both sides of their switch; and the J2 point on both sides of it and at a trial b_e with
a nearly repeated eigenvalue."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workbench.materials import TABLE1_STEEL, kernels

EPS = np.finfo(float).eps
# Both solvers are backward stable: each entry of V diag(x) Vᵀ sums three products of values that
# each carry a few roundings (≈ 8 eps of max|S| in all); 24 eps is three times that.
TOL_BACKWARD = 24 * EPS
TOL_ORTHO = 24 * EPS  # VᵀV − I: the same count for unit vectors
# Eigenvalues: by Weyl's theorem each is within the 2-norm of the backward error (≤ 3 × its max
# entry) of the exact one, for either solver: 2 × 3 × 24 eps of max|S|.
TOL_VALUES = 6 * TOL_BACKWARD
# Eigenvectors and invariant subspaces: perturbation ≤ ‖backward error‖₂ / gap (Davis–Kahan),
# from both solvers: 2 × 3 × 24 eps max|S| / gap.


def random_rotation(rng):
    Q, R = np.linalg.qr(rng.standard_normal((3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else -Q


def decompose(S):
    a = np.array(S, dtype=float)
    V = np.empty((3, 3))
    assert kernels.eig_sym3_closed(a, V) == 0
    return np.diag(a).copy(), V


def check_eigen(S):
    """All the properties against eigh for one matrix S; returns the observed errors / eps."""
    x, V = decompose(S)
    scale = np.max(np.abs(S))
    if scale == 0:
        assert np.all(x == 0) and np.array_equal(V, np.eye(3))
        return
    back = np.max(np.abs(V @ np.diag(x) @ V.T - S)) / scale
    ortho = np.max(np.abs(V.T @ V - np.eye(3)))
    assert back <= TOL_BACKWARD, back / EPS
    assert ortho <= TOL_ORTHO, ortho / EPS
    w, U = np.linalg.eigh(S)
    order = np.argsort(x)
    xs, Vs = x[order], V[:, order]
    assert np.max(np.abs(xs - w)) <= TOL_VALUES * scale, np.max(np.abs(xs - w)) / (EPS * scale)
    # eigenvectors where isolated, else the projector onto the cluster
    for k in range(3):
        gap = min(abs(w[k] - w[m]) for m in range(3) if m != k)
        if gap > 0:
            sin = np.linalg.norm(np.cross(Vs[:, k], U[:, k]))
            assert sin <= TOL_VALUES * scale / gap, (k, sin, gap)
    for lo, hi in ((0, 2), (1, 3)):  # a pair {k, k+1} against the third eigenvalue
        other = 2 if lo == 0 else 0
        gap = min(abs(w[other] - w[lo]), abs(w[other] - w[hi - 1]))
        Pk = Vs[:, lo:hi] @ Vs[:, lo:hi].T
        Pe = U[:, lo:hi] @ U[:, lo:hi].T
        if gap > 0:
            assert np.max(np.abs(Pk - Pe)) <= 2 * TOL_VALUES * scale / gap


def battery(seed, n):
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        Q = random_rotation(rng)
        kind = k % 7
        if kind == 0:  # generic
            d = rng.standard_normal(3)
        elif kind == 1:  # a pair split by 1e-17 … 1e-3 (relative)
            d = np.array([1.0, 1.0 + 10 ** rng.uniform(-17, -3), 3.0]) * rng.choice([-1, 1])
        elif kind == 2:  # the pair on the other side of the third
            d = np.array([-3.0, 2.0, 2.0 + 10 ** rng.uniform(-17, -1)])
        elif kind == 3:  # a near triple
            d = 2.0 + 10 ** rng.uniform(-16, -6) * rng.standard_normal(3)
        elif kind == 4:  # elastic b_e of a metal: I + O(1e-3)
            d = 1.0 + 1e-3 * rng.standard_normal(3)
        elif kind == 5:  # exactly repeated, rotated
            d = np.array([1.0, 2.0, 2.0]) * rng.uniform(0.1, 10)
        else:  # extreme scales
            d = rng.standard_normal(3) * 10.0 ** rng.choice([-200, -70, 70, 200])
        S = Q @ np.diag(d) @ Q.T
        out.append(0.5 * (S + S.T))
    return out


def test_closed_form_eigen_against_lapack_on_a_random_battery():
    for S in battery(1, 3500):
        check_eigen(S)


@pytest.mark.parametrize("S", [
    np.zeros((3, 3)),
    np.eye(3),
    np.diag([3.0, -1.0, 2.0]),                                 # diagonal: returned as is
    np.diag([1.0, 1.0 + 1e-15, 3.0]) + 1e-200 * np.ones((3, 3)),
    np.diag([1.0, 1.0, 1.0]) + 1e-280 * (np.ones((3, 3)) - np.eye(3)),  # deviator ~ 1e-280
    np.array([[1.0, 1e-9, 0.0], [1e-9, 1.0, 0.0], [0.0, 0.0, 1.0]]),    # split 2e-9 off a triple
    np.array([[2.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 1.0, 2.0]]),      # eigenvalues 4, 1, 1
    np.array([[0.0, 1.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 0.0]]),      # 2, −1, −1
    -np.array([[0.0, 1.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 0.0]]),     # −2, 1, 1 (r < 0)
    np.array([[1e300, 1e299, 0.0], [1e299, -1e300, 1e298], [0.0, 1e298, 5e299]]),
    # a repeated pair split by ~1e-155 (found by hypothesis: squares of the 2×2 rotation underflowed)
    np.array([[0.0, 4e-35, 0.0], [4e-35, 4.0, 1.2e-120], [0.0, 1.2e-120, 0.0]]),
])
def test_closed_form_eigen_hard_cases(S):
    check_eigen(S)


def test_diagonal_input_gives_identity_vectors():
    """Diagonal b_e (uniaxial paths) is returned exactly: no rotation, no round-off."""
    x, V = decompose(np.diag([1.2, 0.9, 0.9]))
    assert np.array_equal(x, [1.2, 0.9, 0.9]) and np.array_equal(V, np.eye(3))


@settings(max_examples=300, deadline=None)
@given(st.lists(st.floats(-1e6, 1e6, allow_nan=False, allow_subnormal=False), min_size=6,
                max_size=6))
def test_closed_form_eigen_property(entries):
    a00, a01, a02, a11, a12, a22 = entries
    S = np.array([[a00, a01, a02], [a01, a11, a12], [a02, a12, a22]])
    check_eigen(S)


# --- the J2 point at a nearly repeated trial eigenvalue --------------------------------------
TOL_FD = 1e-6  # central differences of P: truncation O(h²) ~ 1e-12, round-off O(eps/h) ~ 1e-9


def _points(F, h, tangent=False):
    F = np.ascontiguousarray(np.asarray(F, dtype=float).reshape(-1, 3, 3))
    h = np.ascontiguousarray(np.broadcast_to(h, (len(F), h.shape[-1])))
    prm = TABLE1_STEEL.params()[None]
    mid = np.zeros(len(F), np.int64)
    if tangent:
        P, A, hn, st_ = kernels.material_points_tangent(F, h.copy(), prm, mid)
        return P, A, hn, st_
    return kernels.material_points(F, h.copy(), prm, mid)


@pytest.mark.parametrize("split", [0.0, 1e-11, 1e-9, 1e-6])
def test_j2_tangent_at_nearly_repeated_eigenvalues(split):
    """A rotated plastic uniaxial stretch whose two lateral trial eigenvalues differ by ``split``
    (relative): across EIG_GAP = 1e-8 the off-diagonal modulus switches from the divided
    difference to its limit; both must match central differences of P."""
    R = random_rotation(np.random.default_rng(5))
    lat = np.exp(-0.5 * 0.02)
    F = R @ np.diag([np.exp(0.02), lat * (1 + split), lat])
    h = TABLE1_STEEL.initial_history(1)[0]
    P, A, hn, st_ = _points(F, h, tangent=True)
    assert st_[0] == 0 and hn[0, 9] > 0  # a plastic step
    step = 1e-7
    Afd = np.empty((3, 3, 3, 3))
    for k, l in np.ndindex(3, 3):
        Fp, Fm = F.copy(), F.copy()
        Fp[k, l] += step
        Fm[k, l] -= step
        Pp, _, _ = _points(Fp, h)
        Pm, _, _ = _points(Fm, h)
        Afd[:, :, k, l] = (Pp[0] - Pm[0]) / (2 * step)
    err = np.max(np.abs(A[0] - Afd)) / np.max(np.abs(Afd))
    assert err < TOL_FD, err


# --- matrix logarithm and exponential --------------------------------------------------------
def sym6(M):
    return (M[0, 0], M[0, 1], M[0, 2], M[1, 1], M[1, 2], M[2, 2])


def full(t):
    return np.array([[t[0], t[1], t[2]], [t[1], t[3], t[4]], [t[2], t[4], t[5]]])


def spd_with_log_size(rng, size):
    """b = exp(L) with L symmetric, ‖L‖_F = size (eigh reference: L is known exactly)."""
    Q = random_rotation(rng)
    d = rng.standard_normal(3)
    d *= size / np.linalg.norm(d)
    return Q @ np.diag(np.exp(d)) @ Q.T, Q @ np.diag(d) @ Q.T


def test_log_and_exp_against_the_spectral_reference_across_the_switch():
    """ln b against Q diag(ln x) Qᵀ, for ‖ln b‖ from 1e-9 to 1.5 (the series ends at ‖Y‖_F = 0.2,
    ‖ln b‖ ≈ 0.4), and exp(D) likewise (series to ‖D‖ = 0.25). Absolute errors: b and
    its reference are built from the same (Q, d) with round-off ~ 4 eps |b| each; ln amplifies an
    error of b by 1/λ_min(b) ≤ e; the series adds ≤ 2⁻⁵⁶ relative and a few roundings per term.
    100 eps (of max(1, |b|)) is about three times that budget."""
    rng = np.random.default_rng(71)
    n_series = n_spectral = 0
    for k in range(3000):
        size = 10.0 ** rng.uniform(-9, -1) if k % 2 else rng.uniform(0.1, 1.5)
        b, L = spd_with_log_size(rng, size)
        b = 0.5 * (b + b.T)
        Ls, ok = kernels.log_spd(sym6(b))
        assert ok
        err = np.max(np.abs(full(Ls) - L))
        assert err <= 100 * EPS * np.max(np.abs(b)), (size, err / EPS)
        Y = np.linalg.solve(b + np.eye(3), b - np.eye(3))
        if np.linalg.norm(Y) <= kernels.LOG_SERIES_MAX:
            n_series += 1
        else:
            n_spectral += 1
        # exp of a symmetric D of the same size
        E = kernels.exp_sym(sym6(L))
        assert np.max(np.abs(full(E) - b)) <= 100 * EPS * np.max(np.abs(b)), size
    assert n_series > 1500 and n_spectral > 1000  # both sides of the switch were exercised


def test_log_of_non_positive_definite_matrix_is_refused():
    for M in (np.diag([1.0, 1.0, -0.1]), np.diag([1.0, 0.0, 1.0]), np.full((3, 3), np.nan)):
        _, ok = kernels.log_spd(sym6(M))
        assert not ok


def hencky_P(mat, F):
    """P of Hencky elasticity at a virgin J2 point, from numpy's eigh (independent reference):
    τ = λ tr ε I + 2μ ε, ε = ½ ln(F Fᵀ), P = τ F⁻ᵀ."""
    w, V = np.linalg.eigh(F @ F.T)
    eps = V @ np.diag(0.5 * np.log(w)) @ V.T
    tau = mat.lam * np.trace(eps) * np.eye(3) + 2 * mat.mu * eps
    return tau @ np.linalg.inv(F).T


@pytest.mark.parametrize("amp", [1e-3, 0.05, 0.15, 0.2, 0.3, 0.6])
def test_j2_elastic_stress_on_both_sides_of_the_series_switch(amp):
    """A J2 material that stays elastic to large strains (Swift C = 1e15 Pa), stretched by
    F = R (I + amp G): its P is the Hencky stress, whichever branch computes ln be. 1e-12: the
    stresses are O(μ |ε|) and both sides carry O(10 eps) relative round-off, plus the reference's
    eigh (κ of the logs ≲ 10 at these strains)."""
    mat = TABLE1_STEEL.replace(C=1e15)
    rng = np.random.default_rng(72)
    G = rng.standard_normal((3, 3))
    F = random_rotation(rng) @ (np.eye(3) + amp * G / np.linalg.norm(G))
    P, hn, st_ = kernels.material_points(np.ascontiguousarray(F[None]), mat.initial_history(1),
                                         mat.params()[None], np.zeros(1, np.int64))
    assert st_[0] == 0 and hn[0, 9] == 0.0  # elastic
    ref = hencky_P(mat, F)
    assert np.max(np.abs(P[0] - ref)) <= 1e-12 * np.max(np.abs(ref))
