"""Gate 2, second half: the slow impact. Specimen A at :data:`SLOW_VELOCITY` (nothing cracks or
yields): csph's mid-span history against an implicit FEM of the same beam with the weight a rigid
mass on the plate (:class:`SlowImpactFem`) over the first half period — the runs, the comparison,
its tolerance with its reason (:data:`TOL_SLOW`), its dataset variables, gates and note. Full run
only (its csph run alone costs ~30 s of CPU, the FEM's ladder minutes)."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..common import Gate
from ..sweep import Task, run_tasks
from .ladders import NAME, OPTIONS, SCENE
from .scene import RCBeam


# -- gate 2, second half: a slow impact against the FEM ----------------------------------------
#
# An impact too slow to crack anything: specimen A struck at SLOW_VELOCITY, csph (the study's
# nodal csph, the scene's own penalty contact at the plate and the supports) against the FEM of
# the same beam over the first half period of its response (~10 ms).
#
# The FEM's idealisation (SlowImpactFem). Over the first half period the weight stays pressed on
# the plate and the supports in compression on average (the 1 ms means of both contact forces stay
# positive: checked in the particle run, slow_comparison and slow_gates), so the FEM needs no
# contact:
# * the weight (quarter mass 25 kg) is a mass carried by the plate's top face under its footprint
#   (fem_reference.model.lump_mass: lumped in proportion to the nodes' ∫N dA, every component),
#   those nodes starting with the impact velocity: the weight's inertia acts on the face while the
#   face may bend (a rigid tie would stiffen the mid-span by the weight's own bending stiffness,
#   which a frictionless contact does not transmit). The weight's own elasticity (its axial
#   stiffness E A/h ~ 8e9 N/m against the beam's ~2e6 N/m, quarter) is left out;
# * each support is a hinge: u_z = 0 on the line z = 0 across the width at the support block's
#   inner column, x = span/2 − Δx. The scene's support is a flat block of three lattice columns
#   (span/2 − Δx, span/2, span/2 + Δx); under a beam that rotates at its ends a flat block bears
#   on its inner edge: the rotation over one spacing (θΔx ~ 1e-6 m here) exceeds the penalty's
#   overlap under the reaction (~1e-8 m) by two orders. Measured in the particle run (the contact
#   force of each column, sph.contact.contact_forces on the positions at each of 200 records
#   through driver.solve's on_record, summed over the window): 97 % of A's support impulse on the
#   inner column, 3 % on the middle one, none on the outer. On B (span 400 mm) the mortar's
#   local indentation under the inner column reaches the middle column (68 % / 32 %), and a hinge
#   half a spacing further out changes B's FEM history by 15 % of its peak (A's by 8 %): B's
#   support is no clean hinge at 12.5 mm, which is why the check runs on A;
# * the regions are the particles' (their cells at Δx: the plate, rounded by the scene to the
#   beam's top lattice layer, is the steel layer [H − Δx/2, H]; the beam ends at its last cell),
#   the same equivalent steel of the bars and stirrups, the symmetry rollers, the same laws (they
#   stay elastic: no damage, no plastic strain, checked).
# The FEM's Newmark runs by modified Newton (initial_tangent: one factorisation; the residual is
# the full one), Δt = T₁/n with T₁ its lowest period (~20 ms), n of SLOW_FEM_STEPS.
#
# The metric: max over the window |w_csph − w_FEM| / max w_FEM, the window [0, t½] ending where
# the reference FEM's mid-span displacement returns to zero (the end of the first half period; the
# FEM's weight force −M a stays compressive to about there; csph's weight leaves at the same time,
# 10.02 ms against t½ = 9.95 ms). What it holds, and the tolerance:
# * the FEM's own error, the ladder's last steps (slow_fem_mesh_error, slow_fem_time_error):
#   meshes 4, 6, 8 at 200 steps a period differ from the finest by 0.9 % and 0.5 % of the peak
#   (slowly: a line hinge's local compliance grows like log(1/h), so the FEM is taken at the
#   particle spacing, the scale over which the particles' contact spreads the reaction); 200
#   against 400 steps a period, 1.1 % (the impulsive start excites the mesh's high modes, whose
#   phase the trapezoidal rule distorts at any step: ~1 % of high-frequency content). 1.6 %;
# * csph's error at H/dx = 8: nodal integration, second order; A's bare beam on hinges has its
#   first frequency 0.9 % above the FEM's at this spacing (gate 2's modal check: 173.1 against
#   171.5 Hz), a stiffness 1.9 % high: in the weight-on-beam response a phase error of π · 0.9 %
#   ≈ 2.9 % of the peak at the end of the half period;
# * the contact the FEM idealises: csph's penalty is stiff and undamped. Its compliance is
#   negligible (E_s Δx per particle pair, ~1e10 N/m for a column of four, against the beam's
#   ~2e6 N/m: 1e-4 of the deflection); its being one-sided is not: the
#   weight bounces off the plate at its first impact and then chatters at ~3 kHz (21 % of the
#   records in the window without impact force), the supports likewise; the FEM's weight sticks:
#   3.5 % of the peak at 0.7 ms, the largest difference of the first ms (measured: no FEM here
#   has the contact). And the weight bears where it touches, half of its force on the plate's edge
#   column (the force's centroid 41 mm from mid-span, the face's 25 mm): the FEM with all of the
#   weight on the plate's edge differs by 2.5 % of the peak, so ~1.3 % late in the half period,
#   csph the more compliant (against its stiffer beam).
# The FEM's own error and csph's expected one, 1.6 + 2.9 = 4.5 %, are within the 5 %. The
# contact's differences come on top at different instants: early, its transient with the FEM's
# own error there and csph's small phase error (3.5 + 0.9 + 0.2 %); late, csph's phase less the
# bearing plus the FEM's own (2.9 − 1.3 + 1.6 %; csph's difference is largest there, 3.7 % of the
# peak at 8 ms). Both stay within 5 %, and csph's present difference trebled fails it.
TOL_SLOW = 0.05
SLOW_DAMAGE_DEFECT = 1e-3
"""The slow impact's 'nothing cracks or yields' gate is an exactness gate (tests/test_gates.py)
with tolerance 0: any damage or plastic strain at all fails it, a third of any defect too; this is
a nominal small damage (1e-3) for that test."""
SLOW_SPECIMEN = "A"
"""The slow impact's specimen: A (span 800 mm; see the idealisation above for why not B)."""
SLOW_VELOCITY = 0.01
"""Impact speed of the slow impact, m/s. The estimate (:func:`slow_impact_stress`): the weight on
the beam's static mid-span stiffness k (Timoshenko, transformed section with both D10 bars:
8.3e6 N/m for A) reaches the force F = v √(k M), the bottom fibre σ = F L/4 · z_c/I: 0.31 MPa
at 0.01 m/s, a fifth of the mortar's 1.61 MPa (the contact force's peaks, with its chatter, reach
about 3 times its smooth value: still below). The particle run confirms it: no damage, no plastic
strain. The response is linear (strains ~1e-5; penalty contact and elasticity are both
homogeneous of degree one in v), so the speed only scales it."""
SLOW_RESOLUTION = 8
"""csph's spacing of the slow impact: 12.5 mm (H/dx = 8)."""
SLOW_T_END = 1.05e-2
"""Simulated time, s: A's first half period is ~10 ms."""
SLOW_N_OUT = 210
"""Records of the slow runs (every 50 µs)."""
SLOW_FEM_RESOLUTIONS = (4, 6, 8)
"""The FEM's mesh ladder of the slow impact (elements of H/r, 27-node hexahedra, on a grid through
every region face), each at the first of :data:`SLOW_FEM_STEPS`."""
SLOW_FEM_STEPS = (200, 400)
"""Newmark steps per lowest period: the mesh ladder's, and the finest mesh's again (the time
rung); the finest mesh at the most steps is the reference."""
SLOW_N_TIME = 201
"""Points of the common time axis over the window."""
SLOW_MEAN_WINDOW = 1e-3
"""The moving time mean (s) over which the contact forces must stay compressive (three chatter
periods)."""


