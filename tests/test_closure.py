"""The closure constraints' Hessians in factored form (qsa.closure).

The factored form is the dense matrix exactly; it is second order against exact second
differences of the closure at large N (where the dense form would not fit), and on the
tangent space of the closed manifold (range M) it is the derivative of the constraint
gradients Psi the multipliers are computed with.
"""

import numpy as np
import pytest
import scipy.sparse as sp

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.closure import closure_hessian
from qsa.linalg import ReducedHessian, to_dense
from tests.helpers import exact_closure, fitted_order, inner, skew_curve


def generic(grid):
    """A curve off the closed manifold (kappa perturbed), so that D eta jumps at the seam."""
    c = skew_curve(grid)
    return c.with_kappa(c.kappa * (1 + 0.05 * np.cos(2 * np.pi * c.grid.s + 0.4)))


@pytest.mark.parametrize("lam", [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.3, -0.7, 0.2)])
def test_factored_is_the_dense_matrix(lam):
    c = generic(FiniteDifference(96))
    Hf = closure_hessian(c, lam, form="factored")
    Hd = closure_hessian(c, lam, form="dense")
    assert isinstance(Hf, ReducedHessian) and isinstance(Hd, np.ndarray)
    assert np.abs(Hf.toarray() - Hd).max() < 1e-13 * np.abs(Hd).max()
    Hs = geometry.constraint_hessians(c)
    ref = sum(l * to_dense(H) for l, H in zip(lam, Hs, strict=False))
    assert np.abs(Hd - ref).max() < 1e-13 * np.abs(ref).max()
    W = np.concatenate([c.dsigma, c.dsigma])[:, None] * Hd
    assert np.abs(W - W.T).max() < 1e-13 * np.abs(W).max()  # dsigma-self-adjoint


def test_factored_storage_is_linear_in_N():
    sizes = [closure_hessian(generic(FiniteDifference(N)), (0.4, 0.1, 0.0)).nbytes
             for N in (2000, 4000)]
    assert 1.8 < sizes[1] / sizes[0] < 2.2


def test_no_translation_multipliers_gives_a_sparse_matrix():
    c = generic(FiniteDifference(64))
    H = closure_hessian(c, (0.0, 0.0, 2.0))
    assert sp.issparse(H)
    assert np.allclose(H.toarray(), 2 * geometry.constraint_hessians(c)[2].toarray())


def test_second_differences_of_the_closure_at_large_N():
    """Order 2 at N up to 4096 against fourth-order second differences of the exact closure."""
    ref = skew_curve(Fourier(255))
    kfun = lambda s: ref.grid.interpolate(ref.kappa, s)
    L = ref.length()
    k1 = lambda s: 0.3 * np.cos(2 * np.pi * s) + 0.2 * np.sin(6 * np.pi * s)
    g1 = lambda s: 0.4 * np.sin(4 * np.pi * s + 0.2) + 0.1 + 0.2 * np.cos(2 * np.pi * s)
    C = lambda t: exact_closure(lambda s: kfun(s) + t * k1(s), lambda s: L + t * g1(s),
                                ref.theta0)
    d = 1e-3
    d2C = (-C(2 * d) + 16 * C(d) - 30 * C(0) + 16 * C(-d) - C(-2 * d)) / (12 * d**2)
    Ns, errs = [1024, 2048, 4096], []
    lam = np.array([0.6, -0.8, 0.0])
    for N in Ns:
        grid = FiniteDifference(N)
        c = Curve(kfun(grid.s), L, grid, ref.theta0, ref.origin)
        U1 = np.concatenate([k1(grid.s), g1(grid.s)])
        H = closure_hessian(c, lam, form="factored")
        errs.append(abs(inner(c, H @ U1, U1) - lam @ d2C))
    assert errs[-1] < 1e-5 * np.abs(d2C).max()
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


@pytest.mark.parametrize("kind", ["fd", "fourier"])
def test_derivative_of_Psi_on_the_tangent_space(kind):
    """``H U1 = d Psi[U1] + (g1/g) Psi`` for ``U1 = M V`` (tangent to C = 0).

    ``W Psi`` is the Euclidean gradient, so its derivative is ``W H``; Psi's position form
    is the gradient of C on closed curves, and along range M the curve stays closed to
    first order. Second order on finite differences (max norm), and on Fourier grids the
    seam's mean value makes the column second order too while the quadratic form is exact.
    """
    Ns = [512, 1024, 2048] if kind == "fd" else [255]
    errs = []
    for N in Ns:
        grid = FiniteDifference(N) if kind == "fd" else Fourier(N)
        c = skew_curve(grid)
        s = grid.s
        V = np.concatenate([0.3 * np.cos(2 * np.pi * s) + 0.2 * np.sin(6 * np.pi * s),
                            0.4 * np.sin(4 * np.pi * s + 0.2) + 0.2 * np.cos(2 * np.pi * s)])
        U1 = geometry.M(c) @ V
        d = 1e-5
        Psi = lambda t: geometry.constraint_gradients(c.with_U(c.U + t * U1))
        g1g = np.concatenate([U1[N:] / c.g] * 2)
        col = (Psi(d) - Psi(-d)) / (2 * d) + g1g[None, :] * Psi(0)
        err = 0.0
        for j in range(2):
            HU = closure_hessian(c, np.eye(3)[j]) @ U1
            err = max(err, np.abs(HU - col[j]).max() / np.abs(HU).max())
            if kind == "fourier":
                assert abs(inner(c, HU, U1) - inner(c, col[j], U1)) < 1e-9 * abs(inner(c, HU, U1))
        errs.append(err)
    if kind == "fd":
        assert errs[-1] < 3e-5
        assert abs(fitted_order(Ns, errs) - 2) < 0.2
    else:
        assert errs[0] < 1e-3


def test_bad_input():
    c = generic(FiniteDifference(32))
    with pytest.raises(ValueError, match="weights"):
        closure_hessian(c, (1.0, 2.0))
    with pytest.raises(ValueError, match="weights"):
        closure_hessian(c, (np.nan, 0.0, 0.0))
    with pytest.raises(ValueError, match="form"):
        closure_hessian(c, (1.0, 0.0, 0.0), form="sparse")
    with pytest.raises(ValueError, match="finite-difference"):
        closure_hessian(skew_curve(Fourier(33)), (1.0, 0.0, 0.0), form="factored")
    with pytest.raises(ValueError, match="form"):
        geometry.constraint_hessians(c, form="reduced")
