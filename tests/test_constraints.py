"""The enclosed area and the length as functions of U = (kappa, g), and the constraint objects."""

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.constraints import (
    FixedArea,
    FixedLength,
    area_gradient,
    area_gradient_euclidean,
    area_hessian,
    bind_constraints,
    constraint_normals,
    length_gradient,
    length_hessian,
)
from qsa.linalg import to_dense
from tests.helpers import fitted_order, inner, skew_curve

GRIDS = {"fourier": Fourier(33), "fd": FiniteDifference(40)}


def off_manifold(grid, seed=0):
    """A smooth state that is not closed (theta is not periodic, gamma does not close)."""
    c = skew_curve(grid)
    rng = np.random.default_rng(seed)
    s = grid.s
    dk = 0.2 * np.cos(2 * np.pi * s + rng.uniform()) + 0.1
    dg = 0.1 * np.sin(4 * np.pi * s + rng.uniform()) * c.g.mean()
    return Curve(c.kappa + dk, c.g + dg, grid, 0.3, (0.2, -0.1))


def directions(grid, seed):
    rng = np.random.default_rng(seed)
    out = [rng.standard_normal(2 * grid.N) for _ in range(3)]
    s = grid.s
    out.append(np.concatenate([np.cos(6 * np.pi * s), 0.5 * np.sin(2 * np.pi * s)]))
    return [v / np.linalg.norm(v) for v in out]


# ------------------------------------------------------------------- the area
@pytest.mark.parametrize("R, centre", [(1.0, (0.0, 0.0)), (2.5, (1.0, -3.0))])
def test_area_of_circles_does_not_depend_on_their_centre(R, centre):
    assert Curve.circle(R, Fourier(17), center=centre).area() == pytest.approx(np.pi * R**2,
                                                                             rel=1e-13)
    a0 = Curve.circle(R, FiniteDifference(64)).area()
    assert Curve.circle(R, FiniteDifference(64), center=centre).area() == pytest.approx(
        a0, rel=1e-13)
    assert a0 == pytest.approx(np.pi * R**2, rel=2e-3)


def test_area_converges_spectrally_and_at_order_two():
    r = lambda t: 1 + 0.2 * np.cos(3 * t) + 0.1 * np.sin(2 * t)
    exact = np.pi * (1 + 0.2**2 / 2 + 0.1**2 / 2)  # 1/2 int r^2
    assert Curve.polar(r, Fourier(257)).area() == pytest.approx(exact, rel=1e-13)
    Ns = [64, 128, 256]
    errs = [abs(Curve.polar(r, FiniteDifference(N)).area() - exact) for N in Ns]
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


@pytest.mark.parametrize("gname", GRIDS)
@pytest.mark.parametrize("closed", [True, False])
def test_area_gradient_is_the_exact_derivative(gname, closed):
    grid = GRIDS[gname]
    c = skew_curve(grid) if closed else off_manifold(grid)
    g_inner = area_gradient(c)
    g_euc = area_gradient_euclidean(c)
    assert np.allclose(g_euc, g_inner * np.concatenate([c.dsigma, c.dsigma]), rtol=1e-14)
    for U1 in directions(grid, 1):
        d = 1e-6 * np.linalg.norm(c.U)
        A = lambda t: c.with_U(c.U + t * U1).area()
        num = (-A(2 * d) + 8 * A(d) - 8 * A(-d) + A(-2 * d)) / (12 * d)
        scale = np.sqrt(inner(c, g_inner, g_inner) * inner(c, U1, U1))
        assert abs(num - inner(c, g_inner, U1)) <= 1e-8 * scale


@pytest.mark.parametrize("gname", GRIDS)
@pytest.mark.parametrize("closed", [True, False])
def test_area_hessian_is_the_exact_second_derivative(gname, closed):
    grid = GRIDS[gname]
    c = skew_curve(grid) if closed else off_manifold(grid, seed=2)
    H = area_hessian(c)
    W = np.concatenate([c.dsigma, c.dsigma])
    WH = W[:, None] * H
    assert np.abs(WH - WH.T).max() <= 1e-13 * np.abs(WH).max()
    for U1 in directions(grid, 3):
        # columns against central differences of the Euclidean gradient
        d = 1e-6 * np.linalg.norm(c.U)
        col = (area_gradient_euclidean(c.with_U(c.U + d * U1))
               - area_gradient_euclidean(c.with_U(c.U - d * U1))) / (2 * d)
        assert np.abs(col - WH @ U1).max() <= 1e-7 * np.abs(WH @ U1).max()
        # the quadratic form against fourth-order second differences of A
        d = 1e-3 * np.linalg.norm(c.U)
        A = lambda t: c.with_U(c.U + t * U1).area()
        num = (-A(2 * d) + 16 * A(d) - 30 * A(0) + 16 * A(-d) - A(-2 * d)) / (12 * d**2)
        bound = max(abs(inner(c, H @ U1, U1)), np.abs(H).max() * inner(c, U1, U1))
        assert abs(num - inner(c, H @ U1, U1)) <= 1e-7 * bound


