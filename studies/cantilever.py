"""Cantilever study: static tip-loaded cantilever of 004 E at the paper's small load and at
P L²/(E I) = 1, 2, 5 (geometrically nonlinear), plane strain.

References: ``analytic`` stores the inextensible elastica (Bisshopp & Drucker 1945) of the plane
beam; Timoshenko and Euler–Bernoulli deflections are stored beside it. The converged FEM of the same
2-D continuum with the same clamp and load is the reference every discrete run is measured against
(error = |δ − δ_FEM,ref| / δ_FEM,ref with δ_FEM,ref Richardson-extrapolated from the FEM ladder).
"""
from __future__ import annotations

import sys

import numpy as np
import xarray as xr

from workbench import analytic, results
from workbench.scenes import Cantilever

from .common import Gate, field_options, field_series, observed_order, planned, validate
from .common import ladders as study_ladders
from .sweep import Task, run_tasks

NAME = "cantilever"
SCENE = Cantilever
SOLVERS = ("analytic", "fem", "csph", "csph_quad", "csph_bl", "hpm", "hpm_vc")
# Elements or particles across H (every method with a static Newton; hpm through the shared solver).
# csph and hpm on the full ladder (their orders are reported); the other variants beside them.
RESOLUTIONS = {"fem": (2, 4, 8, 16), "csph": (5, 10, 20, 40), "csph_quad": (5, 10, 20),
               "csph_bl": (5, 10, 20), "hpm": (5, 10, 20, 40), "hpm_vc": (5, 10, 20)}
QUICK_RESOLUTIONS = {"fem": (2, 4, 8), "csph": (5, 10), "csph_bl": (10,), "hpm": (10,)}
ERROR_LABEL = "relative tip-deflection error vs converged FEM [-]"

# The field snapshot of the report (``workbench run cantilever --fields``): the CSPH series, the
# equilibrium of the largest load, coloured by the von Mises stress.
FIELD_VIEW = dict(prefer="cantilever_csph", scalars="von_mises", label="von Mises stress [Pa]",
                  time_label="P L^2/(E I) = {:g}")

# Tolerances, each the error the method should have (its order, the resolution, the reference's
# own error), tight enough that three times the recorded error fails it (tests/test_gates.py).
# FEM at the small load against Timoshenko: the Timoshenko shear term P L/(κ G H) is 1.32 % of
# Timoshenko's tip deflection for H/L = 1/8 (plane strain); the rigid clamp of the continuum
# restrains warping and the Poisson contraction at the root, which stiffens it by a fraction of
# that term, so the continuum lies between Euler–Bernoulli and Timoshenko: within the shear term
# of Timoshenko (measured −0.46 % at 8 across H, a tripled 1.38 % fails). (Was 3 % here and 1.5 %
# in tests/test_fem_cantilever.py: one value now, the shear term.)
TOL_FEM_TIMOSHENKO = 0.0132
# FEM at large loads against the inextensible elastica: at the small load the continuum lies 0.9 %
# above the elastica's linear limit (Euler–Bernoulli) by shear; as the beam rotates the axial
# stretch P/(E'H) and the shear of the rotated sections add to it: +1.1, +1.3, +1.9 % at loads 1,
# 2, 5 (16 across H) — 3 % bounds shear plus stretch. (Was 4 % here, 3 % in
# tests/test_fem_cantilever.py.)
TOL_FEM_ELASTICA = 0.03
# The integration-consistent methods (csph; hpm_vc: HPM's gradient, consistent integration) against
# the converged FEM at H/Δx = 10, every load: both are second order (quadratic basis, volumes exact
# for quadratics), so the bending error is O((Δx/H)²): the bulk's bending stiffness at H/Δx = 10
# is off by twice the free–free beam's period error at that spacing, 2 × 0.04 %
# (tests/test_consistency.py, a problem without the clamp), and the clamp's corner singularity
# (cut out of the integration) adds a term of about that size: 0.2 % (measured csph +0.05 …
# +0.10 %, a tripled 0.30 % fails; hpm_vc +0.03 %). (Was 2.5e-3 = (Δx/H)²/4 here and
# 2e-3 in tests/test_consistency.py: one value now.) The nodal-integration variants miss it:
# csph_quad by ~0.35 %, csph_bl by ~5 %, hpm by ~3 %.
TOL_CONSISTENT_FEM = 2e-3
CONSISTENT = ("csph", "hpm_vc")
# Observed order of csph and hpm over their full ladders (5 … 40): second order expected; 1.5
# fails a method that has fallen back to first order.
MIN_ORDER = 1.5
# Paper 000's CSPH with the quadratic correction and nodal integration (csph_quad) at H/Δx = 10:
# the consistent methods' 0.2 % plus nodal integration's boundary error, whose size the plate
# gives at the same spacing (its period −0.19 %, so its bending stiffness 0.4 %; the compliance
# at every load within twice that): 1 % (measured −0.23 … +0.35 %, a tripled 1.05 % fails).
# (Was issue 4's 3 %, the paper's claim, which a tripled error passed.) HPM's own gradient misses
# 3 % at the large loads (+3.2 %; shown, not hidden): not gated here.
TOL_PAPER_FEM = 0.01
N_GATES = {False: 7, True: 3}
"""Gates of the default run (full, ``--quick``): the FEM against Timoshenko and the elastica;
csph, hpm_vc and csph_quad at H/Δx = 10 (csph alone in the quick ladder); the observed orders of
csph and hpm (full). ``verify`` fails where fewer were evaluated."""


