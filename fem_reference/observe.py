"""Observables of a FEM run, for the scenes' reader: reactions on node sets, displacement at any
point, energies, and the failed fraction of each region.

All take a :class:`~fem_reference.static.Problem` (or its discretisation) and a committed
:class:`~fem_reference.static.State` (or a displacement vector).
"""
from __future__ import annotations

import numpy as np


def reaction(problem, state, where=None, dofs=None, lam: float | None = None,
             f_int=None) -> np.ndarray:
    """Reaction force (d,) of the supports on a node set, N (N/m in 2-D): the sum of
    f_int − f_ext(λ) over the constrained DOFs of the nodes of ``where`` (a node predicate; or
    explicit ``dofs``), per component — the force the supports there exert on the body
    (equilibrium f_int = f_ext + reaction). ``lam``: the load parameter of f_ext; None when no
    external load acts on the set (then the reaction is the internal force alone). Components
    without a constrained DOF in the set are 0. ``f_int`` (N,) may be passed when already
    evaluated at ``state``."""
    disc = problem.disc
    if f_int is None:
        f_int = problem.evaluate(state.u, state, tangent=False)["f_int"]
        if f_int is None:
            raise ValueError("state: the material update failed at this state (no internal force)")
    r = f_int if lam is None else f_int - problem.external(lam)
    if dofs is None:
        if where is None:
            raise ValueError("where: give a node predicate or dofs")
        dofs = disc.dofs_where(where)
    dofs = np.intersect1d(np.asarray(dofs, dtype=np.int64), disc.fixed)
    out = np.zeros(disc.d)
    np.add.at(out, dofs % disc.d, r[dofs])
    return out


def displacement_at(disc, u: np.ndarray, x) -> np.ndarray:
    """Displacement (n, d) at the points x (n, d) of the reference configuration, interpolated
    with the shape functions of the element containing each point (m)."""
    return disc.interpolate(u, x)


def kinetic_energy(problem, v: np.ndarray, M=None) -> float:
    """½ vᵀ M v with the consistent mass of the active elements, J (J/m in 2-D)."""
    M = problem.mass() if M is None else M
    return 0.5 * float(v @ (M @ v))


def stored_energy(problem, state) -> float:
    """∫ ψ dV over the live points, J (J/m in 2-D); see
    :meth:`fem_reference.static.Problem.stored_energy`."""
    return problem.stored_energy(state)


def failed_elements(problem, state=None) -> np.ndarray:
    """bool (nel,): elements that failed — deleted, or (given ``state``) failed at every point
    (a run without deletion; failed as :func:`workbench.materials.failure.failed` says, any law)."""
    from workbench.materials.failure import failed as failed_points

    disc = problem.disc
    failed = ~disc.active
    if state is not None:
        pts = failed_points(problem.table, problem.point_mat, state.history)
        failed = failed | np.all(pts.reshape(disc.nel, disc.nqp), axis=1)
    return failed


def failed_fraction(problem, region=None, by: str = "count", state=None) -> dict:
    """Fraction of failed elements (:func:`failed_elements`) per region: {region id: fraction}.
    ``region`` (nel,) integer region ids (default the problem's material ids); ``by`` 'count'
    (elements) or 'volume' (reference volume)."""
    disc = problem.disc
    region = problem.mat_id if region is None else np.asarray(region)
    if region.shape != (disc.nel,):
        raise ValueError(f"region: must have shape ({disc.nel},), got {region.shape}")
    if by == "count":
        w = np.ones(disc.nel)
    elif by == "volume":
        w = disc.volumes()
    else:
        raise ValueError(f"by: {by!r} is not one of 'count', 'volume'")
    dead = failed_elements(problem, state)
    return {int(r): float(w[(region == r) & dead].sum() / w[region == r].sum())
            for r in np.unique(region)}


def mean_stress(problem, state, elements=None) -> np.ndarray:
    """Volume-weighted mean Cauchy stress (3, 3), Pa, over the active elements (or the bool mask
    / indices ``elements``): ∫ σ dv / ∫ dv = Σ dV J σ / Σ dV J over their points, with
    σ = P Fᵀ/J (with F-bar σ(F̄), weighted by J̄, whose element integral is that of J). In 2-D
    the 3×3 F has F33 (1 in plane strain) and σ33 comes from the full 3-D update."""
    from .constitutive import embed, points_3d

    disc = problem.disc
    mask = disc.active.copy()
    if elements is not None:
        sel = np.zeros(disc.nel, dtype=bool)
        sel[elements] = True
        mask &= sel
    pts = np.repeat(mask, disc.nqp) & problem.live_points(state)
    if not pts.any():  # every point failed: nothing carries stress
        return np.zeros((3, 3))
    H = disc.displacement_gradient(state.u)
    if disc.fbar is not None:
        H = disc.fbar_kinematics(H)["Hbar"]
    F = embed(H[pts], state.F33[pts])
    # the committed history is the state's own: re-evaluating at it returns its stress
    P, _, _, _ = points_3d(problem.table, F, state.history[pts], False, problem.point_mat[pts])
    J = np.linalg.det(F)
    tau = np.einsum("nij,nkj->nik", P, F)  # J σ
    w = disc.dV.ravel()[pts]
    return np.einsum("n,nij->ij", w, tau) / np.sum(w * J)


def plastic_strain(problem, state, reduce: str = "max") -> float:
    """The equivalent plastic strain over the live and failed points of active elements:
    'max' or 'mean' (volume-weighted); 0 for elastic tables."""
    from workbench.materials import HIST_EPS_P

    disc = problem.disc
    if problem.table.n_history <= HIST_EPS_P:
        return 0.0
    ep = state.history[:, HIST_EPS_P].reshape(disc.nel, disc.nqp)
    if reduce == "max":
        act = disc.active
        return float(ep[act].max()) if act.any() else 0.0
    if reduce == "mean":
        return float(np.sum(ep * disc.dV) / np.sum(disc.dV))
    raise ValueError(f"reduce: {reduce!r} is not one of 'max', 'mean'")
