"""Soft-mode Newton: the Lyapunov-Schmidt reduction along J's smallest singular value."""

import numpy as np
import pytest
import scipy.sparse as sp

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import residual_scale
from qsa.equilibria import npulse, polish
from qsa.equilibria.newton import newton_solve
from qsa.equilibria.softmode import REASONS, smallest_singular, soft_mode_newton
from qsa.equilibria.system import EquilibriumSystem, equal_arclength

EQ = npulse(2, 0.1, grid=Fourier(255))


def shifted_guess(shift):
    """EQ with its second pulse moved along the curve by ``shift`` of the period."""
    c = EQ.curve
    N = c.N
    s = np.arange(N) / N
    K = np.fft.rfft(c.kappa) * np.exp(2j * np.pi * np.fft.rfftfreq(N, 1.0 / N) * shift / 2)
    moved = np.fft.irfft(K, N)
    w = 0.5 * (1 + np.tanh(20 * np.sin(2 * np.pi * s - np.pi / 2)))   # the pulse at s = 1/2
    k = (1 - w) * c.kappa + w * moved
    k *= 2 * np.pi / (np.sum(k) / N * c.g[0])
    return equal_arclength(Curve(k, c.g, c.grid, c.theta0, c.origin))


@pytest.mark.parametrize("sparse", [False, True])
def test_smallest_singular(sparse):
    rng = np.random.default_rng(3)
    A = rng.normal(size=(40, 40))
    U, _, Vt = np.linalg.svd(A)
    sig = np.concatenate([np.linspace(5, 1, 38), [1e-2, 1e-5]])
    A = (U * sig) @ Vt
    sig_est, u, v = smallest_singular(sp.csc_matrix(A) if sparse else A)
    assert sig_est[0] == pytest.approx(1e-5, rel=1e-6)
    assert sig_est[1] == pytest.approx(1e-2, rel=1e-6)
    assert np.linalg.norm(A @ v - sig_est[0] * u) < 1e-12
    assert abs(abs(v @ Vt[-1]) - 1) < 1e-10 and abs(abs(u @ U[:, -1]) - 1) < 1e-10


def test_soft_mode_newton_slides_a_pulse_back():
    c = shifted_guess(0.1)
    S = EquilibriumSystem(EQ.energy, c)
    x0 = S.pack(c)
    run = soft_mode_newton(S, x0, newton_solve, tol=1e-10)
    assert run.success and run.reason == "converged" and run.newton.history[-1] <= 1e-10
    assert len(run.s) == len(run.tau) == len(run.dtau) == len(run.sigma)
    assert len(run.history) == len(run.states) == len(run.s) + 1
    # Newton on tau(s): |tau| falls at every step, and the tau' are alike (nearly linear)
    assert np.all(np.diff(np.abs(run.tau)) < 0)
    assert np.ptp(run.dtau) < 0.05 * np.abs(run.dtau).max()
    # tau is the residual's component along the soft left singular vector there
    for tau, x in zip(run.tau, run.states[1:], strict=True):
        _, u, _ = smallest_singular(S.jacobian(x))
        assert abs(u[:S.size] @ S.residual(x)) == pytest.approx(abs(tau), rel=1e-4)
    # the equilibrium polish finds from the same guess (the 2-pulse, up to the phase)
    ref = polish(EQ.energy, c, globalize=False)
    assert ref.success
    assert np.max(np.abs(S.curve(run.x).kappa - ref.curve.kappa)) < 1e-7
    assert EQ.energy.energy(S.curve(run.x)) == pytest.approx(EQ.energy.energy(EQ.curve), rel=1e-12)


def test_soft_mode_newton_on_finite_differences():
    grid = FiniteDifference(200)
    c = equal_arclength(Curve.from_positions(*EQ.curve.positions(), grid))
    S = EquilibriumSystem(EQ.energy, c)
    run = soft_mode_newton(S, S.pack(c), newton_solve, tol=1e-9)
    assert run.reason in REASONS
    assert run.success
    F = S.residual(run.x)
    assert S.scaled_norm(F, S.curve(run.x), residual_scale(EQ.energy, c)) <= 1e-9


# ---------------------------------------------------------------- polish with a soft mode
def folded_rho14():
    """The folded CHA state of f:fold at rho = 1.4 (Table T1, l* = 0.1): the 1200-node
    flow's state at t = 30, resampled to Fourier(601), with its energy."""
    from pathlib import Path

    from qsa.paper.folded import folded_energy

    d = np.load(Path(__file__).parents[1] / "reference" / "folded_rho14_601.npz")
    kappa = d["kappa"]
    c = Curve(kappa, np.full(kappa.size, float(d["L"])), Fourier(kappa.size),
              float(d["theta0"]), d["origin"])
    return folded_energy(0.08, 60.0, 1.4 * float(d["L0"]), 40.0, 0.1, 1.0), c


def test_polish_through_the_soft_mode_of_a_folded_state():
    """J has a near-singular direction (smallest singular values 1.8e-5 and 2.8e-3): the
    Newton steps, almost entirely along it, overshoot and Newton fails; with the soft
    coordinate fixed the other equations solve, and Newton converges from there."""
    E, c = folded_rho14()
    S = EquilibriumSystem(E, c)
    sig = smallest_singular(S.jacobian(S.pack(c)))[0]
    assert sig[0] < 1e-2 * sig[1]
    assert not polish(E, c, maxiter=10, globalize=False).success
    res = polish(E, c, maxiter=10)
    assert res.success and res.history[-1] <= 1e-10
    assert "soft-mode Newton" in res.message and "pseudo-transient" not in res.message
    assert not res.curve.self_intersects()
    # near the flow's state, and below its energy
    assert E.energy(res.curve) < E.energy(c)
    assert abs(res.curve.length() / c.length() - 1) < 1e-3
    # an equilibrium: a fixed point of plain Newton
    again = polish(E, res.curve, globalize=False)
    assert again.success and again.n_newton <= 1


@pytest.mark.slow
def test_the_old_globalization_fails_on_the_folded_state(monkeypatch):
    """Without the soft-mode stage, Newton and pseudo-transient continuation stall."""
    import qsa.equilibria.newton as newton

    E, c = folded_rho14()
    monkeypatch.setattr(newton, "SOFT_RATIO", 0.0)
    res = polish(E, c, maxiter=10)
    assert not res.success and res.history[-1] > 1e-6
    assert "pseudo-transient" in res.message and "soft-mode" not in res.message
