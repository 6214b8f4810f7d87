"""Material update at the quadrature points: the shared material library on arrays, reduced to the
2-D idealisation of the scene.

Every stress comes from :func:`workbench.materials.evaluate` (one material-point implementation
for all methods). This module only embeds the in-plane deformation gradient into 3×3, takes the
in-plane blocks of P and A = ∂P/∂F (plane strain, F33 = 1), or solves P33 = 0 for F33 per point and
condenses the tangent (plane stress).

Until the numba kernels of :mod:`workbench.materials.kernels` exist, a numpy Saint Venant–Kirchhoff
point routine stands in (:func:`svk_points`), with the same contract; the other laws need the
kernels.
"""
from __future__ import annotations

import numpy as np

from workbench.materials import Material, evaluate


def svk_points(material: Material, F: np.ndarray, tangent: bool = True):
    """Saint Venant–Kirchhoff: S = λ tr(E) I + 2μ E, E = ½(FᵀF − I), P = F S.

    F: (N, 3, 3). Returns P (N, 3, 3) and, with ``tangent``, A (N, 3, 3, 3, 3) with
    A_iJkL = δ_ik S_JL + λ F_iJ F_kL + μ ((FFᵀ)_ik δ_JL + F_iL F_kJ).
    """
    lam, mu = material.lam, material.mu
    I = np.eye(3)
    E = 0.5 * (np.einsum("nki,nkj->nij", F, F) - I)
    trE = np.trace(E, axis1=1, axis2=2)
    S = lam * trE[:, None, None] * I + 2 * mu * E
    P = F @ S
    if not tangent:
        return P, None
    Fs = F[:, :, :, None, None]  # F_iJ
    Ft = F[:, None, None, :, :]  # F_kL
    A = lam * Fs * Ft
    A += mu * F[:, :, None, None, :] * np.swapaxes(F, 1, 2)[:, None, :, :, None]  # F_iL F_kJ
    FFt = F @ np.swapaxes(F, 1, 2)
    A += (mu * FFt)[:, :, None, :, None] * I[None, None, :, None, :]  # (FFᵀ)_ik δ_JL
    A += I[None, :, None, :, None] * S[:, None, :, None, :]  # δ_ik S_JL
    return P, A


def svk_energy(material: Material, F: np.ndarray) -> np.ndarray:
    """Stored energy density W = λ/2 (tr E)² + μ E:E of Saint Venant–Kirchhoff, J/m³, shape (N,)."""
    E = 0.5 * (np.einsum("nki,nkj->nij", F, F) - np.eye(3))
    trE = np.trace(E, axis1=1, axis2=2)
    return 0.5 * material.lam * trE ** 2 + material.mu * np.einsum("nij,nij->n", E, E)


SERIAL_BELOW = 20000  # points: smaller updates run on one thread


def _kernels_available() -> bool:
    try:
        from workbench.materials import kernels  # noqa: F401
    except ImportError:
        return False
    return True


def points_3d(material: Material, F: np.ndarray, history: np.ndarray, tangent: bool = True):
    """P, A, new history and status of 3×3 deformation gradients F (N, 3, 3)."""
    if material.law == "svk" and not _kernels_available():
        P, A = svk_points(material, F, tangent)
        return P, A, history, np.zeros(len(F), dtype=np.int64)
    import numba

    threads = numba.get_num_threads()
    if len(F) < SERIAL_BELOW:
        # a parallel launch costs ~15 ms on a busy 2-core machine: more than a small mesh's update
        numba.set_num_threads(1)
    try:
        res = evaluate(material, F, history, tangent=tangent)
    finally:
        numba.set_num_threads(threads)
    return res["stress"], res.get("A"), res["history"], np.asarray(res["status"])


def embed(H: np.ndarray, F33=None) -> np.ndarray:
    """3×3 deformation gradients from displacement gradients H (N, d, d); in 2-D F33 = 1 or
    the given (N,) values."""
    n, d = H.shape[0], H.shape[1]
    F = np.zeros((n, 3, 3))
    F[:, :d, :d] = H
    F[:, 0, 0] += 1.0
    F[:, 1, 1] += 1.0
    F[:, 2, 2] += 1.0
    if d == 2 and F33 is not None:
        F[:, 2, 2] = F33
    return F


def update(material: Material, H: np.ndarray, history: np.ndarray, plane: str | None,
           tangent: bool = True, F33: np.ndarray | None = None, tol: float = 1e-12):
    """Stress and tangent of the discretisation's dimension from displacement gradients.

    H: (N, d, d) with d = 3, or d = 2 with ``plane`` 'strain' (F33 = 1) or 'stress' (F33 solved per
    point so that P33 = 0 by Newton from the guess ``F33``; the tangent is the condensed
    A_abcd − A_ab33 A_33cd / A_3333).
    Returns dict(P (N,d,d), A (N,d,d,d,d) or None, history, status (N,), F33 (N,) in 2-D).
    """
    d = H.shape[1]
    if d == 3 or plane == "strain":
        F = embed(H)
        P, A, h, st = points_3d(material, F, history, tangent)
        return dict(P=P[:, :d, :d], A=None if A is None else A[:, :d, :d, :d, :d], history=h,
                    status=st, F33=np.ones(len(H)))
    if plane != "stress":
        raise ValueError(f"plane: {plane!r} is not one of 'strain', 'stress'")
    F33 = np.ones(len(H)) if F33 is None else np.array(F33, dtype=float)
    scale = max(material.E, 1.0)
    for _ in range(30):
        F = embed(H, F33)
        P, A, h, st = points_3d(material, F, history, True)
        r = P[:, 2, 2]
        if np.max(np.abs(r)) <= tol * scale:
            break
        step = r / A[:, 2, 2, 2, 2]
        F33 = F33 - step
        # keep the out-of-plane stretch positive
        F33 = np.where(F33 <= 0, 0.5 * (F33 + step), F33)
    else:
        st = np.where(np.abs(P[:, 2, 2]) > 1e-8 * scale, 1, st)
    out = dict(P=P[:, :2, :2], history=h, status=st, F33=F33, A=None)
    if tangent:
        A2 = A[:, :2, :2, :2, :2]
        out["A"] = A2 - np.einsum("nij,nkl->nijkl", A[:, :2, :2, 2, 2], A[:, 2, 2, :2, :2]) \
            / A[:, 2, 2, 2, 2][:, None, None, None, None]
    return out


def strain_energy_density(material: Material, H: np.ndarray, F33=None) -> np.ndarray:
    """W(F) per point for Saint Venant–Kirchhoff (the dynamic runs' strain energy), J/m³."""
    if material.law != "svk":
        raise ValueError(f"law: strain energy only for 'svk', not {material.law!r}")
    return svk_energy(material, embed(H, F33))
