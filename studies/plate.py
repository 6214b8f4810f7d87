"""Plate study: the oscillating clamped plate of 004 D (Table I; Gray, Monaghan & Swift 2001),
plane strain, rigid clamp.

References: the thin-plate period and amplitude (004 eq. 13–16) as ``analytic``; the FEM modal
period of the same 2-D plate with the same clamp (the continuum reference, ~0.46 % above thin-plate
theory) — every discrete period is measured against the FEM modal period extrapolated to zero element
size. Table I of 004 is reproduced as dimensionless period T c0 / L and amplitude A / L.
"""
from __future__ import annotations

import sys

import numpy as np
import xarray as xr

from workbench import analytic, results
from workbench.oscillation import with_period_notes
from workbench.scenes import Plate

from .common import Gate, field_options, field_series, observed_order, validate
from .common import ladders as study_ladders
from .sweep import Task, run_tasks

NAME = "plate"
SCENE = Plate
SOLVERS = ("analytic", "fem", "csph", "csph_quad", "csph_bl", "hpm", "hpm_vc", "sph")
# Intervals across H (spacing H/r; r quadratic elements). The FEM's modal period is cheap on every rung; its one
# dynamic run (period and amplitude from the tip history) is at FEM_DYNAMIC.
RESOLUTIONS = {"fem": (2, 4, 8, 16), "csph": (5, 10, 20, 40), "csph_quad": (5, 10, 20),
               "csph_bl": (5, 10, 20), "hpm": (5, 10, 20), "hpm_vc": (5, 10, 20), "sph": (5, 10)}
QUICK_RESOLUTIONS = {"fem": (2, 4, 8), "csph": (5, 10), "hpm": (10,), "sph": (5,)}
FEM_DYNAMIC = {False: 8, True: 4}  # by quick
ERROR_LABEL = "relative period error vs converged FEM modal period [-]"
N_TIME = 401  # common time grid of the stored tip histories

# The FEM modal period against thin-plate theory: shear and rotary inertia lengthen the 2-D
# continuum's period by ~0.46 % at H/L = 0.1 (notes.md); the clamp is rigid in both. 1 % bounds it.
TOL_FEM_THIN_PLATE = 0.01
# Particle methods at H/Δx = 10 against the FEM modal period (issues 4 and 5): 3 % (004's HPM model
# is 2.7 % from thin-plate theory); amplitude within 5 % of the FEM's dynamic amplitude (the linear
# thin-plate amplitude ignores the 2-D and nonlinear effects). Energy drift of the symplectic
# schemes below 0.1 % over the run (two periods) without damping.
TOL_PERIOD = 0.03
TOL_AMPLITUDE = 0.05
TOL_DRIFT = 1e-3
GATED = ("csph", "hpm", "hpm_vc")
# The integration-consistent methods (csph; hpm_vc: HPM's gradient with consistent integration):
# second order, the period's error half the stiffness error, O((Δx/H)²)/8 ≈ 0.1 % at H/Δx = 10
# (the clamped corners are cut out of the integration; the dynamic run's finite amplitude shifts
# the period by ~0.015 % against the modal reference). The nodal variants miss it: csph_quad by
# 0.19 %, csph_bl by 2.7 %, hpm by 1.8 %.
TOL_PERIOD_CONSISTENT = 1e-3
CONSISTENT = ("csph", "hpm_vc")
# csph at H/Δx = 40 (full ladder): issue 10's target 0.05 % (second order predicts 0.006 % from the
# 0.1 % bound at 10; the finite amplitude's ~0.015 % shift against the modal reference remains),
# and the observed order over 5 … 40 at least 1.5 (second order expected; nodal integration ~1).
TOL_PERIOD_FINE = 5e-4
MIN_ORDER = 1.5
# Method options of this study: classic SPH on the cell lattice (Gray et al.'s arrangement; the
# free surfaces half a spacing outside the outermost particles), the others on the node lattice.
OPTIONS = {"sph": {"lattice": "cell"}}  # classic SPH is the baseline: it is expected to fail, not gated
# The field snapshot of the report: the CSPH series (finest written), deformed particles coloured
# by the von Mises stress, at the frame of largest displacement.
FIELD_VIEW = dict(prefer="plate_csph", scalars="von_mises", label="von Mises stress [Pa]")
# Table I (004): T c0 / L and A / L.
TABLE_I = analytic.TABLE_I


