"""Stability study: where the particle methods fail (scenes.md, "Stability scenes"; issues 5, 13).

**One footing.** The time-step factor of this study is Δt/Δt_crit, with Δt_crit = 2/ω_max the
critical step of each method's own linearised discrete system at the initial state
(:mod:`sph.spectrum`: Lanczos on the tangent of the method's force and the lumped masses), so a
factor 1 means the same for every method. The CFL estimate Δx/c_p, Δt_crit and their ratio are
recorded per (solver, scene) (``dt_cfl``, ``dt_crit``, ``dt_crit_over_cfl``).

For every particle method and scene (``ring``, ``slab``, ``rings``, ``plate``) and every factor of
the ladder (:data:`DT_FACTORS`; ``--quick``: :data:`QUICK_DT_FACTORS`) one run is classified stable
or not by the driver's one criterion (:mod:`sph.monitor`: non-finite state or failed material
point; the energy gain above the lowest balance growing exponentially — fitted rate ≥ 0.01 per
step — beyond an absolute floor (the energy of a strain 1e-5) and beyond half the largest energy
seen; one-sided: a loss of energy, e.g. to artificial viscosity, is recorded as ``dissipated``;
particle disorder η₉₅ > 0.15). The full study then **bisects** the critical factor between the
largest factor of the ladder below which every run was stable and the next, unstable, one, until
the two differ by at most :data:`BISECTION_TOL` (5 %): ``critical_factor`` is the largest stable
factor found (``critical_factor_unstable`` the smallest unstable one above it), ``max_stable_dt``
the step it stands for (s). The runs are :class:`studies.sweep.Task` s executed by
:func:`studies.sweep.run_tasks` (serial, local or remote dask; finished runs cached), one batch per
bisection round. A scene with a prescribed motion (the slab) has no energy criterion; its
time-step failures show as a non-finite state or disorder.

Variables of the theory of the instabilities (Swegle's prediction, hourglass-energy fraction,
long-run drift) come from ``studies/stability_theory.py`` where that module exists: ``run``
merges the dataset returned by its ``dataset(ds, quick=..., scheduler=...)``.

Method options of this study (recorded in the attributes): ``hpm`` runs the stability scenes with
the zero-energy-mode stabilisation α = 1 (without it the ring's point loads excite the zero-energy
modes, see tests/test_stability.py) and the plate without it; ``sph`` uses the Eulerian cubic
spline, h = 1.3Δx, Monaghan viscosity α = β = 1, no artificial stress, and the hyperelastic stress
path (F from Ḟ = L F, stress from the shared library) in the stability scenes, the hypoelastic
Jaumann path on the plate (its Δt_crit leaves the viscosity out, which damps: its measured
critical factor is below 1); ``csph`` its defaults (quadratic gradient correction; h = 1.3Δx in
ring/slab/rings, 1.1Δx on the plate) with, like hpm, its zero-energy-mode control on in the
stability scenes (hourglass α = 0.1) and off on the plate. Without it the total-Lagrangian kernel
is still free of the tensile instability, but the rank deficiency of nodal integration shows in
the slab's long run: η₉₅ = 0.18 at t = 0.125 s (stretch ≈ 1.25) against 0.115 with α = 0.1 and
0.007 for stabilised hpm (tests/test_stability.py). A run that fails is recorded as an
error status, not a crash.
"""
from __future__ import annotations

import dataclasses
import math
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
DT_FACTORS = (0.5, 0.9, 1.1, 1.5)
"""The ladder of the full study, Δt/Δt_crit; the critical factor is then bisected."""
QUICK_DT_FACTORS = (0.5, 0.9, 1.1)
"""The ladder of ``--quick`` (no bisection)."""
BISECTION_TOL = 0.05
"""The bisection stops when the smallest unstable factor is within 5 % of the largest stable one."""
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


