"""Plate study: the oscillating clamped plate of 004 D (Table I; Gray, Monaghan & Swift 2001),
plane strain, rigid clamp.

References: the thin-plate period and amplitude (004 eq. 13–16) as ``analytic``; the FEM modal
period of the same 2-D plate with the same clamp (the continuum reference, ~0.46 % above thin-plate
theory) — every discrete period is measured against the FEM modal period extrapolated to zero element
size. Table I of 004 is reproduced as dimensionless period T c0 / L and amplitude A / L.
"""
from __future__ import annotations

import sys

import numpy as np
import xarray as xr

from workbench import analytic, results
from workbench.oscillation import with_period_notes
from workbench.scenes import Plate
from workbench.scenes.model import Modal

from .common import Gate, field_options, field_series, observed_order, planned, validate
from .common import ladders as study_ladders
from .sweep import Task, run_tasks

NAME = "plate"
SCENE = Plate
SOLVERS = ("analytic", "fem", "csph", "csph_quad", "csph_bl", "hpm", "hpm_vc", "sph")
# Intervals across H (spacing H/r; r quadratic elements). The FEM's modal period is cheap on every rung; its one
# dynamic run (period and amplitude from the tip history) is at FEM_DYNAMIC.
RESOLUTIONS = {"fem": (2, 4, 8, 16), "csph": (5, 10, 20, 40), "csph_quad": (5, 10, 20),
               "csph_bl": (5, 10, 20), "hpm": (5, 10, 20), "hpm_vc": (5, 10, 20), "sph": (5, 10)}
QUICK_RESOLUTIONS = {"fem": (2, 4, 8), "csph": (5, 10), "hpm": (10,), "sph": (5,)}
FEM_DYNAMIC = {False: 8, True: 4}  # by quick
ERROR_LABEL = "relative period error vs converged FEM modal period [-]"
N_TIME = 401  # common time grid of the stored tip histories

