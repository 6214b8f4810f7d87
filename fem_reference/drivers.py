"""FEM problems that are not scene models (the scenes, the headline ones included, run through
:mod:`fem_reference.model`):

- :func:`micro_cantilever_problem`, :func:`solve_micro_cantilever`: the micro-cantilever of 000 on
  its block, 27-node hexahedra with F-bar, J2 with damage and element deletion, the beam pushed
  down by a rigid (or frictionless) patch — a loaded patch of a face, and grains given per element;
- :func:`cylinder_problem`, :func:`solve_cylinder`: the thick-walled cylinder of the locking tests
  on a quarter ring with quadratic (curved) geometry, which a structured box mesh cannot give;
- :func:`solve_plate`: the plate through :func:`fem_reference.model.solve` under its old name.
"""
from __future__ import annotations

import time

import numpy as np

from workbench.results import error_status as _error_status

from .assembly import Discretisation
from .mesh import quarter_ring
from .static import Problem, load_path




# ------------------------------------------------------------------------------------------------
# 3-D micro-cantilever on a fixed block (000 §4–5, without grains unless region_of gives them)
# ------------------------------------------------------------------------------------------------

MICRO = dict(L=20e-6, B=5e-6, H=5e-6, block=(5e-6, 10e-6, 10e-6), load_length=2.5e-6)


def micro_cantilever_problem(material, resolution: int, L: float = MICRO["L"],
                             B: float = MICRO["B"], H: float = MICRO["H"],
                             block=MICRO["block"], load_length: float = MICRO["load_length"],
                             region_of=None, fbar="linear", deletion=True, grip: str = "rigid"):
    """The micro-cantilever L × B × H (X from 0 to L, centred on Y = Z = 0) on the block
    [−a, 0] × [−b/2, b/2] × [−c/2, c/2], ``block`` = (a, b, c) (paper 000 gives no dimensions:
    20 × 5 × 5 µm on 5 × 10 × 10 µm). 27-node hexahedra with F-bar (plastic flow), about cubic,
    ``resolution`` across H (:func:`fem_reference.mesh.beam_on_block`). The block's back face
    X = −a and bottom face Z = −c/2 are clamped ("two faces of the block fixed"); the load is a
    patch of the beam's top face, L − ``load_length`` ≤ X ≤ L, moved down by λ (m) — the static
    counterpart of the paper's prescribed velocity. ``grip`` 'rigid' (default): all components
    prescribed, u = (0, 0, −λ): the patch neither rotates nor slides, so the beam is fixed at
    the root and guided at the patch (plastic collapse at 2 M_p/(L − load_length), two hinges),
    and a broken-off piece stays attached to the patch; 'vertical': only u_Z = −λ, a frictionless
    flat punch — it cannot tilt either (the same two-hinge collapse), but it leaves the beam free
    to shorten (no membrane force at large deflection); the problem becomes singular once a piece
    breaks off.

    ``material``: a Material or MaterialTable; ``region_of(centroids (nel, 3)) -> (nel,) int``
    gives each element's row (grains; default all 0). ``deletion``: delete failed elements.
    Returns (problem, dict(patch: the node predicate of the loaded patch, boxes, h)).
    """
    from .boundary import Constraints
    from .mesh import beam_on_block, element_size

    h = element_size(H, resolution)
    mesh, boxes = beam_on_block(L, B, H, block, h)
    disc = Discretisation(mesh, order=2, fbar=fbar)
    mat_id = (np.zeros(disc.nel, dtype=np.int64) if region_of is None
              else np.asarray(region_of(disc.centroids()), dtype=np.int64))
    a, _, c = block
    tol = 1e-9 * L

    def patch(x):
        return (x[2] > H / 2 - tol) & (x[0] > L - load_length - tol)

    bc = Constraints(disc)
    bc.clamp(lambda x: x[0] < -a + tol)
    bc.clamp(lambda x: x[2] < -c / 2 + tol)
    if grip == "rigid":
        bc.prescribe(patch, 0, 0.0)
        bc.prescribe(patch, 1, 0.0)
    elif grip != "vertical":
        raise ValueError(f"grip: {grip!r} is not one of 'rigid', 'vertical'")
    bc.prescribe(patch, 2, -1.0)  # u_Z = −λ
    bc.apply()
    problem = Problem(disc, material, None, bc.values, lambda lam: np.zeros(disc.N),
                      mat_id=mat_id, deletion=deletion)
    return problem, dict(patch=patch, boxes=boxes, h=h)


