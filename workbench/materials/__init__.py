"""The one material-point library that every method (FEM quadrature points, CSPH, HPM, classic SPH)
calls.

A material is a frozen :class:`Material` whose :meth:`Material.params` packs it into a flat float64
vector ``prm`` that the numba point routines in :mod:`workbench.materials.kernels` read:

====  ==========================================================================
slot  meaning
====  ==========================================================================
0     law code: 0 Saint Venant–Kirchhoff, 1 compressible neo-Hookean,
      2 Mooney–Rivlin-like (004 eq. 12), 3 finite-strain J2 (Hencky, Swift or linear hardening),
      4 mortar of 003 (slots 3–9 its own: :mod:`workbench.materials.mortar`),
      5 brittle solid with a fracture energy (slots 3–8 its own: :mod:`workbench.materials.brittle`)
1     Lamé λ, Pa (for law 2: the λ of eq. 12)
2     shear modulus μ, Pa (law 2: unused, its small-strain value is c1 + c2)
3     Swift C, Pa            (law 3, Swift);  linear: initial yield stress σ_y0, Pa
4     Swift ε0, -            (law 3, Swift);  linear: hardening modulus H = dσ_y/dε_p, Pa
5     Swift n, -             (law 3, Swift);  linear: 0
6     damage limit ε_L, -    (law 3; ``inf``: no damage) — D = ε_p/ε_L, failed once D ≥ 1
7     c1, Pa                 (law 2); initial yield stress σ_y(0), Pa (law 3: derived from the
      hardening constants; a trial state with q ≤ σ_y(0) is elastic without evaluating σ_y(ε_p))
8     c2, Pa                 (law 2)
9     tolerance of the local Newton on the plastic multiplier (relative)
10    hardening kind of J2: 0 Swift (slots 3–5 as above), 1 linear
11    failure mode of J2 once D ≥ 1: 0 literal (P = 0), 1 compression only (τ = K ln J I if
      J < 1, else 0); see :meth:`Material.j2`
====  ==========================================================================

Law code 4 is the mortar law of 003 (:mod:`workbench.materials.mortar`; its own meanings of slots 1–9);
law code 5 the brittle law (:mod:`workbench.materials.brittle`: Rankine onset, linear softening
regularised by G_c over the method's crack band). What "failed" means for each law:
:mod:`workbench.materials.failure`.

History per point (``n_history`` columns): none for the elastic laws; for J2 thirteen floats,
``[Cp⁻¹ (3×3, row-major), ε_p, D, W_p, W_rel]`` with Cp⁻¹ = Fp⁻¹ Fp⁻ᵀ, so that the elastic trial
left Cauchy–Green tensor is ``be_tr = F Cp⁻¹ Fᵀ`` and only the current F is needed; D = ε_p/ε_L;
W_p the plastic work ∫₀^{ε_p} σ_y dε_p and W_rel the stored energy released when the point failed,
both per unit reference volume, J/m³ (:func:`energies`). Along any path the work done on a point
is ∫ P : dF = ψ + W_p + W_rel, ψ the stored energy (:func:`energies`), up to the quadrature error
of the path's time steps.

Deformation gradients are always 3×3; plane strain is F33 = 1 with the 2×2 block taken from P.

J2 hardening acts on the Kirchhoff yield stress as a function of the equivalent plastic strain:
Swift σ_y = C (ε_p + ε0)^n (paper 000) or linear σ_y = σ_y0 + H ε_p (the bilinear steel of paper
003, Fig. 14). A post-yield slope E_t of the uniaxial stress–strain curve is H = E E_t/(E − E_t)
(:func:`linear_hardening_modulus`; the papers' E_t = E/100 is H = E/99).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import jitcache as _jitcache
from .layout import (FAILURE_CODES, HARDENING_CODES, HIST_DAMAGE, HIST_EPS_P,  # noqa: F401
                     HIST_W_P, HIST_W_REL, LAW_CODES, N_HISTORY_J2, N_PARAMS)

# the dispatch (kernels.py) calls the laws of the other modules: drop the package's cached machine
# code when any of them changed (numba keys a function's cache on its own file only)
_jitcache.guard(Path(__file__).parent / "__pycache__", _jitcache.sources_of(Path(__file__).parent))


@dataclass(frozen=True)
class Material:
    """A constitutive law and its constants (SI units).

    Build with the class methods (:meth:`svk`, :meth:`neo_hooke`, :meth:`mooney_rivlin`,
    :meth:`j2`, :meth:`j2_linear`); they validate the constants and raise ``ValueError`` naming the parameter and its
    allowed range.
    """

    law: str
    E: float = 0.0
    nu: float = 0.0
    rho: float = 1000.0
    C: float = 0.0
    eps0: float = 0.0
    n: float = 0.0
    eps_L: float = math.inf
    c1: float = 0.0
    c2: float = 0.0
    lam_mr: float = 0.0
    tol: float = 1e-12
    hardening: str = "swift"
    sy0: float = 0.0  # linear hardening: initial yield stress, Pa
    H: float = 0.0    # linear hardening: dσ_y/dε_p, Pa
    failure: str = "compression"
    f_t: float = 0.0          # mortar (law 4): tensile strength, Pa
    f_c: float = 0.0          # mortar: compressive strength (initial Mises yield), Pa
    eps_release: float = 0.0  # mortar: strain of complete stress release, -
    H_c: float = 0.0          # mortar: linear hardening modulus, Pa
    phi_min: float = 0.05     # mortar: floor of the reduction factor φ
    shear_retention: float = 0.05  # mortar: shear rate of a cracked pair (0: 003's eq. 7)
    G_c: float = 0.0          # brittle (law 5): fracture energy, J/m²
    band: float = 0.0         # brittle: crack band width, m (0: the method's, MaterialTable.with_band)

    # -- constructors -------------------------------------------------------------------------
    @classmethod
    def svk(cls, E: float, nu: float, rho: float = 1000.0) -> "Material":
        return cls(law="svk", E=E, nu=nu, rho=rho).validated()

    @classmethod
    def neo_hooke(cls, E: float, nu: float, rho: float = 1000.0) -> "Material":
        return cls(law="neo_hooke", E=E, nu=nu, rho=rho).validated()

    @classmethod
    def mooney_rivlin(cls, c1: float, c2: float, lam: float, rho: float = 1000.0) -> "Material":
        """004 eq. 12: ψ = ½c1 I1 + ½c2 I2 − [3/2 c1 I3^{1/3} + 3/2 c2 I3^{2/3} − λ/4 (ln I3)²].

        Linearised at C = I: S = 2(c1 + c2) ε + (2λ − ⅔(c1 + c2)) tr ε I, i.e. shear modulus
        μ = c1 + c2 and bulk modulus K = 2λ (under pure dilation ψ = λ (ln J)²); the λ of eq. 12
        is not the Lamé λ. E and ν below are those small-strain moduli.
        """
        if not lam > 0:
            raise ValueError(f"lam: {lam} Pa is not allowed; the λ of eq. 12 must be > 0")
        mu = c1 + c2
        K = 2 * lam
        E = 9 * K * mu / (3 * K + mu)
        nu = (3 * K - 2 * mu) / (2 * (3 * K + mu))
        return cls(law="mooney_rivlin", E=E, nu=nu, rho=rho, c1=c1, c2=c2, lam_mr=lam).validated()

    @classmethod
    def j2(cls, E: float, nu: float, C: float, eps0: float, n: float, rho: float = 7974.0,
           eps_L: float = math.inf, failure: str = "compression") -> "Material":
        """Finite-strain J2: multiplicative split, Hencky elasticity, exponential-map return
        mapping, Swift hardening σ_y = C (ε_p + ε0)^n on the Kirchhoff stress.

        eps_L: limit plastic strain ε_L of the damage D = ε_p/ε_L (paper 000 eq. 36; ``inf``: no
        failure). failure: what a point keeps once D ≥ 1 — ``"literal"``: nothing (P = 0, the
        paper as printed, "stress zero once D ≥ 1"); ``"compression"`` (default): only a
        compressive volumetric response τ = K ln J I for J < 1 (no tension, no shear; failed
        points still do not interpenetrate)."""
        return cls(law="j2", E=E, nu=nu, rho=rho, C=C, eps0=eps0, n=n, eps_L=eps_L,
                   failure=failure).validated()

    @classmethod
    def j2_linear(cls, E: float, nu: float, sigma_y0: float, H: float, rho: float = 7850.0,
                  eps_L: float = math.inf, failure: str = "compression") -> "Material":
        """Finite-strain J2 (as :meth:`j2`) with linear isotropic hardening on the Kirchhoff
        stress, σ_y = σ_y0 + H ε_p. Under uniaxial stress the post-yield slope of τ against the
        log strain is E_t = E H/(E + H); from a given E_t use :func:`linear_hardening_modulus`."""
        return cls(law="j2", E=E, nu=nu, rho=rho, eps_L=eps_L, hardening="linear", sy0=sigma_y0,
                   H=H, failure=failure).validated()

    @classmethod
    def mortar(cls, E: float, nu: float, f_t: float, f_c: float, eps_release: float | None = None,
               *, G_f: float | None = None, particle_size: float | None = None,
               H_c: float | None = None, phi_min: float = 0.05, shear_retention: float = 0.05,
               rho: float = 2200.0) -> "Material":
        """Mortar of paper 003 (:mod:`workbench.materials.mortar`): tension softening by stress
        release (eq. 5–7) on the degraded orthotropic matrix (eq. 8), Mises plasticity with linear
        hardening H_c (default E/99: post-yield slope E/100 in uniaxial stress, Fig. 14). The
        release strain is ``eps_release`` or, by eq. 5, 2 G_f/(f_t · particle_size) (G_f in J/m²,
        particle_size in m). ρ = 2200 kg/m³ by default (003 gives none). ``shear_retention`` β
        in [0, 1]: the constant shear rate of a pair of crack axes once one has cracked (a fixed
        smeared crack; default 0.05, so that a crack that slides releases its normal g_F only);
        0 gives eq. 7 as printed (rates φ̃_iφ̃_j falling with the opening, floored by ``phi_min``).
        See the module docstring of :mod:`workbench.materials.mortar`, "Shear retention".

        Eq. 5 assumes a crack band one particle wide, but the particle methods crack a band of two
        lattice columns (a particle's gradient is formed from its neighbours: a jump between two
        columns is a strain of both; :mod:`workbench.scenes.crack_band`, docs/fracture.md): a
        material built from (G_f, particle_size) releases **2 G_f** per unit crack area there. To
        release G_f, give ``particle_size`` = 2 Δx (or use :meth:`brittle`, whose band is the
        method's)."""
        from .mortar import release_strain

        if eps_release is None:
            if G_f is None or particle_size is None:
                raise ValueError("eps_release: give it, or both G_f and particle_size (eq. 5)")
            eps_release = release_strain(E, f_t, G_f, particle_size)
        elif G_f is not None or particle_size is not None:
            raise ValueError("eps_release: give either eps_release or (G_f, particle_size), not both")
        H_c = E / 99.0 if H_c is None else H_c
        return cls(law="mortar", E=E, nu=nu, rho=rho, f_t=f_t, f_c=f_c, eps_release=eps_release,
                   H_c=H_c, phi_min=phi_min, shear_retention=shear_retention).validated()

    @classmethod
    def brittle(cls, E: float, nu: float, f_t: float, G_c: float, rho: float = 7850.0,
                band: float = 0.0) -> "Material":
        """A brittle solid (:mod:`workbench.materials.brittle`): elastic (Saint Venant–Kirchhoff)
        up to the Rankine onset, the largest principal stress reaching f_t (Pa); then linear
        softening of the damage on the tensile part of a volumetric–deviatoric split, whose
        energy per unit crack area is G_c (J/m²) over the crack band the method cracks: ``band``
        (m) or, with 0 (default), the method's own (particle methods 2 Δx, the FEM one element).
        Where G_c < f_t² b/(2E) the strength is reduced locally to √(2 E G_c/b) (Bažant–Oh):
        no parameter is capped by the spacing. No plasticity, no compressive failure; a cracked
        point keeps its bulk stiffness in compression. ρ defaults to a steel's 7850 kg/m³."""
        return cls(law="brittle", E=E, nu=nu, rho=rho, f_t=f_t, G_c=G_c, band=band).validated()

    @classmethod
    def from_bulk_shear(cls, law: str, K: float, G: float, rho: float) -> "Material":
        E = 9 * K * G / (3 * K + G)
        nu = (3 * K - 2 * G) / (2 * (3 * K + G))
        return cls(law=law, E=E, nu=nu, rho=rho).validated()

    # -- checks -------------------------------------------------------------------------------
    def validated(self) -> "Material":
        if self.law not in LAW_CODES:
            raise ValueError(f"law: {self.law!r} is not one of {sorted(LAW_CODES)}")
        if not self.E > 0:
            raise ValueError(f"E: {self.E} Pa is not allowed; E must be > 0")
        if not (-1.0 < self.nu < 0.5):
            raise ValueError(f"nu: {self.nu} is not allowed; Poisson's ratio must lie in (-1, 0.5)")
        if not self.rho > 0:
            raise ValueError(f"rho: {self.rho} kg/m^3 is not allowed; density must be > 0")
        if self.law == "j2":
            if self.hardening not in HARDENING_CODES:
                raise ValueError(f"hardening: {self.hardening!r} is not one of "
                                 f"{sorted(HARDENING_CODES)}")
            if self.hardening == "swift":
                if not self.C > 0:
                    raise ValueError(f"C: {self.C} Pa is not allowed; Swift C must be > 0")
                if not self.eps0 > 0:
                    raise ValueError(f"eps0: {self.eps0} is not allowed; Swift eps0 must be > 0")
                if not (0 <= self.n < 1):
                    raise ValueError(f"n: {self.n} is not allowed; Swift exponent must lie in [0, 1)")
            else:
                if not (self.sy0 > 0 and math.isfinite(self.sy0)):
                    raise ValueError(f"sigma_y0: {self.sy0} Pa is not allowed; the initial yield "
                                     "stress must be > 0 and finite")
                if not (self.H >= 0 and math.isfinite(self.H)):
                    raise ValueError(f"H: {self.H} Pa is not allowed; the hardening modulus must "
                                     "be >= 0 and finite")
            if self.failure not in FAILURE_CODES:
                raise ValueError(f"failure: {self.failure!r} is not one of {sorted(FAILURE_CODES)}")
            if not self.eps_L > 0:
                raise ValueError(f"eps_L: {self.eps_L} is not allowed; strain limit must be > 0")
        if self.law == "mooney_rivlin" and not (self.c1 >= 0 and self.c2 >= 0 and self.c1 + self.c2 > 0):
            raise ValueError("c1, c2: must be >= 0 with c1 + c2 > 0")
        if self.law == "mortar":
            from .mortar import check_material

            check_material(self)
        if self.law == "brittle":
            from .brittle import check_material

            check_material(self)
        return self

    def replace(self, **changes) -> "Material":
        return dataclasses.replace(self, **changes).validated()

    # -- derived quantities -------------------------------------------------------------------
    @property
    def mu(self) -> float:
        """Small-strain shear modulus, Pa."""
        return self.E / (2 * (1 + self.nu))

    @property
    def lam(self) -> float:
        """Small-strain Lamé λ, Pa."""
        return self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))

    @property
    def K(self) -> float:
        """Small-strain bulk modulus, Pa."""
        return self.E / (3 * (1 - 2 * self.nu))

    @property
    def sigma_y0(self) -> float:
        """Initial yield stress, Pa (J2 only): C ε0^n (Swift) or σ_y0 (linear)."""
        if self.hardening == "linear":
            return self.sy0
        return self.C * self.eps0 ** self.n

    def yield_stress(self, eps_p):
        """Kirchhoff yield stress σ_y(ε_p), Pa (J2 only; numpy, for references and plots)."""
        eps_p = np.asarray(eps_p, dtype=float)
        if self.hardening == "linear":
            return self.sy0 + self.H * eps_p
        return self.C * (eps_p + self.eps0) ** self.n

    def wave_speed(self, plane: str | None = "strain") -> float:
        """Fastest small-strain elastic wave speed, m/s (P wave; in plane stress the plate wave)."""
        if plane == "stress":
            return math.sqrt(self.E / (self.rho * (1 - self.nu ** 2)))
        return math.sqrt((self.lam + 2 * self.mu) / self.rho)

    @property
    def n_history(self) -> int:
        if self.law == "mortar":
            from .mortar import N_HISTORY

            return N_HISTORY
        if self.law == "brittle":
            from .brittle import N_HISTORY as N_BRITTLE

            return N_BRITTLE
        return N_HISTORY_J2 if self.law == "j2" else 0

    def params(self) -> np.ndarray:
        """The flat float64 vector the numba kernels read (layout in the module docstring)."""
        p = np.zeros(N_PARAMS)
        p[0] = LAW_CODES[self.law]
        p[1] = self.lam_mr if self.law == "mooney_rivlin" else self.lam
        p[2] = self.mu
        p[3], p[4], p[5] = self.C, self.eps0, self.n
        p[6] = self.eps_L
        p[7], p[8] = self.c1, self.c2
        p[9] = self.tol
        if self.law == "j2":
            p[7] = self.sigma_y0
            p[10] = HARDENING_CODES[self.hardening]
            if self.hardening == "linear":
                p[3], p[4], p[5] = self.sy0, self.H, 0.0
            p[11] = FAILURE_CODES[self.failure]
        if self.law == "mortar":
            from .mortar import pack_params

            pack_params(self, p)
        if self.law == "brittle":
            from .brittle import pack_params as pack_brittle

            pack_brittle(self, p)
        return p

    def initial_history(self, n_points: int) -> np.ndarray:
        """History of ``n_points`` virgin points, shape ``(n_points, n_history)``."""
        h = np.zeros((n_points, self.n_history))
        if self.law == "j2":
            h[:, 0] = h[:, 4] = h[:, 8] = 1.0  # Cp⁻¹ = I
        return h

    def describe(self) -> dict:
        """Attributes for a dataset (law and its constants)."""
        d = {"material_law": self.law, "E": self.E, "nu": self.nu, "rho": self.rho}
        if self.law == "j2" and self.hardening == "linear":
            d.update(hardening="linear", sigma_y0=self.sy0, H=self.H)
        elif self.law == "j2":
            d.update(hardening="swift", swift_C=self.C, swift_eps0=self.eps0, swift_n=self.n)
        if self.law == "j2":
            d.update(eps_L=self.eps_L, failure=self.failure, hardening_on="Kirchhoff stress")
        if self.law == "mooney_rivlin":
            d.update(c1=self.c1, c2=self.c2, lambda_mr=self.lam_mr)
        if self.law == "mortar":
            d.update(f_t=self.f_t, f_c=self.f_c, eps_release=self.eps_release, H_c=self.H_c,
                     phi_min=self.phi_min, shear_retention=self.shear_retention)
        if self.law == "brittle":
            d.update(f_t=self.f_t, G_c=self.G_c, band=self.band)
        return d