# Tolerances, each the error the method should have (its order, the resolution, the reference's
# own error), tight enough that three times the recorded error fails it (tests/test_gates.py).
# The FEM modal period against thin-plate theory: shear and rotary inertia lengthen the 2-D
# continuum's period; their first-order correction ½ (k r)² (1 + E'/(κ G)), r² = H²/12, is 0.73 %
# here (plane strain, ν = 0.3975), an upper estimate (notes.md: 0.46 % for the rigidly clamped
# continuum; measured +0.47 % at 16 across H, whose own error is 0.01 %). Was 1 % (and 0.75 % in
# tests/test_fem_plate.py): one value now, the upper estimate.
TOL_FEM_THIN_PLATE = 0.0075
# Particle methods at H/Δx = 10 against the FEM modal period (issues 4 and 5): 3 % (004's HPM model
# is 2.7 % from thin-plate theory; hpm measures +1.8 %, a tripled 5.4 % fails).
TOL_PERIOD = 0.03
# Their amplitude against the FEM's dynamic amplitude: A = V/ω, so the amplitude carries the
# period's error (3 %), plus the reference's own: the FEM dynamic run's period error at its mesh
# against the converged modal period (:func:`_fem_dynamic_error`: 0.12 % at 4 across H in the
# quick run, 0.04 % at 8). (Was issue 4's 5 %, against hpm's 1.6 %: a tripled 4.7 % passed.)
TOL_AMPLITUDE = 0.03
# Energy of the symplectic schemes over the run (two periods, no damping): velocity Verlet's energy
# error is bounded, O((ω Δt)²) of the energy, with no secular growth (csph 6e-6 at H/Δx = 4,
# tests/test_csph_plate.py). A conservation gate ("exact" in tests/test_gates.py): the smallest
# defect it must catch is a scheme that does not conserve, e.g. a first-order explicit step, whose
# energy grows by (ω₁Δt)(ω₁ t_end) over the run: 3.3e-3 at H/Δx = 10 (ω₁Δt = 2.6e-4 at dt factor
# 0.3, ω₁ t_end = 4π; DRIFT_DEFECT). 0.1 %, under a third of it (unchanged).
TOL_DRIFT = 1e-3
DRIFT_DEFECT = 3.3e-3
GATED = ("csph", "hpm", "hpm_vc")
# The integration-consistent methods (csph; hpm_vc: HPM's gradient with consistent integration):
# second order. Their expected period error at H/Δx = 10: the bulk O((Δx/H)²) error, measured on a
# free–free beam without the clamp's corners at the same spacing (+0.04 %,
# tests/test_consistency.py: an estimate independent of this plate), the clamped corners (cut out
# of the integration) at most 0.015 % and the reference's own error 0.005 % (TOL_PERIOD_MODAL
# says why), and the dynamic run's finite amplitude, which shifts the period by ~0.015 % against
# the modal reference: 0.075 %. (Was 6e-4, a sum without the corners' and the reference's terms;
# before that 1e-3 = (Δx/H)²/8, against a measured +0.0305 %: a tripled 0.09 % passed.) hpm_vc's
# dynamic period is gated with it: −0.046 %, its modal −0.03 % and the shift adding (its bulk on
# the free–free beam is csph's, +0.043 % at 10; its corners' term is larger than csph's and of
# the opposite sign, as its cantilever's +0.03 % against the bulk's +0.087 % of compliance says
# too); a tripled 0.14 % fails. csph's dynamic period is not gated at 10: its two terms of
# opposite sign (the discretisation's +0.025 %, the finite amplitude's −0.014 %) nearly cancel,
# so csph's period at 10 is gated like with like, its modal period against the FEM's modal limit
# (TOL_PERIOD_MODAL). The nodal variants miss it by far: csph_quad by 0.19 %, csph_bl by 2.7 %,
# hpm by 1.8 %.
TOL_PERIOD_CONSISTENT = 7.5e-4
# csph's modal (linearised) period at H/Δx = 10 against the FEM's modal limit: the same quantity,
# the continuum's linear period, by two independent discretisations, so no finite-amplitude term.
# Its expected error is the discretisation's alone: the bulk's +0.04 % (free–free beam above), the
# clamped corners' term and the reference's own error. The corners' term, from the cantilever's
# clamp at the same spacing (studies/cantilever.py: csph's compliance +0.05 … +0.10 % against the
# bulk's 2 × 0.0415 %, so the corners −0.033 … +0.017 % of the compliance), is at most 0.015 % of
# the period (T ∝ √compliance: half of it, 0.0165 %; the corner's share of the strain energy
# scales as H/L, so 8/10 of it on the plate's longer span, 0.013 %). The reference's own error:
# the quick run's limit (FEM at 2, 4, 8 across H) lies 0.005 % below the full run's (4, 8, 16),
# whose own is smaller still. Together 0.06 %: 6e-4. (The dynamic period was gated against the
# same limit with TOL_PERIOD_CONSISTENT: +0.016 % (quick) and +0.011 % (full), whose tripled
# errors passed. The modal error, recorded full run +0.025 % and quick +0.030 %: tripled 0.075 %
# and 0.090 %, both fail.)
TOL_PERIOD_MODAL = 6e-4
MODAL_AT = 10
"""The resolution of csph's modal period gate (computed in the quick run too)."""
# Their amplitude against the FEM's dynamic amplitude: A = V/ω, the period's error (the finite
# amplitude is in both runs and cancels: 0.045 %) and the peak's sampling (parabolic refinement of
# records ~T/200 apart: (π/200)²/2 ≈ 1e-4), plus the reference's own error as TOL_AMPLITUDE's.
# (Was 5 % in the study and 0.3 % in tests/test_csph_plate.py; measured +0.066 % against the
# quick run's FEM at 4 across H, whose own error is 0.12 %.) Open (issue 42): the reference's own error counts its
# mesh but not its Newmark step, which moves its amplitude as much — at 8 across H −0.077 % from
# the study's 100 to 200 steps per period (tests/test_gates.py, FULL_PLATE_SLIPS).
TOL_AMPLITUDE_CONSISTENT = 6e-4
CONSISTENT = ("csph", "hpm_vc")
# csph at H/Δx = 40 (full ladder), its dynamic period against the FEM's modal limit. The expected
# error is the discretisation's plus the finite amplitude's. Discretisation: second order from the
# bulk's 0.04 % at 10 predicts 0.0025 %, the corners' term falls alike: 0.005 % at most. Finite
# amplitude: the period of the 0.12 L oscillation lies below the linear (modal) one; the FEM's
# dynamic runs measure it apart from csph — dynamic/modal − 1 at 4 across H is +0.044 % at 100
# Newmark steps per period and −0.019 % at 400 (−0.018 % at 8 across H: mesh-independent), so
# −0.023 % with Newmark's O(Δt²) elongation extrapolated away (csph's own dynamic/modal − 1: −0.013 … −0.016 % on 5 … 40). Together 0.028 %:
# 3e-4. (Was 2e-4 — "the finite amplitude's ~0.015 %" with the discretisation's 0.0025 % — which
# the recorded −0.0192 % passed only barely; before that 5e-4, issue 10's target, 8 times the error
# it predicted. A tripled 0.058 % fails.)
TOL_PERIOD_FINE = 3e-4
# Observed order of csph's period error over its ladder (5 … 40), on the MODAL periods (the
# linearised eigenperiod, ``modal_period``) against the FEM's modal limit: the reference and the
# computed value are then the same quantity (the continuum's linear period), by independent
# discretisations. The dynamic periods carry the finite amplitude's shift (−0.013 … −0.016 % in
# csph, −0.023 % in the FEM), which no mesh refinement removes: against the modal limit their
# error tends to that shift, not to zero, and the fitted order to 0 (recorded full run: +0.387,
# +0.011, −0.025, −0.019 % on 5 … 40: order 1.18, a false failure). Against a dynamic limit the
# finest two errors (−0.002, +0.004 %) fall below the shift's own uncertainty (the FEM's −0.023 %
# and csph's −0.013 … −0.016 % differ by 0.008 %): no order can be read from them. The modal errors (recorded: +0.403, +0.025, −0.0097, −0.0067 %)
# give 1.91. At least 1.5: second order in the bulk, the clamped corners' singular term slower (the
# FEM's own modal order is 1.4–1.6); nodal integration converges at ~1.
MIN_ORDER = 1.5
MODAL_RUNGS = 3
"""csph's modal period is computed on its ladder where that has this many rungs (the order gate's
minimum): the full ladder; the quick one (two rungs, no order gate) at MODAL_AT alone."""
N_GATES = {False: 12, True: 7}
"""Gates of the default run (full, ``--quick``): the FEM against thin-plate theory; period (csph's
the modal one), amplitude and energy drift at H/Δx = 10 of csph, hpm and hpm_vc (csph and hpm in
the quick ladder); csph at H/Δx = 40 and its observed order (full). ``verify`` fails where fewer
were evaluated."""
# Method options of this study: classic SPH on the cell lattice (Gray et al.'s arrangement; the
# free surfaces half a spacing outside the outermost particles), the others on the node lattice.
OPTIONS = {"sph": {"lattice": "cell"}}  # classic SPH is the baseline: it is expected to fail, not gated
# The field snapshot of the report: the CSPH series (finest written), deformed particles coloured
# by the von Mises stress, at the frame of largest displacement.
FIELD_VIEW = dict(prefer="plate_csph", scalars="von_mises", label="von Mises stress [Pa]")
# Table I (004): T c0 / L and A / L.
TABLE_I = analytic.TABLE_I


