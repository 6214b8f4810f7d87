"""The micro-cantilever study's dataset (``microcantilever.nc``) from its runs: the histories per
case × rule × resolution × time, the scalars of :func:`.derive.run_summary`, the FEM ladder, the
static csph runs, the loads at the first failure in the root region, the FEM with element deletion
and the final particles for the figure of the cracked cantilevers."""
from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from workbench import results

from ..common import observed_order
from .derive import SINGULAR_ORDER, csph_slope, run_summary
from .ladders import CASES, NAME, RULES


N_TIME = 301

SERIES = {"load": ("load", "N", "force of the loading patch on the beam, downward (N/m in 2-D)"),
          "deflection": ("deflection_down", "m", "mean downward displacement of the loading patch"),
          "external_work": ("external_work", "J", "work of the prescribed motion (J/m in 2-D)"),
          "kinetic_energy": ("kinetic_energy", "J", "kinetic energy"),
          "elastic_energy": ("strain_energy", "J", "stored (elastic) energy"),
          "plastic_work": ("plastic_work", "J", "plastic work"),
          "released_energy": ("released_energy", "J",
                              "stored energy released by failure and cracking"),
          "merge_dissipation": ("merge_dissipation", "J",
                                "kinetic energy taken by the merge of the opened failed particles "
                                "into the faces of their crack (sph.crack.Cracks.merge)")}
FAILED = {"all": "failed", "grains": "failed_grains", "boundaries": "failed_gb"}

PLANE_3D = "none (3-D)"
"""The dataset's ``plane`` attribute in 3-D."""