def run(scene: Plate | None = None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None, fields=None, field_runs=None) -> xr.Dataset:
    """``fields`` (a folder, or None): the particle runs write their fields there as ParaView
    series (``field_runs``: the (solver, resolution) pairs that do; None: all); the names of the
    written series are the dataset's ``field_series`` attribute. The FEM writes its mesh for the dynamic rung only."""
    scene = scene or Plate()
    validate(sys.modules[__name__], scene, solvers, resolutions, quick)  # before any work
    solvers = list(solvers or SOLVERS)
    if "analytic" not in solvers:
        solvers.insert(0, "analytic")
    if "fem" not in solvers:
        solvers.insert(1, "fem")
    solvers, ladders = study_ladders(solvers, resolutions, sys.modules[__name__], quick)
    all_res = sorted({r for lad in ladders.values() for r in lad})
    T0 = analytic.plate_period(scene)
    A0 = analytic.plate_amplitude(scene)
    time = np.linspace(0.0, scene.periods * T0, N_TIME)
    shp = (len(solvers), len(all_res))
    period = np.full(shp, np.nan)
    amplitude = np.full(shp, np.nan)
    drift = np.full(shp, np.nan)
    wall = np.full(shp, np.nan)
    npart = np.zeros(shp, dtype=np.int64)
    status = np.full(shp, "not run", dtype=object)
    hist = np.full(shp + (N_TIME,), np.nan)
    # The FEM contributes its modal period on every rung and one dynamic run on the finest.
    dyn = FEM_DYNAMIC[bool(quick)]
    tasks = [Task.make(s, scene, r, **({"dynamic": r == dyn} if s == "fem" else OPTIONS.get(s, {})),
                       **field_options(s, r, fields, field_runs))
             for s, lad in ladders.items() for r in lad]
    outs = dict(zip(((t.solver, t.resolution) for t in tasks), run_tasks(tasks, scheduler, NAME)))
    for i, s in enumerate(solvers):
        if s == "analytic":
            period[i] = T0
            amplitude[i] = A0
            hist[i] = A0 * np.sin(2 * np.pi * time / T0)  # linear thin-plate response
            status[i] = "ok"
            wall[i] = 0.0
            continue
        for r in ladders[s]:
            j = all_res.index(r)
            out = outs[(s, r)]
            # a period that could not be measured says why (issue 38.4: no oscillation)
            status[i, j] = (with_period_notes(out["status"], out, ["period"])
                            if isinstance(out["status"], str) else str(out["status"]))
            period[i, j] = out.get("period", np.nan)
            amplitude[i, j] = out.get("amplitude", np.nan)
            # the FEM's period is the modal one: its cost is the modal solve's
            wall[i, j] = float(out.get("wall_time_modal", np.sum(out.get("wall_time", np.nan))))
            npart[i, j] = int(out.get("n_particles", out.get("n_dof", 0)))
            if "time" in out and "tip_displacement" in out and len(out["time"]) > 1:
                hist[i, j] = np.interp(time, out["time"], out["tip_displacement"], right=np.nan)
            ke, se = out.get("kinetic_energy"), out.get("strain_energy")
            if ke is not None and se is not None and len(ke) > 1:
                e = np.asarray(ke) + np.asarray(se)
                drift[i, j] = (e[-1] - e[0]) / e[0] if e[0] != 0 else np.nan  # no energy: no drift
    ds = xr.Dataset(
        {
            "period": (("solver", "resolution"), period, {"units": "s", "long_name":
                       "period from the tip history (fem: the modal eigenvalue)"}),
            "amplitude": (("solver", "resolution"), amplitude, {"units": "m", "long_name": "tip amplitude"}),
            "tip_displacement": (("solver", "resolution", "time"), hist,
                                 {"units": "m", "long_name": "vertical tip displacement"}),
            "energy_drift": (("solver", "resolution"), drift, {"units": "-", "long_name":
                             "relative change of total energy over the run"}),
            "wall_time": (("solver", "resolution"), wall, {"units": "s"}),
            "n_particles": (("solver", "resolution"), npart, {"units": "-", "long_name":
                            "particles (particle methods) or degrees of freedom (fem)"}),
            "status": (("solver", "resolution"), status.astype(str), {"units": "-"}),
        },
        coords={"solver": solvers, "resolution": ("resolution", np.array(all_res),
                                                  {"units": "-", "long_name": "intervals across H (spacing H/r): r + 1 particles (node lattice), r (cell), r elements"}),
                "time": ("time", time, {"units": "s"})},
    )
    ds["period_nondim"] = (ds.period * scene.c0 / scene.L).assign_attrs(units="-", long_name="T c0 / L")
    ds["amplitude_nondim"] = (ds.amplitude / scene.L).assign_attrs(units="-", long_name="A / L")
    ds["fem_modal_converged"] = ((), _extrapolated(ds.period.sel(solver="fem").values, ds.resolution.values),
                                 {"units": "s", "long_name": "FEM modal period extrapolated to zero element size"})
    ds.attrs.update(results.provenance(NAME, scene))
    if fields is not None:
        ds.attrs["field_series"] = field_series(scene, tasks)
    ds.attrs.update(analytic_period=T0, analytic_amplitude=A0, plane="strain",
                    clamp="rigid: particles in the clamp block fixed; FEM clamps X = 0")
    return ds


def _extrapolated(values, res) -> float:
    ok = np.isfinite(values)
    v, r = values[ok], res[ok]
    if len(v) == 0:
        return float("nan")
    if len(v) >= 3 and r[-1] == 2 * r[-2] and r[-2] == 2 * r[-3]:
        q = (v[-1] - v[-2]) / (v[-2] - v[-3]) if v[-2] != v[-3] else 0.0
        if 0 < q < 1:
            return float(v[-1] + (v[-1] - v[-2]) * q / (1 - q))
    return float(v[-1])


