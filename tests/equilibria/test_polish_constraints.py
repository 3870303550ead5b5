"""Polishing with fixed length / area and with area energies: Jacobian, rings, vesicles."""

import json

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.constraints import FixedArea, FixedLength
from qsa.energies import AreaPenalty, CanhamHelfrich, Faceting, Perimeter, Pressure
from qsa.equilibria import polish
from qsa.equilibria.newton import EquilibriumSystem
from qsa.linalg import to_dense
from tests.helpers import assert_quadratic_convergence, fd_jacobian, fitted_order, skew_curve


def ellipse(grid, a, b):
    return Curve.polar(lambda t: a * b / np.sqrt((b * np.cos(t)) ** 2 + (a * np.sin(t)) ** 2),
                       grid)


def vesicle_constraints(nu, L=2 * np.pi):
    """Fixed length L and reduced area nu = 4 pi A / L^2."""
    return [FixedLength(L), FixedArea(nu * L**2 / (4 * np.pi))]


ENERGIES = {
    "pressure": CanhamHelfrich(0.7) + Pressure(-0.3),
    "penalty": CanhamHelfrich(0.7) + AreaPenalty(2.0, 2.5) + Perimeter(1.0, 6.0),
    "faceting": Faceting(0.1, 5.0) + Pressure(0.4),
}


@pytest.mark.parametrize("kind", [Fourier, FiniteDifference])
@pytest.mark.parametrize("ename", ENERGIES)
@pytest.mark.parametrize("cons", [[FixedLength(6.0)], [FixedArea(3.0), FixedLength(6.5)], []])
def test_jacobian_against_central_differences(kind, ename, cons):
    c = skew_curve(kind(41))
    S = EquilibriumSystem(ENERGIES[ename], c, cons)
    x = S.pack(c)
    x[S.N + 1: S.N + 4] = [0.1, -0.2, 0.3]
    x[S.size - S.m:] = 0.5 + np.arange(S.m)  # the multiplier columns are checked too
    A, B, Crows, D, low = S.jacobian_parts(x)
    A = to_dense(A) + sum(P @ Q.T for P, Q in low)  # low-rank terms folded back in
    J = np.block([[A, B], [Crows, D]])
    Jfd = fd_jacobian(S, x)
    assert J.shape == (S.N + 4 + S.m, S.N + 4 + S.m) == (S.size, S.size)
    assert np.max(np.abs(J - Jfd)) < 1e-7 * np.max(np.abs(J))
    assert bool(low) == (ename == "penalty")


@pytest.mark.parametrize("grid", [Fourier(33), FiniteDifference(64)])
@pytest.mark.parametrize("p", [-2.0, 0.0, 1.5])
def test_pressurized_ring_relaxes_to_the_circle_of_its_length(grid, p):
    """CanhamHelfrich + Pressure at fixed length: the circle, mu_L = -R (p + eps / (2 R^3))."""
    eps, L = 0.5, 5.0
    R = L / (2 * np.pi)
    guess = Curve.polar(lambda t: R * (1 + 0.02 * np.cos(2 * t) + 0.01 * np.sin(3 * t)), grid)
    r = polish(CanhamHelfrich(eps) + Pressure(p), guess, constraints=[FixedLength(L)])
    assert r.success, r.message
    assert_quadratic_convergence(r)
    assert r.params["L"] == pytest.approx(L, rel=1e-12)
    # FD: the trapezoidal curvature of a circle is exact, so is the equilibrium
    assert np.allclose(r.curve.kappa, 1 / R, atol=1e-9)
    assert r.constraint_multipliers[0] == pytest.approx(-R * (p + eps / (2 * R**3)), rel=1e-9)
    assert r.params["mu_L"] == r.constraint_multipliers[0] and r.params["p"] == p
    assert r.residual <= 1e-9 * r.residual_scale and r.closure < 1e-10


