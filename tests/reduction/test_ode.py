"""The front-position ODE: derivatives, metric, constraints, velocity, collisions."""

import numpy as np
import pytest

from qsa.equilibria import splice_closure, splice_polygon
from qsa.paper import SCENARIOS, scenario_splice
from qsa.reduction.ode import FrontODE, collision_distance, collision_sensitivity

ALPHA, KSTAR = 0.1, 5.0


@pytest.fixture(scope="module")
def triangle():
    eq = scenario_splice("triangle", ALPHA, KSTAR)
    p = np.array(eq.params["positions"])
    ode = FrontODE(ALPHA, KSTAR, eq.params["L"], points_per_width=8)
    return ode, p, tuple(eq.params["cutoff"])


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


def test_collision_distance_quartic():
    from qsa.equilibria import heteroclinic

    front = heteroclinic(ALPHA, kstar=KSTAR)
    assert np.isclose(collision_distance(front), 2 * np.log(3) / front.decay_rate, rtol=1e-10)


def test_collision_sensitivity_exact_for_pair_law():
    lam, c, d0 = 30.0, 1e-3, 0.3
    tc = (np.exp(lam * d0) - 1) / (lam * c)
    eps, t = 1e-4, 0.6 * tc

    def d(t, c):
        return np.log(np.exp(lam * d0) - lam * c * t) / lam

    assert np.isclose(d(t, c) - d(t, c * (1 + eps)), collision_sensitivity(eps, t, tc, lam),
                      rtol=1e-2)


