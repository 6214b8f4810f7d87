"""Scene parameters: the frozen dataclass :class:`Scene` whose fields are what ``workbench list``
shows and ``--set NAME=VALUE`` overrides.

Each field carries its units, allowed range and a description in its ``metadata`` (:func:`param`).
Scenes are changed by copies: :func:`with_overrides` validates every value and raises
:class:`ParameterError` naming the parameter and its allowed range. A concrete scene turns its
parameters into data, :meth:`Scene.model` (a :class:`workbench.scenes.model.Model`: regions,
sets, loads, drive, observables), which every method reads, and :meth:`Scene.summarise` turns a
run's generic observables into the quantities of its study.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any



class ParameterError(ValueError):
    """A scene or run parameter outside its allowed range (the CLI prints it as one line)."""


class SceneError(ParameterError):
    """A model that does not hold together (a region without a material, a load on a set that does
    not exist, a set that selects nothing): one line naming the part and what is wrong."""


def param(default, units: str, doc: str, lo: float | None = None, hi: float | None = None,
          lo_open: bool = False, hi_open: bool = False, choices: tuple | None = None):
    """A scene field with units, an allowed range (``lo``/``hi``, open or closed) and a description."""
    return field(default=default, metadata=dict(units=units, doc=doc, lo=lo, hi=hi,
                                                lo_open=lo_open, hi_open=hi_open, choices=choices,
                                                boolean=isinstance(default, bool)))


def _range_text(md) -> str:
    if md.get("boolean"):
        return "true or false"
    if md.get("choices"):
        return "one of " + ", ".join(map(str, md["choices"]))
    lo, hi = md.get("lo"), md.get("hi")
    left = "(" if md.get("lo_open") else "["
    right = ")" if md.get("hi_open") else "]"
    lo_s = "-inf" if lo is None else f"{lo:g}"
    hi_s = "inf" if hi is None else f"{hi:g}"
    if lo is None:
        left = "("
    if hi is None:
        right = ")"
    return f"{left}{lo_s}, {hi_s}{right}"


def _check_value(name: str, value, md) -> None:
    units = md.get("units") or ""
    unit_s = f" {units}" if units and units != "-" else ""
    if md.get("choices"):
        if value not in md["choices"]:
            raise ParameterError(f"{name}: {value!r} is not allowed; allowed: {_range_text(md)}")
        return
    if isinstance(value, tuple):
        for v in value:
            _check_value(name, v, md)
        return
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return
    lo, hi = md.get("lo"), md.get("hi")
    bad = (isinstance(value, float) and math.isnan(value))
    if lo is not None:
        bad |= value <= lo if md.get("lo_open") else value < lo
    if hi is not None:
        bad |= value >= hi if md.get("hi_open") else value > hi
    if bad:
        raise ParameterError(f"{name}: {value:g}{unit_s} is out of range; allowed: {_range_text(md)}{unit_s}")


@dataclass(frozen=True)
class Scene:
    """Base class: validation, parameter listing and overrides shared by every scene."""

    name: str = field(default="scene", metadata=dict(hidden=True))

    def __post_init__(self):
        for f in dataclasses.fields(self):
            if f.metadata.get("hidden"):
                continue
            _check_value(f.name, getattr(self, f.name), f.metadata)
        self.check()

    def check(self) -> None:
        """Cross-parameter checks of a concrete scene."""

    def model(self):
        """The scene as data (:class:`workbench.scenes.model.Model`)."""
        raise NotImplementedError(f"scene '{self.name}' has no model")

    def summarise(self, out: dict) -> dict:
        """The study's quantities from a run's generic result ``out`` (observables by name, their
        histories, energies): a dict merged into ``out``. The default adds nothing."""
        return {}

    @classmethod
    def parameters(cls) -> list[dict[str, Any]]:
        """Name, default, units, allowed range and description of every parameter."""
        out = []
        for f in dataclasses.fields(cls):
            if f.metadata.get("hidden"):
                continue
            out.append(dict(name=f.name, default=f.default, units=f.metadata.get("units", ""),
                            range=_range_text(f.metadata), doc=f.metadata.get("doc", "")))
        return out

    def attrs(self) -> dict[str, Any]:
        """The parameters as dataset attributes (``param_NAME``) with their units."""
        out = {}
        for f in dataclasses.fields(self):
            if f.metadata.get("hidden"):
                continue
            v = getattr(self, f.name)
            if isinstance(v, bool):
                v = int(v)
            elif isinstance(v, tuple):
                v = list(v)
            out[f"param_{f.name}"] = v
            out[f"param_{f.name}_units"] = f.metadata.get("units", "")
        return out


def with_overrides(scene: Scene, overrides: dict[str, str]) -> Scene:
    """A copy of ``scene`` with string overrides (``--set NAME=VALUE``) parsed and validated."""
    fields = {f.name: f for f in dataclasses.fields(scene) if not f.metadata.get("hidden")}
    changes = {}
    for name, text in overrides.items():
        if name not in fields:
            raise ParameterError(f"{name}: unknown parameter of scene '{scene.name}'; "
                                 f"known: {', '.join(fields)}")
        default = fields[name].default
        try:
            if isinstance(default, bool):
                if text.lower() not in ("true", "false", "1", "0", "yes", "no"):
                    raise ValueError
                value = text.lower() in ("true", "1", "yes")
            elif isinstance(default, int):
                value = int(text)
            elif isinstance(default, float):
                value = float(text)
            elif isinstance(default, tuple):
                value = tuple(float(t) for t in text.split(",") if t.strip())
            else:
                value = text
        except ValueError:
            raise ParameterError(f"{name}: cannot read {text!r} as {type(default).__name__}; "
                                 f"allowed: {_range_text(fields[name].metadata)}") from None
        changes[name] = value
    try:
        return dataclasses.replace(scene, **changes)
    except ValueError as err:  # Material validation or a cross check
        raise ParameterError(str(err)) from None
