"""What the micro-cantilever study's report says beside its gates: the fracture energy's trend with
the spacing, the FEM's limits and their uncertainty, the loads at the first failure, the
fragments and the FEM with element deletion."""
from __future__ import annotations

import numpy as np
import xarray as xr

from .dataset import _is_3d
from .derive import (SINGULAR_ORDER, TAIL, band_ladder, band_width, fem_slope_limit,
                     fracture_ladder, spacing_power)
from .gates import _runs, _slope_tolerance_ds, root_tolerance
from .ladders import FEM_DELETION_RESOLUTION, LADDER_RULES
from .static import EDGE_CLEARANCE


def fracture_note(ds: xr.Dataset, case: str) -> str | None:
    """Gate 5's line of the report for ``case``: the crack's energy per run of each ladder rule,
    its fitted power of Δx and its spread — the regularised rule's over the gate's runs
    (:func:`.derive.band_ladder`); None without a ladder."""
    unit = "J/m" if ds.attrs.get("plane") == "strain" else "J"
    parts = []
    for rule in LADDER_RULES:
        res, G = fracture_ladder(ds, case, rule)
        if len(res) < 2:
            continue
        parts.append(f"{rule}: " + ", ".join(f"{g:.3g} (H/dx = {r})" for r, g in zip(res, G))
                     + f", G ~ dx^{spacing_power(res, G):.2f}")
        if rule == "regularised":
            res, G = band_ladder(ds, case)
            parts[-1] += (f", max/min - 1 = {100 * (np.max(G) / np.min(G) - 1):.1f} % over H/dx = "
                          f"{', '.join(str(r) for r in res)} (band > dx)")
        else:
            parts[-1] += f", max/min - 1 = {100 * (G.max() / G.min() - 1):.1f} %"
    if not parts:
        return None
    return (f"gate 5, {case}: energy of the main crack when it cut the body ({unit}; plastic work "
            f"and released energy of its particles, and of the cut pairs, at the record of the "
            f"cut) — " + "; ".join(parts) + f". compression: eps_L as given (band "
            f"{float(ds.attrs.get('param_band', 0.0)):g} m); regularised: crack band "
            f"{band_width(ds):g} m.")


