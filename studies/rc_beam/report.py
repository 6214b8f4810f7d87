"""What the RC beam study's report says beside its gates: the largest values with their time ("≥ …
(truncated at t_end)" where they are lower bounds), the kernel-reduction ratios, 003's validation
rows, the energy released per crack area at each spacing and the slow impact's note."""
from __future__ import annotations

import numpy as np
import xarray as xr

from .dataset import SCALARS
from .derive import ANGLE_BINS, LOAD_CELL_WINDOW, PAPER, PAPER_LOAD_CELL_RANGE, TRUNCATION_MARGIN
from .gates import _runs
from .ladders import KERNEL_REDUCTION_SPECIMEN, MODAL_RESOLUTION
from .slow_impact import slow_note


def show_largest(value: float, when: float, truncated: bool, scale: float, unit: str,
                 digits: int = 3) -> str:
    """A largest value as the report shows it: '6.13 mm at 4.2 ms' where it is a maximum, '≥ 6.13 mm
    (truncated at t_end)' where it came within :data:`.derive.TRUNCATION_MARGIN` of the run's end (a
    lower bound, never a maximum)."""
    if not np.isfinite(value):
        return "n/a"
    v = f"{value * scale:.{digits}g} {unit}"
    return f"≥ {v} (truncated at t_end)" if truncated else f"{v} at {when * 1e3:.3g} ms"


def report_notes(ds: xr.Dataset) -> list[str]:
    notes = []
    if "first_frequency" in ds:
        for sp in ds.specimen.values:
            f = ds.first_frequency.sel(specimen=sp).values
            if np.isfinite(f).any():
                notes.append(f"{sp}, beam with rebar on hinges (H/dx = {MODAL_RESOLUTION}): first "
                              f"flexural frequency csph {f[0]:.5g} Hz, FEM {f[1]:.5g} Hz "
                              f"({100 * float(ds.frequency_error.sel(specimen=sp)):+.2f} %).")
    if "slow_error" in ds:
        notes.append(slow_note(ds))
    for s, sp, r, sel in _runs(ds):
        v = {k: float(ds[k].sel(**sel)) for k in SCALARS}
        row = (f"{sp}, {s}, H/dx = {r}: {ds.status.sel(**sel).values}; largest mid-span displacement "
               f"{_largest(ds, 'max_displacement', sel, 1e3, 'mm')}, residual "
               f"{v['residual_displacement'] * 1e3:.3g} mm, impact force as a load cell sees it "
               f"({LOAD_CELL_WINDOW * 1e3:g} ms mean) "
               f"{_largest(ds, 'impact_force_window_peak', sel, 1e-3, 'kN')} (003's load cell: "
               f"{PAPER_LOAD_CELL_RANGE / 1e3:g} kN range; not gated), the penalty's "
               f"instantaneous force at the records up to {v['max_impact_force'] / 1e3:.3g} kN "
               "(depends on the record interval); cracked mortar "
               + ", ".join(f"{k} {100 * v[f'cracked_{k}']:.2g} %" for k in ANGLE_BINS)
               + f"; energy error {v['energy_balance_error']:.2e}, momentum error "
               f"{v['momentum_error']:.1e}; {float(ds.particle_steps_per_second.sel(**sel)):.3g} "
               "particle-steps/s.")
        if sp in PAPER:
            row += (f" Validation (not gated): 003 reports about "
                    f"{PAPER[sp]['max_displacement'] * 1e3:g} mm without kernel reduction"
                    + ("; this run ends before its largest displacement, not comparable."
                       if v["max_displacement_truncated"] == 1 else "."))
        notes.append(row)
    if "kr_max_displacement" in ds:
        sp = KERNEL_REDUCTION_SPECIMEN
        for r in ds.resolution.values:
            a, b = (float(ds.kr_max_displacement.sel(kernel_reduction=k, resolution=r)) for k in (0, 1))
            cut = [float(ds.kr_max_displacement_truncated.sel(kernel_reduction=k,
                                                              resolution=r)) == 1
                   if "kr_max_displacement_truncated" in ds else False for k in (0, 1)]
            if np.isfinite(a) and np.isfinite(b):
                ratio = (f"x{b / a:.2f}" if not any(cut) else
                         "no ratio: a truncated value is a lower bound, not a maximum")
                notes.append(f"{sp}, sph, H/dx = {int(r)}: largest mid-span displacement "
                             f"{_show(a, cut[0])} without the kernel reduction, {_show(b, cut[1])} "
                             f"with it ({ratio}). Validation (not gated): 003 reports about "
                             f"{PAPER[sp]['max_displacement'] * 1e3:g} and "
                             f"{PAPER[sp]['max_displacement_kernel_reduction'] * 1e3:g} mm (x2).")
    notes += crack_band_notes(ds)
    return notes