def _setup(solver, name, quick):
    """(scene, resolution, options) of one (solver, scene) of the study."""
    scene, res, qres, (t_full, t_quick) = SETUP[name]
    t_end = t_quick if quick else t_full
    if name == "plate":
        sc = dataclasses.replace(scene, periods=t_end if t_end is not None else scene.periods)
        return sc, (qres if quick else res), dict(PLATE_OPTIONS[solver])
    if t_end is not None:
        sc = dataclasses.replace(scene, t_end=t_end)
    else:
        sc = scene
    return sc, (qres if quick else res), dict(OPTIONS[solver])


def time_steps(solver, name, quick) -> dict:
    """``dt_cfl`` and ``dt_crit`` (s) of ``solver`` on the scene ``name`` of the study
    (:func:`sph.driver.scene_time_steps` on the study's body and constraints)."""
    from sph.driver import scene_time_steps

    sc, r, opts = _setup(solver, name, quick)
    return scene_time_steps(solver, sc, r, **opts)


def _task(solver, name, cfl_factor, quick) -> Task:
    """One run of the sweep: the scene of ``SETUP[name]`` with the time step ``cfl_factor``·Δx/c_p
    (and the end time of the study) set on the scene itself, so that the task's cache key carries
    them."""
    sc, r, opts = _setup(solver, name, quick)
    return Task.make(solver, dataclasses.replace(sc, dt_factor=float(cfl_factor)), r, **opts)


def _stable(out) -> bool:
    st = out["status"] if isinstance(out["status"], str) else str(out["status"])
    return bool(out.get("stable", st == "ok")) and st == "ok"


def _bracket(factors, stable) -> tuple[float, float]:
    """(largest factor below which every run was stable, the next factor: unstable); NaN where
    there is none (unstable at the smallest factor; stable up to the largest)."""
    lo, hi = math.nan, math.nan
    for f, ok in sorted(zip(factors, stable)):
        if not ok:
            hi = f
            break
        lo = f
    return lo, hi