@dataclass(frozen=True)
class MaterialTable:
    """The materials of one body, indexed by a material id per particle or element (a region's
    material, a grain, mortar and steel): the numba loops read row ``mat_id[a]`` of
    :meth:`params`, so one compiled kernel serves bodies of any number of materials.

    ``n_history`` is the widest law's; every point carries that many history columns (an elastic
    point keeps its columns untouched)."""

    materials: tuple

    def __post_init__(self):
        mats = tuple(self.materials)
        if not mats:
            raise ValueError("materials: a table needs at least one material")
        for m in mats:
            if not isinstance(m, Material):
                raise ValueError(f"materials: {m!r} is not a Material")
        object.__setattr__(self, "materials", mats)

    @classmethod
    def of(cls, material) -> "MaterialTable":
        """A table of one material (or the table itself)."""
        return material if isinstance(material, MaterialTable) else cls((material,))

    def __len__(self) -> int:
        return len(self.materials)

    def __getitem__(self, i) -> Material:
        return self.materials[i]

    def with_band(self, band: float) -> "MaterialTable":
        """The table with the crack band width ``band`` (m) given to every brittle material that
        leaves it to the method (``band`` = 0): a method calls it with its band at its spacing
        (:data:`workbench.materials.brittle.PARTICLE_BAND` Δx, the FEM's element size)."""
        if not any(m.law == "brittle" and m.band == 0 for m in self.materials):
            return self
        return MaterialTable(tuple(m.replace(band=band) if m.law == "brittle" and m.band == 0
                                   else m for m in self.materials))

    def params(self) -> np.ndarray:
        """(n_materials, N_PARAMS) float64, row k = ``materials[k].params()``."""
        return np.ascontiguousarray(np.stack([m.params() for m in self.materials]))

    @property
    def n_history(self) -> int:
        return max(m.n_history for m in self.materials)

    def initial_history(self, mat_id) -> np.ndarray:
        """History of virgin points with materials ``mat_id`` (N,): (N, n_history)."""
        mat_id = np.asarray(mat_id, dtype=np.int64)
        h = np.zeros((mat_id.size, self.n_history))
        for k, m in enumerate(self.materials):
            sel = mat_id == k
            if m.n_history and sel.any():
                h[sel, : m.n_history] = m.initial_history(int(sel.sum()))
        return h

    def rho(self, mat_id) -> np.ndarray:
        """Density of each point, kg/m³."""
        return np.array([m.rho for m in self.materials])[np.asarray(mat_id, dtype=np.int64)]

    def wave_speed(self, plane: str | None = "strain") -> float:
        """Fastest small-strain elastic wave speed over the materials, m/s."""
        return max(m.wave_speed(plane) for m in self.materials)

    @property
    def mu(self) -> float:
        """Largest small-strain shear modulus of the table, Pa."""
        return max(m.mu for m in self.materials)

    @property
    def all_svk(self) -> bool:
        return all(m.law == "svk" for m in self.materials)


