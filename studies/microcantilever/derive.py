"""What the micro-cantilever study derives: from the static ladders, the first failure, the elastic
slope and their limits at the singular order (:data:`SINGULAR_ORDER`); from one dynamic run, the
crack's particles and its fracture energy, the fragments' speeds, the quasi-static window and the
run's scalars (:func:`run_summary`, with what "separated" means: :data:`TOL_SEPARATION`); from
the dataset, the fracture-energy ladders of gate 5."""
from __future__ import annotations

import numpy as np
import xarray as xr

from .ladders import BAND
from .scene import MicroCantilever


SINGULAR_ORDER = 2 * 0.5445
"""Order of convergence of the compliance (elastic slope) of a body with a re-entrant right-angle
corner (the root of the beam on its block, and the edge of the rigidly moved patch): the stress
there goes as r^(λ-1), λ = 0.5445 (Williams 1952, plane elasticity, 270° corner), and the energy
error as h^(2λ) (Strang & Fix §8.2) — for the FEM and for any consistent particle method alike.
The FEM ladder of this scene observes 1.15 (H/h = 5, 10, 20), csph's 1.03 (H/Δx = 5, 10, 20)."""

# Complete separation, "force back to zero" (issue 11): the mean load over the last 20 % of the run
# within 5 % of the peak load before the first failure. After separation the broken-off beam,
# carried by the loading patch, still vibrates: the load oscillates about zero with an amplitude
# of 10–25 % of that peak; its mean is below 2 % in the runs measured. Reported beside it, not
# gated: whether the loading patch and the held faces are still in one connected part of the body
# (sph.csph.CSPH.components: a chain of intact particles that still see each other) — a last
# ligament of one or two particles may carry a per cent of the load for a while.
TOL_SEPARATION = 0.05
TAIL = 0.2


def by_region(names, regions) -> tuple[float, str]:
    """(share in the grain boundaries, 'gb01 5, grain0 2'): of a set of particles or elements whose
    region ids (into ``names``) are ``regions``; NaN and '' for an empty set."""
    regions = np.asarray(regions, np.int64)
    if not regions.size:
        return float("nan"), ""
    gb = np.array([names[r].startswith("gb") for r in regions], bool)
    counts = {names[r]: int(c) for r, c in zip(*np.unique(regions, return_counts=True))}
    return float(gb.mean()), ", ".join(f"{n} {c}" for n, c in sorted(counts.items()))


def deletion_summary(case: str, names, region, deleted) -> dict:
    """``n_deleted``, ``share_low`` (the share of the deleted elements in the material of the
    low ε_L: the grain boundaries for ``inter``, the grains for ``intra`` — gate 3's measure
    for the FEM) and ``regions`` ('gb01 5, gb34 2') from the region names, each element's region
    (nel,) and the deleted element ids."""
    deleted = np.asarray(deleted, np.int64)
    gb, regions = by_region(names, np.asarray(region)[deleted])
    return dict(n_deleted=int(deleted.size), share_low=gb if case == "inter" else 1.0 - gb,
                regions=regions)


def first_failure(d, F, D) -> tuple[float, float]:
    """(deflection, load) where the largest damage D first reaches 1, linear between path
    points (NaN, NaN if it does not)."""
    k = np.flatnonzero(np.asarray(D) >= 1.0)
    if not k.size:
        return np.nan, np.nan
    k = int(k[0])
    if k == 0:
        return float(d[0] / D[0]), float(F[0] / D[0])  # elastic-linear from the origin
    w = (1.0 - D[k - 1]) / (D[k] - D[k - 1])
    return float(d[k - 1] + w * (d[k] - d[k - 1])), float(F[k - 1] + w * (F[k] - F[k - 1]))


def fem_slope_limit(res, slopes, order: float = SINGULAR_ORDER) -> float:
    """Richardson limit of the elastic slope (or of any value converging at ``order``) from the
    two finest meshes, at the singular order by default."""
    (r1, s1), (r2, s2) = sorted(zip(res, slopes))[-2:]
    q = (r2 / r1) ** order
    return float(s2 + (s2 - s1) / (q - 1))


def limit_spread(res, values) -> float:
    """The uncertainty of a Richardson limit taken at the singular order, as a fraction of it:
    |L(p) − L(q)|/|L(p)|, L the limit from the two finest meshes at p = SINGULAR_ORDER and at the
    order q observed on the three finest (:func:`_order3`). NaN below three meshes or where no order
    is observed (the differences change sign). It is the reference's own error where a computed
    value is checked against the limit rather than against a mesh (:func:`.gates.finest_gates`): the
    finest mesh's distance from the limit (``slope_error``, ``root_error``) is the error of that
    mesh, not of the limit."""
    res, values = np.asarray(res, float), np.asarray(values, float)
    if len(res) < 3:
        return float("nan")
    q = _order3(res[-3:], values[-3:])
    if not np.isfinite(q):
        return float("nan")
    lp = fem_slope_limit(res, values)
    return float(abs(lp - fem_slope_limit(res, values, q)) / abs(lp))


