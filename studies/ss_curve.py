"""SS curve study: uniaxial tension of the Table 1 steel (000, Fig. 1) to a log strain of 0.3.

Methods: ``analytic`` (exact, :func:`workbench.analytic.uniaxial_curve`), ``fem`` (3-D block of a
few elements) and ``csph`` (3-D block of a few particles), each solving the equilibrium of the block
under rollers and a prescribed end displacement. The state is homogeneous, so a handful of elements
or particles is all the scene needs: a linearly complete method reproduces it to solver tolerance.
"""
from __future__ import annotations

import sys

import numpy as np
import xarray as xr

from workbench import analytic, results
from workbench.scenes import SSCurve

from .common import Gate, validate
from .common import ladders as study_ladders
from .sweep import Task, run_tasks

NAME = "ss_curve"
SCENE = SSCurve
SOLVERS = ("analytic", "fem", "csph", "csph_quad", "csph_bl")
# The state is homogeneous: more buys nothing — except the proof that the method is exact at any
# resolution, which is what the csph ladder is for (the integration-consistent CSPH keeps the
# homogeneous state as its discrete equilibrium; the nodal-integration variants do not).
# Resolution = hexahedra (fem) or lattice cells (csph, (r+1)³ particles incl. the faces) per edge.
RESOLUTIONS = {"fem": (1, 2), "csph": (1, 2, 3, 5, 7), "csph_quad": (2, 3), "csph_bl": (2, 3)}
QUICK_RESOLUTIONS = {"fem": (1,), "csph": (1, 3), "csph_quad": (3,), "csph_bl": (3,)}
# The resolution whose curve is the method's result (``stress(solver, strain)``): the smallest of
# the ladder; every rung is kept on ``stress_by_resolution`` and reported.
# Gates. csph (integration-consistent) at every rung: the homogeneous state is the discrete
# equilibrium, so the error is Newton's tolerance (1e-8 of the reaction) and the return mapping's
# round-off (1e-12): 1e-6 leaves room for nothing but a defect (the nodal variants miss by 5-22 %
# from 4 particles per edge on). The FEM (hex8, homogeneous: exact) likewise: its Newton stops at
# 1e-6 of the load and the curve is exact to that (tests/test_fem_ss_curve.py). (Was issue 2's
# 0.5 % for the FEM in the study and 1e-6 in the test: one value now, 1e-6.) Both are exactness
# gates (tests/test_gates.py): the smallest defect they must catch is a modelling slip in the
# shared material code, e.g. hardening on the Cauchy instead of the Kirchhoff stress, which moves
# the curve by ~0.1 % (:data:`DEFECT`). The nodal-integration variants csph_quad and csph_bl are
# paper 000's CSPH as printed: reported, not gated — they pass only where symmetry hides the
# defect (2 cells per edge).
TOL_CONSISTENT = 1e-6
TOL_REL = TOL_CONSISTENT
DEFECT = 1e-3
REFERENCE = ("the exact uniaxial curve (workbench.analytic.uniaxial_curve: 1-D return mapping in "
             "log strains solved by brentq), written apart from the 3-D material code it checks")
N_GATES = {False: 6, True: 3}
"""Gates of the default run (full, ``--quick``): csph at each rung of its ladder (5; quick 2) and
the FEM. ``verify`` fails where fewer were evaluated."""
EXACT_AT_EVERY_RUNG = ("csph",)
GATED = ("fem", "csph")
# Method options of this study: h = 1.3Δx (support 2.6Δx: enough neighbours on the coarse block for
# the gradient correction); the FEM on trilinear hexahedra (2×2×2 Gauss: a homogeneous state needs
# no more; the FEM's default in 3-D is the 27-node element).
OPTIONS = {"csph": {"h_ratio": 1.3}, "csph_quad": {"h_ratio": 1.3}, "csph_bl": {"h_ratio": 1.3},
           "fem": {"element": "hex8"}}


