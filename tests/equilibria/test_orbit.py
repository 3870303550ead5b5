"""Periodic orbits of alpha^2 psi'' - W'(psi) = nu1: period, turning, profile, range."""

import importlib

import mpmath
import numpy as np
import pytest
from scipy.special import ellipkm1

from qsa.energies.wells import QuarticWell
from qsa.equilibria import periodic_orbit, periodic_range
from qsa.equilibria.orbit import _build, _family, orbit_with_turning
from tests.reference.orbits import mp_period

orbit_module = importlib.import_module("qsa.equilibria.orbit")

K = 5.0


def elliptic_period(alpha, nu2, k=K):
    """Quartic, nu1 = 0: T = 4 sqrt2 alpha K(m) / sqrt(k^2/4 + rho), 1 - m = 2 rho/(k^2/4 + rho)."""
    rho = 2 * np.sqrt(-nu2)
    return 4 * np.sqrt(2) * alpha * ellipkm1(2 * rho / (k**2 / 4 + rho)) / np.sqrt(k**2 / 4 + rho)


@pytest.mark.parametrize("nu2", [-9.7, -1.0, -1e-3, -1e-12, -1e-40, -1e-200])
def test_quartic_period_matches_elliptic_integral(nu2):
    orb = periodic_orbit(0.1, nu2, kstar=K)
    assert orb.period == pytest.approx(elliptic_period(0.1, nu2), rel=1e-14)
    # symmetric well, nu1 = 0: mean curvature kstar/2, so Theta = kstar T / 2
    assert orb.turning == pytest.approx(K * orb.period / 2, rel=1e-14)


@pytest.mark.parametrize("nu2", [-9.7, -1.0, -1e-4, -1e-10])
def test_generic_quadrature_agrees_with_exact_roots(nu2, monkeypatch):
    """The well-independent path (P from mean P') on the quartic itself."""
    monkeypatch.setattr(orbit_module, "_poly", lambda well, kstar: None)
    fam = _family(QuarticWell(K), K, 1e-300)  # nu1 != 0 bypasses the exact path
    assert not fam.closed
    orb = _build(fam, 0.1, nu2)
    rtol = 1e-13 if nu2 < -1e-6 else 1e-9  # double-precision roots near kstar
    assert orb.period == pytest.approx(elliptic_period(0.1, nu2), rel=rtol)


@pytest.mark.parametrize("nu1", [0.0, 0.4, -0.7])
def test_profile_solves_first_integral(nu1):
    alpha = 0.1
    lo, hi = periodic_range(nu1, kstar=K)
    orb = periodic_orbit(alpha, lo + 0.3 * (hi - lo), nu1, kstar=K)
    s = np.linspace(-orb.period, 2 * orb.period, 2001)
    psi, dpsi = orb(s), orb.derivative(s)
    P = QuarticWell(K).W(psi) + nu1 * psi + orb.nu2
    assert np.max(np.abs(alpha**2 * dpsi**2 / 2 - P)) < 1e-12 * K**4
    assert orb(0.0) == pytest.approx(orb.a, abs=1e-14)
    assert orb(orb.period / 2) == pytest.approx(orb.b, abs=1e-14)
    assert np.allclose(orb(s + orb.period), psi, atol=1e-13)
    # the turning is the integral of psi over one period (trapezoid, periodic)
    n = 4001
    grid = np.arange(n) * orb.period / n
    assert orb.turning == pytest.approx(orb(grid).sum() * orb.period / n, rel=1e-12)


def test_ode_residual_by_fourier_differentiation():
    alpha, orb = 0.2, periodic_orbit(0.2, -0.5, kstar=K)
    n = 257
    s = np.arange(n) * orb.period / n
    k = 2 * np.pi * np.fft.fftfreq(n, d=orb.period / n)
    psi = orb(s)
    d2 = np.fft.ifft(-(k**2) * np.fft.fft(psi)).real
    res = alpha**2 * d2 - QuarticWell(K).dW(psi)
    assert np.max(np.abs(res)) < 1e-9 * np.max(np.abs(alpha**2 * d2))


