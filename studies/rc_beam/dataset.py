"""The RC beam study's dataset (``rc_beam.nc``) from its runs: the histories per solver × specimen ×
resolution × time, the scalars of :func:`.derive.run_summary` with their units, the kernel-reduction
runs, the modal check, the final cracked particles and (full run) the slow impact's variables."""
from __future__ import annotations

import numpy as np
import xarray as xr

from workbench import results

from .derive import (ANGLE_BINS, LOAD_CELL_WINDOW, PAPER, PAPER_LOAD_CELL_RANGE, TRUNCATION_MARGIN,
                     crack_orientation, energy_error, history_maximum, run_summary, window_mean)
from .ladders import (KERNEL_REDUCTION_SPECIMEN, MODAL_RESOLUTION, MODAL_SOLVERS, NAME, OPTIONS,
                      QUICK_T_END, SPECIMENS, scene_for)
from .scene import RCBeam
from .scene import SPECIMENS as SPECIMENS_OF
from .slow_impact import _slow


N_TIME = 201

SERIES = {
    "midspan_displacement": ("midspan_displacement", "m", "mid-span displacement of the beam's "
                             "bottom, positive downward", 1.0),
    "impact_force": ("impact_force", "N", "contact force of the plate on the weight (at the "
                     "record)", 1.0),
    "support_reaction": ("support_reaction", "N", "contact force of both supports on the beam "
                         "(at the record)", 1.0),
    "impact_impulse": ("impact_impulse", "N s", "impulse of the plate's push on the weight since "
                       "t = 0 (the weight's change of z momentum: exact at any record interval)",
                       1.0),
    "impact_force_window": ("impact_force_window", "N", "impact force as a load cell sees it: its "
                            f"time mean over the last {LOAD_CELL_WINDOW * 1e3:g} ms, from the "
                            "impulse", 1.0),
    "support_reaction_mean": ("support_reaction_mean", "N", "force holding both supports, time "
                              "mean over the interval since the previous record", 1.0),
    "kinetic_energy": ("kinetic_energy", "J", "kinetic energy (full beam and weight)", 4.0),
    "strain_energy": ("strain_energy", "J", "stored elastic energy with the contact's penalty "
                      "energy (full beam and weight)", 4.0),
    "plastic_work": ("plastic_work", "J", "plastic work (full beam)", 4.0),
    "released_energy": ("released_energy", "J", "energy released by cracking (stress release, "
                        "full beam)", 4.0),
    "viscous_work": ("viscous_work", "J", "energy dissipated by sph's artificial viscosity "
                     "(its option viscous_work; full beam and weight; 0 for csph)", 4.0),
    "external_work": ("external_work", "J", "work of loads and prescribed motion (none here)", 4.0),
}

SCALARS = dict(max_displacement=("m", "largest mid-span displacement over the run: its maximum "
                                "only where not max_displacement_truncated, else a lower bound"),
               max_displacement_time=("s", "time of the largest mid-span displacement"),
               max_displacement_truncated=("-", "1: the largest mid-span displacement comes less "
                                           f"than {TRUNCATION_MARGIN * 1e3:g} ms before the run's "
                                           "end (truncated at t_end: a lower bound, not a "
                                           "maximum); 0: a maximum"),
               residual_displacement=("m", "mid-span displacement, mean over the last 20 % of the run"),
               max_impact_force=("N", "largest impact force at the records (the penalty's "
                                 "instantaneous force: depends on the record interval, not what a "
                                 "load cell reads; see impact_force_window_peak)"),
               impact_force_window_peak=("N", "largest impact force as a load cell sees it: its "
                                         f"time mean over {LOAD_CELL_WINDOW * 1e3:g} ms, from the "
                                         "impulse (independent of the record interval)"),
               impact_force_window_peak_time=("s", "end of the window of "
                                              "impact_force_window_peak"),
               impact_force_window_peak_truncated=("-", "1: impact_force_window_peak comes less "
                                                   f"than {TRUNCATION_MARGIN * 1e3:g} ms before "
                                                   "the run's end (a lower bound)"),
               max_support_reaction=("N", "largest support reaction at the records (the "
                                     "penalty's instantaneous force: depends on the record "
                                     "interval)"),
               energy_balance_error=("-", "max over time |initial KE - (K + E + contact + W_p + "
                                     "W_rel + viscous)| / initial KE"),
               momentum_error=("-", "max over time |p_z - p_z(0) - support impulse| / |p_z(0)|"),
               **{f"cracked_{k}": ("-", f"mortar particles with an open crack (a fully "
                                   "released direction: the damage tensor's largest eigenvalue "
                                   "1; without a history the residual strain above the release "
                                   f"strain) opening {lo:g}-{hi:g} deg from the span, over all "
                                   "mortar particles")
                  for k, (lo, hi) in ANGLE_BINS.items()},
               **{f"strain_cracked_{k}": ("-", "the residual-strain stand-in of cracked_"
                                          f"{k} (largest principal residual strain above the "
                                          "release strain, along it)")
                  for k in ANGLE_BINS})