def dataset(scene, outs: dict, rules, res, fem: dict | None = None,
            static: dict | None = None, deletion: dict | None = None,
            solvers=("csph",)) -> xr.Dataset:
    """The study's dataset from the runs ``outs`` {(solver, case, rule, resolution): driver
    output} (``solvers`` in that order; a key of three is csph's) and the FEM reference ``fem``
    (:func:`.static.fem_ladder`, or None)."""
    outs = {(k if len(k) == 4 else ("csph",) + tuple(k)): v for k, v in outs.items()}
    solvers = list(solvers)
    time = np.linspace(0.0, scene.t_end, N_TIME)
    dims = ("solver", "case", "rule", "resolution")
    shp = (len(solvers), len(CASES), len(rules), len(res))
    series = {n: np.full(shp + (N_TIME,), np.nan) for n in SERIES}
    failed = np.full(shp + (len(FAILED), N_TIME), np.nan)
    scal = {}
    status = np.full(shp, "not run", dtype=object)
    wall = np.full(shp, np.nan)
    npart = np.zeros(shp, np.int64)
    steps = np.zeros(shp, np.int64)
    pss = np.full(shp, np.nan)
    finest = {}
    for (solver, case, rule, r), out in outs.items():
        idx = (solvers.index(solver), CASES.index(case), rules.index(rule), res.index(r))
        status[idx] = str(out.get("status", "error: no status"))
        wall[idx] = float(out.get("run_wall_time", out.get("wall_time", np.nan)))
        npart[idx] = int(out.get("n_particles", 0))
        steps[idx] = int(out.get("steps", 0))
        pss[idx] = float(out.get("particle_steps_per_second", np.nan))
        t = np.asarray(out.get("time", ()))
        if len(t) > 1:
            for n, (src, _, _) in SERIES.items():
                if src in out:
                    series[n][idx] = np.interp(time, t, np.asarray(out[src], float), right=np.nan)
            for j, src in enumerate(FAILED.values()):
                if src in out:
                    failed[idx + (j,)] = np.interp(time, t, np.asarray(out[src], float), right=np.nan)
        for k, v in run_summary(out, dataclasses.replace(scene, case=case), r).items():
            scal.setdefault(k, np.full(shp, "" if isinstance(v, str) else np.nan, dtype=object
                                       if isinstance(v, str) else float))[idx] = v
        if "x" in out and r >= finest.get((solver, case, rule), (0, None))[0]:
            finest[(solver, case, rule)] = (r, out)
    data = {n: (dims + ("time",), series[n], {"units": u, "long_name": ln})
            for n, (_, u, ln) in SERIES.items()}
    data["failed_fraction"] = (dims + ("part", "time"), failed, {
        "units": "-", "long_name": "fraction of the particles of the part whose damage reached 1"})
    data["status"] = (dims, status.astype(str), {"units": "-"})
    data["wall_time"] = (dims, wall, {"units": "s", "long_name": "run wall time, set-up included"})
    data["n_particles"] = (dims, npart, {"units": "-"})
    data["steps"] = (dims, steps, {"units": "-"})
    data["particle_steps_per_second"] = (dims, pss, {"units": "1/s", "long_name":
                                                     "particles x steps / time-loop wall time"})
    units = dict(peak_load="N", deflection_at_peak="m", t_first_failure="s", load_at_first_failure="N",
                 deflection_at_first_failure="m", elastic_slope="N/m", energy_balance_error="-",
                 kinetic_ratio="-", n_failed="-", share_boundaries="-", mean_tail_load="N",
                 tail_load_ratio="-", separated="-", connected="-", crack_regions="-",
                 released_final="J", fracture_energy="J", fracture_energy_all="J", n_crack="-",
                 fracture_energy_end="J", fragment_speed_max="m/s", fragment_kinetic_share="-",
                 fragment_relative_speed_max="m/s", fragment_relative_kinetic_share="-",
                 crack_x="m", crack_region="-", max_load="N",
                 t_separated="s", t_last="s")
    for k, arr in scal.items():
        if k == "separated":
            arr = arr.astype(float)
        data[k] = (dims, arr.astype(str) if k in ("crack_regions", "crack_region") else arr,
                   {"units": units[k]})
    coords = {"solver": solvers, "case": list(CASES), "rule": list(rules),
              "resolution": ("resolution", np.array(res), {"units": "-", "long_name":
                                                           "particles across H"}),
              "time": ("time", time, {"units": "s"}), "part": list(FAILED)}
    ds = xr.Dataset(data, coords=coords)
    ds.attrs["plane"] = "strain" if scene.dim == 2 else PLANE_3D
    if fem is not None:
        _fem_variables(ds, fem, outs, rules, res)
        if static:
            _static_variables(ds, fem, static)
            if scene.dim == 2 or fem.get("root_runs") is not None:  # 3-D: root_ladder's
                _root_variables(ds, fem, static)
    if deletion:
        _deletion_variables(ds, deletion)
    _final_particles(ds, finest, rules, solvers)
    ds.attrs.update(results.provenance(NAME, scene))
    ds.attrs["rules"] = "; ".join(f"{k}: failure {a}, crack {b}" for k, (a, b) in RULES.items()
                                  if k in rules)
    ds.attrs["seeds_um"] = str(np.round(scene.seeds() * 1e6, 3).tolist())
    return ds


