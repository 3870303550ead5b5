"""SecondOrderFlow: the DAE of any local energy (second order included) plus perimeters.

Exact Jacobian, identity with FacetingFlow on the faceting energy, V equal to the energy's
own discrete V^n, energy dissipation at O(h^2), monotone energy along solve_flow (both
steppers), circle modes against the closed-form spectrum (order 2 in N), relaxation near
functionalized N-pulses against the slowest eigenvalue of J, checkpoint and resume.
"""

import zlib

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import (
    Adhesion,
    CanhamHelfrich,
    Faceting,
    FunctionalizedCurvature,
    Perimeter,
)
from qsa.equilibria import npulse, polish
from qsa.flows import FacetingFlow, SecondOrderFlow, flow_model, solve_flow
from qsa.flows.solve import MESSAGES
from qsa.studies import mode_amplitude, mode_decay
from tests.helpers import (
    assert_status_convention,
    coupled_second_order,
    fitted_order,
    numerical_jacobians,
    smooth_curve,
)

FC = FunctionalizedCurvature
MODELS = {
    "functionalized": SecondOrderFlow(FC(0.3, 1.0, 2.0) + Perimeter(5.0, 6.0)),
    "coupled": SecondOrderFlow(coupled_second_order() + Perimeter(2.0, 7.0)),
    "coupled-edge": SecondOrderFlow(coupled_second_order("edge")),
    "faceting": SecondOrderFlow(Faceting(0.3, 2.0) + Perimeter(5.0, 6.0)),
    "sum": SecondOrderFlow(FC(0.3, 0.5, 2.0) + CanhamHelfrich(0.2) + Perimeter(1.0, 6.0)
                           + Perimeter(2.0, 7.0)),
}
# the critical circle R = 1/kstar of FC(0.3, 1.1, 1): mode 2 grows, modes 3, 4, ... decay
CRITICAL = FC(0.3, 1.1, 1.0)
CRITICAL_BETA = 2.0


def _critical_flow():
    return SecondOrderFlow(CRITICAL + Perimeter(CRITICAL_BETA, 2 * np.pi))


def _polar(r, N):
    th = 2 * np.pi * np.arange(8 * N) / (8 * N)
    rr = r(th)
    return rr * np.cos(th), rr * np.sin(th)


# ------------------------------------------------------------- the system
@pytest.mark.parametrize("name", MODELS)
def test_jacobian_matches_central_differences(name):
    sys = MODELS[name].setup(*smooth_curve(24))
    rng = np.random.default_rng(zlib.crc32(name.encode()))  # str hash() is salted per process
    yy = sys.y0 + 0.02 * rng.standard_normal(sys.size) * (1 + np.abs(sys.y0))
    yd = rng.standard_normal(sys.size)
    Jy, Jd = numerical_jacobians(sys, yy, yd)
    c = 2.7
    J = sys.jacobian(yy, yd, c).toarray()
    assert np.max(np.abs(J - (Jy + c * Jd))) <= 1e-7 * np.max(np.abs(Jy + c * Jd))
    # the model rows carry the energy's Hessian: a wrong d mu/dL would show here
    rows = slice(3 * sys.N, 4 * sys.N)
    assert np.max(np.abs(J[rows, -1] - Jy[rows, -1])) <= 1e-6 * np.max(np.abs(Jy[rows, -1]))


def test_faceting_energy_gives_the_faceting_flow():
    x, y = smooth_curve(64)
    a = MODELS["faceting"].setup(x, y)
    b = FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=6.0).setup(x, y)
    assert np.max(np.abs(a.y0 - b.y0)) <= 1e-14 * np.max(np.abs(b.y0))
    rng = np.random.default_rng(2)
    yy = b.y0 + 0.01 * rng.standard_normal(b.size) * (1 + np.abs(b.y0))
    yd = rng.standard_normal(b.size)
    Fb = b.residual(yy, yd)
    assert np.max(np.abs(a.residual(yy, yd) - Fb)) <= 1e-13 * np.max(np.abs(Fb))
    Ja, Jb = a.jacobian(yy, yd, 2.0), b.jacobian(yy, yd, 2.0)
    assert abs(Ja - Jb).max() <= 1e-13 * abs(Jb).max()
    assert a.energy(yy) == pytest.approx(b.energy(yy), rel=1e-14)
    assert type(flow_model(Faceting(0.3, 2.0) + Perimeter(5.0, 6.0))) is FacetingFlow


@pytest.mark.parametrize("name", ["functionalized", "coupled", "sum"])
def test_velocity_and_energy_are_the_energys_own_on_the_fd_grid(name):
    model = MODELS[name]
    sys = model.setup(*smooth_curve(64))
    u = sys.unpack(sys.y0)
    c = Curve(u["kappa"], u["L"], FiniteDifference(64))
    V = model.energy.normal_velocity(c)
    assert np.max(np.abs(sys.normal_velocity(sys.y0) - V)) <= 1e-11 * np.max(np.abs(V))
    assert sys.energy(sys.y0) == pytest.approx(model.energy.energy(c), rel=1e-13)
    # a consistent initial state: every algebraic row holds
    F = sys.residual(sys.y0, np.zeros(sys.size))
    alg = np.setdiff1d(np.arange(sys.size), sys.differential_rows)
    assert np.max(np.abs(F[alg])) <= 1e-10 * (1 + np.max(np.abs(sys.y0)))


