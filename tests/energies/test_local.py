import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.energies import (
    CanhamHelfrich,
    DoubleWell,
    Faceting,
    FirstOrderEnergy,
    Perimeter,
    Well,
)
from qsa.linalg import to_dense
from tests.helpers import (
    assert_gradient_matches_energy,
    assert_hessian_matches_energy,
    coupled_energy,
    directions,
    fitted_order,
    off_manifold,
    skew_curve,
)


def sextic_well(kstar=3.0):
    # W = k^2 (k - k*)^2 (1 + k^2) / 4: equal wells at 0 and k*, not quartic
    W = lambda k: 0.25 * k**2 * (k - kstar) ** 2 * (1 + k**2)
    dW = lambda k: 0.25 * (2 * k * (k - kstar) ** 2 * (1 + k**2) + 2 * k**2 * (k - kstar)
                           * (1 + k**2) + 2 * k**3 * (k - kstar) ** 2)
    h = 1e-5
    d2W = lambda k: (dW(k + h) - dW(k - h)) / (2 * h)
    return Well(W, dW, d2W, kstar=kstar)


ENERGIES = {
    "faceting": Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0),
    "helfrich": CanhamHelfrich(eps=0.1) + Perimeter(beta=1.0, L_star=9.0),
    "coupled": coupled_energy(),
    "userwell": Faceting(alpha=0.2, kstar=3.0, well=sextic_well()),
}
GRIDS = {"fourier": Fourier(65), "fd": FiniteDifference(64)}


@pytest.mark.parametrize("gname", GRIDS)
@pytest.mark.parametrize("ename", ENERGIES)
def test_gradient_is_derivative_of_energy(ename, gname):
    c = off_manifold(GRIDS[gname])
    assert_gradient_matches_energy(ENERGIES[ename], c, directions(GRIDS[gname], 1))


@pytest.mark.parametrize("gname", GRIDS)
@pytest.mark.parametrize("ename", ENERGIES)
def test_hessian_is_second_derivative_and_self_adjoint(ename, gname):
    c = off_manifold(GRIDS[gname], seed=3)
    assert_hessian_matches_energy(ENERGIES[ename], c, directions(GRIDS[gname], 2))


def test_fd_hessian_is_sparse_plus_rank_one():
    from qsa.linalg import SparsePlusLowRank

    c = skew_curve(FiniteDifference(64))
    H = ENERGIES["faceting"].hessian(c)
    assert isinstance(H, SparsePlusLowRank) and H.rank == 1
    assert H.S.nnz < 20 * c.N


def test_perimeter_hessian_rank_one_formula():
    c = off_manifold(Fourier(33))
    P = Perimeter(beta=3.0, L_star=2.0)
    g1 = np.sin(2 * np.pi * c.grid.s) + 0.5
    HU = P.hessian(c) @ np.concatenate([np.zeros(c.N), g1])
    assert np.allclose(HU[c.N:], 3.0 / c.g * np.mean(g1))
    assert np.allclose(HU[: c.N], 0)


@pytest.mark.parametrize("ename", ["faceting", "helfrich", "userwell"])
def test_W_invar_identity(ename):
    """M-dagger_2 grad E = d_kappa E grad_s kappa - grad_s(g d_g E) = 0 for any U (e:W-invar).

    Reparameterization invariance holds for the continuum energy: spectrally small on
    Fourier grids, second order on finite differences; the perimeter term alone is exact.
    """
    E = ENERGIES[ename]

    def state(grid):
        c = Curve.polar(lambda t: 1.5 + 0.1 * np.cos(3 * t) + 0.05 * np.sin(2 * t), grid)
        s = grid.s
        return Curve(c.kappa + 0.1 + 0.1 * np.cos(2 * np.pi * s), c.g * (1 + 0.1 * np.sin(
            2 * np.pi * s + 0.4)), grid, c.theta0, c.origin)

    c = state(Fourier(257))
    r = geometry.M_adjoint(c) @ E.gradient(c)
    assert np.abs(r[c.N:]).max() < 1e-8 * np.abs(E.gradient(c)).max()
    Ns = [256, 512, 1024]
    errs = []
    for N in Ns:
        c = state(FiniteDifference(N))
        errs.append(np.abs((geometry.M_adjoint(c) @ E.gradient(c))[N:]).max())
    assert abs(fitted_order(Ns, errs) - 2) < 0.25


