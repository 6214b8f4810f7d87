"""The fracture scenes of the papers, as parameters and models.

:class:`MicroCantilever` — the ceramic micro-cantilever of paper 000 (§4–5, Fig. 2–6, Tables 2–3):
five Voronoi grains and the four grain boundaries between them, the grain at the support merged
with the fixed block, finite-strain J2 with Swift hardening and the damage D = ε_p/ε_L of eq. 36;
inter-granular (ε_L = 0.002 on the grain boundaries) or intra-granular (in the grains) fracture.

The paper gives no dimensions: our choices (parameters, ``--set`` changes them): a beam
L × B × H = 20 × 5 × 5 µm on a block 5 µm long, 10 µm high (the beam's top flush with the
block's) and 15 µm wide in 3-D (``block_margin`` = 5 µm beyond each side face of the beam: the
particle lattice starts at the block's side face, so the beam's side faces lie on lattice lines at
every H/Δx — with a margin of B/2 they fell half a spacing between lines at odd H/Δx, where the
integration-consistent correction extrapolates to them and breaks down), the block's back face
and bottom face held; the load a downward velocity of the
top-face patch 2–4 µm from the free end (its ends on the lattice lines nearest to 0.8 L and 0.9 L:
:meth:`MicroCantilever.patch_edges`), 0.2 m/s, ramped up over 0.5 µs (about five periods
of the beam's first bending mode, ~0.1 µs: the kinetic energy stays below 1 % of the elastic
energy before the first failure); the run stops ``t_after`` = 1.5 µs after the crack has cut the
loading patch off from the held faces (no chain of intact particles joins them: the driver's
``separate``; ``t_after`` = 0: on to ``t_end``, the cut still recorded), 8 µs at most
(``t_end``; the first failure near 0.7–1 µs; the last ligament of the crack breaks between 1 and
7 µs depending on the case, the rule and the resolution — a one-particle ligament, a hinge that
bends without straining, is detached by :func:`sph.crack.ligaments`); grain boundaries 1 µm thick
(``gb_thickness``: one particle spacing at resolution 5, the coarsest that resolves them). The
resolution r puts r particles across H (spacing H/r). 2-D runs are plane strain (csph does not
model plane stress). Grains: the Voronoi cells (nearest-seed assignment, exact for any point — no
polyhedra are built) of ``n_grains`` seeds placed one per equal slice of the beam's length, jittered
inside their slice and across the section by a seeded generator (``seed``); a grain boundary is
the set of points within half its thickness of the bisector plane of the two nearest seeds, when
those are consecutive grains (:class:`GrainBoundary`). With seeds ordered along the beam, each
grain meets only its neighbours, so there are ``n_grains − 1`` boundaries, as in Fig. 2.

Crack band (``band`` > 0, Bažant & Oh 1983): the damage D = ε_p/ε_L fails a band one particle
wide, so the energy a crack dissipates per unit area is Δx·g(ε_L), g the energy per unit volume
spent to failure — the literal rule's goes to zero with the spacing (Bažant & Belytschko 1985).
Tying ε_L to a fixed band width b keeps it: the limit of the material where the low ε_L applies
becomes ε_L,eff with Δx·g(ε_L,eff) = b·g(ε_L) (:func:`crack_band_limit`; ε_L as given at Δx = b),
g the area under the uniaxial stress–strain curve of the J2 law to failure
(:func:`band_energy_density`). A band narrower than Δx·g(0)/g(ε_L) has no such ε_L (a failure at
first yield would already release more: Bažant's snap-back limit): refused.

Observables: ``force`` the reaction on the loading patch (the time mean over each output
interval, :mod:`sph.driver`), ``support`` the reaction on the held faces, ``deflection`` the
patch's mean displacement, and the failed fraction of all particles, of the grains, of the grain
boundaries and of each region; explicit runs also record the energies (external work, kinetic,
stored, plastic work, released by failure).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

import workbench.scenes.model as m

from workbench.materials import Material
from workbench.scenes.params import ParameterError, SceneError, Scene, param
from workbench.scenes.shapes import Box, Plane, Shape, Union, VoronoiCell, _points

TABLE2_E = (222e9, 212e9, 202e9, 192e9, 182e9)
"""000 Table 2: Young's moduli of the five grains, Pa (the grain at the support first)."""
TABLE3_E = 202e9
"""000 Table 3: Young's modulus of the grain boundaries, Pa."""


