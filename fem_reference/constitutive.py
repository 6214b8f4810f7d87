"""Material update at the quadrature points: the shared material library on arrays, reduced to the
2-D idealisation of the scene.

Every stress comes from :func:`workbench.materials.evaluate` (one material-point implementation
for all methods). A body of several materials is a :class:`workbench.materials.MaterialTable` with
a material id per point (every quadrature point of an element carries its element's id); a single
:class:`~workbench.materials.Material` is a one-row table. This module only embeds the in-plane
deformation gradient into 3×3, takes the in-plane blocks of P and A = ∂P/∂F (plane strain,
F33 = 1), or solves P33 = 0 for F33 per point and condenses the tangent (plane stress).

The stored energy density comes from the library too (:func:`stored_energy_density`).
"""
from __future__ import annotations

import numpy as np

from workbench.materials import MaterialTable, evaluate

SERIAL_BELOW = 20000  # points: smaller updates run on one thread


def points_3d(material, F: np.ndarray, history: np.ndarray, tangent: bool = True, mat_id=None):
    """P (N, 3, 3), A (N, 3, 3, 3, 3) or None, new history (N, n_history) and status (N,) of
    3×3 deformation gradients F (N, 3, 3); ``material`` a Material or a MaterialTable with
    ``mat_id`` (N,) rows of it (default all 0)."""
    import numba

    threads = numba.get_num_threads()
    if len(F) < SERIAL_BELOW:
        # a parallel launch costs ~15 ms on a busy 2-core machine: more than a small mesh's update
        numba.set_num_threads(1)
    try:
        res = evaluate(material, F, history, tangent=tangent, mat_id=mat_id)
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


def update(material, H: np.ndarray, history: np.ndarray | None, plane: str | None,
           tangent: bool = True, F33: np.ndarray | None = None, tol: float = 1e-12, mat_id=None):
    """Stress and tangent of the discretisation's dimension from displacement gradients.

    material: a Material, or a MaterialTable with ``mat_id`` (N,) its row per point.
    H: (N, d, d) with d = 3, or d = 2 with ``plane`` 'strain' (F33 = 1) or 'stress' (F33 solved per
    point so that P33 = 0 by Newton from the guess ``F33``; the tangent is the condensed
    A_abcd − A_ab33 A_33cd / A_3333).
    Returns dict(P (N,d,d), A (N,d,d,d,d) or None, history, status (N,), F33 (N,) in 2-D).
    """
    d = H.shape[1]
    if d == 3 or plane == "strain":
        F = embed(H)
        P, A, h, st = points_3d(material, F, history, tangent, mat_id)
        return dict(P=P[:, :d, :d], A=None if A is None else A[:, :d, :d, :d, :d], history=h,
                    status=st, F33=np.ones(len(H)))
    if plane != "stress":
        raise ValueError(f"plane: {plane!r} is not one of 'strain', 'stress'")
    F33 = np.ones(len(H)) if F33 is None else np.array(F33, dtype=float)
    scale = max(max(m.E for m in MaterialTable.of(material).materials), 1.0)
    for _ in range(30):
        F = embed(H, F33)
        P, A, h, st = points_3d(material, F, history, True, mat_id)
        r = P[:, 2, 2]
        if np.max(np.abs(r), initial=0.0) <= tol * scale:
            break
        with np.errstate(invalid="ignore", divide="ignore"):
            step = np.where(A[:, 2, 2, 2, 2] != 0, r / A[:, 2, 2, 2, 2], 0.0)
        F33 = F33 - step
        # keep the out-of-plane stretch positive
        F33 = np.where(F33 <= 0, 0.5 * (F33 + step), F33)
    else:
        st = np.where(np.abs(P[:, 2, 2]) > 1e-8 * scale, 1, st)
    out = dict(P=P[:, :2, :2], history=h, status=st, F33=F33, A=None)
    if tangent:
        A2 = A[:, :2, :2, :2, :2]
        a33 = A[:, 2, 2, 2, 2]
        with np.errstate(invalid="ignore", divide="ignore"):
            inv = np.where(a33 != 0, 1.0 / a33, 0.0)  # a failed point: A = 0, nothing to condense
        out["A"] = A2 - np.einsum("nij,nkl,n->nijkl", A[:, :2, :2, 2, 2], A[:, 2, 2, :2, :2], inv)
    return out


def stored_energy_density(material, F: np.ndarray, history: np.ndarray | None = None,
                          mat_id=None) -> np.ndarray:
    """Stored energy density ψ(F, h) per point, J/m³, shape (N,): the library's closed forms
    (:func:`workbench.materials.energies`, every law, J2 and the mortar included; ψ of a failed
    J2 point as the library defines it).

    F: (N, 3, 3) (:func:`embed` of the points' H and F33); history: (N, n_history) of the end of
    the step (None: virgin); ``material`` a Material or a MaterialTable with ``mat_id`` (N,).
    """
    from workbench.materials import energies

    return np.asarray(energies(MaterialTable.of(material), np.ascontiguousarray(F, dtype=float),
                               history, mat_id)["psi"], dtype=float).reshape(-1)
