"""Micro-cantilever study: inter- and intra-granular fracture of a ceramic micro-cantilever with five
Voronoi grains and four grain boundaries (paper 000 §4–5, Fig. 5–6).

The case's folder: its scene (:mod:`.scene`), its study (:mod:`.study`) and the study of its 3-D
root ladder (:mod:`.root`, ``workbench run microcantilever_root``). This module exposes the study
protocol of :mod:`studies` (``studies.get("microcantilever")``) and the gates' tolerances (tests
import the same constants).
"""
from .scene import MicroCantilever  # noqa: F401
from .study import (ERROR_LABEL, N_GATES, NAME, QUICK_RESOLUTIONS, RESOLUTIONS, SCENE,  # noqa: F401
                    SOLVERS, TOL_BAND, TOL_ENERGY, TOL_FIRST_FAILURE, TOL_QUASI_STATIC,
                    TOL_SEPARATION, TOL_SLOPE, default_resolutions, errors, gates, plot,
                    quick_scene, report_notes, run)
