"""Integration of the front ODE through collisions; collision distance and sensitivity."""

import numpy as np
import pytest

from qsa.equilibria import splice_polygon
from qsa.paper import SCENARIOS, scenario_splice
from qsa.reduction.integrate import (
    MESSAGES,
    ODECollision,
    ODESegment,
    collision_distance,
    collision_sensitivity,
)
from qsa.reduction.ode import FrontODE
from tests.helpers import assert_status_convention

ALPHA, KSTAR = 0.1, 5.0


@pytest.fixture(scope="module")
def trapezoid():
    """A splice with a short facet [p_4, p_5] (0-based 3, 4)."""
    eq = scenario_splice("short-facet", ALPHA, KSTAR)
    return FrontODE(ALPHA, KSTAR, eq.params["L"]), np.array(eq.params["positions"])


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


def test_integrate_removes_pair_and_recloses(trapezoid):
    ode, p = trapezoid
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


def test_result_types_and_stop_after_max_collisions(trapezoid):
    """Segments, events and the track-indexed positions of a run stopped by max_collisions."""
    ode, p = trapezoid
    r = ode.integrate(p, 0.08, rtol=1e-5, max_collisions=0)
    assert r.status == 1 and r.success and "stopped after collision" in r.message
    assert_status_convention(r, MESSAGES)
    assert len(r.events) == 1 and len(r.segments) == 1
    seg, ev = r.segments[0], r.first_collision
    assert isinstance(seg, ODESegment) and isinstance(ev, ODECollision)
    assert seg.p.shape == (seg.t.size, p.size) and np.all(seg.L == ode.length)
    assert np.isclose(seg.t[-1], ev.time, rtol=0, atol=0) and r.t.shape == seg.t.shape
    assert r.n_fronts == p.size and np.array_equal(r.positions, seg.p)  # nothing removed yet
    assert r.n_rhs > seg.t.size and r.nfev == r.n_rhs and r.elapsed > 0
    # no collision before t_final: status 0, no events
    short = ode.integrate(p, 0.2 * ev.time, rtol=1e-5)
    assert short.status == 0 and short.first_collision is None
    assert_status_convention(short, MESSAGES)
    assert np.isclose(short.t[-1], 0.2 * ev.time)


def _corners(p, L):
    """Corner lengths (up -> down) and facet lengths of positions (up, down, ...)."""
    g = np.diff(np.append(p, p[0] + L))
    return g[0::2], g[1::2]


@pytest.mark.parametrize("i", [2, 3, 5])  # a corner, a facet, the facet across s = 0
def test_remove_pair_keeps_the_turning_local(i):
    from qsa.reduction.integrate import remove_pair

    L = 3.0
    p = np.array([0.1, 0.35, 0.7, 0.78, 1.3, 1.6])
    if i == 5:
        p = np.array([0.1, 0.35, 0.7, 0.98, 1.3, 3.05])  # facet (3.05, 0.1 + L) short
    corners, facets = _corners(p, L)
    q, ids = remove_pair(p, np.arange(6), i, L)
    assert q.size == 4 and np.all(np.diff(q) > 0) and q[-1] - q[0] < L
    c2, f2 = _corners(q, L)
    assert np.isclose(c2.sum(), corners.sum())  # total turning kstar * sum(corners) kept
    if i == 2:  # corner (0.7, 0.78) gone: its 0.08 goes half to each neighbour
        assert ids.tolist() == [0, 1, 4, 5]
        assert np.allclose(c2, [0.25 + 0.04, 0.3 + 0.04])
        assert np.allclose(0.5 * (q[0::2] + q[1::2]), 0.5 * (p[[0, 4]] + p[[1, 5]]))
    elif i == 3:  # facet (0.78, 1.3) gone: corners (0.7, 0.78) and (1.3, 1.6) merge
        assert ids.tolist() == [0, 1, 2, 5]
        assert np.isclose(c2[1], 0.08 + 0.3)
    else:  # facet across the base point: the merged corner is (1.3, 0.35 + L)
        assert ids.tolist() == [2, 3, 4, 1]
        assert np.isclose(c2[1], corners[2] + corners[0])
        assert np.isclose(0.5 * (q[2] + q[3]), 0.5 * (1.3 + 0.35 + L))
    # "uniform" only removes the pair (the closure spreads the deficit)
    qu, idu = remove_pair(p, np.arange(6), i, L, "uniform")
    assert idu.tolist() == ids.tolist()
    kept = np.delete(p, [i, (i + 1) % 6])
    assert np.allclose(qu, kept if i != 5 else np.append(kept[1:], kept[0] + L))


def test_redistribute_is_checked(trapezoid):
    ode, p = trapezoid
    with pytest.raises(ValueError, match="redistribute"):
        ode.integrate(p, 0.01, redistribute="nearest")
