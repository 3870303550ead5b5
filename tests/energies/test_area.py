"""Pressure and area-penalty energies: derivatives, normal velocity, dissipation."""

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.constraints import FixedArea, FixedLength
from qsa.energies import (
    AreaPenalty,
    CanhamHelfrich,
    Perimeter,
    Pressure,
    multipliers,
    residual_scale,
)
from tests.helpers import (
    assert_gradient_matches_energy,
    assert_hessian_matches_energy,
    directions,
    inner,
    off_manifold,
)

ENERGIES = {
    "pressure": Pressure(0.7),
    "penalty": AreaPenalty(k=2.0, A_star=2.5),
    "ring": CanhamHelfrich(0.1) + Pressure(-0.4) + Perimeter(1.0, 5.0),
}
GRIDS = {"fourier": Fourier(33), "fd": FiniteDifference(40)}


@pytest.mark.parametrize("gname", GRIDS)
@pytest.mark.parametrize("ename", ENERGIES)
def test_gradient_is_derivative_of_energy(ename, gname):
    c = off_manifold(GRIDS[gname])
    assert_gradient_matches_energy(ENERGIES[ename], c, directions(GRIDS[gname], 1))


@pytest.mark.parametrize("gname", GRIDS)
@pytest.mark.parametrize("ename", ENERGIES)
def test_hessian_is_second_derivative_and_self_adjoint(ename, gname):
    c = off_manifold(GRIDS[gname], seed=3)
    assert_hessian_matches_energy(ENERGIES[ename], c, directions(GRIDS[gname], 2))


@pytest.mark.parametrize("ename", ["pressure", "penalty"])
def test_normal_velocity_is_the_generic_formula_of_the_gradient(ename):
    """V^n = -F'(A) equals -[M-dagger nabla_I E]_1 on closed curves (spectrally)."""
    E = ENERGIES[ename]
    c = Curve.polar(lambda t: 1.2 + 0.1 * np.cos(3 * t) + 0.05 * np.sin(2 * t), Fourier(129))
    generic = -(geometry.M_adjoint(c) @ E.gradient(c))[: c.N]
    assert np.allclose(E.normal_velocity(c), generic, atol=1e-9 * abs(E.dF(c.area())))
    assert np.allclose(E.normal_velocity(c), -E.dF(c.area()))


@pytest.mark.parametrize("E, sign", [(Pressure(0.5), 1), (Pressure(-0.5), -1),
                                     (AreaPenalty(1.0, 2.0), -1), (AreaPenalty(1.0, 5.0), 1)])
def test_gradient_flow_decreases_the_energy_and_moves_the_area_the_right_way(E, sign):
    """gamma_t = V^n n: dE/dt = -int (V^n)^2 dsigma; p > 0 inflates, a penalty restores A*."""
    c = Curve.polar(lambda t: 1.2 + 0.1 * np.cos(3 * t), Fourier(65))  # area ~ 4.56
    V = E.normal_velocity(c)
    U1 = geometry.M(c) @ np.concatenate([V, np.zeros(c.N)])
    d = 1e-5
    rateE = (E.energy(c.with_U(c.U + d * U1)) - E.energy(c.with_U(c.U - d * U1))) / (2 * d)
    rateA = (c.with_U(c.U + d * U1).area() - c.with_U(c.U - d * U1).area()) / (2 * d)
    assert rateE == pytest.approx(-inner(c, V, V), rel=1e-7)
    assert rateE < 0 and np.sign(rateA) == sign


def test_pressure_equilibrium_is_a_fixed_area_equilibrium_with_mu_the_pressure():
    """A circle under CanhamHelfrich + Pressure + FixedLength: V^n = eps/(2R^3) + p - mu_L/R."""
    eps, p, R = 0.3, -0.2, 1.4
    c = Curve.circle(R, Fourier(33))
    E = CanhamHelfrich(eps) + Pressure(p)
    assert np.allclose(E.normal_velocity(c), eps / (2 * R**3) + p)
    mu_L = multipliers(E, c, constraints=[FixedLength()])[3]
    assert mu_L == pytest.approx(-R * (p + eps / (2 * R**3)), rel=1e-10)
    # the same circle at fixed area with CH alone: mu_A = -eps / (2 R^3), so that
    # E - mu_A A has the pressure's Euler-Lagrange equation
    mu_A = multipliers(CanhamHelfrich(eps), c, constraints=[FixedArea()])[3]
    assert mu_A == pytest.approx(-eps / (2 * R**3), rel=1e-10)


def test_residual_scale_counts_the_pressure_term():
    c = Curve.circle(1.0, Fourier(33))
    assert residual_scale(Pressure(3.0), c) == pytest.approx(3.0)
    assert residual_scale(CanhamHelfrich(0.1) + Pressure(3.0), c) == pytest.approx(3.0)


def test_models_are_frozen_values_with_parameters():
    assert Pressure(1) == Pressure(1.0) and Pressure(1.0) != Pressure(2.0)
    assert AreaPenalty(1.0, 2.0).params() == {"energy": "AreaPenalty", "k": 1.0, "A_star": 2.0}
    with pytest.raises(AttributeError):
        Pressure(1.0).p = 2.0


@pytest.mark.parametrize("make, match", [
    (lambda: Pressure(float("nan")), "p must be a finite"),
    (lambda: AreaPenalty(-1.0, 2.0), "k must be non-negative"),
    (lambda: AreaPenalty(1.0, 0.0), "A_star must be positive"),
])
def test_bad_arguments(make, match):
    with pytest.raises(ValueError, match=match):
        make()
