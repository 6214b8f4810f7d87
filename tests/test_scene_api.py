"""The scene API (workbench.scenes.model, sph.particles): bad input gets one line naming the part,
the particle discretisation of a union of boxes has the exact volumes and the discrete divergence
theorem, probes reproduce linear fields, and regions carry their own materials."""
import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sph import particles
from workbench.materials import Material
from workbench.scenes import SceneError
from workbench.scenes import model as M
from workbench.scenes.shapes import Box, Cylinder, Plane, Point, VoronoiCell

STEEL = Material.svk(E=2e11, nu=0.3, rho=7800.0)
SOFT = Material.svk(E=1e9, nu=0.3, rho=1000.0)


def bar(**changes):
    parts = dict(dim=2, length=0.1,
                 regions=(M.Region("a", Box((0, 0), (1.0, 0.1)), STEEL),),
                 sets=(M.Set("left", Plane(0, 0.0)), M.Set("tip", Point((1.0, 0.05)))),
                 constraints=(M.Clamp("left"),),
                 loads=(M.Traction("left", (1.0, 0.0)),),
                 drive=M.Static((1.0,)),
                 observables=(M.Displacement("u", "tip", 0),))
    parts.update(changes)
    return M.Model(**parts)


# --- bad input: one line naming the part --------------------------------------------------------

@pytest.mark.parametrize("changes, match", [
    (dict(regions=(M.Region("a", Box((0, 0), (1.0, 0.1))),)), "region 'a': no material"),
    (dict(loads=(M.Traction("nowhere", (1.0, 0.0)),)), "Traction on set 'nowhere': no such set"),
    (dict(constraints=(M.Roller("left", 2),)), "axis 2 is out of range"),
    (dict(observables=(M.Displacement("u", "tipp", 0),)), "observable 'u': set 'tipp' does not exist"),
    (dict(sets=(M.Set("left", Plane(0, 0.0), region="b"),)), "set 'left': region 'b' does not exist"),
    (dict(loads=(M.BodyForce((0.0, -9.8), regions=("c",)),)), "BodyForce: region 'c' does not exist"),
    (dict(regions=(M.Region("a", Box((0, 0), (1.0, 0.1)), STEEL),
                   M.Region("a", Box((1, 0), (2.0, 0.1)), STEEL))), "region 'a': the name is used twice"),
    (dict(drive=M.Explicit(t_end=-1.0)), "t_end"),
])
def test_bad_model_is_one_line_naming_the_part(changes, match):
    with pytest.raises(SceneError, match=match) as err:
        bar(**changes)
    assert "\n" not in str(err.value)


def test_discretisation_errors_name_the_set_and_the_regions():
    empty = bar(sets=(M.Set("left", Plane(0, 0.0)), M.Set("tip", Point((1.0, 0.05))),
                      M.Set("hole", Box((2.0, 0.0), (3.0, 0.1)))))
    with pytest.raises(SceneError, match="set 'hole': selects no particle"):
        particles.discretise(empty, 2)
    overlap = bar(regions=(M.Region("a", Box((0, 0), (1.0, 0.1)), STEEL),
                           M.Region("b", Box((0.5, 0), (1.5, 0.1)), SOFT)))
    with pytest.raises(SceneError, match="regions 'a' and 'b' overlap .* without a stated priority"):
        particles.discretise(overlap, 4)
    ok = bar(regions=(M.Region("a", Box((0, 0), (1.0, 0.1)), STEEL),
                      M.Region("b", Box((0.5, 0), (1.5, 0.1)), SOFT, priority=1)))
    ps = particles.discretise(ok, 4)
    inside_b = ps.X[:, 0] > 0.5 - 1e-9  # the common boundary goes to the higher priority
    assert np.all(ps.region[inside_b] == 1) and np.all(ps.region[~inside_b] == 0)
    assert np.all(ps.rho[inside_b] == 1000.0) and np.all(ps.rho[~inside_b] == 7800.0)


# --- volumes and the discrete divergence theorem ------------------------------------------------

