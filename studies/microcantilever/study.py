"""Micro-cantilever study: inter- and intra-granular fracture of a ceramic micro-cantilever with five
Voronoi grains and four grain boundaries (paper 000 §4–5, Fig. 5–6; the scene is
:class:`.scene.MicroCantilever`, its choices in :mod:`.scene`).

Each case (``inter``: ε_L = 0.002 on the grain boundaries; ``intra``: in the grains) runs with
CSPH under a failure rule — ``compression`` (the default: a failed particle keeps a compressive
volumetric response) or ``literal`` (stress zero) — both with the visibility criterion of
:mod:`sph.crack`, and, in the full run, ``compression`` without it (``none``: the pairs never
change), which shows why the criterion is there, and, on a ladder, ``regularised`` (``compression``
with the crack band of :func:`.scene.crack_band_limit`). Stored per run: the
load–deflection curve at the loading patch, the failed fraction per region over time, the energies
over time (external work, kinetic, elastic, plastic work, released by failure and cracking), the
energy of the main crack, and the final particles (for the figure of the cracked cantilevers, as
Fig. 5 and 6).

Before the first failure a 2-D run has a reference: the static FEM of the same grains, boundaries
and materials (:func:`fem_ladder`: 9-node quadrilaterals, plane strain, J2 with Swift per
element, the patch pushed down rigidly) on a ladder of meshes, its elastic slope extrapolated at
the order of the re-entrant corners (:data:`SINGULAR_ORDER`); gate 1 checks the csph slope
against it (:func:`fem_gates`). The load at the first failure anywhere is reported, not gated: it
is at the edges of the rigid patch or at the re-entrant corner, singular points, and its load falls
with the spacing in both methods. Gate 2 (the full 2-D run) gates the load at the first failure in
:func:`root_region` — the tension half of the root half, where the bending stress is largest and
no singular point lies — which converges on the FEM's ladder; csph's comes from static runs on
the FEM's path (:func:`csph_static`; the dynamic runs fail first at the singular points)
(:func:`root_gates`), at the run's resolutions and at H/Δx = 40 (:data:`STATIC_FINEST`), where
the issue's bounds at the finest resolution — elastic slope within 1 %, load at the first failure
within 3 % — are gated as written (:func:`finest_gates`). Gate 6 (the full 2-D run, shown, not
gated): the same scene by the FEM with element deletion (:func:`fem_deletion`), its load beside
csph's and its deleted elements beside the failed particles, with their share where the low ε_L
is. Gate 5 (:func:`band_gates`): the energy the main crack takes to cut the body
(:func:`fracture_energy`, at the record of the cut) falls with the spacing under the literal ε_L
and stays within 10 % across the ladder under the crack band (rule ``regularised``,
:data:`BAND`). The other gates are the
checks the physics and the paper's robustness claim allow without a reference (:func:`gates`).
2-D runs are plane strain (csph has no plane stress); ``--quick`` runs the 2-D variant at
H/Δx = 5, the full run the scene's own dimension (3-D by default, integration-consistent as in
2-D, :data:`OPTIONS_3D`; gate 1 there against the 3-D FEM of :data:`FEM_RESOLUTIONS_3D`, a ladder of three
hexahedral meshes, the finer two at their elastic first point only, with csph's static elastic
slopes on a ladder of their own, :data:`STATIC_RESOLUTIONS_3D` — the observed order and the 1 %
at the finest (:func:`static_slope_gates`); gates 2 and 5 need a 2-D ladder: ``--set dim=2``;
gate 2 of the 3-D scene, hours on 2 cores, is :func:`root_ladder`, apart from the default run).
"""
from __future__ import annotations

import dataclasses
import functools

import numpy as np
import xarray as xr

from workbench import results
from .scene import MicroCantilever

from ..common import Gate, check_resolutions, observed_order
from ..sweep import Task, run_tasks

NAME = "microcantilever"
SCENE = MicroCantilever
SOLVERS = ("csph",)
RESOLUTIONS = {"csph": (5, 10, 15, 20)}
"""Particles across H of a 2-D run (``--set dim=2``): the ladder of gates 1, 2 and 5 (the rules
outside LADDER_RULES stop at H/Δx = 10). Gate 5 takes the runs whose crack band is wider than the
spacing (:func:`band_ladder`: H/Δx = 10, 15, 20 with the 1 µm band; at 5 the band is one spacing
and the regularised run is the ``compression`` one), so the ladder holds three of them."""
RESOLUTIONS_3D = (5,)
"""Particles across H of the 3-D run (the default): 1776 particles; the cases cut apart at 1.36 µs
(inter) and 1.04 µs (intra) and stop 1.5 µs later (t_after), 59 k and 52 k steps, 63 s and 98 s on
one thread (integration-consistent, the other core busy); H/Δx = 10 has eight times the particles
and twice the steps."""
QUICK_RESOLUTIONS = {"csph": (5,)}
QUICK_DIM = 2
"""``--quick``: the 2-D (plane-strain) variant at H/Δx = 5 — two runs of about 8 s each on one
core."""
CASES = ("inter", "intra")
RULES = {"compression": ("compression", "visibility"), "literal": ("literal", "visibility"),
         "no_crack_rule": ("compression", "none"), "regularised": ("compression", "visibility")}
"""Rule name -> (failure mode of the J2 law, ``crack`` option of csph). ``regularised`` is
``compression`` with the low ε_L tied to a crack band of width :data:`BAND` (the scene's ``band``
when that is set; :func:`.scene.crack_band_limit`)."""
QUICK_RULES = ("compression",)
GATED_RULES = ("compression", "literal", "regularised")
LADDER_RULES = ("compression", "regularised")
"""The rules run at every resolution of a ladder (gate 5 compares them); the others only up to
:data:`MAX_OTHER_RESOLUTION` (their runs at H/Δx = 20 cost 5–10 minutes each)."""
MAX_OTHER_RESOLUTION = 10
BAND = 1.0e-6
"""Crack-band width of the ``regularised`` rule, m: the grain-boundary thickness, one spacing at
H/Δx = 5 (there ε_L is the paper's own)."""
OPTIONS_3D = {}
"""csph options of 3-D runs: none — the integration-consistent correction, as in 2-D. It needs
every face of the body on a lattice plane (:func:`sph.csph.off_lattice_share`); the scene's block
reaches ``block_margin`` = 5 µm beyond the beam's side faces, which puts them there at every
H/Δx. (With the block B/2 beyond them, as before, they fell half a spacing between the planes at
odd H/Δx: the correction grew to ten times the gradients, the critical step to 0.016 of the CFL
estimate, the elastic slope 27 % too stiff at H/Δx = 5, and the study ran nodal integration.)
Measured at H/Δx = 5 (3-D, one thread): critical step 2/ω_max 0.87 of the CFL estimate Δx/c_p
(nodal 0.66); static elastic slope 8.80 and 8.48 kN/m at H/Δx = 5 and 10, +5.7 and +1.8 % from
the 3-D FEM's limit 8.33 kN/m (the FEM itself +5.4 and +2.6 %), nodal integration 7.78 and
7.82 kN/m, −6.5 and −6.1 % (it hardly converges: the one-sided gradients at the faces are not
integration-consistent); the dynamic runs (compression rule) are stable, their energy balance
within 1.4e-3 (intra) and 2.1e-4 (inter) of the external work, 98 s and 63 s."""
FEM_RESOLUTIONS = (5, 10, 20, 40, 80)
"""Elements (9-node quadrilaterals, plane strain) across H of the FEM reference of a 2-D run; the
smallest is 5 (the grain boundary, 1 µm, must hold an element: H/h >= 5). The reference of the
static csph run at :data:`STATIC_FINEST` is the limit of the two finest. The ladder goes to 80
(38 400 elements, 4 minutes on one core along the root path) because the inter case's load at
the first failure, read where the geometry puts each point (:func:`fem_static`), converges at
first order from above: 206.4, 192.9, 185.3, 181.8, 180.5 N/m at H/h = 5 to 80, and at 40 the FEM
is 1.8 % from the limit of 20 and 40, more than half the 3 % it checks; at 80 it is 0.6 % from the
limit of 40 and 80, which is within 0.4 % of the former."""
STATIC_FINEST = 40
"""Gate 2's static csph runs (the full 2-D run) are at the run's resolutions and at H/Δx =
STATIC_FINEST, where the issue's bounds at the finest resolution are checked: the elastic slope
within 1 % and the load at the first failure within 3 % of the FEM's limit (:func:`finest_gates`).
9600 particles, about 3.5 minutes on one core; the dynamic runs stop at H/Δx = 20 (a dynamic run
at 40 has 4 times the particles and twice the steps of one at 20, about an hour)."""
QUICK_FEM_RESOLUTIONS = (5, 10)
"""``--quick``: the two cheapest meshes (about 2 and 4 s)."""
STATIC_RESOLUTIONS_3D = (5, 10, 15)
"""Gate 1's ladder of static csph elastic slopes in the 3-D run (the first point of the FEM's
path, by Newton): 1776, 12 001 and 38 176 particles; 2 s, 41 s and 4.5 minutes on one core,
4.1 GB at 15. The Newton systems above 20 000 unknowns are solved by AMG-preconditioned CG
(:mod:`workbench.linear_systems`; the direct solve took 61 s per iteration at H/Δx = 10, where
AMG-CG takes 16 s, and did not finish at 15). They run after the FEM ladder, so that the two
largest jobs do not hold their memory at once. Measured: 8797.5, 8478.6 and 8395.6 N/m, +5.69,
+1.86 and +0.86 % from the FEM's limit; observed order of the error 1.7 (least squares), and
1.43 on the values alone (:func:`_order3`; their own limit 8286 N/m, 0.46 % below the FEM's)
(:func:`static_slope_gates`)."""
FEM_RESOLUTIONS_3D = (5, 10, 15)
FEM_FULL_PATH_3D = (5,)
"""Gate 1 of the 3-D run (the default): the FEM of the same 3-D grains and boundaries (27-node
hexahedra, J2 with Swift per element) at H/h = 5 along the whole static path to FEM_MAX·H (the
csph slope window and the first failures: 1250 elements, about 2 minutes on one core) and at
H/h = 10 and 15 at its first path point only, which is elastic (the slope: 10 000 and 33 750
elements, 2.5e5 and 8.4e5 unknowns, 2.5 and 5.7 minutes, 5.9 and 13.2 GB; the Newton systems by
AMG-preconditioned CG, :mod:`workbench.linear_systems` — the direct solve took 8 minutes and
12.6 GB at 10). The slope's limit is the Richardson limit of the two finest at
:data:`SINGULAR_ORDER` (the re-entrant edge where the beam meets its block is the 2-D corner
extruded, the same exponent); the three meshes observe the order. Measured: 8778.3, 8538.1 and
8461.7 N/m; observed order 1.08 (the singular order 1.09); limit 8324.1 N/m (8325.0 from the
5/10 pair)."""
FEM_STEP = 1e-3
FEM_MAX = 0.02
"""The FEM's static path: the patch pushed down in steps of FEM_STEP·H to FEM_MAX·H (5 nm to
0.1 µm), past the first failure of both cases on every mesh."""
FEM_MAX_ROOT = 0.06
ROOT_STEP = 4e-3
"""The static path of gate 2 (the full run): on from FEM_MAX·H in steps of ROOT_STEP·H (20 nm) to
FEM_MAX_ROOT·H = 0.3 µm, past the first failure in the root region of both cases in both methods
on every mesh (0.16–0.23 µm). The first-failure loads move by less than 0.07 % against steps of
5 nm throughout (FEM, H/h = 5 and 10), at half the cost."""
ROOT_LADDER_STEP = 4e-3
"""The path of :func:`root_ladder` (:func:`root_ladder_path`: the FEM's and the static csph's, in
2-D and 3-D): the elastic first point FEM_STEP·H, then steps of ROOT_LADDER_STEP·H (20 nm) towards
FEM_MAX_ROOT·H, each run stopped at the point where both cases have failed in the root region — a
quarter of the points of the full 2-D run's path, whose 20 steps of FEM_STEP·H cost a 3-D mesh as
much as the rest. Measured against that fine path (linear interpolation between points is second
order in the step): the first-failure loads move by 0.03 % (inter) and 0.11 % (intra) at H/h = 10
in 2-D, and by 0.06 % and 0.49 % at H/h = 5 in 3-D (measured before EDGE_CLEARANCE, when intra
failed at the edge at 0.10 µm, 0.02 H, where the fine path's steps are a quarter as long; with it,
at 0.15 µm) — the same on every mesh and in both methods, a fraction of gate 2's 3 %; steps twice
as long move intra by 1.9 % in 3-D."""
SINGULAR_ORDER = 2 * 0.5445
"""Order of convergence of the compliance (elastic slope) of a body with a re-entrant right-angle
corner (the root of the beam on its block, and the edge of the rigidly moved patch): the stress
there goes as r^(λ-1), λ = 0.5445 (Williams 1952, plane elasticity, 270° corner), and the energy
error as h^(2λ) (Strang & Fix §8.2) — for the FEM and for any consistent particle method alike.
The FEM ladder of this scene observes 1.15 (H/h = 5, 10, 20), csph's 1.03 (H/Δx = 5, 10, 20)."""
N_TIME = 301
ERROR_LABEL = "energy balance error |W_ext - (K + E + W_p + W_rel)| / W_ext, max over time [-]"

