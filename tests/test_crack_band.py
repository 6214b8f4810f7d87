"""Issue 12 gate 6, the regularisation: a mortar bar (workbench.scenes.crack_band.MortarBar, the
mortar of 003 with ν = 0) pulled apart at three spacings, 5, 3.33 and 2.5 mm, with csph and
classic SPH as the RC beam study runs them. The reference is the closed form of the law: a fully
released particle releases g_F = ½ f_t ε_0 per unit volume, so a crack band n layers wide releases
n G_F(Δx) per unit crack area, G_F(Δx) = ½ f_t ε_0(Δx) Δx (workbench.materials.mortar.
fracture_energy). With eq. 5 (``scale_release``: ε_0 ∝ 1/Δx) that is the same at every spacing;
without it it scales with Δx (Bažant & Belytschko's mesh dependence).

Measured (2 shared cores; the runs 15–40 s together, with the machine's load): the band is two
lattice columns in both methods (the scene's docstring says why), so the energy per crack area is
2 G_F: with eq. 5, csph 2.0002 / 2.0003 / 2.0001 G_F at 5, 3.33 and 2.5 mm, classic SPH 2.200 /
2.162 / 2.111; without it the same multiples of G_F(Δx) ∝ Δx: csph 136.9 / 91.2 / 68.4 J/m², sph
150.6 / 98.4 / 72.2 J/m². (Before the mortar law's crack frame was fixed, classic SPH gave 2.132 /
2.101 / 2.073: the turning principal directions of its free-surface particles ratcheted their
damage up, releasing the band's surface particles fully and shortening the softening tail.)"""
import math

import numpy as np
import pytest

from studies.rc_beam.ladders import OPTIONS as RC_OPTIONS
from studies.common import observed_order
from studies.crack_band import crack_band
from workbench.scenes.crack_band import MortarBar
from workbench.materials.mortar_constants import PAPER_SPACING

RESOLUTIONS = (4, 6, 8)
"""Particles across B = 20 mm: 5 (003's spacing), 3.33 and 2.5 mm."""
OPTIONS = {"csph": dict(RC_OPTIONS["csph"], crack="none"), "sph": RC_OPTIONS["sph"]}
"""The solvers as the RC beam study runs them: csph with nodal integration and no crack rule (the
beam's quarter model has mirror images, where csph's ``crack='auto'`` is 'none'), classic SPH
with the hyperelastic stress path (and its viscous work tracked). (The integration-consistent csph,
the default: 2.061 / 2.045 / 2.036 G_F — the columns beside the band keep 2–4 % partial damage.
With csph's visibility rule, which cuts the pairs across a particle once it has failed, its
partner in the band stops straining at damage ~0.998 and 1.5 of the two columns count as fully
released at 5 mm; the energy per crack area is still 2.0005 G_F.)"""
OPENING = {"csph": 3.0, "sph": 5.0}
"""Final opening over ε_0(Δx) Δx: csph's band separates (force ≤ 5 % of the peak) at 2.0–2.1,
classic SPH's softening branch is longer (3.2–4.5): its Eulerian kernel (support 2.6 Δx) keeps
pairs across the opening crack until the gap exceeds it."""
DT_FACTOR = {"csph": 0.5, "sph": 1.0}
"""Time step over Δx/c_p: about half of csph's critical step on this bar (0.92 Δx/c_p with nodal
integration, sph.spectrum), 0.4 of classic SPH's (2.5–3.4)."""
BAND = 2
"""Layers of the crack band: two lattice columns (a particle's gradient spans its neighbours, not
itself: a jump between two columns is a strain of both)."""
TOL_BAND = 0.01
"""|energy per crack area / (2 G_F) − 1| for csph. Exact for the two fully released columns (the
law releases g_F per unit volume; the midpoint rule's E Δε²/8 with Δε of one time step, ~1e-9 of
it). What may be added is the partial damage of the columns beside the band, which see across
the opening crack through their second neighbours: none with csph's nodal integration (the
integration-consistent csph leaves 2–4 %), so 1 %. Classic SPH has no such bound: its Eulerian
kernel (support 2.6 Δx) damages the columns beside the band, and its band's free-surface
particles lag (truncated kernel) and stop short of full release (damage 0.98), so its softening
tail creeps on and the energy at the run's end depends on how far the bar is pulled (5 mm: 2.200
G_F at an opening of 5 ε_0 Δx, 2.322 at 7). For classic SPH the test asks that the excess over
2 G_F, an artefact of the layers next to the crack and the surface, converges to the closed form
2 G_F as the spacing shrinks (:data:`MIN_EXCESS_ORDER`)."""
TOL_SPREAD = {"csph": 0.01}
"""The regularisation: the energy per crack area at the three spacings agrees within the part
that is not the band's (the only part that may depend on the spacing): 1 % (csph). Without eq. 5
the spacings' energies differ by their spacings' ratio, 1.5 and 2: a regression to a fixed release
strain fails by 10 to 100 times this."""
MIN_EXCESS_ORDER = 0.5
"""Classic SPH: its energy per crack area above the closed form 2 G_F (the partly damaged columns
beside the band, a fixed number of particle layers within the kernel's 2.6 Δx, and the band's
lagging surface particles) falls as the spacing does, first order in Δx (measured with eq. 5:
+10.0, +8.1, +5.5 % at 5, 3.33, 2.5 mm, order 0.87; without it alike), so the value converges to
the closed form: the excess's observed order, least squares over the three spacings, at least
half the first order. (It replaces a spread of 5 % across the spacings against 4.2 % observed.)"""
TOL_LAYER = 0.02
"""Energy of the fully released particles over their volume × g_F: 1 for a particle released
along one axis; the band's free-surface particles see some shear as the crack opens, and with
φ_min on the shear terms a little of that is released too (classic SPH: up to 1 %)."""