def arclength_polar(N, a=0.04, b=0.02, scale=1.3, M=4096):
    """N nodes at equal arc length on ``r = scale (1 + a cos 3t + b sin 2t)``, to rounding.

    A sixth-order flow amplifies the interpolation error of resampled samples by
    ``N^6``; these nodes come from the spectrally accurate arc length instead.
    """
    def r(t):
        return scale * (1 + a * np.cos(3 * t) + b * np.sin(2 * t))

    def dr(t):
        return scale * (-3 * a * np.sin(3 * t) + 2 * b * np.cos(2 * t))

    t = 2 * np.pi * np.arange(M) / M
    coef = np.fft.rfft(np.hypot(r(t), dr(t)))[: M // 4] / M
    k = np.arange(1, coef.size)[:, None]
    L = 2 * np.pi * coef[0].real

    def arc(th):  # int_0^th |gamma'|
        return coef[0].real * th + np.sum(2 * coef[1:, None] / (1j * k)
                                          * (np.exp(1j * k * th) - 1), axis=0).real

    target = L * np.arange(N) / N
    th = 2 * np.pi * np.arange(N) / N
    for _ in range(30):
        step = (arc(th) - target) / np.hypot(r(th), dr(th))
        th -= step
        if np.max(np.abs(step)) < 1e-15:
            break
    return r(th) * np.cos(th), r(th) * np.sin(th)


def test_energy_dissipation_converges_at_order_two():
    """dE/dt = -int V^2 dsigma (1 + O(h^2)) for the sixth-order functionalized flow."""
    model = MODELS["functionalized"]
    Ns, errs = [100, 200, 400], []
    for N in Ns:
        sys = model.setup(*arclength_polar(N))
        yd = sys.time_derivative(sys.y0)
        d = 1e-5 / np.max(np.abs(yd[: 3 * N]))
        dEdt = (sys.energy(sys.y0 + d * yd) - sys.energy(sys.y0 - d * yd)) / (2 * d)
        assert dEdt < 0
        errs.append(abs(dEdt / -sys.dissipation(sys.y0) - 1))
    assert errs[-1] < 1e-4
    assert fitted_order(Ns, errs) == pytest.approx(2.0, abs=0.2)


def test_bad_input_raises_value_error():
    with pytest.raises(ValueError, match="Energy"):
        SecondOrderFlow(lambda c: 0.0)
    with pytest.raises(ValueError, match="Adhesion"):
        SecondOrderFlow(FC(0.1, 1.0, 5.0) + Adhesion(1.0, 0.5))
    with pytest.raises(ValueError, match="local energy"):
        SecondOrderFlow(Perimeter(1.0, 6.0))
    with pytest.raises(ValueError, match="counter-clockwise"):
        MODELS["functionalized"].setup(*smooth_curve(32)[::-1])


def test_diverged_iterate_gives_nonfinite_residual_not_exception():
    sys = MODELS["functionalized"].setup(*smooth_curve(32))
    y = sys.y0.copy()
    y[-1] = -1.0  # a negative length
    assert not np.all(np.isfinite(sys.residual(y, np.zeros(sys.size))))
    y[-1], y[2 * 32] = sys.y0[-1], np.nan
    assert not np.all(np.isfinite(sys.residual(y, np.zeros(sys.size))))


# ------------------------------------------------------------ along flows
@pytest.mark.parametrize("method", ["be", "bdf2"])
def test_energy_non_increasing_from_a_perturbed_circle(method):
    init = _polar(lambda t: 1 + 0.05 * np.cos(3 * t) + 0.02 * np.sin(5 * t), 48)
    res = solve_flow(_critical_flow(), init, 0.05, N=48, tol=1e-5, method=method)
    assert res.success and res.status == 0
    assert_status_convention(res, MESSAGES)
    E = res.energy_steps
    assert np.all(np.diff(E) <= 1e-12 * np.max(np.abs(E))), np.max(np.diff(E))
    assert E[-1] < E[0]


def _fc_npulse(n, shift, grid):
    """A faceting N-pulse polished as an equilibrium of FC + Perimeter (L* moved by shift)."""
    eq = npulse(n, 0.2, kstar=5.0, grid=grid)
    p = eq.params
    energy = FC(0.2, 1.0, 5.0) + Perimeter(5.0, p["L"] + 1.0 * p["nu2"] / 5.0 + shift)
    res = polish(energy, eq.curve)
    assert res.success
    return res


@pytest.mark.parametrize("method", ["be", "bdf2"])
def test_energy_non_increasing_from_a_perturbed_npulse(method):
    eq = _fc_npulse(3, 0.05, FiniteDifference(96))
    x, y = eq.curve.positions()
    nx, ny = eq.curve.normal()
    bump = 3e-3 * np.cos(2 * np.pi * eq.curve.grid.s)  # breaks the 3-fold symmetry
    res = solve_flow(flow_model(eq.energy), (x + bump * nx, y + bump * ny), 2e-3, N=96,
                     tol=1e-5, method=method)
    assert res.success
    E = res.energy_steps
    # variable-step BDF2 is not energy stable: in the fast transient one step may raise E
    # by a few 1e-11 of itself (the Newton tolerance's level); backward Euler never does
    rise = 1e-12 if method == "be" else 1e-9
    assert np.all(np.diff(E) <= rise * np.max(np.abs(E))), np.max(np.diff(E))
    assert E[-1] < E[0]


def _circle_mode_rate(k, N, amplitude=1e-3):
    lam = CRITICAL.circle_eigenvalues(1.0, k, CRITICAL_BETA)[k]
    T = 2.0 / abs(lam)
    res = solve_flow(_critical_flow(), _polar(lambda t: 1 + amplitude * np.cos(k * t), N), T,
                     N=N, tol=1e-8, method="bdf2", t_eval=np.linspace(0, T, 11))
    assert res.success
    assert np.all(np.diff(res.energy_steps) <= 1e-12 * np.max(np.abs(res.energy_steps)))
    amp = [mode_amplitude(*res.positions(i), k) for i in range(len(res.t))]
    return np.polyfit(res.t, np.log(amp), 1)[0], lam


def test_circle_modes_grow_and_decay_at_the_closed_form_rates_order_two():
    """The critical circle R = 1/kstar: lambda_2 > 0 (growth), lambda_4 < 0 (decay)."""
    assert CRITICAL.circle_tension(1.0) == 0.0
    Ns = [32, 64, 128]
    for k in (2, 4):
        errs = []
        for N in Ns:
            rate, lam = _circle_mode_rate(k, N)
            errs.append(abs(rate - lam) / abs(lam))
        assert np.sign(lam) == (1 if k == 2 else -1)
        assert errs[-1] < 0.02, (k, errs)
        assert fitted_order(Ns, errs) == pytest.approx(2.0, abs=0.2), (k, errs)


def test_circle_eigenvectors_relax_at_their_eigenvalues():
    """mode_decay at the critical circle: the slowest decaying mode is the length mode
    (k = 0, single); the next is the k = 3 pair."""
    eq = polish(CRITICAL + Perimeter(CRITICAL_BETA, 2 * np.pi),
                Curve.circle(1.0, FiniteDifference(96)))
    lam = CRITICAL.circle_eigenvalues(1.0, 3, CRITICAL_BETA)
    for mode, k, multiplicity in ((None, 0, 1), (5, 3, 2)):
        out = mode_decay(eq, N=96, mode=mode, amplitude=1e-4, tol=1e-9)
        assert out["success"] and out["multiplicity"] == multiplicity
        assert out["eigenvalue"] == pytest.approx(lam[k], rel=0.03)  # the FD(96) eigenvalue
        assert out["relative_error"] < 0.01, out
        assert out["max_energy_increase"] <= 0


def test_relaxation_near_a_functionalized_npulse_is_the_slowest_eigenvalue():
    """Off the faceting family (Z != 0, Lambda_3 != 0): the slowest decaying mode of J."""
    eq = _fc_npulse(3, 0.05, Fourier(101))
    out = mode_decay(eq, N=192)
    assert out["success"] and out["multiplicity"] == 2  # the 3-fold symmetry: a double pair
    assert out["relative_error"] < 0.01, out
    assert out["max_energy_increase"] <= 0


@pytest.mark.slow
def test_relaxation_near_a_functionalized_four_pulse():
    """The 4-pulse's linear regime is narrow (weak pulses, 4 alpha = 0.8 near the limit 1):
    a small amplitude and a tight tolerance."""
    out = mode_decay(_fc_npulse(4, 0.0, Fourier(101)), N=192, amplitude=5e-5, tol=2e-10)
    assert out["success"] and out["relative_error"] < 0.01, out


# ----------------------------------------------------------------- resume
@pytest.mark.parametrize("method", ["be", "bdf2"])
def test_stop_and_resume_equals_uninterrupted(tmp_path, method):
    model = _critical_flow()
    init = _polar(lambda t: 1 + 0.05 * np.cos(3 * t), 40)
    path = tmp_path / f"{method}.npz"
    T = 0.02
    full = solve_flow(model, init, T, N=40, tol=1e-4, method=method)
    part = solve_flow(model, init, T, N=40, tol=1e-4, method=method, checkpoint=path,
                      callback=lambda t, y, s: t > 0.4 * T)
    assert part.status == 1 and part.t[-1] < T
    res = solve_flow(model, None, T, tol=1e-4, method=method, resume=path)
    assert res.n_steps == full.n_steps and res.n_newton == full.n_newton
    np.testing.assert_allclose(res.states, full.states, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(res.t, full.t)
    other = SecondOrderFlow(FC(0.3, 1.2, 1.0) + Perimeter(CRITICAL_BETA, 2 * np.pi))
    with pytest.raises(ValueError, match="model"):
        solve_flow(other, None, T, tol=1e-4, method=method, resume=path)