def _largest(ds: xr.Dataset, name: str, sel: dict, scale: float, unit: str) -> str:
    """The report's text of the largest value ``name`` of a run (:func:`show_largest`, with its
    ``name_time`` and ``name_truncated``)."""
    return show_largest(float(ds[name].sel(**sel)), float(ds[f"{name}_time"].sel(**sel)),
                        float(ds[f"{name}_truncated"].sel(**sel)) == 1, scale, unit)


def _show(w: float, truncated: bool) -> str:
    """A largest displacement (m) in mm, '≥ … (truncated at t_end)' where truncated."""
    return f"≥ {w * 1e3:.3g} mm (truncated at t_end)" if truncated else f"{w * 1e3:.3g} mm"


def crack_band_notes(ds: xr.Dataset) -> list[str]:
    """Issue 12 gate 6 across the ladder's spacings, per specimen and solver: the energy released
    per crack area over G_F (with the fully released fraction of the mortar and its share of the
    released energy: where most of the mortar is released the damage is diffuse, not bands, and
    the crack area is only the bands' equivalent) and the largest mid-span displacement at each
    spacing, and the displacement's trend (its change from each spacing to the next finer one)."""
    if "released_per_crack_area_over_GF" not in ds:
        return []
    notes = []
    for sp in ds.specimen.values:
        for s in ds.solver.values:
            rows = []
            stopped = []
            for r in ds.resolution.values:
                sel = dict(solver=s, specimen=sp, resolution=r)
                st = str(ds.status.sel(**sel).values)
                if st != "ok":  # not run, or stopped early: no end state to compare
                    if st != "not run":
                        stopped.append(f"{_dx_label(ds, r)} stopped ({st})")
                    continue
                rows.append((float(ds.spacing.sel(resolution=r)),
                             float(ds.released_per_crack_area_over_GF.sel(**sel)),
                             float(ds.released_per_crack_area.sel(**sel)),
                             float(ds.max_displacement.sel(**sel)),
                             sum(float(ds[f"cracked_{k}"].sel(**sel)) for k in ANGLE_BINS),
                             float(ds.released_share_full.sel(**sel)),
                             float(ds.max_displacement_truncated.sel(**sel)) == 1))
            if not rows:
                if stopped:
                    notes.append(f"{sp}, {s}, energy released per crack area: {'; '.join(stopped)}.")
                continue
            rows.sort(reverse=True)  # coarse to fine
            text = "; ".join(f"dx = {dx * 1e3:.3g} mm: {e:.3g} G_F ({a:.4g} J/m^2; mortar fully "
                             f"released {100 * c:.2g} %, holding {100 * f:.2g} % of the released "
                             f"energy), largest displacement {_show(w, cut)}"
                             for dx, e, a, w, c, f, cut in rows)
            w = [row[3] for row in rows]
            if len(w) > 1 and any(row[6] for row in rows):  # a lower bound has no trend
                text += (". No trend of the largest displacement: truncated values (within "
                         f"{TRUNCATION_MARGIN * 1e3:g} ms of t_end) are lower bounds")
            elif len(w) > 1 and np.isfinite(w).all():
                steps = [f"{100 * (b / a - 1):+.1f} %" for a, b in zip(w, w[1:])]
                trend = ("grows" if all(b > a for a, b in zip(w, w[1:])) else
                         "falls" if all(b < a for a, b in zip(w, w[1:])) else "is not monotonic")
                text += (f". The largest displacement {trend} with refinement "
                         f"({', '.join(steps)} from each spacing to the next finer)")
            if stopped:
                text += ". " + "; ".join(stopped)
            notes.append(f"{sp}, {s}, energy released per crack area (crack band 2 dx; eq. 5 "
                         f"scaling {'on' if int(ds.attrs.get('param_scale_release', 1)) else 'off'}"
                         f"): {text}.")
    return notes


def _specimens_run(ds: xr.Dataset) -> list:
    """The specimens with at least one run (``--quick`` runs B alone): the figures' columns."""
    return [sp for sp in ds.specimen.values if (ds.status.sel(specimen=sp) != "not run").any()]


def _dx_label(ds: xr.Dataset, r) -> str:
    """'dx = 8.33 mm': the spacing of resolution ``r``, three significant digits."""
    return f"dx = {float(ds.spacing.sel(resolution=r)) * 1e3:.3g} mm"
