"""FrontODE: its derivatives, metric, constraints, velocity, named evaluation and linearization."""

import numpy as np
import pytest

from qsa.equilibria import splice_closure, splice_polygon
from qsa.paper import SCENARIOS
from qsa.reduction.manifold import closure, energy_gradient, length_derivatives
from qsa.reduction.ode import FrontODE

ALPHA, KSTAR = 0.1, 5.0


def test_default_resolution_is_converged(triangle):
    ode, p, cut = triangle
    fine = FrontODE(ALPHA, KSTAR, ode.length, points_per_width=24).velocity(p, cut)
    coarse = FrontODE(ALPHA, KSTAR, ode.length).velocity(p, cut)
    assert np.max(np.abs(coarse - fine)) < 1e-5 * np.max(np.abs(fine))


def test_gradient_matches_energy_differences(triangle):
    ode, p, cut = triangle
    g = ode.gradient(p, cut)
    h = 2e-5
    fd = np.array([(ode.energy(p + h * e, cut) - ode.energy(p - h * e, cut)) / (2 * h)
                   for e in np.eye(p.size)])
    assert np.max(np.abs(g - fd)) < 1e-5 * np.max(np.abs(g))
    assert np.max(np.abs(g)) > 1e-5  # unequal facets: a real interaction force


def curve_positions(ode, p, cut):
    """gamma(sigma) of the splice (gamma(0) = 0, theta(0) = 0) by a different quadrature."""
    from scipy.integrate import cumulative_trapezoid

    s = np.linspace(0, ode.length, 40001)
    psi = ode.profile(p, cut)(s)
    theta = cumulative_trapezoid(psi, s, initial=0)
    x = cumulative_trapezoid(np.cos(theta), s, initial=0)
    y = cumulative_trapezoid(np.sin(theta), s, initial=0)
    return s, np.stack([x, y], 1), theta


def test_normal_velocities_match_position_differences(triangle):
    # along directions tangent to the closure constraints the perturbed curves stay
    # closed (to O(h^2)) and the normal displacement is periodic
    ode, p, cut = triangle
    phi, w = ode.normal_velocities(p, cut)
    s, gam, theta = curve_positions(ode, p, cut)
    n = np.stack([np.sin(theta), -np.cos(theta)], 1)
    tau = np.stack([np.cos(theta), np.sin(theta)], 1)
    R = np.column_stack([n[:, 0], n[:, 1], np.sum(gam * tau, 1)])
    wt = np.full(s.size, s[1] - s[0])
    wt[[0, -1]] *= 0.5
    h = 1e-5
    T = ode.tangent_basis(p, cut)
    for q in T.T:
        dg = (curve_positions(ode, p + h * q, cut)[1]
              - curve_positions(ode, p - h * q, cut)[1]) / (2 * h)
        f = np.sum(n * dg, 1)
        c = np.linalg.solve(R.T @ (wt[:, None] * R), R.T @ (wt * f))
        ref = np.interp(ode.sigma, s, f - R @ c)
        assert np.max(np.abs(phi @ q - ref)) < 1e-5 * np.max(np.abs(ref))
    G = ode.metric(p, cut)
    assert np.allclose(G, G.T)
    ev = np.linalg.eigvalsh(G)
    assert abs(ev[0]) < 1e-6 * ev[-1] and ev[1] > 1e-4 * ev[-1]  # only the shift is free
    assert np.linalg.norm(G @ np.ones(p.size)) < 1e-6 * ev[-1]


def test_constraints_match_splice_closure_and_differences(triangle):
    ode, p, cut = triangle
    C, J = ode.constraints(p, cut)
    C2, J2 = splice_closure(ode.profile(p, cut), ode.grid)
    assert np.allclose(C, C2, atol=1e-14) and np.allclose(J, J2, atol=1e-13)
    assert np.linalg.norm(C) < 1e-10
    h = 1e-6
    fd = np.column_stack([(ode.constraints(p + h * e, cut)[0]
                           - ode.constraints(p - h * e, cut)[0]) / (2 * h)
                          for e in np.eye(p.size)])
    assert np.max(np.abs(J - fd)) < 1e-7