def report_notes(ds: xr.Dataset) -> list[str]:
    notes = []
    if "fem_elastic_slope" in ds:
        fr = [int(r) for r in ds.fem_resolution.values]
        f_unit = ds.fem_load.attrs.get("units", "N/m")
        kind = ("plane strain, Q9" if ds.attrs.get("plane", "strain") == "strain" else
                "3-D, 27-node hexahedra, beyond the coarsest at the first, elastic path point only"
                + (" (and along the root path to the root region's first failures)"
                   if "fem_first_failure_root_load" in ds else ""))
        notes.append(
            f"FEM reference ({kind}, J2 with Swift per grain and boundary, static): elastic "
            "slope " + ", ".join(f"{float(v):.5g} (H/h = {r})" for r, v in
                                 zip(fr, ds.fem_elastic_slope.values))
            + f" {f_unit}/m, Richardson limit {ds.attrs['fem_slope_limit']:.5g} at the singular order "
            f"{SINGULAR_ORDER:.3g} (observed {ds.attrs['fem_observed_order']:.3g}); first failure "
            + "; ".join(f"{c}: " + ", ".join(
                f"{float(L):.4g} {f_unit} at {float(u) * 1e6:.3g} um (H/h = {r})" for r, L, u in
                zip(fr, ds.fem_first_failure_load.sel(case=c).values,
                    ds.fem_first_failure_deflection.sel(case=c).values) if np.isfinite(L))
                for c in ds.case.values)
            + ". The first failure anywhere is on the top face under or beside the rigidly moved "
            "patch, whose edges are singular points: its load falls with the spacing in the FEM "
            "and has no limit to check against (not gated; gate 2 looks at the root region).")
        for case, rule, r, sel in _runs(ds, tuple(ds.rule.values)):
            notes.append(
                f"gate 1, {case}, {rule}, H/dx = {r}: csph slope "
                f"{float(ds.elastic_slope_fem_window.sel(**sel)):.5g} {f_unit}/m, "
                f"{100 * float(ds.slope_error_fem.sel(**sel)):.2f} % from the FEM's limit "
                f"(tolerance {100 * _slope_tolerance_ds(ds, r):.2f} %), "
                f"{100 * float(ds.slope_vs_fem_same_resolution.sel(**sel)):+.2f} % from the FEM at "
                f"the same H/h; csph first failure {float(ds.load_at_first_failure.sel(**sel)):.4g} "
                f"{f_unit} at {float(ds.deflection_at_first_failure.sel(**sel)) * 1e6:.3g} um; "
                f"kinetic/elastic {float(ds.kinetic_ratio.sel(**sel)):.2e}.")
        for case, rule, r, sel in _runs(ds, tuple(ds.rule.values), ("csph_bl",)):
            notes.append(
                f"csph_bl (000 as printed; shown, not gated), {case}, {rule}, H/dx = {r}: slope "
                f"{float(ds.elastic_slope_fem_window.sel(**sel)):.5g} {f_unit}/m, "
                f"{100 * float(ds.slope_error_fem.sel(**sel)):.2f} % from the FEM's limit, "
                f"{100 * float(ds.slope_vs_fem_same_resolution.sel(**sel)):+.2f} % from the FEM at "
                f"the same H/h; first failure {float(ds.load_at_first_failure.sel(**sel)):.4g} "
                f"{f_unit} at {float(ds.deflection_at_first_failure.sel(**sel)) * 1e6:.3g} um.")
    if "static_elastic_slope" in ds and "fem_slope_limit" in ds.attrs:
        sr = ds.static_resolution.values
        notes.append(
            "gate 1, static csph (the secant at the first path point; the finest gated at 1 %): "
            + ", ".join(f"{float(v):.5g} {ds.static_elastic_slope.attrs['units']} (H/dx = {int(r)}, "
                        f"{100 * float(e):.2f} %)" for r, v, e
                        in zip(sr, ds.static_elastic_slope.values, ds.static_slope_error.values))
            + f" against the FEM's slope limit {ds.attrs['fem_slope_limit']:.5g} (its uncertainty, "
            f"singular against observed order: {100 * ds.attrs.get('fem_slope_limit_spread', np.nan):.2f} "
            f"%); observed order of the error {ds.attrs.get('static_slope_order', np.nan):.2f} "
            "(least squares).")
    if "static_first_failure_root_load" in ds:
        fr = [int(r) for r in ds.fem_resolution.values]
        sr = ds.static_resolution.values
        unit = ds.fem_root_limit.attrs.get("units", "N/m")
        for case in ds.case.values:
            f = ds.fem_first_failure_root_load.sel(case=case).values
            c = ds.static_first_failure_root_load.sel(case=case).values
            notes.append(
                f"gate 2 (first failure in the root region: 0 <= x <= L/2, upper half"
                + (f", {EDGE_CLEARANCE * float(ds.attrs['param_H']) * 1e6:g} um clear of the "
                   "re-entrant side edges" if _is_3d(ds) else "") + f"), {case}: FEM "
                + ", ".join(f"{v:.4g} (H/h = {r})" for r, v in zip(fr, f))
                + f" {unit}, limit {float(ds.fem_root_limit.sel(case=case)):.4g} (observed order "
                f"{float(ds.fem_root_order.sel(case=case)):.3g}; the limit's uncertainty "
                f"{100 * float(ds.fem_root_limit_spread.sel(case=case)):.2f} %); csph static "
                + ", ".join(f"{v:.4g} (H/dx = {int(r)}, {100 * float(e):.2f} %, tolerance "
                            f"{100 * root_tolerance(ds, str(case), int(r)):.1f} %)"
                            for r, v, e in zip(sr, c, ds.static_root_error.sel(case=case).values)
                            if np.isfinite(v))
                + f"; observed order of csph's error {float(ds.static_root_order.sel(case=case)):.2f} "
                "(least squares).")
            ok = np.isfinite(c)
            if ok.sum() >= 2:  # csph's own Richardson limit, from its two finest, beside the FEM's
                lim = fem_slope_limit(sr[ok], c[ok])
                notes[-1] += (f" csph's own limit (two finest, singular order) {lim:.4g} {unit}, "
                              f"{100 * (lim / float(ds.fem_root_limit.sel(case=case)) - 1):+.2f} % "
                              f"from the FEM's.")
    if "fracture_energy" in ds:
        notes += [n for n in (fracture_note(ds, str(case)) for case in ds.case.values) if n]
    if "fem_deletion_status" in ds:
        for case in ds.case.values:
            L = ds.fem_deletion_load.sel(case=case).values
            peak = np.nanmax(L) if np.isfinite(L).any() else np.nan
            tail = L[(ds.time.values > (1 - TAIL) * ds.time.values[-1]) & np.isfinite(L)]
            notes.append(
                f"gate 6, {case}: the FEM with element deletion (Q9, H/h = "
                f"{FEM_DELETION_RESOLUTION}, Newmark, plane strain) — "
                f"{ds.fem_deletion_status.sel(case=case).values}, "
                f"{int(ds.fem_deleted.sel(case=case))} elements deleted "
                f"({ds.fem_deleted_regions.sel(case=case).values}; "
                f"{100 * float(ds.fem_deleted_share_low.sel(case=case)):.0f} % where the low eps_L "
                f"is), peak load {peak:.4g} N/m, mean load over the last 20 % "
                f"{(f'{100 * tail.mean() / peak:.2g} %' if tail.size else 'n/a')} of it, "
                f"{float(ds.fem_deletion_wall_time.sel(case=case)):.0f} s.")
    notes += comparison_notes(ds)
    notes += crack_ladder_notes(ds)
    for case, rule, r, sel in _runs(ds, tuple(ds.rule.values), tuple(ds.solver.values)):
        v = {k: ds[k].sel(**sel).values for k in ("peak_load", "t_first_failure", "n_failed",
                                                   "share_boundaries", "tail_load_ratio", "separated",
                                                   "connected", "energy_balance_error",
                                                   "crack_regions", "t_separated", "t_last")}
        unit = "N/m" if ds.attrs.get("plane") == "strain" else "N"
        notes.append(("" if sel["solver"] == "csph" else f"{sel['solver']}, ")
                     + f"{case}, {rule}, H/dx = {r}: peak load before failure "
                     f"{float(v['peak_load']):.4g} {unit}, first failure at "
                     f"{float(v['t_first_failure']) * 1e6:.3g} us, {int(v['n_failed'])} failed "
                     f"particles ({100 * float(v['share_boundaries']):.0f} % in grain boundaries; "
                     f"{v['crack_regions']}), "
                     f"{'separated' if float(v['separated']) == 1 else 'not separated'} (mean load "
                     f"over the last 20 % {100 * float(v['tail_load_ratio']):.2g} % of that peak; "
                     f"{'a ligament still joins' if float(v['connected']) == 1 else 'nothing joins'} "
                     f"the patch and the held faces; "
                     + (f"cut apart at {float(v['t_separated']) * 1e6:.3g} us"
                        if np.isfinite(float(v['t_separated'])) else "never cut apart")
                     + f", run to {float(v['t_last']) * 1e6:.3g} us), energy balance error "
                     f"{float(v['energy_balance_error']):.2e}.")
    return notes


