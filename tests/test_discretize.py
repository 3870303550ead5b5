import numpy as np
import pytest
import scipy.sparse as sp

from qsa import FiniteDifference, Fourier
from tests.helpers import fitted_order


def f(s):
    return np.exp(np.sin(2 * np.pi * s))


def df(s):
    return 2 * np.pi * np.cos(2 * np.pi * s) * f(s)


def d2f(s):
    return (2 * np.pi) ** 2 * (np.cos(2 * np.pi * s) ** 2 - np.sin(2 * np.pi * s)) * f(s)


def test_fd_derivatives_second_order():
    Ns = [64, 128, 256, 512]
    e1, e2, e3, ec = [], [], [], []
    for N in Ns:
        g = FiniteDifference(N)
        s = g.s
        e1.append(np.abs(g.derivative() @ f(s) - df(s)).max())
        e2.append(np.abs(g.second_derivative() @ f(s) - d2f(s)).max())
        mid = s + 0.5 / N
        e3.append(np.abs(g.edge_difference() @ f(s) - df(mid)).max())
        ec.append(np.abs(g.cumulative(df(s)) - (f(s) - f(0))).max())
    for e in (e1, e2, e3, ec):
        assert abs(fitted_order(Ns, e) - 2) < 0.2


def test_fd_operators_sparse_and_skew():
    g = FiniteDifference(32)
    D = g.derivative()
    assert sp.issparse(D) and sp.issparse(g.second_derivative())
    assert abs(D + D.T).max() == 0
    D2 = g.second_derivative()
    assert abs(D2 - D2.T).max() == 0
    # compact Laplacian from the edge pair equals the 3-point second difference
    E = g.edge_difference()
    assert abs(-(E.T @ E) - D2).max() < 1e-9 * abs(D2).max()


def test_fourier_spectral_accuracy():
    g = Fourier(41)
    s = g.s
    assert np.abs(g.derivative() @ f(s) - df(s)).max() < 1e-10
    assert np.abs(g.second_derivative() @ f(s) - d2f(s)).max() < 1e-9
    assert np.abs(g.cumulative(df(s)) - (f(s) - f(0))).max() < 1e-12
    D = g.derivative()
    assert np.abs(D + D.T).max() < 1e-12
    # cumulative of a non-zero-mean integrand keeps the linear part
    assert np.abs(g.cumulative(np.ones(41)) - s).max() < 1e-14
    x = np.array([0.123, 0.777])
    assert np.abs(g.interpolate(f(s), x) - f(x)).max() < 1e-12
    C = g.cumulative_matrix()
    assert np.allclose(C @ df(s), g.cumulative(df(s)), atol=1e-13)


def test_resample_between_grids():
    a, b = Fourier(41), Fourier(67)
    assert np.abs(a.resample(f(a.s), b) - f(b.s)).max() < 1e-12
    assert np.abs(b.resample(f(b.s), a) - f(a.s)).max() < 1e-12
    fd_a, fd_b = FiniteDifference(400), FiniteDifference(300)
    assert np.abs(fd_a.resample(f(fd_a.s), fd_b) - f(fd_b.s)).max() < 1e-6


@pytest.mark.parametrize("bad", [4, 7, 0, -3, 2.5, "10", True])
def test_too_small_or_not_integer(bad):
    with pytest.raises(ValueError, match="N"):
        FiniteDifference(bad)


def test_even_fourier_refused():
    with pytest.raises(ValueError, match="odd"):
        Fourier(64)


def test_mismatched_array_refused():
    with pytest.raises(ValueError, match="shape"):
        FiniteDifference(16).cumulative(np.ones(15))


@pytest.mark.parametrize("grid", [FiniteDifference(17), Fourier(17)], ids=["fd", "fourier"])
def test_cumulative_transpose_is_the_transpose(grid):
    V = np.random.default_rng(1).standard_normal((grid.N, 2))
    C = grid.cumulative_matrix()
    assert np.allclose(grid.cumulative_transpose(V), C.T @ V, atol=1e-14)
    assert np.allclose(grid.cumulative_transpose(V[:, 0]), C.T @ V[:, 0], atol=1e-14)
