"""The manifold of constrained quasi-steady profiles and the reduction built on it."""

import numpy as np
import pytest
from scipy.optimize import brentq

from qsa.discretize import Fourier
from qsa.equilibria import default_cutoff, polish, splice_polygon
from qsa.equilibria.splice import polygon_positions
from qsa.reduction.manifold import (
    PeriodicQuadrature,
    closure,
    energy,
    normal_velocities,
    splice_fields,
)
from qsa.reduction.ode import FrontODE
from qsa.reduction.quasisteady import (
    closure_gradients,
    closure_hessians,
    metric_covectors,
    periodic_d2,
    profile_normal_velocities,
    quasisteady_profile,
)

ALPHA, KSTAR = 0.1, 5.0


def _regular(n, facet, dL=0.0):
    """Positions, length and cutoff of the regular rounded polygon (facets + dL / n)."""
    p, L = polygon_positions(np.full(n, 2 * np.pi / n), np.full(n, facet + dL / n), KSTAR)
    return p, L, default_cutoff(p, L)


def _profile(ode, p, cut, lag=False):
    ref = ode.evaluator
    return quasisteady_profile(ref.fields(p, cut), ALPHA, ode.front.well, ref.band,
                               ref.quadrature, lag=lag)


@pytest.fixture(scope="module")
def octagon():
    p, L, cut = _regular(8, 0.35)
    return FrontODE(ALPHA, KSTAR, L, correction="profile"), p, cut


@pytest.fixture(scope="module")
def triangle():
    eq = splice_polygon(np.radians([130, 120, 110]), [0.3, 0.4, 0.5], ALPHA, kstar=KSTAR)
    p = np.array(eq.params["positions"])
    return FrontODE(ALPHA, KSTAR, eq.params["L"], correction="profile"), p, \
        tuple(eq.params["cutoff"])


def test_cumulative_transpose_is_the_adjoint():
    q = PeriodicQuadrature(17)
    rng = np.random.default_rng(1)
    F, Y = rng.standard_normal((17, 3)), rng.standard_normal((17, 3))
    assert np.isclose(np.sum(Y * q.cumulative(F)), np.sum(q.cumulative_transpose(Y) * F),
                      rtol=1e-13)


def test_closure_gradients_and_hessians_against_differences(triangle):
    ode, p, cut = triangle
    ref = ode.evaluator
    quad, L = ref.quadrature, ode.length
    f = ref.fields(p, cut)
    # d C1 / d kappa on the nodes: a random smooth change of kappa
    X = np.cos(2 * np.pi * 3 * quad.s) + 0.3 * np.sin(2 * np.pi * 5 * quad.s)
    g = closure_gradients(f.theta, quad, L)

    def c1(kappa):
        th = L * quad.cumulative(kappa[:, None])[:, 0]
        return (L / quad.M) * np.array([np.cos(th).sum(), np.sin(th).sum()])

    e = 1e-6
    fd = (c1(f.psi + e * X) - c1(f.psi - e * X)) / (2 * e)
    np.testing.assert_allclose((L / quad.M) * g.T @ X, fd, rtol=1e-7, atol=1e-10)
    # d^2 C1 / d p_i d p_j: differences of the closure Jacobian
    H1 = closure_hessians(f, quad)
    e = 1e-5
    for j in range(p.size):
        d = np.zeros(p.size)
        d[j] = e
        dA = (closure(ref.fields(p + d, cut))[1] - closure(ref.fields(p - d, cut))[1]) / (2 * e)
        np.testing.assert_allclose(H1[:, :, j], dA[:2], atol=1e-6 * np.abs(H1).max())