@dataclass(frozen=True)
class SlowImpactFem:
    """The FEM's model of the slow impact's elastic phase (module comment above ``TOL_SLOW``): the
    beam of ``beam`` (the quarter model; ``structure='impact'``) with the regions its particles fill
    at the spacing H/``resolution``, hinged at the support block's inner column, the weight's mass
    carried by the plate's top face (:meth:`lumped_mass`). A scene for :func:`fem_reference.solve`
    (its FEM resolution r gives elements of H/r; the geometry is that of the particle spacing)."""

    beam: RCBeam
    resolution: int = SLOW_RESOLUTION
    name: str = f"{NAME}_slow_fem"

    @property
    def dx(self) -> float:
        """The particle spacing whose geometry the model has, m."""
        return self.beam.H / self.resolution

    @property
    def hinge_x(self) -> float:
        """x of the hinge line: the support block's inner column, span/2 − Δx, m."""
        return self.beam.span / 2 - self.dx

    @property
    def weight_x(self) -> float:
        """The weight's last lattice column (its footprint on the plate is [0, weight_x]), m."""
        return math.floor(self.beam.plate_length / 2 / self.dx + 1e-9) * self.dx

    def model(self, spacing: float | None = None):
        """The FEM's model (``spacing``, the element size, does not enter)."""
        import workbench.scenes.model as m
        from .scene import staircase
        from workbench.scenes.shapes import Box, Plane, Point, Union

        s, dx = self.beam, self.dx
        if not s.symmetry or s.structure != "impact":
            raise ValueError("beam: the slow impact's FEM models the quarter model of the impact "
                             "(symmetry=True, structure='impact')")
        H, L2 = s.H, s.span / 2
        xe, yb = staircase(L2 + s.overhang, dx), staircase(s.B / 2, dx)
        xh, xw, e = self.hinge_x, self.weight_x, 1e-9 * H
        z_top = math.floor((H + s.plate_thickness) / dx + 1e-9) * dx  # the scene's plate top
        # the plate's cells: its lowest layer (z = H) owns [H − Δx/2, H] and, inside the mortar,
        # half a spacing past its last column; layers above, the plate box's staircase
        plate = [Box((0.0, 0.0, H - dx / 2), (xw, yb, H)),
                 Box((xw, 0.0, H - dx / 2), (xw + dx / 2, yb, H))]
        if z_top > H + e:
            plate.append(Box((0.0, 0.0, H), (staircase(s.plate_length / 2, dx), yb, z_top)))
        regions = [m.Region("mortar", Union((Box((0.0, 0.0, 0.0), (xh, yb, H)),  # a grid line
                                             Box((xh, 0.0, 0.0), (xe, yb, H)))),  # at the hinge
                            s.mortar(dx), body="beam"),
                   m.Region("plate", Union(tuple(plate)), s.steel(), priority=1, body="beam")]
        for name, box, scale, pri in s.bars(dx):  # the bars end with the beam's last cells
            box = Box(box.lo, (min(box.hi[0], xe), box.hi[1], box.hi[2]))
            regions.append(m.Region(name, box, s.steel(scale), priority=pri, body="beam"))
        return m.Model(
            dim=3, plane=None, length=H, name=self.name, regions=tuple(regions),
            sets=(m.Set("sym_x", Plane(0, 0.0)), m.Set("sym_y", Plane(1, 0.0)),
                  m.Set("hinge", Box((xh - e, 0.0, -e), (xh + e, yb, e))),
                  m.Set("weight_face", Box((0.0, 0.0, z_top - e), (xw, yb, z_top + e))),
                  m.Set("midspan_bottom", Point((0.0, 0.0, 0.0)))),
            constraints=(m.Roller("sym_x", 0), m.Roller("sym_y", 1), m.Roller("hinge", 2)),
            drive=m.Explicit(s.t_end, n_out=s.n_out),
            observables=(m.Displacement("midspan_w", "midspan_bottom", 2),
                         m.Displacement("weight_w", "weight_face", 2)),
            notes=("slow impact's elastic phase: the weight a mass on the plate's top face, "
                   "hinges at the support blocks' inner columns",))

    def lumped_mass(self) -> tuple:
        """The FEM option ``lumped_mass``: the quarter weight on ``weight_face`` with the impact
        velocity."""
        s = self.beam
        return (("weight_face", s.mass / s.copies, (0.0, 0.0, -s.impact_velocity)),)

    def summarise(self, out: dict) -> dict:
        """``midspan_displacement`` and ``weight_displacement``, m, positive downward."""
        if "midspan_w" not in out:
            return {}
        return dict(midspan_displacement=-np.asarray(out["midspan_w"], float),
                    weight_displacement=-np.asarray(out["weight_w"], float))


