"""Cluster tree, block partition and cross approximation of qsa.linalg.hierarchical."""

import numpy as np
import pytest

from qsa.linalg.hierarchical import aca, block_partition, cluster_tree, hierarchical_matrix


def _points(n, seed=0):
    return np.random.default_rng(seed).random((n, 2))


def _gauss(pts, scale=0.1):
    return lambda r, c: np.exp(-np.sum((pts[r] - pts[c]) ** 2, axis=-1) / scale)


def test_tree_clusters_are_nested_boxes():
    pts = _points(500)
    t = cluster_tree(pts, 20)
    for k in range(len(t.start)):
        p = pts[t.indices(k)]
        assert np.all(p >= t.lo[k]) and np.all(p <= t.hi[k])
        if t.is_leaf(k):
            assert 0 < t.stop[k] - t.start[k] <= 20
        else:
            a, b = t.children[k]
            assert (t.start[a], t.stop[a], t.stop[b]) == (t.start[k], t.start[b], t.stop[k])


@pytest.mark.parametrize("cutoff", [np.inf, 0.3])
def test_partition_covers_each_pair_within_cutoff_once(cutoff):
    pts = _points(400, 1)
    part = block_partition(cluster_tree(pts, 16), eta=1.0, cutoff=cutoff)
    t = part.tree
    seen = np.zeros((400, 400), dtype=int)
    np.add.at(seen, (part.near_rows, part.near_cols), 1)
    np.add.at(seen, (part.near_cols, part.near_rows), 1)
    for s, u in part.far:
        assert t.gap(s, u) >= max(t.radius[s], t.radius[u]) and t.gap(s, u) <= cutoff
        I, J = t.indices(s), t.indices(u)
        seen[np.ix_(I, J)] += 1
        seen[np.ix_(J, I)] += 1
    dist = np.hypot(*(pts[:, None] - pts[None]).T)
    inside = (dist <= cutoff) & ~np.eye(400, dtype=bool)
    assert np.all(seen[inside] == 1)
    # far blocks may hold pairs beyond the cutoff; near pairs never do
    assert np.all(dist[part.near_rows, part.near_cols] <= cutoff)
    assert len(part.far) > 0


def test_aca_reaches_tolerance_on_smooth_block():
    x, y = np.linspace(0, 1, 60), np.linspace(2, 3, 50)
    S = np.exp(-((x[:, None] - y[None]) ** 2))
    for tol in (1e-4, 1e-8, 1e-12):
        U, V = aca(lambda i: S[i], lambda j: S[:, j], 60, 50, tol)
        assert np.linalg.norm(S - U @ V.T) <= 10 * tol * np.linalg.norm(S)


def test_aca_zero_block_has_rank_zero():
    U, V = aca(lambda i: np.zeros(7), lambda j: np.zeros(5), 5, 7, 1e-8)
    assert U.shape == (5, 0) and V.shape == (7, 0)


@pytest.mark.parametrize("symmetry", [1, -1])
@pytest.mark.parametrize("tol", [1e-6, 1e-11])
def test_matrix_matches_dense_and_estimate(symmetry, tol):
    pts = _points(500, 2)
    g = _gauss(pts, 0.02)  # exp(-32) at the cutoff: below tol
    f = g if symmetry == 1 else (lambda r, c: g(r, c) * (pts[r, 0] - pts[c, 0]))
    part = block_partition(cluster_tree(pts, 24), cutoff=0.8)
    G = hierarchical_matrix(part, f, symmetry=symmetry, tol=tol)
    n = np.arange(500)
    D = np.where(part.within_cutoff(n[:, None], n[None]), f(n[:, None], n[None]), 0.0)
    np.fill_diagonal(D, 0.0)
    err = np.linalg.norm(G.toarray() - D) / np.linalg.norm(D)
    assert err <= 10 * tol
    assert G.relative_error_estimate <= tol
    assert G.norm_estimate == pytest.approx(np.linalg.norm(D), rel=0.05)
    V = np.random.default_rng(3).standard_normal((500, 4))
    assert np.linalg.norm(G @ V - D @ V) <= 10 * tol * np.linalg.norm(D @ V)
    assert np.allclose(G @ V[:, 0], (G @ V)[:, 0], rtol=1e-14, atol=0)


def test_isolated_entry_in_a_far_block_is_kept():
    pts = _points(300, 4)
    g = _gauss(pts, 0.5)
    part = block_partition(cluster_tree(pts, 16))
    s, t = part.far[np.argmax([part.tree.radius[a] for a, _ in part.far])]
    I, J = part.tree.indices(s), part.tree.indices(t)
    r0, c0 = I[3], J[5]
    spike = lambda r, c: g(r, c) + 1e-4 * ((r == r0) & (c == c0) | (r == c0) & (c == r0))
    # an isolated entry on top of a smooth block: found by the crosses or by the
    # check (sampling every entry), which continues the crosses from its row
    G = hierarchical_matrix(part, spike, tol=1e-10, n_samples=10**9)
    n = np.arange(300)
    D = spike(n[:, None], n[None])
    np.fill_diagonal(D, 0.0)
    assert np.linalg.norm(G.toarray() - D) <= 1e-9 * np.linalg.norm(D)


def test_bad_input():
    pts = _points(50)
    part = block_partition(cluster_tree(pts, 8))
    with pytest.raises(ValueError, match="points"):
        cluster_tree(pts[:, :1])
    with pytest.raises(ValueError, match="leaf_size"):
        cluster_tree(pts, 0)
    with pytest.raises(ValueError, match="eta"):
        block_partition(part.tree, eta=0.0)
    with pytest.raises(ValueError, match="cutoff"):
        block_partition(part.tree, cutoff=-1.0)
    with pytest.raises(ValueError, match="symmetry"):
        hierarchical_matrix(part, _gauss(pts), symmetry=0)
    with pytest.raises(ValueError, match="tol"):
        hierarchical_matrix(part, _gauss(pts), tol=0.0)