def run(scene=None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None) -> xr.Dataset:
    """Δt_crit per (solver, scene), the sweep (solver × scene × factor of the ladder) as a list of
    :class:`studies.sweep.Task` run by :func:`studies.sweep.run_tasks` (serially, on dask, cached
    runs reused), then (full study) the bisection of the critical factor. ``scene`` and
    ``resolutions`` are accepted for the common study signature; the scenes and resolutions of
    this study are fixed in ``SETUP``."""
    validate(sys.modules[__name__], scene, solvers, resolutions, quick)  # before any work
    solvers = list(solvers or SOLVERS)
    factors = list(QUICK_DT_FACTORS if quick else DT_FACTORS)
    pairs = list(np.ndindex(len(solvers), len(SCENES)))
    steps = {(i, j): time_steps(solvers[i], SCENES[j], quick) for i, j in pairs}
    ratio = {p: steps[p]["dt_crit"] / steps[p]["dt_cfl"] for p in pairs}
    shp = (len(solvers), len(SCENES), len(factors))
    index = list(np.ndindex(*shp))
    tasks = [_task(solvers[i], SCENES[j], factors[k] * ratio[i, j], quick) for i, j, k in index]
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
        stable[i, j, k] = _stable(out)
        drift[i, j, k] = out.get("energy_drift", np.nan)
        dissipated[i, j, k] = out.get("dissipated", np.nan)
        note[i, j, k] = out.get("note", "")
        disorder[i, j, k] = out.get("disorder", np.nan)
        wall[i, j, k] = float(np.sum(out.get("wall_time", np.nan)))
    max_stable = np.full(shp[:2], np.nan)
    lo = np.full(shp[:2], np.nan)
    hi = np.full(shp[:2], np.nan)
    for i, j in pairs:
        ok = [f for k, f in enumerate(factors) if all(stable[i, j, :k + 1])]
        max_stable[i, j] = max(ok) if ok else 0.0
        lo[i, j], hi[i, j] = _bracket(factors, stable[i, j])
    # bisection of the critical factor (full study), one batch of runs per round
    while not quick:
        open_ = [p for p in pairs if np.isfinite(lo[p]) and np.isfinite(hi[p])
                 and hi[p] > (1 + BISECTION_TOL) * lo[p]]
        if not open_:
            break
        mids = {p: 0.5 * (lo[p] + hi[p]) for p in open_}
        outs = run_tasks([_task(solvers[p[0]], SCENES[p[1]], mids[p] * ratio[p], quick)
                          for p in open_], scheduler, NAME)
        for p, out in zip(open_, outs):
            if _stable(out):
                lo[p] = mids[p]
            else:
                hi[p] = mids[p]
    dt_cfl = np.array([[steps[i, j]["dt_cfl"] for j in range(len(SCENES))] for i in range(len(solvers))])
    dt_crit = np.array([[steps[i, j]["dt_crit"] for j in range(len(SCENES))] for i in range(len(solvers))])
    ps = ("solver", "scene")
    pk = ("solver", "scene", "dt_factor")
    ds = xr.Dataset(
        {
            "stable": (pk, stable, {"units": "-", "long_name":
                       "run stayed stable (criteria in the attribute 'criterion')"}),
            "max_stable_dt_factor": (ps, max_stable, {"units": "-", "long_name":
                                     "largest dt/dt_crit of the ladder with every smaller one stable (0: none)"}),
            "dt_cfl": (ps, dt_cfl, {"units": "s", "long_name": "CFL estimate dx/c_p"}),
            "dt_crit": (ps, dt_crit, {"units": "s", "long_name":
                        "critical step 2/omega_max of the linearised discrete system at the initial state (sph.spectrum)"}),
            "dt_crit_over_cfl": (ps, dt_crit / dt_cfl, {"units": "-", "long_name": "dt_crit / (dx/c_p)"}),
            "critical_factor": (ps, lo, {"units": "-", "long_name":
                                "measured critical factor: the largest stable dt/dt_crit found (bisection in the "
                                "full study to within 5 %, the ladder with --quick); NaN: unstable at the smallest factor"}),
            "critical_factor_unstable": (ps, hi, {"units": "-", "long_name":
                                         "the smallest unstable dt/dt_crit above critical_factor (NaN: none found)"}),
            "max_stable_dt": (ps, lo * dt_crit, {"units": "s", "long_name":
                              "largest stable time step measured (critical_factor * dt_crit)"}),
            "energy_drift": (pk, drift, {"units": "-", "long_name":
                             "relative change of the total energy (balance incl. dead-load work) over the run; NaN for the kinematically driven slab"}),
            "dissipated": (pk, dissipated, {"units": "-", "long_name":
                           "fraction of the energy lost over the run (>= 0; dissipation, not instability)"}),
            "note": (pk, note.astype(str), {"units": "-", "long_name":
                     "remark beside an 'ok' status (strong dissipation)"}),
            "disorder": (pk, disorder, {"units": "-", "long_name":
                         "particle disorder eta95 at the end (sph.monitor)"}),
            "wall_time": (pk, wall, {"units": "s"}),
            "status": (pk, status.astype(str), {"units": "-"}),
        },
        coords={"solver": solvers, "scene": list(SCENES),
                "dt_factor": ("dt_factor", np.array(factors), {"units": "-", "long_name":
                              "time step over the critical step dt_crit = 2/omega_max (sph.spectrum)"})},
    )
    ds.attrs.update(results.provenance(NAME, None))
    from sph import monitor

    ds.attrs.update(
        criterion="unstable if (sph.monitor, every method and scene): non-finite state or failed material "
                  "point; or the energy gain e = B - min(B) of the energy balance B (kinetic + stored + "
                  "dissipated - external work) growing exponentially: least-squares rate of ln e over the "
                  f"last {monitor.WINDOW} records >= {monitor.GROWTH_RATE:g} per step, with e above the "
                  f"absolute floor 0.5 M (eps c_p)^2, eps = {monitor.FLOOR_STRAIN:g} (round-off on a tiny "
                  "state is not instability), and above 0.5 of the largest energy seen (one-sided: a loss of "
                  "energy is dissipation, recorded in 'dissipated' with a note, status ok; the slab, "
                  "kinematically driven, has no energy criterion); or particle disorder eta95 > 0.15 "
                  "(stability scenes; a level: clumping, tensile instability, zero-energy modes)",
        dt_factor_reference="dt_crit = 2/omega_max: Lanczos on the tangent of each method's force "
                            "(central difference of its internal force; classic SPH: the force of the "
                            "stress one unit step of its stress rate gives, viscosity excluded) with "
                            "lumped masses on the free DOFs at the initial state",
        bisection_tol=BISECTION_TOL if not quick else math.nan,
        plane="strain", quick=int(quick),
        options_hpm="stabilisation=1 in ring/slab/rings, 0 on the plate; r_e = 2.1 dx",
        options_csph="quadratic correction, cubic spline, h = 1.3 dx in ring/slab/rings, 1.1 dx on the "
                     "plate; hourglass control alpha = 0.1 in ring/slab/rings, off on the plate",
        options_sph="cubic spline h = 1.3 dx, alpha = beta = 1, no artificial stress; hyperelastic "
                    "stress path in ring/slab/rings, hypoelastic Jaumann on the plate",
        resolutions=str({k: (v[2] if quick else v[1]) for k, v in SETUP.items()}),
    )
    from . import stability_theory

    theory = stability_theory.dataset(ds, quick=quick, scheduler=scheduler)
    merged = ds.merge(theory)
    merged.attrs = {**ds.attrs, **theory.attrs}  # merge keeps the first dataset's attributes only
    return merged


