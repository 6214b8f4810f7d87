"""Building blocks of a scene reader: meshes of unions of boxes with region ids by centroid,
Dirichlet and Neumann data on node sets (body force with a density per element), and the
observables (reaction on a node set, displacement at any point, stored energy, failed fraction).
"""
import numpy as np
import pytest

from fem_reference.assembly import Discretisation
from fem_reference.boundary import Constraints, Loads
from fem_reference.mesh import beam_on_block, boxes_mesh, element_size, grid_lines, in_boxes
from fem_reference.observe import displacement_at, failed_fraction, reaction, stored_energy
from fem_reference.static import Problem, load_path
from workbench.materials import Material, MaterialTable, TABLE1_STEEL

# ------------------------------------------------------------------------------------------------
# meshes of unions of boxes
# ------------------------------------------------------------------------------------------------


def test_grid_lines_hold_every_face_and_the_size():
    boxes = [((0, 0), (2.0, 0.5)), ((-0.3, -1.0), (0.0, 1.0))]
    lx, ly = grid_lines(boxes, element_size(0.5, 2))  # h = 0.25
    for v in (-0.3, 0.0, 2.0):
        assert np.min(np.abs(lx - v)) == 0.0
    for v in (-1.0, 0.0, 0.5, 1.0):
        assert np.min(np.abs(ly - v)) == 0.0
    # each gap between faces is cut into round(gap/h) intervals: 0.3/0.25 -> 1, 2/0.25 -> 8
    assert len(lx) == 1 + 1 + 8
    assert np.all(np.diff(lx) > 0) and np.all(np.diff(ly) > 0)
    with pytest.raises(ValueError, match="resolution"):
        element_size(0.5, 0)


def test_beam_on_block_mesh_is_the_union():
    """The 20 × 5 × 5 µm beam on a 5 × 10 × 10 µm block at 2 elements across H: 8·2·2 beam
    elements and 2·4·4 block elements, volume and surface area those of the union, every element
    inside it."""
    L, B, H = 20e-6, 5e-6, 5e-6
    mesh, boxes = beam_on_block(L, B, H, (5e-6, 10e-6, 10e-6), element_size(H, 2))
    disc = Discretisation(mesh, order=2)
    assert disc.nel == 8 * 2 * 2 + 2 * 4 * 4
    V = L * B * H + 5e-6 * 10e-6 * 10e-6
    assert disc.volumes().sum() == pytest.approx(V, rel=1e-12)
    c = disc.centroids()
    assert in_boxes(c.T, boxes).all()
    # surface: block 2(100 + 50 + 50) − the beam's root face 25, beam 2·(100 + 100) + 25 (µm²)
    area = (2 * (100 + 50 + 50) - 25 + 4 * 100 + 25) * 1e-12
    # a unit traction e_X on every boundary facet: its X forces sum to the boundary area
    vec = disc.traction_load(disc.facets_where(lambda x: np.ones(x.shape[1], bool)),
                             np.array([1.0, 0.0, 0.0]))
    assert vec[0::3].sum() == pytest.approx(area, rel=1e-12)


def test_region_ids_by_centroid_with_priority():
    """The reader's rule: an element takes the region of highest priority containing its
    centroid; here a slab and a box overlap and the box wins."""
    mesh = boxes_mesh([((0, 0, 0), (4.0, 1.0, 1.0))], 0.5)
    disc = Discretisation(mesh)
    c = disc.centroids()
    shapes = [  # (priority, contains)
        (0, lambda p: np.ones(len(p), bool)),
        (1, lambda p: p[:, 0] < 2.0),
        (2, lambda p: (p[:, 0] > 1.0) & (p[:, 0] < 3.0) & (p[:, 1] > 0.5)),
    ]
    region = np.zeros(disc.nel, dtype=np.int64)
    best = np.full(disc.nel, -1)
    for rid, (prio, contains) in enumerate(shapes):
        inside = contains(c) & (prio > best)
        region[inside], best[inside] = rid, prio
    expect = np.where((c[:, 0] > 1) & (c[:, 0] < 3) & (c[:, 1] > 0.5), 2,
                      np.where(c[:, 0] < 2, 1, 0))
    assert np.array_equal(region, expect)
    assert set(np.unique(region)) == {0, 1, 2}


