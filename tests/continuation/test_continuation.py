"""Continuation: folds of the circle branch (exact) and of the 3-pulse branch (semi-analytic)."""

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from qsa import FiniteDifference, Fourier
from qsa.continuation import Branch, continuation
from qsa.continuation.branch import MESSAGES
from qsa.energies import Faceting, Perimeter
from qsa.equilibria import circle, npulse
from tests.helpers import assert_status_convention

K, BETA, ALPHA = 5.0, 5.0, 0.1


def factory(alpha=ALPHA):
    return lambda L_star: Faceting(alpha, K) + Perimeter(BETA, L_star)


def circle_L_star(k):
    """L* of the circle of curvature k: beta (2 pi R - L*) = k W'(k) - W(k)."""
    return 2 * np.pi / k - k**2 * (k - K) * (3 * k - K) / (4 * BETA)


def circle_fold():
    """dL*/dR = 0  <=>  k^3 W''(k) = -2 pi beta (first fold, k in (1.5, 2))."""
    k = brentq(lambda k: k**3 * 0.5 * (6 * k * k - 6 * K * k + K * K) + 2 * np.pi * BETA,
               1.5, 2.0, xtol=1e-15)
    return k, circle_L_star(k)


def test_circle_branch_passes_the_fold_and_locates_it():
    eq = circle(0.77, ALPHA, grid=Fourier(17), kstar=K, beta=BETA)
    Ls0 = eq.params["L_star"]
    b = continuation(factory(), eq.curve, "L_star", (Ls0, 3.0, -0.1))
    assert isinstance(b, Branch) and b.success, b.message
    kf, Lf = circle_fold()
    assert len(b.folds) == 1
    fold = b.folds[0]
    assert fold.param == pytest.approx(Lf, abs=1e-9)
    assert fold.L == pytest.approx(2 * np.pi / kf, abs=1e-6)
    assert "fold" in b.message and f"{Lf:.6f}"[:6] in b.message
    # passed it: p goes down, turns, and comes back up past the start
    v = b.values
    i = fold.index
    assert np.all(np.diff(v[: i + 1]) < 0) and np.all(np.diff(v[i + 1:]) > 0)
    assert v[-1] > Ls0
    # dp/ds and det F_x change sign at the fold only
    dp = np.array([p.dp_ds for p in b.points])
    assert np.all(dp[: i + 1] < 0) and np.all(dp[i + 1:] > 0)
    det = np.array([p.det_sign for p in b.points])
    assert det[i] != det[i + 1] and len(set(det[: i + 1])) == 1 and len(set(det[i + 1:])) == 1
    assert b.branch_points == ()
    # every point is a circle on the exact branch L*(k)
    for p in b.points:
        k = p.curve.kappa
        assert np.ptp(k) < 1e-10
        assert p.param == pytest.approx(circle_L_star(k[0]), abs=1e-9)
        assert p.equilibrium.residual <= 1e-9 * max(p.equilibrium.residual_scale, 1.0)


def test_natural_continuation_follows_circles_and_stops_at_fold():
    eq = circle(0.77, ALPHA, grid=Fourier(17), kstar=K, beta=BETA)
    Ls0 = eq.params["L_star"]
    b = continuation(factory(), eq.curve, "L_star", (Ls0, 3.5, -0.1), method="natural")
    _, Lf = circle_fold()
    assert not b.success and b.status == -3 and "fold" in b.message
    assert_status_convention(b, MESSAGES)
    assert b.values[-1] >= Lf > b.values[-1] - 0.1 - 1e-12
    for p in b.points:
        assert p.param == pytest.approx(circle_L_star(p.curve.kappa[0]), abs=1e-9)
    # below the fold-free range it covers everything
    b2 = continuation(factory(), eq.curve, "L_star", np.linspace(Ls0, 4.0, 5), method="natural")
    assert b2.success and np.allclose(b2.values, np.linspace(Ls0, 4.0, 5))
    assert_status_convention(b2, MESSAGES)


