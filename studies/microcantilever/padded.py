"""The micro-cantilever loaded through a pad that does not fail (:class:`PaddedCantilever`), the
scene of the mode study (:mod:`.mode`). A module of its own: the run cache hashes a scene's source
files, so the study's other code can change without re-running its sweep."""
from __future__ import annotations

import dataclasses
import math

import workbench.scenes.model as m
from workbench.scenes.params import param
from workbench.scenes.shapes import Box

from .scene import MicroCantilever


@dataclasses.dataclass(frozen=True)
class PaddedCantilever(MicroCantilever):
    """:class:`.scene.MicroCantilever` loaded through a pad that does not fail: the material within
    ``pad`` of the loading patch (below it, and beyond each of its ends along the beam) keeps its
    grain's or boundary's law without damage (ε_L = ∞). The rigid patch's ends are singular
    points: without the pad, at ρ ≤ 2 the first particles to fail are the ones under its ends
    (2-D, seed 3, H/Δx = 10: 4 of 5 at ρ = 2, x = 16–18 µm, 0–0.5 µm below the top face) and
    they tear the patch off the beam — the 'cut' the drive's ``separate`` sees — at 0.8 µs, before
    a crack has crossed the beam: the share then measures the indenter's footprint, not the
    mode. A loading plate that does not fail is what a beam test puts under its load (a steel
    plate on concrete, the indenter's contact zone here)."""

    pad: float = param(1.0e-6, "m", "depth below the loading patch, and reach beyond its ends, of "
                       "the material that does not fail (0: none)", lo=0)

    def model(self, spacing: float | None = None) -> m.Model:
        model = super().model(spacing)
        if not self.pad > 0:
            return model
        dx = self.H / 10 if spacing is None else spacing
        a, b = self.patch_edges(dx)
        big = 10 * (self.B + self.H + self.L)
        up = self.dim - 1
        lo = [a - self.pad] + [-big] * (self.dim - 1)
        hi = [b + self.pad] + [big] * (self.dim - 1)
        lo[up], hi[up] = self.H / 2 - self.pad, self.H / 2 + big
        box = Box(tuple(lo), tuple(hi))
        pads = tuple(m.Region(f"pad_{r.name}", r.shape & box,
                              r.material.replace(eps_L=math.inf), priority=r.priority + 2)
                     for r in model.regions if r.name != "grain0")
        return dataclasses.replace(model, regions=model.regions + pads)
