"""Corrected SPH (CSPH), total Lagrangian (paper 000 §2; Bonet & Lok 1999, Bonet & Kulasegaram
2000) — the method module behind ``--solver csph``.

Everything kernel-related is computed once, in the reference configuration X:

* neighbours within the kernel support 2h (:mod:`sph.neighbours`);
* the correction matrix of eq. 31 and the corrected gradients G_ab = V_b L_a ∇W_b(X_a) of eq. 29
  and 34 (:mod:`sph.correction`), or the second-order (quadratic) correction, and beside each G_ab
  the reverse G_ba (the force loop reads memory contiguously).

Per evaluation (:mod:`sph.total_lagrangian`): F_a = Σ_b (x_b − x_a) ⊗ G_ab (eq. 35), P_a from the
shared material library (a row of the body's material table per particle), and the internal force
f = −∂Π/∂x of the stored energy Π = Σ_a V_a ψ(F_a) (eq. 7–24): linear and angular momentum are
conserved to round-off, the tangent is symmetric. Explicit dynamics in one fused velocity-Verlet
loop; statics by Newton (:mod:`sph.static`); optional hourglass control (:mod:`sph.hourglass`).

Integration (``integration``): ``"consistent"`` (the default for particles on a node lattice:
``"auto"`` picks it where every face of the body lies on a lattice plane, and ``"nodal"``
elsewhere — 004's concentric rings, whose boundary is not a union of lattice cells; the cell
lattice, whose faces lie half a spacing outside the outermost particles: there the correction
extrapolates and raises the highest frequency 2.4-fold (ω_max Δx/c = 6.9 against 2.9 nodal on the
slab; 2.3 against 2.9 on a node lattice), which the explicit step of the CFL estimate does not
survive; and a node lattice with some faces half a spacing between its planes, where the
correction is ill-posed: :func:`off_lattice_share`, kept in ``consistency`` when asked for
explicitly; a body with a pre-crack, whose crack faces lie half a spacing from the nodes on either
side, is such a body: it gets ``"nodal"``) replaces G by the smallest change
that makes the force patch test exact (:mod:`sph.consistency`: uniform stretch and shear are
discrete equilibria with free faces, symmetry planes, loaded faces and clamps, at any resolution,
while F stays exact for affine — and with the quadratic correction quadratic — motions and the
force stays −∂Π/∂x), with volumes exact for quadratics and a clamp modelled as a face of the body
(the held particles behind it detached, the clamped corners carrying no volume); ``"nodal"`` is
plain nodal integration, the paper's.

Options of :func:`build`: ``h_ratio`` (h/Δx, default 1.1), ``kernel`` ('cubic_spline' or
'wendland_c2'), ``correction`` ('quadratic', the default; 'linear' = the paper's Bonet–Lok
correction), ``integration`` ('auto', the default; 'consistent'; 'nodal'), ``hourglass`` (α ≥ 0, 0 = off).
``gradient`` ('kernel', the default; 'wls': HPM's weighted-least-squares gradient, 004 eq. 4,
with ``re_ratio`` — HPM is CSPH with that gradient, so its integration-consistent form is this
body). The registry (:data:`sph.METHODS`) names the variants: ``csph`` (quadratic, consistent),
``csph_quad`` (quadratic, nodal), ``csph_bl`` (Bonet–Lok, nodal: paper 000 as printed) and
``hpm_vc`` (HPM's gradient, consistent integration with the quadratic basis).
"""
from __future__ import annotations

import math

import numpy as np

from .correction import correction_matrices, corrected_gradients, quadratic_gradients, reverse_gradients
from .kernels import SUPPORT, kernel_code
from .method import ParticleBody
from .neighbours import neighbour_list
from . import total_lagrangian as tl

