"""A critical circle under Canham-Helfrich + perimeter + adhesion: spectrum against the energy.

At a critical circle of radius R (every normal variation's first derivative vanishes) the
growth rate of the Fourier mode k >= 2 is ``-E''_k / (pi R)``, where ``E''_k`` is the second
derivative of the discrete energy along ``r(phi) = R + h cos(k phi)``: the eigenvalue of the
linearization is the Hessian in ``<f, h> = int f h dsigma`` along the normal perturbation
``cos(k phi)``, whose squared norm is ``pi R``. The second derivative is taken from central
differences of the energy alone (Richardson-extrapolated), so a wrong two-point Hessian fails.
"""

import numpy as np
import pytest

from qsa import Curve, Fourier
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter
from qsa.spectra import spectrum


def _critical_cha(c, eps, A0, l_star, a):
    # the normal velocity on a circle is constant and affine in L*: choose L* to cancel it
    def energy(L_star):
        return (CanhamHelfrich(eps) + Perimeter(1.0, L_star)
                + Adhesion(A0=A0, l_star=l_star, a=a))

    L = c.length()
    v0 = np.mean(energy(L).normal_velocity(c))
    v1 = np.mean(energy(L + 1.0).normal_velocity(c))
    return energy(L - v0 / (v1 - v0))


def _second_derivative(E, R, k, N, h=2e-3):
    e0 = E.energy(Curve.circle(R, Fourier(N)))

    def d2(step):
        ep = E.energy(Curve.polar(lambda t: R + step * np.cos(k * t), Fourier(N)))
        em = E.energy(Curve.polar(lambda t: R - step * np.cos(k * t), Fourier(N)))
        return (ep - 2 * e0 + em) / step**2

    return (4 * d2(h) - d2(2 * h)) / 3


@pytest.mark.parametrize("R, eps, A0, l_star, a", [
    (1.0, 0.1, 10.0, 0.15, 1.0),
    (1.0, 0.1, 10.0, 0.3, 1.0),
    (0.8, 0.05, 4.0, 0.2, 0.7),
])
def test_cha_circle_growth_rates_are_second_differences_of_the_energy(R, eps, A0, l_star, a):
    N = 129
    c = Curve.circle(R, Fourier(N))
    E = _critical_cha(c, eps, A0, l_star, a)
    V = E.normal_velocity(c)
    assert np.max(np.abs(V)) < 1e-10  # the circle is critical before its spectrum is tested
    s = spectrum(E, c)
    assert s.success and s.n_kernel == 2
    phi = np.arctan2(*c.positions()[::-1])
    for k in range(2, 7):
        basis = np.column_stack([np.cos(k * phi), np.sin(k * phi)])
        rate = -_second_derivative(E, R, k, N) / (np.pi * R)
        # the two eigenvectors living on mode k (normal gauge: functions of the nodes)
        proj = (basis * c.dsigma[:, None]).T @ s.eigenvectors
        weight = np.sum(proj**2, axis=0) / (np.pi * R)
        on_k = np.flatnonzero(weight > 0.99)
        assert on_k.size == 2, (k, on_k)
        lam = s.eigenvalues[on_k]
        assert np.all(np.abs(lam - rate) <= 1e-6 * abs(rate)), (k, lam, rate)