# ------------------------------------------------------------------------------------------------
# a bar of two materials hanging under its own weight
# ------------------------------------------------------------------------------------------------
# 0 ≤ X ≤ L, u_X = 0 on X = 0, rollers on every lateral face (uniaxial strain, modulus
# M_k = λ_k + 2μ_k), gravity g along +X, densities ρ_0 (X < L/2), ρ_1 (X > L/2). Small strain
# (g = 9.81e-4 m/s², ρ g L/M ~ 3e-9): N(X) = ∫_X^L ρ g dX' (axial stress),
# u(X) = ∫_0^X N/M dX' — piecewise
# quadratic with its kinks on an element boundary, in the space of the quadratic elements. The
# geometric and material nonlinearity of SVK changes u by 1.5 ε ~ 5e-9 relative: tolerance 1e-7.
# Reaction of the support X = 0 on the body: −(the weight Σ ρ_k g V_k) whatever the law
# (Σ_a ∂N_a/∂X = 0), to the round-off of the internal force, ~1e-16 E A = 1e-8 of this small load:
# 1e-6. Stored energy
# ∫ N²/(2M) dV, within the same O(ε).

L, W = 1.0, 0.25
G = 9.81e-4  # reached as 9.81 λ² at λ = 0.01 (a parameter function of the load)
MATS = MaterialTable((Material.svk(E=2e9, nu=0.3, rho=7800.0),
                      Material.svk(E=0.5e9, nu=0.25, rho=2400.0)))
TOL_SMALL = 1e-7
TOL_REACTION = 1e-6


def exact_bar(X):
    m = MATS.materials
    M = [mm.lam + 2 * mm.mu for mm in m]
    rho = [mm.rho for mm in m]
    h = L / 2
    N = np.where(X < h, rho[0] * G * (h - X) + rho[1] * G * h, rho[1] * G * (L - X))
    # u = ∫ N/M: region 0 then region 1
    u0 = lambda x: (rho[0] * G * (h * x - x ** 2 / 2) + rho[1] * G * h * x) / M[0]  # noqa: E731
    u1 = lambda x: rho[1] * G * (L * x - x ** 2 / 2) / M[1]  # noqa: E731
    u = np.where(X < h, u0(X), u0(h) + u1(X) - u1(h))
    e = (rho[0] ** 2 * G ** 2 / M[0] * ((h + rho[1] / rho[0] * h) ** 3 - (rho[1] / rho[0] * h) ** 3)
         / 3 / 2 + rho[1] ** 2 * G ** 2 / M[1] * h ** 3 / 3 / 2) * W * W
    return u, N, e


@pytest.mark.parametrize("d", [2, 3])
def test_hanging_bimaterial_bar(d):
    lo, hi = (0.0,) + (0.0,) * (d - 1), (L,) + (W,) * (d - 1)
    disc = Discretisation(boxes_mesh([(lo, hi)], L / 8), order=2)
    mat_id = (disc.centroids()[:, 0] > L / 2).astype(np.int64)
    bc = Constraints(disc)
    bc.roller(lambda x: x[0] < 1e-12, 0)
    for k in range(1, d):
        bc.roller(lambda x, k=k: (x[k] < 1e-12) | (x[k] > W - 1e-12), k)
    bc.apply()
    loads = Loads(disc)
    # the gravity load at λ = 1 through a non-trivial parameter function
    loads.body(MATS.rho(mat_id), np.eye(d)[0] * 9.81, scale=lambda lam: lam ** 2)
    problem = Problem(disc, MATS, "strain" if d == 2 else None, bc.values, loads, mat_id=mat_id)
    _, state = load_path(problem, [0.01], rtol=1e-12)
    X = disc.basis.doflocs
    comp = np.arange(disc.N) % d
    u_ex, _, e_ex = exact_bar(X[0])
    u_ex = np.where(comp == 0, u_ex, 0.0)
    umax = np.abs(u_ex).max()
    assert np.abs(state.u - u_ex).max() < TOL_SMALL * umax
    # between the nodes: the interpolated displacement
    rng = np.random.default_rng(0)
    pts = rng.random((20, d)) * np.array(hi)
    u_pts = displacement_at(disc, state.u, pts)
    assert np.abs(u_pts[:, 0] - exact_bar(pts[:, 0])[0]).max() < TOL_SMALL * umax
    assert np.abs(u_pts[:, 1:]).max() < 1e-12 * umax
    # reaction on X = 0: the weight (2-D: per unit thickness)
    weight = sum(m.rho for m in MATS.materials) * G * (L / 2) * W ** (d - 1)
    R = reaction(problem, state, where=lambda x: x[0] < 1e-12, lam=0.01)
    assert R[0] == pytest.approx(-weight, rel=TOL_REACTION)
    # stored energy (2-D: per unit thickness, so divide the 3-D closed form by W)
    e_ex = e_ex / (W if d == 2 else 1.0)
    assert stored_energy(problem, state) == pytest.approx(e_ex, rel=TOL_SMALL)