NAME = "csph"
OPTIONS = dict(h_ratio="h/Δx (default 1.1)", kernel="'cubic_spline' | 'wendland_c2'",
               correction="'quadratic' (default) | 'linear' (the paper's Bonet–Lok)",
               integration="'auto' (default: 'consistent' on a lattice, else 'nodal') | 'consistent' | "
                           "'nodal' (the paper's)",
               hourglass="hourglass-control coefficient α ≥ 0 (default 0)",
               gradient="'kernel' (default: the corrected kernel gradient) | 'wls' (HPM's "
                        "weighted least squares, eq. 4 of 004, r_e = re_ratio·Δx)",
               re_ratio="r_e/Δx of the 'wls' gradient (default: HPM's)",
               crack="'auto' (default: 'visibility' where a material can fail, except with mirror "
                     "images, where it is not modelled: 'none') | 'visibility' (an intact particle "
                     "stops seeing failed particles and what lies behind them, sph.crack; failed "
                     "as workbench.materials.failure says, any law) | 'none' (the pairs never "
                     "change)",
               mirror="'auto' (default: the scene's symmetry planes by mirror images, sph.mirror) "
                      "| 'none' (a one-sided stencil at a symmetry plane)")
CRACKS = ("auto", "visibility", "none")
MIRRORS = ("auto", "none")
INTEGRATIONS = ("auto", "consistent", "nodal")
GRADIENTS = ("kernel", "wls")

DEFAULT_CORRECTION = "quadratic"
"""Gradient correction used unless ``correction=`` is given. The paper's Bonet–Lok correction
(``"linear"``, eq. 31) is first-order accurate at free surfaces, where its one-sided stencil
under-estimates bending strains: at H/Δx = 10 the plate period comes out 2.7 % (node lattice) to
6 % (cell lattice) long and the cantilever 6 % too soft. The quadratic correction keeps eq. 35 and
the energy-consistent force and removes that error (0.2 % and 0.3 %)."""
DEFAULT_H_RATIO = 1.1
CORRECTIONS = ("linear", "quadratic")


def discretise(X, V, m, dx: float, h_ratio: float = DEFAULT_H_RATIO,
               kernel: str = "cubic_spline", correction: str = "linear",
               body=None, cracks=None) -> tl.Discretisation:
    """Neighbours, correction and corrected gradients of the particles X (N, d) with volumes V,
    masses ``m`` (N,) (or a density, kg/m^d), spacing dx and smoothing length h = h_ratio·dx
    (kernel support 2h). ``body`` (N,) int, optional: particles of different bodies are not
    neighbours (separate bodies meet only through :mod:`sph.contact`). ``cracks`` (K, d, d) or
    None: pre-crack facets; no pair across one (:func:`sph.neighbours.cut_pairs`), the correction
    computed on the cut list.

    ``correction``: ``"linear"`` — Bonet–Lok, eq. 31 and 34 (the paper's CSPH); ``"quadratic"`` —
    :func:`sph.correction.quadratic_gradients` (exact for quadratic fields; the same force and
    conservation). Where a particle has too few neighbours for the quadratic fit (a block of two
    particles per edge), the whole body falls back to the linear correction (``disc.correction``
    says which was used)."""
    if correction not in CORRECTIONS:
        raise ValueError(f"correction: {correction!r} is not one of {', '.join(map(repr, CORRECTIONS))}")
    if not (0.5 <= h_ratio <= 4.0):
        raise ValueError(f"h_ratio: {h_ratio} is not allowed; h/dx must lie in [0.5, 4]")
    X = np.ascontiguousarray(X, dtype=np.float64)
    V = np.ascontiguousarray(V, dtype=np.float64)
    m = np.asarray(m, dtype=np.float64)
    mass = m * V if m.ndim == 0 else np.ascontiguousarray(m)
    kind = kernel_code(kernel)
    h = h_ratio * dx
    indptr, indices = neighbour_list(X, SUPPORT * h, body,
                                     None if cracks is None or not len(cracks) else (X, cracks))
    L, ok = correction_matrices(X, V, indptr, indices, h, kind)
    if correction == "quadratic":
        G, ok_q = quadratic_gradients(X, V, indptr, indices, h, kind)
        if ok_q.all():
            ok = ok_q
        else:
            correction = "linear"
    if correction == "linear":
        G = corrected_gradients(X, V, indptr, indices, h, kind, L)
    GT = reverse_gradients(indptr, indices, G)
    return tl.Discretisation(X, V, mass, h, kernel, indptr, indices, G, GT, L, ok, correction)


