"""The reinforced mortar beam of 003 (studies/rc_beam/scene.py): bad input, the quarter model's
particles against closed forms, and a short coarse impact through the particle driver (momentum
through the first contact, contact forces equal and opposite, no NaN)."""
import dataclasses
import math

import numpy as np
import pytest

from sph import driver
from sph.contact import contact_forces
from sph.particles import discretise
from studies.rc_beam.scene import D10_AREA, RCBeam, bar_lines, staircase
from workbench.scenes import ParameterError


# -- bad input: one line naming the parameter and its range ---------------------------------------
@pytest.mark.parametrize("kw, name", [
    (dict(f_t=0.0), "f_t"), (dict(f_c=-1e6), "f_c"), (dict(f_y=0.0), "f_y"),
    (dict(eps_release=1.0e-4), "eps_release"),  # f_t/E = 1.35e-4: no softening branch
    (dict(velocity=-1.0), "velocity"), (dict(velocity=0.0), "velocity"),
    (dict(structure="frame"), "structure"),
    (dict(spacing=0.025), "spacing"),  # above the 20 mm cover
    (dict(specimen="C"), "specimen"),
])
def test_bad_input(kw, name):
    with pytest.raises(ParameterError) as err:
        RCBeam(**kw)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(name)


def test_spacing_of_a_resolution_above_the_cover_is_refused():
    with pytest.raises(ParameterError, match="^spacing"):
        driver.model_at(RCBeam(), 4)  # 100 mm / 4 = 25 mm > 20 mm cover


def test_specimens():
    a, b = RCBeam(), RCBeam(specimen="B")
    assert (a.span, a.impact_velocity, len(a.stirrup_positions)) == (0.8, 2.2, 4)
    assert (b.span, b.impact_velocity, b.stirrup_positions) == (0.4, 1.4, ())
    assert RCBeam(velocity=3.0).impact_velocity == 3.0


# -- the quarter model at the paper's 5 mm ------------------------------------------------------
@pytest.fixture(scope="module")
def quarter_a():
    s = RCBeam()
    return s, discretise(s.model(), s.resolution)


def test_quarter_model_regions_and_counts(quarter_a):
    """Counts of lattice nodes in each box at 5 mm (the lattice has a node at the origin): the
    beam 420 × 37.5 × 100 mm holds 85 × 8 × 21 nodes (37.5 mm is not a node: the last is 35), the
    plate's layers z = 100, 105, 110 over 11 × 8 (it takes the beam's top layer), the weight
    11 × 8 × 11 (50 mm high), the support strip 3 × 8 × 3."""
    s, ps = quarter_a
    count = {n: int(np.count_nonzero(ps.region == i)) for i, n in enumerate(ps.region_names)}
    beam = sum(v for k, v in count.items() if k in ("mortar", "bar") or k.startswith("stirrup"))
    assert beam + count["plate"] == 85 * 8 * 21 + 11 * 8 * 2
    assert count["plate"] == 11 * 8 * 3
    assert count["weight"] == 11 * 8 * 11
    assert count["support"] == 3 * 8 * 3
    assert ps.n == 85 * 8 * 21 + 11 * 8 * 2 + 11 * 8 * 11 + 3 * 8 * 3
    assert sum(k.startswith("stirrup") for k in ps.region_names) == 3 * 4
    assert ps.body_names == ("beam", "weight", "support")
    assert ps.held[ps.in_regions(["support"])].all() and not ps.held[~ps.in_regions(["support"])].any()
    # volumes: the beam's box and the plate's exactly (lattice-aligned halves), the weight's mass
    V_beam = ps.V[ps.body == 0].sum()
    assert V_beam == pytest.approx(0.42 * 0.0375 * 0.1 + 0.05 * 0.0375 * 0.01, rel=1e-12)
    assert ps.m[ps.in_regions(["weight"])].sum() == pytest.approx(100.0 / 4, rel=1e-12)


