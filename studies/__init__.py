"""The studies: one module per study with ``NAME``, ``SCENE``, ``SOLVERS``, ``run(...) -> Dataset``,
``gates(ds)``, ``errors(ds)`` (rows for accuracy against cost) and ``plot(ds, outdir)``. A case with
a scene of its own is a folder (``studies/rc_beam/``: scene, study, gates, figures, notes) whose
``__init__`` exposes the same names; :data:`STUDIES` maps each study to its module."""
from __future__ import annotations

import importlib

STUDIES = {
    "ss_curve": "studies.ss_curve",
    "cantilever": "studies.cantilever",
    "plate": "studies.plate",
    "stability": "studies.stability",
    "microcantilever": "studies.microcantilever",
    "microcantilever_root": "studies.microcantilever.root",
    "microcantilever_mode": "studies.microcantilever.mode",
    "rc_beam": "studies.rc_beam",
    "centre_crack": "studies.centre_crack",
    "crack_path": "studies.crack_path",
}
# The studies that `workbench verify` runs, in order.
HEADLINE = ("ss_curve", "cantilever", "plate", "stability", "rc_beam", "microcantilever")


def get(name: str):
    """The study module called ``name`` (ValueError naming the allowed ones otherwise)."""
    if name not in STUDIES:
        raise ValueError(f"study: {name!r} is unknown; allowed: {', '.join(STUDIES)}")
    return importlib.import_module(STUDIES[name])
