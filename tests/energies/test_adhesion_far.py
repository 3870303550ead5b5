"""The adhesion pair Hessian in hierarchical form against the assembled sparse blocks."""

from dataclasses import replace

import numpy as np
import pytest

from qsa import Curve, FiniteDifference
from qsa.energies.adhesion import AdhesionKernel, adhesion_pairs
from qsa.energies.adhesion_far import PAIR_BLOCKS, hierarchical_pair_hessian
from qsa.energies.adhesion_hessian import _PairPattern, adhesion_derivatives
from qsa.linalg.hierarchical import hierarchical_matrix
from qsa.paper.scenarios import CHAScenario


def _smooth_curve(N, seed):
    rng = np.random.default_rng(seed)
    a, b = 0.08 * rng.standard_normal(6), rng.uniform(0, 2 * np.pi, 6)
    r = lambda t: 1 + sum(a[k] * np.cos((k + 2) * t + b[k]) for k in range(6))
    return Curve.polar(r, FiniteDifference(N))


def _crenellated(N):
    sc = CHAScenario()
    c = Curve.from_positions(*sc.initial(N), FiniteDifference(N))
    return c, AdhesionKernel(sc.A0, sc.l_star, sc.a)


def _exact(k, c):
    d = adhesion_derivatives(k, c, adhesion_pairs(k, *c.positions()))
    pat = _PairPattern(d.i.astype(np.int32), d.j.astype(np.int32), c.N)
    blocks = {name: pat.csr(v) for name, v in d._block_values().items()}
    return d.pair_hessian(), blocks


def _rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


CASES = [("smooth", 300, 0.3, 16), ("smooth", 800, 0.2, 32), ("crenellated", 1200, 0.1, 64)]


@pytest.mark.parametrize("tol", [1e-6, 1e-10])
@pytest.mark.parametrize("case", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_products_match_assembled_blocks(case, tol):
    kind, N, l_star, leaf = case
    if kind == "smooth":
        c, k = _smooth_curve(N, N), AdhesionKernel(10.0, l_star, 1.0)
    else:
        c, k = _crenellated(N)
    H = hierarchical_pair_hessian(k, *c.positions(), c.dsigma, tol=tol, leaf_size=leaf)
    assert len(H.partition.far) > 10 and H.partition.n_far_entries > N * N / 20
    K, blocks = _exact(k, c)
    rng = np.random.default_rng(1)
    V = rng.standard_normal((3 * N, 4))
    assert _rel(H @ V, K @ V) <= 10 * tol
    assert _rel(H @ V[:, 1], K @ V[:, 1]) <= 10 * tol
    W = rng.standard_normal((N, 3))
    for name in PAIR_BLOCKS:
        assert _rel(H.block_matvec(name, W), blocks[name] @ W) <= 10 * tol, name
        assert _rel(H.diagonals[name], blocks[name].diagonal()) <= 10 * tol, name
    assert max(H.error_estimates.values()) <= tol
    assert H.nbytes > 0 and H.near_nnz > 0 and H.far_factor_entries > 0


def test_translations_are_exact_null_vectors():
    c, k = _smooth_curve(400, 7), AdhesionKernel(10.0, 0.3, 1.0)
    H = hierarchical_pair_hessian(k, *c.positions(), c.dsigma, tol=1e-6, leaf_size=16)
    one, zero = np.ones(400), np.zeros(400)
    for t in (np.concatenate([one, zero, zero]), np.concatenate([zero, one, zero])):
        KT = H @ t
        scale = np.abs(H.diagonals["xx"]).max()
        assert np.abs(KT[:800]).max() <= 1e-13 * scale  # K_XX 1 = 0 whatever the tolerance


def test_symmetric_operator():
    c, k = _smooth_curve(300, 3), AdhesionKernel(10.0, 0.3, 1.0)
    H = hierarchical_pair_hessian(k, *c.positions(), c.dsigma, tol=1e-8, leaf_size=16)
    M = H @ np.eye(900)
    assert np.abs(M - M.T).max() <= 1e-13 * np.abs(M).max()


@pytest.mark.parametrize("corruption", ["drop a far block", "transpose mirror blocks"])
def test_comparison_detects_a_wrong_far_field(corruption):
    c, k = _smooth_curve(300, 300), AdhesionKernel(10.0, 0.3, 1.0)
    H = hierarchical_pair_hessian(k, *c.positions(), c.dsigma, tol=1e-10, leaf_size=16)
    K, _ = _exact(k, c)
    V = np.random.default_rng(2).standard_normal((900, 4))
    assert _rel(H @ V, K @ V) <= 1e-9
    part, x, y = H.partition, *c.positions()
    f = lambda r, cc: 4.0 * k.derivatives((x[r] - x[cc]) ** 2 + (y[r] - y[cc]) ** 2)[1] * (
        x[r] - x[cc])
    if corruption == "drop a far block":
        big = np.argmax([part.tree.radius[s] for s, _ in part.far])
        part = replace(part, far=np.delete(part.far, big, axis=0))
        Gx = hierarchical_matrix(part, f, symmetry=-1, tol=1e-10)
    else:  # (t, s) blocks as the transposes of (s, t), without the antisymmetry's sign
        Gx = hierarchical_matrix(part, f, symmetry=1, tol=1e-10)
        Gx = replace(Gx, near=H.G["x"].near)
    bad = replace(H, G={**H.G, "x": Gx})
    assert _rel(bad @ V, K @ V) > 1e-6


def test_bad_input():
    c, k = _smooth_curve(64, 0), AdhesionKernel(10.0, 0.3, 1.0)
    x, y = c.positions()
    with pytest.raises(ValueError, match="x, y, w"):
        hierarchical_pair_hessian(k, x, y[:-1], c.dsigma)
    H = hierarchical_pair_hessian(k, x, y, c.dsigma, leaf_size=16)
    with pytest.raises(ValueError, match="name"):
        H.block_matvec("wx", np.ones(64))
    with pytest.raises(ValueError, match="V has shape"):
        H.block_matvec("xx", np.ones(63))
    with pytest.raises(ValueError, match="V has shape"):
        H @ np.ones(64)


def test_single_leaf_is_the_exact_sparse_matrix():
    c, k = _smooth_curve(40, 5), AdhesionKernel(10.0, 0.3, 1.0)
    H = hierarchical_pair_hessian(k, *c.positions(), c.dsigma)
    assert len(H.partition.far) == 0 and H.far_factor_entries == 0
    K, _ = _exact(k, c)
    V = np.random.default_rng(4).standard_normal((120, 2))
    assert np.allclose(H @ V, K @ V, rtol=0, atol=1e-13 * np.abs(K).max())
