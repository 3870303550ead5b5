"""SecondOrderEnergy and FunctionalizedCurvature: exact discrete derivatives, e:first_var,
e:LIE_NV, e:W-invar, the first-order special case and bad input."""

import dataclasses

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier, geometry
from qsa.energies import (
    DoubleWell,
    Faceting,
    FunctionalizedCurvature,
    Perimeter,
    SecondOrderEnergy,
    Well,
)
from qsa.linalg import to_dense
from tests.helpers import (
    assert_gradient_matches_energy,
    assert_hessian_matches_energy,
    coupled_energy,
    coupled_second_order,
    directions,
    fitted_order,
    off_manifold,
    skew_curve,
)

ENERGIES = {
    "coupled-node": coupled_second_order("node"),
    "coupled-edge": coupled_second_order("edge"),
    "functionalized": FunctionalizedCurvature(alpha=0.1, eta=1.5, kstar=3.0)
    + Perimeter(beta=2.0, L_star=5.0),
    "functionalized-eta0": FunctionalizedCurvature(alpha=0.2, eta=0.0, kstar=2.0),
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


@pytest.mark.parametrize("gname", GRIDS)
@pytest.mark.parametrize("ename", ENERGIES)
def test_factored_hessian_is_the_hessian(ename, gname):
    """``factored_hessian`` (order-4 blocks kept as ``T^T B T``) is the same operator."""
    E, grid = ENERGIES[ename], GRIDS[gname]
    c = off_manifold(grid, seed=5)
    F = E.factored_hessian(c)
    H = to_dense(E.hessian(c))
    assert type(F).__name__ == ("ReducedHessian" if grid.sparse else type(E.hessian(c)).__name__)
    assert np.abs(to_dense(F) - H).max() <= 1e-10 * np.abs(H).max()
    X = np.array(directions(grid, 3)).T
    assert np.allclose(F @ X, H @ X, rtol=0, atol=1e-10 * np.abs(H).max())


def test_fd_hessian_is_banded_and_sparse():
    """Every block couples nodes at most two apart: O(N) storage and assembly."""
    c = skew_curve(FiniteDifference(128))
    H = ENERGIES["coupled-node"].euclidean_hessian(c)
    assert H.nnz <= 4 * 5 * c.N
    N = c.N
    rows, cols = H.nonzero()
    dist = np.abs((rows % N) - (cols % N))
    assert np.minimum(dist, N - dist).max() == 2


@pytest.mark.parametrize("grid", [Fourier(65), FiniteDifference(64)])
def test_edge_placement_without_q_is_the_first_order_energy(grid):
    """F_q = 0 on edges: the discrete energy of FirstOrderEnergy, hence the same derivatives."""
    fo = coupled_energy()
    so = SecondOrderEnergy(
        F=lambda q, p, k: 0.01 * p**2 + 0.02 * p * k**2 + np.cosh(0.5 * k),
        dF=lambda q, p, k: (0 * q, 0.02 * p + 0.02 * k**2, 0.04 * p * k + 0.5 * np.sinh(0.5 * k)),
        d2F=lambda q, p, k: (0 * q, 0 * q, 0 * q, 0.02 + 0 * p, 0.04 * k,
                             0.04 * p + 0.25 * np.cosh(0.5 * k)),
        placement="edge")
    c = off_manifold(grid)
    assert so.energy(c) == pytest.approx(fo.energy(c), rel=1e-14)
    assert np.abs(so.gradient(c) - fo.gradient(c)).max() <= 1e-13 * np.abs(fo.gradient(c)).max()
    H1, H2 = to_dense(so.hessian(c)), to_dense(fo.hessian(c))
    assert np.abs(H1 - H2).max() <= 1e-13 * np.abs(H2).max()


@pytest.mark.parametrize("grid", [Fourier(33), FiniteDifference(32)])
def test_q_is_the_laplace_beltrami_of_kappa(grid):
    """F = q^2/2 at the nodes: E = 1/2 sum (laplace_s kappa)^2 dsigma."""
    E = SecondOrderEnergy(lambda q, p, k: 0.5 * q**2, lambda q, p, k: (q, 0 * q, 0 * q),
                          lambda q, p, k: (1 + 0 * q,) + (0 * q,) * 5)
    c = off_manifold(grid, seed=4)
    q = to_dense(geometry.laplace_s(c)) @ c.kappa
    assert E.energy(c) == pytest.approx(0.5 * np.sum(q**2 * c.dsigma), rel=1e-13)


def test_functionalized_is_squared_potential_minus_eta_faceting():
    alpha, eta, kstar = 0.15, 2.5, 4.0
    w = DoubleWell(kstar)
    Zsq = SecondOrderEnergy(
        lambda q, p, k: 0.5 * (alpha**2 * q - w.dW(k)) ** 2,
        lambda q, p, k: (alpha**2 * (alpha**2 * q - w.dW(k)), 0 * q,
                         -w.d2W(k) * (alpha**2 * q - w.dW(k))),
        lambda q, p, k: (alpha**4 + 0 * q, 0 * q, -alpha**2 * w.d2W(k), 0 * q, 0 * q,
                         w.d2W(k) ** 2 - w.d3W(k) * (alpha**2 * q - w.dW(k))))
    E = FunctionalizedCurvature(alpha, eta, kstar)
    F = Faceting(alpha, kstar)
    for grid in (Fourier(65), FiniteDifference(64)):
        c = off_manifold(grid, seed=5)
        assert E.energy(c) == pytest.approx(Zsq.energy(c) - eta * F.energy(c), rel=1e-13)
        ref = Zsq.gradient(c) - eta * F.gradient(c)
        assert np.abs(E.gradient(c) - ref).max() <= 1e-12 * np.abs(ref).max()
        Href = to_dense(Zsq.hessian(c)) - eta * to_dense(F.hessian(c))
        assert np.abs(to_dense(E.hessian(c)) - Href).max() <= 1e-12 * np.abs(Href).max()


def test_models_are_frozen_and_equal_by_value():
    E = FunctionalizedCurvature(0.1, 1, 5)
    assert dataclasses.is_dataclass(E) and E == FunctionalizedCurvature(alpha=0.1, eta=1.0,
                                                                        kstar=5.0,
                                                                        well=DoubleWell(5.0))
    assert hash(E) == hash(FunctionalizedCurvature(0.1, 1.0, 5.0))
    assert E.params() == {"energy": "FunctionalizedCurvature", "alpha": 0.1, "eta": 1.0,
                          "kstar": 5.0}
    with pytest.raises(dataclasses.FrozenInstanceError):
        E.eta = 2.0
    S = SecondOrderEnergy(_ok_F, _ok_dF, _ok_d2F)
    assert S == SecondOrderEnergy(_ok_F, _ok_dF, _ok_d2F) and S.placement == "node"
    with pytest.raises(dataclasses.FrozenInstanceError):
        S.placement = "edge"


def test_double_well_third_derivative():
    w = DoubleWell(3.0)
    k = np.linspace(-1, 4, 11)
    h = 1e-5
    assert np.allclose(w.d3W(k), (w.d2W(k + h) - w.d2W(k - h)) / (2 * h), rtol=1e-8, atol=1e-8)


def _spectral_ops(c):
    D = c.grid.derivative()
    grad = lambda f: (D @ f) / c.g
    return grad, lambda f: grad(grad(f))


def test_gradient_and_normal_velocity_are_e_first_var_and_e_LIE_NV():
    """Fourier: nabla_I E = (Lap F_q - grad F_p + F_k, (F - F_q Lap k + grad F_q grad k
    - F_p grad k)/g) (e:first_var) and V^n = -G d_kE - k g d_gE (e:LIE_NV), spectrally."""
    E = coupled_second_order()
    c = skew_curve(Fourier(257))
    grad, lap = _spectral_ops(c)
    k = c.kappa
    q, p = lap(k), grad(k)
    F = E.F(q, p, k)
    Fq, Fp, Fk = E.dF(q, p, k)
    mu = lap(Fq) - grad(Fp) + Fk
    xi = F - Fq * q + grad(Fq) * p - Fp * p
    out = E.gradient(c)
    assert np.abs(out[: c.N] - mu).max() <= 1e-9 * np.abs(mu).max()
    assert np.abs(c.g * out[c.N:] - xi).max() <= 1e-9 * np.abs(xi).max()
    V = lap(mu) + k**2 * mu - k * xi
    assert np.abs(E.normal_velocity(c) - V).max() <= 1e-8 * np.abs(V).max()


def test_functionalized_gradient_formulas():
    """mu = (alpha^2 Lap - W'' + eta) Z and g d_gE = Z^2/2 - alpha^2 Z Lap k
    + alpha^2 grad Z grad k + eta (alpha^2/2 |grad k|^2 - W) (module docstring)."""
    alpha, eta, kstar = 0.2, 1.5, 3.0
    E = FunctionalizedCurvature(alpha, eta, kstar)
    w = DoubleWell(kstar)
    c = skew_curve(Fourier(257))
    grad, lap = _spectral_ops(c)
    k = c.kappa
    Z = alpha**2 * lap(k) - w.dW(k)
    mu = alpha**2 * lap(Z) + (eta - w.d2W(k)) * Z
    xi = (0.5 * Z**2 - alpha**2 * Z * lap(k) + alpha**2 * grad(Z) * grad(k)
          + eta * (0.5 * alpha**2 * grad(k) ** 2 - w.W(k)))
    out = E.gradient(c)
    assert np.abs(out[: c.N] - mu).max() <= 1e-9 * np.abs(mu).max()
    assert np.abs(c.g * out[c.N:] - xi).max() <= 1e-9 * np.abs(xi).max()


@pytest.mark.parametrize("ename", ["coupled-node", "coupled-edge", "functionalized"])
def test_W_invar_identity(ename):
    """M-dagger_2 nabla_I E = d_kE nabla_s kappa - nabla_s(g d_gE) = 0 for every U (e:W-invar):
    spectrally small on Fourier grids, second order on finite differences."""
    E = ENERGIES[ename]

    def state(grid):
        c = Curve.polar(lambda t: 1.5 + 0.1 * np.cos(3 * t) + 0.05 * np.sin(2 * t), grid)
        s = grid.s
        return Curve(c.kappa + 0.1 + 0.1 * np.cos(2 * np.pi * s),
                     c.g * (1 + 0.1 * np.sin(2 * np.pi * s + 0.4)), grid, c.theta0, c.origin)

    c = state(Fourier(257))
    r = geometry.M_adjoint(c) @ E.gradient(c)
    assert np.abs(r[c.N:]).max() < 1e-8 * np.abs(E.gradient(c)).max()
    Ns = [256, 512, 1024]
    errs = []
    for N in Ns:
        c = state(FiniteDifference(N))
        errs.append(np.abs((geometry.M_adjoint(c) @ E.gradient(c))[N:]).max())
    assert abs(fitted_order(Ns, errs) - 2) < 0.2


def test_dissipation_rate():
    """gamma_t = V^n n changes the energy at the rate -int (V^n)^2 dsigma."""
    E = ENERGIES["functionalized"]
    grid = Fourier(201)
    c = Curve.polar(lambda t: 1.3 + 0.15 * np.cos(3 * t) + 0.1 * np.sin(2 * t + 0.3), grid)
    V = E.normal_velocity(c)
    x, y = c.positions()
    n = c.normal()
    rate = -np.sum(V**2 * c.dsigma)
    dt = 1e-4 / np.abs(V).max()

    def energy_after(t):
        return E.energy(Curve.from_positions(x + t * V * n[0], y + t * V * n[1], grid))

    # central differences at dt and 2 dt, Richardson-extrapolated (E'''(t) is large: stiff energy)
    d1, d2 = ((energy_after(h) - energy_after(-h)) / (2 * h) for h in (dt, 2 * dt))
    assert (4 * d1 - d2) / 3 / rate == pytest.approx(1.0, abs=1e-5)


# ------------------------------------------------------------------------ bad input
def _ok_F(q, p, k):
    return 0.5 * q**2 + k**2


def _ok_dF(q, p, k):
    return q, 0 * p, 2 * k


def _ok_d2F(q, p, k):
    z = 0 * q
    return 1 + z, z, z, z, z, 2 + z


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: SecondOrderEnergy(1.0, _ok_dF, _ok_d2F), "F must be a callable"),
        (lambda: SecondOrderEnergy(_ok_F, "dF", _ok_d2F), "dF must be a callable"),
        (lambda: SecondOrderEnergy(_ok_F, _ok_dF, None), "d2F must be a callable"),
        (lambda: SecondOrderEnergy(_ok_F, _ok_dF, _ok_d2F, placement="mid"), "placement"),
        (lambda: FunctionalizedCurvature(alpha=0.0, eta=1.0, kstar=5.0), "alpha"),
        (lambda: FunctionalizedCurvature(alpha=0.1, eta=np.nan, kstar=5.0), "eta"),
        (lambda: FunctionalizedCurvature(alpha=0.1, eta=1.0, kstar=-5.0), "kstar"),
        (lambda: FunctionalizedCurvature(0.1, 1.0, 2.0, well=Well(np.sin, np.cos, np.sin)),
         "d3W is missing"),
        (lambda: Well(np.sin, np.cos, np.sin, d3W=3.0), "d3W must be callable"),
    ],
)
def test_bad_parameters(make, match):
    with pytest.raises(ValueError, match=match):
        make()