def scene(method: str, scale: bool) -> MortarBar:
    return MortarBar(scale_release=scale, opening=OPENING[method], dt_factor=DT_FACTOR[method])


@pytest.fixture(scope="module", params=("csph", "sph"))
def ladder(request):
    """{scale_release: [crack_band(...) at each resolution]} of one method. At 5 mm the release
    strain is 003's 17 000 µ with or without eq. 5: one run serves both."""
    from sph import driver

    method = request.param
    out = {}
    for scale in (True, False):
        sc = scene(method, scale)
        rows = []
        for r in RESOLUTIONS:
            dx = sc.B / r
            if not scale and math.isclose(dx, PAPER_SPACING):
                assert sc.mortar(dx).eps_release == pytest.approx(
                    scene(method, True).mortar(dx).eps_release, rel=1e-12)
                rows.append(out[True][RESOLUTIONS.index(r)])
                continue
            run = driver.solve(method, sc, r, **OPTIONS[method])
            assert run["status"] == "ok", run["status"]
            rows.append(crack_band(sc, r, run))
        out[scale] = rows
    return method, out


def test_fracture_energy_closed_form():
    """G_F(Δx) = ½ f_t ε_0(Δx) Δx: 68.4 J/m² at every spacing with eq. 5 (003: 1.61 MPa, 17 000 µ,
    5 mm), and ∝ Δx without; the weak section keeps it (ε_0 over its strength)."""
    on, off = MortarBar(), MortarBar(scale_release=False)
    for dx in (0.005, 0.0025, 0.00125):
        assert on.fracture_energy(dx) == pytest.approx(0.5 * 1.61e6 * 0.017 * 0.005, rel=1e-12)
        assert off.fracture_energy(dx) == pytest.approx(0.5 * 1.61e6 * 0.017 * dx, rel=1e-12)
        for sc in (on, off):
            weak = sc.mortar(dx, sc.weak)
            assert 0.5 * weak.f_t * weak.eps_release * dx == pytest.approx(sc.fracture_energy(dx),
                                                                           rel=1e-12)


def test_crack_band_is_two_layers_each_releasing_its_fracture_energy(ladder):
    """The fully released particles lie in the two columns of the weak section, which are released
    throughout (at every spacing, with and without eq. 5), and the energy of the fully released
    particles is their volume × g_F (the law's closed form)."""
    method, out = ladder
    for scale, rows in out.items():
        for r, c in zip(RESOLUTIONS, rows):
            assert c["band"] == [0, 1], (scale, r, c["band"])
            # classic SPH: the band's free-surface particles stop at damage ~0.99 (the gap outgrows
            # their truncated kernel first); csph releases all of them
            assert c["band_min_damage"] >= (1.0 if method == "csph" else 0.95), (scale, r, c)
            assert c["released_layers"] <= BAND + 1e-9, (scale, r, c)
            assert c["full"] / c["released_layers"] == pytest.approx(1.0, abs=TOL_LAYER), (scale, r, c)
            assert c["residual_force"] < 0.1, (scale, r, c)  # separated: the force has fallen