def run(scene: Plate | None = None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None, fields=None, field_runs=None) -> xr.Dataset:
    """``fields`` (a folder, or None): the particle runs write their fields there as ParaView
    series (``field_runs``: the (solver, resolution) pairs that do; None: all); the names of the
    written series are the dataset's ``field_series`` attribute. The FEM writes its mesh for the dynamic rung only."""
    scene = scene or Plate()
    validate(sys.modules[__name__], scene, solvers, resolutions, quick)  # before any work
    solvers = list(solvers or SOLVERS)
    if "analytic" not in solvers:
        solvers.insert(0, "analytic")
    if "fem" not in solvers:
        solvers.insert(1, "fem")
    solvers, ladders = study_ladders(solvers, resolutions, sys.modules[__name__], quick)
    all_res = sorted({r for lad in ladders.values() for r in lad})
    T0 = analytic.plate_period(scene)
    A0 = analytic.plate_amplitude(scene)
    time = np.linspace(0.0, scene.periods * T0, N_TIME)
    shp = (len(solvers), len(all_res))
    period = np.full(shp, np.nan)
    amplitude = np.full(shp, np.nan)
    drift = np.full(shp, np.nan)
    wall = np.full(shp, np.nan)
    npart = np.zeros(shp, dtype=np.int64)
    status = np.full(shp, "not run", dtype=object)
    hist = np.full(shp + (N_TIME,), np.nan)
    # The FEM contributes its modal period on every rung and one dynamic run on the finest.
    dyn = FEM_DYNAMIC[bool(quick)]
    tasks = [Task.make(s, scene, r, **({"dynamic": r == dyn} if s == "fem" else OPTIONS.get(s, {})),
                       **field_options(s, r, fields, field_runs))
             for s, lad in ladders.items() for r in lad]
    # csph's modal periods: at MODAL_AT (its period gate) and, on a ladder long enough for the
    # order gate, on every rung (their reference: the FEM's modal limit)
    modal_tasks = [Task.make("csph", scene, r, drive=Modal(1)) for r in ladders.get("csph", ())
                   if r == MODAL_AT or len(ladders["csph"]) >= MODAL_RUNGS]
    done = run_tasks(tasks + modal_tasks, scheduler, NAME)
    outs = dict(zip(((t.solver, t.resolution) for t in tasks), done[:len(tasks)]))
    modal_outs = {t.resolution: o for t, o in zip(modal_tasks, done[len(tasks):])}
    for i, s in enumerate(solvers):
        if s == "analytic":
            period[i] = T0
            amplitude[i] = A0
            hist[i] = A0 * np.sin(2 * np.pi * time / T0)  # linear thin-plate response
            status[i] = "ok"
            wall[i] = 0.0
            continue
        for r in ladders[s]:
            j = all_res.index(r)
            out = outs[(s, r)]
            # a period that could not be measured says why (issue 38.4: no oscillation)
            status[i, j] = (with_period_notes(out["status"], out, ["period"])
                            if isinstance(out["status"], str) else str(out["status"]))
            period[i, j] = out.get("period", np.nan)
            amplitude[i, j] = out.get("amplitude", np.nan)
            # the FEM's period is the modal one: its cost is the modal solve's
            wall[i, j] = float(out.get("wall_time_modal", np.sum(out.get("wall_time", np.nan))))
            npart[i, j] = int(out.get("n_particles", out.get("n_dof", 0)))
            if "time" in out and "tip_displacement" in out and len(out["time"]) > 1:
                hist[i, j] = np.interp(time, out["time"], out["tip_displacement"], right=np.nan)
            ke, se = out.get("kinetic_energy"), out.get("strain_energy")
            if ke is not None and se is not None and len(ke) > 1:
                e = np.asarray(ke) + np.asarray(se)
                drift[i, j] = (e[-1] - e[0]) / e[0] if e[0] != 0 else np.nan  # no energy: no drift
    ds = xr.Dataset(
        {
            "period": (("solver", "resolution"), period, {"units": "s", "long_name":
                       "period from the tip history (fem: the modal eigenvalue)"}),
            "amplitude": (("solver", "resolution"), amplitude, {"units": "m", "long_name": "tip amplitude"}),
            "tip_displacement": (("solver", "resolution", "time"), hist,
                                 {"units": "m", "long_name": "vertical tip displacement"}),
            "energy_drift": (("solver", "resolution"), drift, {"units": "-", "long_name":
                             "relative change of total energy over the run"}),
            "wall_time": (("solver", "resolution"), wall, {"units": "s"}),
            "n_particles": (("solver", "resolution"), npart, {"units": "-", "long_name":
                            "particles (particle methods) or degrees of freedom (fem)"}),
            "status": (("solver", "resolution"), status.astype(str), {"units": "-"}),
        },
        coords={"solver": solvers, "resolution": ("resolution", np.array(all_res),
                                                  {"units": "-", "long_name": "intervals across H (spacing H/r): r + 1 particles (node lattice), r (cell), r elements"}),
                "time": ("time", time, {"units": "s"})},
    )
    modal = np.full(shp, np.nan)
    modal_status = np.full(shp, "not run", dtype=object)
    for r, o in modal_outs.items():
        i, j = solvers.index("csph"), all_res.index(r)
        modal[i, j] = o.get("period", np.nan)
        modal_status[i, j] = str(o["status"])
    ds["modal_period"] = (("solver", "resolution"), modal, {"units": "s", "long_name":
                          "linearised (modal) period of the discrete plate (csph: at H/dx = 10; "
                          "full: its ladder)"})
    ds["modal_status"] = (("solver", "resolution"), modal_status.astype(str), {"units": "-"})
    ds["period_nondim"] = (ds.period * scene.c0 / scene.L).assign_attrs(units="-", long_name="T c0 / L")
    ds["amplitude_nondim"] = (ds.amplitude / scene.L).assign_attrs(units="-", long_name="A / L")
    ds["fem_modal_converged"] = ((), _extrapolated(ds.period.sel(solver="fem").values, ds.resolution.values),
                                 {"units": "s", "long_name": "FEM modal period extrapolated to zero element size"})
    ds.attrs.update(results.provenance(NAME, scene))
    if fields is not None:
        ds.attrs["field_series"] = field_series(scene, tasks)
    ds.attrs.update(analytic_period=T0, analytic_amplitude=A0, plane="strain",
                    clamp="rigid: particles in the clamp block fixed; FEM clamps X = 0")
    return ds


