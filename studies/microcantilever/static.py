"""The static references before the first failure (gates 1 and 2) and the FEM with element deletion
(gate 6): the scene's model under a prescribed patch displacement (:func:`static_model`), the
FEM's and static csph's load paths to the first failure in :func:`root_region`
(:func:`fem_static`, :func:`csph_static`), the FEM ladder with its Richardson limits
(:func:`fem_ladder`) and the deletion run (:func:`fem_deletion`)."""
from __future__ import annotations

import dataclasses
import functools

import numpy as np

from workbench import results

from .derive import _order3, deletion_summary, fem_slope_limit, first_failure, limit_spread
from .ladders import (CASES, FEM_DELETION_RESOLUTION, FEM_MAX, FEM_MAX_ROOT, FEM_STEP, NAME,
                      ROOT_LADDER_STEP, ROOT_STEP, options_for, scene_for)
from .scene import MicroCantilever


def static_model(scene: MicroCantilever, spacing: float, path):
    """The scene's model at ``spacing`` as a static problem: the patch pushed down by the load
    parameter (the deflection, m) instead of moved at the scene's velocity, along ``path``; no
    damage (ε_L = 1 everywhere: D of either case is computed from ε_p afterwards, so the curve
    does not depend on the case)."""
    from workbench.scenes import model as M

    sc = dataclasses.replace(scene, eps_L_low=1.0, eps_L_high=1.0)
    model = sc.model(spacing)
    cons = tuple(dataclasses.replace(c, displacement=_down, velocity=None)
                 if isinstance(c, M.Prescribed) else c for c in model.constraints)
    return dataclasses.replace(model, constraints=cons,
                               drive=M.Static(tuple(float(v) for v in path), "deflection", "m"))


def _down(lam):
    return -lam


def static_path(scene: MicroCantilever, fem_max: float = FEM_MAX) -> np.ndarray:
    """The deflections of the static path, m: FEM_STEP·H, 2·FEM_STEP·H, … up to FEM_MAX·H, then
    on in steps of ROOT_STEP·H up to fem_max·H."""
    fine = FEM_STEP * np.arange(1, int(round(min(fem_max, FEM_MAX) / FEM_STEP)) + 1)
    n = int(round((fem_max - FEM_MAX) / ROOT_STEP))
    return scene.H * np.concatenate([fine, FEM_MAX + ROOT_STEP * np.arange(1, max(n, 0) + 1)])


def root_ladder_path(scene: MicroCantilever) -> np.ndarray:
    """The deflections of :func:`.study.root_ladder`'s path (2-D and 3-D), m: FEM_STEP·H (elastic:
    the slope), then on in steps of ROOT_LADDER_STEP·H up to FEM_MAX_ROOT·H
    (:data:`.ladders.ROOT_LADDER_STEP`)."""
    n = int(round((FEM_MAX_ROOT - FEM_STEP) / ROOT_LADDER_STEP))
    return scene.H * (FEM_STEP + ROOT_LADDER_STEP * np.arange(n + 1))


def _root_failed(damage_root: dict, k: int) -> bool:
    """Whether every case's damage in the root region has reached 1 at path point k (a static
    path that follows the root region's first failures stops there)."""
    return all(damage_root[c][k] >= 1.0 for c in CASES)


EDGE_CLEARANCE = 0.4
"""The 3-D root region (:func:`root_region`) leaves out the points closer than EDGE_CLEARANCE·H
(2 µm) to the re-entrant edges where the beam's side faces meet the block's face (x = 0,
y = ±B/2: the block reaches ``block_margin`` beyond them), singular lines of the 3-D scene that
the 2-D one does not have. With them in, the intra case failed first at their top end on every
mesh (FEM, H/h = 5: at (0.11, −2.39, 2.39) µm) and its FEM load fell by 17 % from H/h = 5 to 10
(0.725 to 0.599 mN), as at the patch's edges: no limit to check against. The first failure then
lies where the clearance ends, in the edge's decaying near field (ρ^(λ−1)), sampled at points
O(h) inside: 2 µm rather than 1 µm halves that field's gradient there (FEM, H/h = 5: intra fails
at (1.5, −1.0, 2.39) µm, ρ = 2.1 µm; inter in the first grain boundary, 2.1 µm from the root,
either way)."""


