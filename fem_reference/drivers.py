"""The three headline scenes on the FEM: discretise, drive, measure (scenes.md, contract.md).

- :func:`solve_ss_curve`: 3-D block, trilinear hexahedra, rollers on X=0, Y=0, Z=0, prescribed
  axial displacement of X=a following ``scene.strain_path()``, J2 history at the points.
- :func:`solve_cantilever`: 2-D, biquadratic quadrilaterals, rigid clamp at X=0, uniform dead shear
  traction −P/H on X=L, load stepping through ``scene.loads``.
- :func:`solve_plate`: 2-D plane strain, biquadratic quadrilaterals, rigid clamp at X=0; modal
  period and a Newmark run from the initial velocity of 004 eq. 13.
"""
from __future__ import annotations

import math
import time

import numpy as np

from .assembly import Discretisation
from .dynamic import newmark
from .mesh import block, quarter_ring, rectangle
from .modal import lowest_modes
from .static import Problem, TangentSolver, load_path


def _error_status(err: Exception) -> str:
    return f"error: {type(err).__name__}: {err}".replace("\n", " ")


# ------------------------------------------------------------------------------------------------
# SS curve
# ------------------------------------------------------------------------------------------------

def solve_ss_curve(scene, resolution: int = 2, rtol: float = 1e-9, maxit: int = 25) -> dict:
    """Uniaxial tension of the block [0, a]³ with ``resolution`` elements per edge.

    Returns dict(strain (log axial strain per step), stress (axial Cauchy stress = reaction over
    the current cross-section, Pa), stress_qp (the mean σ_xx over the points, Pa), nominal_stress
    (reaction over a², Pa), eps_p (mean equivalent plastic strain), wall_time, n_dof, n_elements,
    status, residual_history (per step: the relative residual norms of each increment)).
    """
    t0 = time.perf_counter()
    a = scene.size
    material = scene.material
    disc = Discretisation(block(a, resolution))
    tol = 1e-9 * a
    x0 = disc.dofs_on(lambda x: x[0] < tol, 0)
    y0 = disc.dofs_on(lambda x: x[1] < tol, 1)
    z0 = disc.dofs_on(lambda x: x[2] < tol, 2)
    xa = disc.dofs_on(lambda x: x[0] > a - tol, 0)
    disc.set_fixed(np.concatenate([x0, y0, z0, xa]))
    pos_xa = np.searchsorted(disc.fixed, xa)

    def fixed_values(eps):
        g = np.zeros(len(disc.fixed))
        g[pos_xa] = a * math.expm1(eps)
        return g

    problem = Problem(disc, material, None, fixed_values, lambda lam: np.zeros(disc.N))
    corner_y = disc.node_dof(np.array([a, a, a]), 1)
    corner_z = disc.node_dof(np.array([a, a, a]), 2)
    path = np.asarray(scene.strain_path(), dtype=float)
    n = len(path)
    out = dict(strain=path, stress=np.full(n, np.nan), stress_qp=np.full(n, np.nan),
               nominal_stress=np.full(n, np.nan), eps_p=np.full(n, np.nan), n_dof=int(disc.N),
               n_elements=int(disc.nel), status="ok", residual_history=[[] for _ in range(n)])

    def measure(k, lam, state):
        pt = problem.evaluate(state.u, state, tangent=False)
        R = float(np.sum(pt["f_int"][xa]))
        area = (a + state.u[corner_y]) * (a + state.u[corner_z])
        out["nominal_stress"][k] = R / a ** 2
        out["stress"][k] = R / area
        P = pt["P"]
        H = disc.displacement_gradient(state.u)
        F = H + np.eye(3)
        sigma = np.einsum("nij,nkj->nik", P, F) / np.linalg.det(F)[:, None, None]
        out["stress_qp"][k] = float(np.mean(sigma[:, 0, 0]))
        if material.n_history:
            from workbench.materials import HIST_EPS_P
            out["eps_p"][k] = float(np.mean(state.history[:, HIST_EPS_P]))
        else:
            out["eps_p"][k] = 0.0

    try:
        recs, _ = load_path(problem, path, rtol=rtol, maxit=maxit, callback=measure)
        for k, r in enumerate(recs):
            out["residual_history"][k] = r["residual_history"]
        bad = [r["status"] for r in recs if r["status"] != "ok"]
        out["status"] = "ok" if not bad else "diverged: " + bad[0]
    except Exception as err:  # a failed run is a result (contract.md)
        out["status"] = _error_status(err)
    out["wall_time"] = time.perf_counter() - t0
    return out


