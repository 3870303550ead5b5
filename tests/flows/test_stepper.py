"""Steppers: linear solvers agree, simplified Newton solves the same equations as full Newton,
BDF2 is second order and needs far fewer steps than backward Euler for the same accuracy."""

from dataclasses import replace

import numpy as np
import pytest

from qsa.flows import CHA, FacetingFlow, solve_flow
from qsa.flows.stepper import (
    DenseLU,
    LowRankUpdateLU,
    NewtonSolver,
    SparseLU,
    factorize,
    interleaved_ordering,
)
from qsa.paper import CONVERGENCE, CHAScenario
from tests.helpers import circle_radius_errors, paper_curve, paper_samples

PAPER_CHA = CONVERGENCE.model_params()  # the appendix's convergence example


paper_xy = paper_curve  # equal-chord nodes of the appendix example


def test_interleaved_ordering_is_node_major():
    sys = CHA(**PAPER_CHA).setup(*paper_xy(40))
    p = interleaved_ordering(sys)
    assert sorted(p) == list(range(sys.size))
    assert list(p[:6]) == [0, 40, 80, 120, 160, 1]
    J = sys.jacobian(sys.y0, np.zeros(sys.size), 1e3)
    Jloc, _ = sys.jacobian_parts(sys.y0, np.zeros(sys.size), 1e3)
    A = Jloc[p][:, p].tocoo()
    inner = (A.row < sys.size - 1) & (A.col < sys.size - 1)
    gap = np.abs(A.row[inner] // 5 - A.col[inner] // 5)
    gap = np.minimum(gap, 40 - gap)  # periodic
    assert gap.max() <= 1  # neighbouring nodes only: a (periodic) band
    assert J.nnz > Jloc.nnz  # the long-range adhesion block is not in the band


@pytest.mark.parametrize("c", [1e2, 1e4])
def test_linear_solvers_agree(c):
    sys = CHA(**PAPER_CHA).setup(*paper_xy(60))
    y = sys.y0 * (1 + 1e-3 * np.random.default_rng(1).standard_normal(sys.size))
    ydot = np.random.default_rng(2).standard_normal(sys.size)
    b = np.random.default_rng(3).standard_normal(sys.size)
    J = sys.jacobian(y, ydot, c).toarray()
    x_ref = np.linalg.solve(J, b)
    auto = factorize(sys, y, ydot, c)
    assert isinstance(auto, LowRankUpdateLU)  # l* = 1/2: the adhesion block is dense
    for lu in [auto, factorize(sys, y, ydot, c, "sparse"), factorize(sys, y, ydot, c, "dense")]:
        x = lu.solve(b)
        assert np.linalg.norm(J @ x - b) <= 1e-9 * np.linalg.norm(b)
        assert np.linalg.norm(x - x_ref) <= 1e-7 * np.linalg.norm(x_ref)
    short = replace(CHAScenario(), l_star=0.05).model().setup(
        *paper_xy(200))
    assert isinstance(factorize(short, short.y0, 0 * short.y0, c), SparseLU)
    assert isinstance(factorize(sys, y, ydot, c, "dense"), DenseLU)


def test_simplified_newton_solves_the_backward_euler_equations():
    sys = CHA(**PAPER_CHA).setup(*paper_xy(50))
    idx = np.r_[sys.error_index, sys.size - 1]
    k = 1e-4
    full = NewtonSolver(sys, 1e-10, idx, reuse=False)
    simp = NewtonSolver(sys, 1e-10, idx, max_iter=20)
    y = sys.y0
    for _ in range(4):
        y1, ok1 = full.solve(y, 1 / k, y)
        y2, ok2 = simp.solve(y, 1 / (1.2 * k), y)  # pool has c = 1/k: reused for 1.2 k
        assert ok1 and ok2
        F = sys.residual(y1, (y1 - y) / k)
        assert np.max(np.abs(F[sys.N : 2 * sys.N])) < 1e-7  # chords |.|^2/h^2, Newton tol
        assert np.max(np.abs(y1 - y2)[idx]) > 1e-8  # different equations (k vs 1.2 k) ...
        y2b, _ = simp.solve(y, 1 / k, y2)  # ... and the same solution for the same equation
        assert np.max(np.abs(y1 - y2b)[idx]) < 1e-8
        y = y1
    assert full.n_factorizations >= full.n_iterations - 4  # full Newton: one per iteration
    assert simp.n_factorizations < simp.n_iterations / 2


def test_bdf2_reaches_backward_euler_accuracy_with_five_times_fewer_steps():
    # A regular polygon under CH + length penalty: exact reference from the scalar ODE
    # (tests/flows/test_solve.py). Backward Euler at tol 1e-6 against BDF2 at 5e-6.
    err_be, be = circle_radius_errors("be", 1e-6)
    err_bdf, bdf = circle_radius_errors("bdf2", 5e-6)
    assert err_bdf <= err_be
    assert bdf.n_steps * 5 <= be.n_steps, (bdf.n_steps, be.n_steps)


def test_bdf2_global_error_is_second_order_in_the_step():
    # At fixed step sizes (tol huge, max_step fixing h) the error falls 4x per halving.
    model = FacetingFlow(alpha=0.3, kstar=2.0, beta=5.0, L_star=7.0)
    th = 2 * np.pi * np.arange(400) / 400
    r = 1.3 * (1 + 0.1 * np.cos(3 * th))
    init = (r * np.cos(th), r * np.sin(th))
    T = 4e-3
    ref = solve_flow(model, init, T, N=40, tol=1e-11, method="bdf2", t_eval=[T])
    errs = []
    hs = [T / 10, T / 20, T / 40]
    for h in hs:
        res = solve_flow(model, init, T, N=40, tol=1e3, method="bdf2", first_step=h,
                         max_step=h, t_eval=[T], newton_tol=1e-12)
        errs.append(np.max(np.abs(res.states[-1][:80] - ref.states[-1][:80])))
    order = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert 1.7 < order < 2.4, (errs, order)


@pytest.mark.slow
def test_bdf2_beats_backward_euler_on_the_paper_example():
    # The appendix example (N = 64, t = 0.05): backward Euler at tol 1e-6 against a BDF2
    # reference at tol 1e-10; BDF2 at tol 3e-5 is as accurate with >= 5x fewer steps.
    model, init, N, T = CHA(**PAPER_CHA), paper_samples(), 64, 0.05
    ref = solve_flow(model, init, T, N=N, tol=1e-10, method="bdf2", t_eval=[T])
    be = solve_flow(model, init, T, N=N, tol=1e-6, t_eval=[T])
    bdf = solve_flow(model, init, T, N=N, tol=3e-5, method="bdf2", t_eval=[T])

    def err(res):
        return np.max(np.abs(res.states[-1][: 2 * N] - ref.states[-1][: 2 * N]))

    assert err(bdf) <= err(be)
    assert 5 * bdf.n_steps <= be.n_steps