# Tolerances, each with its reason.
# Energy balance (issue 11, gate 2): velocity Verlet's discrete work equals the change of the
# energies to O(dt²) for smooth motion; a failure is a jump of stress within one step, which costs
# an error of the order of that particle's stored energy times a few steps' change — 1e-3 of the
# external work at most in the runs measured; 1 % is the issue's bound.
TOL_ENERGY = 0.01
# Where it breaks (gate 3): at least 80 % of the failed particles in the boundaries (inter) or in
# the grains (intra), the issue's bound.
MIN_SHARE = 0.8
# Quasi-static (gate 4): kinetic energy below 1 % of the elastic energy before the first failure,
# from the end of the velocity ramp (or half the time to the first failure, if later) to the first
# failure (quasi_static_start). Before that the ratio is the ramp's start-up transient, 4/(ω₁t)²,
# measured alike at every resolution (intra, H/Δx = 5, 10, 20: 1.12, 1.16, 1.19 % at 0.27 µs;
# 0.36–0.39 % at 0.47 µs): with the window "the second half of the time to the first failure"
# alone, the intra run at H/Δx = 20, whose first failure (at the loading patch's edge, a singular
# point) comes at 0.55 µs, read 1.13 % from 0.275 µs, inside the ramp.
TOL_QUASI_STATIC = 0.01
# Complete separation, "force back to zero" (issue 11): the mean load over the last 20 % of the run
# within 5 % of the peak load before the first failure. After separation the broken-off beam,
# carried by the loading patch, still vibrates: the load oscillates about zero with an amplitude
# of 10–25 % of that peak; its mean is below 2 % in the runs measured. Reported beside it, not
# gated: whether the loading patch and the held faces are still in one connected part of the body
# (sph.csph.CSPH.components: a chain of intact particles that still see each other) — a last
# ligament of one or two particles may carry a per cent of the load for a while.
TOL_SEPARATION = 0.05
TAIL = 0.2
# Gate 1, elastic slope against the FEM (issue 11: 1 %). The slope of every consistent
# discretisation of this scene converges at the singular order p = 2λ = 1.09 (SINGULAR_ORDER); the
# FEM's own ladder gives its error constant, e_FEM(h) = |S_FEM(h) − S_∞|/S_∞ with S_∞ its
# Richardson limit (6.0 % at H/h = 5). A 9-node element of size h has nodes h/2 apart, so the
# particles at Δx = H/r have the nodal density of the FEM at H/h = r/2, whose error is
# e(r) = e_FEM(r₀)(2r₀/r)^p (r₀ the coarsest FEM mesh): 12.8 % at H/Δx = 5, 6.0 % at 10, 2.8 % at
# 20, 1.3 % at 40. The tolerance of each dynamic run is max(1 %, e(r)); csph is at 8 % at H/Δx = 5
# and 3.4 % at 10 (a three-fold regression exceeds it). At the finest, the static csph run at
# H/Δx = 40 (STATIC_FINEST), the issue's 1 % is gated as written (finest_gates): csph is 0.33 %
# from the FEM's limit there (FEM H/h = 5, 10, 20, 40: 1.7560, 1.7008, 1.6777, 1.6663 GN/m², limit
# 1.6562, observed order 1.02, the limit 0.06 % from the one at that order). The error model asks
# 1.3 % there; the 1 % is the issue's, tighter than the model, which a three-fold regression
# (0.98 %) would just meet.
TOL_SLOPE = 0.01
# The reference's own error: its Richardson error estimate on the finest mesh at most half the
# tolerance it checks (the smallest e(r) of the csph runs).
FEM_SHARE = 0.5
N_GATES = {False: 27, True: 11}
"""Gates of the default run: the 3-D run (27, README) and ``--quick`` (2-D, H/Δx = 5: the FEM
ladder, the slope of each case, and four per case: 11). ``verify`` fails where fewer were
evaluated."""
FEM_REFERENCE = ("the FEM of the same grains (Q9 / 27-node hexahedra, scikit-fem): another "
                 "discretisation, sharing with csph the scene and the J2-plus-damage material code "
                 "(workbench.materials), which is checked apart against the closed-form Swift curve "
                 "and damage onset on the micro-cantilever's own materials "
                 "(tests/test_microcantilever_study.py::test_material_code_against_closed_form)")
# Gate 2 of the issue's gate 1, the load at the first failure (issue 11: 3 % at the finest). The
# first failure anywhere is at the edges of the rigidly moved patch or at the re-entrant corner
# under the root, singular points: its FEM load falls without a limit (H/h = 5, 10, 20: inter
# 144.7, 114.5, 91.6 N/m; intra 115.3, 79.1, 54.9). In root_region (the tension half of the root
# half: no singular point) it converges: H/h = 5, 10, 20, 40 inter 211.1, 190.4, 184.2, 183.0 and
# intra 188.1, 177.3, 172.1, 169.6 N/m (observed orders on the three finest 2.30 and 1.03;
# limits at the singular order 181.85 and 167.37, the finest mesh 0.61 % and 1.34 % from them,
# the limits 0.43 % and 0.12 % from those at the observed orders: limit_spread). Its error model
# is the slope's: e(r) = e_FEM(r₀) (2r₀/r)^p at the singular order (the corners pollute every
# point's stress at that order, and the points sampling the surface lie O(h) inside it), the
# tolerance max(3 %, e(r)): 34.2/16.1/7.6/3.6 % (inter) and 26.3/12.4/5.8/3.0 % (intra) at
# H/Δx = 5/10/20/40, where csph (static, no damage, on the FEM's path) is 23.1/11.6/4.4/1.15 %
# and 19.9/9.4/4.5/2.08 % high. At the finest, H/Δx = 40 (STATIC_FINEST), the issue's 3 % is
# gated as written (finest_gates): csph is within it, and a three-fold regression (3.4 %, 6.2 %)
# fails it. The dynamic runs fail first at the singular points, which changes what follows: csph's
# value comes from the static runs, the damage computed from ε_p as the FEM's.
TOL_FIRST_FAILURE = 0.03
# Gate 5, crack band (issue 11): the energy the main crack takes (fracture_energy) under the
# regularised rule within 10 % across the ladder (max/min - 1), the issue's bound. What it allows:
# the band keeps Δx·g(ε_L,eff) fixed (crack_band_limit), but the crack's path and its width in
# particles may change with the spacing, and the stored energy released at failure depends on the
# stress state, not only on ε_L (g takes the uniaxial value). Under the literal ε_L the same energy
# scales as Δx (Bažant & Belytschko 1985): reported with its fitted power of Δx, not gated.
# The gate takes the runs where the band is wider than the spacing (band_ladder): at b = Δx the
# regularised run is the compression one and tests nothing of the band.
# G is taken at the record where the crack cut the loading patch off from the held faces
# (fracture_energy; the driver's at_separation): what fails later is the broken-off piece's
# business — in the intra runs a particle of the block's top face beside the crack's mouth fails
# 1 µs after the cut, as the piece swings past — and would make G depend on t_after.
# Measured (the full 2-D study, `workbench run microcantilever --set dim=2`, band 1 µm, 2 cores,
# 31 min; every run of the two crack rules cut apart, sph.crack detaching one-particle
# ligaments), µJ/m at H/Δx = 5, 10, 15, 20: compression (literal ε_L) inter 4.99, 2.19, 1.65,
# 1.33 and intra 3.87, 2.19, 1.51, 1.15 (G ~ Δx^0.95 and ~Δx^0.87); regularised inter 4.45,
# 4.28, 4.63 (H/Δx = 10, 15, 20: 8.3 %) and intra 4.25, 4.38, 4.01 (9.0 %): both pass. The
# band's own value, b·g(ε_L)·H straight across the section, is 4.12 (gb01) and 4.01 µJ/m
# (grain 0): the runs are 8 %, 4 %, 12 % (inter) and 6 %, 9 %, 0 % (intra) above it. What they
# carry above it: the surface particles beside the crack's mouth (the whole top face near the
# root yields to D ≈ 0.9 before the first one there fails, so a neighbour follows), the crushed
# bottom corner and, where the crack steps sideways, the particle of the step — 2 to 3 particles
# more than a straight column at H/Δx = 10 and 15, 1 at 20 (13, 18, 22 against 11, 16, 21):
# a count that does not shrink with the spacing, an O(Δx) excess of G (half-volume surface
# particles: about n/(2r)), which the coarser runs carry; the crack particles themselves
# hold the band (W_p + W_rel ≈ V·g(ε_L,eff) each). A three-fold larger spread (25-27 %) fails.
# At the end of the run instead of at the cut (fracture_energy_end) intra is 4.42, 4.48, 4.01
# (11.7 %: fails); before the driver ran to separation and sph.crack detached ligaments (5 µs,
# 5/10/20): intra 5.42, 4.23, 3.82 (the runs at 10 and 20 still joined by a hinge particle).
TOL_BAND = 0.10