def root_region(scene: MicroCantilever, X) -> np.ndarray:
    """(N,) bool: the points X (N, d), m, where gate 2 looks for the first failure — the tension
    half of the beam's root half, 0 ≤ x ≤ L/2 and above the mid-plane. It holds the largest
    bending stress (the root, whose top face runs on flush with the block's: a smooth surface)
    and none of the singular points: the edges of the rigidly moved patch (x = 0.8 L and 0.9 L
    on the top face), the re-entrant corner under the root (x = 0, bottom face), the corners of
    the held faces (in the block, x < 0); in 3-D none within EDGE_CLEARANCE·H of the re-entrant
    edges of the side faces at the root (:data:`EDGE_CLEARANCE`)."""
    X = np.asarray(X)
    inside = (X[:, 0] >= 0.0) & (X[:, 0] <= 0.5 * scene.L) & (X[:, -1] > 0.0)
    if X.shape[1] == 3:
        rho = np.hypot(X[:, 0], 0.5 * scene.B - np.abs(X[:, 1]))  # distance to the nearer edge
        inside &= rho >= EDGE_CLEARANCE * scene.H * (1 - 1e-9)  # a lattice point at it is in
    return inside


def fem_static(scene: MicroCantilever, resolution: int, fem_max: float = FEM_MAX, path=None,
               until_root_failure: bool = False) -> dict:
    """The FEM (9-node quadrilaterals or 27-node hexahedra, J2 with Swift per grain and boundary,
    the scene's plane) of the scene at H/h = ``resolution`` along the static path of FEM_STEP·H
    up to fem_max·H (or along ``path``, m): ``deflection`` (m), ``load`` (N/m in 2-D, downward
    on the beam), ``damage`` {case: max over the quadrature points of ε_p/ε_L of that case, ε_L
    that of the region the scene's geometry puts the point in, not its element's (the mesh draws
    a slanted grain boundary as a staircase of elements, and inter's first failure followed the
    staircase's nearest step to the root, not the boundary: README)} and
    ``damage_root`` (the same over the points of :func:`root_region`) per path point (NaN where
    not reached), ``eps_p_max``, ``status``, ``wall_time``. ``until_root_failure``: stop once
    every case has failed in the root region."""
    import time

    from fem_reference.model import discretise, observe
    from fem_reference.static import load_path
    from workbench.materials import HIST_EPS_P

    t0 = time.perf_counter()
    h = scene.H / resolution
    path = static_path(scene, fem_max) if path is None else np.asarray(path, float)
    model = static_model(scene, h, path)
    fm = discretise(model, int(resolution))
    at = fm.point_regions()  # ε_L where the geometry puts each point, not its element's region
    limits = {c: region_limits(dataclasses.replace(scene, case=c), h, model)[at] for c in CASES}
    root = root_region(scene, fm.disc.Xq.reshape(-1, fm.disc.d))
    n = len(path)
    out = dict(deflection=path, load=np.full(n, np.nan), eps_p_max=np.full(n, np.nan),
               damage={c: np.full(n, np.nan) for c in CASES},
               damage_root={c: np.full(n, np.nan) for c in CASES})

    def record(k, lam, state):
        o = observe(fm, state, lam)
        out["load"][k] = -o["force"]
        ep = state.history[:, HIST_EPS_P]
        out["eps_p_max"][k] = ep.max()
        for c in CASES:
            D = ep / limits[c]
            out["damage"][c][k] = np.max(D)
            out["damage_root"][c][k] = np.max(D[root])
        return until_root_failure and _root_failed(out["damage_root"], k)

    recs, _ = load_path(fm.problem, path, callback=record,
                        max_increment=float(np.max(np.diff(np.r_[0.0, path]))))
    out["status"] = next((r["status"] for r in recs if not results.path_ok(r["status"])), "ok")
    out["wall_time"] = time.perf_counter() - t0
    out["n_elements"] = int(fm.disc.nel)
    return out


class _StaticScene:
    """The scene as a static problem (:func:`static_model`) for :func:`sph.driver.solve`."""

    def __init__(self, scene: MicroCantilever, path):
        self.scene, self.path, self.name = scene, tuple(float(v) for v in path), scene.name + "_static"

    def model(self, spacing=None):
        return static_model(self.scene, self.scene.H / 10 if spacing is None else spacing, self.path)

    def summarise(self, out):
        return {}