def slow_impact_stress(scene: RCBeam, velocity: float) -> float:
    """The estimate of :data:`SLOW_VELOCITY`: the largest tensile stress (Pa) at the mortar's
    bottom when the weight (``scene.mass``) at ``velocity`` (m/s) meets the beam's static mid-span
    stiffness k = 1/(L³/(48 E I) + L/(4 κ G A)) (Timoshenko; the transformed section of the mortar
    with both main bars, n = E_s/E_m; κ = 5/6): F = v √(k M), σ = F L/4 · z_c/I."""
    E, G = scene.E_m, scene.E_m / (2 * (1 + scene.nu_m))
    b, h, L, c = scene.B, scene.H, scene.span, scene.cover
    n, As = scene.E_s / E, 2 * scene.bar_area
    zc = (b * h * h / 2 + (n - 1) * As * c) / (b * h + (n - 1) * As)
    I = b * h ** 3 / 12 + b * h * (h / 2 - zc) ** 2 + (n - 1) * As * (zc - c) ** 2
    k = 1.0 / (L ** 3 / (48 * E * I) + L / (4 * 5 / 6 * G * b * h))
    return velocity * math.sqrt(k * scene.mass) * L / 4 * zc / I


def slow_impact_scene(scene: RCBeam | None = None) -> RCBeam:
    """The particle scene of the slow impact: ``scene`` (default :class:`.scene.RCBeam`) as specimen
    :data:`SLOW_SPECIMEN` struck at :data:`SLOW_VELOCITY` for :data:`SLOW_T_END`."""
    return dataclasses.replace(scene or SCENE(), specimen=SLOW_SPECIMEN, velocity=SLOW_VELOCITY,
                               t_end=SLOW_T_END, n_out=SLOW_N_OUT, structure="impact",
                               symmetry=True, name=f"{NAME}_{SLOW_SPECIMEN}_slow")