def scene_for(scene: MicroCantilever, case: str, rule: str) -> MicroCantilever:
    """The scene of one case and rule (its name too: the field series of each run its own)."""
    band = (scene.band or BAND) if rule == "regularised" else scene.band
    return dataclasses.replace(scene, case=case, failure=RULES[rule][0], band=band,
                               name=f"{NAME}_{case}_{rule}")


def rules_for(resolutions, quick: bool = False) -> list:
    """The failure rules of a run: the default alone with ``quick``; all of :data:`RULES` else,
    ``regularised`` only on a ladder (two resolutions or more: at one it is ``compression``
    with another ε_L)."""
    if quick:
        return list(QUICK_RULES)
    return [r for r in RULES if r != "regularised" or len(resolutions) >= 2]


def runs_rule(rule: str, resolution: int, resolutions) -> bool:
    """Whether ``rule`` runs at ``resolution``: the ladder rules at every one, the others up to
    MAX_OTHER_RESOLUTION (or at the coarsest of the ladder when that is finer)."""
    return (rule in LADDER_RULES or resolution <= MAX_OTHER_RESOLUTION
            or resolution == min(resolutions))


def static_resolutions(resolutions) -> list:
    """H/Δx of gate 2's static csph runs: the run's ``resolutions`` and :data:`STATIC_FINEST`."""
    return sorted({int(r) for r in resolutions} | {STATIC_FINEST})


def options_for(scene: MicroCantilever, rule: str) -> dict:
    opts = {"crack": RULES[rule][1]}
    if scene.dim == 3:
        opts.update(OPTIONS_3D)
    return opts


# ------------------------------------------------------------------------------------------------
# The FEM reference before the first failure (gate 1)
# ------------------------------------------------------------------------------------------------

def static_model(scene: MicroCantilever, spacing: float, path):
    """The scene's model at ``spacing`` as a static problem: the patch pushed down by the load
    parameter (the deflection, m) instead of moved at the scene's velocity, along ``path``; no
    damage (ε_L = 1 everywhere: D of either case is computed from ε_p afterwards, so the curve
    does not depend on the case)."""
    from workbench.scenes import model as M

    sc = dataclasses.replace(scene, eps_L_low=1.0, eps_L_high=1.0)
    model = sc.model(spacing)
    cons = tuple(dataclasses.replace(c, displacement=_down, velocity=None)
                 if isinstance(c, M.Prescribed) else c for c in model.constraints)
    return dataclasses.replace(model, constraints=cons,
                               drive=M.Static(tuple(float(v) for v in path), "deflection", "m"))


def _down(lam):
    return -lam


def static_path(scene: MicroCantilever, fem_max: float = FEM_MAX) -> np.ndarray:
    """The deflections of the static path, m: FEM_STEP·H, 2·FEM_STEP·H, … up to FEM_MAX·H, then
    on in steps of ROOT_STEP·H up to fem_max·H."""
    fine = FEM_STEP * np.arange(1, int(round(min(fem_max, FEM_MAX) / FEM_STEP)) + 1)
    n = int(round((fem_max - FEM_MAX) / ROOT_STEP))
    return scene.H * np.concatenate([fine, FEM_MAX + ROOT_STEP * np.arange(1, max(n, 0) + 1)])


def root_ladder_path(scene: MicroCantilever) -> np.ndarray:
    """The deflections of :func:`root_ladder`'s path (2-D and 3-D), m: FEM_STEP·H (elastic: the
    slope), then on in steps of ROOT_LADDER_STEP·H up to FEM_MAX_ROOT·H
    (:data:`ROOT_LADDER_STEP`)."""
    n = int(round((FEM_MAX_ROOT - FEM_STEP) / ROOT_LADDER_STEP))
    return scene.H * (FEM_STEP + ROOT_LADDER_STEP * np.arange(n + 1))


def _root_failed(damage_root: dict, k: int) -> bool:
    """Whether every case's damage in the root region has reached 1 at path point k (a static
    path that follows the root region's first failures stops there)."""
    return all(damage_root[c][k] >= 1.0 for c in CASES)


EDGE_CLEARANCE = 0.4
"""The 3-D root region (:func:`root_region`) leaves out the points closer than EDGE_CLEARANCE·H
(2 µm) to the re-entrant edges where the beam's side faces meet the block's face (x = 0,
y = ±B/2: the block reaches ``block_margin`` beyond them), singular lines of the 3-D scene that
the 2-D one does not have. With them in, the intra case failed first at their top end on every
mesh (FEM, H/h = 5: at (0.11, −2.39, 2.39) µm) and its FEM load fell by 17 % from H/h = 5 to 10
(0.725 to 0.599 mN), as at the patch's edges: no limit to check against. The first failure then
lies where the clearance ends, in the edge's decaying near field (ρ^(λ−1)), sampled at points
O(h) inside: 2 µm rather than 1 µm halves that field's gradient there (FEM, H/h = 5: intra fails
at (1.5, −1.0, 2.39) µm, ρ = 2.1 µm; inter in the first grain boundary, 2.1 µm from the root,
either way)."""


def root_region(scene: MicroCantilever, X) -> np.ndarray:
    """(N,) bool: the points X (N, d), m, where gate 2 looks for the first failure — the tension
    half of the beam's root half, 0 ≤ x ≤ L/2 and above the mid-plane. It holds the largest
    bending stress (the root, whose top face runs on flush with the block's: a smooth surface)
    and none of the singular points: the edges of the rigidly moved patch (x = 0.8 L and 0.9 L
    on the top face), the re-entrant corner under the root (x = 0, bottom face), the corners of
    the held faces (in the block, x < 0); in 3-D none within EDGE_CLEARANCE·H of the re-entrant
    edges of the side faces at the root (:data:`EDGE_CLEARANCE`)."""
    X = np.asarray(X)
    inside = (X[:, 0] >= 0.0) & (X[:, 0] <= 0.5 * scene.L) & (X[:, -1] > 0.0)
    if X.shape[1] == 3:
        rho = np.hypot(X[:, 0], 0.5 * scene.B - np.abs(X[:, 1]))  # distance to the nearer edge
        inside &= rho >= EDGE_CLEARANCE * scene.H * (1 - 1e-9)  # a lattice point at it is in
    return inside


def fem_static(scene: MicroCantilever, resolution: int, fem_max: float = FEM_MAX, path=None,
               until_root_failure: bool = False) -> dict:
    """The FEM (9-node quadrilaterals or 27-node hexahedra, J2 with Swift per grain and boundary,
    the scene's plane) of the scene at H/h = ``resolution`` along the static path of FEM_STEP·H
    up to fem_max·H (or along ``path``, m): ``deflection`` (m), ``load`` (N/m in 2-D, downward
    on the beam), ``damage`` {case: max over the quadrature points of ε_p/ε_L of that case, ε_L
    that of the region the scene's geometry puts the point in, not its element's (the mesh draws
    a slanted grain boundary as a staircase of elements, and inter's first failure followed the
    staircase's nearest step to the root, not the boundary: README)} and
    ``damage_root`` (the same over the points of :func:`root_region`) per path point (NaN where
    not reached), ``eps_p_max``, ``status``, ``wall_time``. ``until_root_failure``: stop once
    every case has failed in the root region."""
    import time

    from fem_reference.model import discretise, observe
    from fem_reference.static import load_path
    from workbench.materials import HIST_EPS_P

    t0 = time.perf_counter()
    h = scene.H / resolution
    path = static_path(scene, fem_max) if path is None else np.asarray(path, float)
    model = static_model(scene, h, path)
    fm = discretise(model, int(resolution))
    at = fm.point_regions()  # ε_L where the geometry puts each point, not its element's region
    limits = {c: region_limits(dataclasses.replace(scene, case=c), h, model)[at] for c in CASES}
    root = root_region(scene, fm.disc.Xq.reshape(-1, fm.disc.d))
    n = len(path)
    out = dict(deflection=path, load=np.full(n, np.nan), eps_p_max=np.full(n, np.nan),
               damage={c: np.full(n, np.nan) for c in CASES},
               damage_root={c: np.full(n, np.nan) for c in CASES})

    def record(k, lam, state):
        o = observe(fm, state, lam)
        out["load"][k] = -o["force"]
        ep = state.history[:, HIST_EPS_P]
        out["eps_p_max"][k] = ep.max()
        for c in CASES:
            D = ep / limits[c]
            out["damage"][c][k] = np.max(D)
            out["damage_root"][c][k] = np.max(D[root])
        return until_root_failure and _root_failed(out["damage_root"], k)

    recs, _ = load_path(fm.problem, path, callback=record,
                        max_increment=float(np.max(np.diff(np.r_[0.0, path]))))
    out["status"] = next((r["status"] for r in recs if not results.path_ok(r["status"])), "ok")
    out["wall_time"] = time.perf_counter() - t0
    out["n_elements"] = int(fm.disc.nel)
    return out


class _StaticScene:
    """The scene as a static problem (:func:`static_model`) for :func:`sph.driver.solve`."""

    def __init__(self, scene: MicroCantilever, path):
        self.scene, self.path, self.name = scene, tuple(float(v) for v in path), scene.name + "_static"

    def model(self, spacing=None):
        return static_model(self.scene, self.scene.H / 10 if spacing is None else spacing, self.path)

    def summarise(self, out):
        return {}