def linear_hardening_modulus(E: float, E_t: float) -> float:
    """Hardening modulus H = dσ_y/dε_p, Pa, of linear J2 hardening whose uniaxial stress–strain
    curve has the post-yield slope E_t (0 ≤ E_t < E): from dε = dτ/E + dτ/H, E_t = E H/(E + H),
    so H = E E_t/(E − E_t). Paper 003's "E/100" (Fig. 14) is E_t = E/100, i.e. H = E/99."""
    if not E > 0:
        raise ValueError(f"E: {E} Pa is not allowed; E must be > 0")
    if not (0 <= E_t < E):
        raise ValueError(f"E_t: {E_t} Pa is not allowed; the post-yield slope must lie in [0, E)")
    return E * E_t / (E - E_t)


# Materials of the papers (scenes.md).
TABLE1_STEEL = Material.j2(E=202e9, nu=0.3, C=868.8e6, eps0=0.0013, n=0.179, rho=7974.0)
RUBBER = Material.from_bulk_shear("svk", K=3.25e6, G=7.15e5, rho=1000.0)
RING_RUBBER = Material.mooney_rivlin(c1=1.265e5, c2=1.012e4, lam=1.012e7, rho=125.4)
BEAM = Material.svk(E=1.0e5, nu=0.3, rho=1000.0)
# Rebar of paper 003 (Table 1, Fig. 14): E = 206 GPa, ν = 0.3, yield 394 MPa, post-yield slope
# E/100 of the stress–strain curve. The paper gives no density: 7850 kg/m³ (structural steel).
REBAR_003 = Material.j2_linear(E=206e9, nu=0.3, sigma_y0=394e6,
                               H=linear_hardening_modulus(206e9, 206e9 / 100), rho=7850.0)