def test_rebar_carries_the_d10_section(quarter_a):
    """The main bar on lattice lines with its equivalent steel: Σ V_a E_a / L over its particles
    is E_s A_D10 (A = 71.33 mm², JIS nominal), i.e. the quarter section's steel fraction is
    A/(B/2 · H) = 1.902 %; its mass per length is ρ_s A. Closed forms; tolerance round-off."""
    s, ps = quarter_a
    sel = ps.in_regions(["bar"])
    E = np.array([mt.E for mt in ps.table.materials])[ps.mat_id]
    rho = ps.rho
    L = s.span / 2 + s.overhang
    assert float(np.sum(ps.V[sel] * E[sel]) / L) == pytest.approx(206e9 * D10_AREA, rel=1e-12)
    assert float(np.sum(ps.V[sel] * rho[sel]) / L) == pytest.approx(7850.0 * D10_AREA, rel=1e-12)
    frac = float(np.sum(ps.V[sel] * E[sel] / 206e9) / (L * 0.0375 * 0.1))
    assert frac == pytest.approx(71.33 / (37.5 * 100.0), rel=1e-12)
    # at 5 mm the bar (side 8.45 mm about y = 17.5, z = 20 mm) is the lattice lines y = 15, 20
    ys, zs = np.unique(ps.X[sel, 1]), np.unique(ps.X[sel, 2])
    assert np.allclose(ys, [0.015, 0.020]) and np.allclose(zs, [0.020])


def test_lattice_helpers():
    assert bar_lines(0.0175, math.sqrt(D10_AREA), 0.005) == (3, 4)
    assert bar_lines(0.0175, 0.001, 0.0125) == (1, 1)  # none within: the nearest line
    assert staircase(0.0375, 0.005) == pytest.approx(0.0375)
    assert staircase(0.0375, 0.02) == pytest.approx(0.03)  # nodes 0, 20 mm; 20 owns up to 30


# -- a short coarse impact ------------------------------------------------------------------------
def test_contact_forces_equal_and_opposite(quarter_a):
    """With the weight pushed into the plate by a third of a spacing, the contact force on the
    weight is minus that on the beam, and the total is zero to round-off."""
    s, ps = quarter_a
    x = ps.X.copy()
    w = ps.in_regions(["weight"])
    x[w, 2] -= ps.dx / 3
    f, e = contact_forces(x, ps.body, ps.dx, s.contact_stiffness * s.E_s)
    Fw, Fb = f[w].sum(axis=0), f[ps.body == 0].sum(axis=0)
    assert Fw[2] > 0 and e > 0
    assert np.allclose(Fw, -Fb, rtol=1e-12, atol=1e-9 * abs(Fw[2]))


@pytest.mark.parametrize("method, options", [("sph", dict(stress="hyperelastic")), ("csph", {})])
def test_short_impact_conserves_momentum(method, options):
    """Specimen A at 20 mm spacing for 40 µs: the weight strikes the plate (the impact force
    rises), and until the stress wave reaches the support 400 mm away (the steel's P wave,
    5.96 km/s, needs 67 µs) no external force acts along z: the z momentum of weight + beam stays
    −(100 kg/4)·2.2 m/s. Tolerance 1e-6 of it: the support's kernel-smeared precursor (< 1e-2 N
    over 4e-5 s) and round-off; a contact force not equal and opposite would change it by a
    fraction of the impact's impulse (~1 N s, 2 %)."""
    s = RCBeam(t_end=4e-5, n_out=10, dt_factor=0.1)
    out = driver.solve(method, s, 5, **options)
    assert out["status"] == "ok"
    p = np.asarray(out["linear_momentum"])
    p0 = -25.0 * 2.2
    assert np.all(np.isfinite(p)) and np.all(np.isfinite(out["midspan_displacement"]))
    assert np.allclose(p[:, 2], p0, rtol=0, atol=1e-6 * abs(p0))
    assert np.max(out["impact_force"]) > 1e4  # the weight struck the plate
    assert out["midspan_displacement"][-1] > 0  # the beam moves down
    for k in ("impact_force", "support_reaction", "time"):
        assert np.all(np.isfinite(out[k]))