def test_energy_per_crack_area_is_spacing_independent_with_eq5(ladder):
    """With eq. 5 the energy released per crack area is the same at 5, 3.33 and 2.5 mm, and it is
    2 G_F (the band of two layers) within the partial damage beside it."""
    method, out = ladder
    per_area = np.array([c["final_ratio"] * c["G_F"] for c in out[True]])
    GF = out[True][0]["G_F"]
    if method == "csph":
        assert per_area / (BAND * GF) == pytest.approx(np.ones(3), abs=TOL_BAND), per_area / GF
        assert per_area.max() / per_area.min() - 1 <= TOL_SPREAD[method], per_area / GF
    else:  # at least 2 G_F (the band), the excess converging to the closed form with the spacing
        excess = per_area / (BAND * GF) - 1
        dx = np.array([c["spacing"] for c in out[True]])
        assert np.all(excess >= 0) and np.all(np.diff(excess) < 0), per_area / GF
        assert observed_order(dx, excess) >= MIN_EXCESS_ORDER, (excess, observed_order(dx, excess))


def test_energy_per_crack_area_scales_with_spacing_without_eq5(ladder):
    """With a fixed release strain the energy per crack area is 2 G_F(Δx) ∝ Δx: divided by the
    spacing it is the same at the three spacings, and the finest releases half the coarsest's."""
    method, out = ladder
    dx = np.array([c["spacing"] for c in out[False]])
    per_area = np.array([c["final_ratio"] * c["G_F"] for c in out[False]])
    GF5 = MortarBar().fracture_energy(PAPER_SPACING)
    ratio = per_area / (BAND * GF5 * dx / PAPER_SPACING)
    if method == "csph":
        assert ratio == pytest.approx(np.ones(3), abs=TOL_BAND), per_area
        scaled = per_area * PAPER_SPACING / dx
        assert scaled.max() / scaled.min() - 1 <= TOL_SPREAD[method], scaled
        assert per_area[-1] / per_area[0] == pytest.approx(dx[-1] / dx[0], rel=TOL_SPREAD[method])
    else:  # as with eq. 5: at least the band, the excess converging to the closed form
        assert np.all(ratio >= 1) and np.all(np.diff(ratio) < 0), per_area
        assert observed_order(dx, ratio - 1) >= MIN_EXCESS_ORDER, (ratio, observed_order(dx, ratio - 1))
        assert per_area[-1] / per_area[0] == pytest.approx(dx[-1] / dx[0], rel=0.05)


