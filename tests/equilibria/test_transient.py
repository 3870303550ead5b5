"""Pseudo-transient continuation: the globalization of polish (qsa.equilibria.transient)."""

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import Faceting, Perimeter
from qsa.equilibria import polish
from qsa.equilibria.newton import newton_solve
from qsa.equilibria.system import EquilibriumSystem, equal_arclength
from qsa.equilibria.transient import _flow_matrix, pseudo_transient
from qsa.geometry import laplace_s
from qsa.linalg import factorize

E = Faceting(0.15, 5.0) + Perimeter(5.0, 6.0)


def square_guess(grid):
    return Curve.polar(lambda t: 1 + 0.15 * np.cos(4 * t), grid)


@pytest.mark.parametrize("grid", [Fourier(65), FiniteDifference(128)])
def test_flow_step_limits(grid):
    """dt -> infinity: the Newton step; dt -> 0: a flow step ~ -dt G V^n, made consistent
    with the linearized closure and phase rows."""
    c = equal_arclength(square_guess(grid))
    S = EquilibriumSystem(E, c)
    x = S.pack(c)
    F = S.residual(x)
    J = S.jacobian(x)
    N = S.N
    b = np.zeros(J.shape[0])
    b[:F.size] = F
    newton = -factorize(J).solve(b)[:F.size]
    G = laplace_s(c) + grid.diag(c.kappa ** 2)

    def step(dt):
        M, G_used = _flow_matrix(S, x, J, dt)
        rhs = b.copy()
        rhs[:N] = G_used @ F[:N]
        return -factorize(M).solve(rhs)[:F.size]

    dx = step(1e14)
    assert np.allclose(dx, newton, rtol=1e-6, atol=1e-8 * np.abs(newton).max())
    small = step(1e-10)[:N] / 1e-10
    explicit = -(G @ F[:N])
    cos = small @ explicit / np.linalg.norm(small) / np.linalg.norm(explicit)
    assert cos > 0.7
    # and it descends the energy
    assert E.energy(S.curve(x + step(1e-7))) < E.energy(S.curve(x))
    # the closure and phase rows are Newton's: they hold to first order along any step
    Jd = J.toarray() if hasattr(J, "toarray") else J
    dx = step(1e-10)
    assert np.allclose(Jd[N:F.size, :F.size] @ dx, -F[N:], atol=1e-12)


def test_globalized_polish_where_newton_fails():
    c = square_guess(Fourier(65))
    plain = polish(E, c, globalize=False)
    assert not plain.success                      # Newton's line search fails from here
    res = polish(E, c)
    assert res.success and res.history[-1] <= 1e-10
    assert "pseudo-transient flow steps" in res.message
    assert not res.curve.self_intersects()
    assert E.energy(res.curve) < E.energy(c)      # the flow descends the energy
    # an equilibrium: the same state is a fixed point of plain Newton
    again = polish(E, res.curve, globalize=False)
    assert again.success and again.n_newton <= 2
    assert E.energy(again.curve) == pytest.approx(E.energy(res.curve), rel=1e-12)


def test_pseudo_transient_record():
    c = equal_arclength(square_guess(Fourier(65)))
    S = EquilibriumSystem(E, c)
    run = pseudo_transient(S, S.pack(c), newton_solve, tol=1e-10)
    assert run.success and run.n_attempts >= 1 and run.n_steps >= 1
    assert run.dt.size == run.n_steps and np.all(run.dt > 0)
    assert run.time == pytest.approx(run.dt.sum())
    assert run.history[0] == max(run.history)
    # nothing to do at a solution: no flow step, no Newton solve tried
    done = pseudo_transient(S, run.newton.x, newton_solve, tol=1e-6, maxiter=0)
    assert done.n_steps == 0 and done.newton is None and not done.success


def test_pseudo_transient_stops_when_every_step_is_rejected():
    """Rejections shrink the step by 4 each; the flow stops instead of dividing by 0."""
    c = equal_arclength(square_guess(Fourier(65)))

    class Stuck(EquilibriumSystem):
        def scaled_norm(self, F, curve, scale):  # every trial state looks far worse
            r = super().scaled_norm(F, curve, scale)
            self.calls = getattr(self, "calls", 0) + 1
            return r if self.calls == 1 else 1e300

    S = Stuck(E, c)
    run = pseudo_transient(S, S.pack(c), newton_solve, tol=1e-10, maxiter=10**6)
    assert not run.success and run.n_steps == 0 and run.newton is None
    assert 0 < run.n_rejected < 30   # 4^-20 < 1e-12: stopped after about 20 rejections