def test_velocity_is_tangent_and_dissipative(triangle):
    ode, p, cut = triangle
    F, mu = ode.velocity(p, cut, multipliers=True)
    _, J = ode.constraints(p, cut)
    assert np.max(np.abs(J @ F)) < 1e-12 * np.max(np.abs(J)) * np.max(np.abs(F))
    assert abs(F.sum()) < 1e-12
    G = ode.metric(p, cut)
    dEdt = ode.gradient(p, cut) @ F
    assert dEdt < 0 and np.isclose(dEdt, -F @ G @ F, rtol=1e-8)
    # Galerkin: any other admissible velocity fits V^n no better (dE/dt is extremal)
    T = ode.tangent_basis(p, cut)
    q = F + T @ np.array([1e-3, -2e-3])
    assert 0.5 * q @ G @ q + ode.gradient(p, cut) @ q > 0.5 * F @ G @ F + dEdt


def test_regular_polygon_is_stationary_and_symmetric():
    eq = splice_polygon(np.full(3, 2 * np.pi / 3), np.full(3, 0.35), ALPHA, kstar=KSTAR)
    p = np.array(eq.params["positions"])
    ode = FrontODE(ALPHA, KSTAR, eq.params["L"])
    assert np.max(np.abs(ode.velocity(p))) < 1e-10
    ev = ode.eigenvalues(p)
    assert ev.size == 2 and np.allclose(ev.imag, 0)
    assert ev[0].real > 0 and np.isclose(ev[0].real, ev[1].real, rtol=1e-5)  # E-symmetric pair

def test_bad_input(triangle):
    ode, p, cut = triangle
    with pytest.raises(ValueError, match="alpha"):
        FrontODE(-1.0, KSTAR, 2.0)
    with pytest.raises(ValueError, match="p must"):
        ode.velocity(p[::-1])
    with pytest.raises(ValueError, match="p must"):
        ode.velocity(p[:5])
    with pytest.raises(ValueError, match="t_final"):
        ode.integrate(p, -1.0)


@pytest.mark.parametrize("angles, facets", [(s.angles, s.facets) for s in SCENARIOS.values()])
def test_galerkin_identity_with_full_normal_velocity(angles, facets):
    # <V^n, phi_j^perp> = -dE/dp_j on the tangent space: V^n from qsa.energies (e:Facet-NV)
    # on the splice curve, phi from the ODE's own pull-back -- independent code paths
    L = splice_polygon(np.deg2rad(angles), facets, ALPHA, kstar=KSTAR).params["L"]
    ode = FrontODE(ALPHA, KSTAR, L, points_per_width=8)
    eq = splice_polygon(np.deg2rad(angles), facets, ALPHA, kstar=KSTAR, grid=ode.grid)
    p, cut = np.array(eq.params["positions"]), tuple(eq.params["cutoff"])
    V = eq.energy.normal_velocity(eq.curve)
    phi, w = ode.normal_velocities(p, cut)
    T = ode.tangent_basis(p, cut)
    proj = (V * w) @ phi @ T
    grad = ode.gradient(p, cut) @ T
    assert np.max(np.abs(proj + grad)) < 1e-5 * np.max(np.abs(grad))
    # the splice's V^n is mostly off the tangent space (fast): the reduction keeps its
    # projection only
    assert np.max(np.abs(V)) > 10 * np.max(np.abs(grad))

def test_variable_length_dissipates_and_tends_to_fixed_length(triangle):
    ode, p, cut = triangle
    L = ode.length
    var = FrontODE(ALPHA, KSTAR, L, beta=5.0, points_per_width=8, L_star=L + 0.01)
    dp, dL = var.velocity_length(p, L, cut)
    f = var.fields(p, cut, L)
    dEL, dC = length_derivatives(f, ALPHA, var.front.well)
    _, J = closure(f)
    assert np.max(np.abs(J @ dp + dC * dL)) < 1e-10  # closure kept with L moving
    dEdt = energy_gradient(f, ALPHA, var.front.well) @ dp + (dEL + 5.0 * (L - var.L_star)) * dL
    assert dEdt < 0 and dL > 0  # too short: the perimeter term lengthens the curve
    # stiff perimeter: at the quasi-static length (L' = 0) the positions move as in the
    # fixed-length reduction (the L direction costs no dissipation by itself)
    from scipy.optimize import brentq

    stiff = FrontODE(ALPHA, KSTAR, L, beta=1e4, points_per_width=8)
    Lq = brentq(lambda x: stiff.velocity_length(p, x, cut)[1], L - 1e-4, L + 1e-4,
                xtol=1e-15)
    assert abs(Lq - L) < 1e-6
    dp_stiff = stiff.velocity_length(p, Lq, cut)[0]
    fixed = ode.velocity(p, cut)
    assert np.max(np.abs(dp_stiff - fixed)) < 1e-3 * np.max(np.abs(fixed))
    with pytest.raises(ValueError, match="beta"):
        ode.velocity_length(p, L)