def slow_impact_tasks(scene: RCBeam | None = None, fem_resolutions=SLOW_FEM_RESOLUTIONS,
                      steps=SLOW_FEM_STEPS, resolution: int = SLOW_RESOLUTION) -> dict:
    """{key: Task} of the slow impact: ('csph', r, 0) the particle run at ``resolution``;
    ('fem', r, n) the FEM at each of ``fem_resolutions`` with n = ``steps[0]`` Newmark steps per
    period, and the finest at every other n of ``steps``. ``scene``: a particle scene
    (:func:`slow_impact_scene` by default)."""
    sc = scene if scene is not None else slow_impact_scene()
    fem = SlowImpactFem(sc, resolution)
    fem_opts = dict(lumped_mass=fem.lumped_mass(), initial_tangent=True)
    tasks = {("csph", resolution, 0): Task.make("csph", sc, resolution, **OPTIONS["csph"])}
    steps = tuple(int(n) for n in np.atleast_1d(steps))
    for r in fem_resolutions:
        tasks[("fem", r, steps[0])] = Task.make("fem", fem, r, steps_per_period=steps[0], **fem_opts)
    r = max(fem_resolutions)
    for n in steps[1:]:
        tasks[("fem", r, n)] = Task.make("fem", fem, r, steps_per_period=int(n), **fem_opts)
    return tasks


def _history(out: dict | None):
    """(time, mid-span displacement positive downward) of a run, or None."""
    if out is None or len(out.get("time", ())) < 3 or "midspan_displacement" not in out:
        return None
    return np.asarray(out["time"], float), np.asarray(out["midspan_displacement"], float)


def _moving_mean(t: np.ndarray, y: np.ndarray, width: float) -> np.ndarray:
    """The time mean of y (trapezoid, records t) over [t − width, t] at each t ≥ t₀ + width."""
    c = np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))])
    at = t[t >= t[0] + width - 1e-12]
    return (np.interp(at, t, c) - np.interp(at - width, t, c)) / width