@pytest.fixture(scope="module")
def consistent_a():
    """Integration-consistent csph on specimen A at 12.5 mm for 0.1 ms with the time step a factor
    times its own critical step 2/ω_max (``dt_reference='spectrum'``, :mod:`sph.spectrum`): 0.9
    and 1.2. Also the CFL estimate Δx/c_p of the same body. Asked for by name: the beam's end
    faces lie half a spacing between lattice planes at this spacing (2.8 % of the boundary,
    :func:`sph.csph.off_lattice_share`), where ``integration='auto'`` takes nodal integration."""
    from sph.driver import method_entry, model_at

    s = RCBeam(t_end=1e-4, n_out=10, dt_reference="spectrum")
    runs = {f: driver.solve("csph", dataclasses.replace(s, dt_factor=f), 8, integration="consistent")
            for f in (0.9, 1.2)}
    mod, defaults = method_entry("csph")
    model, _ = model_at(s, 8)
    dt_cfl = mod.build(discretise(model, 8), **defaults, integration="consistent").time_step(1.0)
    return runs, dt_cfl


def test_consistent_csph_is_stable_below_its_critical_step(consistent_a):
    """The failure of integration-consistent csph at the CFL step (dt_factor 0.3) on this scene is
    the CFL estimate's, not the method's: its critical step 2/ω_max is 0.20 Δx/c_p here (the bars'
    and stirrups' stiff equivalent steel on lattice lines next to the mortar; nodal integration:
    0.57), below 0.3. At 0.9 Δt_crit it runs the impact (~260 steps: the weight strikes the plate,
    the beam bends) with the energy balance within the study's 2 % (studies.rc_beam.TOL_ENERGY);
    at 1.2 Δt_crit it grows exponentially within a few tens of steps (the central-difference
    amplification of the highest mode above ω Δt = 2: measured 38 steps), so the step that
    separates the two is the spectrum's, within (0.9, 1.2)."""
    from studies.rc_beam.derive import energy_error
    from studies.rc_beam.gates import TOL_ENERGY

    runs, dt_cfl = consistent_a
    ok, bad = runs[0.9], runs[1.2]
    dt_crit = ok["dt"] / 0.9
    assert dt_crit < 0.3 * dt_cfl  # the CFL step of the old default lies above the critical step
    assert ok["status"] == "ok"
    assert ok["steps"] >= 0.9 * 1e-4 / ok["dt"]
    assert np.max(ok["impact_force"]) > 1e4 and -ok["midspan_w"][-1] > 0
    assert np.max(np.abs(energy_error(ok))) <= TOL_ENERGY
    assert bad["status"].startswith("unstable")
    assert bad["dt"] == pytest.approx(1.2 * dt_crit, rel=1e-12)


# -- the kernel reduction of 003 §4.2(2) in classic SPH -------------------------------------------
@pytest.fixture(scope="module")
def small_block():
    """A jittered 5³ block (3-D, 10 mm spacing) with random stresses and velocities, its
    neighbours, and one interior particle p (index 62, the centre) taken as fully released."""
    from sph.kernels import SUPPORT
    from sph.neighbours import neighbour_list

    rng = np.random.default_rng(7)
    dx = 0.01
    g = np.arange(5) * dx
    x = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    x = np.ascontiguousarray(x + 0.1 * dx * rng.standard_normal(x.shape))
    n = len(x)
    h = 1.3 * dx
    ip, ix = neighbour_list(x, SUPPORT * h)
    s = rng.standard_normal((n, 3, 3)) * 1e6
    return dict(x=x, v=rng.standard_normal((n, 3)), m=np.full(n, 2.2),
                rho=2200.0 * (1 + 0.05 * rng.random(n)), sigma=0.5 * (s + s.transpose(0, 2, 1)),
                c=np.full(n, 2300.0), h=h, ip=ip, ix=ix, p=62, phi=0.05)


def _without(ip, ix, i, p):
    """The neighbour list with the pair (i, p) removed from row i (CSR)."""
    row = ix[ip[i]:ip[i + 1]]
    keep = np.ones(len(ix), bool)
    keep[ip[i] + np.flatnonzero(row == p)] = False
    ip2 = ip.copy()
    ip2[i + 1:] -= 1
    return ip2, ix[keep]


