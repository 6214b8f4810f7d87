"""The generic study: any scene model (a user's own, ``workbench run my_scene.py``) with the methods
that can run it, over a resolution ladder, its observables stored as a dataset.

A scene written with the scene API (:mod:`workbench.scenes.model`; README "Your own scene") needs no
study module of its own: this one runs it with every requested method, stores each observable of
the model against the load parameter (static drive), the time (explicit drive, on a common grid of
the drive's ``n_out`` + 1 points) or the mode number (modal drive), with the energies of explicit
runs — kinetic, stored, the external work, the energies dissipated where a method reports them
(plastic work, released by failure) and ``energy_balance``, their balance kinetic + stored +
dissipated − external work, so that conservation can be checked from the dataset — and plots
them. A headline scene (with references and gates) gets a study module of its own.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from workbench import results
from workbench.oscillation import with_period_notes
from workbench.scenes import model as M

from .common import check_resolutions
from .sweep import Task, run_tasks

NAME = "scene"
SCENE = None
RESOLUTIONS = (5, 10, 20)
QUICK_RESOLUTIONS = (5, 10)
ERROR_LABEL = "no reference"


ENERGIES = {"kinetic_energy": "kinetic_energy", "stored_energy": "strain_energy",
            "external_work": "external_work", "plastic_work": "plastic_work",
            "released_energy": "released_energy", "energy_balance": "energy_history"}
"""The energy histories of an explicit run in the dataset -> their key in a solver's result."""
DISSIPATED = ("plastic_work", "released_energy")
"""Stored only where some method reports them."""
ENERGY_NAMES = {"kinetic_energy": "kinetic energy", "stored_energy": "stored (strain) energy",
                "external_work": "work of the loads and of the prescribed motion",
                "plastic_work": "plastic work", "released_energy": "energy released by failure",
                "energy_balance": "kinetic + stored + dissipated - external work (0: conserved)"}


def solvers_for(model: M.Model) -> tuple:
    """The methods that can run ``model``: the gradient-form particle methods (static, modal and
    explicit drives), classic SPH for explicit and static drives (a static one by dynamic
    relaxation through its own explicit step, as ``sph.driver.solve`` runs it; it has no
    tangent for a modal one), the FEM where it reads scene models (not a model with a
    :class:`~workbench.scenes.model.PreCrack` or a :class:`~workbench.scenes.model.CrackTip`: it
    cuts no elements)."""
    from sph import METHODS

    out = [m for m in METHODS if m != "sph" or not isinstance(model.drive, M.Modal)]
    if model.cracks or any(isinstance(o, M.CrackTip) for o in model.observables):
        return tuple(out)
    try:
        import fem_reference

        if hasattr(fem_reference, "solve_model"):
            out.insert(0, "fem")
    except ImportError:  # pragma: no cover
        pass
    return tuple(out)