def errors(ds: xr.Dataset) -> list[dict]:
    return []


def _outcome(ds: xr.Dataset, solver: str, scene: str) -> str:
    """'stable' or 'unstable' at the smallest time-step factor (not a time-step effect there); a run
    that did not finish as either (an error, not run) is its status, which matches no expected
    outcome: a crashed run fails its gate rather than reading as 'unstable'."""
    f0 = float(ds.dt_factor.values[0])
    if bool(ds.stable.sel(solver=solver, scene=scene, dt_factor=f0)):
        return "stable"
    st = str(ds.status.sel(solver=solver, scene=scene, dt_factor=f0).values) \
        if "status" in ds else "unstable"
    return "unstable" if st.startswith(("unstable", "diverged", "ok")) else f"not run ({st})"


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


N_GATES = {False: 11, True: 11}
"""Gates of the default run (full, ``--quick``): the six outcomes of :data:`EXPECTED` and the five
of the theory (Swegle on the ring and the slab, csph's stress-term rate, the drift of hpm and
csph: :func:`studies.stability_theory.theory_gates`). ``verify`` fails where fewer were evaluated."""


def gates(ds: xr.Dataset) -> list[Gate]:
    """Issue 5: the ring and the slab stable with the Lagrangian kernels (hpm, csph) and not with
    the Eulerian one (sph: clumping in the ring, the tensile instability in the slab), each at the
    smallest time-step factor of the ladder so that the outcome is not a time-step effect."""
    g = []
    sol = list(ds.solver.values)
    for solver, scene, expected, why in EXPECTED:
        if solver in sol:
            g.append(Gate.expect(f"stability: {solver} {scene} at dt factor {float(ds.dt_factor[0]):g}",
                                 _outcome(ds, solver, scene), expected, why,
                                 "the outcome the literature predicts, fixed in EXPECTED before "
                                 "the run"))
    from .stability_theory import theory_gates

    return g + theory_gates(ds)


def expected_instability(solver: str, scene: str, dt_factor: float) -> str:
    """Why this study expects the run (``solver`` on ``scene`` at Δt/Δt_crit = ``dt_factor``) to
    blow up, or '' where it expects none: above Δt_crit (factor > 1) by construction of the
    ladder and the bisection, and the instabilities the literature predicts (:data:`EXPECTED`)."""
    if dt_factor > 1.0:
        return f"above dt_crit (dt factor {dt_factor:g} > 1)"
    return next((why for s, sc, outcome, why in EXPECTED
                 if (s, sc, outcome) == (solver, scene, "unstable")), "")