def run(scene: SSCurve | None = None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None) -> xr.Dataset:
    """Run the study; returns the ``ss_curve`` dataset of the contract.

    ``resolutions``: None (the study's ladder), or a list applied to every discrete solver. The
    discrete solvers' smallest resolution is the one stored on ``stress(solver, strain)``; every
    resolution is kept on ``stress_by_resolution``.
    """
    scene = scene or SSCurve()
    validate(sys.modules[__name__], scene, solvers, resolutions, quick)  # before any work
    solvers = list(solvers or SOLVERS)
    if "analytic" not in solvers:
        solvers.insert(0, "analytic")  # the reference is always stored beside the methods
    strain = scene.strain_path()
    try:
        exact = analytic.uniaxial_curve(scene.material, strain)
        exact_status = "ok"
    except (ValueError, ArithmeticError) as err:  # parameters where the closed form breaks down
        exact = {k: np.full(strain.shape, np.nan) for k in ("sigma", "nominal", "eps_p")}
        exact_status = f"error: {type(err).__name__}: {' '.join(str(err).split())}"

    solvers, ladders = study_ladders(solvers, resolutions, sys.modules[__name__], quick)
    tasks = [Task.make(s, scene, r, **OPTIONS.get(s, {})) for s, lad in ladders.items() for r in lad]
    outs = dict(zip(((t.solver, t.resolution) for t in tasks), run_tasks(tasks, scheduler, NAME)))

    names, stress, nominal, wall, status, n_pts, res_used = [], [], [], [], [], [], []
    by_res = {}
    for s in solvers:
        if s == "analytic":
            names.append(s)
            stress.append(exact["sigma"])
            nominal.append(exact["nominal"])
            wall.append(0.0)
            status.append(exact_status)
            n_pts.append(0)
            res_used.append(0)
            continue
        for r in ladders[s]:
            out = outs[(s, r)]
            by_res[(s, r)] = (_on_grid(out, "stress", strain), out)
        r = min(ladders[s])
        sig, out = by_res[(s, r)]
        names.append(s)
        stress.append(sig)
        nominal.append(_on_grid(out, "nominal_stress", strain))
        wall.append(float(np.sum(out.get("wall_time", np.nan))))
        status.append(out["status"] if isinstance(out["status"], str) else str(out["status"]))
        n_pts.append(int(out.get("n_particles", out.get("n_dof", 0))))
        res_used.append(r)

    ds = xr.Dataset(
        {
            "stress": (("solver", "strain"), np.array(stress),
                       {"units": "Pa", "long_name": "axial Cauchy stress"}),
            "nominal_stress": (("solver", "strain"), np.array(nominal),
                               {"units": "Pa", "long_name": "axial force over initial area"}),
            "wall_time": (("solver",), np.array(wall), {"units": "s"}),
            "status": (("solver",), np.array(status, dtype=str), {"units": "-"}),
            "n_points": (("solver",), np.array(n_pts),
                         {"units": "-", "long_name": "particles or degrees of freedom"}),
            "resolution": (("solver",), np.array(res_used),
                           {"units": "-", "long_name": "hexahedra (fem) or particle-lattice cells (csph) per edge"}),
            "engineering_strain": (("strain",), np.expm1(strain), {"units": "-"}),
            "exact_eps_p": (("strain",), exact["eps_p"],
                            {"units": "-", "long_name": "equivalent plastic strain (exact)"}),
        },
        coords={"solver": names, "strain": ("strain", strain,
                                            {"units": "-", "long_name": "logarithmic axial strain"})},
    )
    if by_res:
        keys = sorted(by_res)
        ds["stress_by_resolution"] = (
            ("run", "strain"), np.array([by_res[k][0] for k in keys]),
            {"units": "Pa", "long_name": "axial Cauchy stress of every (solver, resolution) run"})
        ds = ds.assign_coords(run_solver=("run", [k[0] for k in keys]),
                              run_resolution=("run", [k[1] for k in keys]))
        ds["run_wall_time"] = (("run",), np.array([float(np.sum(by_res[k][1].get("wall_time", np.nan)))
                                                    for k in keys]), {"units": "s"})
    ds.attrs.update(results.provenance(NAME, scene))
    ds.attrs["hardening_on"] = "Kirchhoff stress (on the Cauchy stress the curve moves by ~0.1 %)"
    ds.attrs["stress_measure"] = "Cauchy stress against logarithmic strain"
    return ds