# Mortar of paper 003 (Table 1, Fig. 14): E, ν, strengths, post-yield slope E/100 in compression,
# full release at 17 000 µ strain with 5 mm particles (§4.1), i.e. G_F = 68.4 N/m; ρ is not given
# (2200 kg/m³).
MORTAR_003 = Material.mortar(E=11.9e9, nu=0.22, f_t=1.61e6, f_c=16.1e6, eps_release=0.017)


def evaluate(material, F: np.ndarray, history: np.ndarray | None = None,
             tangent: bool = False, stress: str = "P", mat_id=None):
    """Stress at many points.

    material: a :class:`Material` or a :class:`MaterialTable` (then ``mat_id`` (N,) gives each
    point's row; default all 0). F: (N, 3, 3) or (3, 3). history: (N, n_history) or None
    (virgin). Returns a dict with ``stress`` ((N,3,3): 'P' first Piola–Kirchhoff, 'tau' Kirchhoff,
    'sigma' Cauchy), ``history`` (N, n_history), ``status`` (N,) int (0 ok; see kernels) and, with
    ``tangent``, ``A`` = dP/dF of shape (N, 3, 3, 3, 3), A[i, j, k, l] = ∂P_ij/∂F_kl.
    """
    from . import kernels

    table = MaterialTable.of(material)
    F = np.asarray(F, dtype=np.float64)
    single = F.ndim == 2
    F = np.ascontiguousarray(F.reshape(-1, 3, 3))
    mat_id = (np.zeros(F.shape[0], np.int64) if mat_id is None
              else np.ascontiguousarray(np.broadcast_to(mat_id, F.shape[:1]), dtype=np.int64))
    if history is None:
        history = table.initial_history(mat_id)
    history = np.ascontiguousarray(np.asarray(history, dtype=np.float64).reshape(F.shape[0], -1))
    if history.shape[1] != table.n_history:
        raise ValueError(f"history: expected {table.n_history} columns, got {history.shape[1]}")
    prm = table.params()
    if tangent:
        P, A, h, status = kernels.material_points_tangent(F, history, prm, mat_id)
    else:
        P, h, status = kernels.material_points(F, history, prm, mat_id)
        A = None
    if stress == "P":
        out = P
    elif stress in ("tau", "sigma"):
        out = np.einsum("nij,nkj->nik", P, F)
        if stress == "sigma":
            out = out / np.linalg.det(F)[:, None, None]
    else:
        raise ValueError(f"stress: {stress!r} is not one of 'P', 'tau', 'sigma'")
    res = {"stress": out, "history": h, "status": status}
    if A is not None:
        res["A"] = A
    if single:
        res = {k: (v[0] if v is not None else None) for k, v in res.items()}
    return res


