"""Newton polishing: exact Jacobian, quadratic convergence, agreement with N-pulses, orders."""

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import CanhamHelfrich, Faceting, FunctionalizedCurvature, Perimeter
from qsa.equilibria import circle, npulse, splice_polygon
from qsa.equilibria.newton import MESSAGES, PolishResult, normal_velocity, polish
from qsa.equilibria.system import EquilibriumSystem
from qsa.linalg import to_dense
from tests.helpers import (
    assert_quadratic_convergence,
    assert_status_convention,
    fd_jacobian,
    fitted_order,
    skew_curve,
)

K = 5.0


@pytest.mark.parametrize("kind", [Fourier, FiniteDifference])
@pytest.mark.parametrize("which", ["faceting", "helfrich"])
def test_jacobian_against_central_differences(kind, which):
    c = skew_curve(kind(41))
    E = (Faceting(0.1, K) if which == "faceting" else CanhamHelfrich(0.7)) + Perimeter(5.0, 6.0)
    S = EquilibriumSystem(E, c)
    x = S.pack(c)
    x[S.N + 1:] = [0.1, -0.2, 0.3]  # the unfolding columns are checked too
    J = to_dense(S.jacobian(x))
    Jfd = fd_jacobian(S, x)
    assert J.shape == (S.N + 4, S.N + 4)
    assert np.max(np.abs(J - Jfd)) < 1e-7 * np.max(np.abs(J))
    # a wrong term would show: drop the d mu/dL correction and the check fails
    assert np.max(np.abs(J[:, S.N] - Jfd[:, S.N])) < 1e-6 * np.max(np.abs(Jfd[:, S.N]))


def test_fast_normal_velocity_matches_energy():
    for grid in (Fourier(41), FiniteDifference(64)):
        c = skew_curve(grid)
        for E in (Faceting(0.1, K) + Perimeter(5.0, 6.0), CanhamHelfrich(0.3)):
            assert np.allclose(normal_velocity(E, c), E.normal_velocity(c), rtol=0,
                               atol=1e-10 * np.max(np.abs(E.normal_velocity(c))))


def test_npulse_is_reproduced_and_multipliers():
    eq = npulse(3, 0.15, grid=Fourier(127), nu1=0.2)
    r = polish(eq.energy, eq.curve)
    assert isinstance(r, PolishResult) and r.success and r.status == 0, r.message
    assert_status_convention(r, MESSAGES)
    assert r.kind == "polished"
    # the semi-analytic N-pulse is exact up to its quadrature: same state
    assert np.max(np.abs(r.curve.kappa - eq.curve.kappa)) < 1e-9
    assert r.params["L"] == pytest.approx(eq.params["L"], rel=1e-12)
    assert r.residual <= 1e-10 * r.residual_scale
    assert r.closure < 1e-12
    assert np.allclose(r.multipliers, [0.0, 0.0, -0.2], atol=1e-9)
    assert r.params["nu1"] == pytest.approx(0.2, abs=1e-9)
    assert r.params["nu2"] == pytest.approx(eq.params["nu2"], abs=1e-9)
    assert np.max(np.abs(r.unfolding)) < 1e-9


def test_quadratic_convergence_from_perturbed_npulse():
    eq = npulse(3, 0.15, grid=Fourier(127))
    c, s = eq.curve, eq.curve.grid.s
    guess = Curve(c.kappa + 0.05 * np.cos(2 * np.pi * s) + 0.03 * np.sin(6 * np.pi * s + 0.2),
                  1.01 * c.g, c.grid, c.theta0, c.origin)
    r = polish(eq.energy, guess)
    assert r.success, r.message
    assert r.n_newton == len(r.history) - 1 and r.n_newton <= 8
    assert r.n_lu == r.n_newton and r.n_iter == r.n_newton  # one LU per step; the old name
    assert_quadratic_convergence(r)
    # same equilibrium up to the shift fixed by the phase condition
    assert r.params["L"] == pytest.approx(eq.params["L"], rel=1e-12)
    assert np.sort(r.curve.kappa).max() == pytest.approx(eq.curve.kappa.max(), rel=1e-3)
    assert r.energy.energy(r.curve) == pytest.approx(eq.energy.energy(eq.curve), rel=1e-11)


def test_quadratic_convergence_from_splice():
    sp = splice_polygon(np.full(4, np.pi / 2), [1.0] * 4, 0.2, grid=Fourier(255), kstar=K)
    r = polish(sp.energy, sp.curve)
    assert r.success, r.message
    assert_quadratic_convergence(r)
    assert r.residual <= 1e-10 * r.residual_scale and r.closure < 1e-12
    # a square: four-fold symmetric kappa
    k = r.curve.kappa
    assert np.max(np.abs(r.curve.grid.interpolate(k, r.curve.grid.s + 0.25) - k)) < 1e-8