def band_energy_density(material: Material, eps_L: float) -> float:
    """g(ε_L), J/m³: the energy a unit volume of a J2 material spends until it fails at ε_p = ε_L
    under uniaxial stress — the area under its stress–strain curve to failure with a vertical
    drop there (Bažant & Oh 1983, the crack band's G_f/w_c): the plastic work
    W_p(ε_L) = ∫₀^{ε_L} σ_y dε_p (:func:`workbench.materials.j2.plastic_work`, closed form) plus
    the elastic energy released by the drop, σ_y(ε_L)²/(2E)."""
    from workbench.materials.j2 import plastic_work

    sy = float(material.yield_stress(eps_L))
    return float(plastic_work(material.params(), float(eps_L), sy)) + sy * sy / (2.0 * material.E)


def crack_band_limit(material: Material, eps_L: float, band: float, spacing: float) -> float:
    """The limit plastic strain ε_L,eff that a band of failed particles one ``spacing`` (m) wide
    needs to spend the energy per unit crack area of a band ``band`` (m) wide failing at
    ``eps_L``: spacing·g(ε_L,eff) = band·g(ε_L), g = :func:`band_energy_density` (increasing, so
    the root is unique; bisection to 1e-12 relative). SceneError where no ε_L ≥ 0 does it: band
    below spacing·g(0)/g(ε_L)."""
    target = band / spacing * band_energy_density(material, eps_L)
    g0 = band_energy_density(material, 0.0)
    if not target > g0:
        raise SceneError(f"band: {band:g} m is out of range; allowed: 0 or above "
                         f"{spacing * g0 / band_energy_density(material, eps_L):.4g} m at the "
                         f"spacing {spacing:g} m (a failure at first yield would release more)")
    lo, hi = 0.0, max(eps_L, 1e-6)
    while band_energy_density(material, hi) < target:
        lo, hi = hi, 2.0 * hi
    while hi - lo > 1e-12 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if band_energy_density(material, mid) < target else (lo, mid)
    return 0.5 * (lo + hi)


@dataclass(frozen=True)
class GrainBoundary(Shape):
    """The points whose two nearest seeds are ``i`` and ``j`` and that lie within ``thickness``/2
    of their bisector plane — the grain boundary between Voronoi cells i and j — cut by
    ``within``. The distance of X to the bisector is (|X − s_j|² − |X − s_i|²)/(2 |s_j − s_i|)."""

    seeds: tuple
    i: int
    j: int
    thickness: float
    within: Shape | None = None

    def contains(self, X, tol=0.0):
        X = _points(X)
        s = np.asarray(self.seeds, dtype=float)
        d2 = ((X[:, None, :] - s[None]) ** 2).sum(axis=2)
        order = np.argsort(d2, axis=1)[:, :2]
        pair = ((order[:, 0] == self.i) & (order[:, 1] == self.j)) | \
               ((order[:, 0] == self.j) & (order[:, 1] == self.i))
        gap = np.abs(d2[:, self.j] - d2[:, self.i]) / (2 * np.linalg.norm(s[self.j] - s[self.i]))
        ok = pair & (gap <= 0.5 * self.thickness + tol)
        if self.within is not None:
            ok &= self.within.contains(X, tol)
        return ok

    def bounds(self):
        return self.within.bounds() if self.within is not None else None