def csph_slope(d, F, t, t_first, window) -> float:
    """Elastic slope of a csph curve: least-squares line (with intercept: the inertia of the
    ramp) over the deflections in ``window`` (m) before the first failure. Each recorded load is
    the mean over the interval since the record before and the deflection its value at the
    record: the load is paired with the interval's mean deflection, (d_{k-1} + d_k)/2 (the
    trapezoidal rule; pairing it with d_k instead lowers the slope by 2.5 % at 400 records, as
    the patch accelerates during the ramp)."""
    d, F, t = (np.asarray(a, float) for a in (d, F, t))
    d = np.r_[d[:1], 0.5 * (d[1:] + d[:-1])]
    m = (d >= window[0]) & (d <= window[1]) & np.isfinite(F)
    if np.isfinite(t_first):
        m &= t < t_first
    if m.sum() < 3:
        return float("nan")
    return float(np.polyfit(d[m], F[m], 1)[0])


def _order3(res, s) -> float:
    """Observed order p from three meshes r₁ < r₂ < r₃ (h = 1/r): the root of
    (h₁^p − h₂^p)/(h₂^p − h₃^p) = Δ₁/Δ₂, Δ the successive differences of ``s`` — for a constant
    ratio r₂/r₁ = r₃/r₂ = q, log(Δ₁/Δ₂)/log q. NaN where the differences change sign or no
    positive order fits."""
    from scipy.optimize import brentq

    r = np.asarray(res, float)
    d1, d2 = s[0] - s[1], s[1] - s[2]
    if not d1 * d2 > 0:
        return np.nan
    target = np.log(d1 / d2)
    if np.isclose(r[1] / r[0], r[2] / r[1]):
        return float(target / np.log(r[1] / r[0]))

    def excess(p):  # increasing in p
        h = r ** -p
        return np.log((h[0] - h[1]) / (h[1] - h[2])) - target

    lo, hi = 1e-3, 20.0
    if excess(lo) > 0 or excess(hi) < 0:
        return np.nan
    return float(brentq(excess, lo, hi, xtol=1e-10))


CRACK_REACH = 2.25
"""Failed particles within CRACK_REACH spacings of each other in the reference configuration
belong to one crack (2.25: the diagonal neighbours two rows away included, so a band up to
three particles wide, or stepping sideways by a particle, stays one crack)."""