def csph_static(scene: MicroCantilever, resolution: int, fem_max: float = FEM_MAX_ROOT,
                path=None, until_root_failure: bool = False) -> dict:
    """csph (the study's options) on the static path of the FEM (:func:`static_model`, no
    damage; Newton, :mod:`sph.static`) at H/Δx = ``resolution``, to fem_max·H (or along ``path``,
    m; ``until_root_failure``: stopping once every case has failed in :func:`root_region`):
    ``deflection``, ``load``,
    ``eps_p_max`` (over all particles) and ``damage_root`` {case: max of ε_p/ε_L over the
    particles of :func:`root_region`} per path point, ``first_failure_root`` {case: (deflection,
    load)}, ``elastic_slope`` (the secant at the first path point, as the FEM's; NaN where it
    has yielded), ``status``, ``wall_time``."""
    import time

    from sph import driver
    from workbench.materials import HIST_EPS_P

    t0 = time.perf_counter()
    sc = dataclasses.replace(scene, band=0.0, name=f"{NAME}_static")
    path = static_path(sc, fem_max) if path is None else np.asarray(path, float)
    h = sc.H / resolution
    model = static_model(sc, h, path)
    seen = {}

    def on_record(body, run, lam):
        if "limits" not in seen:
            reg = run.ps.region
            seen["root"] = root_region(sc, run.ps.X)
            seen["limits"] = {c: region_limits(dataclasses.replace(sc, case=c), h, model)[reg]
                              for c in CASES}
            seen["D"] = {c: [] for c in CASES}
            seen["eps_p_max"] = []
        ep = body.field_state()["history"][:, HIST_EPS_P]
        seen["eps_p_max"].append(float(ep.max()))
        for c in CASES:
            seen["D"][c].append(float(np.max((ep / seen["limits"][c])[seen["root"]])))
        return until_root_failure and _root_failed(seen["D"], len(seen["eps_p_max"]) - 1)

    out = driver.solve("csph", _StaticScene(sc, path), int(resolution), on_record=on_record,
                       **options_for(sc, "compression"))
    status = out["status"] if isinstance(out["status"], str) else \
        next((s for s in out["status"] if not results.path_ok(s)), "ok")
    d, F = -np.asarray(out["deflection"]), -np.asarray(out["force"])
    D = {c: np.asarray(seen.get("D", {}).get(c, ()), float) for c in CASES}
    ff = {c: first_failure(d[:len(D[c])], F[:len(D[c])], D[c]) for c in CASES}
    ep = np.asarray(seen.get("eps_p_max", ()), float)
    slope = float(F[0] / d[0]) if ep.size and ep[0] == 0 and d.size else float("nan")
    return dict(deflection=d, load=F, damage_root=D, eps_p_max=ep, first_failure_root=ff,
                elastic_slope=slope, status=status, wall_time=time.perf_counter() - t0)


# ------------------------------------------------------------------------------------------------
# Gate 6: the FEM with element deletion, the same scene
# ------------------------------------------------------------------------------------------------

FEM_DELETION_RESOLUTION = 5
"""Elements (9-node quadrilaterals, plane strain) across H of the FEM with element deletion (the
full 2-D run): the scene's own drive (the patch moved at the scene's velocity) by implicit
Newmark (:func:`fem_reference.dynamic.newmark`: a step in which Newton fails is cut), an
element deleted once a point's damage reaches 1 (``deletion='any'``). About 2.5 minutes per
case on one core; the crack is one element wide, H/5 = 1 µm, the grain boundary's thickness."""


def fem_deletion(scene: MicroCantilever, case: str,
                 resolution: int = FEM_DELETION_RESOLUTION) -> dict:
    """The FEM of ``case`` (the scene's ε_L, the ``compression`` scene) with element deletion at
    H/h = ``resolution``: ``time``, ``load`` (N/m, downward on the beam: the time mean over each
    output interval of the patch's reaction, inertia included), ``deflection_down`` (m), the
    deleted elements and their regions (:func:`deletion_summary`), ``status``, ``wall_time``."""
    from fem_reference.model import build, solve_model

    sc = scene_for(scene, case, "compression")
    out = solve_model(sc, int(resolution), deletion=True)
    fm = build(sc, int(resolution), deletion=True)
    names = [r.name for r in fm.model.regions]
    gone = np.asarray(out.get("deleted", ()), np.int64)
    res = dict(time=np.asarray(out.get("time", ()), float),
               load=np.asarray(out.get("load", ()), float),
               deflection_down=np.asarray(out.get("deflection_down", ()), float),
               status=str(out["status"]), wall_time=float(out["wall_time"]),
               centroids=fm.disc.centroids(), region=np.asarray(fm.region), region_names=names,
               deleted=gone)
    res.update(deletion_summary(case, names, np.asarray(fm.region), gone))
    return res


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


def region_limits(scene: MicroCantilever, spacing: float, model) -> np.ndarray:
    """ε_L of each region of ``model`` (its order) for the scene's case at ``spacing``."""
    grains, gb = scene.limits(spacing)
    return np.array([gb if r.name.startswith("gb") else grains[int(r.name[5:])]
                     for r in model.regions])


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
    |L(p) − L(q)|/|L(p)|, L the limit from the two finest meshes at p = SINGULAR_ORDER and at
    the order q observed on the three finest (:func:`_order3`). NaN below three meshes or where
    no order is observed (the differences change sign). It is the reference's own error where a
    computed value is checked against the limit rather than against a mesh (:func:`finest_gates`):
    the finest mesh's distance from the limit (``slope_error``, ``root_error``) is the error of
    that mesh, not of the limit."""
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


def fem_ladder(scene: MicroCantilever, resolutions, fem_max: float = FEM_MAX,
               full=None, root_path: bool = False) -> dict:
    """The FEM static runs at ``resolutions`` and what gate 1 needs: the elastic slope per mesh
    (the secant at the first path point, which is elastic), its Richardson limit, each mesh's
    error against it, the slope window of the csph curves (a quarter to all of the deflection at
    first yield on the finest mesh: the last path point with ε_p = 0), each case's first
    failure anywhere and in :func:`root_region` (``first_failure_root``, with its Richardson
    limit at the singular order, ``root_limit``, and each mesh's error against it,
    ``root_error``; gate 2), on the path to ``fem_max``·H. The FEM does not depend on the case,
    the failure rule, the crack band or the drive: one ladder per geometry and material set,
    computed once per process (read only). ``full``: the resolutions that run the whole path
    (default: all); the others run its first point only, which is elastic — their slope, and NaN
    beyond it (the 3-D ladder, :data:`FEM_FULL_PATH_3D`); the window is then the finest full
    run's. ``root_path`` (:func:`root_ladder`): the first failures in the root region come from runs
    along :func:`root_ladder_path` at every resolution, each stopped once both cases have failed
    there (``root_runs``); their first point gives the slope of the meshes not in ``full``."""
    base = dataclasses.replace(scene, case="inter", failure="compression", name=NAME,
                               dt_reference="cfl", dt_factor=0.3, band=0.0)
    res = tuple(sorted(int(r) for r in resolutions))
    full = res if full is None else tuple(sorted(int(r) for r in full))
    return _fem_ladder(base, res, float(fem_max), full, bool(root_path))


def _first_point_only(scene: MicroCantilever, r: int, fem_max: float, run=None) -> dict:
    """:func:`fem_static` at its first path point only (or the first point of ``run``, a run whose
    path starts there), padded with NaN to the whole path's length."""
    run = dict(fem_static(scene, r, FEM_STEP) if run is None else run)
    path = static_path(scene, fem_max)

    def pad(a):
        return np.r_[np.asarray(a, float)[:1], np.full(len(path) - 1, np.nan)]

    run.update(deflection=path, load=pad(run["load"]), eps_p_max=pad(run["eps_p_max"]),
               damage={c: pad(v) for c, v in run["damage"].items()},
               damage_root={c: pad(v) for c, v in run["damage_root"].items()})
    return run


@functools.lru_cache(maxsize=4)
def _fem_ladder(scene: MicroCantilever, res: tuple, fem_max: float = FEM_MAX,
                full: tuple | None = None, root_path: bool = False) -> dict:
    res = list(res)
    full = res if full is None else list(full)
    root_runs = {r: fem_static(scene, r, path=root_ladder_path(scene), until_root_failure=True)
                 for r in res} if root_path else None
    runs = {r: fem_static(scene, r, fem_max) if r in full else
            _first_point_only(scene, r, fem_max, None if root_runs is None else root_runs[r])
            for r in res}
    slopes = np.array([runs[r]["load"][0] / runs[r]["deflection"][0]
                       if runs[r]["eps_p_max"][0] == 0 else np.nan for r in res])
    fine = runs[max(full)]
    elastic = np.flatnonzero(fine["eps_p_max"] == 0)
    d_yield = float(fine["deflection"][elastic[-1]]) if elastic.size else np.nan
    limit = fem_slope_limit(res, slopes) if len(res) >= 2 else np.nan
    ff = {c: np.array([first_failure(runs[r]["deflection"], runs[r]["load"], runs[r]["damage"][c])
                       for r in res]) for c in CASES}
    rr = runs if root_runs is None else root_runs
    fr = {c: np.array([first_failure(rr[r]["deflection"], rr[r]["load"], rr[r]["damage_root"][c])
                       for r in res]) for c in CASES}
    root_limit = {c: fem_slope_limit(res, fr[c][:, 1]) if len(res) >= 2 else np.nan for c in CASES}
    return dict(resolutions=res, runs=runs, root_runs=root_runs, slopes=slopes, slope_limit=limit,
                slope_error=np.abs(slopes - limit) / abs(limit),
                slope_limit_spread=limit_spread(res, slopes),
                root_limit_spread={c: limit_spread(res, fr[c][:, 1]) for c in CASES},
                observed_order=_order3(res[-3:], slopes[-3:]) if len(res) >= 3 else np.nan,
                window=(0.25 * d_yield, d_yield), first_failure=ff, first_failure_root=fr,
                root_limit=root_limit,
                root_error={c: np.abs(fr[c][:, 1] / root_limit[c] - 1) for c in CASES},
                root_order={c: _order3(res[-3:], fr[c][-3:, 1]) if len(res) >= 3 else np.nan
                            for c in CASES})


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


def slope_tolerance(fem: dict, r: int) -> float:
    """max(TOL_SLOPE, e(r)): the error of a discretisation converging at the singular order with
    the nodal spacing H/r, e(r) = e_FEM(r₀)(2r₀/r)^p from the FEM's coarsest mesh r₀ (TOL_SLOPE)."""
    return _tolerance(fem["resolutions"][0], float(fem["slope_error"][0]), r)


def _tolerance(r0: int, e0: float, r: int) -> float:
    return max(TOL_SLOPE, e0 * (2 * r0 / r) ** SINGULAR_ORDER)


def quick_scene(scene: MicroCantilever) -> MicroCantilever:
    """The scene a ``--quick`` run takes: its 2-D variant (:data:`QUICK_DIM`)."""
    return dataclasses.replace(scene, dim=QUICK_DIM)


def default_resolutions(scene: MicroCantilever, quick: bool = False) -> dict:
    """The ladder a run of ``scene`` takes when none is given: the quick one, the 2-D one
    (:data:`RESOLUTIONS`) or the 3-D one (:data:`RESOLUTIONS_3D`)."""
    if quick:
        return QUICK_RESOLUTIONS
    return RESOLUTIONS if scene.dim == 2 else {"csph": RESOLUTIONS_3D}