def solve_micro_cantilever(material, resolution: int, displacements, max_increment=None,
                           rtol: float = 1e-8, maxit: int = 25, **geometry) -> dict:
    """Follow the patch displacements (m) of :func:`micro_cantilever_problem` (``geometry``:
    its keyword arguments). Returns dict(displacement (m), force (N, the downward force on the
    patch), eps_p_max, failed_fraction (of all elements), deleted (elements deleted while reaching
    each displacement), n_dof, n_elements, status (per load), newton_iterations, wall_time (s))."""
    from .observe import failed_fraction, plastic_strain, reaction

    t0 = time.perf_counter()
    u_tip = np.asarray(displacements, dtype=float)
    n = len(u_tip)
    problem, info = micro_cantilever_problem(material, resolution, **geometry)
    disc = problem.disc
    out = dict(displacement=u_tip, force=np.full(n, np.nan), eps_p_max=np.full(n, np.nan),
               failed_fraction=np.full(n, np.nan), deleted=[[] for _ in range(n)],
               n_dof=int(disc.N), n_elements=int(disc.nel), status=["error: not run"] * n,
               newton_iterations=[[] for _ in range(n)])

    def measure(k, lam, state):
        out["force"][k] = -reaction(problem, state, where=info["patch"])[2]
        out["eps_p_max"][k] = plastic_strain(problem, state, "max")
        out["failed_fraction"][k] = failed_fraction(problem, np.zeros(disc.nel, int))[0]

    if max_increment is None:
        max_increment = float(np.max(np.abs(u_tip))) / 20
    try:
        recs, _ = load_path(problem, u_tip, max_increment=max_increment, rtol=rtol, maxit=maxit,
                            callback=measure)
        for k, r in enumerate(recs):
            out["status"][k] = r["status"]
            out["deleted"][k] = r["deleted"].tolist()
            out["newton_iterations"][k] = r["newton_iterations"]
    except Exception as err:  # a failed run is a result (contract.md)
        out["status"] = [_error_status(err)] * n
    out["wall_time"] = time.perf_counter() - t0
    return out


# ------------------------------------------------------------------------------------------------
# Thick-walled cylinder (a locking benchmark, not a scene)
# ------------------------------------------------------------------------------------------------

def cylinder_problem(material, a: float, b: float, n_r: int, n_theta: int,
                     control: str = "pressure", fbar=None, dim: int = 2):
    """Plane-strain thick-walled cylinder a ≤ R ≤ b under internal loading, one quadrant with
    symmetry rollers (u_X = 0 on X = 0, u_Y = 0 on Y = 0) and a free outer surface.

    ``dim`` 2: the quadrant of :func:`fem_reference.mesh.quarter_ring` (Q9, plane strain).
    ``dim`` 3: a slice 0 ≤ Z ≤ t = (b − a)/n_r of the tube, one layer of 27-node hexahedra
    (:func:`fem_reference.mesh.quarter_ring_3d`) with u_Z = 0 on both end faces — the plane-strain
    end constraints, so that the 3-D problem has the plane-strain solution.

    ``control``: 'pressure' — λ is a dead bore pressure (nominal traction λ e_R on the reference
    bore, see :meth:`~fem_reference.assembly.Discretisation.pressure_load`); 'displacement' — λ is
    a prescribed radial displacement of every bore node (u = λ e_R, no tangential motion, which
    the axisymmetric solution satisfies). Returns (problem, dict(bore, outer: the x DOFs of the
    nodes on R = a and R = b (the y DOF of each is the next one), e_bore, e_outer: their unit
    radial vectors (2, n), length: the bore length over which the reaction is spread, a π/2 in
    2-D and a π/2 t in 3-D)).
    """
    from .boundary import Constraints, Loads
    from .mesh import quarter_ring_3d

    if dim == 2:
        mesh = quarter_ring(a, b, n_r, n_theta)
        t = 1.0
    elif dim == 3:
        t = (b - a) / n_r
        mesh = quarter_ring_3d(a, b, t, n_r, n_theta, 1)
    else:
        raise ValueError(f"dim: {dim} is not one of 2, 3")
    disc = Discretisation(mesh, fbar=fbar)
    on_bore = lambda x: np.hypot(x[0], x[1]) < a * (1 + 1e-9)  # noqa: E731
    on_outer = lambda x: np.hypot(x[0], x[1]) > b * (1 - 1e-9)  # noqa: E731
    tol = 1e-9 * b
    bc = Constraints(disc)
    bc.roller(lambda x: x[0] < tol, 0)
    bc.roller(lambda x: x[1] < tol, 1)
    if dim == 3:
        bc.roller(lambda x: (x[2] < tol) | (x[2] > t - tol), 2)
    bx = disc.dofs_where(on_bore, 0)  # x DOFs of the bore nodes; the y DOF is bx + 1
    ox = disc.dofs_where(on_outer, 0)
    X = disc.basis.doflocs
    e_bore = X[:2, bx] / np.hypot(X[0, bx], X[1, bx])
    e_outer = X[:2, ox] / np.hypot(X[0, ox], X[1, ox])
    loads = Loads(disc)
    if control == "pressure":
        loads.pressure(on_bore, 1.0)
    elif control == "displacement":
        bc.prescribe_dofs(bx, lambda lam: lam * e_bore[0])
        bc.prescribe_dofs(bx + 1, lambda lam: lam * e_bore[1])
    else:
        raise ValueError(f"control: {control!r} is not one of 'pressure', 'displacement'")
    bc.apply()
    problem = Problem(disc, material, "strain" if dim == 2 else None, bc.values, loads)
    return problem, dict(bore=bx, e_bore=e_bore, outer=ox, e_outer=e_outer,
                         length=a * np.pi / 2 * t)