def run(scene: Cantilever | None = None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None, fields=None, field_runs=None) -> xr.Dataset:
    """``fields`` (a folder, or None): the particle runs write their fields there as ParaView
    series (``field_runs``: the (solver, resolution) pairs that do; None: all); the names of the
    written series are the dataset's ``field_series`` attribute. The FEM writes none here (static cantilever)."""
    scene = scene or Cantilever()
    validate(sys.modules[__name__], scene, solvers, resolutions, quick)  # before any work
    solvers = list(solvers or SOLVERS)
    if "analytic" not in solvers:
        solvers.insert(0, "analytic")
    if "fem" not in solvers:
        solvers.insert(1, "fem")  # the reference of every discrete run
    loads = np.asarray(scene.loads, float)
    solvers, ladders = study_ladders(solvers, resolutions, sys.modules[__name__], quick)
    all_res = sorted({r for lad in ladders.values() for r in lad})
    shape = (len(solvers), len(all_res), len(loads))
    tip = np.full(shape, np.nan)
    horiz = np.full(shape, np.nan)
    wall = np.full(shape, np.nan)
    ndof = np.zeros(shape[:2], dtype=np.int64)
    status = np.full(shape[:2], "not run", dtype=object)
    tasks = [Task.make(s, scene, r, **field_options(s, r, fields, field_runs))
             for s, lad in ladders.items() for r in lad]
    outs = dict(zip(((t.solver, t.resolution) for t in tasks), run_tasks(tasks, scheduler, NAME)))
    for i, s in enumerate(solvers):
        if s == "analytic":
            try:
                el = np.array([analytic.cantilever_elastica(scene, p) for p in loads]).reshape(-1, 2)
                status[i] = "ok"
            except (ValueError, ArithmeticError, RuntimeError) as err:  # where the elastica fails
                el = np.full((len(loads), 2), np.nan)
                status[i] = f"error: {type(err).__name__}: {' '.join(str(err).split())}"
            tip[i] = el[:, 0]
            horiz[i] = el[:, 1]
            wall[i] = 0.0
            continue
        for r in ladders[s]:
            j = all_res.index(r)
            out = outs[(s, r)]
            st = out["status"]
            status[i, j] = st if isinstance(st, str) else "; ".join(sorted(set(map(str, st))))
            if "tip_deflection" in out:
                got = np.asarray(out["load"], float)
                for k, p in enumerate(loads):
                    m = np.flatnonzero(np.isclose(got, p, rtol=1e-9))
                    if m.size:
                        tip[i, j, k] = out["tip_deflection"][m[0]]
                        horiz[i, j, k] = out["tip_horizontal"][m[0]]
                        wall[i, j, k] = np.atleast_1d(out["wall_time"])[min(m[0], np.size(out["wall_time"]) - 1)]
            ndof[i, j] = int(out.get("n_dof", out.get("n_particles", 0)))
    ds = xr.Dataset(
        {
            "tip_deflection": (("solver", "resolution", "load"), tip,
                               {"units": "m", "long_name": "tip mid-point displacement in the load direction"}),
            "tip_horizontal": (("solver", "resolution", "load"), horiz,
                               {"units": "m", "long_name": "horizontal shortening of the tip"}),
            "wall_time": (("solver", "resolution", "load"), wall,
                          {"units": "s", "long_name": "wall time to reach the load (cumulative)"}),
            "n_dof": (("solver", "resolution"), ndof,
                      {"units": "-", "long_name": "degrees of freedom (fem) or particles (particle methods)"}),
            "status": (("solver", "resolution"), status.astype(str), {"units": "-"}),
            "timoshenko": (("load",), np.array([analytic.cantilever_tip(scene, p) for p in loads]),
                           {"units": "m", "long_name": "Timoshenko tip deflection (linear)"}),
            "euler_bernoulli": (("load",), np.array([analytic.cantilever_tip(scene, p, "euler_bernoulli")
                                                     for p in loads]),
                                {"units": "m", "long_name": "Euler-Bernoulli tip deflection (linear)"}),
        },
        coords={"solver": solvers, "resolution": ("resolution", np.array(all_res),
                                                  {"units": "-", "long_name": "elements or particles across H"}),
                "load": ("load", loads, {"units": "-", "long_name": "P L^2 / (E I), E Young's modulus"})},
    )
    ref = fem_reference_values(ds)
    ds["fem_converged"] = (("load",), ref, {"units": "m", "long_name":
                                            "FEM tip deflection extrapolated to zero element size"})
    ds.attrs.update(results.provenance(NAME, scene))
    if fields is not None:
        ds.attrs["field_series"] = field_series(scene, tasks)
    ds.attrs["plane"] = scene.plane
    ds.attrs["analytic_solver"] = "inextensible elastica (Bisshopp & Drucker 1945) of the plane beam"
    return ds