def slow_comparison(runs: dict, window: str = "half") -> dict:
    """The slow impact's check from its runs {key of :func:`slow_impact_tasks`: output}.

    Window: [0, t½], t½ where the finest FEM's mid-span displacement first returns to zero after its
    peak (interpolated between records); ``window='quarter'``: [0, t¼], t¼ the record of the FEM's
    peak (the run must go on past it). On a common axis of :data:`SLOW_N_TIME` points over it: both
    histories (``csph``, ``fem``: the finest mesh at the most steps), every rung's (``rungs`` {key:
    history}), and ``error`` = max |w_csph − w_FEM| / max w_FEM; the FEM's own ``fem_mesh_error``
    (the finest mesh against the next, at the most steps both ran) and ``fem_time_error`` (the
    finest mesh at its most steps against its next fewer), the same norm. The particle run's
    contact: ``zero_force_fraction`` (records of the window with no impact force: the chatter),
    ``min_mean_force`` (the smallest :data:`SLOW_MEAN_WINDOW` mean of the impact force over the
    window, over its mean: > 0 means the weight stays pressed on the plate on average),
    ``min_mean_support`` (the same for the supports' reaction, from its first arrival),
    ``separation`` (the first record from which the impact force stays zero, s); ``max_damage``
    (mortar) and ``max_plastic_strain`` (mortar and steel) at the end of the particle run;
    ``peak_csph``, ``peak_fem`` (m), ``status`` and ``wall_time`` per run."""
    from workbench.materials import HIST_EPS_P
    from workbench.materials.mortar import H_DAMAGE, H_EPS_P

    nan = math.nan
    keys = sorted(runs, key=str)
    out = dict(status={k: str(runs[k].get("status", "error: no status")) for k in keys},
               wall_time={k: float(runs[k].get("run_wall_time", runs[k].get("wall_time", nan)))
                          for k in keys},
               error=nan, fem_mesh_error=nan, fem_time_error=nan, window_end=nan, peak_csph=nan,
               peak_fem=nan, zero_force_fraction=nan, min_mean_force=nan, min_mean_support=nan,
               separation=nan, max_damage=nan, max_plastic_strain=nan, time=np.zeros(0),
               csph=np.zeros(0), fem=np.zeros(0), rungs={})
    fem_keys = [k for k in keys if k[0] == "fem"]
    if not fem_keys:
        return out
    top = max(fem_keys, key=lambda k: (k[1], k[2]))
    ref = _history(runs[top])
    if ref is None:
        return out
    tf, wf = ref
    if window not in ("half", "quarter"):
        raise ValueError(f"window: {window!r} is not one of 'half', 'quarter'")
    i = int(np.argmax(wf))
    down = np.flatnonzero((wf[i:-1] > 0) & (wf[i + 1:] <= 0))
    if window == "quarter":
        if i >= len(wf) - 1:
            return out
        t_half = float(tf[i])
    elif not len(down):
        return out
    else:
        j = i + int(down[0])
        t_half = float(tf[j] + wf[j] * (tf[j + 1] - tf[j]) / (wf[j] - wf[j + 1]))
    time = np.linspace(0.0, t_half, SLOW_N_TIME)
    fem = np.interp(time, tf, wf)
    peak = float(np.max(fem))
    out.update(window_end=t_half, time=time, fem=fem, peak_fem=peak)
    for k in fem_keys:
        h = _history(runs[k])
        if h is not None and h[0][-1] >= t_half:
            out["rungs"][k] = np.interp(time, *h)

    def dist(a, b):
        return float(np.max(np.abs(a - b)) / peak)

    rungs = out["rungs"]
    for n in sorted({k[2] for k in rungs}, reverse=True):
        meshes = sorted(k for k in rungs if k[2] == n)
        if len(meshes) > 1:
            out["fem_mesh_error"] = dist(rungs[meshes[-2]], rungs[meshes[-1]])
            break
    times = sorted(k for k in rungs if k[1] == top[1] and k[2] < top[2])
    if times:
        out["fem_time_error"] = dist(rungs[times[-1]], fem)
    pk = [k for k in keys if k[0] != "fem"]
    h = _history(runs[pk[0]]) if pk else None
    if h is None or h[0][-1] < t_half or not np.isfinite(h[1]).all():
        return out
    p = runs[pk[0]]
    csph = np.interp(time, *h)
    t = h[0]
    F = np.asarray(p["impact_force"], float)
    win = t <= t_half
    on = np.flatnonzero(F > 0)
    mean_F = _moving_mean(t[win], F[win], SLOW_MEAN_WINDOW)
    R = np.asarray(p.get("support_reaction_mean", np.zeros_like(t)), float)
    first = np.flatnonzero((R > 0) & win)
    sup = t[win] >= (t[first[0]] if len(first) else np.inf)
    mean_R = _moving_mean(t[win][sup], R[win][sup], SLOW_MEAN_WINDOW) if sup.sum() > 2 else []
    out.update(csph=csph, peak_csph=float(np.max(csph)), error=dist(csph, fem),
               zero_force_fraction=float(np.mean(F[win] <= 0)),
               min_mean_force=float(np.min(mean_F) / np.mean(F[win])) if len(mean_F) else nan,
               min_mean_support=float(np.min(mean_R) / np.mean(R[win][sup]))
               if len(mean_R) else nan,
               separation=float(t[on[-1] + 1]) if len(on) and on[-1] + 1 < len(t) else nan)
    if "history" in p and "region" in p:
        hist, reg, names = np.asarray(p["history"]), np.asarray(p["region"]), list(p["region_names"])
        mortar = reg == names.index("mortar")
        steel = ~mortar & (reg != names.index("weight"))
        out["max_damage"] = float(np.max(hist[mortar, H_DAMAGE]))
        out["max_plastic_strain"] = float(max(np.max(hist[mortar, H_EPS_P]),
                                              np.max(hist[steel, HIST_EPS_P])))
    return out