def test_fd_converges_to_fourier_at_order_two():
    ref = npulse(3, 0.2, kstar=K)
    rF = polish(ref.energy, ref.curve)
    assert rF.success
    Ns = [96, 192, 384, 768]
    eL, ek = [], []
    for N in Ns:
        eq = npulse(3, 0.2, grid=FiniteDifference(N), kstar=K)
        r = polish(eq.energy, eq.curve)
        assert r.success, r.message
        assert r.closure < 1e-10
        eL.append(abs(r.params["L"] - rF.params["L"]))
        kF = rF.curve.grid.interpolate(rF.curve.kappa, eq.curve.grid.s)
        ek.append(np.max(np.abs(r.curve.kappa - kF)))
    assert fitted_order(Ns, eL) == pytest.approx(2.0, abs=0.1)
    assert fitted_order(Ns, ek) == pytest.approx(2.0, abs=0.1)


@pytest.mark.parametrize("grid", [Fourier(65), FiniteDifference(128)])
def test_circle_stays_put_and_perturbed_circle_returns(grid):
    eq = circle(1.0, 0.1, grid=grid, kstar=K, beta=5.0)
    r = polish(eq.energy, eq.curve)
    assert r.success and r.n_newton == 0
    assert np.array_equal(r.curve.kappa, eq.curve.kappa)
    guess = Curve.polar(lambda t: 1 + 0.006 * np.cos(3 * t) + 0.004 * np.sin(2 * t), grid)
    r = polish(eq.energy, guess)
    assert r.success, r.message
    assert np.max(np.abs(r.curve.kappa - 1.0)) < 1e-10
    assert r.params["L"] == pytest.approx(2 * np.pi, rel=1e-12)
    assert r.multipliers[2] == pytest.approx(float(eq.energy.terms()[0].well.dW(1.0)), rel=1e-8)


def test_helfrich_circle_radius():
    # Canham-Helfrich + perimeter: circle of radius R when beta (2 pi R - L*) = eps/(2 R^2)
    eps, beta, R = 0.5, 2.0, 1.3
    L_star = 2 * np.pi * R - eps / (2 * R**2) / beta
    E = CanhamHelfrich(eps) + Perimeter(beta, L_star)
    guess = Curve.polar(lambda t: 1.25 + 0.01 * np.cos(2 * t), FiniteDifference(100))
    r = polish(E, guess)
    assert r.success, r.message
    assert np.allclose(r.curve.kappa, 1 / R, atol=1e-10)


def test_nonconstant_g_is_reparameterized():
    eq = npulse(4, 0.2, grid=Fourier(101), kstar=K)
    c = eq.curve
    grid = c.grid
    # t -> s(t) = t + 0.05 sin(2 pi t): kappa(s(t)), g = L s'(t)
    s_of_t = grid.s + 0.05 * np.sin(2 * np.pi * grid.s)
    warped = Curve(grid.interpolate(c.kappa, s_of_t),
                   c.length() * (1 + 0.1 * np.pi * np.cos(2 * np.pi * grid.s)), grid,
                   c.theta0, c.origin)
    r = polish(eq.energy, warped)
    assert r.success and "reparameterized" in r.message
    assert np.ptp(r.curve.g) == 0
    assert np.max(np.abs(r.curve.kappa - c.kappa)) < 1e-8


def test_failure_is_reported_not_raised():
    eq = npulse(3, 0.15, grid=Fourier(101))
    c, s = eq.curve, eq.curve.grid.s
    guess = c.with_kappa(c.kappa + 0.05 * np.cos(2 * np.pi * s))
    r = polish(eq.energy, guess, maxiter=1)
    assert not r.success and r.status == -1 and "maximum" in r.message
    assert_status_convention(r, MESSAGES)
    assert r.n_newton == 1 and r.history.size == 2 and r.history[1] < r.history[0]
    assert np.all(np.isfinite(r.curve.kappa))


def _functionalized_off_family(n, grid, shift=0.05):
    """A faceting N-pulse as guess for FunctionalizedCurvature + Perimeter with L* moved off
    the faceting family (sixth order in kappa: a full Newton step raises max|V^n| ~100x)."""
    eq = npulse(n, 0.2, kstar=K, grid=grid)
    L_star = eq.params["L"] + 1.0 * eq.params["nu2"] / 5.0 + shift
    return FunctionalizedCurvature(0.2, 1.0, K) + Perimeter(5.0, L_star), eq.curve


@pytest.mark.parametrize("n, shift", [(3, 0.05), (3, 0.2), (4, 0.05), (4, 0.2)])
def test_line_search_takes_full_steps_on_sixth_order_problems(n, shift):
    energy, guess = _functionalized_off_family(n, Fourier(101), shift)
    r = polish(energy, guess)
    free = polish(energy, guess, line_search=False)
    assert r.success and r.residual <= 1e-8 * r.residual_scale
    assert r.n_newton <= 7 and r.n_newton <= free.n_newton + 1
    # the first full step raises the residual: the residual is not the merit
    assert r.history[1] > 10 * r.history[0]


