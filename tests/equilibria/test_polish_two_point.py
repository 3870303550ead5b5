"""Newton polishing with a two-point energy: CanhamHelfrich + Perimeter + Adhesion (CHA).

The adhesion normal velocity is differentiated exactly through the node positions
(``Adhesion.normal_velocity_jacobian``); on finite-difference grids the positions are
extra unknowns of a sparse Newton matrix. The reference equilibrium comes from a DAE
flow polished on a Fourier grid (tests/reference/cha_trillium_equilibrium.json).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import Adhesion, CanhamHelfrich, Faceting, Perimeter
from qsa.equilibria import polish
from qsa.equilibria.newton import EquilibriumSystem
from qsa.equilibria.two_point_terms import StateBorder
from qsa.resample import PeriodicInterpolant
from qsa.spectra import spectrum
from tests.helpers import fitted_order

REF = json.loads((Path(__file__).parents[1] / "reference"
                  / "cha_trillium_equilibrium.json").read_text())


def reference():
    """The reference CHA equilibrium (Fourier(201)) and its energy."""
    E = (CanhamHelfrich(REF["eps"]) + Perimeter(REF["beta"], REF["L_star"])
         + Adhesion(REF["A0"], REF["l_star"], REF["a"]))
    c = Curve(REF["kappa"], REF["L"], Fourier(REF["N"]), REF["theta0"], tuple(REF["origin"]))
    return E, c


def perturbed(c, grid, amp=0.02):
    c = c.on_grid(grid)
    return c.with_kappa(c.kappa * (1 + amp * np.cos(4 * np.pi * c.grid.s + 0.3)))


def reduced_jacobian(S, x):
    """``dF/dx`` with the state unknowns (rows after ``x``) eliminated, dense."""
    J = S.jacobian(x)
    J = J.toarray() if hasattr(J, "toarray") else np.asarray(J)
    n = x.size
    if J.shape[0] == n:
        return J
    return J[:n, :n] - J[:n, n:] @ np.linalg.solve(J[n:, n:], J[n:, :n])


def circle_energy(grid, l_star=0.15, faceting=False):
    """An energy with adhesion for which the unit circle is an equilibrium (L* solved for)."""
    c = Curve.circle(1.0, grid)
    local = Faceting(0.1, 3.0) if faceting else CanhamHelfrich(0.1)
    part = local + Adhesion(A0=10.0, l_star=l_star)
    V0 = part.normal_velocity(c)[0]        # V = V0 - beta (L - L*) kappa on the circle
    return part + Perimeter(2.0, c.length() - V0 / 2.0), c


@pytest.mark.parametrize("grid", [Fourier(61), FiniteDifference(160)])
def test_newton_jacobian_against_central_differences(grid):
    E, c0 = reference()
    E = CanhamHelfrich(REF["eps"]) + Perimeter(REF["beta"], REF["L_star"]) + Adhesion(
        REF["A0"], 0.12, REF["a"])  # a kernel short against the curve: the sparse path on FD
    c = perturbed(c0, grid, 0.01)
    S = EquilibriumSystem(E, c)
    x = S.pack(c)
    x[S.N + 1:] = [0.1, -0.2, 0.3]
    if grid.sparse:
        assert any(isinstance(t, StateBorder) for t in S.jacobian_parts(x)[4])
    J = reduced_jacobian(S, x)
    h = 1e-6
    for i in (0, 7, 30, S.N, S.N + 2):
        e = np.zeros(x.size)
        e[i] = h * max(1.0, abs(x[i]))
        col = (S.residual(x + e) - S.residual(x - e)) / (2 * e[i])
        assert np.abs(J[:, i] - col).max() <= 1e-6 * np.abs(col).max()


def test_polish_fourier_to_round_off():
    E, c0 = reference()
    res = polish(E, perturbed(c0, Fourier(151)))
    assert res.success and res.status == 0 and res.n_newton <= 8
    assert res.residual <= 1e-9 * res.residual_scale
    assert np.abs(res.unfolding).max() <= 1e-9 * res.residual_scale
    assert res.closure < 1e-12 * res.curve.length()
    assert not np.isnan(res.multipliers).any() and abs(res.multipliers[0]) > 1e-3


def test_polish_finite_differences_unfolding_is_second_order():
    """On finite differences the three rigid-motion identities of V^n hold to O(h^2) only for
    a two-point energy: the square system is solved to round-off, and its unfolding
    parameters (which carry max|V^n|) fall like h^2."""
    E, c0 = reference()
    Ns, unf = [120, 240, 480], []
    for N in Ns:
        res = polish(E, perturbed(c0, FiniteDifference(N)))
        assert res.success and res.history[-1] <= 1e-10
        a = np.abs(res.unfolding).max()
        assert res.residual <= 2 * a * np.sqrt(N)   # the residual is the unfolding's
        unf.append(a)
    assert unf[-1] < 1e-5 * res.residual_scale
    assert abs(fitted_order(Ns, unf) - 2) < 0.2


@pytest.mark.parametrize("faceting", [False, True])
def test_polish_circle_with_adhesion_on_fd_reaches_round_off(faceting):
    """The perturbed circle returns to the circle (by symmetry an exact discrete solution),
    through the sparse Newton matrix with the positions as unknowns."""
    grid = FiniteDifference(240)
    E, c = circle_energy(grid, faceting=faceting)
    guess = c.with_kappa(c.kappa * (1 + 0.03 * np.cos(6 * np.pi * grid.s)))
    res = polish(E, guess)
    assert res.success
    assert res.residual <= max(1e-9 * res.residual_scale, 100 * res.noise_floor)
    assert np.ptp(res.curve.kappa) < 1e-8


def test_failure_is_reported_with_a_finite_state():
    E, c0 = reference()
    res = polish(E, perturbed(c0, Fourier(61), 0.1), maxiter=1)
    assert not res.success and res.status < 0
    assert np.all(np.isfinite(res.curve.kappa)) and np.isfinite(res.residual)


def test_touching_or_crossing_state_is_refused():
    t = 2 * np.pi * np.arange(400) / 400
    r = 0.5 + np.cos(t)                    # a limacon: its inner loop crosses the outer one
    # (from_positions refuses such samples; the interpolant gives the crossing state itself)
    c = Curve._from_interpolant(PeriodicInterpolant(r * np.cos(t), r * np.sin(t), "fourier"),
                                Fourier(129))
    E, _ = reference()
    with pytest.raises(ValueError, match=r"crosses itself: segments \d+ and \d+ \(s = "):
        polish(E, c)
    with pytest.raises(ValueError, match="crosses itself"):
        spectrum(E, c)
    # touching: two nodes of a pinched curve at the same point
    s = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    w = np.abs(np.sin(s)) + 1e-13
    x, y = np.cos(s), 0.8 * np.sin(s) * w
    pinched = Curve.from_positions(x, y, FiniteDifference(200))
    with pytest.raises(ValueError, match="(touches|crosses) itself"):
        polish(E, pinched)
