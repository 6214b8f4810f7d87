"""RC mortar beam under drop-weight impact (003): specimens A and B, classic SPH and CSPH.

The case's folder: its scene (:mod:`.scene`), its study (:mod:`.study`). This module exposes the
study protocol of :mod:`studies` (``studies.get("rc_beam")``) and the gates' tolerances with the
defects they stand guard against (tests import the same constants).
"""
from .scene import RCBeam  # noqa: F401
from .study import (ENERGY_DEFECT, ERROR_LABEL, MOMENTUM_DEFECT, N_GATES, NAME,  # noqa: F401
                    QUICK_RESOLUTIONS, RESOLUTIONS, SCENE, SOLVERS, TOL_ENERGY, TOL_ENERGY_QUICK,
                    TOL_FREQUENCY, TOL_MOMENTUM, TOL_SLOW, errors, gates, plot, report_notes, run)
