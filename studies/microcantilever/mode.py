"""The fracture mode predicted (issue 36, item 2): ``workbench run microcantilever_mode``.

The micro-cantilever study puts the mode in by hand — ε_L = 0.002 where the crack is meant to run
and 1.0 elsewhere. Here the two limits compete: the grain boundaries keep the scene's
``eps_L_low`` (0.002) and the grains get ρ times it,

    ρ = ε_L(grains) / ε_L(grain boundaries),

swept over :data:`RATIOS` (1 to 10, and 000's own contrast, 500, which is the study's ``inter``
case), each over :data:`SEEDS` Voronoi realisations (the scene's ``seed``), at two resolutions.
The load goes in through a pad that does not fail (:class:`.padded.PaddedCantilever`, 1 µm
under and beyond the rigid patch: without it the patch's singular ends tear it off the beam
before any crack crosses it). What is reported is the share of the failed particles that lie in
a grain boundary (:func:`gb_share`; all failed particles, the crushed bottom corner at the root
among them) when the crack has cut the loading patch off from the held faces — the run stops
there (the drive's ``separate`` with ``t_after`` = :data:`T_AFTER`: the first record past the cut;
what fails afterwards, as the broken-off piece swings, is not the crack's) — its mean and scatter
over the seeds against ρ, and the ratio at which the mode changes: where the mean share crosses
50 % (:func:`transition`, linear in log ρ between the bracketing ratios), with its uncertainty from
a bootstrap over the seeds (:func:`bootstrap_transition`).

Why 2-D suffices (plane strain): what decides the mode is which material reaches its limit strain
first along the path of the highest bending strain — the competition of the two ε_L with the
strain field of a bent beam and the positions of the boundaries along it, both of which the
plane-strain section has; the 3-D beam's strain varies little across its width B (its grains are
Voronoi cells of seeds jittered across B too, so a boundary is slanted across the width, which
moves where it meets the top face by a fraction of the grain size, as another seed would). A 3-D
run at H/Δx = 5 (1 776 particles, one particle across a boundary, 63–98 s on one thread) costs
what two or three 2-D runs at H/Δx = 10 (671 particles, two across a boundary) do: in 2-D the
refinement and five seeds at eight ratios fit the study's budget, in 3-D one resolution would not.

Its dataset has dims (resolution, ratio, seed) — :func:`dataset` — and its gates
(:func:`gates`): the transition converged (it moves by less than one step of the sweep between the
two resolutions), and per resolution: the share monotone in ρ within the seeds' scatter, the two
limits where the mode is known from the strength contrast (ρ = 1: no contrast, intra; ρ = 500:
000's inter-granular case, at least 80 % in the boundaries), and a crossing inside the sweep.
``--quick``: :data:`QUICK_SEEDS`, :data:`QUICK_RATIOS`, H/Δx = 5 (the coarsest that resolves a
boundary): the per-resolution gates only.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from ..common import Gate, check_resolutions
from ..sweep import Task, run_tasks
from .ladders import quick_scene  # noqa: F401 - the protocol's: the 2-D variant
from .padded import PaddedCantilever
from .scene import MicroCantilever

NAME = "microcantilever_mode"
SCENE = PaddedCantilever
SOLVERS = ("csph",)
RATIOS = (1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 10.0, 500.0)
"""ρ = ε_L(grains)/ε_L(grain boundaries): 1 to 10 in steps of a factor 4/3 to 5/3
(:func:`sweep_step`; the transition, measured, lies between 4 and 6 at both resolutions) and
000's 500 (1.0 against 0.002). Eight ratios: 40 runs per resolution, the full sweep 18.6 minutes
on 2 shared cores (``notes.md``)."""
SEEDS = (1, 2, 3, 4, 5)
"""Voronoi realisations (the scene's ``seed``; 3 is the micro-cantilever study's)."""
RESOLUTIONS = {"csph": (5, 10)}
"""Particles across H: 5, the coarsest that resolves a 1 µm boundary, and one refinement."""
QUICK_RATIOS = (1.0, 6.0, 500.0)
QUICK_SEEDS = (1, 2)
QUICK_RESOLUTIONS = {"csph": (5,)}
"""``--quick``: the two limits and a ratio past the transition (seeds 1 and 2 are inter-granular
at 6), two seeds, H/Δx = 5: six runs, 16 s from a fresh cache."""
T_AFTER = 1e-12
"""s run on past the cut: the first record after it (a record every t_end/400 = 20 ns)."""
LEVEL = 0.5
"""The mode changes where half of the failed particles lie in the grain boundaries."""
N_BOOT = 2000
"""Bootstrap resamples of the seeds (seeded: the same dataset gives the same interval)."""
MIN_SHARE_INTER = 0.8
"""000's inter-granular classification, the issue's: at least 80 % of the failed particles in the
grain boundaries (the micro-cantilever study's gate 3, ``.gates.MIN_SHARE``)."""
N_GATES = {False: 9, True: 4}
"""Gates of the default run (two resolutions: four each and the transition's convergence) and of
``--quick`` (one resolution: four)."""
ERROR_LABEL = "share of the failed particles in the grain boundaries [-]"


def mode_scene(scene: MicroCantilever, ratio: float, seed: int) -> MicroCantilever:
    """The 2-D scene of one run: the grain boundaries at the scene's ``eps_L_low`` (case
    ``inter``), the grains at ``ratio`` times it, Voronoi ``seed``, stopped at the cut
    (:data:`T_AFTER`), no crack band (ε_L as given; both materials alike at each spacing)."""
    return dataclasses.replace(scene, dim=2, case="inter", eps_L_high=ratio * scene.eps_L_low,
                               seed=int(seed), t_after=T_AFTER, band=0.0, failure="compression",
                               name=f"{NAME}_rho{ratio:g}_seed{int(seed)}")


def run(scene: MicroCantilever | None = None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None, ratios=None, seeds=None) -> xr.Dataset:
    """Every (resolution, ratio, seed) run through the sweep (run cache, dask, resume); the 2-D
    variant of ``scene`` whatever its ``dim`` (module doc: why 2-D suffices), its ``case``,
    ``eps_L_high``, ``seed``, ``t_after``, ``band`` and ``failure`` set per run
    (:func:`mode_scene`); ``ratios`` and ``seeds`` replace :data:`RATIOS` and :data:`SEEDS`."""
    scene = quick_scene(scene or SCENE())
    for s in solvers or SOLVERS:
        if s not in SOLVERS:
            raise ValueError(f"solver: {s!r} is not supported by {NAME}; allowed: {', '.join(SOLVERS)}")
    if isinstance(resolutions, dict):
        resolutions = resolutions.get("csph")
    res = check_resolutions(resolutions or (QUICK_RESOLUTIONS if quick else RESOLUTIONS)["csph"])
    ratios = tuple(float(r) for r in (ratios or (QUICK_RATIOS if quick else RATIOS)))
    seeds = tuple(int(s) for s in (seeds or (QUICK_SEEDS if quick else SEEDS)))
    for r in res:  # a grain boundary thinner than the spacing is bad input, not a failed run
        scene.model(scene.H / r)
    keys = [(r, q, s) for r in res for q in ratios for s in seeds]
    tasks = [Task.make("csph", mode_scene(scene, q, s), r, crack="visibility") for r, q, s in keys]
    outs = dict(zip(keys, run_tasks(tasks, scheduler, NAME)))
    return dataset(scene, outs, res, ratios, seeds)


def gb_share(out: dict) -> tuple[float, int, int]:
    """(share, failed, failed in a grain boundary) of one run's final failed particles (NaN share
    where none failed)."""
    failed = np.asarray(out.get("failed_particles", ()), bool)
    if not failed.any():
        return float("nan"), 0, 0
    names = list(out["region_names"])
    gb = np.array([n.startswith("gb") for n in names], bool)[np.asarray(out["region"])[failed]]
    return float(gb.mean()), int(failed.sum()), int(gb.sum())


def dataset(scene: MicroCantilever, outs: dict, res, ratios, seeds) -> xr.Dataset:
    """The study's dataset from ``outs`` {(resolution, ratio, seed): driver output}: per run the
    share, the counts, the time of the cut, status and cost; per resolution the mean and scatter
    over the seeds and the transition with its bootstrap interval (:func:`derive`)."""
    from workbench import results

    shp = (len(res), len(ratios), len(seeds))
    share = np.full(shp, np.nan)
    n_failed, n_gb, npart, steps = (np.zeros(shp, np.int64) for _ in range(4))
    t_cut, wall, pss = (np.full(shp, np.nan) for _ in range(3))
    status = np.full(shp, "not run", dtype=object)
    for (r, q, s), out in outs.items():
        i = (list(res).index(r), list(ratios).index(q), list(seeds).index(s))
        status[i] = str(out.get("status", "error: no status"))
        if status[i].startswith("ok"):
            share[i], n_failed[i], n_gb[i] = gb_share(out)
        t_cut[i] = float(out.get("t_separated", np.nan))
        wall[i] = float(out.get("run_wall_time", out.get("wall_time", np.nan)))
        npart[i] = int(out.get("n_particles", 0))
        steps[i] = int(out.get("steps", 0))
        pss[i] = float(out.get("particle_steps_per_second", np.nan))
    dims = ("resolution", "ratio", "seed")
    ds = xr.Dataset(
        {"share_gb": (dims, share, {"units": "-", "long_name": "share of the failed particles in "
                                    "the grain boundaries, at the cut"}),
         "n_failed": (dims, n_failed, {"units": "-"}),
         "n_failed_gb": (dims, n_gb, {"units": "-"}),
         "t_separated": (dims, t_cut, {"units": "s", "long_name": "time of the cut"}),
         "status": (dims, status.astype(str), {"units": "-"}),
         "wall_time": (dims, wall, {"units": "s"}),
         "n_particles": (dims, npart, {"units": "-"}),
         "steps": (dims, steps, {"units": "-"}),
         "particle_steps_per_second": (dims, pss, {"units": "1/s"})},
        coords={"resolution": ("resolution", np.asarray(res, int),
                               {"units": "-", "long_name": "particles across H"}),
                "ratio": ("ratio", np.asarray(ratios, float),
                          {"units": "-", "long_name": "eps_L(grains) / eps_L(grain boundaries)"}),
                "seed": ("seed", np.asarray(seeds, int))})
    ds.attrs.update(results.provenance(NAME, scene))
    ds.attrs["eps_L_gb"] = float(scene.eps_L_low)
    return derive(ds)


def derive(ds: xr.Dataset) -> xr.Dataset:
    """Add ``share_mean``, ``share_sd`` (over the seeds, ddof 1; NaN where a run gave none) and, per resolution,
    ``transition`` with its bootstrap interval ``transition_lo``/``transition_hi`` (16th and 84th
    percentiles: ± one standard deviation for a normal spread)."""
    share = ds.share_gb.values  # a failed run (NaN) makes its ratio's mean NaN: its gates fail
    mean = share.mean(axis=2)
    sd = share.std(axis=2, ddof=1) if share.shape[2] > 1 else np.zeros(mean.shape)
    ds["share_mean"] = (("resolution", "ratio"), mean, {"units": "-"})
    ds["share_sd"] = (("resolution", "ratio"), sd, {"units": "-"})
    ratios = ds.ratio.values
    mid, lo, hi = [], [], []
    for k in range(len(ds.resolution)):
        mid.append(transition(ratios, share[k].mean(axis=1)))
        a, b = bootstrap_transition(ratios, share[k])
        lo.append(a)
        hi.append(b)
    for name, v in (("transition", mid), ("transition_lo", lo), ("transition_hi", hi)):
        ds[name] = ("resolution", np.asarray(v, float), {"units": "-"})
    return ds


def transition(ratios, share, level: float = LEVEL) -> float:
    """The ratio at which ``share`` (one per ratio, increasing ratios) first crosses ``level``
    upward: linear in log ρ between the last ratio below it and the next; NaN where the share at
    the first ratio is already at or above ``level``, where it never reaches it, or where a value
    is NaN."""
    q = np.log(np.asarray(ratios, float))
    s = np.asarray(share, float)
    if not np.isfinite(s).all() or s[0] >= level:
        return float("nan")
    up = np.flatnonzero(s >= level)
    if not up.size:
        return float("nan")
    k = int(up[0])
    w = (level - s[k - 1]) / (s[k] - s[k - 1])
    return float(np.exp(q[k - 1] + w * (q[k] - q[k - 1])))


def bootstrap_transition(ratios, share, n: int = N_BOOT, seed: int = 0) -> tuple[float, float]:
    """The 16th and 84th percentiles of :func:`transition` of the mean share over ``n`` resamples
    (with replacement) of the seeds — ``share`` (ratios, seeds). A resample without a crossing
    counts as below the sweep (share ≥ level at the first ratio) or above it, so the interval
    widens rather than hides it; NaN where the share itself has a NaN."""
    share = np.asarray(share, float)
    if not np.isfinite(share).all() or share.shape[1] == 0:
        return float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    pick = rng.integers(0, share.shape[1], size=(n, share.shape[1]))
    means = share[:, pick].mean(axis=2)  # (ratios, n)
    ratios = np.asarray(ratios, float)
    out = np.empty(n)
    for j in range(n):
        t = transition(ratios, means[:, j])
        if not np.isfinite(t):
            t = ratios[0] if means[0, j] >= LEVEL else ratios[-1]
        out[j] = t
    lo, hi = np.percentile(np.log(out), [16.0, 84.0])
    return float(np.exp(lo)), float(np.exp(hi))


def sweep_step(ratios, at: float) -> float:
    """The sweep's step at ratio ``at``, as a factor: the ratio of the two sweep values that
    bracket it (the larger of the first two where ``at`` is at or below the first). NaN for a
    NaN ``at``."""
    r = np.asarray(ratios, float)
    if not np.isfinite(at):
        return float("nan")
    k = int(np.clip(np.searchsorted(r, at), 1, len(r) - 1))
    return float(r[k] / r[k - 1])


def monotone_drop(mean, sd, n_seeds: int) -> tuple[float, int]:
    """(the largest fall of the mean share between successive ratios less twice its standard
    error, at which index): the share may fall by sampling noise — two standard errors of a
    difference of two means over ``n_seeds`` seeds, √(sd_i² + sd_j²)/√n — and by no more; a value
    above 0 is a fall beyond the seeds' scatter. NaN where a value is NaN."""
    mean, sd = np.asarray(mean, float), np.asarray(sd, float)
    if len(mean) < 2:
        return float("nan"), -1
    if not (np.isfinite(mean).all() and np.isfinite(sd).all()):
        return float("nan"), -1
    noise = 2.0 * np.sqrt((sd[:-1] ** 2 + sd[1:] ** 2) / max(n_seeds, 1))
    excess = (mean[:-1] - mean[1:]) - noise
    k = int(np.argmax(excess))
    return float(excess[k]), k


SEEDS_REFERENCE = ("the seeds' own scatter: other Voronoi realisations of the same scene, "
                   "independent samples of what the grain geometry does")


def gates(ds: xr.Dataset) -> list:
    """Per resolution: the share monotone in ρ within the seeds' scatter, the limits ρ = 1
    (intra) and ρ = 500 (inter), a crossing inside the sweep; with two resolutions or more, the
    transition's move between the two finest, in steps of the sweep. A NaN share fails each gate
    that reads it."""
    out = []
    ratios = ds.ratio.values
    n = len(ds.seed)
    for r in ds.resolution.values:
        at = ds.sel(resolution=r)
        mean, sd = at.share_mean.values, at.share_sd.values
        tag = f"{NAME} H/dx={int(r)}"
        drop, k = monotone_drop(mean, sd, n)
        reason = ("the share may fall between successive ratios by two standard errors of the "
                  "seeds' scatter (sampling noise, 95 %), by no more: a stronger grain never "
                  "draws the crack out of the boundaries")
        if not np.isfinite(drop):
            out.append(Gate.missing(f"{tag}: share monotone in rho", "a share is NaN", 0.0,
                                    reason, SEEDS_REFERENCE))
        else:
            seen = ("monotone" if drop <= 0 else
                    f"falls {drop:.3g} beyond the scatter from rho={ratios[k]:g} to {ratios[k + 1]:g}")
            out.append(Gate.expect(f"{tag}: share monotone in rho", seen, "monotone", reason,
                                   SEEDS_REFERENCE))
        for q, want, reason in (
                (ratios[0], "intra", "no strength contrast at rho = 1: the crack "
                 "runs where the strain peaks, across the grain at the root (the boundaries, 1 um "
                 "strips, hold a fifth of the beam): fewer than half of the failed particles in "
                 "the boundaries"),
                (ratios[-1], "inter", f"rho = {ratios[-1]:g}: 000's inter-granular contrast when 500 "
                 f"(0.002 against 1.0): at least {MIN_SHARE_INTER:.0%} of the failed particles in "
                 "the boundaries (000's classification, the issue's)")):
            name = f"{tag}: mode at rho={q:g}"
            m = float(at.share_mean.sel(ratio=q))
            ref = ("the strength contrast alone (the limits of the sweep, where the mode is "
                   "known without a run)")
            if not np.isfinite(m):
                out.append(Gate.missing(name, "the share is NaN", LEVEL, reason, ref))
                continue
            if want == "intra":
                got = "intra" if m < LEVEL else "not intra"
            else:
                got = "inter" if m >= MIN_SHARE_INTER else "not inter"
            g = Gate.expect(name, got, want, reason, ref)
            g.shown = f"{got}, share {m:.2f} (expected {want})"
            out.append(g)
        t = float(at.transition)
        name = f"{tag}: share crosses 50 % inside the sweep"
        reason = "the mode changes between the limits: the transition is a measured ratio"
        ref = "the two limits' modes (above)"
        if not np.isfinite(t):
            out.append(Gate.missing(name, "no crossing (or a NaN share)", LEVEL, reason, ref))
        else:
            out.append(Gate.expect(name, "crosses", "crosses", reason, ref))
    if len(ds.resolution) >= 2:
        out.append(convergence_gate(ds))
    return out


def convergence_gate(ds: xr.Dataset) -> Gate:
    """The transition at the finest resolution against the one before, in steps of the sweep
    there: |ln ρ*_fine − ln ρ*_coarse| / ln(step) at most 1 (the issue's bound: the sweep cannot
    place it closer)."""
    r = np.sort(ds.resolution.values)[-2:]
    a, b = (float(ds.transition.sel(resolution=x)) for x in r)
    step = sweep_step(ds.ratio.values, b)
    name = f"{NAME}: transition moves < one sweep step from H/dx={int(r[0])} to {int(r[1])}"
    reason = ("one step of the sweep where the finer transition lies (the ratio of the two sweep "
              "values about it): the sweep places the transition no closer, the issue's bound; "
              "the bootstrap interval says how much of the move the seeds explain")
    ref = (f"the transition at H/dx={int(r[0])}: another discretisation of the same grains and "
           "seeds")
    moved = abs(math.log(b) - math.log(a)) / math.log(step) if np.isfinite(a * b * step) else np.nan
    if not np.isfinite(moved):
        return Gate.missing(name, "a transition is NaN", 1.0, reason, ref)
    return Gate.at_most(name, moved, 1.0, reason, ref)


def errors(ds: xr.Dataset) -> list[dict]:
    """No rows of accuracy against cost: the study measures a ratio, not an error."""
    return []


def report_notes(ds: xr.Dataset) -> list[str]:
    """The transition per resolution with its bootstrap interval, the share at the ends, and the
    cost: wall time summed over the runs, particle-steps per second."""
    notes = []
    for r in ds.resolution.values:
        at = ds.sel(resolution=r)
        m = at.share_mean.values
        notes.append(
            f"H/dx = {int(r)}: the mode changes (share of failed particles in the grain boundaries "
            f"crosses 50 %) at rho = eps_L(grains)/eps_L(boundaries) = {float(at.transition):.3g} "
            f"(bootstrap over {len(ds.seed)} seeds, 16-84 %: {float(at.transition_lo):.3g} to "
            f"{float(at.transition_hi):.3g}); share at rho = {ds.ratio.values[0]:g}: "
            f"{m[0]:.2f} ± {float(at.share_sd.values[0]):.2f}, at rho = {ds.ratio.values[-1]:g}: "
            f"{m[-1]:.2f} ± {float(at.share_sd.values[-1]):.2f}; {int(at.n_particles.max())} "
            f"particles, runs {float(np.nansum(at.wall_time)):.0f} s in all, "
            f"{float(np.nanmedian(at.particle_steps_per_second)):.3g} particle-steps/s (median)")
    return notes


def plot(ds: xr.Dataset, outdir) -> list:
    """The share against ρ per resolution: each seed's runs as points, the mean with ± one seed
    standard deviation as a band, 50 % and the transition with its bootstrap interval marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pathlib import Path

    from ..figures import save

    fig, ax = plt.subplots(figsize=(6.5, 4.3))
    colors = ("tab:blue", "tab:red", "tab:green", "tab:purple")
    q = ds.ratio.values
    for k, r in enumerate(ds.resolution.values):
        c = colors[k % len(colors)]
        at = ds.sel(resolution=r)
        m, sd = at.share_mean.values, at.share_sd.values
        for s in ds.seed.values:
            ax.plot(q, at.share_gb.sel(seed=s).values, ".", color=c, alpha=0.35, ms=4)
        ax.plot(q, m, "-o", color=c, ms=4, label=f"H/dx = {int(r)}: mean over {len(ds.seed)} seeds")
        ax.fill_between(q, np.clip(m - sd, 0, 1), np.clip(m + sd, 0, 1), color=c, alpha=0.15)
        t = float(at.transition)
        if np.isfinite(t):
            ax.axvline(t, color=c, ls="--", lw=1, label=f"transition {t:.3g} "
                       f"({float(at.transition_lo):.3g}-{float(at.transition_hi):.3g})")
            ax.axvspan(float(at.transition_lo), float(at.transition_hi), color=c, alpha=0.1)
    ax.axhline(LEVEL, color="k", lw=0.8)
    ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("rho = eps_L(grains) / eps_L(grain boundaries) [-] (log)")
    ax.set_ylabel("share of failed particles in grain boundaries [-]")
    ax.set_title("micro-cantilever (2-D): fracture mode against strength contrast", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return [save(fig, Path(outdir) / f"{NAME}_share.png")]