def test_kernel_reduction_scales_the_forces_across_a_released_particle(small_block):
    """sph.classic.force_pass with the kernel factors kf (φ_min at p, 1 elsewhere) against the
    unreduced pass: p's acceleration is φ_min times the unreduced one (all its pairs cross it); a
    neighbour i's is its acceleration without the pair (i, p) (the neighbour list with that pair
    removed: an independent split of the sum) plus φ_min times that pair's share; a particle with p
    not among its neighbours is untouched; Σ m a stays zero (the factor is symmetric).
    Tolerance: round-off of the pair sums."""
    from sph.classic import force_pass

    b = small_block
    n, p, phi = len(b["x"]), b["p"], b["phi"]
    zero, fixed = np.zeros((n, 3)), np.zeros((n, 3), np.uint8)
    R = np.zeros((n, 3, 3))

    def acc(ip, ix, kf=None):
        a = np.zeros((n, 3))
        force_pass(b["x"], b["v"], b["m"], b["rho"], b["sigma"], R, ip, ix, b["h"], b["c"], 1.0,
                   1.0, 0, 1.0, zero, a, fixed, zero, 0.0, 0.0, False, kf)
        return a

    kf = np.ones(n)
    kf[p] = phi
    full, red = acc(b["ip"], b["ix"]), acc(b["ip"], b["ix"], kf)
    scale = np.abs(full).max()
    assert np.allclose(red[p], phi * full[p], rtol=0, atol=1e-12 * scale)
    nb = [i for i in range(n) if i != p and p in b["ix"][b["ip"][i]:b["ip"][i + 1]]]
    far = [i for i in range(n) if i != p and i not in nb]
    assert len(nb) > 20 and far
    near = sorted(nb, key=lambda i: np.linalg.norm(b["x"][i] - b["x"][p]))[:6]  # at ~Δx
    for i in near:
        rest = acc(*_without(b["ip"], b["ix"], i, p))[i]
        assert np.allclose(red[i], rest + phi * (full[i] - rest), rtol=0, atol=1e-12 * scale)
        assert np.linalg.norm(full[i] - rest) > 1e-3 * scale  # the pair's share is not small
    assert np.array_equal(red[far], full[far])
    assert np.allclose((b["m"][:, None] * red).sum(axis=0), 0.0, atol=1e-12 * scale * b["m"].sum())


def test_kernel_reduction_scales_the_velocity_gradient_across_a_released_particle(small_block):
    """sph.classic.rates_pass, hypoelastic from zero stress over a unit step (σ = λ tr L I + 2μ sym
    L, linear in L): with the kernel factors, p's stress is φ_min times the unreduced one and a
    neighbour i's is the stress without the pair (i, p) plus φ_min times that pair's share."""
    from sph.classic import rates_pass

    b = small_block
    n, p, phi = len(b["x"]), b["p"], b["phi"]
    lam, mu = np.full(n, 3e9), np.full(n, 5e9)

    def stress(ip, ix, kf=None):
        sig = np.zeros((n, 3, 3))
        rates_pass(b["x"], b["v"], b["m"], b["rho"], b["rho"].copy(), sig,
                   np.tile(np.eye(3), (n, 1, 1)), ip, ix, b["h"], 1.0, lam, mu, False,
                   np.zeros((1, 16)), np.zeros(n, np.int64), np.zeros((n, 0)), np.zeros((n, 0)),
                   0.0, np.zeros(n, np.int64), np.zeros((n, 3, 3)), kf)
        return sig

    kf = np.ones(n)
    kf[p] = phi
    full, red = stress(b["ip"], b["ix"]), stress(b["ip"], b["ix"], kf)
    scale = np.abs(full).max()
    assert np.allclose(red[p], phi * full[p], rtol=0, atol=1e-12 * scale)
    i = int(b["ix"][b["ip"][p]:b["ip"][p + 1]][0])
    rest = stress(*_without(b["ip"], b["ix"], i, p))[i]
    assert np.allclose(red[i], rest + phi * (full[i] - rest), rtol=0, atol=1e-12 * scale)