def run(scene: MicroCantilever | None = None, solvers=None, resolutions=None, quick: bool = False,
        scheduler: str | None = None, fields=None, field_runs=None) -> xr.Dataset:
    """Run both cases under each failure rule at each resolution (``quick``: 2-D, the default
    rule, H/Δx = 5). ``fields`` (a folder): every run writes its particles as a ParaView series
    there (``field_runs``: only these (solver, resolution) pairs)."""
    scene = scene or SCENE()
    solvers = list(solvers or SOLVERS)
    for s in solvers:
        if s not in SOLVERS:
            raise ValueError(f"solver: {s!r} is not supported by {NAME}; allowed: {', '.join(SOLVERS)}")
    if quick:
        scene = quick_scene(scene)
    default = default_resolutions(scene, quick)["csph"]
    if isinstance(resolutions, dict):
        resolutions = resolutions.get("csph", default)
    res = check_resolutions(resolutions or default)
    for r in res:  # a grain boundary thinner than the spacing is bad input, not a failed run
        scene.model(scene.H / r)
    rules = rules_for(res, quick)
    tasks, keys = [], []
    for case in CASES:
        for rule in rules:
            sc = scene_for(scene, case, rule)
            for r in res:
                if not runs_rule(rule, r, res):
                    continue
                sc.model(scene.H / r)  # a crack band too narrow for the spacing: bad input
                opts = options_for(sc, rule)
                if fields is not None and (field_runs is None or ("csph", r) in set(field_runs)):
                    opts["fields"] = str(fields)
                tasks.append(Task.make("csph", sc, r, **opts))
                keys.append((case, rule, r))
    # gate 1's reference: the FEM ladder of the same grains — in 2-D after the runs, in 3-D
    # (minutes, one core) in a process of its own while the particle runs go on
    fem3d = _Background(fem_ladder, scene, FEM_RESOLUTIONS_3D, FEM_MAX, FEM_FULL_PATH_3D) \
        if scene.dim == 3 else None
    fem_failed = None
    try:
        outs = dict(zip(keys, run_tasks(tasks, scheduler, NAME)))
        if fem3d is not None:
            try:
                fem = fem3d.result()
            except BackgroundFailed as err:  # the particle runs are kept; gate 1 says why it has none
                fem, fem_failed = None, str(err)
        else:
            fem = fem_ladder(scene, QUICK_FEM_RESOLUTIONS if quick else FEM_RESOLUTIONS,
                             FEM_MAX if quick else FEM_MAX_ROOT)
    finally:
        if fem3d is not None:
            fem3d.close()
    # gate 2's csph: the static runs on the FEM's path (the full 2-D run); in 3-D the ladder of
    # elastic slopes, gate 1's observed order (the root region's first failures in 3-D:
    # root_ladder, hours on 2 cores)
    if quick:
        static = None
    elif scene.dim == 2:
        static = {r: csph_static(scene, r) for r in static_resolutions(res)}
    else:
        static = {r: csph_static(scene, r, fem_max=FEM_STEP) for r in STATIC_RESOLUTIONS_3D}
    # gate 6: the FEM with element deletion beside the particles (the full 2-D run)
    deletion = {c: fem_deletion(scene, c) for c in CASES} if scene.dim == 2 and not quick else None
    ds = dataset(scene, outs, rules, res, fem, static, deletion)
    if fem_failed is not None:
        ds.attrs["fem_reference_failed"] = f"3-D FEM ladder H/h = {FEM_RESOLUTIONS_3D}: {fem_failed}"
    if fields is not None:
        from pathlib import Path

        from workbench.fields import series_name

        written = [f"{series_name(t.scene.name, t.solver, t.resolution)}.pvd" for t in tasks
                   if t.writes_fields]
        ds.attrs["field_series"] = ", ".join(n for n in written if (Path(fields) / n).exists())
    return ds


def root_ladder(scene: MicroCantilever | None = None, resolutions=FEM_RESOLUTIONS_3D,
                fem_resolutions=None) -> xr.Dataset:
    """Gate 2 of the 3-D scene, apart from the default run: the FEM ladder (27-node hexahedra in
    3-D) and static csph at the same ``resolutions`` along :func:`root_ladder_path`, each stopped at
    the root region's last first failure, in a dataset without particle runs whose :func:`gates`
    are gate 1's static slopes and gate 2's (the elastic slope, the load at the first failure in
    :func:`root_region`, their observed orders). Hours on 2 cores in 3-D: at H/h = 10 the FEM's
    path takes about 20 minutes and csph's 7, at 15 the FEM's 53 minutes (11 GB) and csph's 44
    minutes (3.7 GB). ``fem_resolutions``: the FEM's ladder where it is not the same (the 2-D
    one goes a mesh further: :data:`FEM_RESOLUTIONS`). ``workbench run microcantilever_root``
    runs it (:mod:`studies.microcantilever_root`)."""
    scene = scene or SCENE()
    res = tuple(sorted(int(r) for r in resolutions))
    fres = res if fem_resolutions is None else tuple(sorted(int(r) for r in fem_resolutions))
    fem = fem_ladder(scene, fres, FEM_MAX, fres[:1], root_path=True)
    static = {r: csph_static(scene, r, path=root_ladder_path(scene), until_root_failure=True)
              for r in res}
    return dataset(scene, {}, ["compression"], [res[0]], fem, static)


class _Background:
    """``fn(*args)`` in a process of its own (spawned, daemonic: it ends with this one):
    :meth:`result` waits for it — or raises :class:`BackgroundFailed` (one line) when the process
    ends without a result (killed for memory, say) or ``fn`` raised; :meth:`close` ends it."""

    POLL = 1.0  # s between looks at whether the process is still there

    def __init__(self, fn, *args):
        import multiprocessing

        ctx = multiprocessing.get_context("spawn")
        self.conn, child = ctx.Pipe(duplex=False)
        self.process = ctx.Process(target=_background_call, args=(child, fn, args), daemon=True)
        self.process.start()
        child.close()

    def result(self):
        while not self.conn.poll(self.POLL):  # a result, or the end of the pipe when it died
            if not self.process.is_alive() and not self.conn.poll(0):
                break
        try:
            ok, value = self.conn.recv()
        except (EOFError, OSError):
            self.process.join(10 * self.POLL)
            code = self.process.exitcode
            why = (f"killed by signal {-code}{': out of memory?' if code == -9 else ''}"
                   if code is not None and code < 0 else f"exit status {code}")
            raise BackgroundFailed(f"the process ended without a result ({why})") from None
        if not ok:
            raise BackgroundFailed(value)
        return value

    def close(self):
        if self.process.is_alive():
            self.process.terminate()
        self.process.join()
        self.conn.close()


class BackgroundFailed(RuntimeError):
    """A :class:`_Background` job that gave no result (the reason, one line)."""


def _background_call(conn, fn, args):
    try:
        conn.send((True, fn(*args)))
    except Exception as err:  # the reason travels back; the study records it
        conn.send((False, f"{type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''}"))
    finally:
        conn.close()


SERIES = {"load": ("load", "N", "force of the loading patch on the beam, downward (N/m in 2-D)"),
          "deflection": ("deflection_down", "m", "mean downward displacement of the loading patch"),
          "external_work": ("external_work", "J", "work of the prescribed motion (J/m in 2-D)"),
          "kinetic_energy": ("kinetic_energy", "J", "kinetic energy"),
          "elastic_energy": ("strain_energy", "J", "stored (elastic) energy"),
          "plastic_work": ("plastic_work", "J", "plastic work"),
          "released_energy": ("released_energy", "J", "stored energy released by failure and cracking")}
FAILED = {"all": "failed", "grains": "failed_grains", "boundaries": "failed_gb"}


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


def quasi_static_start(t_first: float, scene: MicroCantilever) -> float:
    """Start of gate 4's window, s, which ends at the first failure ``t_first``: the end of the
    velocity ramp or half the time to the first failure, whichever is later (the second half
    alone where the first failure comes within the ramp). Before it the ratio K/E is the
    start-up transient of the ramp, 4/(ω₁t)² for a beam of first frequency ω₁ whose end moves at
    v₀t/T (K = ½m v², E = ½k d², d = v₀t²/(2T)): the same at every resolution and above 1 % before
    t = 20/ω₁ (about 0.3 µs here), whatever the loading rate after the ramp
    (:data:`TOL_QUASI_STATIC`)."""
    t_ramp = float(getattr(scene, "t_ramp", 0.0))
    return max(0.5 * t_first, t_ramp) if t_ramp < t_first else 0.5 * t_first


def fragment_measures(out: dict, scene: MicroCantilever) -> dict:
    """What the failed particles carry at the end of the run (issue 36): ``fragment_speed_max``,
    their largest speed, m/s, and ``fragment_kinetic_share``, their kinetic energy Σ ½ ρ V |v|²
    (V the volumes of the run's work) over the energy released by cracking (the run's
    ``released_energy`` at its end). NaN without velocities, volumes or failed particles.
    Reported, not gated: the issue asks for below 5× the loading speed and below 5 %; measured
    (2-D, H/Δx = 5) 4.9 and 6.8 m/s and 4.2 and 11.3 % under the compression rule, 1.8 and 2.1 m/s
    and 1.0 and 1.25 % under the literal one (inter, intra) — and the intact particles of the
    broken-off piece themselves move at a median 1.2–1.3 m/s, up to 4–7 m/s, at the end (the
    energy released by brittle failure rings in an undamped body), so a failed particle moving
    with the body would not meet 5× the loading speed either."""
    nan = float("nan")
    v, V = out.get("v"), out.get("volume")
    failed = np.asarray(out.get("failed_particles", ()), bool)
    released = np.asarray(out.get("released_energy", [nan]), float)[-1]
    if v is None or V is None or not failed.any():
        return dict(fragment_speed_max=nan, fragment_kinetic_share=nan)
    speed = np.linalg.norm(np.asarray(v)[failed], axis=1)
    ke = 0.5 * scene.rho * float(np.asarray(V, float)[failed] @ speed ** 2)
    return dict(fragment_speed_max=float(speed.max()),
                fragment_kinetic_share=ke / released if released > 0 else nan)


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
    W = np.asarray(out["external_work"])
    E = (np.asarray(out["kinetic_energy"]) + np.asarray(out["strain_energy"])
         + np.asarray(out.get("plastic_work", 0 * t)) + np.asarray(out.get("released_energy", 0 * t)))
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
    s.update(fragment_measures(out, scene))
    if resolution is not None:
        G, G_all, n = fracture_energy(out, scene.H / resolution)
        s.update(fracture_energy=G, fracture_energy_all=G_all, n_crack=n,
                 fracture_energy_end=fracture_energy(out, scene.H / resolution, at="end")[0])
    return s


PLANE_3D = "none (3-D)"
"""The dataset's ``plane`` attribute in 3-D."""


