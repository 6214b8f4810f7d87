"""Which runs the RC beam study makes: the specimens, the solvers with their options, the spacings
of the full and the quick run, the kernel-reduction and modal runs, and the scene of one specimen
(:func:`scene_for`), each with its reason and measured cost."""
from __future__ import annotations

import dataclasses

from ..common import check_resolutions
from .scene import RCBeam


NAME = "rc_beam"
SCENE = RCBeam
SOLVERS = ("sph", "csph")
SPECIMENS = ("A", "B")
OPTIONS = {"sph": dict(stress="hyperelastic", viscous_work=True),
           "csph": dict(integration="nodal")}
"""Solver options: sph needs the hyperelastic stress path for the mortar and J2 steel, and tracks
its artificial viscosity's dissipation for the energy balance. Both methods keep mirror images
of the neighbours across the symmetry planes (the default ``mirror='auto'``, :mod:`sph.mirror`),
so the quarter moves as the full beam (tests/test_mirror.py). Classic SPH's velocity gradient has
the volume m_j/ρ_i, the power conjugate of its forces (:mod:`sph.classic`; what m_j/ρ_j did:
``notes.md``). csph runs with nodal integration (the integration-consistent correction is stable
only below 0.20 Δx/c_p on specimen A at 12.5 mm, its critical step 2/ω_max: at 0.9 of it,
``dt_reference='spectrum'``, it runs, at about 4 times the cost of nodal csph at 0.9 of its own
critical step; tests/test_rc_beam.py)."""
RESOLUTIONS = {"sph": (5, 8, 10, 12), "csph": (5, 8, 10, 12)}
"""Particles across H = 100 mm: 20, 12.5, 10 and 8.33 mm, so that each specimen's runs finish
within the issue's 15 minutes on 2 cores (the measured times: ``notes.md``). The paper's 5 mm is
``--resolution 20``, not on the default ladder."""
QUICK_RESOLUTIONS = {"sph": (8,), "csph": (8,)}
KERNEL_REDUCTION_SPECIMEN = "B"
"""The kernel reduction of 003 §4.2(2) (classic SPH's ``kernel_reduction``: kernels across fully
released mortar particles × φ_min = 0.05): 003 runs it on specimen B, whose largest displacement it
doubles. A full run adds sph on B with it at every resolution (the ``kernel_reduction`` dimension
of the ``kr_*`` variables); ``--quick`` does not."""
QUICK_T_END = 5e-4
"""``--quick``: the first 0.5 ms (the first contact pulse and the start of the bending), 12.5 mm."""
QUICK_SPECIMENS = ("B",)
"""``--quick`` (and so ``workbench verify --quick``) runs specimen B alone: its 400 mm span has half
of A's particles, and the quick gates (momentum, energy balance, B's modal frequency) check the
methods and the bookkeeping, which A's run repeats at twice the cost (measured under load 5: A 99
and 79 s, B 19 and 7 s for sph and csph). A full run has both."""
MODAL_RESOLUTION = 8
"""Gate 2's spacing, 12.5 mm (the ladder's coarsest: six particles between the bar level and the
top): the beam with its rebar alone on hinges (``structure='beam'``), csph's modal drive (the
tangent of its gradient form about the reference state, lumped masses) against the FEM's modal
analysis of the same model (27-node hexahedra on a grid through every region face, the same
bars with the same equivalent steel, the same hinge line). Classic SPH has no gradient form (no
modal drive); its elastic phase is not checked here."""
MODAL_SPECIMENS = {False: ("A", "B"), True: ("B",)}
"""Specimens of the modal check: both in a full run, B (about 20 s per solver) with ``--quick``."""
MODAL_SOLVERS = ("csph", "fem")


def scene_for(scene: RCBeam, specimen: str, quick: bool) -> RCBeam:
    """The scene of one specimen (its own name, for the field series); ``quick``: the first
    :data:`QUICK_T_END` only (unless the scene's own end is shorter)."""
    kw = dict(specimen=specimen, name=f"{NAME}_{specimen}")
    if quick:
        kw["t_end"] = min(scene.t_end, QUICK_T_END)
    return dataclasses.replace(scene, **kw)


def _ladders(solvers, resolutions, quick) -> dict:
    table = QUICK_RESOLUTIONS if quick else RESOLUTIONS
    out = {}
    for s in solvers:
        if isinstance(resolutions, dict):
            r = resolutions.get(s, table[s])
        else:
            r = resolutions or table[s]
        out[s] = check_resolutions(r)
    return out
