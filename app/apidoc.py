"""The API reference of the scene vocabulary, generated from the docstrings (pdoc).

What a user writes a scene with — :mod:`workbench.scenes.params` (the parameter dataclass),
:mod:`workbench.scenes.shapes` (geometry), :mod:`workbench.scenes.model` (regions, sets,
constraints, loads, drives, observables) and :mod:`workbench.materials` (the material library) —
rendered as HTML by ``workbench docs`` (default folder ``docs/api``). The reference is not kept in
the repository: it is built from the code, and tests/test_docs.py builds it so it cannot rot.
"""
from __future__ import annotations

from pathlib import Path

MODULES = ("workbench.scenes.params", "workbench.scenes.shapes", "workbench.scenes.model",
           "workbench.scenes.cracks", "workbench.crack_geometry", "workbench.materials")
"""The modules of the scene vocabulary, in the order a user meets them."""


def build(out: Path | str = "docs/api") -> Path:
    """Write the HTML reference of :data:`MODULES` into ``out``; returns its index page."""
    import pdoc

    out = Path(out)
    pdoc.pdoc(*MODULES, output_directory=out)
    return out / "index.html"
