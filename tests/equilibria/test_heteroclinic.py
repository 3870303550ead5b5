"""The heteroclinic front: closed form, quadrature for any well, ODE residual."""

import importlib

import numpy as np
import pytest

from qsa.equilibria import heteroclinic

het_module = importlib.import_module("qsa.equilibria.heteroclinic")

SIGMA = np.linspace(-1.5, 1.5, 1201)


def ode_residual(front, sigma):
    """alpha^2 psi'' - W'(psi), psi'' by complex step of the quadrature's psi'."""
    h = 1e-30
    d2 = np.imag(front.derivative(sigma + 1j * h)) / h
    return front.alpha**2 * d2 - front.well.dW(front(sigma))


@pytest.fixture
def generic_path(monkeypatch):
    """Force the quadrature path even for the quartic well."""
    monkeypatch.setattr(het_module, "is_quartic", lambda well, kstar: False)


@pytest.mark.parametrize("alpha", [0.05, 0.1, 0.3])
def test_quartic_closed_form(alpha):
    k = 5.0
    psi = heteroclinic(alpha, kstar=k)
    exact = k / (1 + np.exp(-k * SIGMA / (np.sqrt(2) * alpha)))
    assert np.max(np.abs(psi(SIGMA) - exact)) < 1e-13
    assert np.max(np.abs(ode_residual(psi, SIGMA))) <= 1e-12
    lam = k / (np.sqrt(2) * alpha)
    assert psi.rates == pytest.approx((lam, lam), rel=1e-14)
    assert psi.width == pytest.approx(1 / lam)
    assert psi(0.0) == 2.5


@pytest.mark.parametrize("alpha", [0.05, 0.2])
def test_quadrature_path_reproduces_the_tanh_form(generic_path, alpha):
    k = 5.0
    psi = heteroclinic(alpha, kstar=k)
    assert not psi.closed_form
    exact = k / (1 + np.exp(-k * SIGMA / (np.sqrt(2) * alpha)))
    assert np.max(np.abs(psi(SIGMA) - exact)) < 1e-13
    dexact = k / (np.sqrt(2) * alpha) * exact * (1 - exact / k)
    assert np.max(np.abs(psi.derivative(SIGMA) - dexact)) < 1e-11 * np.max(dexact)
    assert np.max(np.abs(ode_residual(psi, SIGMA))) <= 1e-12
    assert psi.tension == pytest.approx(alpha * k**3 / (6 * np.sqrt(2)), rel=1e-13)


def test_sine_well_matches_its_exact_front(sine_well):
    alpha = 0.1
    psi = heteroclinic(alpha, sine_well)
    assert not psi.closed_form
    exact = sine_well.exact_front(SIGMA, alpha)
    assert np.max(np.abs(psi(SIGMA) - exact)) < 1e-13
    assert np.max(np.abs(ode_residual(psi, SIGMA))) <= 1e-12
    lam = np.pi * np.sqrt(2 * sine_well.A) / (alpha * sine_well.kstar)
    assert psi.rates == pytest.approx((lam, lam), rel=1e-14)


def test_sextic_well(sextic_well):
    alpha = 0.1
    psi = heteroclinic(alpha, sextic_well)
    res = ode_residual(psi, SIGMA)
    assert np.max(np.abs(res)) <= 1e-12
    # first integral alpha^2 psi'^2 / 2 = W(psi)
    fi = alpha**2 * psi.derivative(SIGMA) ** 2 / 2 - sextic_well.W(psi(SIGMA))
    assert np.max(np.abs(fi)) < 1e-12
    # the sextic front is steeper than the quartic one with the same W''(0)
    assert psi(0.0) == pytest.approx(2.5, abs=1e-14)
    # tail rates: log-slopes far out approach sqrt(W'')/alpha
    lam = np.sqrt(sextic_well.d2W(0.0)) / alpha
    s1, s2 = -0.8, -0.9
    slope = (np.log(psi(s1)) - np.log(psi(s2))) / (s1 - s2)
    assert slope == pytest.approx(lam, rel=1e-6)
    z1, z2 = psi.complement(-s1), psi.complement(-s2)
    assert z1 == pytest.approx(5 - psi(-s1), abs=1e-15)
    assert -(np.log(z1) - np.log(z2)) / (s2 - s1) == pytest.approx(lam, rel=1e-6)


def test_position_inverts(sextic_well):
    psi = heteroclinic(0.2, sextic_well)
    values = np.array([1e-6, 0.3, 2.5, 4.9, 5 - 1e-7])
    assert np.allclose(psi(psi.position(values)), values, rtol=1e-12, atol=1e-15)


def test_invalid_input(sine_well):
    with pytest.raises(ValueError, match="alpha"):
        heteroclinic(0.0)
    with pytest.raises(ValueError, match="alpha"):
        heteroclinic(-1.0)
    with pytest.raises(ValueError, match="kstar"):
        heteroclinic(0.1, sine_well, kstar=4.0)

    class Tilted(type(sine_well)):
        def W(self, k):
            return super().W(k) + 0.1 * k

    with pytest.raises(ValueError, match="equal depth"):
        heteroclinic(0.1, Tilted())