def dataset(scene, outs: dict, rules, res, fem: dict | None = None,
            static: dict | None = None, deletion: dict | None = None) -> xr.Dataset:
    """The study's dataset from the runs ``outs`` {(case, rule, resolution): driver output} and
    the FEM reference ``fem`` (:func:`fem_ladder`, or None)."""
    time = np.linspace(0.0, scene.t_end, N_TIME)
    dims = ("solver", "case", "rule", "resolution")
    shp = (1, len(CASES), len(rules), len(res))
    series = {n: np.full(shp + (N_TIME,), np.nan) for n in SERIES}
    failed = np.full(shp + (len(FAILED), N_TIME), np.nan)
    scal = {}
    status = np.full(shp, "not run", dtype=object)
    wall = np.full(shp, np.nan)
    npart = np.zeros(shp, np.int64)
    steps = np.zeros(shp, np.int64)
    pss = np.full(shp, np.nan)
    finest = {}
    for (case, rule, r), out in outs.items():
        idx = (0, CASES.index(case), rules.index(rule), res.index(r))
        status[idx] = str(out.get("status", "error: no status"))
        wall[idx] = float(out.get("run_wall_time", out.get("wall_time", np.nan)))
        npart[idx] = int(out.get("n_particles", 0))
        steps[idx] = int(out.get("steps", 0))
        pss[idx] = float(out.get("particle_steps_per_second", np.nan))
        t = np.asarray(out.get("time", ()))
        if len(t) > 1:
            for n, (src, _, _) in SERIES.items():
                if src in out:
                    series[n][idx] = np.interp(time, t, np.asarray(out[src], float), right=np.nan)
            for j, src in enumerate(FAILED.values()):
                if src in out:
                    failed[idx + (j,)] = np.interp(time, t, np.asarray(out[src], float), right=np.nan)
        for k, v in run_summary(out, dataclasses.replace(scene, case=case), r).items():
            scal.setdefault(k, np.full(shp, "" if isinstance(v, str) else np.nan, dtype=object
                                       if isinstance(v, str) else float))[idx] = v
        if "x" in out and r >= finest.get((case, rule), (0, None))[0]:
            finest[(case, rule)] = (r, out)
    data = {n: (dims + ("time",), series[n], {"units": u, "long_name": ln})
            for n, (_, u, ln) in SERIES.items()}
    data["failed_fraction"] = (dims + ("part", "time"), failed, {
        "units": "-", "long_name": "fraction of the particles of the part whose damage reached 1"})
    data["status"] = (dims, status.astype(str), {"units": "-"})
    data["wall_time"] = (dims, wall, {"units": "s", "long_name": "run wall time, set-up included"})
    data["n_particles"] = (dims, npart, {"units": "-"})
    data["steps"] = (dims, steps, {"units": "-"})
    data["particle_steps_per_second"] = (dims, pss, {"units": "1/s", "long_name":
                                                     "particles x steps / time-loop wall time"})
    units = dict(peak_load="N", deflection_at_peak="m", t_first_failure="s", load_at_first_failure="N",
                 deflection_at_first_failure="m", elastic_slope="N/m", energy_balance_error="-",
                 kinetic_ratio="-", n_failed="-", share_boundaries="-", mean_tail_load="N",
                 tail_load_ratio="-", separated="-", connected="-", crack_regions="-",
                 released_final="J", fracture_energy="J", fracture_energy_all="J", n_crack="-",
                 fracture_energy_end="J", fragment_speed_max="m/s", fragment_kinetic_share="-",
                 t_separated="s", t_last="s")
    for k, arr in scal.items():
        if k == "separated":
            arr = arr.astype(float)
        data[k] = (dims, arr.astype(str) if k == "crack_regions" else arr, {"units": units[k]})
    coords = {"solver": ["csph"], "case": list(CASES), "rule": list(rules),
              "resolution": ("resolution", np.array(res), {"units": "-", "long_name":
                                                           "particles across H"}),
              "time": ("time", time, {"units": "s"}), "part": list(FAILED)}
    ds = xr.Dataset(data, coords=coords)
    ds.attrs["plane"] = "strain" if scene.dim == 2 else PLANE_3D
    if fem is not None:
        _fem_variables(ds, fem, outs, rules, res)
        if static:
            _static_variables(ds, fem, static)
            if scene.dim == 2 or fem.get("root_runs") is not None:  # 3-D: root_ladder's
                _root_variables(ds, fem, static)
    if deletion:
        _deletion_variables(ds, deletion)
    _final_particles(ds, finest, rules)
    ds.attrs.update(results.provenance(NAME, scene))
    ds.attrs["rules"] = "; ".join(f"{k}: failure {a}, crack {b}" for k, (a, b) in RULES.items()
                                  if k in rules)
    ds.attrs["seeds_um"] = str(np.round(scene.seeds() * 1e6, 3).tolist())
    return ds


def _deletion_variables(ds: xr.Dataset, deletion: dict) -> None:
    """Gate 6's variables: the load history of the FEM with element deletion on the dataset's
    time axis, and per case its status, deleted elements and their regions, and the reference
    centroids of the elements (``fem_element_X``, for the figure)."""
    time = ds.time.values
    load = np.full((len(CASES), len(time)), np.nan)
    defl = np.full((len(CASES), len(time)), np.nan)
    for i, c in enumerate(CASES):
        d = deletion[c]
        if len(d["time"]) > 1 and np.isfinite(d["load"]).any():
            ok = np.isfinite(d["load"])
            load[i] = np.interp(time, d["time"][ok], d["load"][ok], left=np.nan, right=np.nan)
            defl[i] = np.interp(time, d["time"], d["deflection_down"], right=np.nan)
    ds["fem_deletion_load"] = (("case", "time"), load, {
        "units": "N/m", "long_name": "FEM with element deletion: force of the loading patch on "
                                     "the beam, downward (time mean per output interval)"})
    ds["fem_deletion_deflection"] = (("case", "time"), defl, {
        "units": "m", "long_name": "FEM with element deletion: downward displacement of the patch"})
    ds["fem_deletion_status"] = (("case",), np.array([deletion[c]["status"] for c in CASES]),
                                 {"units": "-"})
    ds["fem_deletion_wall_time"] = (("case",), np.array([deletion[c]["wall_time"] for c in CASES]),
                                    {"units": "s"})
    ds["fem_deleted"] = (("case",), np.array([deletion[c]["n_deleted"] for c in CASES]),
                         {"units": "-", "long_name": "elements deleted"})
    ds["fem_deleted_share_low"] = (("case",), np.array([deletion[c]["share_low"] for c in CASES]), {
        "units": "-", "long_name": "share of the deleted elements where the low eps_L is"})
    ds["fem_deleted_regions"] = (("case",), np.array([deletion[c]["regions"] for c in CASES]),
                                 {"units": "-", "long_name": "deleted elements per region"})
    first = deletion[CASES[0]]
    ds["fem_element_X"] = (("fem_element", "dim"), np.asarray(first["centroids"]), {"units": "m"})
    ds["fem_element_region"] = (("fem_element",), first["region"], {
        "units": "-", "long_name": "region index into the attribute region_names"})
    dead = np.zeros((len(CASES), len(first["region"])), np.int8)
    for i, c in enumerate(CASES):
        dead[i, deletion[c]["deleted"]] = 1
    ds["fem_element_deleted"] = (("case", "fem_element"), dead, {"units": "-"})


def _static_variables(ds: xr.Dataset, fem: dict, static: dict) -> None:
    """The static csph runs ``static`` {H/Δx: :func:`csph_static`} on their own coordinate
    ``static_resolution``: the elastic slope of each (the secant at the first path point), its
    error against the FEM's slope limit and the error's observed order (least squares; gate 1),
    wall time and status. In 2-D the ladder and H/Δx = 40 (:data:`STATIC_FINEST`), in 3-D
    :data:`STATIC_RESOLUTIONS_3D`."""
    sr = sorted(static)
    ds.coords["static_resolution"] = ("static_resolution", np.array(sr), {
        "units": "-", "long_name": "particles across H of the static csph runs (gates 1 and 2)"})
    slope = np.array([static[r].get("elastic_slope", np.nan) for r in sr], float)
    ds["static_elastic_slope"] = (("static_resolution",), slope, {
        "units": "N/m/m" if ds.attrs.get("plane", "strain") == "strain" else "N/m",
        "long_name": "csph (static) secant at the first path point, elastic"})
    ds["static_slope_error"] = (("static_resolution",), np.abs(slope / fem["slope_limit"] - 1), {
        "units": "-", "long_name": "|csph static slope / FEM slope limit - 1|"})
    ds.attrs["static_slope_order"] = observed_order(1.0 / np.array(sr, float),
                                                    ds.static_slope_error.values)
    ds["static_wall_time"] = (("static_resolution",), np.array([static[r]["wall_time"] for r in sr]),
                              {"units": "s"})
    ds["static_status"] = (("static_resolution",), np.array([str(static[r]["status"]) for r in sr]),
                           {"units": "-"})


def _root_variables(ds: xr.Dataset, fem: dict, static: dict) -> None:
    """Gate 2's variables: the first failure in :func:`root_region` of the FEM ladder (load,
    deflection, Richardson limit and its uncertainty, each mesh's error) and of the static csph
    runs ``static`` on ``static_resolution`` (:func:`_static_variables`: load, deflection, error
    against the FEM's limit, and that error's observed order)."""
    force = "N" if _is_3d(ds) else "N/m"
    fr = np.array([fem["first_failure_root"][c] for c in CASES])  # (case, fem_resolution, 2)
    ds["fem_first_failure_root_deflection"] = (("case", "fem_resolution"), fr[..., 0], {"units": "m"})
    ds["fem_first_failure_root_load"] = (("case", "fem_resolution"), fr[..., 1], {
        "units": force, "long_name": "FEM load at the first failure in the root region (gate 2)"})
    ds["fem_root_limit"] = (("case",), np.array([fem["root_limit"][c] for c in CASES]), {
        "units": force, "long_name": "its Richardson limit at the singular order"})
    ds["fem_root_limit_spread"] = (("case",), np.array([fem["root_limit_spread"][c] for c in CASES]), {
        "units": "-", "long_name": "that limit's uncertainty: |limit at the singular order - limit "
                                   "at the observed order| / limit"})
    ds["fem_root_error"] = (("case", "fem_resolution"), np.array([fem["root_error"][c] for c in CASES]),
                            {"units": "-", "long_name": "|load - limit| / limit (the FEM's own error)"})
    ds["fem_root_order"] = (("case",), np.array([fem["root_order"][c] for c in CASES]), {"units": "-"})
    if fem.get("root_runs") is not None:  # root_ladder: the FEM's own runs along the root path
        ds["fem_root_wall_time"] = (("fem_resolution",), np.array(
            [fem["root_runs"][r]["wall_time"] for r in fem["resolutions"]], float), {
            "units": "s", "long_name": "wall time of the FEM's run along the root path"})
    sr = sorted(static)
    cs = np.array([[static[r]["first_failure_root"][c] for r in sr] for c in CASES], float)
    ds["static_first_failure_root_deflection"] = (("case", "static_resolution"), cs[..., 0],
                                                  {"units": "m"})
    ds["static_first_failure_root_load"] = (("case", "static_resolution"), cs[..., 1], {
        "units": force, "long_name": "csph (static, no damage) load at the first failure in the "
                                    "root region (gate 2)"})
    lim = ds.fem_root_limit.values[:, None]
    ds["static_root_error"] = (("case", "static_resolution"), np.abs(cs[..., 1] / lim - 1), {
        "units": "-", "long_name": "|csph load / FEM limit - 1|"})
    inv = 1.0 / np.array(sr, float)
    ds["static_root_order"] = (("case",), np.array([observed_order(inv, e) for e in
                                                    ds.static_root_error.values]), {
        "units": "-", "long_name": "observed order of static_root_error (least squares)"})


