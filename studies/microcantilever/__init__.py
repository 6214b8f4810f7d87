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
and materials (:func:`.static.fem_ladder`: 9-node quadrilaterals, plane strain, J2 with Swift per
element, the patch pushed down rigidly) on a ladder of meshes, its elastic slope extrapolated at the
order of the re-entrant corners (:data:`.derive.SINGULAR_ORDER`); gate 1 checks the csph slope
against it (:func:`.gates.fem_gates`). The load at the first failure anywhere is reported, not
gated: it is at the edges of the rigid patch or at the re-entrant corner, singular points, and its
load falls with the spacing in both methods. Gate 2 (the full 2-D run) gates the load at the first
failure in :func:`.static.root_region` — the tension half of the root half, where the bending stress
is largest and no singular point lies — which converges on the FEM's ladder; csph's comes from
static runs on the FEM's path (:func:`.static.csph_static`; the dynamic runs fail first at the
singular points) (:func:`.gates.root_gates`), at the run's resolutions and at H/Δx = 40
(:data:`.ladders.STATIC_FINEST`), where the issue's bounds at the finest resolution — elastic slope
within 1 %, load at the first failure within 3 % — are gated as written
(:func:`.gates.finest_gates`). Gate 6 (the full 2-D run, shown, not gated): the same scene by the
FEM with element deletion (:func:`.static.fem_deletion`), its load beside csph's and its deleted
elements beside the failed particles, with their share where the low ε_L is. Gate 5
(:func:`.gates.band_gates`): the energy the main crack takes to cut the body
(:func:`.derive.fracture_energy`, at the record of the cut) falls with the spacing under the literal
ε_L and stays within 10 % across the ladder under the crack band (rule ``regularised``,
:data:`.ladders.BAND`). The other gates are the checks the physics and the paper's robustness claim
allow without a reference (:func:`.gates.gates`). 2-D runs are plane strain (csph has no plane
stress); ``--quick`` runs the 2-D variant at H/Δx = 5, the full run the scene's own dimension (3-D
by default, integration-consistent as in 2-D, :data:`.ladders.OPTIONS_3D`; gate 1 there against the
3-D FEM of :data:`.ladders.FEM_RESOLUTIONS_3D`, a ladder of three hexahedral meshes, the finer two
at their elastic first point only, with csph's static elastic slopes on a ladder of their own,
:data:`.ladders.STATIC_RESOLUTIONS_3D` — the observed order and the 1 % at the finest
(:func:`.gates.static_slope_gates`); gates 2 and 5 need a 2-D ladder: ``--set dim=2``; gate 2 of the
3-D scene, hours on 2 cores, is :func:`.study.root_ladder` (:mod:`.root`), apart from the default
run).

The case's folder, one module per concept: :mod:`.scene` (the grains, boundaries and materials as
parameters and a model), :mod:`.ladders` (which runs), :mod:`.study` (:func:`run` and the 3-D root
ladder), :mod:`.static` (the FEM and static csph references), :mod:`.derive` (what the runs give),
:mod:`.dataset` (``microcantilever.nc``), :mod:`.gates` (the tolerances with their reasons, the
gates), :mod:`.report` (the report's notes), :mod:`.figures`, :mod:`.root` (the study
``microcantilever_root``), :mod:`.mode` (the study ``microcantilever_mode``: the fracture mode
predicted, on the scene of :mod:`.padded`) and ``notes.md`` (the design and the measurement record). This module
exposes the study protocol of :mod:`studies` (``studies.get("microcantilever")``) and the gates'
tolerances (tests import the same constants).
"""
from .figures import plot  # noqa: F401
from .gates import (ERROR_LABEL, N_GATES, TOL_BAND, TOL_ENERGY, TOL_FIRST_FAILURE,  # noqa: F401
                    TOL_QUASI_STATIC, TOL_SLOPE, errors, gates)
from .derive import TOL_SEPARATION  # noqa: F401
from .ladders import (NAME, QUICK_RESOLUTIONS, RESOLUTIONS, SCENE, SOLVERS,  # noqa: F401
                      default_resolutions, quick_scene)
from .report import report_notes  # noqa: F401
from .scene import MicroCantilever  # noqa: F401
from .study import run  # noqa: F401
