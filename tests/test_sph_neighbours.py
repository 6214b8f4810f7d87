"""The cell-list neighbour search equals a brute-force search (random clouds, a lattice with
pairs at exactly the cut-off, 2-D and 3-D), and is symmetric."""
import numpy as np
import pytest

from sph import particles
from sph.neighbours import brute_force, neighbour_list


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("radius", [0.05, 0.13, 0.4])
def test_random_cloud_equals_brute_force(dim, radius):
    x = np.random.default_rng(dim).random((700, dim)) * np.array([1.0, 0.5, 0.3][:dim])
    p1, i1 = neighbour_list(x, radius)
    p2, i2 = brute_force(x, radius)
    assert np.array_equal(p1, p2) and np.array_equal(i1, i2)


@pytest.mark.parametrize("dim", [2, 3])
def test_lattice_with_ties_and_symmetry(dim):
    X, _ = particles.box((0,) * dim, (1,) * dim, 0.125, "node")
    for radius in (0.25, 0.26, 0.125 * 2.2):  # 0.25 = 2Δx exactly: strict '<' excludes it
        p1, i1 = neighbour_list(X, radius)
        p2, i2 = brute_force(X, radius)
        assert np.array_equal(p1, p2) and np.array_equal(i1, i2)
    a = np.repeat(np.arange(len(X)), np.diff(p1))
    pairs = set(zip(a.tolist(), i1.tolist()))
    assert all((b, c) in pairs for c, b in pairs)


def test_bad_input():
    with pytest.raises(ValueError, match="radius"):
        neighbour_list(np.zeros((3, 2)), 0.0)


def test_reverse_pairs_point_at_the_mirrored_pair():
    """rev maps the pair (a, b) of a's row to (b, a) in b's row: the brute-force pair list says
    which index that is."""
    from sph.neighbours import reverse_pairs

    X = np.random.default_rng(4).random((300, 3))
    ip, ix = neighbour_list(X, 0.2)
    rev = reverse_pairs(ip, ix)
    a = np.repeat(np.arange(len(X)), np.diff(ip))
    assert np.array_equal(ix[rev], a) and np.array_equal(a[rev], ix)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_body_labels_split_the_list(dim):
    """With ``body`` labels, pairs of different bodies are not neighbours (brute force with the
    same rule), and the rows stay sorted."""
    rng = np.random.default_rng(10 + dim)
    x = rng.random((500, dim))
    body = rng.integers(0, 3, len(x))
    p1, i1 = neighbour_list(x, 0.15, body)
    p2, i2 = brute_force(x, 0.15, body)
    assert np.array_equal(p1, p2) and np.array_equal(i1, i2)
    with pytest.raises(ValueError, match="body"):
        neighbour_list(x, 0.15, body[:-1])


def test_max_displacement_is_the_largest_move():
    from sph.neighbours import max_displacement

    rng = np.random.default_rng(3)
    x0 = rng.random((1000, 3))
    x = x0 + 1e-3 * rng.standard_normal(x0.shape)
    assert max_displacement(x, x0) == pytest.approx(np.linalg.norm(x - x0, axis=1).max(), rel=1e-15)
