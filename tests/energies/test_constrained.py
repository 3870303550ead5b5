"""V^n, the multipliers and the residual scale as properties of the energy alone."""

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.energies import (
    Adhesion,
    CanhamHelfrich,
    DoubleWell,
    Energy,
    Faceting,
    Perimeter,
    multipliers,
    normal_velocity,
    residual_scale,
)
from qsa.energies.base import generic_normal_velocity
from qsa.linalg import to_dense
from tests.helpers import inner, skew_curve

K = 5.0
GRIDS = [Fourier(41), FiniteDifference(64)]


def _sum():
    return Faceting(0.1, K) + CanhamHelfrich(0.3) + Perimeter(5.0, 6.0)


@pytest.mark.parametrize("grid", GRIDS, ids=["fourier", "fd"])
def test_sum_velocity_is_the_generic_formula_of_the_summed_gradient(grid):
    c = skew_curve(grid)
    E = _sum()
    V = normal_velocity(E, c)
    generic = Energy.normal_velocity(E, c)  # -[M-dagger nabla_I E]_1 of the whole sum
    assert np.max(np.abs(V - generic)) < 1e-12 * residual_scale(E, c)
    # the same as the first row of -M-dagger applied to the gradient, matrix assembled
    Md = to_dense(geometry.M_adjoint(c))
    assert np.allclose(V, -(Md @ E.gradient(c))[: c.N], rtol=0,
                       atol=1e-10 * residual_scale(E, c))


@pytest.mark.parametrize("grid", GRIDS, ids=["fourier", "fd"])
def test_sum_fast_path_equals_the_sum_of_the_summands_velocities(grid):
    c = skew_curve(grid)
    E = _sum() + Adhesion(10.0, 0.5)  # a summand with a velocity of its own
    slow = sum(e.normal_velocity(c) for e in E.terms())
    fast = E.normal_velocity(c)
    assert np.max(np.abs(fast - slow)) <= 1e-12 * np.max(np.abs(slow))
    assert np.array_equal(normal_velocity(E, c), fast)


def test_generic_formula_on_a_circle():
    # CanhamHelfrich(eps) on a circle: mu = eps kappa, xi = eps kappa^2 / 2, V = eps kappa^3 / 2
    c = Curve.circle(0.7, Fourier(17))
    eps = 1.3
    V = generic_normal_velocity(c, eps * c.kappa, 0.5 * eps * c.kappa**2)
    assert np.allclose(V, 0.5 * eps / 0.7**3, rtol=1e-13)


def _circle_equilibrium_L_star(R, beta):
    """beta (L - L*) = k W'(k) - W(k) at k = 1/R (the circle of Faceting + Perimeter)."""
    w = DoubleWell(K)
    k = 1.0 / R
    return 2 * np.pi * R - (k * w.dW(k) - w.W(k)) / beta


@pytest.mark.parametrize("R", [0.3, 0.8, 1.7])
def test_multipliers_of_circles(R):
    beta = 5.0
    c = Curve.circle(R, Fourier(33), center=(0.4, -1.1))
    E = Faceting(0.1, K) + Perimeter(beta, _circle_equilibrium_L_star(R, beta))
    assert np.max(np.abs(normal_velocity(E, c))) < 1e-10 * residual_scale(E, c)
    Lam = multipliers(E, c)
    # nabla_I E = (W'(1/R), ...) = Lambda_3 Psi_3 with Psi_3 = (1, kappa / g)
    assert np.allclose(Lam, [0.0, 0.0, DoubleWell(K).dW(1 / R)], atol=1e-9 * max(1, Lam[2]))
    resid = E.gradient(c) - Lam @ geometry.constraint_gradients(c)
    assert np.sqrt(inner(c, resid, resid)) < 1e-9 * np.sqrt(inner(c, E.gradient(c), E.gradient(c)))
    # Canham-Helfrich: eps kappa^3 / 2 = beta (L - L*) kappa, Lambda_3 = eps kappa
    eps = 0.4
    EH = CanhamHelfrich(eps) + Perimeter(beta, 2 * np.pi * R - eps / (2 * beta * R**2))
    assert np.allclose(multipliers(EH, c), [0.0, 0.0, eps / R], atol=1e-10)


@pytest.mark.parametrize("grid", GRIDS, ids=["fourier", "fd"])
def test_multipliers_are_the_projection_on_span_psi(grid):
    c = skew_curve(grid)
    c = c.with_g(c.g * (1 + 0.3 * np.cos(2 * np.pi * c.grid.s)))  # dsigma not uniform
    E = _sum()
    grad = E.gradient(c)
    Lam = multipliers(E, c)
    Psi = geometry.constraint_gradients(c)
    r = grad - Lam @ Psi
    for j in range(3):  # the residual is <.,.>-orthogonal to every Psi_j
        assert abs(inner(c, r, Psi[j])) < 1e-10 * np.sqrt(inner(c, grad, grad) * inner(
            c, Psi[j], Psi[j]))
    assert np.array_equal(multipliers(E, c, gradient=grad), Lam)