def fem_reference_values(ds: xr.Dataset) -> np.ndarray:
    """Richardson extrapolation of the FEM's three finest resolutions (order fitted), per load;
    the finest value where fewer than three converged."""
    tip = ds.tip_deflection.sel(solver="fem")
    out = np.full(ds.sizes["load"], np.nan)
    for k in range(ds.sizes["load"]):
        v = tip.isel(load=k)
        ok = np.isfinite(v.values)
        res = ds.resolution.values[ok]
        vals = v.values[ok]
        if len(vals) == 0:
            continue
        out[k] = vals[-1]
        if len(vals) >= 3:
            r1, r2, r3 = res[-3:]
            f1, f2, f3 = vals[-3:]
            if r2 == 2 * r1 and r3 == 2 * r2 and (f2 - f1) != 0 and (f3 - f2) / (f2 - f1) > 0:
                q = (f3 - f2) / (f2 - f1)  # = 2^-p
                if q < 1:
                    out[k] = f3 + (f3 - f2) * q / (1 - q)
    return out


def errors(ds: xr.Dataset) -> list[dict]:
    """Relative error of every discrete run against the extrapolated FEM, at the largest load that
    every method reached (the most demanding), with the wall time to reach it."""
    rows = []
    k = ds.sizes["load"] - 1
    ref = ds.fem_converged.values[k]
    for s in ds.solver.values:
        if s == "analytic":
            continue
        for j, r in enumerate(ds.resolution.values):
            v = ds.tip_deflection.sel(solver=s).values[j, k]
            if np.isfinite(v):
                rows.append(dict(solver=str(s), resolution=int(r), error=abs(v - ref) / abs(ref),
                                 wall_time=float(ds.wall_time.sel(solver=s).values[j, k])))
    return rows


def orders(ds: xr.Dataset) -> dict:
    """Observed order of the tip deflection at the largest load, least squares over the ladder."""
    out = {}
    k = ds.sizes["load"] - 1
    ref = ds.fem_converged.values[k]
    for s in ds.solver.values:
        if s == "analytic":
            continue
        v = ds.tip_deflection.sel(solver=s).values[:, k]
        h = 1.0 / ds.resolution.values
        keep = np.isfinite(v)
        if s == "fem":  # the extrapolation is built from fem's own finest levels: use differences
            vv, hh = v[keep], h[keep]
            if len(vv) >= 4:
                out[f"{s} (successive differences)"] = observed_order(hh[1:], np.diff(vv))
            continue
        out[s] = observed_order(h[keep], v[keep] - ref)
    return out