def errors(ds: xr.Dataset) -> list[dict]:
    ref = float(ds.fem_modal_converged)
    rows = []
    for s in ds.solver.values:
        if s == "analytic":
            continue
        for j, r in enumerate(ds.resolution.values):
            v = ds.period.sel(solver=s).values[j]
            if np.isfinite(v):
                rows.append(dict(solver=str(s), resolution=int(r), error=abs(v - ref) / ref,
                                 wall_time=float(ds.wall_time.sel(solver=s).values[j])))
    return rows


def orders(ds: xr.Dataset) -> dict:
    ref = float(ds.fem_modal_converged)
    out = {}
    for s in ds.solver.values:
        if s == "analytic":
            continue
        v = ds.period.sel(solver=s).values
        keep = np.isfinite(v)
        h = 1.0 / ds.resolution.values[keep]
        if s == "fem":
            if keep.sum() >= 4:
                out["fem (successive differences)"] = observed_order(h[1:], np.diff(v[keep]))
            continue
        out[s] = observed_order(h, v[keep] - ref)
    return out


def table_I(ds: xr.Dataset) -> list[list[str]]:
    rows = [["source", "T c0 / L", "A / L"]]
    for name, (t, a) in TABLE_I.items():
        rows.append([name, f"{t:.2f}", f"{a:.3f}"])
    for s in ds.solver.values:
        pn = ds.period_nondim.sel(solver=s).values
        an = ds.amplitude_nondim.sel(solver=s).values
        ok = np.flatnonzero(np.isfinite(pn))
        if ok.size:
            j = ok[-1]
            res = "" if s == "analytic" else f" (H/dx = {int(ds.resolution.values[j])})"
            a = f"{an[j]:.3f}" if np.isfinite(an[j]) else "-"
            rows.append([f"{s}{res}, this workbench", f"{pn[j]:.2f}", a])
    return rows


def report_tables(ds: xr.Dataset) -> list[dict]:
    return [dict(title="Table I of 004, reproduced (dimensionless period and amplitude):",
                 table=table_I(ds))]


def gates(ds: xr.Dataset) -> list[Gate]:
    g = []
    fem = ds.period.sel(solver="fem").values
    T0 = ds.attrs["analytic_period"]
    if np.isfinite(fem).any():
        finest = fem[np.flatnonzero(np.isfinite(fem))[-1]]
        g.append(Gate.at_most("plate fem: modal period vs thin-plate theory",
                              abs(finest - T0) / T0, TOL_FEM_THIN_PLATE,
                              "shear and rotary inertia of the 2-D plate: +0.46 % expected"))
    ref = float(ds.fem_modal_converged)
    fa = ds.amplitude.sel(solver="fem").values
    aref = fa[np.flatnonzero(np.isfinite(fa))[-1]] if np.isfinite(fa).any() else np.nan
    for s in GATED:
        if s not in ds.solver.values or 10 not in ds.resolution.values:
            continue
        v = float(ds.period.sel(solver=s, resolution=10))
        tol, why = ((TOL_PERIOD_CONSISTENT, "second order: ~(Δx/H)²/8 at H/Δx = 10")
                    if s in CONSISTENT else (TOL_PERIOD, "issues 4/5: 3 % (004's model: 2.7 %)"))
        g.append(Gate.at_most(f"plate {s} at H/dx = 10: period vs FEM modal period",
                              abs(v - ref) / ref, tol, why))
        a = float(ds.amplitude.sel(solver=s, resolution=10))
        g.append(Gate.at_most(f"plate {s} at H/dx = 10: amplitude vs FEM dynamic amplitude",
                              abs(a - aref) / aref, TOL_AMPLITUDE, "issue 4: 5 %"))
        d = float(ds.energy_drift.sel(solver=s, resolution=10))
        g.append(Gate.at_most(f"plate {s} at H/dx = 10: |energy drift| over the run, no damping",
                              abs(d), TOL_DRIFT, "symplectic scheme: bounded energy error, 0.1 %"))
    if "csph" in ds.solver.values:
        v = ds.period.sel(solver="csph").values
        res = ds.resolution.values
        if 40 in res and np.isfinite(v[list(res).index(40)]):
            g.append(Gate.at_most("plate csph at H/dx = 40: period vs FEM modal period",
                                  abs(v[list(res).index(40)] - ref) / ref, TOL_PERIOD_FINE,
                                  "issue 10's target; second order predicts 0.006 %"))
        keep = np.isfinite(v)
        if keep.sum() >= 3:
            g.append(Gate.at_least("plate csph: observed order of the period error",
                                   observed_order(1.0 / res[keep], v[keep] - ref), MIN_ORDER,
                                   "second-order method; nodal integration converges at ~1"))
    return g


def plot(ds: xr.Dataset, outdir) -> list:
    from . import figures as plots

    return [plots.plate(ds, outdir)]
