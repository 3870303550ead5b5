import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.linalg import to_dense
from tests.helpers import exact_closure, fitted_order, inner, skew_curve, trillium


def smooth_field(grid, seed, n=2):
    rng = np.random.default_rng(seed)
    s = grid.s
    out = np.zeros((n, grid.N))
    for k in range(1, 5):
        a, b = rng.standard_normal((2, n)) / k**2
        out += a[:, None] * np.cos(2 * np.pi * k * s) + b[:, None] * np.sin(2 * np.pi * k * s)
    return out


@pytest.mark.parametrize("N, amp", [(257, 0.2), (513, 0.3)])
def test_kernels_fourier(N, amp):
    c = trillium(N, amp=amp)
    M, Md = geometry.M(c), geometry.M_adjoint(c)
    for r in geometry.rigid_motions(c):
        assert np.abs(M @ r).max() < 1e-8
    for p in geometry.constraint_gradients(c):
        assert np.abs(Md @ p).max() < 1e-8


@pytest.mark.parametrize("shape", ["trillium", "skew"])
def test_kernels_fd_order_two(shape):
    """Second order also without symmetry: the positions' closure gap must not sit at the
    seam (an O(1) defect at the last node, see ``geometry.periodic_positions``)."""
    Ns = [256, 512, 1024]
    eM, eP = [], []
    for N in Ns:
        c = (trillium(N, kind=FiniteDifference) if shape == "trillium"
             else skew_curve(FiniteDifference(N)))
        M, Md = geometry.M(c), geometry.M_adjoint(c)
        eM.append(max(np.abs(M @ r).max() for r in geometry.rigid_motions(c)))
        eP.append(max(np.abs(Md @ p).max() for p in geometry.constraint_gradients(c)))
    assert abs(fitted_order(Ns, eM) - 2) < 0.2
    assert abs(fitted_order(Ns, eP) - 2) < 0.2


@pytest.mark.parametrize("grid", [Fourier(129), FiniteDifference(128)])
def test_adjoint_and_formula(grid):
    c = skew_curve(grid)
    M, Md = geometry.M(c), geometry.M_adjoint(c)
    a = np.concatenate(smooth_field(grid, 1))
    b = np.concatenate(smooth_field(grid, 2))
    assert inner(c, M @ a, b) == pytest.approx(inner(c, a, Md @ b), rel=1e-12)
    # the continuum formula [[G, g k], [grad_s k, -grad_s(g .)]]
    N = c.N
    G = to_dense(geometry.helmholtz(c))
    gs = to_dense(geometry.grad_s(c))
    ks = c.grad_s(c.kappa)
    ref = np.block([[G, np.diag(c.g * c.kappa)], [np.diag(ks), -gs @ np.diag(c.g)]])
    assert np.abs(to_dense(Md) - ref).max() < 1e-10 * np.abs(ref).max()
    MM = to_dense(geometry.MMdagger(c))
    assert np.allclose(MM, to_dense(M) @ to_dense(Md))
    W = np.concatenate([c.dsigma, c.dsigma])
    assert np.abs(W[:, None] * MM - (W[:, None] * MM).T).max() < 1e-10 * np.abs(MM).max()
    assert N == grid.N


def test_periodic_positions_spread_the_closure_gap():
    c = skew_curve(FiniteDifference(64))
    gap = c.closure()[:2]
    assert np.abs(gap).max() > 1e-6  # FD positions do not close exactly
    P = geometry.periodic_positions(c)
    np.testing.assert_allclose(P, c.positions() - np.outer(gap, c.grid.s), atol=1e-15)
    np.testing.assert_array_equal(P[:, 0], c.origin)


def test_range_of_M_orthogonal_to_Psi():
    c = skew_curve(Fourier(257))
    M = geometry.M(c)
    for seed in range(3):
        V = np.concatenate(smooth_field(c.grid, seed))
        MV = M @ V
        for p in geometry.constraint_gradients(c):
            assert abs(inner(c, MV, p)) < 1e-9 * np.sqrt(inner(c, MV, MV) * inner(c, p, p))


def _reference():
    ref = skew_curve(Fourier(255))
    kfun = lambda s: ref.grid.interpolate(ref.kappa, s)
    return ref, kfun