@dataclass(frozen=True)
class MicroCantilever(Scene):
    """Micro-cantilever with grains and grain boundaries (000 §4–5); module docstring."""

    name: str = field(default="microcantilever", metadata=dict(hidden=True))
    case: str = param("inter", "-", "inter-granular (GB limit strain eps_L_low) or intra-granular",
                      choices=("inter", "intra"))
    dim: int = param(3, "-", "3 (the study's result) or 2 (plane strain, for --quick and tests)",
                     choices=(2, 3))
    L: float = param(20e-6, "m", "beam length", lo=0, lo_open=True)
    B: float = param(5e-6, "m", "beam width (3-D)", lo=0, lo_open=True)
    H: float = param(5e-6, "m", "beam height", lo=0, lo_open=True)
    block: float = param(5e-6, "m", "length of the support block behind the beam", lo=0, lo_open=True)
    block_depth: float = param(5e-6, "m", "depth of the block below the beam", lo=0)
    block_margin: float = param(5e-6, "m", "how far the block reaches beyond each side face of the "
                                "beam (3-D)", lo=0)
    gb_thickness: float = param(1.0e-6, "m", "grain-boundary thickness (at least one particle "
                                "spacing, below the grain size and H)", lo=0, lo_open=True)
    n_grains: int = param(5, "-", "grains along the beam, the Voronoi seed count (a positive integer)",
                          lo=1, hi=50)
    seed: int = param(3, "-", "seed of the random generator placing the Voronoi seeds", lo=0)
    jitter: float = param(0.3, "-", "seed jitter within its slice, over the slice length", lo=0, hi=0.5)
    E_gb: float = param(TABLE3_E, "Pa", "Young's modulus of the grain boundaries (Table 3)", lo=0, lo_open=True)
    nu: float = param(0.3, "-", "Poisson's ratio", lo=-1, hi=0.5, lo_open=True, hi_open=True)
    C: float = param(868.8e6, "Pa", "Swift C", lo=0, lo_open=True)
    eps0: float = param(0.0013, "-", "Swift eps0", lo=0, lo_open=True)
    n: float = param(0.179, "-", "Swift exponent", lo=0, hi=1, hi_open=True)
    rho: float = param(7974.0, "kg/m^3", "density", lo=0, lo_open=True)
    eps_L_low: float = param(0.002, "-", "limit plastic strain where fracture is meant to run", lo=0, lo_open=True)
    eps_L_high: float = param(1.0, "-", "limit plastic strain elsewhere", lo=0, lo_open=True)
    failure: str = param("compression", "-", "failed particle: keeps compression, or literal (stress 0)",
                         choices=("compression", "literal"))
    band: float = param(0.0, "m", "crack-band width (0: eps_L as given; > 0: the low eps_L raised so "
                        "that the energy per crack area is that of a band this wide, crack_band_limit)",
                        lo=0)
    velocity: float = param(0.2, "m/s", "downward velocity of the loading patch", lo=0, lo_open=True)
    t_ramp: float = param(5e-7, "s", "time over which the velocity is ramped up", lo=0, lo_open=True)
    t_end: float = param(8e-6, "s", "longest simulated time (the run stops t_after past the "
                         "separation)", lo=0, lo_open=True)
    t_after: float = param(1.5e-6, "s", "time run on once no chain of intact particles joins the "
                           "loading patch and the held faces (0: run to t_end, the separation "
                           "still recorded)", lo=0)
    dt_factor: float = param(0.3, "-", "time step over its reference (dt_reference)", lo=0, hi=10,
                             lo_open=True)
    dt_reference: str = param("cfl", "-", "what dt_factor multiplies: the CFL estimate or the "
                              "method's critical step 2/omega_max (sph.spectrum)",
                              choices=("cfl", "spectrum"))

    def check(self):
        for name in ("n_grains", "seed"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
                raise ParameterError(f"{name}: {v!r} is not allowed; allowed: a positive integer"
                                     if name == "n_grains" else
                                     f"{name}: {v!r} is not allowed; allowed: an integer >= 0")
        top = min(self.H, self.L / self.n_grains)
        if self.gb_thickness >= top:
            raise ParameterError(f"gb_thickness: {self.gb_thickness:g} m is out of range; allowed: "
                                 f"[one particle spacing, {top:g}) m (below the grain size L/n_grains "
                                 f"and H)")

    # -- geometry -----------------------------------------------------------------------------
    def seeds(self) -> np.ndarray:
        """The Voronoi seeds (n_grains, dim), m: one per equal slice of the beam's length."""
        rng = np.random.default_rng(self.seed)
        n, L = self.n_grains, self.L
        x = (np.arange(n) + 0.5 + self.jitter * rng.uniform(-1, 1, n)) * L / n
        cols = [x]
        for w in ((self.B, self.H) if self.dim == 3 else (self.H,)):
            cols.append(0.3 * w * rng.uniform(-1, 1, n))
        return np.stack(cols, axis=1)

    def beam(self) -> Box:
        if self.dim == 3:
            return Box((0.0, -self.B / 2, -self.H / 2), (self.L, self.B / 2, self.H / 2))
        return Box((0.0, -self.H / 2), (self.L, self.H / 2))

    def block_box(self) -> Box:
        top = self.H / 2
        bottom = -self.H / 2 - self.block_depth
        if self.dim == 3:
            side = self.B / 2 + self.block_margin
            return Box((-self.block, -side, bottom), (0.0, side, top))
        return Box((-self.block, bottom), (0.0, top))

    def limits(self, spacing: float) -> tuple[tuple[float, ...], float]:
        """(ε_L of each grain, ε_L of the grain boundaries) for the case at ``spacing`` (m): the
        low limit where the case puts it, crack-band scaled when ``band`` > 0
        (:func:`crack_band_limit`, with each material's own modulus)."""
        grains, gb = self.materials(spacing)
        return tuple(g.eps_L for g in grains), gb.eps_L

    def materials(self, spacing: float):
        """(the grains' materials, the grain boundaries' material) at ``spacing`` (m)."""
        j2 = dict(nu=self.nu, C=self.C, eps0=self.eps0, n=self.n, rho=self.rho, failure=self.failure)
        grains = [Material.j2(E=TABLE2_E[k % len(TABLE2_E)], **j2) for k in range(self.n_grains)]
        gb = Material.j2(E=self.E_gb, **j2)

        def limited(mat, low):
            eps = self.eps_L_low if low else self.eps_L_high
            if low and self.band > 0:
                eps = crack_band_limit(mat, eps, self.band, spacing)
            return mat.replace(eps_L=eps)

        inter = self.case == "inter"
        return [limited(g, not inter) for g in grains], limited(gb, inter)

    def patch_edges(self, spacing: float) -> tuple[float, float]:
        """The loading patch's ends along the beam, m, at ``spacing``: the lattice lines (node
        lattice from the block's back face, x = −block + kΔx) nearest to 0.8 L and 0.9 L, a tie
        outward. The patch moves rigidly, so it holds the beam's slope at zero between its end
        particles and the load is stiffer the farther apart they are (2-D, first static point:
        csph's slope 1.11e9 N/m² at H/Δx = 6 with the end particles 0.83 µm apart, inside
        [0.8 L, 0.9 L], against the FEM's 1.66e9); the nearest lines keep that span within Δx of
        the patch's 2 µm at every spacing (node lattice, the model's; a cell lattice,
        ``lattice='cell'``, has its points half a spacing off these lines). On the study's ladder
        (H/Δx = 5, 10, 15, 20) 0.8 L and 0.9 L are lattice lines already and nothing moves; the
        FEM's mesh, built on the same model, has nodes on these lines."""
        x0 = self.block_box().lo[0]  # the lattice's first line (the model's lowest x)
        qa = (0.8 * self.L - x0) / spacing
        qb = (0.9 * self.L - x0) / spacing
        ka = math.ceil(qa - 0.5 - 1e-9)
        kb = math.floor(qb + 0.5 + 1e-9)
        return x0 + ka * spacing, x0 + kb * spacing

    def model(self, spacing: float | None = None) -> m.Model:
        dx = self.H / 10 if spacing is None else spacing
        if not dx <= self.gb_thickness * (1 + 1e-9):
            raise SceneError(f"gb_thickness: {self.gb_thickness:g} m is out of range; allowed: at least "
                             f"one particle spacing ({dx:g} m at this resolution)")
        d = self.dim
        up = d - 1  # the vertical axis
        seeds = self.seeds()
        beam = self.beam()
        grains, gb = self.materials(dx)
        regions = [m.Region("grain0", Union((VoronoiCell(seeds, 0, beam), self.block_box())), grains[0])]
        regions += [m.Region(f"grain{k}", VoronoiCell(seeds, k, beam), grains[k])
                    for k in range(1, self.n_grains)]
        regions += [m.Region(f"gb{k}{k + 1}", GrainBoundary(seeds, k, k + 1, self.gb_thickness, beam),
                             gb, priority=1) for k in range(self.n_grains - 1)]
        lo = self.block_box().lo
        big = 10 * (self.B + self.H)
        a, b = self.patch_edges(dx)
        patch = Plane(up, self.H / 2) & Box((a,) + (-big,) * (d - 1), (b,) + (big,) * (d - 1))
        v = m.Table((0.0, self.t_ramp), (0.0, -self.velocity))
        grain_names = tuple(f"grain{k}" for k in range(self.n_grains))
        gb_names = tuple(f"gb{k}{k + 1}" for k in range(self.n_grains - 1))
        return m.Model(
            dim=d, plane="strain" if d == 2 else None, length=self.H, name=self.name,
            regions=tuple(regions),
            sets=(m.Set("back", Plane(0, lo[0])), m.Set("bottom", Plane(up, lo[up])),
                  m.Set("held", Union((Plane(0, lo[0]), Plane(up, lo[up])))),
                  m.Set("patch", patch)),
            constraints=(m.Clamp("back"), m.Clamp("bottom"),
                         m.Prescribed("patch", up, velocity=v)),
            drive=m.Explicit(self.t_end, self.dt_factor, n_out=400, energy_growth=None,
                             dt_reference=self.dt_reference,
                             separate=("patch", "held"),
                             after=self.t_after if self.t_after > 0 else math.inf),
            observables=(m.Reaction("force", "patch", up), m.Reaction("support", "held", up),
                         m.Displacement("deflection", "patch", up),
                         m.FailedFraction("failed", None),
                         m.FailedFraction("failed_grains", grain_names),
                         m.FailedFraction("failed_gb", gb_names),
                         *[m.FailedFraction(f"failed_{r}", (r,)) for r in grain_names + gb_names]),
            notes=(f"case {self.case}; grains: Voronoi cells of seeds {np.round(seeds * 1e6, 3).tolist()} um; "
                   f"grain boundaries {self.gb_thickness * 1e6:g} um thick; grain 0 merged with the block",))

    def summarise(self, out: dict) -> dict:
        """``load`` (N; N/m in 2-D: the force the loading patch exerts on the beam, positive
        downward) and ``deflection_down`` (m: the patch's mean displacement, positive downward)
        histories."""
        return dict(load=-np.asarray(out.get("force", ()), float),
                    deflection_down=-np.asarray(out.get("deflection", ()), float))
