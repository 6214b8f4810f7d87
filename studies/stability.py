"""Stability study: where the particle methods fail (scenes.md, "Stability scenes"; issue 5).

For every particle method and scene (``ring``, ``slab``, ``rings``, ``plate``) and every time-step
factor of the ladder, one run is classified as stable or not by the criteria of
the driver's one criterion (:mod:`sph.monitor`: non-finite state or failed material point; energy balance grown by more
than 50 % — one-sided: a loss of energy, e.g. to artificial viscosity, is recorded as ``dissipated``
with a ``note`` and the status stays 'ok'; particle disorder η₉₅ > 0.15), and its energy drift is
recorded. The runs are :class:`studies.sweep.Task` s executed by :func:`studies.sweep.run_tasks`
(serial, local or remote dask; finished runs cached). ``max_stable_dt_factor`` is
the largest factor below which every run of the ladder was stable. The plate uses the methods' own
plate drivers (criteria: non-finite state, total energy grown by more than 50 %; the
period of a dissipating classic-SPH plate is still read from its tip history).

Method options of this study (recorded in the attributes): ``hpm`` runs the stability scenes with
the zero-energy-mode stabilisation α = 1 (without it the ring's point loads excite the zero-energy
modes, see tests/test_stability.py) and the plate without it; ``sph`` uses the Eulerian cubic
spline, h = 1.3Δx, Monaghan viscosity α = β = 1, no artificial stress, and the hyperelastic stress
path (F from Ḟ = L F, stress from the shared library) in the stability scenes, the hypoelastic
Jaumann path on the plate; ``csph`` its defaults (quadratic gradient correction; h = 1.3Δx in
ring/slab/rings, 1.1Δx on the plate) with, like hpm, its zero-energy-mode control on in the
stability scenes (hourglass α = 0.1) and off on the plate. Without it the total-Lagrangian kernel
is still free of the tensile instability, but the rank deficiency of nodal integration shows in
the slab's long run: η₉₅ = 0.18 at t = 0.125 s (stretch ≈ 1.25) against 0.115 with α = 0.1 and
0.007 for stabilised hpm (tests/test_stability.py). A run that fails is recorded as an
error status, not a crash.
"""
from __future__ import annotations

import dataclasses
import sys

import numpy as np
import xarray as xr

from workbench import results
from workbench.scenes import Plate
from workbench.scenes import Ring, Rings, Slab

from .common import Gate, validate
from .sweep import Task, run_tasks

NAME = "stability"
SCENE = Ring
SOLVERS = ("hpm", "sph", "csph")
SCENES = ("ring", "slab", "rings", "plate")
DT_FACTORS = (0.3, 0.6, 1.0, 1.5)
QUICK_DT_FACTORS = (0.3, 0.6, 1.0)
# scene name -> (scene, resolution, quick resolution, end-time override (full, quick))
SETUP = {
    "ring": (Ring(), 8, 6, (0.05, 0.01)),
    "slab": (Slab(), 10, 6, (None, 0.05)),
    "rings": (Rings(), 5, 4, (None, 0.03)),
    "plate": (Plate(), 10, 5, (2.0, 0.5)),
}
OPTIONS = {"hpm": {"stabilisation": 1.0}, "sph": {"stress": "hyperelastic"},
           "csph": {"hourglass": 0.1, "h_ratio": 1.3}}
PLATE_OPTIONS = {"hpm": {}, "sph": {"lattice": "cell"}, "csph": {}}


def _task(solver, name, dt_factor, quick) -> Task:
    """One run of the sweep: the scene of ``SETUP[name]`` with ``dt_factor`` (and the end time of
    the study) set on the scene itself, so that the task's cache key carries them."""
    scene, res, qres, (t_full, t_quick) = SETUP[name]
    t_end = t_quick if quick else t_full
    r = qres if quick else res
    if name == "plate":
        sc = dataclasses.replace(scene, dt_factor=dt_factor,
                                 periods=t_end if t_end is not None else scene.periods)
        return Task.make(solver, sc, r, **PLATE_OPTIONS[solver])
    fields = {"dt_factor": dt_factor}
    if t_end is not None:
        fields["t_end"] = t_end
    return Task.make(solver, dataclasses.replace(scene, **fields), r, **OPTIONS[solver])