def _perturbation(tangent_to_C3=False):
    k1 = lambda s: 0.3 * np.cos(2 * np.pi * s) + 0.2 * np.sin(6 * np.pi * s)
    g1 = lambda s: 0.4 * np.sin(4 * np.pi * s + 0.2) + 0.1 + 0.2 * np.cos(2 * np.pi * s)
    return k1, g1


def test_Psi_is_constraint_gradient():
    """<Psi, U1> = d/d delta C(U + delta U1): spectral on Fourier, order 2 on FD."""
    ref, kfun = _reference()
    L = ref.length()
    k1, g1 = _perturbation()
    d = 1e-5
    dC = (exact_closure(lambda s: kfun(s) + d * k1(s), lambda s: L + d * g1(s), ref.theta0)
          - exact_closure(lambda s: kfun(s) - d * k1(s), lambda s: L - d * g1(s), ref.theta0)
          ) / (2 * d)
    errs, Ns = [], [128, 256, 512]
    for grid in [Fourier(255)] + [FiniteDifference(N) for N in Ns]:
        c = Curve(kfun(grid.s), L, grid, ref.theta0, ref.origin)
        U1 = np.concatenate([k1(grid.s), g1(grid.s)])
        got = np.array([inner(c, p, U1) for p in geometry.constraint_gradients(c)])
        if grid.sparse:
            errs.append(np.abs(got - dC).max())
        else:
            assert np.abs(got - dC).max() < 1e-8
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


def test_constraint_hessians_second_differences():
    ref, kfun = _reference()
    L = ref.length()
    k1, g1 = _perturbation()
    d = 1e-3

    def C(t):
        return exact_closure(lambda s: kfun(s) + t * k1(s), lambda s: L + t * g1(s), ref.theta0)

    # fourth-order accurate second difference
    d2C = (-C(2 * d) + 16 * C(d) - 30 * C(0) + 16 * C(-d) - C(-2 * d)) / (12 * d**2)
    Ns = [128, 256, 512]
    errs = []
    for N in Ns:
        grid = FiniteDifference(N)
        c = Curve(kfun(grid.s), L, grid, ref.theta0, ref.origin)
        U1 = np.concatenate([k1(grid.s), g1(grid.s)])
        got = np.array([inner(c, to_dense(H) @ U1, U1) for H in geometry.constraint_hessians(c)])
        errs.append(np.abs(got - d2C).max())
    assert errs[-1] < 1e-3 * np.abs(d2C).max()
    assert abs(fitted_order(Ns, errs) - 2) < 0.25
    # H_C3 is exact: 2 int kappa1 g1 ds
    assert d2C[2] == pytest.approx(2 * np.mean(k1(grid.s) * g1(grid.s)), rel=1e-6)
    assert abs(got[2] - d2C[2]) < 1e-6 * abs(d2C[2])


def test_constraint_hessians_fourier_second_order():
    """B and D eta jump across s = 0 == 1, so Fourier grids are second order here too."""
    ref, kfun = _reference()
    L = ref.length()
    k1, g1 = _perturbation()
    d = 1e-3

    def C(t):
        return exact_closure(lambda s: kfun(s) + t * k1(s), lambda s: L + t * g1(s), ref.theta0)

    d2C = (-C(2 * d) + 16 * C(d) - 30 * C(0) + 16 * C(-d) - C(-2 * d)) / (12 * d**2)
    Ns = [127, 255, 511]
    errs = []
    for N in Ns:
        grid = Fourier(N)
        c = Curve(kfun(grid.s), L, grid, ref.theta0, ref.origin)
        U1 = np.concatenate([k1(grid.s), g1(grid.s)])
        got = np.array([inner(c, to_dense(H) @ U1, U1) for H in geometry.constraint_hessians(c)])
        errs.append(np.abs(got - d2C).max())
    assert abs(fitted_order(Ns, errs) - 2) < 0.25


def test_reparameterization_mode_is_M_of_tangential_field():
    c = skew_curve(Fourier(65))
    v = smooth_field(c.grid, 5, n=1)[0]
    lhs = geometry.M(c) @ np.concatenate([np.zeros(c.N), v])
    assert np.allclose(lhs, geometry.reparameterization_mode(c, v), atol=1e-12)