def test_periodic_range_and_errors():
    assert periodic_range(kstar=K) == (-(K**4) / 64, 0.0)
    with pytest.raises(ValueError, match="periodic range"):
        periodic_orbit(0.1, 0.1, kstar=K)
    with pytest.raises(ValueError, match="periodic range"):
        periodic_orbit(0.1, -K**4 / 64 - 1e-3, kstar=K)
    with pytest.raises(ValueError, match="alpha"):
        periodic_orbit(0.0, -1.0, kstar=K)
    with pytest.raises(ValueError, match="nu1"):
        periodic_range(nu1=100.0, kstar=K)
    with pytest.raises(ValueError, match="nu2"):
        periodic_orbit(0.1, float("nan"), kstar=K)


@pytest.mark.parametrize(("n", "alpha"), [(2, 0.05), (3, 0.3), (8, 0.1), (2, 0.49)])
def test_turning_solve(n, alpha):
    orb = orbit_with_turning(alpha, 2 * np.pi / n, kstar=K)
    assert n * orb.turning == pytest.approx(2 * np.pi, rel=1e-13)


def test_existence_condition_n_alpha_below_one():
    """Theta_0 = 2 pi alpha for the quartic: N alpha < 1 is necessary and sufficient."""
    orbit_with_turning(0.33, 2 * np.pi / 3, kstar=K)  # N alpha = 0.99
    with pytest.raises(ValueError, match="N alpha < 1"):
        orbit_with_turning(0.34, 2 * np.pi / 3, kstar=K)
    # small-oscillation limit of the turning
    orb = periodic_orbit(0.2, -(K**4) / 64 * (1 - 1e-10), kstar=K)
    assert orb.turning == pytest.approx(2 * np.pi * 0.2, rel=1e-6)


def test_non_quartic_symmetric_well(sextic_well):
    """Generic path: Theta_0 = pi alpha kstar / sqrt(-W''(kstar/2)); turning solve works."""
    alpha = 0.1
    c = sextic_well.kstar / 2
    theta0 = np.pi * alpha * sextic_well.kstar / np.sqrt(-sextic_well.d2W(c))
    lo, hi = periodic_range(well=sextic_well)
    orb = periodic_orbit(alpha, lo * (1 - 1e-9), well=sextic_well)
    assert orb.turning == pytest.approx(theta0, rel=1e-5)
    orb = orbit_with_turning(alpha, 2 * np.pi / 4, well=sextic_well)
    assert 4 * orb.turning == pytest.approx(2 * np.pi, rel=1e-13)
    s = np.linspace(0, orb.period, 999)
    psi = orb(s)
    P = sextic_well.W(psi) + orb.nu2
    assert np.max(np.abs(alpha**2 * orb.derivative(s) ** 2 / 2 - P)) < 1e-12 * np.max(P)


@pytest.mark.parametrize(("nu1", "ystar"), [(0.3, -1e-3), (0.3, -1e-20), (-0.2, 1e-12)])
def test_polynomial_path_near_the_separatrix_against_mpmath(nu1, ystar):
    """nu1 != 0: the orbit labelled by the offset of its turning point from the well of P."""
    fam = _family(QuarticWell(K), K, nu1)
    assert fam.q is not None
    orb = _build(fam, 0.1, None, ystar=ystar)
    dps = 30 + 2 * int(-np.log10(abs(ystar)))  # P ~ ystar^2 must stay resolved
    with mpmath.workdps(dps):
        k = mpmath.mpf(K)
        # the well of P in high precision, and the turning point ystar away from it
        star = mpmath.findroot(lambda x: x * (x - k) * (2 * x - k) / 2 + nu1, fam.star,
                               df=lambda x: (6 * x**2 - 6 * x * k + k**2) / 2)
        t = star + mpmath.mpf(ystar)
        nu2 = -(t**2 * (t - k) ** 2 / 4 + nu1 * t)
        a0, b0 = (mpmath.mpf(orb.a), t) if ystar < 0 else (t, mpmath.mpf(orb.b))
        ref = mp_period(0.1, nu1, nu2, a0, b0, kstar=K, dps=dps)
    assert orb.period == pytest.approx(float(ref), rel=1e-12)