def _extrapolated(values, res) -> float:
    ok = np.isfinite(values)
    v, r = values[ok], res[ok]
    if len(v) == 0:
        return float("nan")
    if len(v) >= 3 and r[-1] == 2 * r[-2] and r[-2] == 2 * r[-3]:
        q = (v[-1] - v[-2]) / (v[-2] - v[-3]) if v[-2] != v[-3] else 0.0
        if 0 < q < 1:
            return float(v[-1] + (v[-1] - v[-2]) * q / (1 - q))
    return float(v[-1])


def _fem_dynamic_error(ds: xr.Dataset) -> float:
    """The FEM dynamic run's own error (the amplitude gates' reference): its mesh's modal period
    against the converged one, |T_h − T_0|/T_0, at the rung of its dynamic run (the last with an
    amplitude); NaN, which fails the gate, where there is none."""
    fa = ds.amplitude.sel(solver="fem").values
    ok = np.flatnonzero(np.isfinite(fa))
    if not ok.size:
        return float("nan")
    ref = float(ds.fem_modal_converged)
    return abs(float(ds.period.sel(solver="fem").values[ok[-1]]) - ref) / ref


def errors(ds: xr.Dataset) -> list[dict]:
    ref = float(ds.fem_modal_converged)
    rows = []
    for s in ds.solver.values:
        if s == "analytic":
            continue
        for j, r in enumerate(ds.resolution.values):
            v = ds.period.sel(solver=s).values[j]
            if np.isfinite(v):
                rows.append(dict(solver=str(s), resolution=int(r), error=abs(v - ref) / ref,
                                 wall_time=float(ds.wall_time.sel(solver=s).values[j])))
    return rows


