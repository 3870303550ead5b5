"""Exact gradient and Hessian of the discrete two-point energy E_A(kappa, g) (e:AdhE, e:LJ).

Central differences use the five-point stencil on the Euclidean gradient ``W G``
(``W = diag(dsigma)`` depends on g, so ``d/dd G = H V - (g1/g) G`` for the
``<.,.>`` gradient ``G``). The gradient is a sum of terms that cancel, so its
round-off is amplified by 1/step; a step that moves the nodes by 3e-3 l* keeps
truncation and round-off below 1e-8 relative.
"""

import numpy as np
import pytest
import scipy.sparse as sp

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter
from qsa.energies.adhesion import AdhesionKernel, dense_pairs
from qsa.energies.adhesion_hessian import adhesion_derivatives, cumulative_factors
from qsa.linalg import ReducedHessian, to_dense
from tests.helpers import assert_gradient_matches_energy, inner, random_curve

GRIDS = {"fourier": Fourier(101), "fd": FiniteDifference(200)}
#: (l*, method): the cutoff removes most pairs / some pairs / the all-pairs path
CASES = {"short": (0.05, "neighbours"), "medium": (0.15, "neighbours"), "long": (0.5, "dense")}


def off_manifold(c, seed):
    """A generic state: kappa and g perturbed smoothly (the curve no longer closes)."""
    rng = np.random.default_rng(seed)
    s = c.grid.s
    dk = 0.2 * sum(rng.normal() * np.cos(2 * np.pi * k * s + rng.uniform(0, 6)) for k in (1, 2))
    dg = 1 + 0.05 * np.sin(2 * np.pi * s + rng.uniform(0, 6))
    return Curve(c.kappa + dk, c.g * dg, c.grid, c.theta0, c.origin)


def direction(grid, seed, g_scale):
    rng = np.random.default_rng(seed)
    s = grid.s
    f = lambda n: sum(rng.normal() * np.cos(2 * np.pi * k * s + rng.uniform(0, 6))
                      for k in range(n))
    return np.concatenate([f(5), g_scale * f(4)])


def five_point(f, h):
    return (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12 * h)


def node_speed(c, V, t=1e-7):
    """``max_j |dX_j / dd|`` along ``U + d V``."""
    return np.abs(c.with_U(c.U + t * V).positions() - c.positions()).max() / t


def w2(c):
    return np.concatenate([c.dsigma, c.dsigma])


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("gname", GRIDS)
def test_gradient_is_derivative_of_energy(gname, case):
    """<grad E, U1> = dE(U + d U1)/dd for every direction (closure not required)."""
    l_star, method = CASES[case]
    c = off_manifold(random_curve(1, GRIDS[gname]), seed=2)
    E = Adhesion(A0=10.0, l_star=l_star, method=method)
    assert_gradient_matches_energy(
        E, c, [direction(c.grid, seed, 0.3 * c.g.mean()) for seed in (3, 4)], rtol=1e-8)


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("gname", GRIDS)
def test_hessian_is_derivative_of_gradient(gname, case):
    """W H V = d(W G)(U + d V)/dd to relative 1e-7, dense and neighbour-list paths."""
    l_star, method = CASES[case]
    c = off_manifold(random_curve(5, GRIDS[gname]), seed=6)
    E = Adhesion(A0=10.0, l_star=l_star, method=method)
    d = E.derivatives(c)
    if method == "neighbours":
        assert d.n_pairs < 0.9 * c.N * (c.N - 1) / 2  # the cutoff removes pairs
    H = E.hessian(c)
    for seed in (7, 8):
        V = direction(c.grid, seed, 0.3 * c.g.mean())
        h = 3e-3 * l_star / node_speed(c, V)

        def WG(t):
            ct = c.with_U(c.U + t * V)
            return E.gradient(ct) * w2(ct)

        num = five_point(WG, h)
        ana = w2(c) * (H @ V)
        assert np.abs(num - ana).max() <= 1e-7 * np.abs(ana).max()
        # the same for the <.,.> gradient itself: d/dd G = H V - (g1 / g) G
        num_G = five_point(lambda t: E.gradient(c.with_U(c.U + t * V)), h)
        corr = H @ V - np.concatenate([V[c.N:] / c.g] * 2) * E.gradient(c)
        assert np.abs(num_G - corr).max() <= 1e-7 * np.abs(corr).max()