def test_bad_correction():
    with pytest.raises(ValueError, match="correction"):
        FrontODE(ALPHA, KSTAR, 2.0, correction="exact")


@pytest.mark.parametrize("beta", [None, 5.0])
def test_evaluate_names_what_the_methods_return(triangle, beta):
    """``evaluate`` is one evaluation, named: the pieces the methods return and the solve."""
    ode, p, cut = triangle
    if beta is not None:
        ode = FrontODE(ALPHA, KSTAR, ode.length, beta=beta, points_per_width=8)
    L = None if beta is None else ode.length
    e = ode.evaluate(p, cut, L)
    n = p.size + (beta is not None)
    assert e.velocity.shape == (n,) and e.multipliers.shape == (4,)
    assert e.matrix.shape == (n + 4, n + 4) and e.metric.shape == (n, n)
    assert np.allclose(e.matrix @ np.concatenate([e.velocity, e.multipliers]), e.rhs,
                       rtol=0, atol=1e-12 * np.max(np.abs(e.rhs)))
    assert np.array_equal(e.rhs[:n], -e.force) and not np.any(e.rhs[n:])
    # (the compiled backend's velocity-only kernel may differ from the full one in the
    # last bits: contraction to FMA is decided per compiled function)
    if beta is None:
        assert np.allclose(e.velocity, ode.velocity(p, cut), rtol=1e-12, atol=0)
        assert np.array_equal(e.metric, ode.metric(p, cut))
        assert np.array_equal(e.force, ode.gradient(p, cut))
        assert np.array_equal(e.closure, ode.constraints(p, cut)[0])
        phi, w = ode.normal_velocities(p, cut)
        assert np.array_equal(e.normal_velocities, phi) and np.array_equal(e.weights, w)
    else:
        dp, dL = ode.velocity_length(p, L, cut)
        assert np.allclose(e.velocity, np.append(dp, dL), rtol=1e-12, atol=0)
        assert not np.any(e.metric[-1]) and not np.any(e.metric[:, -1])  # L' costs nothing
        assert np.array_equal(ode.rhs(np.append(p, L), cut), np.append(dp, dL))


def test_evaluate_bad_input(triangle):
    ode, p, cut = triangle
    with pytest.raises(ValueError, match="beta"):
        ode.evaluate(p, cut, L=ode.length)  # a length needs the variable-length reduction
    var = FrontODE(ALPHA, KSTAR, ode.length, beta=5.0)
    with pytest.raises(ValueError, match="L must"):
        var.evaluate(p, cut, L=-1.0)
    with pytest.raises(ValueError, match="p must"):
        var.evaluate(p, cut, L=0.5 * (p[-1] - p[0]))



def test_pickles_for_process_pools(triangle):
    import pickle

    ode, p, cut = triangle
    other = pickle.loads(pickle.dumps(ode))
    assert other.backend_used == ode.backend_used
    assert np.array_equal(other.velocity(p, cut), ode.velocity(p, cut))


def test_corrected_jacobian_is_consistently_differenced(triangle):
    # jacobian() differences the velocity of the ODE's own force: with the Newton
    # correction the corrected velocity (central differences, O(h^2))
    ode, p, cut = triangle
    corr = FrontODE(ALPHA, KSTAR, ode.length, points_per_width=8, correction="newton")
    h = 1e-3 * corr.front.width
    J, JT = corr.jacobian(p, cut)
    J2, _ = corr.jacobian(p, cut, step=h / 2)
    assert np.max(np.abs(J - J2)) < 1e-5 * np.max(np.abs(J))
    # a directional difference of the corrected velocity along a tangent direction
    q = corr.tangent_basis(p, cut)[:, 0]
    dv = (corr.velocity(p + 10 * h * q, cut) - corr.velocity(p - 10 * h * q, cut)) / (20 * h)
    assert np.max(np.abs(J @ q - dv)) < 1e-4 * np.max(np.abs(dv))
    # and it is not the uncorrected Jacobian (by 0.1% here, far above the differencing)
    J0, _ = ode.jacobian(p, cut)
    assert np.max(np.abs(J - J0)) > 100 * np.max(np.abs(J - J2))
    ev = corr.eigenvalues(p, cut)
    assert np.allclose(np.sort(ev.real), np.sort(np.linalg.eigvals(JT).real))
