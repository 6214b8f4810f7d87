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
import numbers
from dataclasses import dataclass, field
from typing import Any


class ParameterError(ValueError):
    """A scene or run parameter outside its allowed range (the CLI prints it as one line)."""


class SceneError(ParameterError):
    """A model that does not hold together (a region without a material, a load on a set that does
    not exist, a set that selects nothing): one line naming the part and what is wrong."""


def param(default, units: str, doc: str, lo: float | None = None, hi: float | None = None,
          lo_open: bool = False, hi_open: bool = False, choices: tuple | None = None):
    """A scene field with units, an allowed range (``lo``/``hi``, open or closed) and a description.
    A number must be finite unless the default is infinite (``eps_L = inf``: no damage); a tuple
    of numbers must hold at least one value."""
    values = default if isinstance(default, tuple) else (default,)
    infinite = any(isinstance(v, float) and math.isinf(v) for v in values)
    return field(default=default, metadata=dict(units=units, doc=doc, lo=lo, hi=hi,
                                                lo_open=lo_open, hi_open=hi_open, choices=choices,
                                                boolean=isinstance(default, bool),
                                                allow_inf=infinite))


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
        right = "]" if md.get("allow_inf") else ")"
    return f"{left}{lo_s}, {hi_s}{right}"


def _kind(default) -> str:
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, int):
        return "int"
    if isinstance(default, float):
        return "float"
    if isinstance(default, tuple):
        return "tuple"
    return "other"


def _check_type(name: str, value, default, md) -> None:
    """The value has the parameter's type: a bool, an integer, a real number, a non-empty tuple of
    real numbers (a scene built in Python gets the one-line error the command line gets)."""
    kind = _kind(default)
    allowed = _range_text(md)
    if kind == "bool" and not isinstance(value, bool):
        raise ParameterError(f"{name}: {value!r} is not allowed; allowed: {allowed}")
    if kind == "int" and (isinstance(value, bool) or not isinstance(value, numbers.Integral)):
        raise ParameterError(f"{name}: {value!r} is not an integer; allowed: integers in {allowed}")
    if kind == "float" and (isinstance(value, bool) or not isinstance(value, numbers.Real)):
        raise ParameterError(f"{name}: {value!r} is not a number; allowed: {allowed}")
    if kind == "tuple":
        if not isinstance(value, tuple) or not all(
                isinstance(v, numbers.Real) and not isinstance(v, bool) for v in value):
            raise ParameterError(f"{name}: {value!r} is not a list of numbers; allowed: one or more "
                                 f"comma-separated values in {allowed}")
        if default and not value:
            raise ParameterError(f"{name}: the list is empty; allowed: one or more comma-separated "
                                 f"values in {allowed}")


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
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return
    value = float(value) if not isinstance(value, numbers.Integral) else value
    if isinstance(value, float) and not math.isfinite(value) and not (
            math.isinf(value) and md.get("allow_inf") and value > 0):
        raise ParameterError(f"{name}: {value:g} is not a finite number; allowed: "
                             f"{_range_text(md)}{unit_s}")
    lo, hi = md.get("lo"), md.get("hi")
    bad = False
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
            value = getattr(self, f.name)
            if isinstance(f.default, tuple) and isinstance(value, list):
                value = tuple(value)
                object.__setattr__(self, f.name, value)
            if f.default is not dataclasses.MISSING:
                _check_type(f.name, value, f.default, f.metadata)
            _check_value(f.name, value, f.metadata)
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
        for v in (value if isinstance(value, tuple) else (value,)):
            if (isinstance(v, float) and math.isinf(v) and "inf" not in text.lower()):
                units = fields[name].metadata.get("units") or ""
                unit_s = f" {units}" if units and units != "-" else ""
                raise ParameterError(f"{name}: {text} overflows to inf (not a finite number); "
                                     f"allowed: {_range_text(fields[name].metadata)}{unit_s}")
        changes[name] = value
    try:
        return dataclasses.replace(scene, **changes)
    except ValueError as err:  # Material validation or a cross check
        raise ParameterError(str(err)) from None
