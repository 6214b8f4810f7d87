"""The micro-cantilever study's figures: the load–deflection curves, the failed fractions and
energies, the fracture energy against the spacing and the cracked cantilevers (as 000's Fig. 5
and 6, with the FEM's deleted elements beside them)."""
from __future__ import annotations

import numpy as np
import xarray as xr

from .derive import fracture_ladder
from .ladders import FEM_DELETION_RESOLUTION, LADDER_RULES, NAME


def plot(ds: xr.Dataset, outdir) -> list:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pathlib import Path

    from ..figures import save

    outdir = Path(outdir)
    figs = []
    styles = {"compression": "-", "literal": "--", "no_crack_rule": ":"}
    # load–deflection
    fig, axes = plt.subplots(1, len(ds.case), figsize=(6 * len(ds.case), 4.2), squeeze=False)
    for ax, case in zip(axes[0], ds.case.values):
        for solver in ds.solver.values:
            for rule in ds.rule.values:
                for r in ds.resolution.values:
                    sel = dict(solver=solver, case=case, rule=rule, resolution=r)
                    if str(ds.status.sel(**sel).values) == "not run":
                        continue
                    ax.plot(ds.deflection.sel(**sel) * 1e6, ds["load"].sel(**sel),
                            ls="-." if solver == "csph_bl" else styles.get(str(rule), "-"), lw=1,
                            label=("" if solver == "csph" else f"{solver} (000 as printed), ")
                            + f"{rule}, H/dx = {int(r)}")
        if "fem_load" in ds:  # the static FEM (no damage) to the first failure of this case
            for r in ds.fem_resolution.values:
                u = float(ds.fem_first_failure_deflection.sel(case=case, fem_resolution=r))
                keep = ds.fem_deflection.values <= (u if np.isfinite(u) else np.inf)
                ax.plot(ds.fem_deflection.values[keep] * 1e6,
                        ds.fem_load.sel(fem_resolution=r).values[keep], "k", lw=0.8,
                        alpha=0.4 + 0.6 * float(r) / float(ds.fem_resolution.values[-1]),
                        label=f"FEM, H/h = {int(r)}, to its first failure")
        if "fem_deletion_load" in ds:
            ax.plot(ds.fem_deletion_deflection.sel(case=case) * 1e6,
                    ds.fem_deletion_load.sel(case=case), "k--", lw=1.2,
                    label=f"FEM with element deletion, H/h = {FEM_DELETION_RESOLUTION}")
        ax.set_xlabel("deflection of the loading patch [um]")
        ax.set_ylabel("load [N/m]" if ds.attrs.get("plane") == "strain" else "load [N]")
        ax.set_title(f"{case}-granular")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    figs.append(save(fig, outdir / f"{NAME}_load_deflection.png"))
    # failed fraction per part over time, and energies, of the default rule
    rule = "compression" if "compression" in ds.rule.values else str(ds.rule.values[0])
    fig, axes = plt.subplots(2, len(ds.case), figsize=(6 * len(ds.case), 7.5), squeeze=False)
    for k, case in enumerate(ds.case.values):
        ax = axes[0, k]
        for r in ds.resolution.values:
            for part, ls in zip(ds.part.values, ("-", "--", ":")):
                ax.plot(ds.time * 1e6, ds.failed_fraction.sel(solver="csph", case=case, rule=rule,
                                                              resolution=r, part=part),
                        ls=ls, lw=1, label=f"{part}, H/dx = {int(r)}")
        ax.set_xlabel("time [us]")
        ax.set_ylabel("failed fraction [-]")
        ax.set_title(f"{case}-granular, {rule}")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        ax = axes[1, k]
        sel = dict(solver="csph", case=case, rule=rule, resolution=ds.resolution.values[-1])
        total = 0
        for n in ("kinetic_energy", "elastic_energy", "plastic_work", "released_energy",
                  "merge_dissipation"):
            if n not in ds:
                continue
            y = ds[n].sel(**sel).fillna(0.0) if n == "merge_dissipation" else ds[n].sel(**sel)
            total = total + y
            ax.plot(ds.time * 1e6, y, lw=1, label=n)
        ax.plot(ds.time * 1e6, ds.external_work.sel(**sel), "k", lw=2, label="external work")
        ax.plot(ds.time * 1e6, total, "y--", lw=1, label="their sum")
        ax.set_xlabel("time [us]")
        ax.set_ylabel("energy [J/m]" if ds.attrs.get("plane") == "strain" else "energy [J]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    figs.append(save(fig, outdir / f"{NAME}_failure_energies.png"))
    if "fracture_energy" in ds and any(len(fracture_ladder(ds, str(c), r)[0]) >= 2
                                       for c in ds.case.values for r in LADDER_RULES):
        figs.append(fracture_figure(ds, outdir / f"{NAME}_fracture_energy.png"))
    if "particle_x" in ds:
        figs.append(cracked(ds, outdir / f"{NAME}_cracks.png"))
    return figs


def fracture_figure(ds: xr.Dataset, path):
    """Gate 5: the main crack's energy against the spacing, literal ε_L (``compression``) and crack
    band (``regularised``), each case; the line G ∝ Δx through the coarsest literal run."""
    import matplotlib.pyplot as plt

    from ..figures import save

    fig, ax = plt.subplots(figsize=(6, 4.2))
    H = float(ds.attrs["param_H"])
    for case, c in zip(ds.case.values, ("tab:blue", "tab:red")):
        for rule, mk in (("compression", "o--"), ("regularised", "s-")):
            res, G = fracture_ladder(ds, str(case), rule)
            if len(res):
                ax.loglog(H / res * 1e6, G, mk, color=c, label=f"{case}, {rule} ("
                          + ("eps_L as given)" if rule == "compression" else "crack band)"))
        res, G = fracture_ladder(ds, str(case), "compression")
        if len(res):
            dx = H / res
            ax.loglog(dx * 1e6, G[0] * dx / dx[0], ":", color=c, lw=0.8, label="~ dx")
    ax.set_xlabel("particle spacing dx [um]")
    ax.set_ylabel("energy of the main crack [J/m]" if ds.attrs.get("plane") == "strain"
                  else "energy of the main crack [J]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    return save(fig, path)


CRACK_MAP_PAD = 1e-6
"""Margin of a crack map's axes around the particles it draws, m."""


def crack_map_limits(x: np.ndarray, up: int) -> tuple[tuple[float, float], tuple[float, float]]:
    """(x limits, vertical limits) of a crack map, µm: the deformed positions ``x`` (n, d), m, of
    every particle drawn — the failed ones wherever they went — with :data:`CRACK_MAP_PAD`
    around them (the map used to take the reference body's box, which cut out the failed
    particles that had left it: the inter crack showed as a gap with none drawn)."""
    lo = np.nanmin(x, axis=0) - CRACK_MAP_PAD
    hi = np.nanmax(x, axis=0) + CRACK_MAP_PAD
    return (lo[0] * 1e6, hi[0] * 1e6), (lo[up] * 1e6, hi[up] * 1e6)


def cracked(ds: xr.Dataset, path):
    """The cracked cantilevers side by side (Fig. 5 and 6 of 000), :func:`crack_figure`."""
    from ..figures import save

    return save(crack_figure(ds), path)


def crack_figure(ds: xr.Dataset):
    """The figure of :func:`cracked`: final particles of the finest run on the deformed shape,
    coloured by grain (the boundaries grey), failed particles red, the axes around every particle
    drawn (:func:`crack_map_limits`); a 3-D run is shown by its particles within half a spacing of
    the mid-plane y = 0."""
    import matplotlib.pyplot as plt

    names = ds.attrs["region_names"].split(", ")
    solvers = list(ds.solver.values) if "solver" in ds.particle_x.dims else [None]
    # one row per solver and rule with particles (csph_bl runs the default rule only)
    maps = [(s, rule) for s in solvers for rule in ds.rule.values
            if s is None or int(ds.particle_resolution.sel(solver=s, rule=rule).max()) > 0]
    fem = "fem_element_deleted" in ds
    rows = len(maps) + int(fem)
    fig, axes = plt.subplots(rows, len(ds.case), figsize=(6 * len(ds.case), 2.6 * rows),
                             squeeze=False)
    palette = np.array(["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown",
                        "tab:pink", "tab:olive", "tab:cyan"])
    for i, case in enumerate(ds.case.values):
        for j, (solver, rule) in enumerate(maps):
            ax = axes[j, i]
            on = dict(case=case, rule=rule, **({} if solver is None else dict(solver=solver)))
            X = ds.particle_X.sel(**on).values
            x = ds.particle_x.sel(**on).values
            reg = ds.particle_region.sel(**on).values
            bad = ds.particle_failed.sel(**on).values.astype(bool)
            at = int(ds.particle_resolution.sel(**on))
            ok = reg >= 0
            if not ok.any():
                ax.set_axis_off()
                continue
            if X.shape[1] == 3:
                # the lattice plane nearest the beam's mid-plane y = 0 (the lattice starts at the
                # block's side face: at even particle counts across B the planes straddle y = 0)
                dx = float(ds.attrs["param_H"]) / at
                mid = X[ok, 1][np.argmin(np.abs(X[ok, 1]))]
                ok &= np.abs(X[:, 1] - mid) <= 0.25 * dx
            up = X.shape[1] - 1
            col = np.array(["tab:gray" if names[r].startswith("gb") else
                            palette[int(names[r][5:]) % len(palette)] if r >= 0 else "w" for r in reg])
            m = ok & ~bad
            ax.scatter(x[m, 0] * 1e6, x[m, up] * 1e6, c=col[m], s=6)
            ax.scatter(x[ok & bad, 0] * 1e6, x[ok & bad, up] * 1e6, c="red", s=8)
            xlim, ylim = crack_map_limits(x[ok], up)
            ax.set_xlim(*xlim)
            ax.set_ylim(*ylim)
            ax.set_aspect("equal")
            ax.set_title(("" if solver in (None, "csph") else f"{solver} (000 as printed), ")
                         + f"{case}-granular, {rule}, H/dx = {at}", fontsize=9)
            ax.set_xlabel("x [um]")
            ax.set_ylabel(("y" if up == 1 else "z") + " [um]")
        if fem:  # the FEM with element deletion: element centres, reference configuration
            ax = axes[-1, i]
            Xe = ds.fem_element_X.values
            reg = ds.fem_element_region.values
            dead = ds.fem_element_deleted.sel(case=case).values.astype(bool)
            col = np.array(["tab:gray" if names[r].startswith("gb") else
                            palette[int(names[r][5:]) % len(palette)] for r in reg])
            ax.scatter(Xe[~dead, 0] * 1e6, Xe[~dead, 1] * 1e6, c=col[~dead], s=14, marker="s")
            ax.scatter(Xe[dead, 0] * 1e6, Xe[dead, 1] * 1e6, c="red", s=14, marker="s")
            ax.set_aspect("equal")
            ax.set_title(f"{case}-granular, FEM with element deletion, H/h = "
                         f"{FEM_DELETION_RESOLUTION} (element centres, reference)", fontsize=9)
            ax.set_xlabel("x [um]")
            ax.set_ylabel("y [um]")
    from matplotlib.lines import Line2D

    grains = sorted({int(n[5:]) for n in names if n.startswith("grain")})
    key = [Line2D([], [], ls="", marker="o", color=palette[g % len(palette)], label=f"grain {g}")
           for g in grains]
    key += [Line2D([], [], ls="", marker="o", color="tab:gray", label="grain boundary"),
            Line2D([], [], ls="", marker="o", color="red", label="failed / deleted (D >= 1)")]
    axes[-1, 0].legend(handles=key, loc="upper left", bbox_to_anchor=(0.0, -0.3), ncol=4,
                       fontsize=8, frameon=False)
    return fig