@pytest.mark.parametrize("gname", GRIDS)
def test_second_variation_of_energy(gname):
    """d^2/dd^2 E(U + d U1) = <H U1, U1> (the Energy protocol)."""
    c = off_manifold(random_curve(9, GRIDS[gname]), seed=10)
    E = Adhesion(A0=10.0, l_star=0.15)
    H = E.hessian(c)
    U1 = direction(c.grid, 11, 0.3 * c.g.mean())
    f = lambda t: E.energy(c.with_U(c.U + t * U1))
    h = 1e-3
    num = (-f(2 * h) + 16 * f(h) - 30 * f(0) + 16 * f(-h) - f(-2 * h)) / (12 * h**2)
    ana = inner(c, H @ U1, U1)
    assert num == pytest.approx(ana, rel=1e-6)


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("gname", GRIDS)
def test_self_adjoint_and_forms_agree(gname, case):
    """W H symmetric; products, dense and factored forms are the same matrix."""
    l_star, method = CASES[case]
    c = off_manifold(random_curve(12, GRIDS[gname]), seed=13)
    d = Adhesion(A0=10.0, l_star=l_star, method=method).derivatives(c)
    Hd = d.hessian("dense")
    A = w2(c)[:, None] * Hd
    assert np.abs(A - A.T).max() <= 1e-12 * np.abs(A).max()
    V = np.random.default_rng(14).standard_normal((2 * c.N, 3))
    # round-off scale: |H| |V|, amplified by the cancellations inside the chain rule
    # (fields of size A0 w summed by cumulative sums); a wrong term is O(1)
    scale = 1e-10 * (np.abs(Hd) @ np.abs(V)).max()
    assert np.abs(d.hessian_vector(V) - Hd @ V).max() <= scale
    assert np.abs(d.hessian_vector(V[:, 0]) - Hd @ V[:, 0]).max() <= scale
    if c.grid.sparse:
        R = d.hessian("reduced")
        assert isinstance(R, ReducedHessian)
        assert np.abs(R @ V - Hd @ V).max() <= scale
        assert np.abs(R.toarray() - Hd).max() <= 1e-10 * np.abs(Hd).max()
        assert np.abs((R.T @ V) - Hd.T @ V).max() <= scale


def test_reduced_form_is_sparse_and_solves():
    """O(N + P) storage; (H - sigma I)^{-1} from the sparse saddle-point system."""
    c = random_curve(15, FiniteDifference(400))
    E = Adhesion(A0=10.0, l_star=0.03)
    d = E.derivatives(c)
    H = E.hessian(c)
    assert isinstance(H, ReducedHessian)
    assert H.nnz <= 18 * d.n_pairs + 40 * c.N
    assert d.n_pairs < 0.1 * c.N * (c.N - 1) / 2
    b = np.random.default_rng(16).standard_normal(2 * c.N)
    for sigma in (0.0, -3.0):
        x = H.shift_invert(sigma) @ b
        assert np.abs(H @ x - sigma * x - b).max() <= 1e-8 * np.abs(b).max()


@pytest.mark.parametrize("gname", GRIDS)
def test_base_point_rigid_motions(gname):
    """Moving theta0 or gamma0 moves X rigidly: the mixed second derivatives vanish exactly.

    With d_theta0 = 1 the position change is the rotation (X - gamma0)^perp and theta
    shifts by 1: every term of the chain (the pair Hessian, -g a, p) contributes and
    they cancel.
    """
    c = off_manifold(random_curve(17, GRIDS[gname]), seed=18)
    d = Adhesion(A0=10.0, l_star=0.15).derivatives(c)
    zero = np.zeros(2 * c.N)
    scale = np.abs(d.euclidean_hessian_vector(np.concatenate([np.ones(c.N), zero[c.N:]]))).max()
    for d_theta0, d_origin in ((1.0, (0.0, 0.0)), (0.0, (1.0, 0.0)), (0.0, (0.0, 1.0))):
        out = d.euclidean_hessian_vector(zero, d_theta0=d_theta0, d_origin=d_origin)
        assert np.abs(out).max() <= 1e-13 * scale
    # the rotation is not trivially zero term by term: the pair part alone is not
    X = np.stack(c.positions(), axis=1) - np.asarray(c.origin)
    F1, B1 = d.pair_product(np.column_stack([-X[:, 1], X[:, 0]]), np.zeros(c.N))
    assert np.abs(F1).max() > 1e-3 * np.abs(d.F).max()
    assert np.abs(F1 - np.column_stack([-d.F[:, 1], d.F[:, 0]])).max() <= 1e-12 * np.abs(F1).max()
    assert np.abs(B1).max() <= 1e-12 * np.abs(d.B).max()


