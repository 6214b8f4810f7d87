"""Scenes: parameters (what ``workbench list`` shows and ``--set`` overrides) and models (the scene
as data — regions, named sets, constraints, loads, drive, observables — that every method runs).

- :mod:`.params` — :class:`Scene` (the parameter dataclass base), :func:`param`,
  :func:`with_overrides`, :class:`ParameterError`, :class:`SceneError`;
- :mod:`.shapes` — the geometry of regions and sets;
- :mod:`.model` — :class:`~.model.Model` and its parts;
- :mod:`.headline` — the SS curve, the cantilever and the plate;
- :mod:`.stability` — the ring, the slab and the colliding rings;
- :mod:`.crack_band` — the mortar bar of the crack-band check;
- :mod:`.verification` — scenes written only with the API, with exact or classical answers (a 3-D
  cantilever, a bi-material bar).
- :mod:`.cracks` — :class:`~.cracks.PreCrack` and :class:`~.cracks.CrackTip` (part of
  :mod:`.model`); :mod:`.centre_crack` — a plate with a zero-width centre pre-crack under tension
  and its closed-form compliance (``workbench run centre_crack``).

The scenes of the fracture cases live with their case (``studies/rc_beam/scene.py``,
``studies/microcantilever/scene.py``); :data:`studies.STUDIES` names every study and its scene.

A user's own scene is a :class:`Scene` subclass whose :meth:`~Scene.model` returns a
:class:`~.model.Model` (README: "Your own scene").
"""
from __future__ import annotations

from . import model, shapes  # noqa: F401
from .headline import Cantilever, Plate, SSCurve
from .params import ParameterError, Scene, SceneError, param, with_overrides
from .stability import Ring, Rings, Slab
from .verification import BiMaterialBar, Cantilever3D

SCENES = {"ss_curve": SSCurve, "cantilever": Cantilever, "plate": Plate}
STABILITY_SCENES = {"ring": Ring, "slab": Slab, "rings": Rings}
VERIFICATION_SCENES = {"cantilever3d": Cantilever3D, "bimaterial_bar": BiMaterialBar}

__all__ = ["Scene", "SceneError", "ParameterError", "param", "with_overrides", "SSCurve",
           "Cantilever", "Plate", "Ring", "Slab", "Rings", "Cantilever3D", "BiMaterialBar", "SCENES",
           "STABILITY_SCENES", "VERIFICATION_SCENES",
           "model", "shapes"]
