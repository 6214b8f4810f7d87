"""The micro-cantilever's load at the first failure in the root region, on a ladder of its own
(``workbench run microcantilever_root``): gate 1's second half and gate 5's observed order of the
issue for the 3-D scene, which the default ``microcantilever`` run leaves out because it takes
hours on 2 cores (:func:`studies.microcantilever.study.root_ladder`).

At each resolution the FEM (27-node hexahedra in 3-D, 9-node quadrilaterals in 2-D; J2 with Swift
per grain and boundary) and static csph (the study's options, Newton) push the loading patch down
along :func:`studies.microcantilever.static.root_ladder_path` without damage, and each stops once both
cases have failed in :func:`studies.microcantilever.static.root_region` (ε_p ≥ ε_L: the grain boundaries'
0.002 for ``inter``, the grains' for ``intra``). The FEM's loads at that first failure give a
Richardson limit at the singular order; csph's are gated against it at each resolution (within the
FEM's own error at the same nodal spacing, at least 3 %) and at the finest (3 %, the issue's
bound), beside the elastic slopes (1 % at the finest). The dataset carries no particle dynamics:
its variables are the ``fem_*`` and ``static_*`` ones of ``microcantilever.nc`` (contract).

``--quick``: the 2-D scene (plane strain), csph at H/Δx = 5, 10, 20, 40 and the FEM at H/h = 5 to
80, about 6 minutes.
Solvers: csph (the FEM runs beside it as the reference).
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from ..common import check_resolutions
# gates, report_notes and quick_scene are the micro-cantilever study's: this study's protocol too
from .gates import TOL_FIRST_FAILURE, gates  # noqa: F401
from .ladders import FEM_RESOLUTIONS, FEM_RESOLUTIONS_3D, quick_scene  # noqa: F401
from .report import report_notes  # noqa: F401
from .scene import MicroCantilever
from .study import root_ladder

NAME = "microcantilever_root"
SCENE = MicroCantilever
SOLVERS = ("csph",)
RESOLUTIONS = {"csph": list(FEM_RESOLUTIONS_3D)}
"""3-D: H/Δx = H/h = 5, 10, 15 (1776 to 38 176 particles, 1250 to 33 750 hexahedra); measured on 2
cores, the FEM at 10 takes 20 minutes and at 15 53 minutes and 11 GB, csph at 10 7 minutes and at
15 44 minutes and 3.7 GB (its AMG-CG solves run on one core). csph's load is then 16.8, 8.8 and
5.2 % (intra; observed order 1.06) and 17.1, 7.1 and 5.0 % (inter; 1.13) above the FEM's limit:
every per-resolution gate passes, the issue's 3 % at the finest would need H/Δx ≈ 26 (README)."""
QUICK_RESOLUTIONS = {"csph": [5, 10, 20, 40]}
"""``--quick`` (2-D, plane strain): the 2-D ladder of gate 2 up to H/Δx = 40, where the issue's
bounds at the finest hold in 2-D (5 min 51 s on one core beside another job, csph at 40 42 s and
the FEM at 80 3.9 minutes of it; every gate passes). Below 40 csph's 2-D loads are not within 3 %
of the FEM's limit: 5.9 % (inter) and 4.6 % (intra) at 20."""
QUICK_FEM_RESOLUTIONS = FEM_RESOLUTIONS
"""``--quick``: the FEM's 2-D ladder, H/h = 5 to 80, a mesh beyond csph's
(:data:`studies.microcantilever.ladders.FEM_RESOLUTIONS` says why)."""
ERROR_LABEL = "|load at the first failure in the root region / FEM limit - 1| [-]"


def run(scene: MicroCantilever | None = None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None) -> xr.Dataset:
    """:func:`studies.microcantilever.study.root_ladder` at ``resolutions`` (a list, or a dict with
    'csph'; the FEM runs at the same ones); ``quick``: the 2-D scene at QUICK_RESOLUTIONS. The runs
    are in this process, one after the other (``scheduler`` is accepted and unused: the largest
    of them needs most of this machine's memory)."""
    scene = scene or SCENE()
    for s in solvers or SOLVERS:
        if s not in SOLVERS:
            raise ValueError(f"solver: {s!r} is not supported by {NAME}; allowed: {', '.join(SOLVERS)}")
    if quick:
        scene = quick_scene(scene)
    table = QUICK_RESOLUTIONS if quick else RESOLUTIONS
    if isinstance(resolutions, dict):
        resolutions = resolutions.get("csph")
    res = check_resolutions(resolutions or table["csph"])
    for r in res:  # a grain boundary thinner than the spacing is bad input, not a failed run
        scene.model(scene.H / r)
    return root_ladder(scene, res, QUICK_FEM_RESOLUTIONS if quick and not resolutions else None)


def errors(ds: xr.Dataset) -> list[dict]:
    """Per case, csph's and the FEM's error in the load at the first failure in the root region
    against the FEM's Richardson limit, with the wall time of each one's run along the root path
    (the accuracy-against-cost chart)."""
    rows = []
    for case in ds.case.values:
        for r, e, t in zip(ds.static_resolution.values, ds.static_root_error.sel(case=case).values,
                           ds.static_wall_time.values):
            if np.isfinite(e):
                rows.append(dict(solver=f"csph ({case})", resolution=int(r), error=float(e),
                                 wall_time=float(t)))
        for r, e, t in zip(ds.fem_resolution.values, ds.fem_root_error.sel(case=case).values,
                           ds.fem_root_wall_time.values):
            if np.isfinite(e):
                rows.append(dict(solver=f"fem ({case})", resolution=int(r), error=float(e),
                                 wall_time=float(t)))
    return rows


def plot(ds: xr.Dataset, outdir) -> list:
    """The load at the first failure in the root region against the resolution, csph and the FEM
    per case, with the FEM's limit and the issue's 3 % about it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pathlib import Path

    from ..figures import STYLE, save

    unit = ds.fem_root_limit.attrs.get("units", "N")
    scale, shown = (1e3, "mN") if unit == "N" else (1e-3, "kN/m")
    fig, axes = plt.subplots(1, len(ds.case), figsize=(5.5 * len(ds.case), 4.2), squeeze=False)
    for ax, case in zip(axes[0], ds.case.values):
        lim = float(ds.fem_root_limit.sel(case=case)) * scale
        if np.isfinite(lim):
            ax.axhline(lim, color="k", lw=1, label="FEM limit (singular order)")
            ax.axhspan(lim * (1 - TOL_FIRST_FAILURE), lim * (1 + TOL_FIRST_FAILURE),
                       color="0.85", label="limit ± 3 % (issue, finest)")
        ax.plot(ds.fem_resolution.values, ds.fem_first_failure_root_load.sel(case=case) * scale,
                label="FEM, elements across H", **{**STYLE["fem"], "ls": "-"})
        ax.plot(ds.static_resolution.values,
                ds.static_first_failure_root_load.sel(case=case) * scale,
                label="csph static, particles across H", **{**STYLE["csph"], "ls": "-"})
        ticks = sorted({int(r) for r in ds.fem_resolution.values}
                       | {int(r) for r in ds.static_resolution.values})
        ax.set_xscale("log")
        ax.set_xticks(ticks, [str(r) for r in ticks])
        ax.minorticks_off()
        ax.set_xlabel("resolution H/h, H/dx [-] (log)")
        ax.set_ylabel(f"load at the first failure in the root region [{shown}]")
        ax.set_title(f"{case}-granular ({'3-D' if unit == 'N' else '2-D, plane strain'})")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    return [save(fig, Path(outdir) / f"{NAME}_first_failure.png")]
