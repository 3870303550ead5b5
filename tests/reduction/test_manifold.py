"""The splice-manifold fields on the quadrature grid, against the profile and differences."""

import numpy as np
import pytest

from qsa.equilibria import heteroclinic
from qsa.paper import scenario_splice
from qsa.reduction.manifold import (
    PeriodicQuadrature,
    SpliceFields,
    closure,
    energy,
    length_derivatives,
    normal_velocities,
    quadrature_size,
    splice_fields,
)

ALPHA, KSTAR = 0.1, 5.0


@pytest.fixture(scope="module", params=["triangle", "short-facet"])
def state(request):
    eq = scenario_splice(request.param)
    p, L, cut = np.array(eq.params["positions"]), eq.params["L"], tuple(eq.params["cutoff"])
    front = heteroclinic(ALPHA, kstar=KSTAR)
    quad = PeriodicQuadrature(quadrature_size(L, front.width, 8.0))
    return front, p, L, cut, quad, eq.extra["profile"]


def test_fields_are_the_splice_profile(state):
    front, p, L, cut, quad, prof = state
    f = splice_fields(front, p, L, cut, quad)
    assert isinstance(f, SpliceFields) and f.g_L is None and f.length == L
    sigma = L * quad.s
    for a, b in zip((f.psi, f.dpsi, f.d2psi), prof(sigma, derivatives=True), strict=True):
        assert np.max(np.abs(a - b)) < 1e-12 * np.max(np.abs(b))
    ref = prof.position_derivatives(sigma)
    assert np.max(np.abs(f.dpsi_dp - ref)) < 1e-12 * np.max(np.abs(ref))
    assert np.allclose(f.weights, L / quad.M, rtol=1e-15)
    # theta and Theta by an independent (trapezoid, fine grid) cumulative integral
    from scipy.integrate import cumulative_trapezoid

    s = np.linspace(0, L, 40001)
    theta = cumulative_trapezoid(prof(s), s, initial=0)
    assert np.max(np.abs(np.interp(sigma, s, theta) - f.theta)) < 1e-6
    Theta = cumulative_trapezoid(prof.position_derivatives(s), s, axis=0, initial=0)
    for j in range(p.size):
        assert np.max(np.abs(np.interp(sigma, s, Theta[:, j]) - f.Theta[:, j])) < 1e-6
    E = energy(f, ALPHA, front.well)
    psi, d1, _ = prof(s, derivatives=True)
    E_ref = np.trapezoid(0.5 * ALPHA**2 * d1**2 + front.well.W(psi), s)
    assert abs(E - E_ref) < 1e-7 * abs(E_ref)


def test_position_derivatives_match_differences(state):
    front, p, L, cut, quad, _ = state
    f = splice_fields(front, p, L, cut, quad)
    h = 1e-6
    for j in range(p.size):
        e = np.zeros(p.size)
        e[j] = h
        fp, fm = splice_fields(front, p + e, L, cut, quad), splice_fields(front, p - e, L, cut,
                                                                          quad)
        scale = np.max(np.abs(f.dpsi_dp[:, j]))
        assert np.max(np.abs((fp.psi - fm.psi) / (2 * h) - f.dpsi_dp[:, j])) < 1e-6 * scale
        dtheta = (fp.theta - fm.theta) / (2 * h)
        assert np.max(np.abs(dtheta - f.Theta[:, j])) < 1e-6 * np.max(np.abs(f.Theta[:, j]))
        C, J = closure(fp)[0], closure(fm)[0]
        assert np.max(np.abs((C - J) / (2 * h) - closure(f)[1][:, j])) < 1e-7


def test_length_fields_match_differences(state):
    """``g_L`` and ``Theta_L`` against ``d/dL`` at fixed nodes ``s`` (the nodes move with L)."""
    front, p, L, cut, quad, _ = state
    f = splice_fields(front, p, L, cut, quad, variable=True)
    fixed = splice_fields(front, p, L, cut, quad)
    for a, b in ((f.psi, fixed.psi), (f.theta, fixed.theta), (f.Theta, fixed.Theta)):
        assert np.array_equal(a, b) or np.max(np.abs(a - b)) < 1e-13 * np.max(np.abs(b))
    h = 1e-6
    fp, fm = (splice_fields(front, p, L + d, cut, quad) for d in (h, -h))
    # psi(L s) at fixed s: d/dL = psi_L + s psi' = g_L
    g = (fp.psi - fm.psi) / (2 * h)
    assert np.max(np.abs(g - f.g_L)) < 1e-6 * np.max(np.abs(f.g_L))
    dg = np.gradient(f.g_L, L / quad.M)  # (second order: only a sanity check of dg_L)
    assert np.max(np.abs(dg - f.dg_L)) < 1e-2 * np.max(np.abs(f.dg_L))
    # theta(L s) at fixed s: d/dL = s psi + Theta_L
    T = (fp.theta - fm.theta) / (2 * h) - quad.s * f.psi
    assert np.max(np.abs(T - f.Theta_L)) < 1e-6 * max(np.max(np.abs(f.Theta_L)), 1.0)
    # d psi_N / d p_j at fixed s
    dP = (fp.dpsi_dp - fm.dpsi_dp) / (2 * h)
    assert np.max(np.abs(dP - f.dpsi_dp_L)) < 1e-6 * np.max(np.abs(f.dpsi_dp_L))