def slow_impact(scene: RCBeam | None = None, fem_resolutions=SLOW_FEM_RESOLUTIONS,
                steps=SLOW_FEM_STEPS, resolution: int = SLOW_RESOLUTION,
                scheduler: str | None = None) -> dict:
    """Gate 2's slow impact on its own: the runs of :func:`slow_impact_tasks` (cached like every
    run) and their :func:`slow_comparison`."""
    tasks = slow_impact_tasks(slow_impact_scene(scene), fem_resolutions, steps, resolution)
    done = run_tasks(list(tasks.values()), scheduler, NAME)
    return slow_comparison(dict(zip(tasks, done)))


def _slow(ds, scene: RCBeam, slow: dict | None) -> None:
    """The slow impact's variables (``slow_*``): both histories on the window's time axis, the
    FEM's rungs, the errors and the contact checks."""
    if not slow:
        return
    c = slow_comparison(slow)
    labels = [f"{k[0]} H/dx={k[1]}" + (f" {k[2]} steps/period" if k[0] == "fem" else "")
              for k in sorted(slow, key=str)]
    ds.coords["slow_time"] = ("slow_time", c["time"], {
        "units": "s", "long_name": "slow impact: time over the first half period"})
    ds.coords["slow_run"] = ("slow_run", labels)
    lad = np.full((len(labels), len(c["time"])), np.nan)
    for n, k in enumerate(sorted(slow, key=str)):
        if k in c["rungs"]:
            lad[n] = c["rungs"][k]
    ds["slow_csph_displacement"] = ("slow_time", c["csph"] if len(c["csph"]) else
                                    np.full(len(c["time"]), np.nan), {
        "units": "m", "long_name": f"slow impact ({SLOW_SPECIMEN}, {SLOW_VELOCITY} m/s): csph's "
        "mid-span displacement, positive downward"})
    ds["slow_fem_displacement"] = ("slow_time", c["fem"], {
        "units": "m", "long_name": "slow impact: the FEM's mid-span displacement (finest rung)"})
    ds["slow_fem_rungs"] = (("slow_run", "slow_time"), lad, {
        "units": "m", "long_name": "slow impact: every FEM run's mid-span displacement"})
    ds["slow_status"] = ("slow_run", np.array([c["status"][k] for k in sorted(slow, key=str)]),
                         {"units": "-"})
    ds["slow_wall_time"] = ("slow_run", np.array([c["wall_time"][k] for k in sorted(slow, key=str)]),
                            {"units": "s", "long_name": "run wall time, set-up included"})
    for k, u, ln in (("error", "-", "max |w_csph - w_FEM| over the window / the FEM's peak"),
                     ("fem_mesh_error", "-", "the FEM's finest mesh against the next, same norm"),
                     ("fem_time_error", "-", "the FEM's finest against half its steps, same norm"),
                     ("window_end", "s", "end of the window: the FEM's return to zero"),
                     ("peak_csph", "m", "csph's largest mid-span displacement in the window"),
                     ("peak_fem", "m", "the FEM's largest mid-span displacement"),
                     ("zero_force_fraction", "-", "records of the window without impact force"),
                     ("min_mean_force", "-", f"smallest {SLOW_MEAN_WINDOW * 1e3:g} ms mean of the "
                      "impact force in the window over its mean (> 0: pressed on average)"),
                     ("min_mean_support", "-", "the same of the supports' reaction"),
                     ("separation", "s", "the weight leaves the plate (impact force zero from "
                      "then on)"),
                     ("max_damage", "-", "largest mortar damage at the end of csph's run"),
                     ("max_plastic_strain", "-", "largest plastic strain (mortar, steel)")):
        ds[f"slow_{k}"] = ((), float(c[k]), {"units": u, "long_name": ln})
    ds["slow_error"].attrs["tolerance"] = TOL_SLOW
    ds.attrs.update(slow_specimen=SLOW_SPECIMEN, slow_velocity=SLOW_VELOCITY,
                    slow_resolution=SLOW_RESOLUTION,
                    slow_estimated_stress=slow_impact_stress(slow_impact_scene(scene),
                                                             SLOW_VELOCITY))