CRACK_SCALARS = dict(
    crack_area=("m^2", "crack area, full beam: fully released mortar volume / (2 dx), the crack "
                "band two particles wide (workbench.scenes.crack_band)"),
    released_per_crack_area=("J/m^2", "energy released by cracking at the end of the run over the "
                             "crack area"),
    released_per_crack_area_over_GF=("-", "released_per_crack_area over eq. 5's G_F(dx) = f_t "
                                     "eps_0(dx) dx / 2 (2 for bands of fully released particles "
                                     "alone)"),
    released_share_full=("-", "share of the released energy in the fully released mortar "
                         "particles"))
"""Issue 12 gate 6, the energy released per crack area (:func:`.derive.crack_band_energy`)."""
SCALARS.update(CRACK_SCALARS)


def dataset(scene: RCBeam, outs: dict, solvers, res, quick: bool, modal: dict | None = None,
            kr: dict | None = None, slow: dict | None = None) -> xr.Dataset:
    """The study's dataset from the runs ``outs`` {(solver, specimen, resolution): driver output},
    the modal runs ``modal`` {(csph | fem, specimen): output} of gate 2 and classic SPH's runs with
    the kernel reduction ``kr`` {resolution: output} (specimen
    :data:`.ladders.KERNEL_REDUCTION_SPECIMEN`) and the slow impact's runs ``slow`` {key of
    :func:`.slow_impact.slow_impact_tasks`: output}."""
    t_end = min(scene.t_end, QUICK_T_END) if quick else scene.t_end
    time = np.linspace(0.0, t_end, N_TIME)
    dims = ("solver", "specimen", "resolution")
    shp = (len(solvers), len(SPECIMENS), len(res))
    series = {n: np.full(shp + (N_TIME,), np.nan) for n in SERIES}
    extra = {n: np.full(shp + (N_TIME,), np.nan) for n in ("energy_error", "momentum_z",
                                                              "support_impulse")}
    scal = {k: np.full(shp, np.nan) for k in SCALARS}
    status = np.full(shp, "not run", dtype=object)
    wall, loop, pss, dt = (np.full(shp, np.nan) for _ in range(4))
    npart, steps = np.zeros(shp, np.int64), np.zeros(shp, np.int64)
    cracks = {}
    for (s, sp, r), out in outs.items():
        idx = (solvers.index(s), SPECIMENS.index(sp), res.index(r))
        status[idx] = str(out.get("status", "error: no status"))
        wall[idx] = float(out.get("run_wall_time", out.get("wall_time", np.nan)))
        loop[idx] = float(out.get("loop_time", np.nan))
        pss[idx] = float(out.get("particle_steps_per_second", np.nan))
        dt[idx] = float(out.get("dt", np.nan))
        npart[idx] = int(out.get("n_particles", 0))
        steps[idx] = int(out.get("steps", 0))
        t = np.asarray(out.get("time", ()), float)
        if len(t) < 2:
            continue
        sc = scene_for(scene, sp, quick)
        derived = {}
        if "impact_impulse" in out:  # the load cell's force at the records, from the impulse
            derived["impact_force_window"] = window_mean(t, out["impact_impulse"])
        have = {**out, **derived}
        for n, (src, _, _, f) in SERIES.items():
            if src in have:
                y = np.asarray(have[src], float)
            elif src in ("impact_impulse", "impact_force_window"):
                y = np.full_like(t, np.nan)  # a run without the weight's momentum: not known
            else:
                y = np.zeros_like(t)
            series[n][idx] = np.interp(time, t, f * y, right=np.nan)
        extra["energy_error"][idx] = np.interp(time, t, energy_error(out), right=np.nan)
        p = np.asarray(out["linear_momentum"], float)[:, 2]
        extra["momentum_z"][idx] = np.interp(time, t, 4.0 * p, right=np.nan)
        R = np.asarray(out.get("support_hold", np.zeros_like(t)), float)
        imp = np.concatenate([[0.0], np.cumsum(R[1:] * np.diff(t))])
        extra["support_impulse"][idx] = np.interp(time, t, 4.0 * imp, right=np.nan)
        for k, v in run_summary(out, sc, r).items():
            scal[k][idx] = v
        if r == max(res) and "x" in out and np.isfinite(out["x"]).all():
            cracks[(s, sp)] = crack_orientation(sc, r, np.asarray(out["x"]), out.get("history"))
    data = {n: (dims + ("time",), series[n], {"units": u, "long_name": ln})
            for n, (_, u, ln, _) in SERIES.items()}
    data["energy_error"] = (dims + ("time",), extra["energy_error"], {
        "units": "-", "long_name": "(K + E + contact + W_p + W_rel + viscous - W_ext)(t) minus its "
        "initial value, over the initial kinetic energy"})
    data["momentum_z"] = (dims + ("time",), extra["momentum_z"], {
        "units": "kg m/s", "long_name": "z momentum of weight plus beam (full model)"})
    data["support_impulse"] = (dims + ("time",), extra["support_impulse"], {
        "units": "N s", "long_name": "impulse the supports gave since t = 0 (full model)"})
    for k, (u, ln) in SCALARS.items():
        data[k] = (dims, scal[k], {"units": u, "long_name": ln})
    data["status"] = (dims, status.astype(str), {"units": "-"})
    data["wall_time"] = (dims, wall, {"units": "s", "long_name": "run wall time, set-up included"})
    data["loop_time"] = (dims, loop, {"units": "s", "long_name": "time loop alone"})
    data["particle_steps_per_second"] = (dims, pss, {"units": "1/s", "long_name":
                                                     "particles x steps / time-loop wall time"})
    data["dt"] = (dims, dt, {"units": "s", "long_name": "time step"})
    data["n_particles"] = (dims, npart, {"units": "-"})
    data["steps"] = (dims, steps, {"units": "-"})
    coords = {"solver": list(solvers), "specimen": list(SPECIMENS),
              "resolution": ("resolution", np.array(res), {"units": "-", "long_name":
                                                           "particles across H"}),
              "spacing": ("resolution", scene.H / np.array(res, float), {"units": "m"}),
              "time": ("time", time, {"units": "s"})}
    ds = xr.Dataset(data, coords=coords)
    _crack_particles(ds, cracks, solvers)
    _modal(ds, modal or {})
    _kernel_reduction(ds, outs, kr or {}, res, time)
    _slow(ds, scene, slow)
    ds.attrs.update(results.provenance(NAME, scene))
    ran = [sp for sp in SPECIMENS if any(k[1] == sp for k in outs)]
    # the scene's own parameters describe its default specimen and length (A, 10 ms): the
    # attributes say what ran — the specimens (each with its span and speed) and the run length
    ds.attrs.update(param_specimen=", ".join(ran) or "none", param_t_end=t_end,
                    specimens_run=", ".join(ran) or "none",
                    **{f"specimen_{sp}_{k}": v for sp in ran for k, v in (
                        ("span", SPECIMENS_OF[sp]["span"]),
                        ("impact_velocity", scene_for(scene, sp, quick).impact_velocity))})
    ds.attrs.update(
        plane="none (3-D)", quick=int(quick),
        truncation_margin=TRUNCATION_MARGIN, load_cell_window=LOAD_CELL_WINDOW,
        paper_load_cell_range=PAPER_LOAD_CELL_RANGE,
        options="; ".join(f"{s}: {OPTIONS[s]}" for s in solvers),
        angle_bins="; ".join(f"{k}: {lo:g}-{hi:g} deg" for k, (lo, hi) in ANGLE_BINS.items()),
        crack_measure="the mortar's damage tensor from the final history: cracked where its "
                      "largest eigenvalue reaches 1 (fully released), the opening direction its "
                      "principal direction; strain_cracked_*: the stand-in, the largest principal "
                      "residual Green-Lagrange strain above the release strain eps_release(dx) (F "
                      "by csph's corrected gradients on the reference neighbours)",
        model="quarter model by two symmetry planes; forces and energies x 4 (the full beam)",
        paper_B_max_displacement=PAPER["B"]["max_displacement"],
        paper_B_max_displacement_kernel_reduction=PAPER["B"]["max_displacement_kernel_reduction"],
        paper_note="003 gives A's displacement history only in Fig. 17 (no number in the text); "
                   "the kernel reduction of 003 4.2(2): classic SPH's kernel_reduction option, "
                   "specimen B in a full run (kr_* variables)")
    return ds