COMPARED = ("peak_load", "max_load", "load_at_first_failure", "t_first_failure", "t_separated",
            "crack_x", "crack_region", "crack_regions", "fragment_speed_max",
            "fragment_kinetic_share")


def comparison_notes(ds: xr.Dataset, rule: str = "compression") -> list[str]:
    """One line per case and resolution where csph and csph_bl (000's CSPH as printed: Bonet–Lok
    correction, nodal integration) both ran under ``rule``: the peak load before the first
    failure, the load and time of the first failure, the largest load until the cut, the time and
    place the crack cut the body, the regions the failed particles lie in and the fragments' top
    speed and kinetic share, side by side."""
    if "csph_bl" not in ds.solver.values or rule not in ds.rule.values:
        return []
    unit = "N/m" if ds.attrs.get("plane") == "strain" else "N"
    notes = []
    for case in ds.case.values:
        for r in ds.resolution.values:
            vals = {}
            for solver in ("csph", "csph_bl"):
                sel = dict(solver=solver, case=case, rule=rule, resolution=r)
                if str(ds.status.sel(**sel).values) == "not run":
                    break
                vals[solver] = {k: ds[k].sel(**sel).values for k in COMPARED}
            if len(vals) < 2:
                continue

            def one(v):
                t_sep = float(v["t_separated"])
                return (f"peak {float(v['peak_load']):.4g} {unit}, first failure "
                        f"{float(v['load_at_first_failure']):.4g} {unit} at "
                        f"{float(v['t_first_failure']) * 1e6:.3g} us, largest load until the cut "
                        f"{float(v['max_load']):.4g} {unit}, "
                        + (f"cut at {t_sep * 1e6:.3g} us through {v['crack_region']} at x = "
                           f"{float(v['crack_x']) * 1e6:.2f} um" if np.isfinite(t_sep) else
                           "never cut")
                        + f" ({v['crack_regions']}), fragments up to "
                        f"{float(v['fragment_speed_max']):.2g} m/s, "
                        f"{100 * float(v['fragment_kinetic_share']):.2g} % of the released energy")

            notes.append(f"000's method beside ours, {case}, {rule}, H/dx = {int(r)}: csph "
                         f"{one(vals['csph'])}; csph_bl {one(vals['csph_bl'])}.")
    return notes


def crack_ladder_notes(ds: xr.Dataset) -> list[str]:
    """Issue 36 item 3's line per solver and case with two runs or more that cut the body (the
    default rule): where the crack cut it (x, region) and the largest load until the cut at each
    resolution, with the peak load's observed order over the three finest where there are three."""
    from .derive import _order3
    from .gates import crack_ladder

    unit = "N/m" if ds.attrs.get("plane") == "strain" else "N"
    notes = []
    for solver in ds.solver.values:
        for case in ds.case.values:
            res, x, reg, peak = crack_ladder(ds, str(case), solver=str(solver))
            if len(res) < 2:
                continue
            order = (f"; observed order of the peak load (H/dx = {', '.join(map(str, res[-3:]))}) "
                     f"{_order3(res[-3:].astype(float), peak[-3:]):.2f}" if len(res) >= 3 else "")
            notes.append(f"crack ladder, {solver}, {case}: " + ", ".join(
                f"H/dx = {r}: cut through {g} at x = {xx * 1e6:.2f} um, largest load {p:.4g} {unit}"
                for r, xx, g, p in zip(res, x, reg, peak)) + order + ".")
    return notes