# -- the RC beam study's measure (studies.rc_beam.crack_band_energy) ------------------------------
def test_rc_beam_energy_per_crack_area_of_a_constructed_band():
    """studies.rc_beam.crack_band_energy on the beam (B, 12.5 mm) with a constructed final history:
    the mortar of the two lattice columns x = 5Δx, 6Δx (beyond the loading plate, whose bottom
    layer takes the beam's top one) fully released (damage 1, W_r = g_F(Δx) =
    ½ f_t ε_0(Δx)) and the released energy their Σ V W_r. In the full beam that is two cracks (the
    quarter model's and its mirror image), each through the section less the bars' lattice lines:
    crack area 2 (B H − 2 A_bar,lattice), and the energy per crack area exactly 2 G_F (closed form:
    Σ V g_F / (Σ V/(2Δx)) = 2 Δx g_F). Then the rest of the mortar partly damaged with a further
    energy W': the ratio grows by W'/W, the fully released share is W/(W + W')."""
    from sph.driver import model_at
    from sph.particles import discretise
    from studies.rc_beam.derive import crack_band_energy
    from workbench.materials.mortar import H_DAMAGE, H_W_RELEASED, N_HISTORY, fracture_energy
    from studies.rc_beam import RCBeam

    s = RCBeam(specimen="B")
    model, dx = model_at(s, 8)
    ps = discretise(model, 8)
    mortar = ps.region == ps.region_names.index("mortar")
    band = mortar & (np.abs(ps.X[:, 0] - 5.5 * dx) < dx)  # the columns x = 5 dx, 6 dx
    gF = 0.5 * s.f_t * s.release_strain(dx)
    h = np.zeros((ps.n, N_HISTORY))
    h[band, H_DAMAGE] = 1.0
    h[band, H_W_RELEASED] = gF
    W = float(ps.V[band].sum()) * gF  # quarter model
    out = crack_band_energy(s, 8, dict(history=h, released_energy=np.array([0.0, W])))
    _, _, scale, _ = s.bars(dx)[0]
    bar_lattice = s.bar_area / scale  # the bar's lattice lines: n dx²
    assert out["crack_area"] == pytest.approx(2 * (s.B * s.H - 2 * bar_lattice), rel=1e-9)
    GF = fracture_energy(s.f_t, s.release_strain(dx), dx)
    assert out["released_per_crack_area_over_GF"] == pytest.approx(2.0, rel=1e-12)
    assert out["released_per_crack_area"] == pytest.approx(2.0 * GF, rel=1e-12)
    assert out["released_share_full"] == pytest.approx(1.0, rel=1e-12)
    rest = mortar & ~band
    h[rest, H_DAMAGE] = 0.5
    h[rest, H_W_RELEASED] = 0.1 * gF
    W2 = W + float(ps.V[rest].sum()) * 0.1 * gF
    out = crack_band_energy(s, 8, dict(history=h, released_energy=np.array([0.0, W2])))
    assert out["released_per_crack_area_over_GF"] == pytest.approx(2.0 * W2 / W, rel=1e-12)
    assert out["released_share_full"] == pytest.approx(W / W2, rel=1e-12)
    # no final history: NaN
    assert np.isnan(crack_band_energy(s, 8, dict(released_energy=np.array([W])))["crack_area"])


# -- the brittle law (issue 41): G_c spread over the method's band -------------------------------
BRITTLE_OPTIONS = {"csph": RC_OPTIONS["csph"], "sph": RC_OPTIONS["sph"]}
"""csph with nodal integration and its default crack rule (the visibility of sph.crack acts on
this bar: no mirror images), classic SPH with the hyperelastic stress path."""
TOL_BRITTLE = 0.01
"""|energy per crack area / G_c − 1| at the end of the run. The brittle law spreads G_c over the
band 2 Δx the particle methods crack (workbench.materials.brittle.PARTICLE_BAND), so the two
columns release exactly G_c per crack area (the law's closed form ½ f_t ε_f · 2 Δx; the trapezoid
rule of the released energy adds O(Δε²) per step, ~1e-9). What may be added is the partial damage
of the columns beside the band, as for the mortar: 1 %. A band factor of 1 (eq. 5 as printed for
the mortar) gives 2 G_c and fails by 100 times this; the mortar's classic-SPH excess of 10 % would
fail it too."""


@pytest.fixture(scope="module", params=("csph", "sph"))
def brittle_ladder(request):
    """[crack_band(...) at each resolution] of the brittle bar (G_c = 68.4 J/m², 003's mortar's
    E and f_t, ν = 0) with one method."""
    from sph import driver

    method = request.param
    sc = MortarBar(law="brittle", opening=OPENING[method], dt_factor=DT_FACTOR[method])
    rows = []
    for r in RESOLUTIONS:
        run = driver.solve(method, sc, r, **BRITTLE_OPTIONS[method])
        assert run["status"] == "ok", run["status"]
        rows.append(crack_band(sc, r, run))
    return method, rows


def test_brittle_law_releases_its_fracture_energy_per_crack_area_at_every_spacing(brittle_ladder):
    """Issue 41 item 1: the energy released per unit crack area is the material's G_c at 5, 3.33 and
    2.5 mm (no eq.-5 scaling by the user: the law takes the method's band), the crack in the weak
    section's two columns, the bar separated."""
    method, rows = brittle_ladder
    per_area = np.array([c["final_ratio"] for c in rows])
    assert per_area == pytest.approx(np.ones(3), abs=TOL_BRITTLE), (method, per_area)
    for c in rows:
        assert c["band"] == [0, 1], (method, c)
        assert c["released_layers"] >= 1.0, (method, c)  # at least one column cut through
        assert c["residual_force"] < 0.1, (method, c)
        assert c["peak_force"] <= 1.0, (method, c)  # the Rankine onset: at most f_t A
