"""Cracks in a gradient-form body (CSPH): which neighbour pairs still interact once particles have
failed (damage D = ε_p/ε_L ≥ 1, paper 000 eq. 36; for any law, :func:`workbench.materials.failure.failed`:
the mortar fully released along some axis, the brittle law's crack fully open).

The paper says only "stress zero once D ≥ 1". With neighbours fixed in the reference
configuration that is not enough for a crack to open: an intact particle's deformation gradient
F_a = Σ_b (x_b − x_a) ⊗ G_ab (eq. 35) still sees the neighbours on the far side of a band of failed
particles (the kernel support, 2h = 2.2 Δx, reaches across a band one particle wide) and the failed
particles themselves, whose positions follow both faces; the opening of the band is read as a
strain of the intact particles beside it, which keep pulling the faces together, and the load does
not fall to zero (measured: the micro-cantilever keeps about half its peak load, studies
``microcantilever``).

The rule here is the *visibility criterion* of meshfree crack modelling (Belytschko, Lu & Gu 1994;
Organ, Fleming, Terry & Belytschko 1996), with a failed particle as the opaque body: the row of any
particle a drops the pair (a, b) when b has failed or when the segment X_a–X_b passes through the
interior of the cell (the cube of side Δx centred on the particle) of a failed neighbour of a, in
the reference configuration (:func:`visible_rows`). Failed cells that touch close the crack between
them: a segment that meets the closed cells of two blocked neighbours at one point — the corner (an
edge in 3-D) where the cells of a crack stepping sideways by one particle meet — is cut too. Without
that a staircase crack leaks along its diagonal: the intact particles on either side of the step
see each other through the common corner, and a one-particle ligament keeps carrying the load
(measured: the intra-granular micro-cantilever at H/Δx = 10 kept 7 % of its peak load to the end
of the run). So two failed particles no longer interact,
an intact particle no longer sees failed ones nor what lies behind them, and a failed particle
still sees the intact particles around it: its F, and so its compressive response (the
'compression' failure mode), follows the faces of the crack, which push on each other through it
when it closes.

A row that loses pairs is corrected again so that its F stays exact for affine motions — but from
the current configuration, not the reference one: with F = Σ_alive (x_b − x_a) ⊗ G_ab and
N = Σ_kept (x_b − x_a) ⊗ G_ab at the current positions, G'_ab = (N⁻¹ F)ᵀ G_ab on the kept pairs.
Then F is continuous at the change (Σ_kept (x_b − x_a) ⊗ G'_ab = F: no jump of stress or stored
energy, which a correction on the reference configuration gives wherever the displacement is not
affine — near a crack tip, everywhere), and any later affine motion x ↦ A x + c gives A F. Where
what a still sees hardly spans a direction (a sliver between a crack and a free surface), N⁻¹ F
would multiply the gradients — the stiffness — without bound and the explicit step would go
unstable: when the smallest singular value of F⁻¹ N is below :data:`MIN_SINGULAR` the particle is
*detached* instead (its row emptied, its integration volume zero: a fragment that keeps its mass
and moves on freely), and from then on it blocks the view of the others as a failed particle does
(else, seen from both faces, it would pass forces across the crack). A *ligament one particle
thick* is detached too (:func:`ligaments`): an intact particle whose lattice neighbours on both
sides along an axis (±Δx) are failed or detached — the gap of one particle left where two crack
fronts meet (the intra-granular micro-cantilever: a crack down from the top face and one up from
the crushed bottom of the root, the last particle at D = 0.64). Its row still sees both faces, and
its F, a weighted mean of what both sides do, reads a rotation of one face about it as half that
rotation, not as strain: it is a hinge — a node shared by two parts, as two finite elements
sharing one node — that carries the beam's shear but no moment, never strains to failure, and
keeps the parts joined to the end of the run (measured before this rule: H/Δx = 10 and 15, 8 µs,
2.7 % and 5.0 % of the peak load left, the crack never complete). The continuum ligament it
stands for has no width. The integration-consistent correction of the body is left as it is near a
crack.

A failed particle of the 'compression' mode that fails compressed (J < 1: the crushed bottom of
the micro-cantilever's root, the top face under its loading patch) keeps its volumetric pressure
(:func:`workbench.materials.j2.failed_stress`) and is *not* blocked while it stays compressed:
its neighbours keep it in their rows, so their stresses still balance its pressure, and it carries
the compression across the crack as the crushed material does. It is blocked once J ≥ 1 (it
opens; :meth:`Cracks.opened`, checked at the end of every call of the time loop and at every
failure), when its pressure is zero. Blocked at once instead, as every failed particle was, it
kept its pressure with nothing to balance it but its own one-sided row (f_a = V_a P_a Σ_b G_ab):
within 5–30 steps that pressure expelled it, its kinetic energy the volumetric energy
½ K (ln J)² V it failed with (measured: studies.microcantilever 2-D, H/Δx = 5, intra: J = 0.9979
at failure, ½ K (ln J)² V = 4.2e-7 J/m, 3.75e-7 J/m of kinetic energy gained by the work of its
own stress within 30 steps, 13.7 m/s; the failed particles' kinetic energy 1.1 times the energy
released by cracking; with this rule, and the force of the new pairs after a change,
:func:`sph.total_lagrangian._new_force`: at most 6.8 m/s and 13 %, inter 4.9 m/s and 5 %; at
H/Δx = 10 15.2 → 8.7 m/s and 147 → 24 % (intra), 15.6 → 10.3 m/s and 48 → 18 % (inter); 3-D
H/Δx = 5 21 → 7.4 and 19 → 10 m/s). What was left: a failed particle, once open, is free in
tension and meets the faces only through its compressive response, which still threw it off when
they closed on it, and a detached particle moves on at the speed it was last kicked to.

So a particle blocked for good — failed and opened, or detached — is *merged into the faces* of
its crack (:meth:`Cracks.merge`): the intact particles of its reference row take its mass, with
its velocity (a perfectly inelastic merge: mass and momentum kept, the kinetic energy of the
relative motion lost once, recorded as ``merge_dissipation``), and it keeps no volume and no
mass of its own; where it is drawn is where its partners' mean displacement puts it
(:meth:`Cracks.place`). It is crushed or cracked material of the faces, and it now moves as
they do. Tying it to the faces by its velocity instead — every step, an inelastic tie to the
mean velocity of its partners — was measured and dropped: it damps the partners' vibration at
the rate of their highest modes (2-D, H/Δx = 5, intra: 1.6 times the energy released by cracking
taken by the tie, 26 % of the external work; the intact particles' median speed at the end 0.3
m/s against 1.2). Under the compression rule a merged particle's compressive response is gone
with its volume: the faces of an opened crack that close again do not push on each other (in the
micro-cantilever the cut faces part; the crushed bottom of the root stays compressed and is
never merged).

Under the 'literal' failure mode a failed particle keeps no stress at all; the body gives it zero
integration volume too, so it takes no part in any force and its F is not evaluated (no inverted
particle stops the run). Every change of the pairs leaves the stored energy Π = Σ V_a ψ(F_a)
unchanged except for what a detached particle takes with it; the difference before − after is
recorded as energy released by cracking, so that the energy balance stays closed.
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from .correction import reverse_gradients
from .kernels import JIT

SHADE = 1.0 - 1e-6
"""Width of the opaque cell of a failed particle over Δx: its interior (a segment that only grazes a
cell's face or corner, as between two particles of a straight lattice row beside a failed one, is
not cut)."""
CLOSED = 1.0 + 1e-9
"""Width of the closed cell of a failed particle over Δx, for the corner where two failed cells meet:
a segment through it meets both within round-off."""
OPEN_J = 1.0 - 1e-9
"""A failed particle of the compression mode counts as compressed while J = det F < OPEN_J and as
open from there on (its pressure K ln J is then below 1e-9 K: nothing; the margin keeps a
particle failing at the reference state, J = 1 to round-off, from counting as compressed)."""
MAX_CASCADE = 50
"""Most rounds of detachment per update (a detached particle blocks its neighbours' view as a
failed one does, which may detach another)."""
MERGED_MASS = 1e-9
"""The share of its mass a particle merged into the faces keeps (:meth:`Cracks.merge`): not
zero, so that its acceleration f/m = 0/m stays defined; its kinetic energy is then below 1e-9 of
what it was."""
MIN_SINGULAR = 0.4
"""Smallest singular value of F⁻¹ N (= M_a, Σ_kept (X_b − X_a) ⊗ G_ab, for an affine state; I for
a full row, about 0.5 in the normal direction for a particle on the face of a crack, as for one on
a free surface) for which a row is corrected: its gradients grow by at most 1/0.4 = 2.5. Below it
the particle is detached. (An earlier form of the rule with 0.3 went unstable in the
micro-cantilever at H/Δx = 10 after the crack had opened; with 0.4 every run of that study is
stable.)"""


@njit(inline="always", **JIT)
def _segment_cell_interval(xa, xb, c, half):
    """(t0, t1): the part of the segment xa + t (xb − xa), 0 ≤ t ≤ 1, inside the closed cube of
    half-width ``half`` centred on c (slab method); t0 > t1 when they do not meet."""
    t0 = 0.0
    t1 = 1.0
    for k in range(xa.shape[0]):
        d = xb[k] - xa[k]
        lo = c[k] - half - xa[k]
        hi = c[k] + half - xa[k]
        if d == 0.0:
            if lo > 0.0 or hi < 0.0:
                return 1.0, 0.0
        else:
            s0 = lo / d
            s1 = hi / d
            if s0 > s1:
                s0, s1 = s1, s0
            if s0 > t0:
                t0 = s0
            if s1 < t1:
                t1 = s1
    return t0, t1


@njit(inline="always", **JIT)
def _segment_hits_cell(xa, xb, c, half):
    """Whether the segment xa–xb meets the closed cube of half-width ``half`` centred on c."""
    t0, t1 = _segment_cell_interval(xa, xb, c, half)
    return t0 <= t1


@njit(inline="always", **JIT)
def _segment_blocked(X, a, b, lo, hi, indices, blocked, half, closed, t0s, t1s):
    """Whether the reference segment X_a–X_b is cut: it meets the interior of the cell (half-width
    ``half``) of a blocked neighbour c ≠ b of a (indices[lo:hi]), or the closed cells (half-width
    ``closed``) of two blocked neighbours at a common point, where the two cells touch (the
    corner of a crack stepping sideways). t0s, t1s: scratch of at least hi − lo entries."""
    m = 0
    for q in range(lo, hi):
        c = indices[q]
        if c == b or not blocked[c]:
            continue
        if _segment_hits_cell(X[a], X[b], X[c], half):
            return True
        t0, t1 = _segment_cell_interval(X[a], X[b], X[c], closed)
        if t0 <= t1:
            for i in range(m):
                if t0 <= t1s[i] and t0s[i] <= t1:
                    return True
            t0s[m] = t0
            t1s[m] = t1
            m += 1
    return False


@njit(parallel=True, **JIT)
def visible_rows(x, X, dx, indptr, indices, G, alive, blocked, skip, s_min, shade, closed):
    """One update of the visibility criterion (module docstring), in place: G (nnz, d) the current
    gradients, ``alive`` (nnz,) bool the pairs still in use, ``blocked`` (N,) bool the failed
    (and detached) particles, ``skip`` (N,) bool rows left alone (particles without volume). A row that loses
    pairs — to a blocked neighbour, or to a
    neighbour whose reference segment X_a–X_b crosses the cell (``shade`` Δx wide) of a blocked
    neighbour, or the common point of the closed cells (``closed`` Δx wide) of two — keeps its deformation gradient at the current positions x and stays exact for
    affine motions from there on: G'_ab = Cᵀ G_ab on the kept pairs with C = N⁻¹ F, F = Σ_alive
    (x_b − x_a) ⊗ G_ab, N = Σ_kept (x_b − x_a) ⊗ G_ab. Where the smallest singular value of
    F⁻¹ N is below ``s_min`` (:data:`MIN_SINGULAR`) the particle is detached instead: its row is
    zeroed. Returns (pairs dropped (N,), detached (N,) bool)."""
    N, d = x.shape
    half = 0.5 * dx * shade
    hclosed = 0.5 * dx * closed
    cut = np.zeros(N, np.int64)
    detached = np.zeros(N, np.bool_)
    for a in prange(N):
        if skip[a]:
            continue
        lo, hi = indptr[a], indptr[a + 1]
        keep = np.empty(hi - lo, np.bool_)
        t0s = np.empty(hi - lo)
        t1s = np.empty(hi - lo)
        lost = 0
        for p in range(lo, hi):
            b = indices[p]
            k = alive[p] and not blocked[b]
            if k and shade > 0.0:
                k = not _segment_blocked(X, a, b, lo, hi, indices, blocked, half, hclosed, t0s, t1s)
            keep[p - lo] = k
            if alive[p] and not k:
                lost += 1
        if lost == 0:
            continue
        F = np.zeros((d, d))
        Nm = np.zeros((d, d))
        for p in range(lo, hi):
            if alive[p]:
                b = indices[p]
                for i in range(d):
                    for j in range(d):
                        v = (x[b, i] - x[a, i]) * G[p, j]
                        F[i, j] += v
                        if keep[p - lo]:
                            Nm[i, j] += v
        detF = np.linalg.det(F)
        smin = 0.0
        if detF > 0.0:
            smin = np.linalg.svd(np.linalg.solve(F, Nm))[1][d - 1]  # of F⁻¹ N
        C = np.zeros((d, d))
        if smin >= s_min:
            C = np.linalg.solve(Nm, F)
        else:
            detached[a] = True
        for p in range(lo, hi):
            if keep[p - lo] and not detached[a]:
                g = np.zeros(d)
                for i in range(d):  # G' = Cᵀ G: G'_i = Σ_j C[j, i] G_j
                    for j in range(d):
                        g[i] += C[j, i] * G[p, j]
                for i in range(d):
                    G[p, i] = g[i]
            else:
                if alive[p]:
                    cut[a] += 1
                alive[p] = False
                for i in range(d):
                    G[p, i] = 0.0
    return cut, detached


def lattice_sides(X: np.ndarray, dx: float, indptr: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """(N, d, 2) int: for each particle and lattice axis, the particle at X − Δx e_k and the one
    at X + Δx e_k (−1 where there is none: a surface, or no lattice there), to 1e-6 Δx, read from
    the neighbour rows ``indptr``, ``indices`` (CSR; mirror images, indices ≥ N, left out)."""
    X = np.asarray(X, float)
    N, d = X.shape
    rows = np.repeat(np.arange(N), np.diff(indptr))
    cols = np.asarray(indices, np.int64)
    real = cols < N
    rows, cols = rows[real], cols[real]
    step = (X[cols] - X[rows]) / dx
    out = np.full((N, d, 2), -1, np.int64)
    for k in range(d):
        off = np.delete(step, k, axis=1)
        on_axis = np.all(np.abs(off) < 1e-6, axis=1)
        for j, sign in enumerate((-1.0, 1.0)):
            hit = on_axis & (np.abs(step[:, k] - sign) < 1e-6)
            out[rows[hit], k, j] = cols[hit]
    return out


def ligaments(sides: np.ndarray, blocked: np.ndarray) -> np.ndarray:
    """(N,) bool: the particles not ``blocked`` whose lattice neighbours on both sides along some
    axis (``sides``, :func:`lattice_sides`) are — a ligament one particle thick between two failed
    (or detached) cells (module docstring)."""
    both = (sides >= 0).all(axis=2)
    on = both & blocked[np.maximum(sides[..., 0], 0)] & blocked[np.maximum(sides[..., 1], 0)]
    return ~blocked & on.any(axis=1)


def volume_ratios(x, indptr, indices, G, idx) -> np.ndarray:
    """J = det F_a (eq. 35, F_a = Σ_b (x_b − x_a) ⊗ G_ab; F33 = 1 in 2-D) of the particles
    ``idx`` at the positions x (N, d)."""
    out = np.empty(len(idx))
    for k, a in enumerate(idx):
        lo, hi = indptr[a], indptr[a + 1]
        F = (x[indices[lo:hi]] - x[a]).T @ G[lo:hi]
        out[k] = np.linalg.det(F)
    return out


class Cracks:
    """The visibility criterion on a :class:`sph.total_lagrangian.Body` (module docstring).

    ``tlb`` the body (its gradients, reverse gradients and volumes are changed in place), ``dx``
    the spacing, m; ``literal`` (N,) bool the particles whose failure mode leaves no stress (their
    integration volume goes to zero once failed). :meth:`update` applies the rule when the failed
    set has grown, or when a failed particle that was still compressed has opened, and returns
    the stored energy released by the change, J. ``failed``, ``detached``, ``compressed`` (N,)
    bool, ``pairs_cut``, ``released`` (J) and ``updates`` (the changes applied) are the state so
    far; ``compressed``: the failed particles of the compression mode that failed with J < 1 and
    have not opened since — they stay in their neighbours' rows and block no view (module
    docstring)."""

    def __init__(self, tlb, dx: float, literal: np.ndarray):
        self.tlb = tlb
        self.dx = float(dx)
        dsc = tlb.disc
        # the body's own volumes: it zeroes those of the inert particles, and under nodal
        # integration dsc.V is the particles' array (sph.csph.discretise keeps it), which the
        # driver's observables weight with (a patch of detached particles read 0/0)
        dsc.V = np.array(dsc.V, dtype=np.float64)
        self.alive = np.ones(dsc.indices.shape[0], bool)
        self.V0 = dsc.V.copy()
        self.literal = np.asarray(literal, bool)
        self.failed = np.zeros(dsc.n, bool)
        self.detached = np.zeros(dsc.n, bool)
        self.compressed = np.zeros(dsc.n, bool)
        self.pairs_cut = 0
        self.released = 0.0
        self.merged = np.zeros(dsc.n, bool)
        self.lone = np.zeros(dsc.n, bool)
        self.rides = {}
        self.merge_dissipated = 0.0
        self.updates = 0
        self.sides = lattice_sides(dsc.X, self.dx, dsc.indptr, dsc.indices)

    def _J(self, x, mask) -> np.ndarray:
        """(N,) J = det F at x of the particles in ``mask``, 1 elsewhere."""
        dsc = self.tlb.disc
        idx = np.flatnonzero(mask)
        J = np.ones(len(mask))
        J[idx] = volume_ratios(x, dsc.indptr, dsc.indices, dsc.G, idx)
        return J

    def opened(self, x: np.ndarray) -> np.ndarray:
        """(N,) bool: the ``compressed`` failed particles whose J is no longer below
        :data:`OPEN_J` at x."""
        if not self.compressed.any():
            return self.compressed.copy()
        return self.compressed & (self._J(x, self.compressed) >= OPEN_J)

    def merge(self, v: np.ndarray, fixed: np.ndarray | None = None) -> float:
        """Merge every particle newly :attr:`blocked` (failed and opened, or detached; none with a
        prescribed DOF in ``fixed`` (N, d): its velocity is given) into the faces of its crack
        (module docstring): its partners are the intact particles of its reference row (not
        failed, not detached, none prescribed); each partner b takes the share δm_b = m_a m_b / M
        of its mass (M = Σ m_b) with its velocity, v_b ← (m_b v_b + δm_b v_a)/(m_b + δm_b) — a
        perfectly inelastic merge: the linear momentum is kept, the kinetic energy
        Σ ½ m_b δm_b/(m_b + δm_b) |v_b − v_a|² is lost (returned, J, and added to
        :attr:`merge_dissipated`) —, and a keeps :data:`MERGED_MASS` of its mass (no kinetic
        energy, no force: it has no volume, :attr:`inert`) and rides on its partners
        (:meth:`place`). The particles blocked by one update merge at once, each partner taking
        the sum of its shares (v_b ← (m_b v_b + Σ δm_b v_a)/(m_b + Σ δm_b)). A particle without
        partners stays free. ``v`` (N, d) in place; the masses (the body's ``disc.m``) too."""
        held = (np.zeros(len(self.failed), bool) if fixed is None
                else np.asarray(fixed).any(axis=1))
        new = np.flatnonzero(self.blocked & ~self.merged & ~self.lone & ~held)
        if not new.size:
            return 0.0
        dsc = self.tlb.disc
        m = dsc.m
        free = ~self.failed & ~self.detached & ~held
        # all of this update's merges at once, from the state before them: no order between them
        # (merged one after the other, two mirror images sharing partners were not mirror images
        # after: the crack_path study's mode-I crack kinked by 4 degrees)
        gain = np.zeros(dsc.n)
        push = np.zeros_like(v)
        merged = []
        for a in new:
            row = dsc.indices[dsc.indptr[a]:dsc.indptr[a + 1]]
            row = row[(row < dsc.n) & (row != a)]
            b = row[free[row]]
            if not b.size:
                self.lone[a] = True
                continue
            dm = m[a] * m[b] / m[b].sum()
            gain[b] += dm
            push[b] += dm[:, None] * v[a]
            self.rides[int(a)] = (b, m[b] / m[b].sum())
            merged.append(a)
        if not merged:
            return 0.0
        merged = np.array(merged)
        on = np.flatnonzero(gain > 0)
        ke = (lambda idx: 0.5 * float(m[idx] @ np.sum(v[idx] ** 2, axis=1)))  # noqa: E731
        before = ke(on) + ke(merged)
        v[on] = (m[on, None] * v[on] + push[on]) / (m[on] + gain[on])[:, None]
        m[on] += gain[on]
        m[merged] *= MERGED_MASS
        v[merged] = 0.0  # placed on its partners by the caller (place); no kinetic energy
        self.merged[merged] = True
        lost = before - ke(on)
        self.merge_dissipated += lost
        return lost

    def place(self, x: np.ndarray, v: np.ndarray) -> None:
        """The merged particles' positions and velocities from their partners', in place: the
        reference position plus the partners' mean displacement, and their mean velocity
        (weights their masses when merged). Nothing acts on a merged particle (no volume, no
        pair): where it is changes no force, and this is what the records and the final state
        show of it."""
        X = self.tlb.disc.X
        for a, (b, w) in self.rides.items():
            x[a] = X[a] + w @ (x[b] - X[b])
            v[a] = w @ v[b]

    @property
    def inert(self) -> np.ndarray:
        """(N,) bool: the particles without integration volume — failed under the literal mode,
        or detached."""
        return (self.failed & self.literal) | self.detached | self.merged

    @property
    def blocked(self) -> np.ndarray:
        """(N,) bool: the particles that block the view (module docstring)."""
        return (self.failed & ~self.compressed) | self.detached

    def update(self, failed: np.ndarray, x: np.ndarray, energy, v: np.ndarray | None = None,
               fixed: np.ndarray | None = None) -> float:
        """Apply the criterion at the current positions x (N, d) for the failed set ``failed``
        (N,) bool if it grew or a ``compressed`` particle opened; ``energy()`` gives the stored
        energy at the current state (called before and after: a detached particle takes its
        energy with it). With the velocities ``v`` (N, d), the particles blocked by the change
        are merged into the faces (:meth:`merge`; ``fixed`` the prescribed DOFs). Returns the
        energy released by this change, J."""
        failed = np.asarray(failed, bool)
        new = failed & ~self.failed
        x = np.ascontiguousarray(x)
        opened = self.opened(x)
        if not new.any() and not opened.any():
            return 0.0
        before = energy()
        self.updates += 1
        keep = new & ~self.literal
        self.compressed = ((self.compressed & ~opened)
                           | (keep & (self._J(x, keep) < OPEN_J)) & ~self.detached)
        self.failed = failed.copy()
        dsc = self.tlb.disc
        for _ in range(MAX_CASCADE):  # a detached particle blocks like a failed one
            skip = self.inert
            cut, det = visible_rows(x, dsc.X, self.dx, dsc.indptr, dsc.indices, dsc.G, self.alive,
                                    self.blocked, skip, MIN_SINGULAR, SHADE, CLOSED)
            self.pairs_cut += int(cut.sum())
            det |= ligaments(self.sides, self.blocked | det)
            if not (det & ~self.detached).any():
                break
            self.detached |= det
            self.compressed &= ~self.detached
        if v is not None:
            self.merge(v, fixed)
            self.place(x, v)
        dsc.GT[:] = reverse_gradients(dsc.indptr, dsc.indices, dsc.G)
        dsc.V[:] = np.where(self.inert, 0.0, self.V0)
        released = before - energy()
        self.released += released
        return released