def test_pressure_sets_the_radius_and_fixed_area_finds_the_pressure():
    """An equilibrium of E + Pressure(p) is one of E at fixed area with mu_A = p."""
    eps = 0.4
    guess = Curve.polar(lambda t: 1.1 + 0.02 * np.cos(3 * t), Fourier(33))
    r1 = polish(CanhamHelfrich(eps) + Pressure(-0.05), guess)
    assert r1.success, r1.message
    R = (eps / (2 * 0.05)) ** (1 / 3)  # eps / (2 R^3) + p = 0
    assert np.allclose(r1.curve.kappa, 1 / R, atol=1e-10)
    r2 = polish(CanhamHelfrich(eps), guess, constraints=[FixedArea(np.pi * R**2)])
    assert r2.success, r2.message
    assert np.allclose(r2.curve.kappa, 1 / R, atol=1e-10)
    assert r2.constraint_multipliers[0] == pytest.approx(-0.05, rel=1e-9)


@pytest.fixture(scope="module")
def vesicle():
    """The 2-D vesicle of reduced area 0.9 (Canham-Helfrich at fixed length and area)."""
    guess = ellipse(Fourier(65), 1.25, 0.8)
    return polish(CanhamHelfrich(1.0), guess, constraints=vesicle_constraints(0.9))


def test_vesicle_is_a_symmetric_non_circular_constrained_equilibrium(vesicle):
    r = vesicle
    assert r.success, r.message
    assert_quadratic_convergence(r)
    c = r.curve
    assert r.residual <= 1e-10 * r.residual_scale and r.closure < 1e-12
    assert c.length() == pytest.approx(2 * np.pi, rel=1e-13)
    assert 4 * np.pi * c.area() / c.length() ** 2 == pytest.approx(0.9, rel=1e-12)
    # non-circular, with the two-fold symmetry of the ellipse it came from
    assert np.ptp(c.kappa) > 1.0
    k_half = c.grid.interpolate(c.kappa, c.grid.s + 0.5)
    assert np.max(np.abs(k_half - c.kappa)) < 1e-9
    # and mirror symmetric about the axis through the curvature maximum
    j = int(np.argmax(c.kappa))
    s0 = c.grid.s[j]
    mirror = c.grid.interpolate(c.kappa, 2 * s0 - c.grid.s)
    assert np.max(np.abs(mirror - c.kappa)) < 1e-6
    # a flat-sided shape: both multipliers non-zero (tension and pressure)
    mu_L, mu_A = r.constraint_multipliers
    assert abs(mu_L) > 0.1 and abs(mu_A) > 0.1
    assert json.loads(r.to_json())["constraint_multipliers"] == [mu_L, mu_A]


def test_vesicle_on_finite_differences_converges_at_order_two(vesicle):
    ref = vesicle.energy.energy(vesicle.curve)
    Ns = [64, 128, 256]
    errs = []
    for N in Ns:
        r = polish(CanhamHelfrich(1.0), ellipse(FiniteDifference(N), 1.25, 0.8),
                   constraints=vesicle_constraints(0.9))
        assert r.success, r.message
        errs.append(abs(r.energy.energy(r.curve) - ref))
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


def test_constraints_default_to_the_curve_values_and_are_reported():
    guess = ellipse(Fourier(65), 1.25, 0.8)
    r = polish(CanhamHelfrich(1.0), guess, constraints=[FixedLength(), FixedArea()])
    assert r.success, r.message
    assert r.curve.length() == pytest.approx(guess.length(), rel=1e-12)
    assert r.curve.area() == pytest.approx(guess.area(), rel=1e-12)
    assert [k.target for k in r.constraints] == [guess.length(), guess.area()]
    assert "mu_L" in r.message and "mu_A" in r.message


def test_bad_constraints_raise():
    guess = ellipse(Fourier(33), 1.25, 0.8)
    with pytest.raises(ValueError, match="given twice"):
        polish(CanhamHelfrich(1.0), guess, constraints=[FixedArea(), FixedArea()])
    with pytest.raises(ValueError, match="constraints must"):
        polish(CanhamHelfrich(1.0), guess, constraints=["area"])