def run(scene, solvers=None, resolutions=None, quick: bool = False, scheduler: str | None = None,
        fields=None, field_runs=None, options=None) -> xr.Dataset:
    """Run ``scene`` with ``solvers`` (default: :func:`solvers_for`) at ``resolutions`` (a list,
    or a dict solver -> list; default :data:`RESOLUTIONS`, or :data:`QUICK_RESOLUTIONS`);
    ``options``: solver -> {name: value}, the method's options (``sph.driver.solve``'s, the
    FEM's ``solve_model``'s)."""
    model = scene.model()
    allowed = solvers_for(model)
    solvers = list(solvers or allowed)
    for s in solvers:
        if s not in allowed:
            raise ValueError(f"solver: {s!r} cannot run scene '{scene.name}' ({type(model.drive).__name__} "
                             f"drive); allowed: {', '.join(allowed)}")
    default = QUICK_RESOLUTIONS if quick else RESOLUTIONS
    ladders = {s: check_resolutions(resolutions.get(s, default) if isinstance(resolutions, dict)
                                    else (resolutions or default)) for s in solvers}
    options = options or {}
    tasks = [Task.make(s, scene, r, **options.get(s, {}),
                       **({"fields": str(fields)} if fields is not None and
                          (field_runs is None or (s, r) in field_runs) else {}))
             for s, lad in ladders.items() for r in lad]
    outs = dict(zip(((t.solver, t.resolution) for t in tasks), run_tasks(tasks, scheduler, scene.name)))
    all_res = sorted({r for lad in ladders.values() for r in lad})
    shp = (len(solvers), len(all_res))
    status = np.full(shp, "not run", dtype=object)
    wall = np.full(shp, np.nan)
    npart = np.zeros(shp, np.int64)
    drive = model.drive
    obs = [o for o in model.observables if not isinstance(o, M.Period)]
    if isinstance(drive, M.Static):
        axis = ("parameter", np.asarray(drive.path, float),
                {"units": drive.units, "long_name": drive.parameter})
    elif isinstance(drive, M.Explicit):
        axis = ("time", np.linspace(0.0, drive.t_end, drive.n_out + 1), {"units": "s"})
    else:
        axis = ("mode", np.arange(1, drive.n_modes + 1), {"units": "-"})
    n_ax = len(axis[1])
    series = {n: np.full(shp + (n_ax,), np.nan) for o in obs for n in M.record_names(o, model.dim)}
    if isinstance(drive, M.Explicit):
        series.update({k: np.full(shp + (n_ax,), np.nan) for k in ENERGIES})
    if isinstance(drive, M.Modal):
        series["period"] = np.full(shp + (n_ax,), np.nan)
    scalars = {}
    notes = {}
    notes_of = [o.name for o in model.observables if isinstance(o, M.Period)]
    for p in (o for o in model.observables if isinstance(o, M.Period)):
        scalars[p.name] = np.full(shp, np.nan)
        scalars[f"{p.name}_amplitude"] = np.full(shp, np.nan)
        notes[f"{p.name}_status"] = np.full(shp, "not run", dtype=object)
    if getattr(drive, "stop", ()):  # where the drive's stop rules ended the run (NaN: none did)
        scalars["t_threshold"] = np.full(shp, np.nan)
    for i, s in enumerate(solvers):
        for r in ladders[s]:
            j = all_res.index(r)
            out = outs[(s, r)]
            st = out.get("status", "error: no status")
            status[i, j] = with_period_notes(st, out, list(notes_of)) if isinstance(st, str) else _summary(st)
            wall[i, j] = float(np.nanmax(np.atleast_1d(out.get("wall_time", np.nan))))
            npart[i, j] = int(out.get("n_particles", out.get("n_dof", 0)))
            for name, arr in series.items():
                src = {"period": "periods", **ENERGIES}.get(name, name)
                if src not in out:
                    continue
                y = np.asarray(out[src], float)
                if isinstance(drive, M.Explicit) and "time" in out and len(out["time"]) == len(y):
                    arr[i, j] = np.interp(axis[1], out["time"], y, right=np.nan)
                elif len(y) == n_ax:
                    arr[i, j] = y
            for name, arr in scalars.items():
                arr[i, j] = float(out.get(name, np.nan))
            for name, arr in notes.items():
                arr[i, j] = str(out.get(name, "not measured"))
    dims = ("solver", "resolution")
    data = {"status": (dims, status.astype(str), {"units": "-"}),
            "wall_time": (dims, wall, {"units": "s"}),
            "n_particles": (dims, npart, {"units": "-", "long_name": "particles or degrees of freedom"})}
    units = {M.Displacement: "m", M.Position: "m", M.Reaction: "N", M.MeanStress: "Pa",
             M.FailedFraction: "-"}
    for o in obs:
        if isinstance(o, M.CrackTip):
            for n, u in o.outputs(model.dim):
                data[n] = (dims + (axis[0],), series[n], {"units": u, "long_name": f"{n} of {o!r}"})
            continue
        data[o.name] = (dims + (axis[0],), series[o.name],
                        {"units": units.get(type(o), "-"), "long_name": repr(o)})
    for name in (*ENERGIES, "period"):
        if name in series and (name not in DISSIPATED or np.isfinite(series[name]).any()):
            data[name] = (dims + (axis[0],), series[name],
                          {"units": "s" if name == "period" else "J" if model.dim == 3 else "J/m",
                           "long_name": ENERGY_NAMES.get(name, name)})
    for name, arr in scalars.items():
        unit = "m" if name.endswith("amplitude") else "s"
        if name == "t_threshold" and isinstance(drive, M.Static):
            unit = drive.units  # a static path stops at a value of its load parameter
        data[name] = (dims, arr, {"units": unit})
    for name, arr in notes.items():
        data[name] = (dims, arr.astype(str), {"units": "-", "long_name": "'ok', or why there is no period"})
    for o in (o for o in obs if isinstance(o, M.CrackTip)):
        data[f"{o.name}_path"] = _paths(o, model.dim, solvers, all_res, outs)
    ds = xr.Dataset(data, coords={"solver": solvers, "resolution": all_res,
                                  axis[0]: (axis[0], axis[1], axis[2])})
    ds.attrs.update(results.provenance(scene.name, scene))
    ds.attrs.update(model.describe())
    ds.attrs["plane"] = str(model.plane)
    return ds


