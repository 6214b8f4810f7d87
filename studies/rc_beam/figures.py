"""The RC beam study's figures: the mid-span displacement of each specimen, the impact force as a
load cell sees it, the energies of every run, the cracked mortar by orientation and the slow
impact against the FEM."""
from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.materials.mortar_constants import PAPER_SPACING

from .derive import CRACK_DAMAGE, LOAD_CELL_WINDOW, PAPER, PAPER_LOAD_CELL_RANGE, TRUNCATION_MARGIN
from .ladders import KERNEL_REDUCTION_SPECIMEN, NAME
from .report import _dx_label, _largest, _specimens_run


def plot(ds: xr.Dataset, outdir) -> list:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pathlib import Path

    from ..figures import save

    outdir = Path(outdir)
    figs = []
    specimens = _specimens_run(ds)
    fig, axes = plt.subplots(1, len(specimens), figsize=(8 * len(specimens), 4.2), squeeze=False)
    styles = {"sph": "--", "csph": "-"}
    for ax, sp in zip(axes[0], specimens):
        curves = [(str(s), ds.midspan_displacement.sel(solver=s, specimen=sp),
                   styles.get(str(s), "-"),
                   ds.max_displacement_truncated.sel(solver=s, specimen=sp)
                   if "max_displacement_truncated" in ds else None) for s in ds.solver.values]
        if "kr_midspan_displacement" in ds and str(sp) == KERNEL_REDUCTION_SPECIMEN:
            curves.append(("sph + kernel reduction",
                           ds.kr_midspan_displacement.sel(kernel_reduction=1), "-.",
                           ds.kr_max_displacement_truncated.sel(kernel_reduction=1)
                           if "kr_max_displacement_truncated" in ds else None))
        cuts = []
        for what, ys, ls, cut in curves:  # colour: the spacing; line style: the method
            for k, r in enumerate(ds.resolution.values):
                y = ys.sel(resolution=r)
                if not np.isfinite(y).any():
                    continue
                # its largest value: a dot where a maximum, an open triangle where truncated
                c = cut.sel(resolution=r) if cut is not None else np.nan
                c = bool(np.isfinite(c) and c == 1)
                cuts.append(c)
                j = int(np.nanargmax(y.values))
                ax.plot(ds.time * 1e3, y * 1e3, ls=ls, lw=1, color=f"C{k}",
                        label=f"{what}, {_dx_label(ds, r)}"
                        + (f": ≥ {float(y[j]) * 1e3:.3g} mm (truncated at t_end)" if c else ""))
                ax.plot(float(ds.time[j]) * 1e3, float(y[j]) * 1e3, "^" if c else "o",
                        mfc="none" if c else f"C{k}", color=f"C{k}", ms=5)
        if cuts and all(cuts):  # nothing here is a maximum: 003's maxima are not drawn beside it
            ax.text(0.02, 0.97, f"every run ends within {TRUNCATION_MARGIN * 1e3:g} ms of its "
                    "largest displacement\n(open triangles): truncated at t_end, not maxima;\n"
                    "003's largest values (about 3 and 6 mm) are not comparable",
                    transform=ax.transAxes, va="top", fontsize=7)
        elif str(sp) in PAPER:
            p = PAPER[str(sp)]
            ax.axhline(p["max_displacement"] * 1e3, color="k", ls=":", lw=1,
                       label="003 SPH, largest (no kernel reduction)")
            ax.axhline(p["max_displacement_kernel_reduction"] * 1e3, color="gray", ls=":", lw=1,
                       label="003 SPH, largest (kernel reduction)")
        ax.set_xlabel("time [ms]")
        ax.set_ylabel("mid-span displacement [mm]")
        ax.set_title(f"specimen {sp}, 0–{float(ds.time[-1]) * 1e3:.3g} ms")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.tight_layout()
    figs.append(save(fig, outdir / f"{NAME}_displacement.png"))
    if "impact_force_window" in ds:
        figs.append(impact_force_figure(ds, specimens, outdir / f"{NAME}_impact_force.png"))
    # energies of the finest run
    r = ds.resolution.values[-1]
    fig, axes = plt.subplots(len(ds.solver), len(specimens), figsize=(6 * len(specimens),
                             3.8 * len(ds.solver)), squeeze=False)
    parts = ("kinetic_energy", "strain_energy", "plastic_work", "released_energy",
             "viscous_work")
    for i, s in enumerate(ds.solver.values):
        for j, sp in enumerate(specimens):
            ax = axes[i, j]
            sel = dict(solver=s, specimen=sp, resolution=r)
            tot = 0
            for n in parts:
                y = ds[n].sel(**sel)
                tot = tot + y
                ax.plot(ds.time * 1e3, y, lw=1, label=n)
            ax.plot(ds.time * 1e3, tot, "k--", lw=1, label="sum")
            ax.set_title(f"{sp}, {s}, H/dx = {int(r)}", fontsize=9)
            ax.set_xlabel("time [ms]")
            ax.set_ylabel("energy [J]")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=6)
    figs.append(save(fig, outdir / f"{NAME}_energies.png"))
    if "mortar_X" in ds:
        figs.append(crack_figure(ds, outdir / f"{NAME}_cracks.png"))
    if "slow_csph_displacement" in ds:
        fig, ax = plt.subplots(figsize=(6.5, 4.2))
        for n, run in enumerate(ds.slow_run.values):
            if str(run).startswith("fem"):
                ax.plot(ds.slow_time * 1e3, ds.slow_fem_rungs.isel(slow_run=n) * 1e6, lw=0.8,
                        label=str(run).replace("fem", "FEM,", 1))
        ax.plot(ds.slow_time * 1e3, ds.slow_csph_displacement * 1e6, "k", lw=1.2,
                label=f"csph, H/dx = {ds.attrs.get('slow_resolution')}")
        ax.set_xlabel("time [ms]")
        ax.set_ylabel("mid-span displacement [µm]")
        ax.set_title(f"{ds.attrs.get('slow_specimen')}, slow impact at "
                     f"{ds.attrs.get('slow_velocity'):g} m/s: first half period", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        figs.append(save(fig, outdir / f"{NAME}_slow_impact.png"))
    return figs


def impact_force_figure(ds: xr.Dataset, specimens, path):
    """The impact force of the finest run of each method: the penalty's instantaneous force at the
    records (thin: it rings at ~20 µs and its peak depends on the record interval) and the load
    cell's, its :data:`.derive.LOAD_CELL_WINDOW` mean from the impulse (thick), with 003's load-cell
    range."""
    import matplotlib.pyplot as plt

    from ..figures import save

    r = ds.resolution.values[-1]
    fig, axes = plt.subplots(1, len(specimens), figsize=(7 * len(specimens), 4.0), squeeze=False)
    for ax, sp in zip(axes[0], specimens):
        for k, s in enumerate(ds.solver.values):
            sel = dict(solver=s, specimen=sp, resolution=r)
            if not np.isfinite(ds.impact_force_window.sel(**sel)).any():
                continue
            ax.plot(ds.time * 1e3, ds.impact_force.sel(**sel) / 1e3, color=f"C{k}", lw=0.5,
                    alpha=0.5, label=f"{s}: at the records (interval-dependent)")
            ax.plot(ds.time * 1e3, ds.impact_force_window.sel(**sel) / 1e3, color=f"C{k}", lw=1.8,
                    label=f"{s}: {LOAD_CELL_WINDOW * 1e3:g} ms mean (load cell), peak "
                    + _largest(ds, "impact_force_window_peak", sel, 1e-3, "kN"))
        ax.axhline(PAPER_LOAD_CELL_RANGE / 1e3, color="k", ls=":", lw=1,
                   label="003's load cell range (200 kN)")
        ax.set_title(f"specimen {sp}, {_dx_label(ds, r)}", fontsize=9)
        ax.set_xlabel("time [ms]")
        ax.set_ylabel("impact force, full beam [kN]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6)
    return save(fig, path)


def crack_figure(ds: xr.Dataset, path):
    """The cracked beams (as Fig. 16 and 19 of 003): the mortar particles of the finest run in the
    symmetry plane y = 0, at their reference positions, coloured by the damage (the damage tensor's
    largest eigenvalue; without a history the largest residual principal strain over the release
    strain at that spacing, clipped to [0, 2]), the crack line — perpendicular to the principal
    damage direction — drawn where the particle is cracked (:func:`.derive.crack_orientation`)."""
    import matplotlib.pyplot as plt

    from ..figures import save

    dx = float(ds.spacing.values[-1])
    eps_cr = float(ds.attrs["param_eps_release"]) * (
        PAPER_SPACING / dx if int(ds.attrs.get("param_scale_release", 1)) else 1.0)
    specimens = _specimens_run(ds)
    fig, axes = plt.subplots(len(ds.solver), len(specimens), figsize=(7 * len(specimens),
                             2.4 * len(ds.solver) + 0.6), squeeze=False)
    for i, s in enumerate(ds.solver.values):
        for j, sp in enumerate(specimens):
            ax = axes[i, j]
            X = ds.mortar_X.sel(solver=s, specimen=sp).values
            e = ds.mortar_strain.sel(solver=s, specimen=sp).values
            d = (ds.mortar_damage.sel(solver=s, specimen=sp).values if "mortar_damage" in ds
                 else np.full_like(e, np.nan))
            n = ds.mortar_opening.sel(solver=s, specimen=sp).values
            ok = np.isfinite(e) & (np.abs(X[:, 1]) < 1e-9)
            if not ok.any():
                ax.set_axis_off()
                continue
            if np.isfinite(d[ok]).all():
                c, vmax, label, cr = d[ok], 1.0, "damage", ok & (d >= CRACK_DAMAGE)
            else:
                c, vmax, label, cr = np.clip(e[ok] / eps_cr, 0, 2), 2.0, "strain / release strain", ok & (e > eps_cr)
            sc = ax.scatter(X[ok, 0] * 1e3, X[ok, 2] * 1e3, c=c, cmap="magma_r", s=10, vmin=0,
                            vmax=vmax)
            # the crack line: perpendicular to the opening, in the x-z plane
            ax.quiver(X[cr, 0] * 1e3, X[cr, 2] * 1e3, -n[cr, 2], n[cr, 0], angles="xy",
                      pivot="middle", headwidth=0, headlength=0, headaxislength=0, scale=40,
                      width=0.003, color="tab:blue")
            ax.set_aspect("equal")
            ax.set_title(f"{sp}, {s} (crack lines blue)", fontsize=9)
            ax.set_xlabel("x from mid-span [mm]")
            ax.set_ylabel("z [mm]")
            fig.colorbar(sc, ax=ax, shrink=0.7, label=label)
    return save(fig, path)