# ------------------------------------------------------------------------------------------------
# Cantilever
# ------------------------------------------------------------------------------------------------

def cantilever_problem(scene, resolution: int, aspect: float = 1.0, element=None,
                       tip_load: str = "traction", fbar=None):
    """The discretised cantilever: (problem, tip DOFs (x, y)); λ is the dimensionless load.
    ``element``: (scalar element, quadrature order) other than the default Q2 (for tests).
    ``tip_load``: 'traction' (the scene's uniform dead shear traction on X = L) or 'point' (the
    same total force as a point load on the tip mid-node (L, 0)). ``fbar``: see
    :class:`fem_reference.assembly.Discretisation` (plane strain only)."""
    L, H = scene.L, scene.H
    disc = Discretisation(rectangle(L, H, resolution, aspect), element=element, fbar=fbar)
    disc.set_fixed(disc.dofs_on(lambda x: x[0] < 1e-9 * L))
    tip = np.array([L, 0.0])
    point_loads = ()
    if tip_load == "traction":
        f_unit = disc.traction_load(lambda x: x[0] > L * (1 - 1e-9),
                                    np.array([0.0, -scene.force(1.0) / H]))
    elif tip_load == "point":
        f_unit = np.zeros(disc.N)
        point_loads = ((tip, np.array([0.0, -scene.force(1.0)])),)
    else:
        raise ValueError(f"tip_load: {tip_load!r} is not one of 'traction', 'point'")
    problem = Problem(disc, scene.material, scene.plane, lambda lam: np.zeros(len(disc.fixed)),
                      lambda lam: lam * f_unit, point_loads=point_loads)
    return problem, (disc.node_dof(tip, 0), disc.node_dof(tip, 1))


def solve_cantilever(scene, resolution: int = 4, max_increment: float = 3.0, rtol: float = 1e-9,
                     maxit: int = 25, aspect: float = 1.0, element=None, tip_load: str = "traction",
                     fbar=None) -> dict:
    """Static tip-loaded cantilever with ``resolution`` elements across H (elements about square).

    Returns dict(load (dimensionless P L²/(E I)), force (N/m), tip_deflection (m, positive
    downward), tip_horizontal (m, shortening positive), wall_time (cumulative s to reach each load),
    n_dof, n_elements, status (per load), residual_history (per load, per increment),
    newton_iterations (per load), assembly_time, solve_time (per load, s)).
    """
    t0 = time.perf_counter()
    loads = np.asarray(scene.loads, dtype=float)
    n = len(loads)
    problem, (ix, iy) = cantilever_problem(scene, resolution, aspect, element, tip_load, fbar)
    disc = problem.disc
    out = dict(load=loads, force=np.array([scene.force(p) for p in loads]),
               tip_deflection=np.full(n, np.nan), tip_horizontal=np.full(n, np.nan),
               wall_time=np.full(n, np.nan), n_dof=int(disc.N), n_elements=int(disc.nel),
               status=["error: not run"] * n, residual_history=[[] for _ in range(n)],
               newton_iterations=[[] for _ in range(n)], assembly_time=np.full(n, np.nan),
               solve_time=np.full(n, np.nan))
    setup = time.perf_counter() - t0

    def measure(k, lam, state):
        out["tip_deflection"][k] = -state.u[iy]
        out["tip_horizontal"][k] = -state.u[ix]

    try:
        solver = TangentSolver()
        recs, _ = load_path(problem, loads, max_increment=max_increment, rtol=rtol, maxit=maxit,
                            callback=measure, solver=solver)
        out["factorisations"] = solver.factorisations
        out["krylov_iterations"] = solver.krylov_iterations
        for k, r in enumerate(recs):
            out["status"][k] = r["status"]
            out["residual_history"][k] = r["residual_history"]
            out["newton_iterations"][k] = r["newton_iterations"]
            out["wall_time"][k] = setup + r["wall_time"]
            out["assembly_time"][k] = r["assembly_time"]
            out["solve_time"][k] = r["solve_time"]
    except Exception as err:  # a failed run is a result (contract.md)
        out["status"] = [_error_status(err)] * n
    return out


# ------------------------------------------------------------------------------------------------
# 3-D cantilever (rectangular section, tip load)
# ------------------------------------------------------------------------------------------------