def test_profile_solves_the_constrained_problem(triangle):
    ode, p, cut = triangle
    ref = ode.evaluator
    f = ref.fields(p, cut)
    qs = _profile(ode, p, cut)
    assert qs.converged and qs.iterations <= 6
    kappa, L, M = qs.fields.psi, ode.length, ref.quadrature.M
    R = -(ALPHA**2) * (f.d2psi + periodic_d2(qs.delta, L)) + ode.front.well.dW(kappa)
    np.testing.assert_allclose(qs.residual, R)
    # R lies in span{psi_p t (t keeping the closure), 1, dC1/dkappa}
    C0, A = closure(f)
    Tc = np.linalg.svd(A)[2][3:].T
    B = np.column_stack([f.dpsi_dp @ Tc, np.ones(M),
                         closure_gradients(qs.fields.theta, ref.quadrature, L)])
    off = R - B @ np.linalg.lstsq(B, R, rcond=None)[0]
    assert np.abs(off).max() < 1e-9  # Newton tolerance 1e-11 kstar, times W''
    # the gauge and the constraints: the splice's closure, its turning
    assert np.abs(Tc.T @ f.dpsi_dp.T @ qs.delta).max() < 1e-9
    assert abs(qs.delta.sum()) < 1e-9
    np.testing.assert_allclose(closure(qs.fields)[0], C0, atol=1e-11)


@pytest.mark.parametrize("shape, tol", [("octagon", 1e-7), ("triangle", 1e-5)])
def test_tangents_are_the_derivatives_of_the_profile(shape, tol, request):
    """``kappa_j`` against central differences of ``kappa(p)`` (the multipliers of C1,
    zero on a regular polygon, are not differentiated: ~1e-6 on the unequal triangle)."""
    ode, p, cut = request.getfixturevalue(shape)
    K = _profile(ode, p, cut).fields.dpsi_dp
    e = 1e-5
    for j in (0, 1, p.size - 1):
        d = np.zeros(p.size)
        d[j] = e
        fd = (_profile(ode, p + d, cut).fields.psi - _profile(ode, p - d, cut).fields.psi) / (2 * e)
        assert np.abs(fd - K[:, j]).max() < tol * np.abs(K[:, j]).max()