def _fem_variables(ds: xr.Dataset, fem: dict, outs: dict, rules, res) -> None:
    """Gate 1's variables: the FEM curves, slopes and first failures, and the csph slope over the
    FEM's elastic window with its error against the FEM's limit."""
    fr = fem["resolutions"]
    runs = fem["runs"]
    d = runs[fr[0]]["deflection"]
    plane = ds.attrs.get("plane", "strain") == "strain"
    force = "N/m" if plane else "N"
    ds.coords["fem_resolution"] = ("fem_resolution", np.array(fr), {
        "units": "-", "long_name": "elements across H (9-node quadrilaterals)" if plane else
        "elements across H (27-node hexahedra; beyond the coarsest, the first path point only"
        + (" of the root path)" if fem.get("root_runs") is not None else ")")})
    ds.coords["fem_deflection"] = ("fem_deflection", d, {"units": "m"})
    data = {}
    data["fem_load"] = (("fem_resolution", "fem_deflection"),
                        np.array([runs[r]["load"] for r in fr]),
                        {"units": force, "long_name": "FEM static load of the patch (no damage)"})
    data["fem_max_damage"] = (("case", "fem_resolution", "fem_deflection"),
                              np.array([[runs[r]["damage"][c] for r in fr] for c in CASES]),
                              {"units": "-", "long_name": "largest eps_p/eps_L over the points"})
    data["fem_elastic_slope"] = (("fem_resolution",), fem["slopes"], {"units": force + "/m"})
    data["fem_slope_error"] = (("fem_resolution",), fem["slope_error"], {
        "units": "-", "long_name": "|slope - Richardson limit| / limit (the FEM's own error)"})
    data["fem_wall_time"] = (("fem_resolution",), np.array([runs[r]["wall_time"] for r in fr]),
                             {"units": "s"})
    ff = np.array([fem["first_failure"][c] for c in CASES])  # (case, fem_resolution, 2)
    data["fem_first_failure_deflection"] = (("case", "fem_resolution"), ff[..., 0], {"units": "m"})
    data["fem_first_failure_load"] = (("case", "fem_resolution"), ff[..., 1], {"units": force})
    dims = ("solver", "case", "rule", "resolution")
    shp = (1, len(CASES), len(rules), len(res))
    slope = np.full(shp, np.nan)
    for (case, rule, r), out in outs.items():
        if len(out.get("time", ())) > 3:
            fail = np.flatnonzero(np.asarray(out["failed"]) > 0)
            tf = float(np.asarray(out["time"])[fail[0]]) if fail.size else np.inf
            slope[0, CASES.index(case), rules.index(rule), res.index(r)] = csph_slope(
                out["deflection_down"], out["load"], out["time"], tf, fem["window"])
    lim = fem["slope_limit"]
    data["elastic_slope_fem_window"] = (dims, slope, {
        "units": force + "/m", "long_name": "csph elastic slope over the FEM's elastic window"})
    data["slope_error_fem"] = (dims, np.abs(slope / lim - 1), {
        "units": "-", "long_name": "|csph slope / FEM limit - 1|"})
    same = np.full(shp, np.nan)
    for j, r in enumerate(res):
        if r in fr:
            same[..., j] = slope[..., j] / fem["slopes"][fr.index(r)] - 1
    data["slope_vs_fem_same_resolution"] = (dims, same, {
        "units": "-", "long_name": "csph slope / FEM slope at the same H/dx - 1"})
    for k, v in data.items():
        ds[k] = v
    ds.attrs.update(fem_slope_limit=float(lim), fem_observed_order=float(fem["observed_order"]),
                    fem_slope_limit_spread=float(fem.get("slope_limit_spread", np.nan)),
                    fem_slope_window_m=str([float(w) for w in fem["window"]]),
                    fem_assumed_order=SINGULAR_ORDER)


def _final_particles(ds: xr.Dataset, finest: dict, rules) -> None:
    """The final particles of the finest run of each case and rule (padded to the largest count);
    ``finest`` {(case, rule): (resolution, driver output)}."""
    if not finest:
        return
    n = max(len(o["x"]) for _, o in finest.values())
    d = next(iter(finest.values()))[1]["x"].shape[1]
    X = np.full((len(CASES), len(rules), n, d), np.nan)
    x = np.full_like(X, np.nan)
    grain = np.full((len(CASES), len(rules), n), -1, np.int64)
    failed = np.zeros((len(CASES), len(rules), n), np.int8)
    names = None
    at = np.zeros((len(CASES), len(rules)), np.int64)
    for (case, rule), (r, o) in finest.items():
        i, j = CASES.index(case), rules.index(rule)
        at[i, j] = r
        m = len(o["x"])
        X[i, j, :m], x[i, j, :m] = o["X"], o["x"]
        grain[i, j, :m] = o["region"]
        failed[i, j, :m] = np.asarray(o.get("failed_particles", np.zeros(m)), np.int8)
        names = o["region_names"]
    ds["particle_X"] = (("case", "rule", "particle", "axis"), X, {"units": "m", "long_name":
                        "reference positions, finest resolution (NaN: padding)"})
    ds["particle_x"] = (("case", "rule", "particle", "axis"), x, {"units": "m", "long_name":
                        "final positions, finest resolution"})
    ds["particle_region"] = (("case", "rule", "particle"), grain, {"units": "-", "long_name":
                             "region index into the attribute region_names (-1: padding)"})
    ds["particle_failed"] = (("case", "rule", "particle"), failed, {"units": "-"})
    ds["particle_resolution"] = (("case", "rule"), at, {"units": "-", "long_name":
                                 "H/dx of the run whose final particles these are (0: none)"})
    ds.attrs["region_names"] = ", ".join(names)


def _runs(ds, rules=GATED_RULES):
    for case in ds.case.values:
        for rule in ds.rule.values:
            if rule not in rules:
                continue
            for r in ds.resolution.values:
                sel = dict(solver="csph", case=case, rule=rule, resolution=r)
                if str(ds.status.sel(**sel).values) != "not run":
                    yield str(case), str(rule), int(r), sel


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


def band_gates(ds: xr.Dataset) -> list[Gate]:
    """Gate 5 (issue 11): on a ladder of three resolutions or more where the band is wider than
    the spacing (:func:`band_ladder`), the regularised rule's fracture energy within TOL_BAND
    across it (max/min − 1; NaN, a failed gate, when a run of it reports none)."""
    g = []
    for case in ds.case.values:
        res, G = band_ladder(ds, str(case))
        if len(res) < 3:
            continue
        g.append(Gate.at_most(
            f"microcantilever {case} regularised H/dx={', '.join(str(r) for r in res)} (band "
            f"{band_width(ds) * 1e6:g} um > dx): fracture energy's spread across the ladder "
            f"(max/min - 1)", float(np.max(G) / np.min(G) - 1), TOL_BAND,
            "issue 11 gate 5: within 10 % across the ladder",
            "the same rule's energy at the other spacings (its closed form b g(eps_L) H, "
            "4.0-4.1 uJ/m, is reported beside it, not gated: the runs lie 0-12 % above it)"))
    return g


def gates(ds: xr.Dataset) -> list[Gate]:
    g = []
    if "fem_elastic_slope" in ds:
        g += fem_gates(ds)
    if "fem_reference_failed" in ds.attrs:
        g.append(Gate.expect("microcantilever gate 1's FEM reference", ds.attrs["fem_reference_failed"],
                             "computed", "issue 11 gate 1 needs the FEM of the same grains",
                             FEM_REFERENCE))
    three_d = _is_3d(ds)
    if three_d and "static_elastic_slope" in ds and "fem_elastic_slope" in ds:
        g += static_slope_gates(ds)
    if "static_first_failure_root_load" in ds:
        g += root_gates(ds, slope=not three_d)
    if "fracture_energy" in ds:
        g += band_gates(ds)
    for case, rule, r, sel in _runs(ds):
        tag = f"microcantilever {case} {rule} H/dx={r}"
        # a balance-law gate: the smallest defect it must catch is a term of the balance lost, the
        # least of them the energy released by the failures (~10 % of the external work)
        lost = float(np.nanmax(ds.released_energy.sel(**sel).values)
                     / np.nanmax(ds.external_work.sel(**sel).values))
        g.append(Gate.at_most(f"{tag}: energy balance, max over time", float(ds.energy_balance_error.sel(**sel)),
                              TOL_ENERGY, "issue 11 gate 2: 1 % of the external work",
                              "the run's own external work against its kinetic, elastic, plastic "
                              "and released energies (a balance law)", defect=lost))
        share = float(ds.share_boundaries.sel(**sel))
        share = share if case == "inter" else 1.0 - share
        g.append(Gate.at_most(f"{tag}: failed particles outside the "
                              f"{'grain boundaries' if case == 'inter' else 'grains'}",
                              1.0 - share if np.isfinite(share) else np.nan, 1.0 - MIN_SHARE,
                              "issue 11 gate 3: at least 80 % where the low eps_L is",
                              "the scene's regions (where the low eps_L is), fixed before the run"))
        g.append(Gate.at_most(f"{tag}: kinetic / elastic energy before the first failure",
                              float(ds.kinetic_ratio.sel(**sel)), TOL_QUASI_STATIC,
                              "issue 11 gate 4: quasi-static loading",
                              "the run's own elastic energy (a ratio of two energies of the run)"))
        sep = "separated" if float(ds.separated.sel(**sel)) == 1.0 else \
            f"not separated ({ds.status.sel(**sel).values})"
        g.append(Gate.expect(f"{tag}: complete separation, no NaN, no crash", sep, "separated",
                             "the paper's robustness claim: the mean load over the last 20 % of "
                             "the run within 5 % of the peak load before failure",
                             "the run's own peak load before the first failure"))
    return g


MIN_ORDER_SHARE = 0.5
"""The observed order of csph's slope error (least squares over the static ladder) must reach
this share of :data:`SINGULAR_ORDER`: a consistent discretisation converges at the singular
order asymptotically; half of it leaves room for a pre-asymptotic ladder and the reference
limit's own error, and it separates converging from stagnating (nodal integration in 3-D, −6.5
and −6.1 % at H/Δx = 5 and 10, observes about 0.1)."""