def _on_grid(out: dict, key: str, strain: np.ndarray) -> np.ndarray:
    """A solver's curve on the study's strain grid (NaN where the run failed or stopped early)."""
    if key not in out or "strain" not in out:
        return np.full(strain.shape, np.nan)
    vals = np.asarray(out[key], float)
    grid = np.asarray(out["strain"], float)
    res = np.full(strain.shape, np.nan)
    n = min(len(vals), len(strain))
    if n and np.allclose(grid[:n], strain[:n], rtol=1e-9, atol=1e-12):
        res[:n] = vals[:n]
    return res


def relative_error(ds: xr.Dataset, values: np.ndarray) -> np.ndarray:
    """|σ − σ_exact| / max(|σ_exact|, σ_y0) at every strain (the floor keeps the measure finite
    where an unload cycle passes through zero stress)."""
    exact = ds.stress.sel(solver="analytic").values
    floor = ds.attrs["param_C"] * ds.attrs["param_eps0"] ** ds.attrs["param_n"]
    return np.abs(np.asarray(values) - exact) / np.maximum(np.abs(exact), floor)


def gates(ds: xr.Dataset) -> list[Gate]:
    out = []
    for s in ds.solver.values:
        if s not in GATED:
            continue
        if s in EXACT_AT_EVERY_RUNG and "run" in ds.dims:
            for i in np.flatnonzero(ds.run_solver.values == s):
                err = relative_error(ds, ds.stress_by_resolution.values[i])
                r = int(ds.run_resolution.values[i])
                out.append(Gate.at_most(
                    f"ss_curve {s} ({r + 1} particles per edge): max relative error over the curve",
                    float(np.max(err)) if np.all(np.isfinite(err)) else float("nan"),
                    TOL_CONSISTENT, "integration-consistent: the homogeneous state is the discrete "
                    "equilibrium; Newton's tolerance and round-off only (nodal variants: 5-22 %)",
                    REFERENCE, defect=DEFECT))
            continue
        err = relative_error(ds, ds.stress.sel(solver=s).values)
        out.append(Gate.at_most(
            f"ss_curve {s}: max relative error of the Cauchy stress over the curve",
            float(np.max(err)) if np.all(np.isfinite(err)) else float("nan"), TOL_REL,
            "homogeneous state (hex8): exact up to the Newton and return-mapping tolerances",
            REFERENCE, defect=DEFECT))
    return out


def errors(ds: xr.Dataset) -> list[dict]:
    """Rows for the report: solver, resolution, max relative error, wall time."""
    rows = []
    if "run" in ds.dims:
        for i in range(ds.sizes["run"]):
            s = str(ds.run_solver.values[i])
            e = relative_error(ds, ds.stress_by_resolution.values[i])
            rows.append(dict(solver=s, resolution=int(ds.run_resolution.values[i]),
                             error=float(np.max(e)), wall_time=float(ds.run_wall_time.values[i])))
    return rows


def report_notes(ds: xr.Dataset) -> list[str]:
    notes = ["Each method's curve is at its smallest resolution; the table lists every rung."]
    if {"csph_bl", "csph_quad"} & set(ds.solver.values):
        notes.append("csph_bl and csph_quad integrate nodally (paper 000 as printed): the uniaxial "
                     "block is not their discrete equilibrium, and from 4 particles per edge on it "
                     "relaxes into a non-homogeneous state that is too soft. csph (integration-"
                     "consistent) keeps the exact curve at every resolution.")
    return notes


def plot(ds: xr.Dataset, outdir) -> list:
    from . import figures as plots

    return [plots.ss_curve(ds, outdir)]
