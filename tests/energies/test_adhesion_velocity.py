"""The exact Jacobian of the adhesion normal velocity (qsa.energies.adhesion_velocity)."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import Adhesion
from qsa.energies.adhesion_hessian import position_state_equations

GRIDS = {"fourier": Fourier(101), "fd": FiniteDifference(200)}
CASES = {"short": (0.05, "neighbours"), "medium": (0.15, "neighbours"), "long": (0.5, "dense")}


def state(grid):
    """A generic state: not closed, g not constant."""
    c = Curve.polar(lambda t: 1 + 0.3 * np.cos(3 * t) + 0.05 * np.sin(5 * t), grid)
    s = grid.s
    return Curve(c.kappa * (1 + 0.05 * np.cos(2 * np.pi * s)),
                 c.g * (1 + 0.05 * np.sin(2 * np.pi * s)), grid, c.theta0, c.origin)


def direction(grid, seed):
    rng = np.random.default_rng(seed)
    s = grid.s
    f = lambda n: sum(rng.normal() * np.cos(2 * np.pi * k * s + rng.uniform(0, 6))
                      for k in range(n))
    return np.concatenate([f(5), 0.3 * f(4)])


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("gname", GRIDS)
def test_jacobian_is_derivative_of_the_normal_velocity(gname, case):
    l_star, method = CASES[case]
    c = state(GRIDS[gname])
    E = Adhesion(A0=10.0, l_star=l_star, method=method)
    J = E.normal_velocity_jacobian(c)
    h = 1e-4
    for seed in range(2):
        U1 = direction(c.grid, seed)
        f = lambda t: E.normal_velocity(c.with_U(c.U + t * U1))
        fd = (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12 * h)
        assert np.abs(J @ U1 - fd).max() < 1e-8 * np.abs(fd).max()
        assert np.allclose(J.dense() @ U1, J @ U1, rtol=0, atol=1e-11 * np.abs(fd).max())


def test_state_direction_and_its_sparse_equations():
    c = state(FiniteDifference(64))
    J = Adhesion(A0=10.0, l_star=0.2).normal_velocity_jacobian(c)
    U1 = direction(c.grid, 3)
    h = 1e-6
    th = lambda t: c.with_U(c.U + t * U1).theta()
    X = lambda t: c.with_U(c.U + t * U1).positions().ravel()
    Y1 = J.state_direction(U1)
    assert np.allclose(Y1[:64], (th(h) - th(-h)) / (2 * h), atol=1e-8)
    assert np.allclose(Y1[64:], (X(h) - X(-h)) / (2 * h), atol=1e-8)
    cY, cU = position_state_equations(c)
    assert np.allclose(spla.spsolve(cY.tocsc(), -(cU @ U1)), Y1, atol=1e-12)


def test_sum_needs_one_curve():
    c = state(FiniteDifference(64))
    E = Adhesion(A0=10.0, l_star=0.2)
    J = E.normal_velocity_jacobian(c)
    U1 = direction(c.grid, 1)
    assert np.allclose((J + J) @ U1, 2 * (J @ U1))
    with pytest.raises(ValueError, match="different curves"):
        J + E.normal_velocity_jacobian(state(FiniteDifference(64)))