def test_octagon_profile_is_the_polished_n_pulse():
    """At the N-pulse's length the regular splice's profile is the exact equilibrium:
    plateaus lifted by the turning multiplier, corners shortened (the splice is 0.12 off)."""
    n, facet = 8, 0.35
    p, L, _ = _regular(n, facet)
    ode0 = FrontODE(ALPHA, KSTAR, L, correction="profile")
    eq = splice_polygon(np.full(n, 2 * np.pi / n), np.full(n, facet), ALPHA, kstar=KSTAR,
                        grid=Fourier(ode0.grid.s.size))
    pol = polish(eq.energy, eq.curve)
    assert pol.success and pol.residual < 1e-6
    c = pol.curve
    assert np.ptp(c.dsigma) < 1e-12  # uniform g: compare on the same nodes
    p, L, cut = _regular(n, facet, c.length() - L)
    ode = FrontODE(ALPHA, KSTAR, L, correction="profile")
    assert ode.grid.s.size == c.N
    qs = _profile(ode, p, cut)
    nu = qs.multipliers[-3]
    assert 0.5 < nu < 0.56 and np.abs(qs.multipliers[:-3]).max() < 1e-10
    # same rest point up to the base point: align by the shift nearest the splice's
    k = np.arange(c.N // 2 + 1)
    F = np.fft.rfft(c.kappa)
    shifts = np.linspace(-2, 2, 801) / c.N
    err = [np.abs(np.fft.irfft(F * np.exp(-2j * np.pi * k * s), n=c.N) - qs.fields.psi).max()
           for s in shifts]
    assert min(err) < 2e-4  # 9e-8 measured
    assert np.abs(qs.fields.psi - ode.evaluator.fields(p, cut).psi).max() > 0.1


def test_metric_covectors_give_the_metric(triangle):
    ode, p, cut = triangle
    ref = ode.evaluator
    f = _profile(ode, p, cut).fields
    phi = normal_velocities(f, ref.quadrature)
    r = metric_covectors(f, ref.quadrature, phi)
    T = ode.tangent_basis(p, cut)
    G = phi.T @ (f.weights[:, None] * phi)
    np.testing.assert_allclose(T.T @ r.T @ f.dpsi_dp @ T, T.T @ G @ T,
                               atol=1e-6 * np.abs(G).max())


def test_lag_matrix_is_positive_semidefinite(triangle):
    ode, p, cut = triangle
    C = _profile(ode, p, cut, lag=True).lag
    assert np.allclose(C, C.T) and np.linalg.eigvalsh(C).min() > -1e-12 * np.abs(C).max()


def test_profile_reduction_decreases_the_energy(triangle):
    ode, p, cut = triangle
    e = ode.evaluate(p, cut)
    assert ode.backend_used == "numpy"
    assert abs(e.velocity.sum()) < 1e-12 and e.force @ e.velocity < 0
    np.testing.assert_allclose(e.force @ e.velocity,
                               -e.velocity @ e.metric @ e.velocity, rtol=1e-8)
    np.testing.assert_allclose(e.closure_jacobian @ e.velocity, 0, atol=1e-10)


def test_profile_force_is_the_derivative_of_the_energy_on_the_manifold(triangle):
    ode, p, cut = triangle
    ref = ode.evaluator
    L, M = ode.length, ref.quadrature.M

    def energy(q):
        kappa = _profile(ode, q, cut).fields.psi
        k = 2 * np.pi * np.fft.rfftfreq(M, d=1.0 / M) / L
        dk = np.fft.irfft(1j * k * np.fft.rfft(kappa), n=M)
        return (L / M) * np.sum(0.5 * ALPHA**2 * dk**2 + ode.front.well.W(kappa))

    force = ode.evaluate(p, cut).force
    T = ode.tangent_basis(p, cut)
    e = 1e-4
    for t in T.T[:3]:
        fd = (energy(p + e * t) - energy(p - e * t)) / (2 * e)
        assert abs(fd - force @ t) < 1e-5 * np.abs(force).max()


def test_profile_lag_reduction_runs_and_matches_at_rest(octagon):
    ode, p, cut = octagon
    lagged = FrontODE(ALPHA, KSTAR, ode.length, correction="profile-lag")
    v0, v1 = ode.velocity(p, cut), lagged.velocity(p, cut)
    assert np.abs(v0).max() < 1e-8 and np.abs(v1).max() < 1e-8  # a rest point


def test_profile_options_are_checked():
    with pytest.raises(ValueError, match="backend='numba'"):
        FrontODE(ALPHA, KSTAR, 4.0, correction="profile", backend="numba")
    with pytest.raises(ValueError, match="correction must be"):
        FrontODE(ALPHA, KSTAR, 4.0, correction="exact")
    assert FrontODE(ALPHA, KSTAR, 4.0, correction="profile").backend_used == "numpy"


# ---- variable length


def _profile_at(ode, p, L, cut, length=False, lag=False):
    """The profile at length ``L`` (nodes at fixed ``s``), with its tangent in ``L``."""
    ref = ode.evaluator
    f = splice_fields(ode.front, p, L, cut, ref.quadrature, variable=True)
    return quasisteady_profile(f, ALPHA, ode.front.well, ref.band, ref.quadrature,
                               length=length, lag=lag)


@pytest.mark.parametrize("shape, tol", [("octagon", 1e-7), ("triangle", 1e-5)])
def test_length_tangent_is_the_derivative_of_the_profile(shape, tol, request):
    """``d kappa / dL`` at fixed ``s`` against central differences of ``kappa(p, L)``
    (3e-10 on the octagon, 3e-7 on the triangle: its undifferentiated ``nu_2, nu_3``)."""
    ode, p, cut = request.getfixturevalue(shape)
    L = ode.length
    KL = _profile_at(ode, p, L, cut, length=True).fields.g_L
    e = 1e-5
    fd = (_profile_at(ode, p, L + e, cut).fields.psi
          - _profile_at(ode, p, L - e, cut).fields.psi) / (2 * e)
    assert np.abs(fd - KL).max() < tol * np.abs(KL).max()


def test_length_normal_velocity_against_the_moving_curve(octagon):
    """``phi_L``: the normal part of ``d gamma / dL`` (fixed ``s``) of the curve of
    ``kappa(p, L)``, modulo rigid motions; not small where the corners overlap."""
    ode, p, cut = octagon
    L, quad = ode.length, ode.evaluator.quadrature
    qs = _profile_at(ode, p, L, cut, length=True)

    def curve(Lv):
        th = Lv * quad.cumulative(_profile_at(ode, p, Lv, cut).fields.psi[:, None])[:, 0]
        return Lv * quad.cumulative(np.column_stack([np.cos(th), np.sin(th)])), th

    e = 1e-5
    dg = (curve(L + e)[0] - curve(L - e)[0]) / (2 * e)
    g0, th = curve(L)
    sn, cs = np.sin(th), np.cos(th)
    phi = sn * dg[:, 0] - cs * dg[:, 1]
    Rr = np.column_stack([sn, -cs, g0[:, 0] * cs + g0[:, 1] * sn])
    Rw = Rr.T * qs.fields.weights
    phi -= Rr @ np.linalg.solve(Rw @ Rr, Rw @ phi)
    got = profile_normal_velocities(qs.fields, quad)
    assert got.shape == (quad.M, p.size + 1)
    assert np.abs(phi).max() > 1e-3  # 7e-3: the plateaus' lift changes with L
    assert np.abs(got[:, -1] - phi).max() < 1e-6 * np.abs(phi).max()  # 6e-8 measured


def test_variable_length_force_is_the_derivative_of_the_energy(triangle):
    """``dE/dL`` on the manifold (perimeter penalty included) against differences, and
    the energy decreasing at the rate ``v^T G v`` with the length's own metric column."""
    ode0, p, cut = triangle
    L = ode0.length
    ode = FrontODE(ALPHA, KSTAR, L, beta=5.0, L_star=L - 0.01, correction="profile")

    def total(Lv):
        f = _profile_at(ode, p, Lv, cut).fields
        return energy(f, ALPHA, ode.front.well) + 2.5 * (Lv - ode.L_star) ** 2

    e = ode.evaluate(p, cut, L)
    h = 1e-5
    assert abs(e.force[-1] - (total(L + h) - total(L - h)) / (2 * h)) < 1e-8  # 7e-11
    v = e.velocity
    assert e.metric.shape == (p.size + 1, p.size + 1) and e.metric[-1, -1] > 0
    np.testing.assert_allclose(e.force @ v, -v @ e.metric @ v, rtol=1e-10)
    # the closure is kept to first order: dC/dp p' + dC/dL L' = 0
    A = e.matrix[p.size + 1:p.size + 4, :p.size + 1]
    np.testing.assert_allclose(A @ v, 0, atol=1e-10)
    lagged = FrontODE(ALPHA, KSTAR, L, beta=5.0, L_star=L - 0.01, correction="profile-lag")
    w = lagged.velocity_length(p, L, cut)
    assert abs(w[1] - v[-1]) < 0.01 * abs(v[-1])  # the lag is small away from rest


def test_variable_length_lag_matrix_has_the_length_row(octagon):
    """With the length the lag matrix gains its row and column (``phi_L``), symmetric
    and positive semi-definite, ``C_LL > 0``."""
    ode, p, cut = octagon
    C = _profile_at(ode, p, ode.length, cut, length=True, lag=True).lag
    assert C.shape == (p.size + 1, p.size + 1) and C[-1, -1] > 0
    assert np.allclose(C, C.T) and np.linalg.eigvalsh(C).min() > -1e-12 * np.abs(C).max()


def test_variable_length_rest_point_is_the_polished_n_pulse():
    """On the octagon the length-free reduction rests at the N-pulse's length (the
    perimeter penalty against the lifted plateaus: 1.66e-3 longer than the splice;
    agreement 2e-13 measured), where the splice manifold rests 5e-4 below the splice's
    length, 2.2e-3 below the N-pulse's."""
    n, facet, beta = 8, 0.35, 5.0
    p0, L0, cut = _regular(n, facet)
    ode = FrontODE(ALPHA, KSTAR, L0, beta=beta, correction="profile")

    def length_rate(dL):
        p, L, _ = _regular(n, facet, dL)
        return ode.velocity_length(p, L, cut)

    dL = brentq(lambda d: length_rate(d)[1], 0.0, 4e-3, xtol=1e-15)
    v, _ = length_rate(dL)
    assert np.abs(v - v.mean()).max() < 1e-10  # a rest point (up to the base point)
    eq = splice_polygon(np.full(n, 2 * np.pi / n), np.full(n, facet), ALPHA, kstar=KSTAR,
                        beta=beta, grid=Fourier(ode.grid.s.size))
    pol = polish(eq.energy, eq.curve)
    assert pol.success and pol.residual < 1e-6
    assert abs(dL - (pol.curve.length() - L0)) < 1e-10