def run_outcomes(ds: xr.Dataset) -> list[dict]:
    """Every run of the map that did not end ``ok``: ``run`` (solver scene dt factor), ``status``,
    ``expected`` (:func:`expected_instability`, '' where none is expected) and ``failed``. An
    instability is a result of this study, never a failed run (its gates judge the outcomes the
    literature predicts); a run that ended in an error is a failed run."""
    out = []
    for s in ds.solver.values:
        for sc in ds.scene.values:
            for f in ds.dt_factor.values:
                st = str(ds.status.sel(solver=s, scene=sc, dt_factor=f).values)
                if st.startswith("ok") or st == "not run":
                    continue
                unstable = st.startswith("unstable")
                out.append(dict(run=f"{s} {sc} dt factor {float(f):g}", status=st,
                                expected=expected_instability(str(s), str(sc), float(f))
                                if unstable else "", failed=not unstable))
    return out


def stability_map(ds: xr.Dataset) -> list[list[str]]:
    """The stability map as a table: one row per (solver, scene), one column per time-step factor:
    'stable' with the energy drift, or 'UNSTABLE' with the time and reason."""
    head = (["solver", "scene", "dt_crit/CFL"] + [f"dt factor {f:g}" for f in ds.dt_factor.values]
            + ["critical factor"])
    rows = [head]
    for s in ds.solver.values:
        for sc in ds.scene.values:
            row = [str(s), str(sc)]
            if "dt_crit_over_cfl" in ds:
                row.append(f"{float(ds.dt_crit_over_cfl.sel(solver=s, scene=sc)):.3g}")
            else:
                row.append("")
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
            if "critical_factor" in ds:
                lo = float(ds.critical_factor.sel(solver=s, scene=sc))
                hi = float(ds.critical_factor_unstable.sel(solver=s, scene=sc))
                row.append(f"[{lo:.3g}, {hi:.3g})" if np.isfinite(lo) and np.isfinite(hi) else
                           f">= {lo:.3g}" if np.isfinite(lo) else f"< {hi:.3g}")
            else:
                row.append(f"{float(ds.max_stable_dt_factor.sel(solver=s, scene=sc)):g}")
            rows.append(row)
    return rows


def report_tables(ds: xr.Dataset) -> list[dict]:
    from .stability_theory import theory_tables

    return [dict(title="Stability map (time-step factor = dt over each method's critical step dt_crit = "
                       "2/omega_max, sph.spectrum; critical factor: [largest stable, smallest unstable); "
                       "criterion: "
                       + ds.attrs.get("criterion", "") + "):", table=stability_map(ds))] + theory_tables(ds)


def plot(ds: xr.Dataset, outdir) -> list:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pathlib import Path

    fig, ax = plt.subplots(figsize=(6, 3))
    m = (np.nan_to_num(ds.critical_factor.values, nan=0.0) if "critical_factor" in ds
         else ds.max_stable_dt_factor.values)
    im = ax.imshow(m, cmap="viridis", vmin=0, vmax=float(ds.dt_factor.max()))
    ax.set_xticks(range(len(ds.scene)), [str(s) for s in ds.scene.values])
    ax.set_yticks(range(len(ds.solver)), [str(s) for s in ds.solver.values])
    for i in range(m.shape[0]):
        for j in range(m.shape[1]):
            ax.text(j, i, f"{m[i, j]:.3g}", ha="center", va="center", color="w")
    fig.colorbar(im, ax=ax, label="max stable dt / dt_crit [-]")
    ax.set_title("largest stable time step / dt_crit = 2/omega_max (ladder "
                 + ", ".join(f"{f:g}" for f in ds.dt_factor.values)
                 + ("" if ds.attrs.get("quick") else ", then bisection to 5 %") + "; 0: none)", fontsize=8)
    from .figures import save

    return [save(fig, Path(outdir) / "stability_max_dt.png")]