def orders(ds: xr.Dataset) -> dict:
    ref = float(ds.fem_modal_converged)
    out = {}
    for s in ds.solver.values:
        if s == "analytic":
            continue
        v = ds.period.sel(solver=s).values
        keep = np.isfinite(v)
        h = 1.0 / ds.resolution.values[keep]
        if s == "fem":
            if keep.sum() >= 4:
                out["fem (successive differences)"] = observed_order(h[1:], np.diff(v[keep]))
            continue
        out[s] = observed_order(h, v[keep] - ref)
    if "modal_period" in ds and "csph" in ds.solver.values:
        v = ds.modal_period.sel(solver="csph").values
        keep = np.isfinite(v)
        out["csph (modal)"] = observed_order(1.0 / ds.resolution.values[keep], v[keep] - ref)
    return out


def table_I(ds: xr.Dataset) -> list[list[str]]:
    rows = [["source", "T c0 / L", "A / L"]]
    for name, (t, a) in TABLE_I.items():
        rows.append([name, f"{t:.2f}", f"{a:.3f}"])
    for s in ds.solver.values:
        pn = ds.period_nondim.sel(solver=s).values
        an = ds.amplitude_nondim.sel(solver=s).values
        ok = np.flatnonzero(np.isfinite(pn))
        if ok.size:
            j = ok[-1]
            res = "" if s == "analytic" else f" (H/dx = {int(ds.resolution.values[j])})"
            a = f"{an[j]:.3f}" if np.isfinite(an[j]) else "-"
            rows.append([f"{s}{res}, this workbench", f"{pn[j]:.2f}", a])
    return rows


