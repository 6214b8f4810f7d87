"""The studies' figures, read from the datasets only (never recomputed): references beside the
computed curves, axes labelled with units. :func:`save` is the one figure writer."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

STYLE = {"analytic": dict(color="k", lw=1.5, ls="-"),
         "fem": dict(color="tab:blue", marker="s", ms=4, ls="none"),
         "csph": dict(color="tab:red", marker="o", ms=4, mfc="none", ls="none"),
         "hpm": dict(color="tab:green", marker="^", ms=4, mfc="none", ls="none"),
         "sph": dict(color="tab:purple", marker="x", ms=4, ls="none")}


def save(fig, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def ss_curve(ds, outdir) -> Path:
    """Cauchy stress against log strain and nominal stress against engineering strain, each method
    beside the exact curve, and the relative error."""
    fig, ax = plt.subplots(1, 3, figsize=(14, 4.2))
    eps = ds.strain.values
    eng = ds.engineering_strain.values
    exact = ds.stress.sel(solver="analytic").values
    for s in ds.solver.values:
        st = STYLE.get(str(s), {})
        label = str(s) if s == "analytic" else f"{s} ({int(ds.resolution.sel(solver=s))}/edge)"
        ax[0].plot(eps, ds.stress.sel(solver=s).values / 1e6, label=label, **st)
        ax[1].plot(eng, ds.nominal_stress.sel(solver=s).values / 1e6, label=label, **st)
        if s != "analytic":
            err = np.abs(ds.stress.sel(solver=s).values - exact) / np.maximum(np.abs(exact), 1.0)
            ax[2].semilogy(eps, np.maximum(err, 1e-17), label=str(s), **{**st, "ls": "-"})
    ax[0].set(xlabel="logarithmic axial strain [-]", ylabel="Cauchy stress [MPa]",
              title="uniaxial tension, Table 1 steel")
    ax[1].set(xlabel="engineering strain [-]", ylabel="nominal stress [MPa]",
              title="force over initial area")
    ax[2].axhline(5e-3, color="grey", ls="--", label="gate 0.5 %")
    ax[2].set(xlabel="logarithmic axial strain [-]", ylabel="relative error of Cauchy stress [-]",
              title="error against the exact curve")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    return save(fig, Path(outdir) / "ss_curve.png")


def accuracy_vs_cost(rows: list[dict], title: str, path, error_label: str) -> Path:
    """Error against wall time, log–log, one line per method over its resolutions."""
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    for s in sorted({r["solver"] for r in rows}):
        pts = sorted((r["wall_time"], r["error"], r["resolution"]) for r in rows
                     if r["solver"] == s and np.isfinite(r["error"]) and r["wall_time"] > 0)
        if not pts:
            continue
        t, e, res = zip(*pts)
        st = {**STYLE.get(s, {}), "ls": "-"}
        ax.loglog(t, np.maximum(e, 1e-16), label=s, **st)
        for ti, ei, ri in pts:
            ax.annotate(str(ri), (ti, max(ei, 1e-16)), fontsize=7, xytext=(3, 3),
                        textcoords="offset points")
    ax.set(xlabel="wall time [s]", ylabel=error_label, title=title)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    return save(fig, path)


def cantilever(ds, outdir) -> Path:
    """Tip deflection over L against the load for each method (finest resolution) beside the
    elastica and the linear theories, and the error against resolution."""
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    loads = ds["load"].values
    L = float(ds.attrs.get("param_L", 1.0))
    fine = np.geomspace(max(loads.min(), 1e-3), loads.max(), 60)
    from workbench.analytic import elastica_tip, plane_moduli

    Ep, _ = plane_moduli(ds.attrs["param_E"], ds.attrs["param_nu"], ds.attrs.get("plane", "strain"))
    ax[0].plot(fine, [elastica_tip(p * ds.attrs["param_E"] / Ep)[0] for p in fine], "k-",
               label="elastica (analytic)")
    slope = ds.timoshenko.values[0] / loads[0]  # linear theory: δ ∝ P
    ax[0].plot(fine, slope * fine / L, "k--", lw=0.8, label="Timoshenko (linear)")
    for s in ds.solver.values:
        if s == "analytic":
            continue
        v = ds.tip_deflection.sel(solver=s).values
        ok = np.flatnonzero(np.isfinite(v).all(axis=1))
        if ok.size:
            j = ok[-1]
            ax[0].plot(loads, v[j] / L, label=f"{s} ({int(ds.resolution.values[j])} across H)",
                       **STYLE.get(str(s), {}))
        ref = ds.fem_converged.values
        for k, p in enumerate(loads):
            e = np.abs(v[:, k] - ref[k]) / abs(ref[k])
            good = np.isfinite(e) & (e > 0)
            if good.any():
                ax[1].loglog(ds.resolution.values[good], e[good],
                             **{**STYLE.get(str(s), {}), "ls": "-"},
                             label=f"{s}, P L²/EI = {p:.3g}", alpha=0.4 + 0.6 * k / max(1, len(loads) - 1))
    ax[0].set(xscale="log", yscale="log", xlabel="load P L² / (E I) [-]", ylabel="tip deflection / L [-]",
              title=f"cantilever, plane {ds.attrs.get('plane', 'strain')}")
    ax[1].set(xlabel="intervals across H, H/Δx or H/h [-]",
              ylabel="|δ − δ_FEM,converged| / δ_FEM,converged [-]", title="convergence")
    for a in ax:
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    return save(fig, Path(outdir) / "cantilever.png")


def plate(ds, outdir) -> Path:
    """Tip displacement histories beside the thin-plate response, and the period against resolution
    beside the FEM modal and thin-plate periods."""
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    t = ds.time.values
    for s in ds.solver.values:
        h = ds.tip_displacement.sel(solver=s).values
        ok = np.flatnonzero(np.isfinite(h).any(axis=1))
        if ok.size:
            j = ok[-1]
            label = "thin plate (analytic)" if s == "analytic" else f"{s} ({int(ds.resolution.values[j])} across H)"
            st = {"color": STYLE.get(str(s), {}).get("color", "k"), "lw": 1.2 if s != "analytic" else 0.8,
                  "ls": "--" if s == "analytic" else "-"}
            ax[0].plot(t, h[j] * 1e3, label=label, **st)
    ax[0].set(xlabel="time [s]", ylabel="tip displacement [mm]", title="plate, tip history")
    res = ds.resolution.values
    ax[1].axhline(ds.attrs["analytic_period"], color="k", ls="--", lw=0.8, label="thin plate")
    ax[1].axhline(float(ds.fem_modal_converged), color="tab:blue", ls=":", label="FEM modal, converged")
    for s in ds.solver.values:
        if s == "analytic":
            continue
        v = ds.period.sel(solver=s).values
        good = np.isfinite(v)
        if good.any():
            ax[1].plot(res[good], v[good], **{**STYLE.get(str(s), {}), "ls": "-"}, label=str(s))
    ax[1].set(xscale="log", xlabel="intervals across H, H/Δx or H/h [-]", ylabel="period [s]",
              title="period against resolution")
    for a in ax:
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    return save(fig, Path(outdir) / "plate.png")
