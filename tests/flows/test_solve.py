"""solve_flow: invariants along the flow, the exact shrinking/growing circle, input errors,
snapshots, callback, failure reporting."""


import numpy as np
import pytest

from qsa import Curve, FiniteDifference
from qsa.flows import CHA, FacetingFlow, FlowResult, solve_flow
from qsa.flows.solve import MESSAGES
from qsa.paper import CONVERGENCE
from tests.helpers import assert_status_convention, circle_radius_errors, paper_samples

PAPER_CHA = CONVERGENCE.model_params()  # the appendix's convergence example


def wobbly_samples(M=2000, amp=0.1, lobes=3, scale=1.3):
    th = 2 * np.pi * np.arange(M) / M
    r = scale * (1 + amp * np.cos(lobes * th) + 0.03 * np.sin(2 * th))
    return r * np.cos(th), r * np.sin(th)


def chords(res, i=-1):
    X, Y = res.positions(i)
    return np.hypot(np.roll(X, -1) - X, np.roll(Y, -1) - Y)


# ------------------------------------------------------------------ invariants
@pytest.mark.parametrize("tol", [1e-3, 1e-4])
@pytest.mark.parametrize("which", ["cha", "facet"])
def test_energy_non_increasing_and_constraints_held(which, tol):
    if which == "cha":
        model, init, N, T = CHA(**PAPER_CHA), paper_samples(), 64, 0.05
    else:
        model = FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=7.0)
        init, N, T = wobbly_samples(), 64, 2e-3
    res = solve_flow(model, init, T, N=N, tol=tol)
    assert res.success and res.status == 0 and res.t[-1] == pytest.approx(T, rel=1e-14)
    assert_status_convention(res, MESSAGES)
    E = res.energy_steps
    scale = np.max(np.abs(E))
    assert np.all(np.diff(E) <= 1e-12 * scale), np.max(np.diff(E))
    assert E[-1] < E[0]
    ntol = 1e-2 * tol  # the default Newton tolerance
    for i in range(res.states.shape[0]):
        L = res.system.length(res.states[i])
        # constant (scaled) arc length: equal chords L/N, to the Newton tolerance
        assert np.max(np.abs(chords(res, i) - L / N)) < 10 * ntol
        # closure: the node polygon stays a simple closed curve turning once
        X, Y = res.positions(i)
        ex, ey = np.roll(X, -1) - X, np.roll(Y, -1) - Y
        turn = np.arctan2(ex * np.roll(ey, -1) - ey * np.roll(ex, -1),
                          ex * np.roll(ex, -1) + ey * np.roll(ey, -1))
        assert abs(np.sum(turn) - 2 * np.pi) < 1e-10
        # the algebraic rows (curvature, velocity law ...) hold at the accepted state
        F = res.system.residual(res.states[i], np.zeros(res.system.size))
        k = res.system.curvature(res.states[i])
        assert np.max(np.abs(F[2 * N : 3 * N])) < 1e3 * ntol * np.max(np.abs(k))
    assert len(res.t_steps) == res.n_steps + 1
    assert res.n_newton >= 3 * res.n_steps and res.n_lu >= 1 and res.n_factorizations == res.n_lu


@pytest.mark.parametrize("method, tol", [("be", 1e-3), ("bdf2", 1e-3), ("bdf2", 1e-4)])
def test_circle_follows_scalar_ode_of_discrete_velocity(method, tol):
    err, _ = circle_radius_errors(method, tol)
    assert err < 10 * tol


def test_backward_euler_global_error_scales_like_sqrt_tol():
    # Local error control per step: k ~ sqrt(tol), so the global error ~ n tol ~ sqrt(tol)
    # (why 10 tol can only hold for loose tolerances with backward Euler).
    tols = [1e-3, 1e-4, 1e-5]
    errs = [circle_radius_errors("be", tol)[0] for tol in tols]
    slope = np.polyfit(np.log(tols), np.log(errs), 1)[0]
    assert 0.35 < slope < 0.65, (errs, slope)