def test_three_pulse_branch_fold_matches_semi_analytic():
    """3-pulses exist for every nu1 in a range; L*(nu1) has a minimum = a fold in L*."""
    alpha = 0.2
    res = minimize_scalar(
        lambda nu1: npulse(3, alpha, nu1=nu1, grid=Fourier(33), kstar=K).params["L_star"],
        bracket=(0.06, 0.09, 0.12), tol=1e-10)
    eq = npulse(3, alpha, grid=Fourier(129), kstar=K, beta=BETA)
    Ls0 = eq.params["L_star"]
    b = continuation(factory(alpha), eq.curve, "L_star", (Ls0, Ls0 - 0.2, -0.02), max_steps=20,
                     stability=False)
    assert b.success, b.message
    assert len(b.folds) == 1
    assert b.folds[0].param == pytest.approx(res.fun, abs=1e-9)
    # each point is a 3-pulse: nu1 = -Lambda_3 reproduces its L* semi-analytically
    for p in b.points[1:4]:
        nu1 = -p.equilibrium.multipliers[2]
        ref = npulse(3, alpha, nu1=nu1, grid=Fourier(33), kstar=K, beta=BETA)
        assert p.param == pytest.approx(ref.params["L_star"], abs=1e-8)


def test_fd_fold_converges_at_order_two():
    alpha = 0.2
    ref = minimize_scalar(
        lambda nu1: npulse(3, alpha, nu1=nu1, grid=Fourier(33), kstar=K).params["L_star"],
        bracket=(0.06, 0.09, 0.12), tol=1e-10).fun
    errs = []
    for N in (150, 300):
        eq = npulse(3, alpha, grid=FiniteDifference(N), kstar=K, beta=BETA)
        Ls0 = eq.params["L_star"]
        b = continuation(factory(alpha), eq.curve, "L_star", (Ls0, Ls0 - 0.2, -0.02),
                         max_steps=20, stability=False)
        assert len(b.folds) == 1
        errs.append(abs(b.folds[0].param - ref))
    assert np.log2(errs[0] / errs[1]) == pytest.approx(2.0, abs=0.15)


def test_stability_hook_is_called_at_every_point():
    calls = []

    def hook(energy, curve):
        calls.append(energy.terms()[1].L_star)
        # analytic k = 0 eigenvalue of the circle: -k (k^3 W''(k) + 2 pi beta)
        k = curve.kappa[0]
        lam0 = -k * (k**3 * 0.5 * (6 * k * k - 6 * K * k + K * K) + 2 * np.pi * BETA)
        return int(lam0 > 0)

    eq = circle(0.77, ALPHA, grid=Fourier(17), kstar=K, beta=BETA)
    b = continuation(factory(), eq.curve, "L_star", (eq.params["L_star"], 3.0, -0.1),
                     stability=hook)
    nu = b.n_unstable
    assert nu is not None and len(calls) == len(b.points)
    i = b.folds[0].index
    # the k = 0 mode changes stability exactly at the fold
    assert np.all(nu[: i + 1] == 0) and np.all(nu[i + 1:] == 1)
    assert np.allclose(calls, b.values)


def test_stability_true_uses_spectra_or_says_it_is_missing():
    import qsa.spectra

    eq = circle(0.77, ALPHA, grid=Fourier(17), kstar=K, beta=BETA)
    args = (factory(), eq.curve, "L_star", (eq.params["L_star"], 3.0, -0.1))
    if not hasattr(qsa.spectra, "spectrum"):
        with pytest.raises(ValueError, match="spectra"):
            continuation(*args, stability=True)
        return
    b = continuation(*args, stability=True)
    # circle spectrum (Conventions and errata, section 4): mode k >= 2 (double) is unstable when
    # alpha^2 k^2 k0^2 + W''(k0) < 0, mode 0 when k0^3 W''(k0) + 2 pi beta < 0
    for p in b.points:
        k0 = p.curve.kappa[0]
        W2 = 0.5 * (6 * k0**2 - 6 * K * k0 + K**2)
        ks = np.arange(2, 9)  # resolved by Fourier(17)
        expected = 2 * int(np.sum(ALPHA**2 * ks**2 * k0**2 + W2 < 0))
        expected += int(k0**3 * W2 + 2 * np.pi * BETA < 0)
        assert p.n_unstable == expected