def report_tables(ds: xr.Dataset) -> list[dict]:
    return [dict(title="Table I of 004, reproduced (dimensionless period and amplitude):",
                 table=table_I(ds))]


FEM_REFERENCE = ("the FEM's modal period extrapolated to zero element size: quadratic elements of "
                 "scikit-fem (fem_reference), another discretisation of the same 2-D continuum that "
                 "shares no code with the particle methods but the scene and the SVK law (itself "
                 "checked against its closed-form energy, tests/test_materials.py)")


def modal_order_gate(ds: xr.Dataset, ref: float) -> Gate:
    """csph's observed order of the modal period's error against the FEM's modal limit ``ref``
    over its ladder (:data:`MIN_ORDER`; why modal: the comment at it). A modal run that is missing
    or gave NaN makes the order NaN, which fails."""
    name = "plate csph: observed order of the (modal) period error"
    why = "second order in the bulk; nodal integration converges at ~1"
    if "modal_period" not in ds:
        return Gate.missing(name, "no modal periods in the dataset", MIN_ORDER, why, FEM_REFERENCE)
    run = planned(ds.status.sel(solver="csph").values)
    v = ds.modal_period.sel(solver="csph").values[run]
    order = (observed_order(1.0 / ds.resolution.values[run], (v - ref) / ref)
             if np.all(np.isfinite(v)) else np.nan)
    return Gate.at_least(name, order, MIN_ORDER, why, FEM_REFERENCE)


def modal_period_gate(ds: xr.Dataset, ref: float) -> Gate:
    """csph's modal period at H/Δx = MODAL_AT against the FEM's modal limit ``ref``
    (:data:`TOL_PERIOD_MODAL`: like with like, no finite-amplitude term); a modal run that is
    missing or gave NaN fails."""
    name = f"plate csph at H/dx = {MODAL_AT}: modal period vs FEM modal period"
    why = ("second order: the bulk error at H/dx = 10 (0.04 %, free-free beam) + the corners' "
           "0.015 % (the cantilever's clamp) + the reference's 0.005 %")
    if "modal_period" not in ds:
        return Gate.missing(name, "no modal periods in the dataset", TOL_PERIOD_MODAL, why,
                            FEM_REFERENCE)
    v = float(ds.modal_period.sel(solver="csph", resolution=MODAL_AT))
    return Gate.at_most(name, abs(v - ref) / ref, TOL_PERIOD_MODAL, why, FEM_REFERENCE)