def static_slope_gates(ds: xr.Dataset) -> list[Gate]:
    """Gate 1 on the static slope ladder (the 3-D run, :data:`STATIC_RESOLUTIONS_3D`): each
    static csph slope within max(1 %, e(r)) of the FEM's limit (:func:`slope_tolerance`), the
    error's observed order at least MIN_ORDER_SHARE of the singular order, and the finest within
    1 % (:func:`finest_slope_gates`)."""
    res = [int(r) for r in ds.static_resolution.values]
    g = [Gate.at_most(
        f"microcantilever csph static H/dx={r}: elastic slope against the FEM's limit",
        float(ds.static_slope_error.sel(static_resolution=r)), _slope_tolerance_ds(ds, r),
        "issue 11 gate 1: max(1 %, the FEM's own error at the same nodal spacing at the singular "
        "order)", FEM_REFERENCE) for r in res]
    g.append(Gate.at_least(
        f"microcantilever csph static: observed order of the elastic slope's error "
        f"(H/dx = {', '.join(map(str, res))})", float(ds.attrs.get("static_slope_order", np.nan)),
        MIN_ORDER_SHARE * SINGULAR_ORDER,
        "issue 11 gate 5: converging at the singular order (2 x 0.5445), half of it at least",
        FEM_REFERENCE))
    return g + finest_slope_gates(ds)


def root_tolerance(ds: xr.Dataset, case: str, r: int) -> float:
    """Gate 2's tolerance at H/Δx = r: max(TOL_FIRST_FAILURE, e_FEM(r₀)(2r₀/r)^p)."""
    e0 = float(ds.fem_root_error.sel(case=case).values[0])
    r0 = int(ds.fem_resolution.values[0])
    return max(TOL_FIRST_FAILURE, e0 * (2 * r0 / r) ** SINGULAR_ORDER)


def _is_3d(ds: xr.Dataset) -> bool:
    return ds.attrs.get("plane") == PLANE_3D


def root_gates(ds: xr.Dataset, slope: bool = True) -> list[Gate]:
    """Gate 2 (the issue's gate 1, its second half): the FEM's first-failure load in the root
    region converged on its own ladder (its Richardson error on the finest mesh at most half the
    smallest tolerance it checks), and the static csph's within root_tolerance at each
    resolution; then :func:`finest_gates` (``slope``: with the elastic slope's, which the 3-D run
    has from :func:`static_slope_gates`)."""
    g = []
    fr = [int(r) for r in ds.fem_resolution.values]
    res = [int(r) for r in ds.static_resolution.values]
    for case in ds.case.values:
        case = str(case)
        tol = min(root_tolerance(ds, case, r) for r in res)
        g.append(Gate.at_most(
            f"microcantilever {case} FEM H/h={fr[-1]}: load at the first failure in the root region, "
            f"error against its Richardson limit (H/h = {', '.join(map(str, fr))})",
            float(ds.fem_root_error.sel(case=case).values[-1]), FEM_SHARE * tol,
            "the reference's own error at most half the tolerance it checks", FEM_REFERENCE))
        for r in res:
            g.append(Gate.at_most(
                f"microcantilever {case} csph static H/dx={r}: load at the first failure in the root "
                f"region against the FEM's limit",
                float(ds.static_root_error.sel(case=case, static_resolution=r)),
                root_tolerance(ds, case, r),
                "issue 11 gate 1: max(3 %, the FEM's own error at the same nodal spacing at the "
                "singular order)", FEM_REFERENCE))
    return g + finest_gates(ds, slope)


def finest_gates(ds: xr.Dataset, slope: bool = True) -> list[Gate]:
    """Gate 1 at the finest resolution, the issue's bounds as written: the static csph run at the
    finest H/Δx (:data:`STATIC_FINEST` in 2-D, the last of :data:`STATIC_RESOLUTIONS_3D` in 3-D)
    has its elastic slope within TOL_SLOPE (1 %; ``slope``) and each case's load at the first
    failure in the root region within TOL_FIRST_FAILURE (3 %) of the FEM's Richardson limits;
    each limit's own uncertainty (:func:`limit_spread`) at most FEM_SHARE of the bound it serves
    (NaN, so failing, below three meshes)."""
    r = int(ds.static_resolution.values.max())
    g = finest_slope_gates(ds) if slope else []
    for case in ds.case.values:
        g.append(Gate.at_most(
            f"microcantilever {case} FEM: the uncertainty of the root region's first-failure "
            f"load limit (singular against observed order)",
            float(ds.fem_root_limit_spread.sel(case=case)), FEM_SHARE * TOL_FIRST_FAILURE,
            "the reference's own error at most half the tolerance it checks", FEM_REFERENCE))
        g.append(Gate.at_most(
            f"microcantilever {case} csph static H/dx={r} (the finest): load at the first failure "
            f"in the root region against the FEM's limit",
            float(ds.static_root_error.sel(case=case, static_resolution=r)), TOL_FIRST_FAILURE,
            "issue 11 gate 1: the load at the first failure within 3 % at the finest resolution",
            FEM_REFERENCE))
    return g


def finest_slope_gates(ds: xr.Dataset) -> list[Gate]:
    """The issue's 1 % on the elastic slope at the finest static csph run (both dimensions), and
    the FEM limit's own uncertainty (:func:`limit_spread`) at most FEM_SHARE of it (NaN, so
    failing, below three meshes)."""
    r = int(ds.static_resolution.values.max())
    return [Gate.at_most(
        "microcantilever FEM: the uncertainty of the elastic slope's Richardson limit (singular "
        "against observed order)", float(ds.attrs.get("fem_slope_limit_spread", np.nan)),
        FEM_SHARE * TOL_SLOPE, "the reference's own error at most half the tolerance it checks",
        FEM_REFERENCE),
        Gate.at_most(
        f"microcantilever csph static H/dx={r} (the finest): elastic slope against the FEM's limit",
        float(ds.static_slope_error.sel(static_resolution=r)), TOL_SLOPE,
        "issue 11 gate 1: the elastic slope within 1 % at the finest resolution",
        FEM_REFERENCE)]


def _slope_tolerance_ds(ds: xr.Dataset, r: int) -> float:
    return _tolerance(int(ds.fem_resolution.values[0]), float(ds.fem_slope_error.values[0]), r)


def fem_gates(ds: xr.Dataset) -> list[Gate]:
    """Gate 1 (issue 11), before the first failure: the FEM converged on its own ladder, and the
    csph elastic slope of each run against the FEM's limit within max(1 %, e(r)) (TOL_SLOPE). The
    load at the first failure is reported, not gated: the first failure is at the edge of the
    rigidly moved patch, a singular point, and its load falls with the spacing in both methods
    (report_notes)."""
    g = []
    fr = ds.fem_resolution.values
    tol = min(_slope_tolerance_ds(ds, int(r)) for r in ds.resolution.values)
    g.append(Gate.at_most(
        f"microcantilever FEM H/h={int(fr[-1])}: elastic slope's error against its Richardson limit "
        f"(H/h = {', '.join(str(int(r)) for r in fr)}, order {SINGULAR_ORDER:.3g})",
        float(ds.fem_slope_error.values[-1]), FEM_SHARE * tol,
        "the reference's own error at most half the tolerance it checks", FEM_REFERENCE))
    for case, rule, r, sel in _runs(ds):
        g.append(Gate.at_most(
            f"microcantilever {case} {rule} H/dx={r}: elastic slope against the FEM's limit",
            float(ds.slope_error_fem.sel(**sel)), _slope_tolerance_ds(ds, r),
            "issue 11 gate 1: max(1 %, the FEM's own error at the same nodal spacing, "
            "H/h = H/(2 dx), at the singular order 2*0.5445)", FEM_REFERENCE))
    return g


def errors(ds: xr.Dataset) -> list[dict]:
    """No reference here: the energy balance error of each run against its wall time."""
    rows = []
    for case, rule, r, sel in _runs(ds, ("compression",)):
        e = float(ds.energy_balance_error.sel(**sel))
        if np.isfinite(e):
            rows.append(dict(solver=f"csph ({case})", resolution=r, error=e,
                             wall_time=float(ds.wall_time.sel(**sel))))
    return rows


def fracture_note(ds: xr.Dataset, case: str) -> str | None:
    """Gate 5's line of the report for ``case``: the crack's energy per run of each ladder rule,
    its fitted power of Δx and its spread — the regularised rule's over the gate's runs
    (:func:`band_ladder`); None without a ladder."""
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
    for case, rule, r, sel in _runs(ds, tuple(ds.rule.values)):
        v = {k: ds[k].sel(**sel).values for k in ("peak_load", "t_first_failure", "n_failed",
                                                   "share_boundaries", "tail_load_ratio", "separated",
                                                   "connected", "energy_balance_error",
                                                   "crack_regions", "t_separated", "t_last")}
        unit = "N/m" if ds.attrs.get("plane") == "strain" else "N"
        notes.append(f"{case}, {rule}, H/dx = {r}: peak load before failure "
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
        for rule in ds.rule.values:
            for r in ds.resolution.values:
                sel = dict(solver="csph", case=case, rule=rule, resolution=r)
                ax.plot(ds.deflection.sel(**sel) * 1e6, ds["load"].sel(**sel), ls=styles.get(str(rule), "-"),
                        lw=1, label=f"{rule}, H/dx = {int(r)}")
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
        for n in ("kinetic_energy", "elastic_energy", "plastic_work", "released_energy"):
            y = ds[n].sel(**sel)
            total = total + y
            ax.plot(ds.time * 1e6, y, lw=1, label=n)
        ax.plot(ds.time * 1e6, ds.external_work.sel(**sel), "k", lw=2, label="external work")
        ax.plot(ds.time * 1e6, total, "y--", lw=1, label="sum of the four")
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
    """Gate 5: the main crack's energy against the spacing, literal ε_L (``compression``)
    and crack band (``regularised``), each case; the line G ∝ Δx through the coarsest literal run."""
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
    rules = list(ds.rule.values)
    fem = "fem_element_deleted" in ds
    rows = len(rules) + int(fem)
    fig, axes = plt.subplots(rows, len(ds.case), figsize=(6 * len(ds.case), 2.6 * rows),
                             squeeze=False)
    palette = np.array(["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown",
                        "tab:pink", "tab:olive", "tab:cyan"])
    for i, case in enumerate(ds.case.values):
        for j, rule in enumerate(rules):
            ax = axes[j, i]
            X = ds.particle_X.sel(case=case, rule=rule).values
            x = ds.particle_x.sel(case=case, rule=rule).values
            reg = ds.particle_region.sel(case=case, rule=rule).values
            bad = ds.particle_failed.sel(case=case, rule=rule).values.astype(bool)
            ok = reg >= 0
            if not ok.any():
                ax.set_axis_off()
                continue
            if X.shape[1] == 3:
                # the lattice plane nearest the beam's mid-plane y = 0 (the lattice starts at the
                # block's side face: at even particle counts across B the planes straddle y = 0)
                dx = float(ds.attrs["param_H"]) / int(ds.particle_resolution.sel(case=case, rule=rule))
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
            ax.set_title(f"{case}-granular, {rule}, H/dx = "
                         f"{int(ds.particle_resolution.sel(case=case, rule=rule))}", fontsize=9)
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