def _deletion_variables(ds: xr.Dataset, deletion: dict) -> None:
    """Gate 6's variables: the load history of the FEM with element deletion on the dataset's
    time axis, and per case its status, deleted elements and their regions, and the reference
    centroids of the elements (``fem_element_X``, for the figure)."""
    time = ds.time.values
    load = np.full((len(CASES), len(time)), np.nan)
    defl = np.full((len(CASES), len(time)), np.nan)
    for i, c in enumerate(CASES):
        d = deletion[c]
        if len(d["time"]) > 1 and np.isfinite(d["load"]).any():
            ok = np.isfinite(d["load"])
            load[i] = np.interp(time, d["time"][ok], d["load"][ok], left=np.nan, right=np.nan)
            defl[i] = np.interp(time, d["time"], d["deflection_down"], right=np.nan)
    ds["fem_deletion_load"] = (("case", "time"), load, {
        "units": "N/m", "long_name": "FEM with element deletion: force of the loading patch on "
                                     "the beam, downward (time mean per output interval)"})
    ds["fem_deletion_deflection"] = (("case", "time"), defl, {
        "units": "m", "long_name": "FEM with element deletion: downward displacement of the patch"})
    ds["fem_deletion_status"] = (("case",), np.array([deletion[c]["status"] for c in CASES]),
                                 {"units": "-"})
    ds["fem_deletion_wall_time"] = (("case",), np.array([deletion[c]["wall_time"] for c in CASES]),
                                    {"units": "s"})
    ds["fem_deleted"] = (("case",), np.array([deletion[c]["n_deleted"] for c in CASES]),
                         {"units": "-", "long_name": "elements deleted"})
    ds["fem_deleted_share_low"] = (("case",), np.array([deletion[c]["share_low"] for c in CASES]), {
        "units": "-", "long_name": "share of the deleted elements where the low eps_L is"})
    ds["fem_deleted_regions"] = (("case",), np.array([deletion[c]["regions"] for c in CASES]),
                                 {"units": "-", "long_name": "deleted elements per region"})
    first = deletion[CASES[0]]
    ds["fem_element_X"] = (("fem_element", "dim"), np.asarray(first["centroids"]), {"units": "m"})
    ds["fem_element_region"] = (("fem_element",), first["region"], {
        "units": "-", "long_name": "region index into the attribute region_names"})
    dead = np.zeros((len(CASES), len(first["region"])), np.int8)
    for i, c in enumerate(CASES):
        dead[i, deletion[c]["deleted"]] = 1
    ds["fem_element_deleted"] = (("case", "fem_element"), dead, {"units": "-"})


def _static_variables(ds: xr.Dataset, fem: dict, static: dict) -> None:
    """The static csph runs ``static`` {H/Δx: :func:`.static.csph_static`} on their own coordinate
    ``static_resolution``: the elastic slope of each (the secant at the first path point), its
    error against the FEM's slope limit and the error's observed order (least squares; gate 1),
    wall time and status. In 2-D the ladder and H/Δx = 40 (:data:`.ladders.STATIC_FINEST`), in 3-D
    :data:`.ladders.STATIC_RESOLUTIONS_3D`."""
    sr = sorted(static)
    ds.coords["static_resolution"] = ("static_resolution", np.array(sr), {
        "units": "-", "long_name": "particles across H of the static csph runs (gates 1 and 2)"})
    slope = np.array([static[r].get("elastic_slope", np.nan) for r in sr], float)
    ds["static_elastic_slope"] = (("static_resolution",), slope, {
        "units": "N/m/m" if ds.attrs.get("plane", "strain") == "strain" else "N/m",
        "long_name": "csph (static) secant at the first path point, elastic"})
    ds["static_slope_error"] = (("static_resolution",), np.abs(slope / fem["slope_limit"] - 1), {
        "units": "-", "long_name": "|csph static slope / FEM slope limit - 1|"})
    ds.attrs["static_slope_order"] = observed_order(1.0 / np.array(sr, float),
                                                    ds.static_slope_error.values)
    ds["static_wall_time"] = (("static_resolution",), np.array([static[r]["wall_time"] for r in sr]),
                              {"units": "s"})
    ds["static_status"] = (("static_resolution",), np.array([str(static[r]["status"]) for r in sr]),
                           {"units": "-"})