def csph_static(scene: MicroCantilever, resolution: int, fem_max: float = FEM_MAX_ROOT,
                path=None, until_root_failure: bool = False) -> dict:
    """csph (the study's options) on the static path of the FEM (:func:`static_model`, no
    damage; Newton, :mod:`sph.static`) at H/Δx = ``resolution``, to fem_max·H (or along ``path``,
    m; ``until_root_failure``: stopping once every case has failed in :func:`root_region`):
    ``deflection``, ``load``,
    ``eps_p_max`` (over all particles) and ``damage_root`` {case: max of ε_p/ε_L over the
    particles of :func:`root_region`} per path point, ``first_failure_root`` {case: (deflection,
    load)}, ``elastic_slope`` (the secant at the first path point, as the FEM's; NaN where it
    has yielded), ``status``, ``wall_time``."""
    import time

    from sph import driver
    from workbench.materials import HIST_EPS_P

    t0 = time.perf_counter()
    sc = dataclasses.replace(scene, band=0.0, name=f"{NAME}_static")
    path = static_path(sc, fem_max) if path is None else np.asarray(path, float)
    h = sc.H / resolution
    model = static_model(sc, h, path)
    seen = {}

    def on_record(body, run, lam):
        if "limits" not in seen:
            reg = run.ps.region
            seen["root"] = root_region(sc, run.ps.X)
            seen["limits"] = {c: region_limits(dataclasses.replace(sc, case=c), h, model)[reg]
                              for c in CASES}
            seen["D"] = {c: [] for c in CASES}
            seen["eps_p_max"] = []
        ep = body.field_state()["history"][:, HIST_EPS_P]
        seen["eps_p_max"].append(float(ep.max()))
        for c in CASES:
            seen["D"][c].append(float(np.max((ep / seen["limits"][c])[seen["root"]])))
        return until_root_failure and _root_failed(seen["D"], len(seen["eps_p_max"]) - 1)

    out = driver.solve("csph", _StaticScene(sc, path), int(resolution), on_record=on_record,
                       **options_for(sc, "compression"))
    status = out["status"] if isinstance(out["status"], str) else \
        next((s for s in out["status"] if not results.path_ok(s)), "ok")
    d, F = -np.asarray(out["deflection"]), -np.asarray(out["force"])
    D = {c: np.asarray(seen.get("D", {}).get(c, ()), float) for c in CASES}
    ff = {c: first_failure(d[:len(D[c])], F[:len(D[c])], D[c]) for c in CASES}
    ep = np.asarray(seen.get("eps_p_max", ()), float)
    slope = float(F[0] / d[0]) if ep.size and ep[0] == 0 and d.size else float("nan")
    return dict(deflection=d, load=F, damage_root=D, eps_p_max=ep, first_failure_root=ff,
                elastic_slope=slope, status=status, wall_time=time.perf_counter() - t0)


def fem_deletion(scene: MicroCantilever, case: str,
                 resolution: int = FEM_DELETION_RESOLUTION) -> dict:
    """The FEM of ``case`` (the scene's ε_L, the ``compression`` scene) with element deletion at H/h
    = ``resolution``: ``time``, ``load`` (N/m, downward on the beam: the time mean over each output
    interval of the patch's reaction, inertia included), ``deflection_down`` (m), the deleted
    elements and their regions (:func:`.derive.deletion_summary`), ``status``, ``wall_time``."""
    from fem_reference.model import build, solve_model

    sc = scene_for(scene, case, "compression")
    out = solve_model(sc, int(resolution), deletion=True)
    fm = build(sc, int(resolution), deletion=True)
    names = [r.name for r in fm.model.regions]
    gone = np.asarray(out.get("deleted", ()), np.int64)
    res = dict(time=np.asarray(out.get("time", ()), float),
               load=np.asarray(out.get("load", ()), float),
               deflection_down=np.asarray(out.get("deflection_down", ()), float),
               status=str(out["status"]), wall_time=float(out["wall_time"]),
               centroids=fm.disc.centroids(), region=np.asarray(fm.region), region_names=names,
               deleted=gone)
    res.update(deletion_summary(case, names, np.asarray(fm.region), gone))
    return res


def region_limits(scene: MicroCantilever, spacing: float, model) -> np.ndarray:
    """ε_L of each region of ``model`` (its order) for the scene's case at ``spacing``."""
    grains, gb = scene.limits(spacing)
    return np.array([gb if r.name.startswith("gb") else grains[int(r.name[5:])]
                     for r in model.regions])


