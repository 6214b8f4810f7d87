"""Particle generation on regular lattices, with named particle sets for boundary conditions.

Two lattices over an axis-aligned box of spacing Δx (``mode``):

* ``"cell"``: one particle at the centre of each cubic cell of side Δx, volume Δx^d — the box is
  tiled exactly, every particle carries the same volume, and the free surfaces lie Δx/2 outside the
  outermost particles;
* ``"node"``: particles on the lattice nodes including the faces, volumes by the trapezoid rule
  (halved on each face the particle lies on) so that Σ V = box volume and the energy
  Σ V_a ψ(F_a) is the trapezoid quadrature of ∫ ψ dV.

The scene builders (:func:`block`, :func:`plate`, :func:`cantilever`) return a :class:`ParticleSet`
whose ``sets`` name the particles each boundary condition acts on; every particle method (CSPH,
HPM, classic SPH) builds its particles here so that all methods see the same discretisation.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

MODES = ("cell", "node")


@dataclass
class ParticleSet:
    """Reference positions ``X`` (N, d) m, volumes ``V`` (N,) m^d (m² per unit thickness in 2-D),
    spacing ``dx`` m, named index sets (``sets[name]`` int arrays) and probes
    (``probes[name] = (indices, weights)``: an observable Σ w_i u(X_i), e.g. a tip mid-point)."""

    X: np.ndarray
    V: np.ndarray
    dx: float
    sets: dict = field(default_factory=dict)
    probes: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return self.X.shape[0]

    @property
    def dim(self) -> int:
        return self.X.shape[1]

    def mask(self, name: str) -> np.ndarray:
        m = np.zeros(self.n, bool)
        m[self.sets[name]] = True
        return m


def _axis(lo: float, hi: float, dx: float, mode: str):
    """1-D coordinates and volume weights (in units of dx) of one lattice axis."""
    n = int(round((hi - lo) / dx))
    if n < 1 or abs(n * dx - (hi - lo)) > 1e-9 * max(abs(hi - lo), dx):
        raise ValueError(f"dx: {dx:g} m does not divide the length {hi - lo:g} m into whole cells")
    if mode == "cell":
        return lo + (np.arange(n) + 0.5) * dx, np.ones(n)
    if mode == "node":
        w = np.ones(n + 1)
        w[0] = w[-1] = 0.5
        return lo + np.arange(n + 1) * dx, w
    raise ValueError(f"mode: {mode!r} is not one of {MODES}")


def grid(lo, hi, dx: float, mode: str = "cell") -> tuple[np.ndarray, np.ndarray]:
    """Lattice points ``X`` (N, d) and volumes ``V`` (N,) of the box [lo, hi] (d = len(lo)),
    first axis slowest."""
    axes = [_axis(a, b, dx, mode) for a, b in zip(lo, hi)]
    mesh = np.meshgrid(*[a[0] for a in axes], indexing="ij")
    wts = np.meshgrid(*[a[1] for a in axes], indexing="ij")
    X = np.stack([m.ravel() for m in mesh], axis=1)
    V = np.prod(np.stack([m.ravel() for m in wts], axis=1), axis=1) * dx ** len(lo)
    return X, V


def _near(a, b, dx):
    return np.abs(a - b) < 1e-6 * dx


def block(size, n: int, mode: str = "node") -> ParticleSet:
    """A box [0, size[0]] × … with ``n`` cells along the first edge (cubic cells). Sets: the faces
    ``x0, x1, y0, y1[, z0, z1]`` (particles on the face in ``node`` mode, the outermost layer in
    ``cell`` mode)."""
    size = np.atleast_1d(np.asarray(size, dtype=np.float64))
    dx = size[0] / n
    X, V = grid(np.zeros_like(size), size, dx, mode)
    ps = ParticleSet(X, V, dx)
    for k, ax in enumerate("xyz"[: len(size)]):
        ps.sets[f"{ax}0"] = np.nonzero(_near(X[:, k], X[:, k].min(), dx))[0]
        ps.sets[f"{ax}1"] = np.nonzero(_near(X[:, k], X[:, k].max(), dx))[0]
    return ps


def _beam(L: float, H: float, back: float, resolution: int, mode: str) -> ParticleSet:
    """2-D beam 0 ≤ X ≤ L, −H/2 ≤ Y ≤ H/2 with a fixed block of length ``back`` behind X = 0.

    Sets: ``fixed`` (the block; in ``node`` mode also the particles on X = 0, so the clamp face is
    X = 0), ``free`` (the rest), ``tip`` (the column at the largest X). Probe ``tip_mid``: the
    displacement of the tip mid-point (X = L, Y = 0), interpolated linearly along the tip column to
    Y = 0 and, in ``cell`` mode, extrapolated linearly from the last two columns to X = L.
    """
    if not (isinstance(resolution, (int, np.integer)) and resolution >= 1):
        raise ValueError(f"resolution: {resolution!r} is not allowed; particles across H, an integer >= 1")
    dx = H / resolution
    X, V = grid((-back, -H / 2), (L, H / 2), dx, mode)
    if mode == "node":
        # X = 0 lies inside the combined box: full volume there already; the tip face stays halved.
        fixed = X[:, 0] <= 1e-9 * dx
    else:
        fixed = X[:, 0] < 0
    ps = ParticleSet(X, V, dx)
    ps.sets["fixed"] = np.nonzero(fixed)[0]
    ps.sets["free"] = np.nonzero(~fixed)[0]
    xmax = X[:, 0].max()
    tip = np.nonzero(_near(X[:, 0], xmax, dx))[0]
    ps.sets["tip"] = tip[np.argsort(X[tip, 1])]
    idx, wts = [], []
    cols = [(xmax, 1.5 if mode == "cell" else 1.0), (xmax - dx, -0.5 if mode == "cell" else 0.0)]
    for xc, wc in cols:
        if wc == 0.0:
            continue
        col = np.nonzero(_near(X[:, 0], xc, dx))[0]
        col = col[np.argsort(X[col, 1])]
        y = X[col, 1]
        j = int(np.searchsorted(y, 0.0))
        if j < len(y) and _near(y[j], 0.0, dx):
            idx.append(col[j]); wts.append(wc)
        else:
            t = (0.0 - y[j - 1]) / (y[j] - y[j - 1])
            idx += [col[j - 1], col[j]]; wts += [wc * (1 - t), wc * t]
    ps.probes["tip_mid"] = (np.asarray(idx, np.int64), np.asarray(wts))
    return ps


def plate(scene, resolution: int, mode: str = "cell") -> ParticleSet:
    """Particles of the oscillating plate (004 D): free length ``scene.L``, a fixed block of
    ``scene.clamp_length`` behind X = 0 (rounded to whole cells), ``resolution`` = H/Δx."""
    dx = scene.H / resolution
    back = round(scene.clamp_length / dx) * dx
    return _beam(scene.L, scene.H, max(back, dx), resolution, mode)


def cantilever(scene, resolution: int, mode: str = "cell") -> ParticleSet:
    """Particles of the static cantilever (004 E): ``scene.clamp_layers`` fixed layers behind X = 0
    (in ``node`` mode the X = 0 layer is fixed too), ``resolution`` = H/Δx."""
    dx = scene.H / resolution
    return _beam(scene.L, scene.H, scene.clamp_layers * dx, resolution, mode)