def test_failed_fraction_per_region():
    disc = Discretisation(boxes_mesh([((0, 0, 0), (5.0, 1.0, 1.0))], 1.0))
    mat_id = (disc.centroids()[:, 0] > 2.0).astype(np.int64)  # 2 elements in region 0, 3 in 1
    problem = Problem(disc, MaterialTable((TABLE1_STEEL, TABLE1_STEEL)), None,
                      lambda lam: np.zeros(0), lambda lam: np.zeros(disc.N), mat_id=mat_id,
                      deletion=True)
    disc.deactivate([0, 4])
    assert failed_fraction(problem) == {0: 0.5, 1: pytest.approx(1 / 3)}
    assert failed_fraction(problem, by="volume") == {0: 0.5, 1: pytest.approx(1 / 3)}


# ------------------------------------------------------------------------------------------------
# point loads anywhere, mean stress per region
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("order", [1, 2])
def test_point_load_between_nodes_is_consistent(order):
    """A force F at any point x: its nodal forces N_a(x) F sum to F and have the moment x × F
    (the shape functions reproduce constants and linear fields)."""
    disc = Discretisation(boxes_mesh([((0, 0, 0), (2.0, 1.0, 1.0))], 0.5), order=order)
    loads = Loads(disc)
    x = np.array([0.61, 0.37, 0.83])  # not a node
    F = np.array([1.0, -2.0, 0.5])
    f = loads.point(x, F).reshape(-1, 3)  # (nodes, 3), interleaved
    X = disc.basis.doflocs[:, ::3].T
    assert np.allclose(f.sum(axis=0), F, rtol=0, atol=1e-14)
    assert np.allclose(np.cross(X, f).sum(axis=0), np.cross(x, F), rtol=0, atol=1e-14)
    assert np.count_nonzero(np.abs(f).sum(axis=1)) > 1  # spread over the element's nodes


def test_mean_stress_per_region():
    """Two SVK regions in series under uniaxial strain (rollers on the lateral faces) and a dead
    axial traction t: σ₁₁ = P₁₁ λ/J = t in both, σ₂₂ = S₂₂/λ = λ_L E₁₁/λ in each region
    (E₁₁ = (λ² − 1)/2 from M λ (λ² − 1)/2 = t), exact in the finite-element space."""
    from scipy.optimize import brentq

    from fem_reference.observe import mean_stress

    disc = Discretisation(boxes_mesh([((0, 0, 0), (2.0, 0.5, 0.5))], 0.5), order=2)
    mat_id = (disc.centroids()[:, 0] > 1.0).astype(np.int64)
    bc = Constraints(disc)
    bc.roller(lambda x: x[0] < 1e-12, 0)
    bc.roller(lambda x: (x[1] < 1e-12) | (x[1] > 0.5 - 1e-12), 1)
    bc.roller(lambda x: (x[2] < 1e-12) | (x[2] > 0.5 - 1e-12), 2)
    bc.apply()
    t = 0.02 * MATS[1].E
    loads = Loads(disc)
    loads.traction(lambda x: x[0] > 2.0 - 1e-12, np.array([t, 0.0, 0.0]))
    problem = Problem(disc, MATS, None, bc.values, loads, mat_id=mat_id)
    _, state = load_path(problem, [1.0], rtol=1e-12)
    for k, m in enumerate(MATS.materials):
        M = m.lam + 2 * m.mu
        lam = brentq(lambda s: M * s * (s * s - 1) / 2 - t, 0.5, 2.0, xtol=1e-16, rtol=1e-15)
        sig = mean_stress(problem, state, elements=mat_id == k)
        assert sig[0, 0] == pytest.approx(t, rel=1e-10)
        assert sig[1, 1] == pytest.approx(m.lam * (lam * lam - 1) / 2 / lam, rel=1e-10)
        assert abs(sig[0, 1]) < 1e-10 * t