def gates(ds: xr.Dataset) -> list[Gate]:
    """The plate's gates (:data:`N_GATES`): every gate of a run the study meant to make is
    evaluated; a run that is missing or gave NaN fails its gate (never removes it)."""
    g = []
    fem = ds.period.sel(solver="fem").values
    T0 = ds.attrs["analytic_period"]
    name = "plate fem: modal period vs thin-plate theory"
    why = ("shear and rotary inertia of the 2-D plate: +0.46 % expected, first-order correction "
           "0.73 % an upper estimate")
    thin = "thin-plate theory (004 eq. 15), a closed form"
    if np.isfinite(fem).any():
        finest = fem[np.flatnonzero(np.isfinite(fem))[-1]]
        g.append(Gate.at_most(name, abs(finest - T0) / T0, TOL_FEM_THIN_PLATE, why, thin))
    else:
        g.append(Gate.missing(name, "no FEM modal period", TOL_FEM_THIN_PLATE, why, thin))
    ref = float(ds.fem_modal_converged)
    fa = ds.amplitude.sel(solver="fem").values
    aref = fa[np.flatnonzero(np.isfinite(fa))[-1]] if np.isfinite(fa).any() else np.nan
    amp_ref = ("the FEM's dynamic run (Newmark on quadratic elements, fem_reference): the same "
               "finite-amplitude response computed by another discretisation and time integrator")
    for s in GATED:
        if s not in ds.solver.values or 10 not in ds.resolution.values:
            continue  # not asked for (a solver or ladder of the user's): not a gate of this run
        if not planned(ds.status.sel(solver=s, resolution=10)):
            continue
        if s == "csph":
            g.append(modal_period_gate(ds, ref))
        else:
            v = float(ds.period.sel(solver=s, resolution=10))
            tol, why = ((TOL_PERIOD_CONSISTENT, "second order: the bulk error at H/dx = 10 (0.04 "
                         "%, free-free beam) + the corners' 0.015 % + the finite amplitude's "
                         "0.015 % + the reference's 0.005 %") if s in CONSISTENT
                        else (TOL_PERIOD, "issues 4/5: 3 % (004's model: 2.7 %)"))
            g.append(Gate.at_most(f"plate {s} at H/dx = 10: period vs FEM modal period",
                                  abs(v - ref) / ref, tol, why, FEM_REFERENCE))
        a = float(ds.amplitude.sel(solver=s, resolution=10))
        own = _fem_dynamic_error(ds)
        tol, why = ((TOL_AMPLITUDE_CONSISTENT, "A = V/omega: the period's error 0.045 % + the "
                     "peak's sampling 1e-4")
                    if s in CONSISTENT else (TOL_AMPLITUDE, "A = V/omega: the period's 3 %"))
        g.append(Gate.at_most(f"plate {s} at H/dx = 10: amplitude vs FEM dynamic amplitude",
                              abs(a - aref) / aref, tol + own,
                              f"{why}, + the FEM dynamic run's own error {own:.2%}", amp_ref))
        d = float(ds.energy_drift.sel(solver=s, resolution=10))
        g.append(Gate.at_most(f"plate {s} at H/dx = 10: |energy drift| over the run, no damping",
                              abs(d), TOL_DRIFT, "symplectic scheme: bounded energy error "
                              "O((omega dt)^2), no secular growth",
                              "the run's own initial energy (conservation: no damping, no external "
                              "work)", defect=DRIFT_DEFECT))
    if "csph" in ds.solver.values:
        v = ds.period.sel(solver="csph").values
        res = ds.resolution.values
        run = planned(ds.status.sel(solver="csph").values)
        if 40 in res and run[list(res).index(40)]:
            g.append(Gate.at_most("plate csph at H/dx = 40: period vs FEM modal period",
                                  abs(v[list(res).index(40)] - ref) / ref, TOL_PERIOD_FINE,
                                  "second order from H/dx = 10 (0.005 %) + the finite "
                                  "amplitude's shift (FEM dynamic/modal, dt -> 0: 0.023 %)",
                                  FEM_REFERENCE))
    if "csph" in ds.solver.values and planned(ds.status.sel(solver="csph").values).sum() >= MODAL_RUNGS:
        g.append(modal_order_gate(ds, ref))
    return g


def plot(ds: xr.Dataset, outdir) -> list:
    from . import figures as plots

    return [plots.plate(ds, outdir)]