def test_kernel_factors_from_the_released_flag():
    """sph.classic.kernel_factors: φ_min of the particle's mortar where its fully-released flag is
    set, 1 for partly released mortar and for any other law (the steel's history column 16 is not a
    flag); and the option needs the hyperelastic stress path."""
    from sph.classic import Body, kernel_factors
    from workbench.materials import Material, MaterialTable
    from workbench.materials.mortar import H_RELEASED

    mortar = Material.mortar(E=11.9e9, nu=0.22, f_t=1.61e6, f_c=16.1e6, eps_release=0.017,
                             phi_min=0.07)
    table = MaterialTable((Material.j2_linear(E=2e11, nu=0.3, sigma_y0=4e8, H=2e9), mortar))
    mat_id = np.array([1, 1, 0, 1])
    h = np.zeros((4, table.n_history))
    h[[0, 2], H_RELEASED] = 1.0
    h[3, H_RELEASED - 1] = 0.9  # damaged, not released
    assert np.array_equal(kernel_factors(table, mat_id, h, np.empty(4)), [0.07, 1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="^kernel_reduction"):
        Body(np.zeros((2, 3)), np.ones(2), mortar, 0.01, stress="hypoelastic",
             kernel_reduction=True)


# -- the full beam (symmetry=False) against the quarter model -------------------------------------
@pytest.mark.parametrize("r", [5, 8])
def test_full_beam_is_the_quarter_model_mirrored(r):
    """``symmetry=False`` at 20 and 12.5 mm (12.5 mm: x_e = 420 mm is not a lattice multiple, the
    lattice must still have a node on x = 0 and y = 0): the full beam's particles are the quarter
    model's mirrored in x = 0 and y = 0 (as sets of positions, per region), every body's mass is
    four times the quarter's (the plane particles' half volumes become whole), the weight's is
    the full 100 kg, and there are no symmetry rollers. Closed forms; tolerance round-off."""
    q, f = RCBeam(), RCBeam(symmetry=False)
    pq, pf = discretise(driver.model_at(q, r)[0], r), discretise(driver.model_at(f, r)[0], r)
    assert not driver.model_at(f, r)[0].constraints
    assert pq.region_names == pf.region_names
    key = lambda X: {tuple(np.round(p / pq.dx, 6)) for p in X}
    for k, name in enumerate(pq.region_names):
        Xq = pq.X[pq.region == k]
        mirrored = np.concatenate([Xq * s for s in ((1, 1, 1), (-1, 1, 1), (1, -1, 1), (-1, -1, 1))])
        assert key(pf.X[pf.region == k]) == key(mirrored), name
        assert pf.m[pf.region == k].sum() == pytest.approx(4 * pq.m[pq.region == k].sum(), rel=1e-12)
    assert pf.m[pf.in_regions(["weight"])].sum() == pytest.approx(100.0, rel=1e-12)
    assert f.copies == 1 and q.copies == 4


def test_quarter_model_contact_is_a_quarter_of_the_full_beams():
    """The contact of the quarter model (weighted on its symmetry planes: sph.contact, the masks
    from the scene's rollers, driver.Run.mirror_planes) against the full beam's (no planes) at
    20 mm, in the same symmetric configuration: the beam pushed Δx/4 into the supports and the
    weight Δx/3 into the plate. The impact force, the support force and the contact energy of the
    quarter model are exactly a quarter of the full beam's (round-off). Without the weights the
    pairs on the planes (4 of the 6 weight-plate pairs, one of them on both planes; 3 of the 6
    beam-support pairs) push as whole ones: impact force x 1.6, support force x 1.33."""
    from sph.contact import contact_forces

    r = 5
    out = {}
    for sym in (True, False):
        model, dx = driver.model_at(RCBeam(symmetry=sym), r)
        ps = discretise(model, r)
        x = ps.X.copy()
        x[ps.body != ps.body_names.index("support"), 2] -= 0.25 * dx
        x[ps.body == ps.body_names.index("weight"), 2] -= dx / 3
        run = driver.Run(model, ps, None)
        rc, k, planes = run._contact_setup()
        assert (planes is None) == (not sym)
        f, e = contact_forces(x, ps.body, rc, k, planes)
        out[sym] = [e] + [f[ps.body == ps.body_names.index(b), 2].sum()
                          for b in ("weight", "support")]
    (eq, wq, sq), (ef, wf, sf) = out[True], out[False]
    assert ef > 0 and wf > 0 and sf < 0
    assert 4 * eq == pytest.approx(ef, rel=1e-12)
    assert 4 * wq == pytest.approx(wf, rel=1e-12)
    assert 4 * sq == pytest.approx(sf, rel=1e-12)


# The quarter model against the full beam (issue 12 gate 4): tests/test_mirror.py.