def _root_variables(ds: xr.Dataset, fem: dict, static: dict) -> None:
    """Gate 2's variables: the first failure in :func:`.static.root_region` of the FEM ladder (load,
    deflection, Richardson limit and its uncertainty, each mesh's error) and of the static csph
    runs ``static`` on ``static_resolution`` (:func:`_static_variables`: load, deflection, error
    against the FEM's limit, and that error's observed order)."""
    force = "N" if _is_3d(ds) else "N/m"
    fr = np.array([fem["first_failure_root"][c] for c in CASES])  # (case, fem_resolution, 2)
    ds["fem_first_failure_root_deflection"] = (("case", "fem_resolution"), fr[..., 0], {"units": "m"})
    ds["fem_first_failure_root_load"] = (("case", "fem_resolution"), fr[..., 1], {
        "units": force, "long_name": "FEM load at the first failure in the root region (gate 2)"})
    ds["fem_root_limit"] = (("case",), np.array([fem["root_limit"][c] for c in CASES]), {
        "units": force, "long_name": "its Richardson limit at the singular order"})
    ds["fem_root_limit_spread"] = (("case",), np.array([fem["root_limit_spread"][c] for c in CASES]), {
        "units": "-", "long_name": "that limit's uncertainty: |limit at the singular order - limit "
                                   "at the observed order| / limit"})
    ds["fem_root_error"] = (("case", "fem_resolution"), np.array([fem["root_error"][c] for c in CASES]),
                            {"units": "-", "long_name": "|load - limit| / limit (the FEM's own error)"})
    ds["fem_root_order"] = (("case",), np.array([fem["root_order"][c] for c in CASES]), {"units": "-"})
    if fem.get("root_runs") is not None:  # root_ladder: the FEM's own runs along the root path
        ds["fem_root_wall_time"] = (("fem_resolution",), np.array(
            [fem["root_runs"][r]["wall_time"] for r in fem["resolutions"]], float), {
            "units": "s", "long_name": "wall time of the FEM's run along the root path"})
    sr = sorted(static)
    cs = np.array([[static[r]["first_failure_root"][c] for r in sr] for c in CASES], float)
    ds["static_first_failure_root_deflection"] = (("case", "static_resolution"), cs[..., 0],
                                                  {"units": "m"})
    ds["static_first_failure_root_load"] = (("case", "static_resolution"), cs[..., 1], {
        "units": force, "long_name": "csph (static, no damage) load at the first failure in the "
                                    "root region (gate 2)"})
    lim = ds.fem_root_limit.values[:, None]
    ds["static_root_error"] = (("case", "static_resolution"), np.abs(cs[..., 1] / lim - 1), {
        "units": "-", "long_name": "|csph load / FEM limit - 1|"})
    inv = 1.0 / np.array(sr, float)
    ds["static_root_order"] = (("case",), np.array([observed_order(inv, e) for e in
                                                    ds.static_root_error.values]), {
        "units": "-", "long_name": "observed order of static_root_error (least squares)"})


def _fem_variables(ds: xr.Dataset, fem: dict, outs: dict, rules, res) -> None:
    """Gate 1's variables: the FEM curves, slopes and first failures, and the csph slope over the
    FEM's elastic window with its error against the FEM's limit."""
    fr = fem["resolutions"]
    runs = fem["runs"]
    d = runs[fr[0]]["deflection"]
    plane = ds.attrs.get("plane", "strain") == "strain"
    force = "N/m" if plane else "N"
    ds.coords["fem_resolution"] = ("fem_resolution", np.array(fr), {
        "units": "-", "long_name": "elements across H (9-node quadrilaterals)" if plane else
        "elements across H (27-node hexahedra; beyond the coarsest, the first path point only"
        + (" of the root path)" if fem.get("root_runs") is not None else ")")})
    ds.coords["fem_deflection"] = ("fem_deflection", d, {"units": "m"})
    data = {}
    data["fem_load"] = (("fem_resolution", "fem_deflection"),
                        np.array([runs[r]["load"] for r in fr]),
                        {"units": force, "long_name": "FEM static load of the patch (no damage)"})
    data["fem_max_damage"] = (("case", "fem_resolution", "fem_deflection"),
                              np.array([[runs[r]["damage"][c] for r in fr] for c in CASES]),
                              {"units": "-", "long_name": "largest eps_p/eps_L over the points"})
    data["fem_elastic_slope"] = (("fem_resolution",), fem["slopes"], {"units": force + "/m"})
    data["fem_slope_error"] = (("fem_resolution",), fem["slope_error"], {
        "units": "-", "long_name": "|slope - Richardson limit| / limit (the FEM's own error)"})
    data["fem_wall_time"] = (("fem_resolution",), np.array([runs[r]["wall_time"] for r in fr]),
                             {"units": "s"})
    ff = np.array([fem["first_failure"][c] for c in CASES])  # (case, fem_resolution, 2)
    data["fem_first_failure_deflection"] = (("case", "fem_resolution"), ff[..., 0], {"units": "m"})
    data["fem_first_failure_load"] = (("case", "fem_resolution"), ff[..., 1], {"units": force})
    dims = ("solver", "case", "rule", "resolution")
    solvers = list(ds.solver.values)
    shp = (len(solvers), len(CASES), len(rules), len(res))
    slope = np.full(shp, np.nan)
    for (solver, case, rule, r), out in outs.items():
        if len(out.get("time", ())) > 3:
            fail = np.flatnonzero(np.asarray(out["failed"]) > 0)
            tf = float(np.asarray(out["time"])[fail[0]]) if fail.size else np.inf
            k = (solvers.index(solver), CASES.index(case), rules.index(rule), res.index(r))
            slope[k] = csph_slope(out["deflection_down"], out["load"], out["time"], tf,
                                  fem["window"])
    lim = fem["slope_limit"]
    data["elastic_slope_fem_window"] = (dims, slope, {
        "units": force + "/m", "long_name": "csph elastic slope over the FEM's elastic window"})
    data["slope_error_fem"] = (dims, np.abs(slope / lim - 1), {
        "units": "-", "long_name": "|csph slope / FEM limit - 1|"})
    same = np.full(shp, np.nan)
    for j, r in enumerate(res):
        if r in fr:
            same[..., j] = slope[..., j] / fem["slopes"][fr.index(r)] - 1
    data["slope_vs_fem_same_resolution"] = (dims, same, {
        "units": "-", "long_name": "csph slope / FEM slope at the same H/dx - 1"})
    for k, v in data.items():
        ds[k] = v
    ds.attrs.update(fem_slope_limit=float(lim), fem_observed_order=float(fem["observed_order"]),
                    fem_slope_limit_spread=float(fem.get("slope_limit_spread", np.nan)),
                    fem_slope_window_m=str([float(w) for w in fem["window"]]),
                    fem_assumed_order=SINGULAR_ORDER)


