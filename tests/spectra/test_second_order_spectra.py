"""Second-order energies through polish, spectrum and kernel_report.

Circle spectra of FunctionalizedCurvature (and of a generic SecondOrderEnergy) against the
closed form and against second differences of the energy along normal Fourier modes;
N-pulse equilibria of FunctionalizedCurvature + Perimeter from faceting pulses.
"""

import numpy as np
import pytest
from scipy.optimize import brentq

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import FunctionalizedCurvature, Perimeter
from qsa.equilibria import npulse, polish, residual_scale
from qsa.spectra import kernel_report, spectrum
from tests.helpers import coupled_second_order, fitted_order

pytestmark = pytest.mark.filterwarnings("error::qsa.spectra.NotEquilibriumWarning")


def _with_perimeter(E, R, beta):
    """``E + Perimeter(beta, L*)`` with ``L*`` making the circle of radius R an equilibrium."""
    if not beta:
        return E
    return E + Perimeter(beta, 2 * np.pi * R - E.circle_tension(R) / beta)


def _critical_radius(E, kappa_lo, kappa_hi):
    """A root of the circle tension: a critical circle of E alone (no perimeter)."""
    return 1.0 / brentq(lambda k: E.circle_tension(1.0 / k), kappa_lo, kappa_hi, xtol=1e-15)


def _with_multiplicities(lam):
    """``lambda_0`` once, every ``k >= 1`` twice, sorted decreasingly."""
    return np.sort(np.concatenate([lam[:1], np.repeat(lam[1:], 2)]))[::-1]


def _expected_unstable(lam):
    return int(lam[0] > 0) + 2 * int(np.sum(lam[2:] > 0))


FC = FunctionalizedCurvature
# (energy, R, beta): stable and unstable circles, with and without a perimeter penalty
FC_CIRCLES = {
    "perimeter-stable": (FC(alpha=0.15, eta=1.0, kstar=2.0), 0.4, 20.0),
    "perimeter-spinodal": (FC(alpha=0.15, eta=3.0, kstar=3.0), 0.7, 2.0),
    "perimeter-unstable": (FC(alpha=0.1, eta=1.0, kstar=5.0), 1.0, 5.0),
    "perimeter-eta0": (FC(alpha=0.2, eta=0.0, kstar=2.0), 0.8, 1.0),
    "critical": (FC(alpha=0.1, eta=1.0, kstar=5.0), None, 0.0),
}


