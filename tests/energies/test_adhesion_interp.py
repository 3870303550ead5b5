"""The adhesion pair Hessian by panel interpolation against the assembled one."""

import numpy as np
import pytest

from qsa import Curve, FiniteDifference
from qsa.energies.adhesion import AdhesionKernel, adhesion_pairs
from qsa.energies.adhesion_hessian import adhesion_derivatives
from qsa.energies.adhesion_interp import (
    interpolated_pair_hessian,
    interpolated_reduced_hessian,
)


def _row_error(Ka, K, N):
    """Largest relative error of the three rows (x_r, y_r, w_r) of each node."""
    rows = lambda A: sum((A[a * N:(a + 1) * N] ** 2).sum(axis=1) for a in range(3))
    return float(np.max(np.sqrt(rows(Ka - K) / rows(K))))


def _folded(N):
    """A smooth curve with two tight folds (radius of curvature ~ 0.03)."""
    t = 2 * np.pi * np.arange(N) / N
    r = 1.0 + 0.55 * np.tanh(6 * np.cos(2 * t))
    return Curve.from_positions(r * np.cos(t), 0.6 * r * np.sin(t), FiniteDifference(N))


_smooth = lambda N: Curve.polar(lambda t: 1 + 0.2 * np.cos(5 * t), FiniteDifference(N))

# (curve(N), kernel, N, options, compressed): at N the panels of the first two hold enough
# nodes to pick interpolation points from (M < N); the folded one keeps every node
CASES = {
    "smooth, l* = 0.5": (_smooth, AdhesionKernel(10.0, 0.5, 1.0), 1600, {}, True),
    "smooth, l* = 0.3": (_smooth, AdhesionKernel(10.0, 0.3, 1.0), 1200,
                         {"degrees": 10, "tol": 1e-8}, True),
    "folds, l* = 0.2": (_folded, AdhesionKernel(40.0, 0.2, 1.0), 600,
                        {"degrees": 8, "tol": 1e-7}, False),
}


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    make, k, N, kw, compressed = CASES[request.param]
    c = make(N)
    H = interpolated_pair_hessian(k, c, **kw)
    d = adhesion_derivatives(k, c, adhesion_pairs(k, *c.positions()))
    assert (H.M < N) == compressed
    return c, k, H, d, kw


def test_compressed_pair_hessian_matches_the_assembled_one(case):
    c, k, H, d, kw = case
    N, tol = c.N, kw.get("tol", 1e-10)
    K = d.pair_hessian().toarray()
    Ka = H.toarray()
    err = _row_error(Ka, K, N)
    assert err <= 10 * tol
    # the sampled estimate is honest: within a factor 10 of the true largest row error
    assert err / 10 <= max(H.error_estimate, 1e-15) and H.error_estimate <= err * (1 + 1e-12)
    V = np.random.default_rng(1).standard_normal((3 * N, 4))
    assert np.allclose(H @ V, Ka @ V, rtol=0, atol=1e-12 * np.abs(Ka @ V).max())
    assert np.allclose(H @ V[:, 0], Ka @ V[:, 0], rtol=0, atol=1e-12 * np.abs(Ka @ V).max())
    # the node-diagonal 3 x 3 blocks are exact, and so are the fields
    n = np.arange(N)
    for a in range(3):
        for b in range(3):
            assert np.allclose(Ka[a * N + n, b * N + n], K[a * N + n, b * N + n], rtol=1e-12,
                               atol=1e-12 * np.abs(K).max())
    assert np.allclose(H.F, d.F, rtol=1e-12, atol=1e-12 * np.abs(d.F).max())
    assert np.allclose(H.Bw, d.B, rtol=1e-12)


def test_coarse_matrix_is_exactly_symmetric(case):
    H = case[2]
    assert H.C.shape == (H.rank, H.rank) and H.rank == 3 * H.M
    assert abs(H.C - H.C.T).max() == 0.0
    assert H.Pi[H.nodes, np.arange(H.M)].min() == 1.0


def test_reduced_hessian_matches_the_exact_one(case):
    c, k, H, d, kw = case
    R = interpolated_reduced_hessian(c, H)
    exact = d.reduced_hessian()
    tol = kw.get("tol", 1e-10)
    v = np.random.default_rng(2).standard_normal((2 * c.N, 6))
    Rv, Ev = R @ v, exact @ v
    assert np.linalg.norm(Rv - Ev) <= 30 * tol * np.linalg.norm(Ev)
    if c.N <= 800:  # assembled: the factored form is the matrix
        Ha, He = R.toarray(), exact.toarray()
        assert np.linalg.norm(Ha - He) <= 30 * tol * np.linalg.norm(He)
        assert np.allclose(Rv, Ha @ v, rtol=1e-9, atol=1e-9 * np.abs(Ha @ v).max())
    # the extended state equations stay lower triangular
    cY = R.cY.tocoo()
    assert np.all(cY.col <= cY.row)


def test_rank_independent_of_N():
    k = AdhesionKernel(10.0, 0.5, 1.0)
    M = [interpolated_pair_hessian(k, _smooth(N), samples=8).M for N in (3200, 6400)]
    assert M[0] == M[1] < 1000


def test_too_loose_a_build_is_flagged():
    k = AdhesionKernel(10.0, 0.5, 1.0)
    c = Curve.polar(lambda t: 1 + 0.2 * np.cos(5 * t), FiniteDifference(800))
    with pytest.warns(RuntimeWarning, match="sampled relative error"):  # below round-off
        H = interpolated_pair_hessian(k, c, tol=1e-17, attempts=1)
    assert H.error_estimate > 1e-17


def test_bad_arguments():
    k = AdhesionKernel(10.0, 0.5, 1.0)
    c = Curve.circle(1.0, FiniteDifference(64))
    with pytest.raises(ValueError, match="tol"):
        interpolated_pair_hessian(k, c, tol=0.0)
    with pytest.raises(ValueError, match="degrees"):
        interpolated_pair_hessian(k, c, degrees=(1, 8))
    H = interpolated_pair_hessian(k, c)
    with pytest.raises(ValueError, match="V has shape"):
        H @ np.ones(5)
    with pytest.raises(ValueError, match="N = 64"):
        interpolated_reduced_hessian(Curve.circle(1.0, FiniteDifference(32)), H)