def _rel(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b)) / np.abs(np.asarray(b))))


FEM_REFERENCE = ("the converged FEM (Richardson limit of quadratic elements, scikit-fem, "
                 "fem_reference): another discretisation of the same 2-D continuum, clamp and load, "
                 "sharing no code with the particle methods but the scene and the SVK law (checked "
                 "against its closed-form energy, tests/test_materials.py)")


def gates(ds: xr.Dataset) -> list[Gate]:
    """The cantilever's gates (:data:`N_GATES`): every gate of a run the study meant to make is
    evaluated; a run that is missing or gave NaN fails its gate (never removes it)."""
    g = []
    fem = ds.tip_deflection.sel(solver="fem")
    finest = fem.isel(resolution=int(np.flatnonzero(np.isfinite(fem.values[:, 0]))[-1])) \
        if np.isfinite(fem.values[:, 0]).any() else None
    loads = ds["load"].values
    small = loads < 0.05
    checks = []
    if small.any():
        checks.append(("cantilever fem: small-load tip deflection vs Timoshenko", small,
                       ds.timoshenko.values, TOL_FEM_TIMOSHENKO,
                       "within Timoshenko's shear term (1.32 %): the clamp's warping restraint "
                       "stiffens by a fraction of it", "Timoshenko beam theory, a closed form"))
    if (~small).any():
        checks.append(("cantilever fem: large-load tip deflection vs elastica", ~small,
                       ds.tip_deflection.sel(solver="analytic").values[0], TOL_FEM_ELASTICA,
                       "shear (~1 %) and axial stretch, absent from the inextensible elastica "
                       "(+1.1 … +1.9 % measured)",
                       "the inextensible elastica (Bisshopp & Drucker), an ODE solved by scipy"))
    for name, sel, refv, tol, why, what in checks:
        if finest is None:
            g.append(Gate.missing(name, "no converged FEM run", tol, why, what))
        else:
            g.append(Gate.at_most(name, _rel(finest.values[sel], refv[sel]), tol, why, what))
    ref = ds.fem_converged.values
    for m in CONSISTENT + ("csph_quad",):
        if m in ds.solver.values and 10 in ds.resolution.values \
                and planned(ds.status.sel(solver=m, resolution=10)):
            v = ds.tip_deflection.sel(solver=m, resolution=10).values
            tol, why = ((TOL_CONSISTENT_FEM, "second order: the bulk's 0.08 % (free-free beam) "
                         "and the clamp's corners at H/dx = 10")
                        if m in CONSISTENT else (TOL_PAPER_FEM, "nodal integration: 0.2 % + twice the "
                                                               "plate's stiffness error 0.4 %"))
            g.append(Gate.at_most(f"cantilever {m} at H/dx = 10 vs converged FEM (every load)",
                                  _rel(v, ref), tol, why, FEM_REFERENCE))
    for m in ("csph", "hpm"):
        if m not in ds.solver.values:
            continue
        tip = ds.tip_deflection.sel(solver=m).values[:, -1]
        run = planned(ds.status.sel(solver=m).values)
        if run.sum() >= 4:  # NaN on a planned rung: the order is NaN and the gate fails
            h = 1.0 / ds.resolution.values[run]
            g.append(Gate.at_least(f"cantilever {m}: observed order of the tip error (largest load)",
                                   observed_order(h, tip[run] - ref[-1])
                                   if np.all(np.isfinite(tip[run])) else np.nan, MIN_ORDER,
                                   "csph second order; hpm's linearly exact F converges at ~2 in "
                                   "the bulk (measured 1.9); an O(1) defect would show as < 1",
                                   FEM_REFERENCE))
    return g


def plot(ds: xr.Dataset, outdir) -> list:
    from . import figures as plots

    return [plots.cantilever(ds, outdir)]