def test_curve_input_and_snapshots_at_t_eval():
    c = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), FiniteDifference(80))
    t_eval = [0.0, 0.01, 0.02]
    res = solve_flow(CHA(eps=0.1, beta=1.0, rho=1.2), c, 0.02, tol=1e-3, t_eval=t_eval)
    assert isinstance(res, FlowResult)
    assert res.N == 80 and res.x.shape == (80,)
    np.testing.assert_allclose(res.t, t_eval, rtol=0, atol=1e-15)
    assert res.states.shape == (3, res.system.size)
    # the first node is kept
    x0, y0 = c.positions()
    assert np.hypot(res.states[0, 0] - x0[0], res.states[0, 80] - y0[0]) < 1e-12
    np.testing.assert_array_equal(res.x, res.positions(-1)[0])


def test_callback_sees_every_step_and_can_stop():
    seen = []

    def cb(t, y, system):
        seen.append(t)
        return len(seen) == 5

    res = solve_flow(CHA(eps=0.1, beta=1.0, rho=1.2), wobbly_samples(), 1.0, N=40, tol=1e-3,
                     callback=cb)
    assert res.status == 1 and res.success and res.n_steps == 5
    assert_status_convention(res, MESSAGES)
    assert seen == list(res.t_steps[1:])


def test_newton_failure_is_reported_and_state_kept(tmp_path):
    # min_step above every step the problem can take: Newton cannot be rescued.
    model = FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=7.0)
    path = tmp_path / "fail.npz"
    res = solve_flow(model, wobbly_samples(), 1.0, N=40, tol=1e-3, first_step=10.0,
                     min_step=5.0, checkpoint=path)
    assert not res.success and res.status == -1
    assert_status_convention(res, MESSAGES)
    assert "Newton" in res.message and str(path) in res.message
    assert path.exists() and res.checkpoint == str(path)
    np.testing.assert_array_equal(res.states[-1], res.system.y0)


# ------------------------------------------------------------------ bad input
def test_bad_input_raises_value_error():
    model = CHA(**PAPER_CHA)
    good = paper_samples(400)
    th = 2 * np.pi * np.arange(400) / 400
    eight = (np.sin(th), np.sin(2 * th))
    cases = [
        ((model, eight, 0.1), {"N": 64}, "intersects"),
        ((model, (np.cos(th[:200]), np.sin(th[:200])), 0.1), {"N": 64}, "not closed"),
        ((model, (np.where(th > 1, np.cos(th), np.nan), np.sin(th)), 0.1), {"N": 64}, "NaN"),
        ((model, good, 0.1), {"N": 64, "tol": 0.0}, "tol"),
        ((model, good, 0.1), {"N": 64, "tol": -1e-3}, "tol"),
        ((model, good, 0.1), {"N": 64, "tol": float("nan")}, "tol"),
        ((model, good, 0.1), {"N": 8}, "l_star"),  # h = L/N > l_star
        ((model, good, -1.0), {"N": 64}, "t_final"),
        ((model, good, 0.1), {"N": 64, "method": "rk4"}, "method"),
        ((model, good, 0.1), {"N": 2}, "N"),
        ((model, good, 0.1), {"N": 64, "t_eval": [0.2, 0.1]}, "t_eval"),
        ((model, "circle", 0.1), {"N": 64}, "initial"),
    ]
    for args, kwargs, word in cases:
        with pytest.raises(ValueError, match=word):
            solve_flow(*args, **kwargs)


@pytest.mark.parametrize("N, offset", [(3000, 0.0), (3000, 100.0), (30000, 100.0)])
def test_equalize_chords_stops_at_round_off_for_large_N(N, offset):
    # A fixed tolerance below round-off made the projection fail from N ~ 3000 on.
    from qsa.flows import equalize_chords
    from qsa.resample import resample_closed

    x, y = paper_samples(4096)
    X, Y, _ = resample_closed(x + offset, y, N, method="chord")
    X = X + 1e-3 * (X[1] - X[0]) * np.random.default_rng(0).standard_normal(N)
    X, Y, L = equalize_chords(X, Y)
    c = np.hypot(np.roll(X, -1) - X, np.roll(Y, -1) - Y)
    assert np.max(np.abs(c - L / N)) < 1e3 * np.finfo(float).eps * (offset + 2)


def test_one_self_intersection_implementation():
    from qsa.curve import polygon_self_intersects, self_intersections
    from qsa.flows import self_intersections as flows_version

    assert flows_version is self_intersections
    th = 2 * np.pi * np.arange(50) / 50
    assert polygon_self_intersects(np.sin(th), np.sin(2 * th))
    assert not polygon_self_intersects(np.cos(th), np.sin(th))