@pytest.mark.parametrize("scenario", ["triangle", "short-facet"])
def test_length_derivatives_match_differences(scenario):
    from qsa.reduction.ode import FrontODE

    eq = scenario_splice(scenario)
    p, L, cut = np.array(eq.params["positions"]), eq.params["L"], tuple(eq.params["cutoff"])
    ode = FrontODE(ALPHA, KSTAR, L, beta=5.0, points_per_width=8)
    well = ode.front.well
    dE, dC = length_derivatives(ode.fields(p, cut, L), ALPHA, well)
    h = 1e-5
    fp, fm = ode.fields(p, cut, L + h), ode.fields(p, cut, L - h)
    fdE = (energy(fp, ALPHA, well) - energy(fm, ALPHA, well)) / (2 * h)
    fdC = (closure(fp)[0] - closure(fm)[0]) / (2 * h)
    assert abs(dE - fdE) < 1e-6 * abs(fdE) and abs(fdE) > 1e-5  # the wrap facet's force
    assert np.max(np.abs(dC - fdC)) < 1e-8
    with pytest.raises(ValueError, match="variable"):
        length_derivatives(FrontODE(ALPHA, KSTAR, L).fields(p, cut), ALPHA, well)


def test_normal_velocities_are_orthogonal_to_rigid_motions(state):
    front, p, L, cut, quad, _ = state
    f = splice_fields(front, p, L, cut, quad)
    phi = normal_velocities(f, quad)
    assert phi.shape == (quad.M, p.size)
    # r^n = (e1 . n, e2 . n, gamma . tau), gamma by an independent trapezoid integral
    from scipy.integrate import cumulative_trapezoid

    sigma = L * quad.s
    s = np.linspace(0, L, 40001)
    th = np.interp(s, sigma, f.theta)
    gx = np.interp(sigma, s, cumulative_trapezoid(np.cos(th), s, initial=0))
    gy = np.interp(sigma, s, cumulative_trapezoid(np.sin(th), s, initial=0))
    c, sn = np.cos(f.theta), np.sin(f.theta)
    R = np.column_stack([sn, -c, gx * c + gy * sn])
    proj = (R.T * f.weights) @ phi
    assert np.max(np.abs(proj)) < 1e-6 * np.max(np.abs(phi)) * L


def test_periodic_quadrature():
    quad = PeriodicQuadrature(15)
    s = quad.s
    F = np.column_stack([np.cos(2 * np.pi * s), np.sin(4 * np.pi * s), np.ones_like(s)])
    I1, I2 = quad.cumulative(F, twice=[0, 2])
    exact = np.column_stack([np.sin(2 * np.pi * s) / (2 * np.pi),
                             (1 - np.cos(4 * np.pi * s)) / (4 * np.pi), s])
    assert np.allclose(I1, exact, rtol=0, atol=1e-14)
    twice = np.column_stack([(1 - np.cos(2 * np.pi * s)) / (2 * np.pi) ** 2, 0.5 * s**2])
    assert np.allclose(I2, twice, rtol=0, atol=1e-14)
    assert np.array_equal(quad.cumulative(F), I1)
    with pytest.raises(ValueError, match="odd"):
        PeriodicQuadrature(16)


def test_quadrature_size():
    def smooth_odd(M):
        r = M
        for q in (3, 5, 7):
            while r % q == 0:
                r //= q
        return M % 2 == 1 and r == 1

    for n in (10, 300, 1000, 1234.5):
        M = quadrature_size(1.0, 1.0 / n, 1.0)
        lo = int(np.ceil(max(n, 255)))
        assert smooth_odd(M) and M >= lo
        assert not any(smooth_odd(m) for m in range(lo, M))  # the smallest such size
