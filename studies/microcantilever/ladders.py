"""Which runs the micro-cantilever study makes: the cases and failure rules, the resolutions of the
particle runs (2-D and 3-D, full and quick), the FEM's and static csph's ladders and load paths,
the options, and the scene of one case and rule (:func:`scene_for`), each with its reason."""
from __future__ import annotations

import dataclasses

from .scene import MicroCantilever


NAME = "microcantilever"
SCENE = MicroCantilever
SOLVERS = ("csph", "csph_bl")
"""``csph`` (integration-consistent, quadratic correction: ours) and ``csph_bl`` (paper 000's CSPH
as printed: Bonet–Lok correction, nodal integration), beside it at the same resolutions under the
default rule (:data:`SOLVER_RULES`) so that the paper's result and the corrected one can be
compared; the gates are csph's (:data:`GATED_SOLVERS`)."""
GATED_SOLVERS = ("csph",)
"""The solvers whose runs the study gates: csph_bl, 000's method, is shown beside csph (the
tables, the report's comparison, the figures), not verified by this study."""
SOLVER_RULES = {"csph_bl": ("compression",)}
"""The failure rules a solver other than csph runs (csph: every rule of the run)."""
RESOLUTIONS = {"csph": (5, 10, 15, 20), "csph_bl": (5, 10, 15, 20)}
"""Particles across H of a 2-D run (``--set dim=2``): the ladder of gates 1, 2 and 5 (the rules
outside LADDER_RULES stop at H/Δx = 10). Gate 5 takes the runs whose crack band is wider than the
spacing (:func:`.derive.band_ladder`: H/Δx = 10, 15, 20 with the 1 µm band; at 5 the band is one
spacing and the regularised run is the ``compression`` one), so the ladder holds three of them."""
RESOLUTIONS_3D = (5,)
"""Particles across H of the 3-D run (the default): 1776 particles; the cases cut apart at 1.36 µs
(inter) and 1.04 µs (intra) and stop 1.5 µs later (t_after), 59 k and 52 k steps, 63 s and 98 s on
one thread (integration-consistent, the other core busy); H/Δx = 10 has eight times the particles
and twice the steps."""
QUICK_RESOLUTIONS = {"csph": (5,)}
QUICK_DIM = 2
"""``--quick``: the 2-D (plane-strain) variant at H/Δx = 5 — two runs of about 8 s each on one
core. csph alone: csph_bl's two runs take as long as csph's (measured at H/Δx = 5: 128 against
116 s of run time on a loaded machine) and would double the quick run's particle runs
(``--solver csph_bl`` or the full run add them)."""
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
H/Δx (what a block B/2 beyond them did, and the measured step, slopes and energy balance:
``notes.md``)."""
FEM_RESOLUTIONS = (5, 10, 20, 40, 80)
"""Elements (9-node quadrilaterals, plane strain) across H of the FEM reference of a 2-D run; the
smallest is 5 (the grain boundary, 1 µm, must hold an element: H/h >= 5). The reference of the
static csph run at :data:`STATIC_FINEST` is the limit of the two finest. The ladder goes to 80
(38 400 elements, 4 minutes on one core along the root path) because the inter case's load at the
first failure, read where the geometry puts each point (:func:`.static.fem_static`), converges at
first order from above: 206.4, 192.9, 185.3, 181.8, 180.5 N/m at H/h = 5 to 80, and at 40 the FEM
is 1.8 % from the limit of 20 and 40, more than half the 3 % it checks; at 80 it is 0.6 % from the
limit of 40 and 80, which is within 0.4 % of the former."""
STATIC_FINEST = 40
"""Gate 2's static csph runs (the full 2-D run) are at the run's resolutions and at H/Δx =
STATIC_FINEST, where the issue's bounds at the finest resolution are checked: the elastic slope
within 1 % and the load at the first failure within 3 % of the FEM's limit
(:func:`.gates.finest_gates`). 9600 particles, about 3.5 minutes on one core; the dynamic runs stop
at H/Δx = 20 (a dynamic run at 40 has 4 times the particles and twice the steps of one at 20, about
an hour)."""
QUICK_FEM_RESOLUTIONS = (5, 10)
"""``--quick``: the two cheapest meshes (about 2 and 4 s)."""
STATIC_RESOLUTIONS_3D = (5, 10, 15)
"""Gate 1's ladder of static csph elastic slopes in the 3-D run (the first point of the FEM's
path, by Newton): 1776, 12 001 and 38 176 particles; 2 s, 41 s and 4.5 minutes on one core,
4.1 GB at 15. The Newton systems above 20 000 unknowns are solved by AMG-preconditioned CG
(:mod:`workbench.linear_systems`; the direct solve took 61 s per iteration at H/Δx = 10, where
AMG-CG takes 16 s, and did not finish at 15). They run after the FEM ladder, so that the two
largest jobs do not hold their memory at once (:func:`.gates.static_slope_gates`; the measured
slopes: ``notes.md``)."""
FEM_RESOLUTIONS_3D = (5, 10, 15)
FEM_FULL_PATH_3D = (5,)
"""Gate 1 of the 3-D run (the default): the FEM of the same 3-D grains and boundaries (27-node
hexahedra, J2 with Swift per element) at H/h = 5 along the whole static path to FEM_MAX·H (the
csph slope window and the first failures: 1250 elements, about 2 minutes on one core) and at
H/h = 10 and 15 at its first path point only, which is elastic (the slope: 10 000 and 33 750
elements, 2.5e5 and 8.4e5 unknowns, 2.5 and 5.7 minutes, 5.9 and 13.2 GB; the Newton systems by
AMG-preconditioned CG, :mod:`workbench.linear_systems` — the direct solve took 8 minutes and
12.6 GB at 10). The slope's limit is the Richardson limit of the two finest at
:data:`.derive.SINGULAR_ORDER` (the re-entrant edge where the beam meets its block is the 2-D corner
extruded, the same exponent); the three meshes observe the order (measured: ``notes.md``)."""
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
"""The path of :func:`.study.root_ladder` (:func:`.static.root_ladder_path`: the FEM's and the
static csph's, in 2-D and 3-D): the elastic first point FEM_STEP·H, then steps of ROOT_LADDER_STEP·H
(20 nm) towards FEM_MAX_ROOT·H, each run stopped at the point where both cases have failed in the
root region — a quarter of the points of the full 2-D run's path, whose 20 steps of FEM_STEP·H cost
a 3-D mesh as much as the rest. Measured against that fine path (linear interpolation between points
is second order in the step): the first-failure loads move by 0.03 % (inter) and 0.11 % (intra) at
H/h = 10 in 2-D, and by 0.06 % and 0.49 % at H/h = 5 in 3-D (measured before EDGE_CLEARANCE, when
intra failed at the edge at 0.10 µm, 0.02 H, where the fine path's steps are a quarter as long; with
it, at 0.15 µm) — the same on every mesh and in both methods, a fraction of gate 2's 3 %; steps
twice as long move intra by 1.9 % in 3-D."""


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


FEM_DELETION_RESOLUTION = 5
"""Elements (9-node quadrilaterals, plane strain) across H of the FEM with element deletion (the
full 2-D run): the scene's own drive (the patch moved at the scene's velocity) by implicit
Newmark (:func:`fem_reference.dynamic.newmark`: a step in which Newton fails is cut), an
element deleted once a point's damage reaches 1 (``deletion='any'``). About 2.5 minutes per
case on one core; the crack is one element wide, H/5 = 1 µm, the grain boundary's thickness."""


def quick_scene(scene: MicroCantilever) -> MicroCantilever:
    """The scene a ``--quick`` run takes: its 2-D variant (:data:`QUICK_DIM`)."""
    return dataclasses.replace(scene, dim=QUICK_DIM)


def default_resolutions(scene: MicroCantilever, quick: bool = False) -> dict:
    """The ladder a run of ``scene`` takes when none is given: the quick one, the 2-D one
    (:data:`RESOLUTIONS`) or the 3-D one (:data:`RESOLUTIONS_3D`)."""
    if quick:
        return QUICK_RESOLUTIONS
    return RESOLUTIONS if scene.dim == 2 else {s: RESOLUTIONS_3D for s in SOLVERS}


def solver_rules(solver: str, rules) -> list:
    """The rules of ``rules`` that ``solver`` runs (:data:`SOLVER_RULES`; csph: all)."""
    return [r for r in rules if solver not in SOLVER_RULES or r in SOLVER_RULES[solver]]