boxes_2d = st.lists(st.tuples(st.integers(0, 6), st.integers(0, 6), st.integers(1, 4),
                              st.integers(1, 4)), min_size=1, max_size=4)


@settings(max_examples=25, deadline=None)
@given(boxes=boxes_2d, mode=st.sampled_from(["node", "cell"]))
def test_union_of_lattice_aligned_boxes_is_integrated_exactly(boxes, mode):
    """For any union of boxes on the lattice: Σ V is the union's area (counted independently on
    the unit cells), and on the node lattice Σ_c X_c ⊗ n_c = Σ V · I and Σ n_c = 0 (the discrete
    divergence theorem the integration-consistent correction relies on)."""
    dx = 0.25
    shapes = [Box((x * dx, y * dx), ((x + w) * dx, (y + h) * dx)) for x, y, w, h in boxes]
    model = M.Model(dim=2, length=dx, drive=M.Modal(),
                    regions=tuple(M.Region(f"r{k}", s, STEEL, priority=k) for k, s in enumerate(shapes)))
    ps = particles.discretise(model, 1, mode)
    cells = {(i, j) for x, y, w, h in boxes for i in range(x, x + w) for j in range(y, y + h)}
    area = len(cells) * dx * dx
    if mode == "cell":
        assert ps.V.sum() == pytest.approx(area, rel=1e-12)
        assert ps.n == len(cells)
        return
    assert ps.V.sum() == pytest.approx(area, rel=1e-12)
    assert np.abs(ps.normals.sum(axis=0)).max() < 1e-12
    div = np.einsum("ci,cj->ij", ps.X, ps.normals)
    assert np.allclose(div, area * np.eye(2), rtol=0, atol=1e-12)


def test_probe_reproduces_linear_fields_on_both_lattices():
    rng = np.random.default_rng(0)
    A, c = rng.standard_normal((3, 3)), rng.standard_normal(3)
    for mode in ("node", "cell"):
        for p in [(0.3, 0.05, 0.02), (1.0, 0.1, 0.1), (0.0, 0.0, 0.0), (0.55, 0.031, 0.077)]:
            model = M.Model(dim=3, plane=None, length=0.1, drive=M.Modal(),
                            regions=(M.Region("a", Box((0, 0, 0), (1.0, 0.1, 0.1)), STEEL),),
                            sets=(M.Set("p", Point(p)),))
            ps = particles.discretise(model, 3, mode)
            idx, w = ps.probes["p"]
            assert w.sum() == pytest.approx(1.0, abs=1e-14)
            f = ps.X @ A.T + c
            assert np.allclose(w @ f[idx], np.asarray(p) @ A.T + c, rtol=0, atol=1e-12)


def test_concentric_annulus_and_voronoi_regions():
    """An annulus on concentric circles has the annulus's area to O((Δr/R)²) of the polygon sides
    (exactly, by construction of the volumes: 2πrΔr per layer) and boundary area vectors that close
    (Σ n = 0); Voronoi cells partition a block: every particle in exactly one grain."""
    ring = M.Model(dim=2, length=0.1, drive=M.Modal(),
                   regions=(M.Region("r", Cylinder((0, 0), 0.2, inner=0.1), SOFT, arrangement="concentric"),))
    ps = particles.discretise(ring, 10)
    assert ps.V.sum() == pytest.approx(np.pi * (0.2 ** 2 - 0.1 ** 2), rel=1e-12)
    assert np.abs(ps.normals.sum(axis=0)).max() < 1e-12
    seeds = np.random.default_rng(1).uniform(0, 1, (5, 2))
    block = Box((0, 0), (1.0, 1.0))
    grains = tuple(M.Region(f"g{k}", VoronoiCell(seeds, k, block), STEEL) for k in range(5))
    ps = particles.discretise(M.Model(dim=2, length=1.0, drive=M.Modal(), regions=grains), 10)
    near = np.argmin(((ps.X[:, None, :] - seeds[None]) ** 2).sum(-1), axis=1)
    assert np.array_equal(ps.region, near)
    assert ps.V.sum() == pytest.approx(1.0, rel=1e-12)