def test_area_moves_with_the_normal_velocity():
    """-[M-dagger nabla_I A]_1 = -1 on closed curves: spectral on Fourier, order 2 on FD."""
    r = lambda t: 1 + 0.1 * np.cos(3 * t) + 0.05 * np.sin(2 * t)
    c = Curve.polar(r, Fourier(129))
    V = -(geometry.M_adjoint(c) @ area_gradient(c))[: c.N]
    assert np.abs(V + 1).max() < 1e-9
    Ns = [64, 128, 256]
    errs = []
    for N in Ns:
        c = Curve.polar(r, FiniteDifference(N))
        errs.append(np.abs(-(geometry.M_adjoint(c) @ area_gradient(c))[:N] + 1).max())
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


def test_area_gradient_on_closed_curves_is_the_centred_position_form():
    """nabla_I A = (-|g~|^2/2 + c0, (kappa (-|g~|^2/2 + c0) + g~ . n)/g), g~ = gamma - mean."""
    c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t) + 0.05 * np.sin(2 * t), Fourier(129))
    x, y = c.positions()
    w = c.grid.weights
    gx, gy = x - w @ x, y - w @ y
    r2 = 0.5 * (gx**2 + gy**2)
    c0 = w @ r2
    n = c.normal()
    ref = np.concatenate([-r2 + c0, (c.kappa * (-r2 + c0) + gx * n[0] + gy * n[1]) / c.g])
    assert np.allclose(area_gradient(c), ref, atol=1e-9 * np.abs(ref).max())


def test_area_is_invariant_under_rigid_motions_off_closure():
    c = off_manifold(Fourier(33))
    moved = Curve(c.kappa, c.g, c.grid, c.theta0 + 0.7, (3.0, -2.0))
    assert moved.area() == pytest.approx(c.area(), rel=1e-13)
    assert np.allclose(area_gradient(moved), area_gradient(c), rtol=1e-12, atol=1e-13)


def test_area_is_unchanged_by_reparameterization_to_first_order():
    """<nabla_I A, M(0, v)> = 0 on closed curves: A is geometric."""
    c = skew_curve(Fourier(257))
    v = np.sin(2 * np.pi * c.grid.s) + 0.3 * np.cos(6 * np.pi * c.grid.s)
    rep = geometry.reparameterization_mode(c, v)
    assert abs(inner(c, area_gradient(c), rep)) < 1e-12 * np.sqrt(inner(c, rep, rep))


# ----------------------------------------------------------------- the length
@pytest.mark.parametrize("gname", GRIDS)
def test_length_gradient_and_hessian(gname):
    c = off_manifold(GRIDS[gname])
    for U1 in directions(c.grid, 4):
        d = 1e-3
        dL = (c.with_U(c.U + d * U1).length() - c.with_U(c.U - d * U1).length()) / (2 * d)
        assert dL == pytest.approx(inner(c, length_gradient(c), U1), rel=1e-9)
    assert np.abs(to_dense(length_hessian(c))).max() == 0.0
    # the normal velocity of L is -kappa, exactly
    V = -(geometry.M_adjoint(c) @ length_gradient(c))[: c.N]
    assert np.allclose(V, -c.kappa, rtol=1e-12, atol=1e-12)


# ----------------------------------------------------------- the constraints
def test_constraints_bind_to_the_curve_and_report_their_defect():
    c = Curve.circle(1.5, Fourier(17))
    L, A = bind_constraints([FixedLength(), FixedArea(A=7.0)], c)
    assert L.target == pytest.approx(3 * np.pi) and L.defect(c) == pytest.approx(0, abs=1e-12)
    assert A.target == 7.0 and A.defect(c) == pytest.approx(np.pi * 2.25 - 7.0)
    assert FixedArea(2.0).bind(c) == FixedArea(2.0)  # a given target is kept
    assert A.params() == {"constraint": "FixedArea", "A": 7.0}
    n = constraint_normals([L, A], c)
    assert np.allclose(n, [c.kappa, np.ones(17)])
    assert constraint_normals([], c).shape == (0, 17)
    assert bind_constraints(None, c) == () and bind_constraints(FixedLength(), c)[0] == L


def test_normal_variations_are_the_first_variations():
    """d/dt c(U + t M(V, 0)) = <n_c, V> (exactly for L, to the discretization for A)."""
    c = skew_curve(Fourier(257))
    V = 1 + np.cos(2 * np.pi * c.grid.s) + 0.5 * np.sin(6 * np.pi * c.grid.s)
    U1 = geometry.M(c) @ np.concatenate([V, np.zeros(c.N)])
    for con in bind_constraints([FixedLength(), FixedArea()], c):
        d = 1e-5
        rate = (con.value(c.with_U(c.U + d * U1)) - con.value(c.with_U(c.U - d * U1))) / (2 * d)
        assert rate == pytest.approx(inner(c, con.normal_variation(c), V), rel=1e-8)


@pytest.mark.parametrize("bad, match", [
    ([FixedLength(), FixedLength(2.0)], "given twice"),
    (["area"], "FixedLength / FixedArea objects"),
    (3, "must be a list"),
])
def test_bad_constraint_lists(bad, match):
    with pytest.raises(ValueError, match=match):
        bind_constraints(bad, Curve.circle(1.0, Fourier(9)))


@pytest.mark.parametrize("make, match", [
    (lambda: FixedLength(-1.0), "L must be positive"),
    (lambda: FixedArea(float("nan")), "A must be a positive finite"),
])
def test_bad_targets(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_unbound_constraint_has_no_defect():
    with pytest.raises(ValueError, match="bind the constraint"):
        FixedArea().defect(Curve.circle(1.0, Fourier(9)))