def wls(ps, re_ratio: float | None = None, body=None) -> tl.Discretisation:
    """HPM's weighted-least-squares gradient (004 eq. 4–6) of the particles ``ps`` as a
    gradient-form discretisation (:func:`sph.hpm.wls_discretisation`); ``body`` as in
    :func:`discretise`."""
    from . import hpm

    model = hpm.build_model(ps.X, ps.V, ps.table, ps.dx,
                            hpm.RE_RATIO if re_ratio is None else re_ratio, body=body,
                            mat_id=ps.mat_id, cracks=ps.cracks)
    disc = hpm.wls_discretisation(model)
    disc.m = np.ascontiguousarray(ps.m, dtype=np.float64)
    return disc


def off_lattice_share(ps) -> float:
    """The share of the body's boundary that lies half a spacing from the lattice nodes
    (:func:`sph.consistency.off_lattice_faces`): 0 when every face of the integration domain lies
    on a lattice plane, 1 on a cell lattice; NaN off the lattice. ``integration='auto'`` takes the
    integration-consistent correction only at 0: a body with some faces off (a 3-D beam whose side
    faces fall between the lattice planes of its block) makes the correction ill-posed."""
    from .consistency import off_lattice_faces

    if ps.origin is None or ps.domain_shape is None:
        return math.nan
    shape = ps.domain_shape
    return off_lattice_faces(ps.X, ps.dx, lambda q: shape.contains(q, 0.0), origin=ps.origin,
                             cracks=ps.cracks)


def consistent(ps, h_ratio: float = DEFAULT_H_RATIO, kernel: str = "cubic_spline",
               correction: str = DEFAULT_CORRECTION, weights: str = "uniform",
               gradient: str = "kernel", re_ratio: float | None = None):
    """The integration-consistent discretisation of the particles ``ps``
    (:class:`sph.particles.Particles` on a lattice): neighbours only within the body's integration
    domain (held particles outside it — a clamp block behind its face — are detached), volumes
    exact for quadratics (linear with the Bonet–Lok base) with the clamped corners excluded, and
    the gradients of :func:`discretise` corrected by
    :func:`sph.consistency.consistent_discretisation` on every free DOF. Returns
    (Discretisation, info of the correction)."""
    from .consistency import boundary_normals, column_mask, consistent_discretisation

    if ps.origin is None or ps.domain_shape is None:
        raise ValueError("integration: 'consistent' needs lattice particles (a region on the model's "
                         "lattice); allowed for other arrangements: 'nodal'")
    d = ps.dim
    labels = ps.body * 2 + (~ps.domain).astype(np.int64)
    labels = labels if labels.max() > 0 else None
    if gradient == "wls":
        disc = wls(ps, re_ratio, labels)
        disc.correction = correction
    else:
        disc = discretise(ps.X, ps.V, ps.m, ps.dx, h_ratio, kernel, correction, body=labels,
                          cracks=ps.cracks)
    inside = ps.domain_shape

    def predicate(q):
        return inside.contains(q, 0.0)

    _, n1 = boundary_normals(ps.X, ps.dx, predicate, origin=ps.origin, order=1, cracks=ps.cracks)
    edge = np.count_nonzero(np.abs(n1) > 1e-9 * ps.dx ** (d - 1), axis=1) >= 2
    corners = ps.clamped & ps.domain & edge
    V_int, n_int = boundary_normals(ps.X, ps.dx, predicate, origin=ps.origin,
                                    order=2 if disc.correction == "quadratic" else 1,
                                    exclude=corners if corners.any() else None,
                                    cracks=ps.cracks)
    new, info = consistent_discretisation(disc, V_int, n_int, column_mask(ps.fixed, "dof"),
                                          basis=disc.correction, weights=weights)
    new.correction = disc.correction
    return new, info