@pytest.mark.parametrize("gname", GRIDS)
def test_dilation_second_variation_closed_form(gname):
    """U(lam) = (kappa / lam, lam g): E = lam^2 S(lam^2), S(mu) = A0 sum w^2 + 2 sum A(mu l) w w.

    d/dlam E = 2 S + 2 S' and d^2/dlam^2 E = 2 S + 10 S' + 4 S'' at lam = 1 (S' = 2 sum
    A' l w w, S'' = 2 sum A'' l^2 w w), against <G, U'> and <H U', U'> + <G, U''>.
    """
    c = off_manifold(random_curve(19, GRIDS[gname]), seed=20)
    E = Adhesion(A0=10.0, l_star=0.15)
    d = E.derivatives(c)
    x, y = c.positions()
    w = c.dsigma
    i, j = d.i, d.j
    l = (x[i] - x[j]) ** 2 + (y[i] - y[j]) ** 2
    A, dA, d2A = E.kernel.derivatives(l)
    ww = w[i] * w[j]
    S = E.A0 * np.sum(w * w) + 2 * np.sum(A * ww)
    S1, S2 = 2 * np.sum(dA * l * ww), 2 * np.sum(d2A * l * l * ww)
    U1 = np.concatenate([-c.kappa, c.g])
    U2 = np.concatenate([2 * c.kappa, np.zeros(c.N)])
    G, H = d.gradient(), d.hessian()
    terms = abs(2 * S) + abs(10 * S1) + abs(4 * S2)
    assert abs(inner(c, G, U1) - (2 * S + 2 * S1)) <= 1e-12 * terms
    assert abs(inner(c, H @ U1, U1) + inner(c, G, U2) - (2 * S + 10 * S1 + 4 * S2)) \
        <= 1e-11 * terms


@pytest.mark.parametrize("gname", GRIDS)
def test_sum_with_local_energies(gname):
    """CanhamHelfrich + Perimeter + Adhesion: assembles, symmetric in W, second variation."""
    c = off_manifold(random_curve(21, GRIDS[gname]), seed=22)
    E = CanhamHelfrich(eps=0.1) + Perimeter(beta=2.0, L_star=6.0) + Adhesion(10.0, 0.05)
    H = E.hessian(c)
    if c.grid.sparse:
        assert isinstance(H, ReducedHessian) and H.U.shape[1] == 1  # the perimeter's rank one
    Hd = to_dense(H)
    parts = sum(to_dense(t.hessian(c)) for t in E.terms())
    assert np.abs(Hd - parts).max() <= 1e-12 * np.abs(parts).max()
    A = w2(c)[:, None] * Hd
    assert np.abs(A - A.T).max() <= 1e-12 * np.abs(A).max()
    U1 = direction(c.grid, 23, 0.3 * c.g.mean())
    f = lambda t: E.energy(c.with_U(c.U + t * U1))
    h = 1e-3
    num = (-f(2 * h) + 16 * f(h) - 30 * f(0) + 16 * f(-h) - f(-2 * h)) / (12 * h**2)
    assert num == pytest.approx(inner(c, H @ U1, U1), rel=1e-6)
    if c.grid.sparse:
        b = np.random.default_rng(24).standard_normal(2 * c.N)
        x = H.shift_invert(0.5) @ b
        assert np.abs(H @ x - 0.5 * x - b).max() <= 1e-8 * np.abs(b).max()


def test_reduced_hessian_with_constraint_hessian():
    """The Lagrangian Hessian's sparse C_3 term joins the factored form."""
    c = random_curve(25, FiniteDifference(128))
    H = Adhesion(10.0, 0.1).hessian(c)
    Hc3 = geometry.constraint_hessians(c)[2]
    L = H - 0.7 * Hc3
    assert isinstance(L, ReducedHessian)
    assert np.abs(L.toarray() - (H.toarray() - 0.7 * to_dense(Hc3))).max() \
        <= 1e-12 * np.abs(H.toarray()).max()


def test_auto_form_and_errors():
    fd, ff = random_curve(26, FiniteDifference(128)), random_curve(26, Fourier(65))
    assert isinstance(Adhesion(10.0, 0.05).hessian(fd), ReducedHessian)
    assert isinstance(Adhesion(10.0, 0.5, method="dense").hessian(fd), np.ndarray)
    assert isinstance(Adhesion(10.0, 0.05).hessian(ff), np.ndarray)
    d = Adhesion(10.0, 0.05).derivatives(ff)
    with pytest.raises(ValueError, match="finite-difference"):
        d.hessian("reduced")
    with pytest.raises(ValueError, match="form"):
        d.hessian("sparse")
    with pytest.raises(ValueError, match="shape"):
        d.hessian_vector(np.zeros(10))
    with pytest.raises(ValueError, match="pairs"):
        adhesion_derivatives(AdhesionKernel(1.0, 0.1, 1.0), ff, (np.array([3]), np.array([1])))


def test_gradient_fields_match_the_flow_fields():
    """dE^/dX = w force and dE^/dw = B, the fields of the normal velocity."""
    c = random_curve(27, Fourier(65))
    E = Adhesion(10.0, 0.3, method="dense")
    d = adhesion_derivatives(E.kernel, c, dense_pairs(c.N))
    B, force = E.fields(c)
    assert np.allclose(d.B, B, rtol=1e-13, atol=0)
    assert np.allclose(d.F, c.dsigma[:, None] * force, rtol=0, atol=1e-13 * np.abs(d.F).max())


def test_cumulative_factors_reproduce_the_trapezoid_matrix():
    N = 12
    Bd, R = cumulative_factors(N)
    C = np.linalg.solve(Bd.toarray(), R.toarray())
    assert np.allclose(C, FiniteDifference(N).cumulative_matrix(), atol=1e-15)
    assert sp.triu(Bd, 1).nnz == 0