def crack_particles(out: dict, spacing: float) -> np.ndarray:
    """(N,) bool: the failed particles of the main crack — of the groups of failed particles
    joined within CRACK_REACH·``spacing`` (m) in the reference configuration, the one that spans
    most of the beam's height (the most particles among equals). Failures elsewhere — at the
    loading patch, in the broken-off piece after separation — are other groups. None when
    nothing failed."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    failed = np.asarray(out.get("failed_particles", ()), bool)
    if not failed.any():
        return failed
    idx = np.flatnonzero(failed)
    X = np.asarray(out["X"])[idx]
    pairs = cKDTree(X).query_pairs(CRACK_REACH * spacing * (1 + 1e-9), output_type="ndarray")
    n = len(idx)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    k, label = connected_components(graph, directed=False)
    up = X.shape[1] - 1
    height = np.array([np.ptp(X[label == j, up]) for j in range(k)])
    count = np.bincount(label, minlength=k)
    main = max(range(k), key=lambda j: (round(height[j] / spacing), count[j]))
    crack = np.zeros_like(failed)
    crack[idx[label == main]] = True
    return crack


def fracture_energy(out: dict, spacing: float, at: str = "separation") -> tuple[float, float, int]:
    """(G, G_all, n): the energy the main crack took to cut the body, J (J/m in 2-D) — the
    plastic work and the released stored energy of its particles (:func:`crack_particles`;
    history columns W_p and W_rel times the volumes of the run's work) plus what cutting pairs
    released (the run's released energy less Σ V W_rel of all particles: :mod:`sph.crack`) —, the
    same over every failed particle, and the crack's particle count. ``at``: 'separation' takes
    the state of the record at which the crack first cut the loading patch off from the held faces
    (the driver's ``at_separation``; the final state where the run was never cut apart), 'end'
    the final state. What fails after the cut — the broken-off piece, still driven by the patch,
    swinging past the block for the ``t_after`` the run goes on — is not the crack's, and would
    make G depend on how long one watches. NaN without the history and volumes."""
    from workbench.materials import HIST_W_P, HIST_W_REL

    state = (out.get("at_separation") if at == "separation" else None) or dict(
        history=out.get("history"), failed_particles=out.get("failed_particles", ()),
        released_energy=np.asarray(out.get("released_energy", [np.nan]))[-1])
    h, V = state.get("history"), out.get("volume")
    failed = np.asarray(state.get("failed_particles", ()), bool)
    if h is None or V is None or not failed.size or np.shape(h)[1] <= HIST_W_REL:
        return np.nan, np.nan, 0
    h, V = np.asarray(h), np.asarray(V, float)
    W = h[:, HIST_W_P] + h[:, HIST_W_REL]
    cut = float(state.get("released_energy", np.nan)) - float(V @ h[:, HIST_W_REL])
    crack = crack_particles(dict(X=out["X"], failed_particles=failed), spacing)
    return float(V[crack] @ W[crack]) + cut, float(V[failed] @ W[failed]) + cut, int(crack.sum())


def crack_position(out: dict, spacing: float) -> tuple[float, str]:
    """(x, region): where the main crack (:func:`crack_particles`) cut the body — the mean
    reference x of its particles, m, and the region (grain or boundary) that holds most of them —
    at the record of the cut (the driver's ``at_separation``; the final state where the run was
    never cut apart). (NaN, '') when nothing failed."""
    state = out.get("at_separation") or out
    failed = np.asarray(state.get("failed_particles", ()), bool)
    if not failed.any() or "X" not in out:
        return float("nan"), ""
    crack = crack_particles(dict(X=out["X"], failed_particles=failed), spacing)
    X = np.asarray(out["X"], float)[crack]
    reg = np.asarray(out["region"])[crack]
    names = list(out["region_names"])
    return float(X[:, 0].mean()), str(names[int(np.bincount(reg).argmax())])


def quasi_static_start(t_first: float, scene: MicroCantilever) -> float:
    """Start of gate 4's window, s, which ends at the first failure ``t_first``: the end of the
    velocity ramp or half the time to the first failure, whichever is later (the second half
    alone where the first failure comes within the ramp). Before it the ratio K/E is the
    start-up transient of the ramp, 4/(ω₁t)² for a beam of first frequency ω₁ whose end moves at
    v₀t/T (K = ½m v², E = ½k d², d = v₀t²/(2T)): the same at every resolution and above 1 % before
    t = 20/ω₁ (about 0.3 µs here), whatever the loading rate after the ramp
    (:data:`.gates.TOL_QUASI_STATIC`)."""
    t_ramp = float(getattr(scene, "t_ramp", 0.0))
    return max(0.5 * t_first, t_ramp) if t_ramp < t_first else 0.5 * t_first


FACE_REACH = 2.2
"""The intact particles a failed particle is measured against (:func:`fragment_measures`): those
within FACE_REACH spacings of it in the reference configuration — csph's kernel support 2h at
h = 1.1 Δx, the particles whose row it was in before it failed: the faces of its crack."""


def fragment_measures(out: dict, scene: MicroCantilever, spacing: float | None = None) -> dict:
    """What the failed particles carry at the end of the run (issue 36), over the failed particles
    that have no prescribed DOF (those of the loading patch move as the drive says, vertically):
    ``fragment_speed_max``, their largest speed, m/s; ``fragment_kinetic_share``, their kinetic
    energy Σ ½ ρ V |v|² (V the volumes of the run's work) over the energy released by cracking (the
    run's ``released_energy`` at its end); and, with the ``spacing`` (m), the same relative to the
    faces of each one's crack — the mean velocity v̄ of the intact particles within
    :data:`FACE_REACH` spacings of it in the reference configuration —:
    ``fragment_relative_speed_max`` (max |v − v̄|) and ``fragment_relative_kinetic_share``
    (Σ ½ ρ V |v − v̄|² over the released energy; a particle with no intact one around counts with
    v̄ = 0). NaN without velocities, volumes or failed particles.

    Why relative: the broken-off piece, released by a brittle failure into an undamped body,
    rings — its intact particles move at a median 1.1–1.75 m/s and up to 4–7 m/s at the end of the
    runs, σ/(ρc) ≈ 7 m/s for such a release —, so failed particles that move with the body can be
    neither below 5× the loading speed (1 m/s) nor, where a few per cent of the body's mass has
    failed, below 5 % of the released energy; what the issue's bars are after, failed particles
    thrown off the body, is their motion relative to the body around them."""
    nan = float("nan")
    v, V = out.get("v"), out.get("volume")
    failed = np.asarray(out.get("failed_particles", ()), bool).copy()
    released = np.asarray(out.get("released_energy", [nan]), float)[-1]
    res = dict(fragment_speed_max=nan, fragment_kinetic_share=nan, fragment_relative_speed_max=nan,
               fragment_relative_kinetic_share=nan)
    if failed.any() and "sets" in out and "patch" in out["sets"]:
        failed[np.asarray(out["sets"]["patch"], int)] = False
    if v is None or V is None or not failed.any():
        return res
    v, V = np.asarray(v, float), np.asarray(V, float)
    speed = np.linalg.norm(v[failed], axis=1)
    share = (lambda e: e / released if released > 0 else nan)  # noqa: E731
    res.update(fragment_speed_max=float(speed.max()),
               fragment_kinetic_share=share(0.5 * scene.rho * float(V[failed] @ speed ** 2)))
    if spacing is not None and "X" in out:
        from scipy.spatial import cKDTree

        X = np.asarray(out["X"], float)
        intact = np.flatnonzero(~np.asarray(out["failed_particles"], bool))
        tree = cKDTree(X[intact])
        idx = np.flatnonzero(failed)
        rel = np.empty(len(idx))
        for k, a in enumerate(idx):
            near = intact[tree.query_ball_point(X[a], FACE_REACH * spacing * (1 + 1e-9))]
            rel[k] = np.linalg.norm(v[a] - (v[near].mean(axis=0) if near.size else 0.0))
        ke = 0.5 * scene.rho * float(V[idx] @ rel ** 2)
        res.update(fragment_relative_speed_max=float(rel.max()),
                   fragment_relative_kinetic_share=share(ke))
    return res


def run_summary(out: dict, scene: MicroCantilever, resolution: int | None = None) -> dict:
    """The scalars of one run from its result ``out`` (driver output): peak load before the first
    failure, deflection and load at the first failure, initial slope, energy balance error,
    kinetic/elastic ratio before the first failure, failed particles and their share in the grain
    boundaries, the mean load over the last 20 % of the run (to its last record: a run stops
    ``t_after`` past the separation, the scene's ``t_end`` the longest it may go), separation,
    whether a chain of intact particles still joins the loading patch and the held faces at the
    end (``connected``), the time at which none first did (``t_separated``, NaN if never) and the
    run's last record (``t_last``)."""
    nan = float("nan")
    s = dict(peak_load=nan, deflection_at_peak=nan, t_first_failure=nan, load_at_first_failure=nan,
             deflection_at_first_failure=nan, elastic_slope=nan, energy_balance_error=nan,
             kinetic_ratio=nan, n_failed=0, share_boundaries=nan, mean_tail_load=nan,
             tail_load_ratio=nan, separated=False, connected=nan, crack_regions="",
             released_final=nan, fracture_energy=nan, fracture_energy_all=nan, n_crack=0,
             fracture_energy_end=nan, fragment_speed_max=nan, fragment_kinetic_share=nan,
             fragment_relative_speed_max=nan, fragment_relative_kinetic_share=nan, crack_x=nan,
             crack_region="", max_load=nan,
             t_separated=nan, t_last=nan)
    if "time" not in out or len(out.get("time", ())) < 3:
        return s
    t = np.asarray(out["time"])
    F = np.asarray(out["load"])
    d = np.asarray(out["deflection_down"])
    if not (np.isfinite(F).all() and np.isfinite(d).all()):
        return s
    fail = np.asarray(out["failed"])
    first = np.flatnonzero(fail > 0)
    before = slice(0, int(first[0]) if first.size else len(t))
    k = int(np.argmax(F[before]))
    s.update(peak_load=float(F[k]), deflection_at_peak=float(d[k]), t_last=float(t[-1]),
             t_separated=float(out.get("t_separated", nan)))
    upto = t <= s["t_separated"] if np.isfinite(s["t_separated"]) else np.ones(len(t), bool)
    s["max_load"] = float(np.max(F[upto]))  # the dynamic peak: the largest load until the cut
    W = np.asarray(out["external_work"])
    E = (np.asarray(out["kinetic_energy"]) + np.asarray(out["strain_energy"])
         + np.asarray(out.get("plastic_work", 0 * t))
         + np.asarray(out.get("released_energy", 0 * t))
         + np.asarray(out.get("merge_dissipation", 0 * t)))
    on = W > 1e-6 * np.max(np.abs(W))
    if on.any():
        s["energy_balance_error"] = float(np.max(np.abs(W[on] - E[on]) / W[on]))
    if first.size:
        i = int(first[0])
        s.update(t_first_failure=float(t[i]), load_at_first_failure=float(F[i - 1]),
                 deflection_at_first_failure=float(d[i - 1]))
        window = (t >= quasi_static_start(t[i], scene)) & (t < t[i])
        if window.any():
            ke, el = np.asarray(out["kinetic_energy"])[window], np.asarray(out["strain_energy"])[window]
            s["kinetic_ratio"] = float(np.max(ke / el))
        lin = (d > 0.2 * d[i - 1]) & (d < 0.5 * d[i - 1]) & (t < t[i])
        if lin.sum() >= 3:
            s["elastic_slope"] = float(np.polyfit(d[lin], F[lin], 1)[0])
    mask = np.asarray(out.get("failed_particles", ()), bool)
    if mask.size:
        s["n_failed"] = int(mask.sum())
        s["share_boundaries"], s["crack_regions"] = by_region(list(out["region_names"]),
                                                            np.asarray(out["region"])[mask])
    # each recorded load is the mean over the interval since the record before: their time mean
    # over the tail is Σ F_k Δt_k / Σ Δt_k
    tail = np.flatnonzero(t[1:] > (1.0 - TAIL) * t[-1]) + 1
    w = t[tail] - t[tail - 1]
    s["mean_tail_load"] = float(np.sum(F[tail] * w) / np.sum(w))
    s["tail_load_ratio"] = s["mean_tail_load"] / s["peak_load"]
    s["separated"] = bool(str(out.get("status")) == "ok" and s["peak_load"] > 0
                          and abs(s["tail_load_ratio"]) <= TOL_SEPARATION)
    parts = out.get("component")
    if parts is not None:
        parts = np.asarray(parts)
        sets = out["sets"]
        s["connected"] = float(bool(set(parts[sets["patch"]]) & set(parts[sets["held"]])))
    if "released_energy" in out:
        s["released_final"] = float(np.asarray(out["released_energy"])[-1])
    s.update(fragment_measures(out, scene, None if resolution is None else scene.H / resolution))
    if resolution is not None:
        G, G_all, n = fracture_energy(out, scene.H / resolution)
        s["crack_x"], s["crack_region"] = crack_position(out, scene.H / resolution)
        s.update(fracture_energy=G, fracture_energy_all=G_all, n_crack=n,
                 fracture_energy_end=fracture_energy(out, scene.H / resolution, at="end")[0])
    return s


def fracture_ladder(ds: xr.Dataset, case: str, rule: str) -> tuple[np.ndarray, np.ndarray]:
    """(resolutions, fracture energies, J) of the runs of ``case`` and ``rule`` that report one."""
    if rule not in ds.rule.values:
        return np.zeros(0, int), np.zeros(0)
    G = ds.fracture_energy.sel(solver="csph", case=case, rule=rule).values
    r = ds.resolution.values
    ok = np.isfinite(G) & (G > 0)
    return r[ok].astype(int), G[ok]


def band_width(ds: xr.Dataset) -> float:
    """The crack band of the ``regularised`` rule, m: the scene's ``band`` when set, else BAND."""
    return float(ds.attrs.get("param_band", 0.0)) or BAND


def band_ladder(ds: xr.Dataset, case: str) -> tuple[np.ndarray, np.ndarray]:
    """(resolutions, fracture energies, J) of gate 5: the ``regularised`` runs of ``case`` whose
    crack band is wider than the spacing, b > Δx = H/r — where the rule raises ε_L and so does
    what the gate tests (at b = Δx ε_L,eff = ε_L: the run is the ``compression`` one). A run
    of those that reports no fracture energy (failed, nothing broke) is NaN, so the gate fails."""
    if "regularised" not in ds.rule.values:
        return np.zeros(0, int), np.zeros(0)
    H = float(ds.attrs["param_H"])
    r = ds.resolution.values.astype(int)
    status = ds.status.sel(solver="csph", case=case, rule="regularised").values
    on = (band_width(ds) > H / r * (1 + 1e-9)) & (status != "not run")
    G = ds.fracture_energy.sel(solver="csph", case=case, rule="regularised").values[on]
    return r[on], np.where(np.isfinite(G) & (G > 0), G, np.nan)


def spacing_power(res, G) -> float:
    """The power q of G ∝ Δx^q = (H/r)^q, least squares on the logarithms (NaN below 2 runs)."""
    if len(res) < 2:
        return float("nan")
    return float(-np.polyfit(np.log(np.asarray(res, float)), np.log(G), 1)[0])
