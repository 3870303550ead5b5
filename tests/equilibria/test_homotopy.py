"""Newton homotopy: the path F(x) = p F(x0) and its end (qsa.equilibria.homotopy)."""

import numpy as np
import pytest

from qsa import Curve, Fourier
from qsa.constraints import FixedLength, bind_constraints
from qsa.energies import residual_scale
from qsa.equilibria import npulse, polish
from qsa.equilibria.homotopy import REASONS, newton_homotopy, state_weights
from qsa.equilibria.newton import newton_solve
from qsa.equilibria.system import EquilibriumSystem, equal_arclength

EQ = npulse(3, 0.15, grid=Fourier(127))


def near_guess(amp=0.02):
    c = EQ.curve
    s = np.arange(c.N) / c.N
    return equal_arclength(Curve(c.kappa * (1 + amp * np.cos(2 * np.pi * 2 * s)), c.g,
                                 c.grid, c.theta0, c.origin))


def on_path(S, run, w, scale):
    """Relative residual of F(x) - p w at each path point (the record's p)."""
    return np.array([S.scaled_norm(S.residual(x) - p * w, S.curve(x), scale)
                     for p, x in zip(run.p, run.states, strict=True)])


@pytest.mark.parametrize("constraints", [None, [FixedLength()]])
def test_state_weights_give_the_step_norm(constraints):
    c = near_guess()
    S = EquilibriumSystem(EQ.energy, c, bind_constraints(constraints, c))
    x = S.pack(c)
    scale = residual_scale(EQ.energy, c)
    dx = np.random.default_rng(1).normal(size=x.size)
    assert np.sqrt(state_weights(S, x, scale) @ dx ** 2) == pytest.approx(
        S.step_norm(dx, x, scale), rel=1e-13)


def test_path_to_an_equilibrium():
    c = near_guess()
    S = EquilibriumSystem(EQ.energy, c)
    x0 = S.pack(c)
    F0 = S.residual(x0)
    scale = residual_scale(EQ.energy, c)
    run = newton_homotopy(S, x0, newton_solve, tol=1e-10)
    assert run.success and run.reason == "crossed" and run.newton.history[-1] <= 1e-10
    assert run.p[0] == 1.0 and run.p[-1] <= 0 < run.p[-2]
    assert np.all(np.diff(run.p) < 0) and run.turning_points.size == 0
    assert np.all(np.diff(run.arclength) > 0)
    # every point is on the path, to the corrector's tolerance (1e-3 of the first residual)
    assert np.all(on_path(S, run, F0, scale) <= 1e-3 * run.history[0])
    # ... so the residual shrinks with p
    assert run.history == pytest.approx(np.abs(run.p) * run.history[0], rel=2e-3, abs=1e-14)
    # the same equilibrium as Newton's from the guess
    ref = polish(EQ.energy, c, globalize=False)
    assert ref.success
    assert np.max(np.abs(S.curve(run.x).kappa - ref.curve.kappa)) < 1e-8


def test_path_along_a_given_direction():
    """``direction``: F(x) = p w for a fixed w; the start is corrected onto the path."""
    c = near_guess()
    S = EquilibriumSystem(EQ.energy, c)
    x0 = S.pack(c)
    F0 = S.residual(x0)
    other = near_guess(0.025)
    w = S.residual(S.pack(other))            # the residual of another guess: not F(x0)
    scale = residual_scale(EQ.energy, c)
    run = newton_homotopy(S, x0, newton_solve, tol=1e-10, direction=w)
    assert run.success
    p0 = w @ F0 / (w @ w)
    assert np.all(on_path(S, run, p0 * w, scale) <= 1e-3 * run.history[0])
    assert not np.array_equal(run.states[0], x0)     # moved onto the path


def test_a_far_guess_is_reported_not_raised():
    c = equal_arclength(Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t) + 0.03 * np.sin(2 * t),
                                    Fourier(127)))
    S = EquilibriumSystem(EQ.energy, c)
    x0 = S.pack(c)
    run = newton_homotopy(S, x0, newton_solve, maxiter=8)
    assert run.reason in REASONS and not run.success
    assert run.n_steps + run.n_rejected <= 8
    assert len(run.p) == len(run.history) == len(run.states) == run.n_steps + 1
    F = S.residual(run.x)
    scale = residual_scale(EQ.energy, c)
    assert S.scaled_norm(F, S.curve(run.x), scale) == pytest.approx(run.history.min())