def run(scene=None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None) -> xr.Dataset:
    """Sweep (solver × scene × dt_factor) as a list of :class:`studies.sweep.Task` run by
    :func:`studies.sweep.run_tasks` (serially, on dask, cached runs reused). ``scene`` and
    ``resolutions`` are accepted for the common study signature; the scenes and resolutions of
    this study are fixed in ``SETUP``."""
    validate(sys.modules[__name__], scene, solvers, resolutions, quick)  # before any work
    solvers = list(solvers or SOLVERS)
    factors = list(QUICK_DT_FACTORS if quick else DT_FACTORS)
    shp = (len(solvers), len(SCENES), len(factors))
    index = list(np.ndindex(*shp))
    tasks = [_task(solvers[i], SCENES[j], factors[k], quick) for i, j, k in index]
    outs = run_tasks(tasks, scheduler, NAME)
    stable = np.zeros(shp, bool)
    drift = np.full(shp, np.nan)
    dissipated = np.full(shp, np.nan)
    disorder = np.full(shp, np.nan)
    wall = np.full(shp, np.nan)
    status = np.full(shp, "not run", dtype=object)
    note = np.full(shp, "", dtype=object)
    for (i, j, k), out in zip(index, outs):
        st = out["status"] if isinstance(out["status"], str) else str(out["status"])
        status[i, j, k] = st
        stable[i, j, k] = bool(out.get("stable", st == "ok")) and st == "ok"
        drift[i, j, k] = out.get("energy_drift", np.nan)
        dissipated[i, j, k] = out.get("dissipated", np.nan)
        note[i, j, k] = out.get("note", "")
        disorder[i, j, k] = out.get("disorder", np.nan)
        wall[i, j, k] = float(np.sum(out.get("wall_time", np.nan)))
    max_stable = np.full(shp[:2], np.nan)
    for i in range(shp[0]):
        for j in range(shp[1]):
            ok = [f for k, f in enumerate(factors) if all(stable[i, j, :k + 1])]
            max_stable[i, j] = max(ok) if ok else 0.0
    ds = xr.Dataset(
        {
            "stable": (("solver", "scene", "dt_factor"), stable, {"units": "-", "long_name":
                       "run stayed stable (criteria in the attribute 'criterion')"}),
            "max_stable_dt_factor": (("solver", "scene"), max_stable, {"units": "-", "long_name":
                                     "largest dt factor of the ladder with every smaller one stable (0: none)"}),
            "energy_drift": (("solver", "scene", "dt_factor"), drift, {"units": "-", "long_name":
                             "relative change of the total energy (balance incl. dead-load work) over the run; NaN for the kinematically driven slab"}),
            "dissipated": (("solver", "scene", "dt_factor"), dissipated, {"units": "-", "long_name":
                           "fraction of the energy lost over the run (>= 0; dissipation, not instability)"}),
            "note": (("solver", "scene", "dt_factor"), note.astype(str), {"units": "-", "long_name":
                     "remark beside an 'ok' status (strong dissipation)"}),
            "disorder": (("solver", "scene", "dt_factor"), disorder, {"units": "-", "long_name":
                         "particle disorder eta95 at the end (sph.monitor)"}),
            "wall_time": (("solver", "scene", "dt_factor"), wall, {"units": "s"}),
            "status": (("solver", "scene", "dt_factor"), status.astype(str), {"units": "-"}),
        },
        coords={"solver": solvers, "scene": list(SCENES),
                "dt_factor": ("dt_factor", np.array(factors), {"units": "-", "long_name":
                              "time step over the CFL estimate dx/c_p"})},
    )
    ds.attrs.update(results.provenance(NAME, None))
    ds.attrs.update(
        criterion="unstable if: non-finite state or failed material point; energy balance GROWN by more "
                  "than 0.5 of the largest energy seen, or non-finite (one-sided: a loss of energy is "
                  "dissipation, recorded in 'dissipated' with a note, status ok); particle disorder "
                  "eta95 > 0.15 (sph.monitor). Plate: non-finite state or failed material point; "
                  "total energy grown by more than 0.5 of the initial energy (every method)",
        plane="strain", quick=int(quick),
        options_hpm="stabilisation=1 in ring/slab/rings, 0 on the plate; r_e = 2.1 dx",
        options_csph="quadratic correction, cubic spline, h = 1.3 dx in ring/slab/rings, 1.1 dx on the "
                     "plate; hourglass control alpha = 0.1 in ring/slab/rings, off on the plate",
        options_sph="cubic spline h = 1.3 dx, alpha = beta = 1, no artificial stress; hyperelastic "
                    "stress path in ring/slab/rings, hypoelastic Jaumann on the plate",
        resolutions=str({k: (v[2] if quick else v[1]) for k, v in SETUP.items()}),
    )
    return ds