def solve_cylinder(material, a: float, b: float, n_r: int, n_theta: int, loads,
                   control: str = "pressure", fbar=None, max_increment: float = np.inf,
                   rtol: float = 1e-9, maxit: int = 25, dim: int = 2) -> dict:
    """Follow the loads λ of :func:`cylinder_problem` and measure at each.

    Returns dict(load, bore_displacement (mean radial displacement of the bore nodes, m),
    outer_displacement (the same on R = b), pressure_nominal (radial bore reaction over the
    reference quarter-bore length aπ/2 (times t in 3-D), Pa; with 'pressure' control it is λ
    itself), pressure (the reaction over the current length (a + u_a)π/2: the Cauchy pressure),
    status (per load), residual_history (per load, per increment), n_dof, wall_time).
    With 'pressure' control the reaction is the applied load and both pressures follow from λ.
    """
    t0 = time.perf_counter()
    loads = np.asarray(loads, dtype=float)
    n = len(loads)
    problem, nodes = cylinder_problem(material, a, b, n_r, n_theta, control, fbar, dim)
    disc = problem.disc
    bx, ox = nodes["bore"], nodes["outer"]
    out = dict(load=loads, bore_displacement=np.full(n, np.nan),
               outer_displacement=np.full(n, np.nan), pressure_nominal=np.full(n, np.nan),
               pressure=np.full(n, np.nan), status=["error: not run"] * n,
               residual_history=[[] for _ in range(n)], n_dof=int(disc.N))

    def radial(v, idx, e):
        return v[idx] * e[0] + v[idx + 1] * e[1]

    def measure(k, lam, state):
        ua = float(np.mean(radial(state.u, bx, nodes["e_bore"])))
        out["bore_displacement"][k] = ua
        out["outer_displacement"][k] = float(np.mean(radial(state.u, ox, nodes["e_outer"])))
        if control == "pressure":
            pn = lam
        else:
            f = problem.evaluate(state.u, state, tangent=False)["f_int"]
            # Σ_a f_a·e_R(X_a) over the bore nodes: the consistent discretisation of ∫ p ds
            pn = float(np.sum(radial(f, bx, nodes["e_bore"]))) / nodes["length"]
        out["pressure_nominal"][k] = pn
        out["pressure"][k] = pn * a / (a + ua)

    try:
        recs, _ = load_path(problem, loads, max_increment=max_increment, rtol=rtol, maxit=maxit,
                            callback=measure)
        for k, r in enumerate(recs):
            out["status"][k] = r["status"]
            out["residual_history"][k] = r["residual_history"]
    except Exception as err:  # a failed run is a result (contract.md)
        out["status"] = [_error_status(err)] * n
    out["wall_time"] = time.perf_counter() - t0
    return out


# ------------------------------------------------------------------------------------------------
# Plate (the interface of an older test)
# ------------------------------------------------------------------------------------------------

def solve_plate(scene, resolution: int = 4, dynamic: bool = True, **options) -> dict:
    """The plate through :func:`fem_reference.model.solve` (``dynamic``: the modal period alone,
    or with the Newmark run). Kept for tests/test_fields_output.py, which calls it by this name."""
    from .model import solve

    return solve(scene, resolution, dynamic=dynamic, **options)