@pytest.mark.parametrize(
    "kwargs, method, match",
    [
        (dict(dF=lambda q, p, k: (q, 2 * k)), "gradient",
         r"dF\(q, p, k\) must return 3 partial derivatives \(F_q, F_p, F_k\), got 2 values"),
        (dict(dF=lambda q, p, k: 1.0), "gradient", "must return 3 partial derivatives.*scalar"),
        (dict(d2F=lambda q, p, k: (1 + 0 * q,) * 5), "hessian",
         r"d2F\(q, p, k\) must return 6 partial derivatives"),
        (dict(F=lambda q, p, k: np.ones(3)), "energy", r"F\(q, p, k\) has shape \(3,\)"),
        (dict(dF=lambda q, p, k: (q[:-1], 0 * p, 2 * k)), "gradient",
         r"dF\(q, p, k\)\[0\] \(F_q\) has shape"),
        (dict(F=lambda q, p, k: np.log(k - 2.0)), "energy",
         r"F\(q, p, k\) is not finite at 33 of 33 points \(first at q=.*, k=1\)$"),
        (dict(d2F=lambda q, p, k: (1 / (0 * q),) + (0 * q,) * 5), "hessian",
         r"d2F\(q, p, k\)\[0\] \(F_qq\) is not finite"),
    ],
)
def test_bad_callables_raise_at_evaluation(kwargs, method, match):
    args = dict(F=_ok_F, dF=_ok_dF, d2F=_ok_d2F) | kwargs
    E = SecondOrderEnergy(**args)
    c = Curve.circle(1.0, Fourier(33))
    with np.errstate(all="ignore"), pytest.raises(ValueError, match=match):
        getattr(E, method)(c)


def test_bad_message_is_one_line():
    E = SecondOrderEnergy(_ok_F, lambda q, p, k: (q, k), _ok_d2F)
    with pytest.raises(ValueError) as info:
        E.gradient(Curve.circle(1.0, FiniteDifference(16)))
    assert "\n" not in str(info.value) and str(info.value).startswith("SecondOrderEnergy: ")