def _kernel_reduction(ds, outs: dict, kr: dict, res, time) -> None:
    """Classic SPH on specimen :data:`.ladders.KERNEL_REDUCTION_SPECIMEN` without (the main runs)
    and with the kernel reduction of 003 §4.2(2): the ``kernel_reduction`` dimension (0: without, 1:
    with) of the mid-span displacement history, its largest value and the run status."""
    if not kr:
        return
    sp = KERNEL_REDUCTION_SPECIMEN
    w = np.full((2, len(res), len(time)), np.nan)
    wmax = np.full((2, len(res)), np.nan)
    wcut = np.full((2, len(res)), np.nan)
    status = np.full((2, len(res)), "not run", dtype=object)
    for k, runs in enumerate(({r: outs.get(("sph", sp, r)) for r in res}, kr)):
        for r, out in runs.items():
            if out is None or r not in res:
                continue
            j = res.index(r)
            status[k, j] = str(out.get("status", "error: no status"))
            t = np.asarray(out.get("time", ()), float)
            if len(t) < 2:
                continue
            y = np.asarray(out["midspan_displacement"], float)
            w[k, j] = np.interp(time, t, y, right=np.nan)
            if np.isfinite(y).all():
                wmax[k, j], _, cut = history_maximum(t, y)
                wcut[k, j] = float(cut)
    ds.coords["kernel_reduction"] = ("kernel_reduction", np.array([0, 1]), {
        "units": "-", "long_name": "003 4.2(2) kernel reduction across fully released mortar "
        "particles (classic SPH, phi_min = 0.05): 0 without, 1 with"})
    dims = ("kernel_reduction", "resolution")
    ds["kr_midspan_displacement"] = (dims + ("time",), w, {
        "units": "m", "long_name": f"specimen {sp}, sph: mid-span displacement, positive downward"})
    ds["kr_max_displacement"] = (dims, wmax, {
        "units": "m", "long_name": f"specimen {sp}, sph: largest mid-span displacement (a lower "
        "bound where kr_max_displacement_truncated)"})
    ds["kr_max_displacement_truncated"] = (dims, wcut, {
        "units": "-", "long_name": "1: the largest mid-span displacement comes less than "
        f"{TRUNCATION_MARGIN * 1e3:g} ms before the run's end (truncated at t_end)"})
    ds["kr_status"] = (dims, status.astype(str), {"units": "-"})