def _final_particles(ds: xr.Dataset, finest: dict, rules, solvers=("csph",)) -> None:
    """The final particles of the finest run of each solver, case and rule (padded to the largest
    count); ``finest`` {(solver, case, rule): (resolution, driver output)}."""
    if not finest:
        return
    solvers = list(solvers)
    n = max(len(o["x"]) for _, o in finest.values())
    d = next(iter(finest.values()))[1]["x"].shape[1]
    shp = (len(solvers), len(CASES), len(rules))
    X = np.full(shp + (n, d), np.nan)
    x = np.full_like(X, np.nan)
    grain = np.full(shp + (n,), -1, np.int64)
    failed = np.zeros(shp + (n,), np.int8)
    names = None
    at = np.zeros(shp, np.int64)
    for (solver, case, rule), (r, o) in finest.items():
        k = (solvers.index(solver), CASES.index(case), rules.index(rule))
        at[k] = r
        m = len(o["x"])
        X[k][:m], x[k][:m] = o["X"], o["x"]
        grain[k][:m] = o["region"]
        failed[k][:m] = np.asarray(o.get("failed_particles", np.zeros(m)), np.int8)
        names = o["region_names"]
    dims = ("solver", "case", "rule")
    ds["particle_X"] = (dims + ("particle", "axis"), X, {"units": "m", "long_name":
                        "reference positions, finest resolution (NaN: padding)"})
    ds["particle_x"] = (dims + ("particle", "axis"), x, {"units": "m", "long_name":
                        "final positions, finest resolution"})
    ds["particle_region"] = (dims + ("particle",), grain, {"units": "-", "long_name":
                             "region index into the attribute region_names (-1: padding)"})
    ds["particle_failed"] = (dims + ("particle",), failed, {"units": "-"})
    ds["particle_resolution"] = (dims, at, {"units": "-", "long_name":
                                 "H/dx of the run whose final particles these are (0: none)"})
    ds.attrs["region_names"] = ", ".join(names)


def _is_3d(ds: xr.Dataset) -> bool:
    return ds.attrs.get("plane") == PLANE_3D