def energies(material, F: np.ndarray, history: np.ndarray | None = None, mat_id=None) -> dict:
    """Energies per unit reference volume, J/m³, of many points, for energy balances: the work
    done on a point along its path is ∫ P : dF = psi + W_p + W_rel.

    material: a :class:`Material` or :class:`MaterialTable` (``mat_id`` as in :func:`evaluate`).
    F: (N, 3, 3) or (3, 3); history: (N, n_history) of the end of the step (None: virgin).
    Returns ``psi`` the stored energy (:func:`kernels.stored_energy_point`), ``W_p`` the plastic
    work and ``W_rel`` the energy released at failure (J2 and brittle history columns; 0 for
    other laws),
    each (N,) (scalars for one F). Multiply by the reference volumes and sum for a body.
    """
    from . import kernels

    table = MaterialTable.of(material)
    F = np.asarray(F, dtype=np.float64)
    single = F.ndim == 2
    F = np.ascontiguousarray(F.reshape(-1, 3, 3))
    mat_id = (np.zeros(F.shape[0], np.int64) if mat_id is None
              else np.ascontiguousarray(np.broadcast_to(mat_id, F.shape[:1]), dtype=np.int64))
    if history is None:
        history = table.initial_history(mat_id)
    history = np.ascontiguousarray(np.asarray(history, dtype=np.float64).reshape(F.shape[0], -1))
    if history.shape[1] != table.n_history:
        raise ValueError(f"history: expected {table.n_history} columns, got {history.shape[1]}")
    psi = kernels.stored_energies(F, history, table.params(), mat_id)
    j2 = np.array([m.law == "j2" for m in table.materials])[mat_id]
    W_p = np.where(j2, history[:, HIST_W_P], 0.0) if history.shape[1] > HIST_W_P else np.zeros_like(psi)
    W_rel = (np.where(j2, history[:, HIST_W_REL], 0.0) if history.shape[1] > HIST_W_REL
             else np.zeros_like(psi))
    from .brittle import H_W_RELEASED as _BR_W

    brittle = np.array([m.law == "brittle" for m in table.materials])[mat_id]
    if brittle.any():
        W_rel = np.where(brittle, history[:, _BR_W], W_rel)
    res = {"psi": psi, "W_p": W_p, "W_rel": W_rel}
    if single:
        res = {k: float(v[0]) for k, v in res.items()}
    return res