def cantilever_3d_problem(material, L: float, B: float, H: float, n_H: int, order: int = 2,
                          fbar=None):
    """A 3-D cantilever 0 ≤ X ≤ L, |Y| ≤ B/2, |Z| ≤ H/2, clamped on X = 0 (all components), a
    uniform dead shear traction on X = L in −Z with total force λ (N): λ is the tip load.
    ``n_H`` elements across H, elements about cubic; ``order`` 2: 27-node hexahedra (3×3×3
    Gauss), 1: 8-node (2×2×2). Returns (problem, tip point (L, 0, 0))."""
    from .boundary import Constraints, Loads
    from .mesh import box

    h = H / n_H
    n = (max(1, int(round(L / h))), max(1, int(round(B / h))), n_H)
    disc = Discretisation(box((0.0, -B / 2, -H / 2), (L, B / 2, H / 2), n), order=order, fbar=fbar)
    bc = Constraints(disc)
    bc.clamp(lambda x: x[0] < 1e-9 * L)
    bc.apply()
    loads = Loads(disc)
    loads.traction(lambda x: x[0] > L * (1 - 1e-9), np.array([0.0, 0.0, -1.0 / (B * H)]))
    return Problem(disc, material, None, bc.values, loads), np.array([L, 0.0, 0.0])


def solve_cantilever_3d(material, L: float, B: float, H: float, loads, n_H: int, order: int = 2,
                        fbar=None, max_increment: float = np.inf, rtol: float = 1e-9) -> dict:
    """Follow the tip loads ``loads`` (N) of :func:`cantilever_3d_problem`. Returns dict(load (N),
    tip_deflection (m, −u_Z at (L, 0, 0), interpolated), n_dof, n_elements, status (per load),
    wall_time (s), assembly_time, solve_time (s, per load), newton_iterations)."""
    t0 = time.perf_counter()
    loads = np.asarray(loads, dtype=float)
    n = len(loads)
    problem, tip = cantilever_3d_problem(material, L, B, H, n_H, order, fbar)
    disc = problem.disc
    probe = disc.probe(tip[None, :])
    out = dict(load=loads, tip_deflection=np.full(n, np.nan), n_dof=int(disc.N),
               n_elements=int(disc.nel), status=["error: not run"] * n,
               assembly_time=np.full(n, np.nan), solve_time=np.full(n, np.nan),
               newton_iterations=[[] for _ in range(n)])

    def measure(k, lam, state):
        out["tip_deflection"][k] = -(probe @ state.u)[2]

    try:
        recs, _ = load_path(problem, loads, max_increment=max_increment, rtol=rtol,
                            callback=measure)
        for k, r in enumerate(recs):
            out["status"][k] = r["status"]
            out["assembly_time"][k] = r["assembly_time"]
            out["solve_time"][k] = r["solve_time"]
            out["newton_iterations"][k] = r["newton_iterations"]
    except Exception as err:  # a failed run is a result (contract.md)
        out["status"] = [_error_status(err)] * n
    out["wall_time"] = time.perf_counter() - t0
    return out


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
# Plate
# ------------------------------------------------------------------------------------------------

def initial_velocity(scene, X):
    """v_y(X) = V_f c0 f(X)/f(L) (004 eq. 13 with Gray et al.'s f), from workbench.analytic."""
    from workbench.analytic import plate_initial_velocity

    return np.asarray(plate_initial_velocity(scene, np.asarray(X, dtype=float)), dtype=float)


def plate_problem(scene, resolution: int, aspect: float = 1.0):
    L, H = scene.L, scene.H
    disc = Discretisation(rectangle(L, H, resolution, aspect))
    disc.set_fixed(disc.dofs_on(lambda x: x[0] < 1e-9 * L))
    problem = Problem(disc, scene.material, "strain", lambda lam: np.zeros(len(disc.fixed)),
                      lambda lam: np.zeros(disc.N))
    return problem, disc.node_dof(np.array([L, 0.0]), 1)


def period_from_history(t: np.ndarray, y: np.ndarray) -> float:
    """Period from the zero crossings of y(t) (linear interpolation), least-squares fit of the
    crossing times against their index (half periods); NaN with fewer than two crossings."""
    t1, y1 = t[1:], y[1:]  # t = 0 is the rest position itself
    i = np.flatnonzero(np.sign(y1[:-1]) * np.sign(y1[1:]) < 0)
    tc = t1[i] - y1[i] * (t1[i + 1] - t1[i]) / (y1[i + 1] - y1[i])
    if len(tc) < 2:
        return float("nan")
    slope = np.polyfit(np.arange(len(tc)), tc, 1)[0]
    return float(2 * slope)