def slow_gates(ds: xr.Dataset) -> list[Gate]:
    """Gate 2, second half: the slow impact's mid-span history within :data:`TOL_SLOW` of the
    FEM's over the first half period; in the particle run nothing cracked or yielded, and the
    weight and the supports stayed pressed on average (the FEM's idealisation)."""
    tag = (f"rc_beam {ds.attrs.get('slow_specimen', SLOW_SPECIMEN)} slow impact "
           f"({ds.attrs.get('slow_velocity', SLOW_VELOCITY):g} m/s, csph H/dx="
           f"{ds.attrs.get('slow_resolution', SLOW_RESOLUTION)})")
    return [Gate.at_most(f"{tag}: mid-span displacement against the FEM over the first half "
                         "period, max |difference| / peak", float(ds.slow_error), TOL_SLOW,
                         "issue 12 gate 2: 5 % (FEM's mesh and step, csph's stiffness at 12.5 mm, "
                         "the contact the FEM idealises: studies/rc_beam/slow_impact.py TOL_SLOW)",
                         "an implicit FEM of the same beam (27-node hexahedra, Newmark, the weight "
                         "a rigid mass): another discretisation and time integrator"),
            Gate.at_most(f"{tag}: largest mortar damage and plastic strain (nothing cracks or "
                         "yields)", max(float(ds.slow_max_damage), float(ds.slow_max_plastic_strain)),
                         0.0, "the elastic phase: exactly zero",
                         "the closed-form estimate of the bottom fibre's stress (slow_impact_stress: "
                         "a fifth of the mortar's strength)", defect=SLOW_DAMAGE_DEFECT)] + [
        Gate.expect(f"{tag}: {what} pressed over the window (smallest {SLOW_MEAN_WINDOW * 1e3:g} ms "
                    "mean of its contact force > 0)",
                    "pressed" if float(ds[var]) > 0 else "separated", "pressed",
                    "the FEM's idealisation (no contact: the weight a mass on the plate's face, "
                    "hinged supports) holds while the contact is compressive on average",
                    "the sign of the run's own contact force")
        for what, var in (("the weight", "slow_min_mean_force"),
                          ("the supports", "slow_min_mean_support"))]


def slow_note(ds: xr.Dataset) -> str:
    """The slow impact's report row."""
    v = {k: float(ds[f"slow_{k}"]) for k in ("error", "fem_mesh_error", "fem_time_error",
                                              "window_end", "peak_csph", "peak_fem",
                                              "zero_force_fraction", "min_mean_force",
                                              "min_mean_support", "separation", "max_damage",
                                              "max_plastic_strain")}
    return (f"{ds.attrs.get('slow_specimen')}, slow impact at {ds.attrs.get('slow_velocity'):g} m/s "
            f"(estimated bottom stress {ds.attrs.get('slow_estimated_stress', math.nan) / 1e6:.2g} "
            f"MPa): mid-span displacement csph (H/dx = {ds.attrs.get('slow_resolution')}) against the "
            f"FEM over the first half period (0–{v['window_end'] * 1e3:.3g} ms): max |difference| "
            f"{100 * v['error']:.2f} % of the peak (csph {v['peak_csph'] * 1e6:.4g} µm, FEM "
            f"{v['peak_fem'] * 1e6:.4g} µm); the FEM's own error: mesh {100 * v['fem_mesh_error']:.2f} %, "
            f"step {100 * v['fem_time_error']:.2f} %. Contact in csph's run: no impact force at "
            f"{100 * v['zero_force_fraction']:.0f} % of the records (chatter), its "
            f"{SLOW_MEAN_WINDOW * 1e3:g} ms mean at least {v['min_mean_force']:.2f} of its mean, the "
            f"supports' {v['min_mean_support']:.2f}; the weight leaves at {v['separation'] * 1e3:.4g} ms; "
            f"damage {v['max_damage']:.2g}, plastic strain {v['max_plastic_strain']:.2g}.")
