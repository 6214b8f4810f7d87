"""The penalty contact of sph.contact on mirror-symmetry planes: the pair weight in closed form, and
a model cut by the planes against the mirrored whole (contact forces and energy exact)."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sph.contact import contact_forces, mirror_planes, pair_weight

RC, K = 0.01, 2.0e9


def _pair(planes, on_a, on_b, gap=0.004):
    """Two particles of different bodies, 2-D, b above a at r = gap < r_c, both at x = 0 (on the
    plane x = 0 where ``on_a``/``on_b`` say so: the bit mask of each)."""
    x = np.array([[0.0, 0.0], [0.0, gap]])
    body = np.array([0, 1])
    return contact_forces(x, body, RC, K, None if planes is None else np.array([on_a, on_b]))


@pytest.mark.parametrize("on_a, on_b, w", [
    (0, 0, 1.0),      # off the planes
    (1, 0, 1.0),      # one on a plane: its image pair is another pair of the whole
    (1, 1, 0.5),      # both on one plane: the pair is its own image
    (3, 1, 0.5),      # on two planes and on one: one shared plane
    (3, 3, 0.25),     # both on two planes
    (1, 2, 1.0),      # on different planes: no shared plane
])
def test_pair_weight_closed_form(on_a, on_b, w):
    """Φ = ½ w k (r_c − r)², f = w k (r_c − r) (2-D, k per unit thickness): the weight is ½ per
    plane both particles lie on (sph.contact module docstring). Exact to round-off."""
    gap = 0.004
    f, e = _pair(True, on_a, on_b, gap)
    assert pair_weight(on_a, on_b) == w
    assert f[1, 1] == pytest.approx(w * K * (RC - gap), rel=1e-14)
    assert np.array_equal(f[0], -f[1]) and f[0, 0] == 0.0
    assert e == pytest.approx(0.5 * w * K * (RC - gap) ** 2, rel=1e-14)


def test_no_planes_is_the_unweighted_contact_bit_for_bit():
    rng = np.random.default_rng(3)
    x = rng.uniform(0, 0.05, (300, 3))
    body = (x[:, 2] > 0.025).astype(np.int64)
    f0, e0 = contact_forces(x, body, RC, K)
    f1, e1 = contact_forces(x, body, RC, K, np.zeros(len(x), np.int64))
    assert e0 > 0 and np.array_equal(f0, f1) and e0 == e1


def _symmetric_pair_of_bodies(seed=11, dx=0.01, n=3):
    """A 3-D configuration symmetric in x = 0 and y = 0: two jittered lattice blocks of different
    bodies, pressed into each other (the upper one's bottom layer 0.6 Δx above the lower one's top),
    given by its quarter x ≥ 0, y ≥ 0 (particles on a plane jittered along it only, so that they
    stay on it) and mirrored. Returns the quarter (X, body, n_images) and the whole (X, body)."""
    rng = np.random.default_rng(seed)
    g = np.arange(n) * dx
    lower = np.stack(np.meshgrid(g, g, np.arange(2) * dx, indexing="ij"), -1).reshape(-1, 3)
    upper = lower + np.array([0.0, 0.0, 1.6 * dx])
    X = np.concatenate([lower, upper])
    body = np.repeat([0, 1], len(lower))
    X += 0.25 * dx * rng.uniform(-1, 1, X.shape) * (X > 0)  # keep x = 0 and y = 0 exact
    X[:, :2] = np.abs(X[:, :2])
    on = X[:, :2] == 0.0
    images = 2 ** (2 - on.sum(axis=1))  # 4 off the planes, 2 on one, 1 on both
    parts, bodies = [], []
    for sx in (1, -1):
        for sy in (1, -1):
            keep = ~(((sx < 0) & on[:, 0]) | ((sy < 0) & on[:, 1]))  # no duplicate on a plane
            parts.append(X[keep] * (sx, sy, 1))
            bodies.append(body[keep])
    return (X, body, images), (np.concatenate(parts), np.concatenate(bodies))


def test_quarter_model_gives_a_quarter_of_the_mirrored_whole():
    """The quarter of a configuration symmetric in x = 0 and y = 0, with the plane masks of
    ``mirror_planes``, against the whole (no planes): contact energy exactly a quarter; each
    particle's force along the planes it lies on is the whole's times its share (n_images/4: 1 off
    the planes, ½ on one, ¼ on both); the whole's force normal to a plane vanishes there (by
    symmetry); the total force along z a quarter. The contact distance 1.5 Δx makes pairs of every
    kind: off the planes, one or both on a plane, on the two different planes (where a weight
    from per-particle area factors — their product, minimum or maximum — is wrong). Tolerance:
    round-off of the pair sums."""
    dx = 0.01
    (Xq, bq, images), (Xf, bf) = _symmetric_pair_of_bodies(dx=dx)
    rc = 1.5 * dx
    planes = mirror_planes(Xq, [(0, 0.0, np.arange(len(Xq))), (1, 0.0, np.arange(len(Xq)))],
                           1e-9 * dx)
    assert np.array_equal(planes, (Xq[:, 0] == 0) * 1 + (Xq[:, 1] == 0) * 2)
    fq, eq = contact_forces(Xq, bq, rc, K, planes)
    ff, ef = contact_forces(Xf, bf, rc, K)
    assert ef > 0 and eq == pytest.approx(ef / 4, rel=1e-12)
    # the pairs of each kind are there
    from sph.neighbours import neighbour_list

    ip, ix = neighbour_list(Xq, rc)
    kinds = set()
    for a in range(len(Xq)):
        for b in ix[ip[a]:ip[a + 1]]:
            if bq[a] != bq[b] and np.linalg.norm(Xq[a] - Xq[b]) < rc:
                kinds.add(tuple(sorted((int(planes[a]), int(planes[b])))))
    assert {(0, 0), (0, 1), (1, 1), (1, 2), (1, 3), (3, 3)} <= kinds, kinds
    # the whole's particles by position
    key = {tuple(np.round(p / dx * 1e6).astype(np.int64)): i for i, p in enumerate(Xf)}
    idx = np.array([key[tuple(np.round(p / dx * 1e6).astype(np.int64))] for p in Xq])
    scale = np.abs(ff).max()
    for a in range(len(Xq)):
        share = images[a] / 4
        for i in range(3):
            if i < 2 and Xq[a, i] == 0.0:  # normal to a plane: the whole's force is zero there
                assert abs(ff[idx[a], i]) <= 1e-12 * scale
            else:
                assert fq[a, i] == pytest.approx(share * ff[idx[a], i], rel=1e-12,
                                                 abs=1e-12 * scale)
    assert fq[bq == 1, 2].sum() == pytest.approx(ff[bf == 1, 2].sum() / 4, rel=1e-12)


def test_mirror_planes_bits_and_refusals():
    X = np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.5, 0.0, 0.0], [0.5, 1.0, 0.0]])
    every = np.arange(4)
    # two constraints on one plane share its bit; a particle off the plane gets none
    assert np.array_equal(mirror_planes(X, [(0, 0.0, [0]), (0, 0.0, [1, 2]), (1, 0.0, every)], 1e-9),
                          [3, 1, 2, 0])
    assert mirror_planes(X, [(2, 1.0, every)], 1e-9) is None
    with pytest.raises(ValueError, match="^planes"):
        contact_forces(X, np.array([0, 0, 1, 1]), 0.1, 1.0, np.zeros(3, np.int64))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), d=st.sampled_from([2, 3]), nb=st.integers(1, 4),
       rc=st.floats(0.01, 0.5))
def test_candidates_are_the_particles_near_another_bodys_box(seed, d, nb, rc):
    """sph.contact.candidates against its definition written out with numpy: the particles within
    rc of another body's bounding box; None when that is all of them. Labels may skip values."""
    from sph.contact import candidates

    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 60))
    x = rng.uniform(0.0, 2.0, (n, d))
    body = rng.choice(np.arange(0, 2 * nb, 2), n).astype(np.int64)
    near = np.zeros(n, bool)
    for b in np.unique(body):
        mb = body == b
        lo, hi = x[mb].min(axis=0) - rc, x[mb].max(axis=0) + rc
        near |= ~mb & np.all((x >= lo) & (x <= hi), axis=1)
    got = candidates(x, body, rc)
    if near.all():
        assert got is None
    else:
        np.testing.assert_array_equal(got, np.flatnonzero(near))
