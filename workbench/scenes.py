"""The benchmark scenes (``../shared/design/scenes.md``) as frozen dataclasses.

A scene says what a problem needs — dimension and plane, geometry, material, loads, end time —
so that each solver models no more than that. Every field is a parameter that ``workbench list``
shows and ``--set NAME=VALUE`` overrides; each carries its units, allowed range and a description in
its ``metadata``. Scenes are changed by copies: :func:`with_overrides` validates every value and
raises :class:`ParameterError` naming the parameter and its allowed range.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

from .materials import Material


class ParameterError(ValueError):
    """A scene or run parameter outside its allowed range (the CLI prints it as one line)."""


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


# ------------------------------------------------------------------------------------------------
# Headline scenes
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class SSCurve(Scene):
    """Uniaxial tension of a block (000, Table 1, Fig. 1): rollers on the three symmetry faces
    X=0, Y=0, Z=0, lateral faces free, the face X=a moved so that the logarithmic axial strain
    grows to ``max_strain`` (optionally unloaded by ``unload_by`` and reloaded). Homogeneous: a
    handful of particles or elements suffices."""

    name: str = field(default="ss_curve", metadata=dict(hidden=True))
    E: float = param(202e9, "Pa", "Young's modulus", lo=0, lo_open=True)
    nu: float = param(0.3, "-", "Poisson's ratio", lo=-1, hi=0.5, lo_open=True, hi_open=True)
    C: float = param(868.8e6, "Pa", "Swift hardening coefficient", lo=0, lo_open=True)
    eps0: float = param(0.0013, "-", "Swift pre-strain", lo=0, lo_open=True)
    n: float = param(0.179, "-", "Swift exponent", lo=0, hi=1, hi_open=True)
    rho: float = param(7974.0, "kg/m^3", "density", lo=0, lo_open=True)
    eps_L: float = param(math.inf, "-", "damage limit plastic strain (inf: no damage)", lo=0, lo_open=True)
    size: float = param(1e-3, "m", "edge of the cubic block (a)", lo=0, lo_open=True)
    max_strain: float = param(0.3, "-", "final logarithmic axial strain", lo=0, hi=2, lo_open=True)
    n_steps: int = param(60, "-", "load steps past twice the yield strain (4 more before)", lo=1, hi=100000)
    unload: bool = param(False, "-", "add an unload-reload cycle at the end")
    unload_by: float = param(0.003, "-", "log strain removed by the unloading (about the elastic "
                                         "strain at yield: a larger value yields in compression)",
                             lo=0, lo_open=True)

    def check(self):
        if self.unload and not self.unload_by <= self.max_strain:
            raise ParameterError(f"unload_by: {self.unload_by:g} is out of range; allowed: "
                                 f"(0, max_strain={self.max_strain:g}]")

    @property
    def material(self) -> Material:
        return Material.j2(E=self.E, nu=self.nu, C=self.C, eps0=self.eps0, n=self.n,
                           rho=self.rho, eps_L=self.eps_L)

    def strain_path(self):
        """The prescribed logarithmic axial strain at each load step (monotonic, then the optional
        unload–reload cycle), starting after 0."""
        import numpy as np

        # four steps through the elastic range (to twice the yield strain), then uniform steps
        e_y = 2 * self.C * self.eps0 ** self.n / self.E
        if e_y < 0.5 * self.max_strain:
            up = np.concatenate([np.linspace(0, e_y, 5)[1:],
                                 np.linspace(e_y, self.max_strain, self.n_steps + 1)[1:]])
        else:
            up = np.linspace(0, self.max_strain, self.n_steps + 1)[1:]
        if not self.unload:
            return up
        k = max(2, self.n_steps // 6)
        low = self.max_strain - self.unload_by
        down = np.linspace(self.max_strain, low, k + 1)[1:]
        back = np.linspace(low, self.max_strain, k + 1)[1:]
        return np.concatenate([up, down, back])


@dataclass(frozen=True)
class Cantilever(Scene):
    """Static tip-loaded cantilever (004 E), 2-D. The beam occupies 0 ≤ X ≤ L, −H/2 ≤ Y ≤ H/2 and is
    rigidly clamped at X = 0 (particle methods hold a block of particles behind X = 0 fixed); the tip
    load P (per unit thickness) acts downward (−Y) as a uniform shear traction on the tip face X = L.
    ``loads`` are the dimensionless loads P L²/(E I), I = H³/12; the paper's small load
    P = 0.005 N is first."""

    name: str = field(default="cantilever", metadata=dict(hidden=True))
    L: float = param(0.16, "m", "free length", lo=0, lo_open=True)
    H: float = param(0.02, "m", "thickness", lo=0, lo_open=True)
    E: float = param(1.0e5, "Pa", "Young's modulus", lo=0, lo_open=True)
    nu: float = param(0.3, "-", "Poisson's ratio", lo=-1, hi=0.5, lo_open=True, hi_open=True)
    rho: float = param(1000.0, "kg/m^3", "density (not given by 004: our choice)", lo=0, lo_open=True)
    law: str = param("svk", "-", "hyperelastic law", choices=("svk", "neo_hooke"))
    plane: str = param("strain", "-", "2-D idealisation", choices=("strain", "stress"))
    loads: tuple = param((0.0019200000000000003, 1.0, 2.0, 5.0), "-",
                         "dimensionless tip loads P L^2/(E I)", lo=0, hi=50, lo_open=True)
    clamp_layers: int = param(3, "-", "particle layers behind X = 0 held fixed (particle methods)",
                              lo=1, hi=20)

    def check(self):
        if self.H >= self.L:
            raise ParameterError(f"H: {self.H:g} m is out of range; allowed: (0, L={self.L:g}) m")

    @property
    def material(self) -> Material:
        return Material(law=self.law, E=self.E, nu=self.nu, rho=self.rho).validated()

    @property
    def I(self) -> float:
        return self.H ** 3 / 12.0

    def force(self, load: float) -> float:
        """Tip force per unit thickness, N/m, for a dimensionless load P L²/(E I)."""
        return load * self.E * self.I / self.L ** 2


@dataclass(frozen=True)
class Plate(Scene):
    """Oscillating cantilever plate (004 D, Table I; Gray, Monaghan & Swift 2001), plane strain.
    Free length L from the clamp (X = 0) with a further ``clamp_length`` behind it held rigidly
    fixed (particle methods fix those particles; the FEM clamps X = 0 rigidly: the same clamp).
    Initial velocity v_y(X) = V_f c0 f(X)/f(L) with Gray et al.'s mode shape f (scenes.md)."""

    name: str = field(default="plate", metadata=dict(hidden=True))
    L: float = param(0.2, "m", "free length", lo=0, lo_open=True)
    clamp_length: float = param(0.04, "m", "clamped length behind X = 0", lo=0, lo_open=True)
    H: float = param(0.02, "m", "thickness", lo=0, lo_open=True)
    K: float = param(3.25e6, "Pa", "bulk modulus", lo=0, lo_open=True)
    G: float = param(7.15e5, "Pa", "shear modulus", lo=0, lo_open=True)
    rho: float = param(1000.0, "kg/m^3", "density", lo=0, lo_open=True)
    law: str = param("svk", "-", "hyperelastic law", choices=("svk", "neo_hooke"))
    V_f: float = param(0.01, "-", "tip velocity over c0", lo=0, hi=1, lo_open=True)
    kL: float = param(1.875104068711961, "-", "first root of cos kL cosh kL = -1", lo=0, lo_open=True)
    periods: float = param(2.0, "-", "simulated time in thin-plate periods", lo=0, hi=1000, lo_open=True)
    dt_factor: float = param(0.3, "-", "time step over the CFL estimate", lo=0, hi=10, lo_open=True)

    def check(self):
        if self.H >= self.L:
            raise ParameterError(f"H: {self.H:g} m is out of range; allowed: (0, L={self.L:g}) m")
        if self.K <= 2 * self.G / 3:
            raise ParameterError(f"K: {self.K:g} Pa gives nu <= 0 here; allowed: K > 2G/3")

    @property
    def material(self) -> Material:
        return Material.from_bulk_shear(self.law, K=self.K, G=self.G, rho=self.rho)

    @property
    def c0(self) -> float:
        return math.sqrt(self.K / self.rho)


SCENES = {"ss_curve": SSCurve, "cantilever": Cantilever, "plate": Plate}