def _modal(ds, modal: dict) -> None:
    """Gate 2's first flexural frequencies (the lowest mode of the hinged beam with rebar)."""
    if not modal:
        return
    f = np.full((len(MODAL_SOLVERS), len(SPECIMENS)), np.nan)
    wall = np.full_like(f, np.nan)
    status = np.full(f.shape, "not run", dtype=object)
    for (s, sp), out in modal.items():
        i, j = MODAL_SOLVERS.index(s), SPECIMENS.index(sp)
        status[i, j] = str(out.get("status", "error: no status"))
        wall[i, j] = float(out.get("run_wall_time", out.get("wall_time", np.nan)))
        p = np.atleast_1d(out.get("periods", [np.nan]))
        f[i, j] = 1.0 / float(p[0]) if np.isfinite(p[0]) and p[0] > 0 else np.nan
    ds.coords["modal_solver"] = list(MODAL_SOLVERS)
    ds["first_frequency"] = (("modal_solver", "specimen"), f, {
        "units": "Hz", "long_name": f"first flexural frequency of the beam with rebar on hinges "
        f"(structure='beam'), H/dx = {MODAL_RESOLUTION}"})
    ds["modal_status"] = (("modal_solver", "specimen"), status.astype(str), {"units": "-"})
    ds["modal_wall_time"] = (("modal_solver", "specimen"), wall, {"units": "s"})
    ds["frequency_error"] = (("specimen",), f[0] / f[1] - 1.0, {
        "units": "-", "long_name": "csph's first frequency over the FEM's, minus 1"})


def _crack_particles(ds, cracks: dict, solvers) -> None:
    """The mortar particles of the finest run of each solver and specimen (padded to the largest
    count) with their residual principal strain and opening direction, for the crack figure."""
    if not cracks:
        return
    n = max(len(c["X"]) for c in cracks.values())
    shp = (len(solvers), len(SPECIMENS), n)
    X = np.full(shp + (3,), np.nan)
    nvec = np.full(shp + (3,), np.nan)
    strain = np.full(shp, np.nan)
    damage = np.full(shp, np.nan)
    for (s, sp), c in cracks.items():
        i, j, k = solvers.index(s), SPECIMENS.index(sp), len(c["X"])
        X[i, j, :k], nvec[i, j, :k], strain[i, j, :k] = c["X"], c["direction"], c["strain"]
        damage[i, j, :k] = c["damage"]
    ds["mortar_X"] = (("solver", "specimen", "particle", "axis"), X, {
        "units": "m", "long_name": "reference positions of the mortar particles, finest run (NaN: padding)"})
    ds["mortar_strain"] = (("solver", "specimen", "particle"), strain, {
        "units": "-", "long_name": "largest principal residual strain at the end of the run"})
    ds["mortar_damage"] = (("solver", "specimen", "particle"), damage, {
        "units": "-", "long_name": "largest eigenvalue of the damage tensor at the end of the run "
        "(NaN: no history)"})
    ds["mortar_opening"] = (("solver", "specimen", "particle", "axis"), nvec, {
        "units": "-", "long_name": "the crack opening direction: the damage tensor's principal "
        "direction (the residual strain's without a history)"})