def test_integrate_removes_pair_and_recloses():
    eq = scenario_splice("short-facet", ALPHA, KSTAR)
    p = np.array(eq.params["positions"])
    ode = FrontODE(ALPHA, KSTAR, eq.params["L"])
    r = ode.integrate(p, 0.08, rtol=1e-6, max_collisions=1)
    assert r.success and len(r.events) >= 1
    ev = r.first_collision
    assert ev.fronts == (3, 4)  # the short facet [p_4, p_5] (0-based 3, 4)
    assert np.isclose(ev.gap, ode.collision_distance, rtol=1e-6)
    seg = r.segments[1]
    assert seg.p.shape[1] == 6
    C, _ = ode.constraints(seg.p[0], seg.cutoff)
    assert np.linalg.norm(C) < 1e-10
    P = r.positions
    assert np.all(np.isnan(P[-1, [3, 4]])) and np.all(np.isfinite(P[-1, [0, 1, 2, 5, 6, 7]]))
    # the energy decreases along the first segment
    s0 = r.segments[0]
    E = [ode.energy(q, s0.cutoff) for q in s0.p[:: max(1, len(s0.p) // 8)]]
    assert np.all(np.diff(E) < 0)
    # collision time independent of the ODE tolerance
    r2 = ode.integrate(p, 0.08, rtol=1e-9, max_collisions=0)
    assert abs(r2.first_collision.time - ev.time) < 1e-4 * ev.time


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


def test_collision_across_the_base_point():
    # the short facet is the last one: s = 0 lies in its middle, the pair is (last, first)
    eq = splice_polygon(np.deg2rad([80, 100, 90, 90]), [0.5, 0.35, 0.5, 0.28], ALPHA,
                        kstar=KSTAR)
    p = np.array(eq.params["positions"])
    L = eq.params["L"]
    ode = FrontODE(ALPHA, KSTAR, L)
    r = ode.integrate(p, 0.08, rtol=1e-5, max_collisions=1)
    ev = r.first_collision
    assert set(ev.fronts) == {0, 7}
    seg = r.segments[1]
    q = seg.p[0]
    assert seg.ids.tolist() == [2, 3, 4, 5, 6, 1]  # the first kept front is up-front 2
    assert np.all(np.diff(q) > 0) and q[-1] - q[0] < L
    assert np.linalg.norm(ode.constraints(q, seg.cutoff)[0]) < 1e-10


@pytest.mark.parametrize("scenario", ["triangle", "short-facet"])
def test_length_derivatives_match_differences(scenario):
    eq = scenario_splice(scenario)
    p, L, cut = np.array(eq.params["positions"]), eq.params["L"], tuple(eq.params["cutoff"])
    ode = FrontODE(ALPHA, KSTAR, L, beta=5.0, points_per_width=8)
    dE, dC = ode._length_derivatives(ode._fields(p, cut, L))
    h = 1e-5
    fp, fm = ode._fields(p, cut, L + h), ode._fields(p, cut, L - h)
    fdE = (ode._energy(fp) - ode._energy(fm)) / (2 * h)
    fdC = (ode._constraints(fp)[0] - ode._constraints(fm)[0]) / (2 * h)
    assert abs(dE - fdE) < 1e-6 * abs(fdE) and abs(fdE) > 1e-5  # the wrap facet's force
    assert np.max(np.abs(dC - fdC)) < 1e-8


def test_variable_length_dissipates_and_tends_to_fixed_length(triangle):
    ode, p, cut = triangle
    L = ode.length
    var = FrontODE(ALPHA, KSTAR, L, beta=5.0, points_per_width=8, L_star=L + 0.01)
    dp, dL = var.velocity_length(p, L, cut)
    f = var._fields(p, cut, L)
    dEL, dC = var._length_derivatives(f)
    _, J = var._constraints(f)
    assert np.max(np.abs(J @ dp + dC * dL)) < 1e-10  # closure kept with L moving
    dEdt = var._gradient(f) @ dp + (dEL + 5.0 * (L - var.L_star)) * dL
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


def test_variable_length_implicit_matches_explicit():
    """Radau with the length-column Jacobian integrates the same flow as RK45.

    The approximate Jacobian only steers Radau's Newton iterations; a wrong one would
    show as failed or wandering steps. Short facet, beta = 5 (mildly stiff: RK45 copes).
    """

    eq = scenario_splice("short-facet")
    p, L = np.array(eq.params["positions"]), eq.params["L"]
    ode = FrontODE(ALPHA, KSTAR, L, beta=5.0)
    rad = ode.integrate(p, 0.09, rtol=1e-4, method="Radau", max_collisions=0)
    rk = ode.integrate(p, 0.09, rtol=1e-6, method="RK45", max_collisions=0)
    assert rad.success and rk.success
    tc_rad, tc_rk = rad.first_collision.time, rk.first_collision.time
    assert abs(tc_rad / tc_rk - 1) < 2e-4
    assert abs(rad.segments[0].L[-1] - rk.segments[0].L[-1]) < 1e-6 * L


# ------------------------------------------------------------ Newton (slow-manifold) correction
def test_slow_correction_is_a_newton_step(triangle):
    """``delta`` keeps positions and turning, and cuts the residual off span(B) quadratically."""
    ode, p, cut = triangle
    f = ode._fields(p, cut)
    delta, Rc = ode.slow_correction(p, cut)
    B = np.column_stack([f["dpsi"], np.ones(delta.size)])
    assert np.max(np.abs(B.T @ delta)) < 1e-9 * np.max(np.abs(B.T @ np.abs(delta)))

    def off_span(R):
        return np.linalg.norm(R - B @ np.linalg.lstsq(B, R, rcond=None)[0])

    R0 = -(ALPHA**2) * f["d2"] + ode.front.well.dW(f["psi"])
    assert off_span(Rc) < 1e-3 * off_span(R0)
    # the correction is the (small) nonlinear response to the overlapping tails
    assert 0 < np.max(np.abs(delta)) < 1e-2 * KSTAR


def _correction_errors(ppw, state):
    eq = scenario_splice(state)
    p, L, cut = np.array(eq.params["positions"]), eq.params["L"], tuple(eq.params["cutoff"])
    ode = FrontODE(ALPHA, KSTAR, L, correction="newton", points_per_width=ppw)
    if state == "short-facet":  # late state: the short facet near its collision
        r = ode.integrate(p, 0.09, rtol=1e-5, max_collisions=0)
        p = r.segments[0].p[-2]
    f = ode._fields(p, cut)
    d_ref, R_ref = ode._correction_dense(f)
    delta, R = ode._correction(f)
    F_ref, F = (R_ref * f["w"]) @ f["dpsi"], (R * f["w"]) @ f["dpsi"]
    shift = np.max(np.abs(F_ref - ode._gradient(f)))  # what the correction changes
    return (np.max(np.abs(delta - d_ref)) / np.max(np.abs(d_ref)),
            np.max(np.abs(F - F_ref)) / shift, shift / np.max(np.abs(F_ref)), ode.grid.N)


@pytest.mark.parametrize("state", ["triangle", "short-facet"])
def test_banded_correction_matches_dense_spectral(state):
    """The banded 8th-order solve against the dense spectral one (the former default).

    At the default 3 points per front width the difference error of ``d^2`` is
    ``~(h lambda)^8 / 560``-small for the smooth ``delta``: ``delta`` within 1e-5 and the
    force correction within 1e-4 of the spectral one (far below the 1e-2 the corrected
    rate is accurate to); a finer grid cuts the difference like ``h^8`` (fitted order > 6).
    """
    e_delta, e_force, shift, M = _correction_errors(3, state)
    assert e_delta < 1e-5 and e_force < 1e-4
    assert shift > 1e-4  # the correction itself is resolved far above these errors
    fine = _correction_errors(6, state)
    gain = (fine[3] / M) ** 6
    assert fine[0] < e_delta / gain and fine[1] < e_force / gain


def test_newton_correction_matches_dae_collision_time():
    """Short facet: the corrected force closes the facet at the DAE's (stiff-perimeter) rate."""
    from qsa import FiniteDifference
    from qsa.flows import FacetingFlow, solve_flow
    from qsa.reduction.fronts import detect_fronts, track_flow

    eq = scenario_splice("short-facet", ALPHA, KSTAR, grid=FiniteDifference(600))
    p, L = np.array(eq.params["positions"]), eq.params["L"]

    def stop(t, y, system):
        return detect_fronts(system.curvature(y), KSTAR, system.length(y)).n < p.size

    res = solve_flow(FacetingFlow(ALPHA, KSTAR, 500.0, L), eq.curve.positions(), 0.09, N=600,
                     tol=1e-6, method="bdf2", callback=stop, progress=False)
    tc_dae = track_flow(res, KSTAR).first_collision.time
    tc = {c: FrontODE(ALPHA, KSTAR, L, correction=c).integrate(
        p, 0.09, rtol=1e-4, max_collisions=0).first_collision.time for c in (None, "newton")}
    assert abs(tc["newton"] / tc_dae - 1) < 0.01
    assert abs(tc[None] / tc_dae - 1) > 0.015  # the splice's own force is measurably slower


def test_bad_correction():
    with pytest.raises(ValueError, match="correction"):
        FrontODE(ALPHA, KSTAR, 2.0, correction="exact")


def test_auto_method_picks_radau_only_for_a_stiff_perimeter_mode():
    """``method="auto"``: RK45 where |dL'/dL| T is mild (short facet), Radau where not (triangle).

    Same choice -> same step sequence -> identical collision times; and the other method
    would give a different one (the test can tell them apart).
    """

    for name, expected, other in (("short-facet", "RK45", "Radau"), ("triangle", "Radau", "RK45")):
        eq = scenario_splice(name)
        p, L = np.array(eq.params["positions"]), eq.params["L"]
        ode = FrontODE(ALPHA, KSTAR, L, beta=5.0)
        T = SCENARIOS[name].t_final
        auto = ode.integrate(p, T, rtol=1e-4, max_collisions=0).first_collision.time
        same = ode.integrate(p, T, rtol=1e-4, method=expected, max_collisions=0)
        diff = ode.integrate(p, T, rtol=1e-4, method=other, max_collisions=0)
        assert auto == same.first_collision.time
        assert auto != diff.first_collision.time
