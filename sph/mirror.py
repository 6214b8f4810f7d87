"""Symmetry planes by mirror images: a quarter (half, eighth) model that *is* the full body.

A roller whose set is a :class:`~workbench.scenes.shapes.Plane` with the roller's axis as its normal,
with the whole body on one side, is a symmetry plane (:func:`symmetry_planes`). Holding the normal
displacement there is the right boundary condition, but a particle near the plane then has a
one-sided kernel stencil: its gradient, its correction and its integration weights are those of a
free surface, not of the interior the plane really is (issue 12: the RC beam's quarter model was
11 % off the full beam at 20 mm, and at 20 mm its half width was too narrow for the quadratic
correction, so it silently fell back to the linear one).

Here the discretisation of a total-Lagrangian gradient-form body (:mod:`sph.total_lagrangian`:
csph and hpm_vc) is built on the **full** body — the particles and their images in every
combination of the planes (:func:`full_particles`), a particle on k planes counted once with
2^k times its volume — and then restricted to the real particles (:func:`restrict`): their rows
keep every neighbour of the full body; a neighbour that is an image becomes a *ghost* whose
position is the mirrored position of its source, x_g = S_g ⊙ x_src + c_g (S_g = ±1 per axis,
c_g = 2·(plane position) on the mirrored axes), and whose stress is the mirrored stress,
P_g = R P_src R with R = diag(S_g).

Why this is the full body's motion, exactly. Let w_a = 2^−k_a (k_a: the planes particle a lies
on; its share of its full-body particle). The full body's stored energy restricted to symmetric
motions is Π_full = 2^P Π_q with Π_q = Σ_real w_a V_a ψ(F_a) (V_a the full-body integration
volume, F_a from the full stencil), and its masses are 2^P times the real particles' own
(m_a = w_a m_a,full), so the quarter with Π_q and its own masses moves as the full body does.
Its force is the full body's force scaled by the share:

    f_a = −∂Π_q/∂x_a = w_a Σ_b (V_a P_a G_ab − V_b P_b G_ba)     (b over the full stencil of a)

(:func:`sph.total_lagrangian.internal_force` with the ghosts' V P mirrored, times ``w``), and its
tangent is the full stencil's, folded onto the real DOFs: K_q = Tᵀ K_ext T with T the map from
the real DOFs to the real and ghost ones (:func:`sph.total_lagrangian.tangent_matrix`).
Energies, work and reactions of the quarter are the full body's divided by 2^P.

Classic SPH (:mod:`sph.classic`) searches its neighbours in the current configuration (with a skin,
again once a particle has moved half of it), so it finds its ghosts with them
(``Body._find_ghosts``): the particles within 2h and the skin of every plane of a combination,
mirrored with their velocity, density and stress (σ_g = R σ_src R), the neighbour sums taking the
full body's masses (a plane particle's whole mass). Its rates and accelerations are per particle, so
they are the full body's without a share.

Only lattice particles on the node lattice are mirrored (a node lies on each plane, so a plane
particle is its own image and the roller holds its normal DOF, which the full body's symmetry
also does); on the cell lattice, where no particle lies on the plane, the roller would hold the
first layer off the plane, so no images are made there (:func:`symmetry_planes` returns none).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

import numpy as np

from workbench.scenes.shapes import Plane


def symmetry_planes(model, ps, tol: float) -> tuple:
    """The symmetry planes of ``model`` discretised as ``ps``: ((axis, at, set name), ...) for
    every :class:`~workbench.scenes.model.Roller` on a :class:`Plane` set with the roller's axis
    as its normal, a set of every region (none named), the body on one side of it, and no other
    such plane of the same axis. ``tol`` m: the sets' tolerance."""
    from workbench.scenes import model as M

    shapes = {s.name: s for s in model.sets}
    out = []
    for c in model.constraints:
        s = shapes.get(c.set)
        if not (isinstance(c, M.Roller) and s is not None and isinstance(s.shape, Plane)
                and s.shape.axis == c.axis and s.region is None):
            continue
        rel = ps.X[:, c.axis] - s.shape.at
        if np.all(rel >= -tol) or np.all(rel <= tol):
            out.append((int(c.axis), float(s.shape.at), c.set))
    axes = [a for a, _, _ in out]
    # two planes of one axis (a channel) mirror each other's images without end: neither is used
    return tuple(p for p in out if axes.count(p[0]) == 1)


@dataclass(frozen=True)
class Folded:
    """``shape`` seen through mirrors: X is inside when its reflection into the side of the
    planes the body lies on is inside ``shape``. planes: ((axis, at, side), ...), side ±1."""

    shape: object
    planes: tuple

    def contains(self, X, tol=0.0):
        X = np.array(X, dtype=np.float64, ndmin=2, copy=True)
        for axis, at, side in self.planes:
            X[:, axis] = at + side * np.abs(X[:, axis] - at)
        return self.shape.contains(X, tol)


@dataclass
class Images:
    """The full body of a mirrored particle set (:func:`full_particles`).

    full: the full body's :class:`sph.particles.Particles` (the real particles first, then the
    images); src (n_full,) the real particle each is an image of; sign (n_full, d) ±1 and offset
    (n_full, d) m: x_full = sign ⊙ x_src + offset; w (N,) each real particle's share 2^−k of its
    full-body particle (k: the planes it lies on)."""

    full: object
    src: np.ndarray
    sign: np.ndarray
    offset: np.ndarray
    w: np.ndarray


def on_planes(X, planes, tol: float) -> np.ndarray:
    """(N, P) bool: point i of X (N, d) lies on plane j of ``planes`` ((axis, at, ...), ...) to
    ``tol`` (m)."""
    X = np.asarray(X)
    return np.stack([np.abs(X[:, p[0]] - p[1]) <= tol for p in planes], axis=1) if planes \
        else np.zeros((len(X), 0), bool)


