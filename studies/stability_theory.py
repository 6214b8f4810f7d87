"""Stability theory against observation (issue 13, items 4–5): variables that the stability study
(:mod:`studies.stability`) merges into ``stability.nc``; :func:`theory_dataset` makes them.

1. **Swegle's tensile instability, predicted per particle, against the clumping observed** —
   classic SPH (``sph``, Eulerian cubic spline, h = 1.3Δx, the stability study's options) on the
   ``ring`` and ``slab`` scenes. At every record (100 per run) the indicator λ_i of
   :mod:`sph.tensile_instability` (λ > 0: predicted unstable; the 1-D condition σ·W''(r) > 0 of
   Swegle, Hicks & Attaway 1995, taken along each principal stress direction) and the particle
   disorder η_i of :mod:`sph.monitor` are computed on the monitored particles. The clumping
   *starts* at the first record where some η_i exceeds ``ETA_ONSET`` (0.15, the threshold of the
   study's disorder criterion, there on η₉₅); the particles above it then are the *first
   disordered*. Compared: the fraction of the first disordered that were predicted unstable one
   record earlier (``swegle_agreement``) against the fraction of all monitored particles predicted
   unstable then (``swegle_base_rate``: what a prediction that says nothing about place would
   score), the time of the first prediction against the onset, and the predicted growth time
   1/√λ (median over the first disordered) against the time from the first prediction to the
   onset. The total-Lagrangian counterpart (:func:`sph.tensile_instability.lagrangian_rates`) is
   evaluated for ``csph`` at the end of its slab run (``tl_rate_max``: ≤ 0, no prediction).
2. **Energy in the zero-energy modes of the colliding rings** (``rings``; csph and hpm, with and
   without their stabilisation, and hpm with the per-bond normalisation ``kondo``): the kinetic
   energy of the non-affine part of the motion, K_hg (:class:`sph.hourglass.NonAffineEnergy`; why
   this measure: a zero-energy mode is a motion the method's stored energy does not see, so its
   energy is not in the method's strain energy; it is the kinetic energy of a motion that no local
   affine field represents, split off by an exact local orthogonal projection, the same for every
   method), over the total energy E₀ (the rings' initial kinetic energy) and over the local
   kinetic energy (a share in [0, 1]).
3. **Long-run energy drift of the symplectic schemes** (hpm and csph, the clamped plate, 100 plate
   periods in the full study, 5 in the quick one): the least-squares slope of the relative energy
   error (E(t) − E₀)/E₀ against t/T (per period) and the peak error. Velocity Verlet is symplectic:
   its energy error is O(Δt²) and oscillates (a modified Hamiltonian is conserved) with no secular
   trend, so the slope times the number of periods must stay below the oscillation's own size.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from workbench.scenes import Plate, Ring, Rings, Slab

ETA_ONSET = 0.15
TOL_SECULAR = 0.1
SECULAR_DEFECT = 1.0
"""The drift gate (an exactness gate, tests/test_gates.py): a symplectic scheme's energy error
oscillates with no secular trend, so the least-squares slope times the run's periods is a small
share of the error's peak; a non-symplectic second-order scheme drifts by about its peak per
period, |slope x periods| / peak >= 1 over any run of a period or more (SECULAR_DEFECT): a tenth
of that is the tolerance, a third of it fails."""
"""Per-particle disorder η_i marking a particle as disordered (the study's disorder threshold)."""
# (scene, resolution, end time) full and quick: the resolutions and end times of the stability
# study's SETUP (studies/stability.py), repeated here so that this module does not depend on its
# layout.
SWEGLE_SETUP = {"ring": ((Ring(), 8, 0.05), (Ring(), 6, 0.01)),
                "slab": ((Slab(), 10, 0.15), (Slab(), 6, 0.05))}
SPH_OPTIONS = {"stress": "hyperelastic"}
CSPH_OPTIONS = {"hourglass": 0.1, "h_ratio": 1.3}
RINGS_SETUP = ((Rings(), 5, 0.1), (Rings(), 4, 0.03))
# variant -> (method, options)
RINGS_VARIANTS = {
    "csph": ("csph", {"h_ratio": 1.3}),
    "csph_hourglass": ("csph", CSPH_OPTIONS),
    "hpm": ("hpm", {}),
    "hpm_stabilised": ("hpm", {"stabilisation": 1.0}),
    "hpm_kondo": ("hpm", {"stabilisation": 1.0, "stabilisation_form": "kondo"}),
}
DRIFT_SETUP = ((10, 100.0), (5, 5.0))  # (resolution, periods): full, quick
DRIFT_METHODS = ("hpm", "csph")


# ------------------------------------------------------------------------------------------------
# One run with a look at the state at every record
# ------------------------------------------------------------------------------------------------

def run_with_records(method: str, scene, resolution: int, on_record, **options) -> dict:
    """Run ``method`` on ``scene`` (an explicit drive) by :func:`sph.driver.solve`, calling
    ``on_record(body, run, t)`` at t = 0 and at every record (about ``n_out`` times) until the
    run ends or the driver's criterion stops it. Returns the driver's output."""
    from sph import driver
    from workbench.scenes import model as M

    model, _ = driver.model_at(scene, resolution)
    if not isinstance(model.drive, M.Explicit):
        raise ValueError(f"scene: {scene.name!r} has no explicit drive; allowed: explicit scenes")
    return driver.solve(method, scene, resolution, on_record=on_record, **options)


# ------------------------------------------------------------------------------------------------
# 1. Swegle against the clumping
# ------------------------------------------------------------------------------------------------

def _monitored(run) -> np.ndarray:
    ps = run.ps
    mask = ~run.fixed.any(axis=1)
    ds = run.model.drive.disorder_set
    if ds is not None:
        sel = np.zeros(ps.n, bool)
        sel[ps.sets[ds]] = True
        mask &= sel
    return mask


def swegle_history(scene, resolution: int, **options) -> dict:
    """Classic SPH on ``scene`` with the per-record prediction and observation of the module
    docstring: times (n_rec,) s; lam (n_rec, N) 1/s² (λ_i); eta (n_rec, N) (η_i); mask (N,) the
    monitored particles; status."""
    from sph.monitor import Disorder, _disorder
    from sph.tensile_instability import classic_rates

    times, lams, etas = [], [], []
    state = {}

    def on_record(body, run, t):
        if "dis" not in state:
            state["dis"] = Disorder(run.ps.X, run.ps.dx)
            state["mask"] = _monitored(run)
        lam, _ = classic_rates(body)
        times.append(t)
        lams.append(lam)
        etas.append(_disorder(np.ascontiguousarray(body.x), *state["dis"].geo))

    out = run_with_records("sph", scene, resolution, on_record, **{**SPH_OPTIONS, **options})
    return dict(times=np.array(times), lam=np.array(lams), eta=np.array(etas),
                mask=state["mask"], status=out["status"])


def swegle_comparison(hist: dict, eta_onset: float = ETA_ONSET) -> dict:
    """Numbers of the module docstring from :func:`swegle_history`: ``agreement``,
    ``base_rate``, ``n_first`` (first disordered particles), ``t_onset`` and ``t_predicted`` (s;
    NaN if never), ``growth_time`` (s, 1/√λ median over the first disordered one record before
    the onset), ``predicted_fraction_max`` (largest fraction of monitored particles predicted
    unstable before the onset)."""
    t, lam, eta, mask = hist["times"], hist["lam"][:, hist["mask"]], hist["eta"][:, hist["mask"]], hist["mask"]
    pred = lam > 0.0
    frac = pred.mean(axis=1)
    dis = eta > eta_onset
    onset = np.flatnonzero(dis.any(axis=1))
    out = dict(agreement=math.nan, base_rate=math.nan, n_first=0, t_onset=math.nan,
               growth_time=math.nan)
    any_pred = np.flatnonzero(pred.any(axis=1))
    out["t_predicted"] = float(t[any_pred[0]]) if any_pred.size else math.nan
    k = int(onset[0]) if onset.size else len(t)
    out["predicted_fraction_max"] = float(frac[:max(k, 1)].max())
    if not onset.size or k == 0:
        return out
    first = dis[k]
    before = pred[k - 1]
    out.update(agreement=float(np.mean(before[first])), base_rate=float(np.mean(before)),
               n_first=int(first.sum()), t_onset=float(t[k]))
    lam_first = lam[k - 1][first]
    if np.any(lam_first > 0):
        out["growth_time"] = float(1.0 / np.sqrt(np.median(lam_first[lam_first > 0])))
    return out


def lagrangian_rate_max(scene, resolution: int, **options) -> dict:
    """The total-Lagrangian stress-term rates (:func:`sph.tensile_instability.lagrangian_rates`)
    of csph at the end of its run on ``scene``, over the monitored particles: ``tension`` the
    largest over the particles whose S is positive semi-definite (≤ 0: no tensile instability
    predicted), ``all`` the largest over all (> 0 only where S has a compressive principal value),
    ``positive_fraction`` the fraction with a positive rate, 1/s²; NaN if the run did not finish."""
    from sph import total_lagrangian as tl
    from sph.tensile_instability import lagrangian_rates
    from workbench.materials import evaluate

    state = {}

    def on_record(body, run, t):
        state.update(body=body, run=run)

    out = run_with_records("csph", scene, resolution, on_record, **{**CSPH_OPTIONS, **options})
    if out["status"] != "ok":
        return dict(tension=math.nan, all=math.nan, positive_fraction=math.nan)
    body, run = state["body"], state["run"]
    d = body.disc
    F = tl.deformation_gradients(body.x, d.indptr, d.indices, d.G)
    P = evaluate(body.tl.table, F, body.tl.history, stress="P", mat_id=body.tl.mat_id)["stress"]
    S = np.linalg.solve(F, P)
    lam = lagrangian_rates(d, S, run.ps.dx)
    sel = _monitored(run)
    Sd = S[:, :d.dim, :d.dim]
    tension = np.linalg.eigvalsh(0.5 * (Sd + np.swapaxes(Sd, 1, 2)))[:, 0] >= 0.0
    lt = lam[sel & tension]
    return dict(tension=float(lt.max()) if lt.size else math.nan, all=float(lam[sel].max()),
                positive_fraction=float(np.mean(lam[sel] > 0)))


# ------------------------------------------------------------------------------------------------
# 2. Energy in the zero-energy modes of the colliding rings
# ------------------------------------------------------------------------------------------------

def rings_hourglass(method: str, scene, resolution: int, **options) -> dict:
    """K_hg and K_loc (:class:`sph.hourglass.NonAffineEnergy`) of ``method`` on the colliding
    rings at every record: times (s), hg, loc, total (J/m: kinetic + stored + contact energy),
    status."""
    from sph.contact import contact_forces
    from sph.hourglass import NonAffineEnergy

    rec = dict(times=[], hg=[], loc=[], total=[])
    state = {}

    def on_record(body, run, t):
        if "na" not in state:
            ps = run.ps
            state["na"] = NonAffineEnergy(ps.X, ps.dx, body=ps.body)
            c = run._contact_setup()
            state["contact"] = c
        hg, loc = state["na"](body.x, body.v, body.m)
        ke, se = body.energies()
        if state["contact"] is not None:
            se += contact_forces(body.x, run.ps.body, *state["contact"])[1]
        for n, v in (("times", t), ("hg", hg), ("loc", loc), ("total", ke + se)):
            rec[n].append(v)

    out = run_with_records(method, scene, resolution, on_record, **options)
    res = {k: np.array(v) for k, v in rec.items()}
    res["status"] = out["status"]
    return res


# ------------------------------------------------------------------------------------------------
# 3. Long-run energy drift of the symplectic schemes
# ------------------------------------------------------------------------------------------------

def drift_slope(time, energy, period: float) -> dict:
    """Least-squares line through the relative energy error e(t) = (E(t) − E(0))/E(0) against
    t/period: ``slope`` (per period), ``secular`` (slope × the run's length in periods: the trend's
    share of the run), ``peak`` (max |e|), ``oscillation`` (max |e − line|)."""
    t = np.asarray(time, float) / period
    E = np.asarray(energy, float)
    e = (E - E[0]) / abs(E[0])
    A = np.c_[t, np.ones_like(t)]
    (slope, icpt), *_ = np.linalg.lstsq(A, e, rcond=None)
    return dict(slope=float(slope), secular=float(slope * (t[-1] - t[0])),
                peak=float(np.max(np.abs(e))), oscillation=float(np.max(np.abs(e - A @ (slope, icpt)))))


def plate_drift(method: str, resolution: int, periods: float, **options) -> dict:
    """:func:`drift_slope` of ``method`` on the clamped plate over ``periods`` thin-plate periods
    (the energy balance of :func:`sph.driver.solve`), with the run's status."""
    from sph import driver
    from workbench import analytic

    sc = Plate(periods=periods)
    out = driver.solve(method, sc, resolution, **options)
    T = analytic.plate_period(sc)
    res = drift_slope(out["time"], out["energy_history"], T)
    res["status"] = out["status"]
    return res


# ------------------------------------------------------------------------------------------------
# The dataset
# ------------------------------------------------------------------------------------------------

def theory_dataset(quick: bool = False) -> xr.Dataset:
    """The variables of items 4–5 of issue 13 (module docstring), for merging into stability.nc.
    Dimensions: ``swegle_scene`` (ring, slab), ``rings_variant`` (RINGS_VARIANTS), ``rings_time``,
    ``drift_solver`` (hpm, csph); ``quick`` the small resolutions and short runs."""
    q = 1 if quick else 0
    sw_scenes = list(SWEGLE_SETUP)
    sw = {k: [] for k in ("agreement", "base_rate", "n_first", "t_onset", "t_predicted",
                          "growth_time", "predicted_fraction_max")}
    sw_status = []
    for name in sw_scenes:
        scene, res, t_end = SWEGLE_SETUP[name][q]
        hist = swegle_history(dataclasses.replace(scene, t_end=t_end), res)
        c = swegle_comparison(hist)
        for k in sw:
            sw[k].append(c[k])
        sw_status.append(hist["status"])
    scene, res, t_end = SWEGLE_SETUP["slab"][q]
    tl_max = lagrangian_rate_max(dataclasses.replace(scene, t_end=t_end), res)

    rscene, rres, rt = RINGS_SETUP[q]
    rscene = dataclasses.replace(rscene, t_end=rt)
    variants = list(RINGS_VARIANTS)
    runs = [rings_hourglass(m, rscene, rres, **o) for m, o in RINGS_VARIANTS.values()]
    t_ref = runs[0]["times"]
    hg_e0 = np.full((len(variants), len(t_ref)), np.nan)
    hg_share = np.full_like(hg_e0, np.nan)
    for i, r in enumerate(runs):
        e0 = r["total"][0]
        n = min(len(r["times"]), len(t_ref))
        hg_e0[i, :n] = r["hg"][:n] / e0
        hg_share[i, :n] = r["hg"][:n] / np.maximum(r["loc"][:n], 1e-300)
    drift_res, periods = DRIFT_SETUP[q]
    drifts = [plate_drift(m, drift_res, periods) for m in DRIFT_METHODS]

    def v(dims, data, units, long_name, **kw):
        return (dims, data, dict(units=units, long_name=long_name, **kw))

    ds = xr.Dataset(
        {
            "swegle_agreement": v("swegle_scene", np.array(sw["agreement"]), "-",
                                  "sph: fraction of the first disordered particles (eta_i > "
                                  f"{ETA_ONSET}) predicted unstable (Swegle lambda_i > 0) one record before"),
            "swegle_base_rate": v("swegle_scene", np.array(sw["base_rate"]), "-",
                                  "sph: fraction of all monitored particles predicted unstable at that record"),
            "swegle_n_first": v("swegle_scene", np.array(sw["n_first"]), "-",
                                "sph: number of first disordered particles"),
            "swegle_t_onset": v("swegle_scene", np.array(sw["t_onset"]), "s",
                                f"sph: time of the first record with some eta_i > {ETA_ONSET} (NaN: none)"),
            "swegle_t_predicted": v("swegle_scene", np.array(sw["t_predicted"]), "s",
                                    "sph: time of the first record with some particle predicted unstable"),
            "swegle_growth_time": v("swegle_scene", np.array(sw["growth_time"]), "s",
                                    "sph: predicted e-folding time 1/sqrt(lambda), median over the "
                                    "first disordered particles one record before the onset"),
            "swegle_predicted_fraction_max": v("swegle_scene", np.array(sw["predicted_fraction_max"]), "-",
                                               "sph: largest fraction of monitored particles predicted "
                                               "unstable before the onset"),
            "swegle_status": v("swegle_scene", np.array(sw_status, dtype=str), "-", "status of the sph run"),
            "tl_rate_max_tension": v((), tl_max["tension"], "1/s^2",
                                     "csph (total Lagrangian) slab: largest stress-term rate at the end "
                                     "over the particles in tension (S >= 0; <= 0: no tensile instability)"),
            "tl_rate_max": v((), tl_max["all"], "1/s^2",
                             "csph slab: largest stress-term rate over all monitored particles "
                             "(> 0 only where S has a compressive principal value)"),
            "tl_positive_fraction": v((), tl_max["positive_fraction"], "-",
                                      "csph slab: fraction of monitored particles with a positive rate"),
            "hourglass_energy_fraction": v(("rings_variant", "rings_time"), hg_e0, "-",
                                           "colliding rings: kinetic energy of the non-affine motion "
                                           "K_hg over the total energy E0"),
            "hourglass_kinetic_share": v(("rings_variant", "rings_time"), hg_share, "-",
                                         "colliding rings: K_hg over the local kinetic energy K_loc (in [0, 1])"),
            "hourglass_energy_fraction_peak": v("rings_variant", np.nanmax(hg_e0, axis=1), "-",
                                                "colliding rings: largest K_hg/E0 of the run"),
            "rings_status": v("rings_variant", np.array([r["status"] for r in runs], dtype=str), "-",
                              "status of the rings run"),
            "rings_energy_change": v("rings_variant",
                                     np.array([abs(r["total"][-1] - r["total"][0]) / r["total"][0]
                                               for r in runs]), "-",
                                     "colliding rings: |E(t_end) - E0|/E0 (conservative forces, "
                                     "symplectic loop)"),
            "drift_slope": v("drift_solver", np.array([d["slope"] for d in drifts]), "1/period",
                             "plate: least-squares slope of (E - E0)/E0 against t/T"),
            "drift_secular": v("drift_solver", np.array([d["secular"] for d in drifts]), "-",
                               "plate: slope times the run length in periods"),
            "drift_peak": v("drift_solver", np.array([d["peak"] for d in drifts]), "-",
                            "plate: largest |E - E0|/E0"),
            "drift_oscillation": v("drift_solver", np.array([d["oscillation"] for d in drifts]), "-",
                                   "plate: largest deviation of (E - E0)/E0 from its line"),
        },
        coords={"swegle_scene": sw_scenes, "rings_variant": variants,
                "rings_time": ("rings_time", t_ref, {"units": "s"}),
                "drift_solver": list(DRIFT_METHODS)},
    )
    ds.attrs.update(
        theory_swegle="Swegle, Hicks & Attaway (1995) per particle for classic SPH (sph.tensile_instability); "
                      f"onset: first record with eta_i > {ETA_ONSET} (sph.monitor)",
        theory_hourglass_energy="K_hg: kinetic energy of the part of the velocity field not represented by "
                                "the local affine fit (WLS over the reference neighbours, r_e = 2.1 dx, "
                                "exact Pythagorean split; sph.hourglass.NonAffineEnergy)",
        theory_rings_variants=str({k: dict(method=m, **o) for k, (m, o) in RINGS_VARIANTS.items()}),
        theory_drift=f"plate, resolution {drift_res}, {periods:g} periods, options of the plate runs (none)",
        theory_resolutions=str({"swegle": {k: v[q][1] for k, v in SWEGLE_SETUP.items()},
                                "rings": rres}),
    )
    return ds


def dataset(stability: xr.Dataset | None = None, quick: bool = False,
            scheduler: str | None = None) -> xr.Dataset:
    """The variables of :func:`theory_dataset` for :func:`studies.stability.run` to merge into
    stability.nc (``stability``, the map's dataset, and ``scheduler`` are accepted for the
    study's hook; these runs are serial: each needs the state at every record)."""
    return theory_dataset(quick)


def theory_tables(ds: xr.Dataset) -> list[dict]:
    """The report's tables of items 4–5 (where ``ds`` carries them): Swegle's prediction against
    the observed clumping, the hourglass-energy fraction of the colliding rings, the long-run
    energy drift."""
    if "swegle_agreement" not in ds:
        return []
    sw = [["scene", "agreement", "base rate", "first disordered", "predicted from (s)",
           "onset (s)", "predicted e-folding (s)"]]
    for sc in ds.swegle_scene.values:
        p = ds.sel(swegle_scene=sc)
        sw.append([str(sc), f"{float(p.swegle_agreement):.2f}", f"{float(p.swegle_base_rate):.2f}",
                   f"{int(p.swegle_n_first)}", f"{float(p.swegle_t_predicted):.3g}",
                   f"{float(p.swegle_t_onset):.3g}", f"{float(p.swegle_growth_time):.2g}"])
    hg = [["variant", "peak K_hg/E0", "|E(t_end) - E0|/E0", "status"]]
    for v in ds.rings_variant.values:
        p = ds.sel(rings_variant=v)
        hg.append([str(v), f"{float(p.hourglass_energy_fraction_peak):.3%}",
                   f"{float(p.rings_energy_change):.1e}" if "rings_energy_change" in ds else "",
                   str(p.rings_status.values)])
    dr = [["solver", "slope (1/period)", "slope x periods", "peak |E - E0|/E0"]]
    for m in ds.drift_solver.values:
        p = ds.sel(drift_solver=m)
        dr.append([str(m), f"{float(p.drift_slope):.2e}", f"{float(p.drift_secular):.2e}",
                   f"{float(p.drift_peak):.2e}"])
    return [
        dict(title="Swegle's tensile-instability condition for sph (Eulerian cubic spline) against the "
                   "observed clumping: agreement = share of the first disordered particles predicted "
                   "unstable one record before (base rate: share of all particles predicted); csph "
                   f"(total Lagrangian) on the slab: largest stress-term rate over particles in tension "
                   f"{float(ds.tl_rate_max_tension):.2g} 1/s^2 (<= 0: none predicted)", table=sw),
        dict(title="Colliding rings: kinetic energy of the non-affine (zero-energy-mode) motion K_hg "
                   "against the initial energy, per Lagrangian method and stabilisation "
                   "(" + ds.attrs.get("theory_hourglass_energy", "") + ")", table=hg),
        dict(title="Energy drift of the symplectic schemes on the plate (" + ds.attrs.get("theory_drift", "")
                   + "): least-squares slope of the energy error", table=dr),
    ]


def theory_gates(ds: xr.Dataset) -> list:
    """Gates of the theory (each reason its own): Swegle's prediction locates the clumping at least
    as well as chance (agreement >= base rate) and precedes it; no tensile instability predicted for
    the total-Lagrangian kernel in tension; no secular energy trend of the symplectic schemes (the
    least-squares slope times the run's periods under a tenth of the error's own peak: a
    non-symplectic second-order scheme drifts by about its peak per period)."""
    from .common import Gate

    if "swegle_agreement" not in ds:
        return []
    g = []
    for sc in ds.swegle_scene.values:
        p = ds.sel(swegle_scene=sc)
        agr, base = float(p.swegle_agreement), float(p.swegle_base_rate)
        g.append(Gate.expect(f"stability theory: Swegle agreement on the {sc} (sph), against its "
                             "base rate", "at least chance" if agr >= base else
                             f"below chance ({agr:.3g} < {base:.3g})", "at least chance",
                             "a prediction that locates the instability scores at least the share "
                             "of particles it flags",
                             "the clumping observed in the run (per-particle disorder), not the "
                             "criterion's own output"))
    rate = float(ds.tl_rate_max_tension)
    g.append(Gate.expect("stability theory: csph stress-term rate in tension on the slab",
                         "none predicted" if rate <= 0 else f"predicted (rate {rate:.3g} 1/s^2)",
                         "none predicted", "total-Lagrangian kernel: the geometric stiffness of a "
                         "tensile stress is positive", "the sign Swegle's criterion gives a "
                         "reference-configuration kernel, a closed-form property"))
    for m in ds.drift_solver.values:
        p = ds.sel(drift_solver=m)
        g.append(Gate.at_most(f"stability theory: {m} plate |slope x periods| / peak energy error",
                              abs(float(p.drift_secular)) / max(float(p.drift_peak), 1e-300),
                              TOL_SECULAR, "symplectic scheme: bounded oscillating energy error, "
                              "no secular trend", "the run's own energy history (a conservation "
                              "law)", defect=SECULAR_DEFECT))
    return g