def mesh_snapshots(folder, name: str, disc, n_steps: int, frames: int):
    """``snapshot(step, t, u, v)`` for :func:`fem_reference.dynamic.newmark` writing the mesh fields
    (vertex ``displacement`` and ``velocity``, m and m/s) as the ParaView series ``name`` (.pvd +
    .vtu) in ``folder``: about ``frames`` frames over ``n_steps`` steps, the last step always."""
    from workbench.fields import FieldSeries, check_frames

    from .mesh import vtk_grid

    every = max(1, -(-int(n_steps) // check_frames(frames)))
    series = FieldSeries(folder, name)
    grid = vtk_grid(disc.basis.mesh)
    nodal = disc.basis.nodal_dofs  # (d, n_vertices): the vertex DOFs of each component

    def snapshot(step, t, u, v):
        if step % every == 0 or step == n_steps:
            series.add(t, grid=grid, displacement=u[nodal].T, velocity=v[nodal].T)

    return snapshot


def solve_plate(scene, resolution: int = 4, dynamic: bool = True, steps_per_period: int = 100,
                periods: float | None = None, aspect: float = 1.0, rtol: float = 1e-9,
                fields=None, field_frames: int = 20) -> dict:
    """Modal period and (``dynamic``) a Newmark run of the plate, ``resolution`` elements across H.

    Returns dict(period (modal, s), omega (three lowest, rad/s), period_dynamic (s, from the
    zero crossings of the tip displacement), amplitude (max |tip displacement|, m), time,
    tip_displacement (m, +Y), kinetic_energy, strain_energy (J per unit thickness; NaN for a law
    other than SVK), dt, wall_time (s), wall_time_modal (s), n_dof, n_elements, status,
    newton_iterations). The time step is T_modal/``steps_per_period`` (an implicit scheme: the
    scene's ``dt_factor``, a CFL factor of the explicit particle methods, does not apply).
    ``fields`` (a folder, or None): the dynamic run writes its mesh fields (vertex displacement
    and velocity) as the ParaView series ``plate_fem_H<resolution>.pvd``, about ``field_frames``
    frames (:func:`mesh_snapshots`); a modal-only run writes none.
    """
    t0 = time.perf_counter()
    problem, iy = plate_problem(scene, resolution, aspect)
    disc = problem.disc
    out = dict(period=np.nan, omega=np.full(3, np.nan), period_dynamic=np.nan, amplitude=np.nan,
               time=np.zeros(0), tip_displacement=np.zeros(0), kinetic_energy=np.zeros(0),
               strain_energy=np.zeros(0), dt=np.nan, n_dof=int(disc.N), n_elements=int(disc.nel),
               status="ok", newton_iterations=[], wall_time_modal=np.nan)
    try:
        omega, _ = lowest_modes(problem, k=3)
        out["omega"] = omega
        out["period"] = float(2 * math.pi / omega[0])
        out["wall_time_modal"] = time.perf_counter() - t0
        if dynamic:
            T = out["period"]
            dt = T / steps_per_period
            n_steps = int(math.ceil((scene.periods if periods is None else periods) * T / dt))
            X = disc.basis.doflocs[0]
            v0 = np.zeros(disc.N)
            ydofs = np.arange(1, disc.N, 2)
            v0[ydofs] = initial_velocity(scene, X[ydofs])
            snap = None
            if fields is not None:
                from workbench.fields import series_name

                snap = mesh_snapshots(fields, series_name(scene.name, "fem", resolution), disc,
                                      n_steps, field_frames)
            run = newmark(problem, v0, dt, n_steps, observe=lambda u: u[iy], rtol=rtol,
                          snapshot=snap)
            out.update(time=run["time"], tip_displacement=run["observed"],
                       kinetic_energy=run["kinetic_energy"], strain_energy=run["strain_energy"],
                       dt=dt, status=run["status"], newton_iterations=run["newton_iterations"])
            out["period_dynamic"] = period_from_history(run["time"], run["observed"])
            out["amplitude"] = float(np.max(np.abs(run["observed"])))
    except Exception as err:  # a failed run is a result (contract.md)
        out["status"] = _error_status(err)
    out["wall_time"] = time.perf_counter() - t0
    return out