def plane_images(X, planes, on, near=None):
    """The images of the points X (N, d) in every combination of the ``planes`` ((axis, at, ...),
    ...): point i has one in a combination when it lies on none of its planes (``on`` (N, P),
    :func:`on_planes`: there it is its own image) and, given ``near`` (N, P) bool, is near every
    one of them. Returns (src, sign, offset): image = sign ⊙ X[src] + offset, sign ±1 and offset
    2·at on the mirrored axes."""
    N, d = np.shape(X)
    src, sign, offset = [np.zeros(0, np.int64)], [np.zeros((0, d))], [np.zeros((0, d))]
    for r in range(1, len(planes) + 1):
        for combo in itertools.combinations(range(len(planes)), r):
            c = list(combo)
            sel = ~on[:, c].any(axis=1)
            if near is not None:
                sel &= near[:, c].all(axis=1)
            idx = np.flatnonzero(sel)
            s, o = np.ones(d), np.zeros(d)
            for j in combo:
                s[planes[j][0]] = -1.0
                o[planes[j][0]] = 2.0 * planes[j][1]
            src.append(idx)
            sign.append(np.tile(s, (len(idx), 1)))
            offset.append(np.tile(o, (len(idx), 1)))
    return np.concatenate(src), np.concatenate(sign), np.concatenate(offset)


def image_rows(a, src, sign=None, offset=None):
    """The rows ``src`` of ``a`` (N, ...) as seen in the mirrors: a scalar per row as it is; a
    vector (n, d) as sign ⊙ a[src] + offset (a position; a velocity without offset); a tensor
    (n, k, k) as R a[src] R with R = diag(sign) padded with ones to k (a plane-strain σ_zz keeps
    its sign)."""
    img = a[src]
    if sign is not None and a.ndim == 2:
        img = sign * img + (0.0 if offset is None else offset)
    elif sign is not None and a.ndim == 3:
        s = np.ones((len(src), a.shape[1]))
        s[:, :sign.shape[1]] = sign
        img = s[:, :, None] * img * s[:, None, :]
    return img


def with_images(a, src, sign=None, offset=None):
    """``a`` (N, ...) followed by its :func:`image_rows`."""
    return np.concatenate([a, image_rows(a, src, sign, offset)])


def full_particles(ps, planes, tol: float) -> Images:
    """The particles ``ps`` and their images in every combination of the symmetry ``planes``
    ((axis, at, set name), ...; :func:`symmetry_planes`): an image is made only where the particle
    is not on one of the mirrors of that combination (there it is its own image). A particle on k
    planes gets 2^k times its volume and mass in the full body; its fixed DOFs along the normals
    of those planes are released (the full body's symmetry holds them), unless it is clamped."""
    N, d = ps.X.shape
    on = on_planes(ps.X, planes, tol)
    w = 0.5 ** on.sum(axis=1)
    s_i, g_i, o_i = plane_images(ps.X, planes, on)
    src = np.concatenate([np.arange(N), s_i])
    sign = np.concatenate([np.ones((N, d)), g_i])
    offset = np.concatenate([np.zeros((N, d)), o_i])
    X = sign * ps.X[src] + offset
    fixed = ps.fixed.copy()
    for j, (a, at, _) in enumerate(planes):
        fixed[on[:, j] & ~ps.clamped, a] = False
    sides = tuple((a, at, 1.0 if np.all(ps.X[:, a] >= at - tol) else -1.0) for a, at, _ in planes)
    full = replace(ps, X=np.ascontiguousarray(X), V=(ps.V / w)[src], mat_id=ps.mat_id[src],
                   region=ps.region[src], body=ps.body[src], held=ps.held[src],
                   # normals: the quarter's mirrored (a plane particle's keeps its plane face);
                   # the consistent integration recomputes them on the folded domain
                   normals=sign * ps.normals[src], sets={}, probes={}, fixed=fixed[src],
                   clamped=ps.clamped[src], domain=ps.domain[src],
                   domain_shape=(None if ps.domain_shape is None
                                 else Folded(ps.domain_shape, sides)))
    return Images(full, src, sign, offset, w)


def restrict(disc, images: Images, m):
    """The rows of the real particles of the full body's discretisation ``disc``
    (:class:`sph.total_lagrangian.Discretisation` of ``images.full``): neighbours that are images
    become ghosts numbered from N on (``ghost_src``, ``ghost_sign``, ``ghost_offset``); X, V, L,
    ok of the real particles (V the full-body integration volumes), masses ``m`` (N,) the real
    particles' own, ``w`` their shares."""
    N = images.w.shape[0]
    end = disc.indptr[N]
    cols = disc.indices[:end]
    ghosts = np.unique(cols[cols >= N])
    remap = np.full(disc.n, -1, np.int64)
    remap[:N] = np.arange(N)
    remap[ghosts] = N + np.arange(len(ghosts))
    out = replace(disc, X=disc.X[:N].copy(), V=disc.V[:N].copy(),
                  m=np.ascontiguousarray(m, dtype=np.float64), indptr=disc.indptr[:N + 1].copy(),
                  indices=remap[cols], G=disc.G[:end].copy(), GT=disc.GT[:end].copy(),
                  L=disc.L[:N].copy() if disc.L is not None and len(disc.L) == disc.n else disc.L,
                  ok=disc.ok[:N].copy())
    out.ghost_src = np.ascontiguousarray(images.src[ghosts])
    out.ghost_sign = np.ascontiguousarray(images.sign[ghosts])
    out.ghost_offset = np.ascontiguousarray(images.offset[ghosts])
    out.w = np.ascontiguousarray(images.w)
    return out