class CSPH(ParticleBody):
    """A CSPH body built from :class:`sph.particles.Particles` (see the module docstring)."""

    name = NAME
    impulse_in_loop = True

    def __init__(self, particles, h_ratio: float = DEFAULT_H_RATIO, kernel: str = "cubic_spline",
                 correction: str = DEFAULT_CORRECTION, integration: str = "auto",
                 hourglass: float = 0.0, gradient: str = "kernel", re_ratio: float | None = None,
                 crack: str = "auto", mirror: str = "auto"):
        super().__init__(particles)
        if mirror not in MIRRORS:
            raise ValueError(f"mirror: {mirror!r} is not one of {', '.join(map(repr, MIRRORS))}")
        if crack not in CRACKS:
            raise ValueError(f"crack: {crack!r} is not one of {', '.join(map(repr, CRACKS))}")
        if gradient not in GRADIENTS:
            raise ValueError(f"gradient: {gradient!r} is not one of {', '.join(map(repr, GRADIENTS))}")
        if particles.plane == "stress":
            raise ValueError("plane: 'stress' is not modelled by csph (F33 = 1: plane strain); "
                             "allowed: 'strain' or a 3-D model")
        if integration not in INTEGRATIONS:
            raise ValueError(f"integration: {integration!r} is not one of {', '.join(map(repr, INTEGRATIONS))}")
        ps = particles
        off = off_lattice_share(ps) if integration != "nodal" else math.nan
        if integration == "auto":
            integration = "consistent" if ps.lattice == "node" and off == 0.0 else "nodal"
        self.integration = integration
        images = None
        if mirror == "auto" and ps.mirrors:  # the full body, restricted below (sph.mirror)
            from .mirror import full_particles

            images = full_particles(ps, ps.mirrors, 1e-6 * ps.dx)
            ps = images.full
        body = ps.body if len(ps.body_names) > 1 else None
        if integration == "consistent":
            disc, self.consistency = consistent(ps, h_ratio, kernel, correction,
                                                gradient=gradient, re_ratio=re_ratio)
            self.normals = self.consistency["normals"]
            self.consistency["off_lattice_share"] = off
        elif gradient == "wls":
            disc = wls(ps, re_ratio, body)
        else:
            disc = discretise(ps.X, ps.V, ps.m, ps.dx, h_ratio, kernel, correction, body=body,
                              cracks=ps.cracks)
        if images is not None:
            from .mirror import restrict

            disc = restrict(disc, images, particles.m)
            if self.normals is not None:  # the real particles' shares of the full body's
                self.normals = images.w[:, None] * self.normals[:particles.n]
            ps = particles
        self.disc = disc
        self.tl = tl.Body(disc, ps.table, ps.mat_id, history=ps.initial_history(),
                          hourglass=hourglass)
        self.m = disc.m
        self._h_scratch = self.tl.history.copy()
        self._V_work = disc.V_energy.copy()  # the volumes of the plastic and released work
        self.cracks = None
        self._fixed = None  # the prescribed DOFs of the last advance (sph.crack merges none)
        mats = ps.table.materials
        from workbench.materials.failure import can_fail

        if crack == "auto":  # the mortar's RC beam runs on a quarter with mirror images
            crack = "none" if disc.n_ghost else "visibility"
        starts_failed = ps.failed is not None and bool(ps.failed.any())
        if crack == "visibility" and (can_fail(ps.table) or starts_failed):
            from .crack import Cracks

            if disc.n_ghost:
                raise ValueError("crack: 'visibility' is not modelled with symmetry planes (mirror "
                                 "images); allowed there: crack='none' or mirror='none'")

            literal = np.array([m.law == "j2" and m.failure == "literal" for m in mats], bool)
            self.cracks = Cracks(self.tl, ps.dx, literal[ps.mat_id])
            self._update_cracks(True)  # particles that start failed (the scene's failed regions)

    def advance(self, n, dt, f_ext, fixed, v_fix, damping=0.0, extra=None) -> int:
        if extra is not None:
            return super().advance(n, dt, f_ext, fixed, v_fix, damping, extra)
        self._fixed = fixed
        done = tl.advance(self.tl, self.x, self.v, self.acc, f_ext, fixed, v_fix, dt, damping, n,
                          self._h_scratch, self.impulse,
                          self._update_cracks if self.cracks is not None else None)
        if self.cracks is not None and self.cracks.rides:  # where the merged particles are
            self.cracks.place(self.x, self.v)
        self.steps += done
        self.t += done * dt
        return done

    def _update_cracks(self, new: bool = True) -> bool:
        """New failures (``new``), or failed particles that were compressed and have opened: the
        pairs of the visibility criterion (:mod:`sph.crack`), the stored energy they release added
        to the released energy. Returns whether the pairs changed."""
        from workbench.materials.failure import failed as failed_points

        if not new and not self.cracks.compressed.any():
            return False
        failed = failed_points(self.tl.table, self.tl.mat_id, self.tl.history)
        before = self.cracks.updates
        self.cracks.update(failed, self.x, self.stored_energy, self.v, self._fixed)
        return self.cracks.updates != before

    def internal_force(self, x):
        return self.tl.evaluate(np.ascontiguousarray(x))

    def commit(self) -> None:
        self.tl.commit()

    def failed(self) -> bool:
        return bool(np.any(self.tl.status != 0))

    def stored_energy(self) -> float:
        """Π = Σ_a V_a ψ(F_a, h_a), J (J/m in 2-D), the energy whose gradient is the internal
        force: hyperelastic laws by :func:`sph.diagnostics.strain_energy`; laws with a history
        (J2, the mortar) by the library's closed form at the committed history
        (:func:`workbench.materials.kernels.stored_energies`)."""
        from .diagnostics import strain_energy

        b = self.tl
        F = b.deformation_gradients(self.x)
        V = self.disc.V_energy  # particles without volume (sph.crack) carry no energy, whatever F
        if b.history.shape[1] > 0:
            from workbench.materials.kernels import stored_energies

            e = float(V[V > 0] @ stored_energies(F, b.history, b.prm, b.mat_id)[V > 0])
        else:
            e = strain_energy(F, V, b.prm, b.mat_id, history=b.history)
        if b.K_hg is not None:
            from .hourglass import hourglass_energy

            e += hourglass_energy(self.disc, b.K_hg, self.x)
        return e

    def dissipated(self) -> dict:
        """``plastic_work`` and ``released_energy``, J: the history columns W_p and W_rel (J/m³)
        of every law that keeps them — J2 and the mortar of 003,
        :func:`sph.diagnostics.dissipated_work` — times the integration volumes (the volumes of
        the stored energy), the released energy with what the crack pairs released
        (:mod:`sph.crack`), and with cracks ``merge_dissipation``: the kinetic energy the merge of
        the opened failed particles into the faces took (:meth:`sph.crack.Cracks.merge`)."""
        from .diagnostics import dissipated_work

        b = self.tl
        out = dissipated_work(b.table, b.mat_id, b.history, self._V_work)
        if out and self.cracks is not None:
            out["released_energy"] += self.cracks.released
            out["merge_dissipation"] = self.cracks.merge_dissipated
        return out

    def components(self):
        """(N,) int labels of the connected parts: a pair (a, b) joins a and b when b is still in
        the row of a (G_ab ≠ 0) and a carries tension (intact: not failed, not detached — a failed
        particle's row, kept for its compressive response, joins nothing). A crack that has cut
        the body leaves the parts on either side with different labels."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        d = self.disc
        rows = np.repeat(np.arange(d.n), np.diff(d.indptr))
        tension = d.V > 0
        if self.cracks is not None:
            tension &= ~self.cracks.failed & ~self.cracks.detached
        on = tension[rows] & np.any(d.G != 0.0, axis=1)
        cols = d.member_src[d.indices]  # a ghost joins its source
        g = coo_matrix((np.ones(on.sum()), (rows[on], cols[on])), shape=(d.n, d.n))
        return connected_components(g, directed=False)[1]

    def gradient_form(self):
        return self.tl

    def diagnostics(self) -> dict:
        """``hourglass_strain``: the root-mean-square zero-energy-mode strain
        (:func:`sph.hourglass.hourglass_strain`)."""
        from .hourglass import hourglass_operator, hourglass_strain

        if not hasattr(self, "_hg_op"):
            self._hg_op = hourglass_operator(self.disc)
        return dict(hourglass_strain=hourglass_strain(self.disc, self.x, *self._hg_op))

    def field_state(self) -> dict:
        F = self.tl.deformation_gradients(self.x)
        # V: the volumes of the stored energy and the work (dissipated), m³ (m² in 2-D)
        return dict(t=self.t, x=self.x, v=self.v, F=F, history=self.tl.history,
                    mat_id=self.tl.mat_id, region=self.particles.region, V=self._V_work)


def build(particles, **options) -> CSPH:
    """A CSPH body of ``particles`` (:func:`sph.particles.discretise`); options in the module
    docstring."""
    return CSPH(particles, **options)