def test_line_search_keeps_faceting_step_counts():
    eq = npulse(3, 0.15, grid=Fourier(127))
    c, s = eq.curve, eq.curve.grid.s
    r = polish(eq.energy, c.with_kappa(c.kappa * (1 + 0.02 * np.cos(6 * np.pi * s))))
    assert r.success and r.n_newton <= 5
    rect = splice_polygon([np.pi / 2] * 4, [1.0, 1.5, 1.0, 1.5], 0.1, grid=Fourier(255))
    r = polish(rect.energy, rect.curve)
    assert r.success and r.n_newton <= 6


def test_params_record_every_scalar_parameter_of_the_energy():
    energy, guess = _functionalized_off_family(4, Fourier(101))
    r = polish(energy, guess)
    p = r.params
    assert (p["alpha"], p["eta"], p["kstar"], p["beta"]) == (0.2, 1.0, K, 5.0)
    assert p["L_star"] == energy.terms()[1].L_star
    assert p["nu2"] == pytest.approx(5.0 * (r.curve.length() - p["L_star"]), rel=1e-12)
    assert all(isinstance(v, float) for v in p.values())


def test_polish_never_returns_a_worse_state_than_its_guess():
    energy, guess = _functionalized_off_family(3, Fourier(101))
    r = polish(energy, guess, maxiter=1, globalize=False)  # Newton alone
    assert not r.success and r.status == -1
    assert r.history[1] > r.history[0]  # the step was taken (and raised the residual) ...
    assert r.residual / r.residual_scale <= r.history[0] * (1 + 1e-12)  # ... but not returned
    assert np.array_equal(r.curve.kappa, guess.kappa)


def test_bad_input_raises():
    eq = npulse(3, 0.15, grid=Fourier(101))
    with pytest.raises(ValueError, match="tol"):
        polish(eq.energy, eq.curve, tol=0)
    with pytest.raises(ValueError, match="maxiter"):
        polish(eq.energy, eq.curve, maxiter=-1)
    with pytest.raises(ValueError, match="curve"):
        polish(eq.energy, eq.curve.positions())
    with pytest.raises(ValueError, match="energy"):
        polish(lambda c: 0.0, eq.curve)


def test_summary_is_json_ready():
    import json

    eq = npulse(3, 0.15, grid=Fourier(101))
    r = polish(eq.energy, eq.curve)
    d = json.loads(json.dumps(r.summary()))
    assert d["status"] == 0 and d["kind"] == "polished" and len(d["history"]) == r.n_newton + 1


def test_cli_polish_option(capsys):
    import argparse
    import json

    from qsa.commands import equilibrium

    parser = argparse.ArgumentParser(prog="qsa")
    equilibrium.add_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["equilibrium", "splice", "--angles", "90", "90", "90", "90",
                              "--facets", "1", "1", "1", "1", "--alpha", "0.2", "--N", "255",
                              "--polish", "--json"])
    assert args.func(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["kind"] == "polished" and out["success"] and out["status"] == 0
    assert out["residual"] <= 1e-10 * out["residual_scale"] and out["closure"] < 1e-12
    assert out["params"]["d_min"] > 0  # construction parameters are kept


class _TotalCurvatureSquared:
    """``E = c/2 (int kappa ds)^2``: its Hessian is low rank in the kappa block."""

    def __new__(cls, coef):
        import scipy.sparse as sps

        from qsa.energies.base import Energy
        from qsa.linalg import SparsePlusLowRank

        class TotalCurvatureSquared(Energy):
            def energy(self, c):
                return 0.5 * coef * (c.grid.weights @ c.kappa) ** 2

            def gradient(self, c):
                m = c.grid.weights @ c.kappa
                return np.concatenate([coef * m / c.g, np.zeros(c.N)])

            def hessian(self, c):
                N = c.N
                U = np.concatenate([coef / c.g, np.zeros(N)])
                V = np.concatenate([c.grid.weights, np.zeros(N)])
                if c.grid.sparse:
                    return SparsePlusLowRank(sps.csr_matrix((2 * N, 2 * N)), U, V)
                return np.outer(U, V)

        return TotalCurvatureSquared()


@pytest.mark.parametrize("kind", [Fourier, FiniteDifference])
def test_jacobian_with_low_rank_kappa_hessian(kind):
    c = skew_curve(kind(41))
    E = Faceting(0.1, K) + Perimeter(5.0, 6.0) + _TotalCurvatureSquared(0.7)
    S = EquilibriumSystem(E, c)
    x = S.pack(c)
    J = to_dense(S.jacobian(x))
    r = J.shape[0] - x.size  # low-rank terms are carried as extra unknowns z = Q^T dkappa
    assert r == (1 if kind is FiniteDifference else 0)
    if r:
        # eliminate z: the Schur complement is the Jacobian of F
        A, B, C, D = J[:-r, :-r], J[:-r, -r:], J[-r:, :-r], J[-r:, -r:]
        J = A - B @ np.linalg.solve(D, C)
    Jfd = fd_jacobian(S, x)
    assert np.max(np.abs(J - Jfd)) < 1e-7 * np.max(np.abs(J))
