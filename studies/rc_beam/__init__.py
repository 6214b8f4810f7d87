"""RC mortar beam under drop-weight impact (003): specimens A and B, classic SPH and CSPH.

Paper 003, §2 and §4; the scene is :class:`.scene.RCBeam` (its reading of the paper
and its choices in :mod:`.scene`): specimens A (800 mm span, stirrups, 100 kg at 2.2 m/s, flexural
failure) and B (400 mm, 1.4 m/s, shear failure), classic SPH (``sph``, the paper's method, with
the hyperelastic stress path the mortar needs) and CSPH (``csph``, nodal integration: the
integration-consistent correction's critical step is 0.2 of the CFL estimate here) side by side.

Stored per specimen, solver and resolution (``rc_beam.nc``; forces and energies are the full beam's,
four times the quarter model's): histories of the mid-span displacement, the impact force, the
support reaction, the energies (kinetic, stored elastic with the contact's, plastic work, released
by cracking, dissipated by sph's artificial viscosity, external work), the z momentum of weight plus
beam and the impulse the supports gave, the impulse of the impact (the weight's change of momentum)
and the impact force as a load cell sees it (its :data:`.derive.LOAD_CELL_WINDOW` mean, from that
impulse: independent of the record interval, beside 003's 200 kN load cell); the largest and the
residual mid-span displacement, each largest value with its time and a ``truncated`` flag (within
:data:`.derive.TRUNCATION_MARGIN` of the run's end: a lower bound, shown as "≥ … (truncated at
t_end)", never as a maximum, and failing any gate that reads it: :func:`.gates.truncation_gate`);
the cracked fraction of the mortar by crack orientation (:func:`.derive.crack_orientation`: the
principal direction of the mortar's damage tensor, from the driver's final history).

Gates (:func:`.gates.gates`), each tolerance with its reason beside it: the elastic phase (issue 12
gate 2) — the first flexural frequency of the beam with its rebar on hinges, csph's modal drive
against the FEM's modal analysis of the same model (:data:`.ladders.MODAL_RESOLUTION`), and a slow
impact (:mod:`.slow_impact`: specimen A at :data:`.slow_impact.SLOW_VELOCITY`, nothing cracks or
yields) whose mid-span history csph follows within :data:`.slow_impact.TOL_SLOW` of the FEM's over
the first half period (the FEM's idealisation of the contacts: :class:`.slow_impact.SlowImpactFem`;
full run only); conservation (issue 12 gate 3) — the momentum of weight plus beam changes by exactly
the supports' impulse, and the weight's initial kinetic energy equals kinetic + elastic + contact +
plastic + released + viscous. Validation rows (shown, not gated): 003's largest mid-span
displacement of B. Resolution (issue 12 gate 6, reported in the notes, not gated): the energy
released per crack area (:func:`.derive.crack_band_energy`, the crack band two particles wide) and
the largest displacement at each spacing of the ladder.

``--quick``: specimen B (:data:`.ladders.QUICK_SPECIMENS`) at one coarse spacing (12.5 mm) over the
first :data:`.ladders.QUICK_T_END` of the impact (shorter than the truncation margin: its largest
values are all truncated, and its figure says so instead of drawing them under 003's maxima); no
slow impact (its csph run alone costs ~30 s of CPU, the FEM's ladder minutes).

The case's folder, one module per concept: :mod:`.scene` (the beam as parameters and a model),
:mod:`.ladders` (which runs), :mod:`.study` (:func:`run`), :mod:`.derive` (what one run gives),
:mod:`.dataset` (``rc_beam.nc``), :mod:`.slow_impact` (gate 2's second half), :mod:`.gates` (the
tolerances with their reasons, the gates), :mod:`.report` (the report's notes), :mod:`.figures`,
and ``notes.md`` (the design and the measurement record). This module exposes the study protocol
of :mod:`studies` (``studies.get("rc_beam")``) and the gates' tolerances with the defects they
stand guard against (tests import the same constants).
"""
from .figures import plot  # noqa: F401
from .gates import (ENERGY_DEFECT, ERROR_LABEL, MOMENTUM_DEFECT, N_GATES, TOL_ENERGY,  # noqa: F401
                    TOL_ENERGY_QUICK, TOL_FREQUENCY, TOL_MOMENTUM, errors, gates)
from .ladders import NAME, QUICK_RESOLUTIONS, RESOLUTIONS, SCENE, SOLVERS  # noqa: F401
from .report import report_notes  # noqa: F401
from .scene import RCBeam  # noqa: F401
from .slow_impact import TOL_SLOW  # noqa: F401
from .study import run  # noqa: F401