def test_bad_input():
    eq = circle(0.77, ALPHA, grid=Fourier(17), kstar=K, beta=BETA)
    with pytest.raises(ValueError, match="energy_factory"):
        continuation(None, eq.curve, "L_star", (4.0, 3.0, -0.1))
    with pytest.raises(ValueError, match="method"):
        continuation(factory(), eq.curve, "L_star", (4.0, 3.0, -0.1), method="secant")
    with pytest.raises(ValueError, match="step"):
        continuation(factory(), eq.curve, "L_star", (4.0, 3.0, 0.1))
    with pytest.raises(ValueError, match="monotone"):
        continuation(factory(), eq.curve, "L_star", [4.0, 3.0, 3.5])
    with pytest.raises(ValueError, match="stability"):
        continuation(factory(), eq.curve, "L_star", (4.0, 3.0, -0.1), stability="yes")
    with pytest.raises(ValueError, match="not close enough"):
        continuation(factory(), eq.curve, "L_star", (1.0, 3.0, 0.1), maxiter=0)


# ---------------------------------------------------- a second-order energy in eta
def _functionalized_pulse_branch(method, values):
    """3-pulses of FunctionalizedCurvature + Perimeter in eta, from the faceting pulse (an
    exact equilibrium at eta = 1 for L* = L + nu2 / beta); off the faceting family for
    eta != 1. The relative residual's round-off floor is ~1e-10 here (sixth order)."""
    from qsa.energies import FunctionalizedCurvature

    eq = npulse(3, 0.2, kstar=K, grid=Fourier(81))
    L_star = eq.params["L"] + eq.params["nu2"] / BETA

    def fc(eta):
        return FunctionalizedCurvature(0.2, eta, K) + Perimeter(BETA, L_star)

    return fc, eq, continuation(fc, eq.curve, "eta", values, method=method)


@pytest.mark.parametrize("method", ["pseudo-arclength", "natural"])
def test_functionalized_npulse_branch_in_eta(method):
    from qsa.equilibria import polish

    values = (1.0, 1.6, 0.15) if method == "pseudo-arclength" else np.linspace(1.0, 1.6, 5)
    fc, eq, b = _functionalized_pulse_branch(method, values)
    assert b.success and b.status == 0, b.message
    assert_status_convention(b, MESSAGES)
    ps = np.array([pt.param for pt in b.points])
    assert ps[0] == 1.0 and ps[-1] >= 1.6 - 1e-12 and len(b.points) >= 4
    assert not b.bifurcations and not b.folds
    for pt in b.points:
        e = pt.equilibrium
        assert e.success and e.residual <= 1e-8 * e.residual_scale
        assert pt.n_unstable == 0
        assert e.params["eta"] == pytest.approx(pt.param, rel=1e-14)
    # at eta = 1 the faceting pulse (Lambda_3 = 0); beyond, Lambda_3 moves off 0 monotonically
    lam3 = np.array([pt.equilibrium.multipliers[2] for pt in b.points])
    assert abs(lam3[0]) < 1e-8 and np.all(np.diff(lam3) < 0)
    # a point of the branch is the equilibrium polish finds from the faceting guess
    direct = polish(fc(ps[2]), eq.curve)
    assert direct.success
    assert abs(direct.curve.length() - b.points[2].equilibrium.curve.length()) < 1e-9