def errors(ds: xr.Dataset) -> list[dict]:
    return []


def _outcome(ds: xr.Dataset, solver: str, scene: str) -> str:
    """'stable' or 'unstable' at the smallest time-step factor (not a time-step effect there)."""
    f0 = float(ds.dt_factor.values[0])
    return "stable" if bool(ds.stable.sel(solver=solver, scene=scene, dt_factor=f0)) else "unstable"


# (solver, scene, expected outcome at the smallest dt factor, why): the failures and non-failures
# that the literature predicts (issue 5).
EXPECTED = (
    ("hpm", "ring", "stable", "Lagrangian kernel: no clumping (004 §III A)"),
    ("csph", "ring", "stable", "total-Lagrangian kernel: no clumping (000 §2)"),
    ("sph", "ring", "unstable", "Eulerian kernel: particle clumping (Rabczuk et al. 2004; 003 Fig. 6)"),
    ("hpm", "slab", "stable", "Lagrangian kernel: no tensile instability (004 §III B)"),
    ("csph", "slab", "stable", "total-Lagrangian kernel: no tensile instability (Belytschko et al. "
                               "2000); its zero-energy modes held by the hourglass control"),
    ("sph", "slab", "unstable", "tensile instability of classic SPH (Swegle et al. 1995)"),
)


def gates(ds: xr.Dataset) -> list[Gate]:
    """Issue 5: the ring and the slab stable with the Lagrangian kernels (hpm, csph) and not with
    the Eulerian one (sph: clumping in the ring, the tensile instability in the slab), each at the
    smallest time-step factor of the ladder so that the outcome is not a time-step effect."""
    g = []
    sol = list(ds.solver.values)
    for solver, scene, expected, why in EXPECTED:
        if solver in sol:
            g.append(Gate.expect(f"stability: {solver} {scene} at dt factor {float(ds.dt_factor[0]):g}",
                                 _outcome(ds, solver, scene), expected, why))
    return g


def stability_map(ds: xr.Dataset) -> list[list[str]]:
    """The stability map as a table: one row per (solver, scene), one column per time-step factor:
    'stable' with the energy drift, or 'UNSTABLE' with the time and reason."""
    head = ["solver", "scene"] + [f"dt factor {f:g}" for f in ds.dt_factor.values] + ["max stable"]
    rows = [head]
    for s in ds.solver.values:
        for sc in ds.scene.values:
            row = [str(s), str(sc)]
            for f in ds.dt_factor.values:
                pt = dict(solver=s, scene=sc, dt_factor=f)
                st = str(ds.status.sel(**pt).values)
                if bool(ds.stable.sel(**pt)):
                    d = float(ds.energy_drift.sel(**pt))
                    cell = "stable" + (f", drift {d:+.1e}" if np.isfinite(d) else "")
                    if str(ds.note.sel(**pt).values):
                        cell += f" ({ds.note.sel(**pt).values})"
                elif st.startswith("unstable"):
                    cell = "UNSTABLE" + st[len("unstable"):]
                else:
                    cell = st
                row.append(cell)
            row.append(f"{float(ds.max_stable_dt_factor.sel(solver=s, scene=sc)):g}")
            rows.append(row)
    return rows


def report_tables(ds: xr.Dataset) -> list[dict]:
    return [dict(title="Stability map (time-step factor = dt over the CFL estimate dx/c_p; criterion: "
                       + ds.attrs.get("criterion", "") + "):", table=stability_map(ds))]


def plot(ds: xr.Dataset, outdir) -> list:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pathlib import Path

    fig, ax = plt.subplots(figsize=(6, 3))
    m = ds.max_stable_dt_factor.values
    im = ax.imshow(m, cmap="viridis", vmin=0, vmax=float(ds.dt_factor.max()))
    ax.set_xticks(range(len(ds.scene)), [str(s) for s in ds.scene.values])
    ax.set_yticks(range(len(ds.solver)), [str(s) for s in ds.solver.values])
    for i in range(m.shape[0]):
        for j in range(m.shape[1]):
            ax.text(j, i, f"{m[i, j]:g}", ha="center", va="center", color="w")
    fig.colorbar(im, ax=ax, label="max stable dt factor [-]")
    ax.set_title("largest stable time step / CFL estimate dx/c_p, over the ladder "
                 + ", ".join(f"{f:g}" for f in ds.dt_factor.values), fontsize=8)
    from .figures import save

    return [save(fig, Path(outdir) / "stability_max_dt.png")]