def _fc_circle(name, grid):
    E, R, beta = FC_CIRCLES[name]
    if R is None:
        R = _critical_radius(E, 3.5, 4.5)
    return _with_perimeter(E, R, beta), Curve.circle(R, grid), E.circle_eigenvalues(
        R, (grid.N - 1) // 2, beta)


@pytest.mark.parametrize("name", FC_CIRCLES)
def test_functionalized_circle_fourier_matches_closed_form(name):
    energy, c, lam = _fc_circle(name, Fourier(33))
    s = spectrum(energy, c)
    assert s.success and s.status == 0 and s.spurious.size == 0
    exact = _with_multiplicities(lam)
    ev = np.sort(s.eigenvalues)[::-1]
    nz = exact != 0
    assert np.all(np.abs(ev[nz] - exact[nz]) <= 1e-8 * np.abs(exact[nz]))
    assert np.all(np.abs(ev[~nz]) <= s.kernel_tol)
    assert s.n_kernel == 2 and s.n_unstable == _expected_unstable(lam)


def test_functionalized_circle_cases_cover_stable_and_unstable():
    counts = {n: _expected_unstable(_fc_circle(n, Fourier(33))[2]) for n in FC_CIRCLES}
    assert counts["perimeter-stable"] == 0 and counts["perimeter-unstable"] > 4
    assert counts["critical"] > 0
    # the multiplier term matters at the critical circle: Lambda_3 = W'(W'' - eta) != 0
    _, c, _ = _fc_circle("critical", Fourier(33))
    assert abs(kernel_report(FC_CIRCLES["critical"][0], c).multipliers[2]) > 1.0


def test_generic_second_order_circle_matches_closed_form():
    """All six second partials non-zero in F; F_qp and F_pk drop out of the circle spectrum."""
    E = coupled_second_order()
    R, beta, N = 0.9, 3.0, 41
    energy, c = _with_perimeter(E, R, beta), Curve.circle(R, Fourier(N))
    lam = E.circle_eigenvalues(R, (N - 1) // 2, beta)
    s = spectrum(energy, c)
    exact = _with_multiplicities(lam)
    ev = np.sort(s.eigenvalues)[::-1]
    nz = exact != 0
    assert np.all(np.abs(ev[nz] - exact[nz]) <= 1e-8 * np.abs(exact[nz]))
    assert s.n_kernel == 2


@pytest.mark.parametrize("name", ["perimeter-stable", "critical"])
def test_functionalized_circle_fd_second_order(name):
    Ns = [64, 128, 256]
    modes = [0, 2, 3, 4, 5]
    errs = []
    for N in Ns:
        energy, c, lam = _fc_circle(name, FiniteDifference(N))
        ev = spectrum(energy, c).eigenvalues
        errs.append(max(np.min(np.abs(ev - lam[k])) / abs(lam[k]) for k in modes))
    assert fitted_order(Ns, errs) == pytest.approx(2.0, abs=0.2)


@pytest.mark.parametrize("name", ["critical", "perimeter-unstable"])
def test_growth_rates_are_second_differences_of_the_energy(name):
    """lambda_k = -E''_k / (pi R) (k >= 2) and lambda_0 = -E''_0 / (2 pi R).

    ``E''_k`` is the second derivative of the energy along the curves r = R + eps cos(k theta);
    their normal displacement is eps cos(k theta) to first order. At an equilibrium the
    extrinsic gradient -V^n vanishes, so the second-order part of the displacement (and the
    length change it brings) does not contribute: no length constraint is needed, with or
    without a perimeter penalty. ``int cos^2 dsigma = pi R`` (``2 pi R`` for k = 0).
    """
    grid = Fourier(65)
    energy, c, _ = _fc_circle(name, grid)
    R = 1.0 / c.kappa[0]
    ev = spectrum(energy, c).eigenvalues
    for k in (0, 2, 3, 4, 5):
        def E(eps):
            return energy.energy(Curve.polar(lambda t: R + eps * np.cos(k * t), grid))

        eps = 1e-4 * R
        d2 = [(E(h) - 2 * E(0.0) + E(-h)) / h**2 for h in (eps, 2 * eps)]
        second = (4 * d2[0] - d2[1]) / 3  # Richardson: O(eps^4)
        rate = -second / ((2 if k == 0 else 1) * np.pi * R)
        nearest = ev[np.argmin(np.abs(ev - rate))]
        assert abs(nearest - rate) <= 1e-6 * abs(rate), (k, nearest, rate)


# ---------------------------------------------------------------------- N-pulses
ALPHA, KSTAR, ETA, BETA = 0.2, 5.0, 1.0, 5.0


def _fc_npulse(n, grid, shift=0.0, **kw):
    """A faceting N-pulse (nu1 = 0) as guess; the perimeter makes it an exact equilibrium
    for shift = 0 (L* = L + eta nu2 / beta, module docstring of functionalized.py)."""
    eq = npulse(n, ALPHA, kstar=KSTAR, grid=grid)
    p = eq.params
    L_star = p["L"] + ETA * p["nu2"] / BETA + shift
    energy = FunctionalizedCurvature(ALPHA, ETA, KSTAR) + Perimeter(BETA, L_star)
    return eq, energy, polish(energy, eq.curve, **kw)


@pytest.mark.parametrize("n", [3, 4])
def test_faceting_pulses_are_functionalized_equilibria(n):
    eq, energy, res = _fc_npulse(n, None)  # the grid resolving the faceting pulse to 1e-14
    # the faceting pulse itself, before polishing
    V = energy.normal_velocity(eq.curve)
    assert np.abs(V).max() <= 1e-6 * residual_scale(energy, eq.curve)
    assert res.success and res.residual <= 1e-8 * res.residual_scale
    assert np.abs(res.multipliers).max() < 1e-10  # Z = 0: mu = 0
    assert np.abs(res.curve.kappa - eq.curve.kappa).max() < 1e-6 * KSTAR
    kr = kernel_report(energy, res.curve)
    assert kr.kernel_dimension == 3 and kr.expected_kernel_dimension == 3
    assert kr.lagrange_kernel < 1e-7
    s = spectrum(energy, res.curve)
    assert s.status == 0 and s.n_kernel == 3 and s.n_unstable == 0


def test_functionalized_npulse_off_the_faceting_family():
    """Another perimeter: the equilibrium leaves Z = 0 and Lambda_3 != 0; (nabla_s kappa, 0)
    is in the kernel of L_Lambda, not of nabla^2 E."""
    eq, energy, res = _fc_npulse(4, Fourier(101), shift=0.05)
    assert res.success and res.residual <= 1e-8 * res.residual_scale
    lam3 = res.multipliers[2]
    assert abs(lam3) > 1e-2 and np.abs(res.multipliers[:2]).max() < 1e-10
    kr = kernel_report(energy, res.curve)
    assert kr.kernel_dimension == 3
    assert kr.lagrange_kernel < 1e-7
    assert kr.energy_kernel == pytest.approx(kr.energy_kernel_predicted, rel=1e-2)
    assert kr.energy_kernel > 10 * kr.lagrange_kernel
    s = spectrum(energy, res.curve)
    assert s.status == 0 and s.n_kernel == 3


def test_functionalized_npulse_converges_at_order_two_on_fd():
    _, _, ref = _fc_npulse(4, Fourier(121), shift=0.05)
    Ns = [96, 192, 384]
    errs = []
    for N in Ns:
        _, energy, res = _fc_npulse(4, FiniteDifference(N), shift=0.05)
        assert res.success
        errs.append([abs(res.multipliers[2] - ref.multipliers[2]),
                     abs(res.curve.length() - ref.curve.length()),
                     abs(energy.energy(res.curve) - ref.energy.energy(ref.curve))])
    for e in np.array(errs).T:
        assert fitted_order(Ns, e) == pytest.approx(2.0, abs=0.2)


def test_functionalized_npulse_spectral_on_fourier():
    _, _, ref = _fc_npulse(4, Fourier(121), shift=0.05)
    _, _, res = _fc_npulse(4, Fourier(81), shift=0.05)
    assert abs(res.multipliers[2] - ref.multipliers[2]) < 1e-8
    assert abs(res.curve.length() - ref.curve.length()) < 1e-9


def test_functionalized_npulse_slowest_eigenvalue_converges_spectrally_on_fourier():
    """The slowest decaying eigenvalue of J at the 3-pulse off the faceting family: errors
    fall by more than 100x from N = 61 to 81 (exponential convergence), then to 1e-8."""
    def slowest(N):
        _, energy, res = _fc_npulse(3, Fourier(N), shift=0.05)
        s = spectrum(energy, res.curve)
        lam = s.eigenvalues
        return lam[int(np.argmax((lam < -1.0) & ~s.is_kernel))]

    ref = slowest(121)
    errs = [abs(slowest(N) - ref) / abs(ref) for N in (61, 81)]
    assert errs[1] < 1e-7 and errs[0] > 100 * errs[1]