def _paths(o, dim: int, solvers, resolutions, outs) -> tuple:
    """The dataset variable ``<name>_path`` of the :class:`~workbench.scenes.model.CrackTip`
    ``o``: each run's crack path at its last record (origin, centroids, tip), m, padded with NaN
    to the longest, dims (solver, resolution, ``<name>_point``, ``<name>_coordinate``)."""
    paths = {k: np.asarray(v.get(f"{o.name}_path"), float).reshape(-1, dim)
             for k, v in outs.items() if v.get(f"{o.name}_path") is not None}
    n = max([len(p) for p in paths.values()] + [1])
    arr = np.full((len(solvers), len(resolutions), n, dim), np.nan)
    for (s, r), p in paths.items():
        if s in solvers and r in resolutions:
            arr[list(solvers).index(s), list(resolutions).index(r), :len(p)] = p
    return ((("solver", "resolution", f"{o.name}_point", f"{o.name}_coordinate")), arr,
            {"units": "m", "long_name": f"crack path at the last record of {o!r} (origin, "
                                        "centroids, tip; NaN-padded)"})


def _summary(statuses) -> str:
    statuses = [str(s) for s in statuses]
    return "ok" if all(results.path_ok(s) for s in statuses) else next(
        s for s in statuses if not results.path_ok(s))


def gates(ds) -> list:
    """A user's scene has no reference, hence no gate."""
    return []


def errors(ds) -> list:
    return []


def plot(ds, outdir) -> list:
    """Every observable against the load parameter, time or mode, one line per solver and
    resolution."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pathlib import Path

    from .figures import STYLE, save

    axis = next(d for d in ("parameter", "time", "mode") if d in ds.dims)
    names = [v for v in ds.data_vars if axis in ds[v].dims]
    if not names:
        return []
    fig, axes = plt.subplots(1, len(names), figsize=(4.6 * len(names), 3.8), squeeze=False)
    for ax, v in zip(axes[0], names):
        for s in ds.solver.values:
            for r in ds.resolution.values:
                y = ds[v].sel(solver=s, resolution=r).values
                if np.all(np.isnan(y)):
                    continue
                st = dict(STYLE.get(str(s), {}))
                st["ls"] = "-"
                ax.plot(ds[axis].values, y, label=f"{s} ({int(r)})", **st)
        ax.set_xlabel(f"{ds[axis].attrs.get('long_name', axis)} [{ds[axis].attrs.get('units', '-')}]")
        ax.set_ylabel(f"{v} [{ds[v].attrs.get('units', '-')}]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(ds.attrs.get("study", ""), fontsize=10)
    return [save(fig, Path(outdir) / f"{ds.attrs.get('study', 'scene')}.png")]