def fem_ladder(scene: MicroCantilever, resolutions, fem_max: float = FEM_MAX,
               full=None, root_path: bool = False) -> dict:
    """The FEM static runs at ``resolutions`` and what gate 1 needs: the elastic slope per mesh (the
    secant at the first path point, which is elastic), its Richardson limit, each mesh's error
    against it, the slope window of the csph curves (a quarter to all of the deflection at first
    yield on the finest mesh: the last path point with ε_p = 0), each case's first failure anywhere
    and in :func:`root_region` (``first_failure_root``, with its Richardson limit at the singular
    order, ``root_limit``, and each mesh's error against it, ``root_error``; gate 2), on the path to
    ``fem_max``·H. The FEM does not depend on the case, the failure rule, the crack band or the
    drive: one ladder per geometry and material set, computed once per process (read only).
    ``full``: the resolutions that run the whole path (default: all); the others run its first point
    only, which is elastic — their slope, and NaN beyond it (the 3-D ladder,
    :data:`.ladders.FEM_FULL_PATH_3D`); the window is then the finest full run's. ``root_path``
    (:func:`.study.root_ladder`): the first failures in the root region come from runs along
    :func:`root_ladder_path` at every resolution, each stopped once both cases have failed there
    (``root_runs``); their first point gives the slope of the meshes not in ``full``."""
    base = dataclasses.replace(scene, case="inter", failure="compression", name=NAME,
                               dt_reference="cfl", dt_factor=0.3, band=0.0)
    res = tuple(sorted(int(r) for r in resolutions))
    full = res if full is None else tuple(sorted(int(r) for r in full))
    return _fem_ladder(base, res, float(fem_max), full, bool(root_path))


def _first_point_only(scene: MicroCantilever, r: int, fem_max: float, run=None) -> dict:
    """:func:`fem_static` at its first path point only (or the first point of ``run``, a run whose
    path starts there), padded with NaN to the whole path's length."""
    run = dict(fem_static(scene, r, FEM_STEP) if run is None else run)
    path = static_path(scene, fem_max)

    def pad(a):
        return np.r_[np.asarray(a, float)[:1], np.full(len(path) - 1, np.nan)]

    run.update(deflection=path, load=pad(run["load"]), eps_p_max=pad(run["eps_p_max"]),
               damage={c: pad(v) for c, v in run["damage"].items()},
               damage_root={c: pad(v) for c, v in run["damage_root"].items()})
    return run


@functools.lru_cache(maxsize=4)
def _fem_ladder(scene: MicroCantilever, res: tuple, fem_max: float = FEM_MAX,
                full: tuple | None = None, root_path: bool = False) -> dict:
    res = list(res)
    full = res if full is None else list(full)
    root_runs = {r: fem_static(scene, r, path=root_ladder_path(scene), until_root_failure=True)
                 for r in res} if root_path else None
    runs = {r: fem_static(scene, r, fem_max) if r in full else
            _first_point_only(scene, r, fem_max, None if root_runs is None else root_runs[r])
            for r in res}
    slopes = np.array([runs[r]["load"][0] / runs[r]["deflection"][0]
                       if runs[r]["eps_p_max"][0] == 0 else np.nan for r in res])
    fine = runs[max(full)]
    elastic = np.flatnonzero(fine["eps_p_max"] == 0)
    d_yield = float(fine["deflection"][elastic[-1]]) if elastic.size else np.nan
    limit = fem_slope_limit(res, slopes) if len(res) >= 2 else np.nan
    ff = {c: np.array([first_failure(runs[r]["deflection"], runs[r]["load"], runs[r]["damage"][c])
                       for r in res]) for c in CASES}
    rr = runs if root_runs is None else root_runs
    fr = {c: np.array([first_failure(rr[r]["deflection"], rr[r]["load"], rr[r]["damage_root"][c])
                       for r in res]) for c in CASES}
    root_limit = {c: fem_slope_limit(res, fr[c][:, 1]) if len(res) >= 2 else np.nan for c in CASES}
    return dict(resolutions=res, runs=runs, root_runs=root_runs, slopes=slopes, slope_limit=limit,
                slope_error=np.abs(slopes - limit) / abs(limit),
                slope_limit_spread=limit_spread(res, slopes),
                root_limit_spread={c: limit_spread(res, fr[c][:, 1]) for c in CASES},
                observed_order=_order3(res[-3:], slopes[-3:]) if len(res) >= 3 else np.nan,
                window=(0.25 * d_yield, d_yield), first_failure=ff, first_failure_root=fr,
                root_limit=root_limit,
                root_error={c: np.abs(fr[c][:, 1] / root_limit[c] - 1) for c in CASES},
                root_order={c: _order3(res[-3:], fr[c][-3:, 1]) if len(res) >= 3 else np.nan
                            for c in CASES})