@pytest.mark.parametrize("ename", ["faceting", "helfrich"])
def test_dissipation_rate(ename):
    """gamma_t = V^n n changes the (position-based) energy at the rate -int (V^n)^2 dsigma."""
    E = ENERGIES[ename]
    grid = Fourier(201)
    c = Curve.polar(lambda t: 1.3 + 0.15 * np.cos(3 * t) + 0.1 * np.sin(2 * t + 0.3), grid)
    V = E.normal_velocity(c)
    x, y = c.positions()
    n = c.normal()
    rate = -np.sum(V**2 * c.dsigma)
    dt = 1e-4 / np.abs(V).max()

    def energy_after(t):
        return E.energy(Curve.from_positions(x + t * V * n[0], y + t * V * n[1], grid))

    num = (energy_after(dt) - energy_after(-dt)) / (2 * dt)
    assert num / rate == pytest.approx(1.0, abs=1e-4)


def test_faceting_normal_velocity_matches_printed_formula():
    """e:Facet-NV: V = -G(-a^2 Lap k + W'(k)) - k(-a^2/2 |grad k|^2 + W(k) + beta(L - L*))."""
    E = ENERGIES["faceting"]
    c = skew_curve(Fourier(129))
    lap, G = to_dense(geometry.laplace_s(c)), to_dense(geometry.helmholtz(c))
    k = c.kappa
    w = DoubleWell(5.0)
    ks = c.grad_s(k)
    mu = -0.01 * lap @ k + w.dW(k)
    ref = -G @ mu - k * (-0.005 * ks**2 + w.W(k) + 5.0 * (c.length() - 6.0))
    assert np.abs(E.normal_velocity(c) - ref).max() < 1e-9 * np.abs(ref).max()


def test_helfrich_normal_velocity_formula():
    """V = eps(Lap k + k^3/2) - beta (L - L*) k (Conventions and errata, section 3)."""
    E = ENERGIES["helfrich"]
    c = skew_curve(Fourier(129))
    k = c.kappa
    ref = 0.1 * (to_dense(geometry.laplace_s(c)) @ k + k**3 / 2) - 1.0 * (c.length() - 9.0) * k
    assert np.abs(E.normal_velocity(c) - ref).max() < 1e-10 * np.abs(ref).max()


@pytest.mark.parametrize("grid", [Fourier(33), FiniteDifference(32)])
@pytest.mark.parametrize("R", [0.4, 1.0, 2.5])
def test_circle_equilibrium_length(grid, R):
    k0 = 1 / R
    w = DoubleWell(5.0)
    beta = 5.0
    Lstar = 2 * np.pi * R - (k0 * w.dW(k0) - w.W(k0)) / beta
    c = Curve.circle(R, grid)
    assert np.allclose(c.kappa, k0) and np.abs(c.closure()).max() < 1e-12
    E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=beta, L_star=Lstar)
    V = E.normal_velocity(c)
    assert np.abs(V).max() < 1e-10 * (abs(k0 * w.W(k0)) + k0**3)
    # a shifted L* does not give an equilibrium: V = -beta (L - L*) k0 changes by beta dL k0
    E2 = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=beta, L_star=Lstar + 0.1)
    assert np.allclose(E2.normal_velocity(c), beta * 0.1 * k0)
    eps = 0.3
    Lh = 2 * np.pi * R - eps * k0**2 / (2 * beta)
    Eh = CanhamHelfrich(eps) + Perimeter(beta=beta, L_star=Lh)
    assert np.abs(Eh.normal_velocity(c)).max() < 1e-10 * (eps * k0**3)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Faceting(alpha=0.0, kstar=5.0), "alpha"),
        (lambda: Faceting(alpha=-0.1, kstar=5.0), "alpha"),
        (lambda: Faceting(alpha=0.1, kstar=np.nan), "kstar"),
        (lambda: Faceting(alpha=0.1, kstar=5.0, well=object()), "well"),
        (lambda: CanhamHelfrich(eps=-1.0), "eps"),
        (lambda: Perimeter(beta=-1.0, L_star=1.0), "beta"),
        (lambda: Perimeter(beta=1.0, L_star=0.0), "L_star"),
        (lambda: Perimeter(beta="x", L_star=1.0), "beta"),
        (lambda: FirstOrderEnergy(1, 2, 3, 4, 5, 6), "callable"),
    ],
)
def test_bad_parameters(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_energy_sums():
    F, P = Faceting(0.1, 5.0), Perimeter(5.0, 6.0)
    c = skew_curve(Fourier(33))
    S = F + P
    assert S.energy(c) == pytest.approx(F.energy(c) + P.energy(c))
    assert np.allclose(S.gradient(c), F.gradient(c) + P.gradient(c))
    assert len((S + CanhamHelfrich(0.1)).terms()) == 3
