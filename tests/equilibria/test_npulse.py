"""N-pulse faceted equilibria: closure, V^n = 0, L*, symmetry, multipliers, errors."""

import numpy as np
import pytest

from qsa import FiniteDifference, Fourier
from qsa.equilibria import Equilibrium, circle, npulse

K = 5.0

CASES = [(n, a) for n in range(2, 9) for a in (0.05, 0.1, 0.15, 0.2, 0.25, 0.3) if n * a < 1]
CASES += [(3, 0.33), (2, 0.49)]  # close to the existence limit N alpha < 1


@pytest.mark.parametrize(("n", "alpha"), CASES)
def test_done_when(n, alpha):
    """|C(U)| <= 1e-10, max|V^n| <= 1e-8 x largest term, on the automatic Fourier grid."""
    eq = npulse(n, alpha, kstar=K)
    assert isinstance(eq, Equilibrium) and eq.success, eq.message
    assert isinstance(eq.curve.grid, Fourier) and eq.curve.N % 2 == 1
    assert eq.closure <= 1e-10
    assert eq.residual <= 1e-8 * eq.residual_scale
    p = eq.params
    assert p["L"] == pytest.approx(n * p["period"], rel=1e-15)
    assert p["nu2"] < 0 and p["L"] <= p["L_star"]
    # beta (L - L*) = nu2, up to the rounding of L* (nu2 can be far below eps L)
    tol = 4 * p["beta"] * np.finfo(float).eps * p["L_star"]
    assert p["beta"] * (p["L"] - p["L_star"]) == pytest.approx(p["nu2"], abs=tol)
    assert np.array_equal(eq.multipliers, [0.0, 0.0, -0.0])


def test_shifted_L_star_is_not_an_equilibrium():
    from qsa.energies import Faceting, Perimeter

    eq = npulse(4, 0.1, kstar=K, beta=5.0)
    for shift in (1e-3, -1e-3):
        E = Faceting(0.1, K) + Perimeter(5.0, eq.params["L_star"] + shift)
        Vn = E.normal_velocity(eq.curve)
        # V^n = psi (nu2 - beta (L - L* - shift)) = beta shift psi
        assert np.max(np.abs(Vn - 5.0 * shift * eq.curve.kappa)) < 2 * eq.residual
        assert np.max(np.abs(Vn)) > 1e3 * eq.residual


@pytest.mark.parametrize("n", [3, 5])
def test_n_fold_symmetry(n):
    eq = npulse(n, 0.15, kstar=K)
    c = eq.curve
    xy = c.positions()
    shifted = c.grid.interpolate(xy.T, c.grid.s + 1.0 / n).T
    ang = 2 * np.pi / n
    rot = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
    assert np.max(np.abs(rot @ xy - shifted)) < 1e-11
    assert np.allclose(c.grid.interpolate(c.kappa, c.grid.s + 1.0 / n), c.kappa, atol=1e-11)
    assert np.allclose((xy @ c.dsigma) / c.length(), 0.0, atol=1e-13)  # centred
    assert not c.self_intersects()


def test_multipliers_with_nu1():
    from qsa import geometry

    nu1 = 0.3
    eq = npulse(3, 0.1, kstar=K, nu1=nu1, grid=Fourier(301))
    assert eq.success, eq.message
    assert np.array_equal(eq.multipliers, [0.0, 0.0, -nu1])
    grad = eq.energy.gradient(eq.curve)
    Psi = geometry.constraint_gradients(eq.curve)
    assert np.max(np.abs(grad - eq.multipliers @ Psi)) < 1e-9 * np.max(np.abs(grad))


def test_finite_differences_converge_at_order_two():
    sizes = np.array([400, 800, 1600, 3200])
    res = []
    for N in sizes:
        eq = npulse(3, 0.15, kstar=K, grid=FiniteDifference(int(N)))
        res.append(eq.residual)
    slope = np.polyfit(np.log(sizes), np.log(res), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.2)


def test_non_quartic_well(sextic_well):
    eq = npulse(4, 0.1, sextic_well, grid=None)
    assert eq.success, eq.message
    assert eq.closure <= 1e-10 and eq.residual <= 1e-8 * eq.residual_scale


def test_circle_equilibrium():
    eq = circle(0.7, 0.1, kstar=K, beta=3.0, grid=Fourier(33))
    assert eq.success
    assert eq.residual < 1e-10 * eq.residual_scale
    k0 = 1 / 0.7
    W, dW = k0**2 * (k0 - K) ** 2 / 4, k0 * (k0 - K) * (2 * k0 - K) / 2
    assert 3.0 * (2 * np.pi * 0.7 - eq.params["L_star"]) == pytest.approx(k0 * dW - W)
    assert eq.multipliers[2] == pytest.approx(dW)


def test_invalid_requests():
    with pytest.raises(ValueError, match="n_pulses"):
        npulse(1, 0.1)
    with pytest.raises(ValueError, match="n_pulses"):
        npulse(2.5, 0.1)
    with pytest.raises(ValueError, match="alpha"):
        npulse(3, 0.0)
    with pytest.raises(ValueError, match="alpha"):
        npulse(3, -0.1)
    with pytest.raises(ValueError, match="beta"):
        npulse(3, 0.1, beta=0.0)
    with pytest.raises(ValueError, match="N alpha < 1"):
        npulse(4, 0.25)
    with pytest.raises(ValueError, match="grid"):
        npulse(3, 0.1, grid="fine")


def test_summary_is_json():
    import json

    eq = npulse(3, 0.2, kstar=K)
    d = json.loads(eq.to_json())
    assert d["kind"] == "npulse" and d["params"]["n_pulses"] == 3


@pytest.mark.parametrize(("n", "alpha", "nu1"), [(2, 0.05, 0.3), (3, 0.05, 0.05), (5, 0.1, 0.3)])
def test_nonzero_nu1_near_the_separatrix(n, alpha, nu1):
    """nu1 != 0 (asymmetric pulses): exact near the separatrix via the polynomial path."""
    eq = npulse(n, alpha, kstar=K, nu1=nu1)
    assert eq.success, eq.message
    assert eq.closure <= 1e-10 and eq.residual <= 1e-8 * eq.residual_scale
    assert eq.params["turning"] * n == pytest.approx(2 * np.pi, rel=1e-13)


@pytest.mark.parametrize("nu1", [0.0, 0.2])
def test_polynomial_well_deep_plateaus(sextic_poly_well, sextic_well, nu1):
    """A well declaring its coefficients gets the exact path (plateau depth ~1e-15 here)."""
    eq = npulse(2, 0.05, sextic_poly_well, nu1=nu1)
    assert eq.success, eq.message
    assert eq.extra["orbit"].depth < 1e-12
    assert eq.closure <= 1e-10 and eq.residual <= 1e-8 * eq.residual_scale
    if nu1 == 0.0:  # the same well as plain callables cannot get this close in double
        with pytest.raises(ValueError, match="separatrix"):
            npulse(2, 0.05, sextic_well)