@pytest.mark.parametrize("grid", GRIDS, ids=["fourier", "fd"])
def test_residual_scale_is_the_largest_term_of_each_density(grid):
    c = skew_curve(grid)
    alpha, beta, Ls = 0.1, 5.0, 6.0
    E = Faceting(alpha, K) + Perimeter(beta, Ls)
    lap = to_dense(geometry.laplace_s(c))
    w = DoubleWell(K)
    k = c.kappa
    grad_E = E.gradient(c)
    N = c.N
    # the |p|^2 density: mu = -alpha^2 Delta_s kappa, xi = -alpha^2/2 |nabla_s kappa|^2
    smooth = E.gradient_parts(c)[0]
    mu_s = smooth[:N]
    xi_s = c.g * smooth[N:]
    terms = [lap @ mu_s, k**2 * mu_s, k * xi_s,
             lap @ w.dW(k), k**2 * w.dW(k), k * w.W(k),
             k * beta * (c.length() - Ls)]
    expected = max(float(np.max(np.abs(t))) for t in terms)
    assert residual_scale(E, c) == pytest.approx(expected, rel=1e-12)
    # -alpha^2 Delta_s kappa is the smooth part's mu (to the grid's consistency)
    assert np.allclose(mu_s, -(alpha**2) * lap @ k, atol=1e-8 * np.max(np.abs(mu_s)))
    assert np.allclose(sum(E.gradient_parts(c)), grad_E, rtol=0,
                       atol=1e-13 * np.max(np.abs(grad_E)))


def test_residual_scale_of_a_zero_energy_is_one():
    c = Curve.circle(1.0, Fourier(17))
    assert residual_scale(CanhamHelfrich(0.0), c) == 1.0


@pytest.mark.parametrize("grid", GRIDS, ids=["fourier", "fd"])
def test_residual_scale_where_every_term_vanishes(grid):
    """At kappa = kstar (W = W' = 0) the terms of V^n vanish; the scale is their change when
    kappa and g grow by 1e-3, in closed form on the circle (Delta_s of a constant is 0)."""
    from qsa.energies import FunctionalizedCurvature
    from qsa.energies.constrained import SCALE_CHANGE

    R, beta = 1.0 / K, 5.0
    c = Curve.circle(R, grid)
    w = DoubleWell(K)
    k1, L1 = K * (1 + SCALE_CHANGE), 2 * np.pi * R * (1 + SCALE_CHANGE)
    # faceting + perimeter at L* = L: kappa^2 W', kappa W and kappa beta (L - L*) at (k1, L1)
    E = Faceting(0.1, K) + Perimeter(beta, 2 * np.pi * R)
    expected = max(k1**2 * w.dW(k1), k1 * w.W(k1), k1 * beta * (L1 - 2 * np.pi * R))
    assert residual_scale(E, c) == pytest.approx(expected, rel=1e-6)
    # functionalized: the Z^2/2 part has mu = -W'' Z = W'' W' (Z = -W'), the largest term
    fc = FunctionalizedCurvature(0.1, 1.0, K)
    assert fc.circle_tension(R) == 0.0
    expected = k1**2 * w.d2W(k1) * w.dW(k1)
    assert residual_scale(fc, c) == pytest.approx(expected, rel=1e-6)
    # the equilibrium is recognised as one by its relative residual
    for energy in (E, fc):
        V = np.max(np.abs(normal_velocity(energy, c)))
        assert V <= 1e-6 * residual_scale(energy, c)


def test_residual_scale_keeps_the_largest_term_where_it_does_not_vanish():
    from qsa.energies.constrained import _velocity_terms

    for c in (Curve.circle(1.0, Fourier(33)), skew_curve(Fourier(41))):
        for E in (Faceting(0.1, K) + Perimeter(5.0, 6.0), CanhamHelfrich(0.3)):
            terms = max(float(np.max(np.abs(t))) for t in _velocity_terms(E, c))
            assert residual_scale(E, c) == terms


def test_gradient_parts():
    c = skew_curve(Fourier(33))
    E = _sum() + Adhesion(10.0, 0.5)
    parts = E.gradient_parts(c)
    assert len(parts) == 2 + 1 + 1 + 1  # Faceting's two densities, CH, perimeter, adhesion
    assert np.allclose(sum(parts), E.gradient(c), rtol=0,
                       atol=1e-12 * np.max(np.abs(E.gradient(c))))
