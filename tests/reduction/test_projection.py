"""The splice nearest a curve (the restart after a collision): fixed point, optimality."""

import numpy as np
import pytest

from qsa.equilibria import splice_polygon
from qsa.equilibria.splice import default_cutoff
from qsa.paper import random_polygon, scenario_splice
from qsa.reduction.integrate import remove_pair
from qsa.reduction.ode import FrontODE
from qsa.reduction.projection import nearest_splice, splice_distance

ALPHA, KSTAR = 0.1, 5.0


@pytest.fixture(scope="module")
def triangle():
    eq = splice_polygon(np.radians([130, 120, 110]), [0.3, 0.4, 0.5], ALPHA, kstar=KSTAR)
    return FrontODE(ALPHA, KSTAR, eq.params["L"], backend="numpy"), \
        np.array(eq.params["positions"])


def test_a_splice_is_its_own_projection(triangle):
    ode, p = triangle
    kappa = ode.fields(p).psi
    exact = nearest_splice(ode, kappa, p)
    assert exact.iterations == 1 and exact.distance < 1e-12
    assert np.max(np.abs(exact.positions - p)) < 1e-12
    # from perturbed positions (no common shift: that one only moves the base point)
    d = 0.3 * ode.front.width * np.sin(np.arange(1, 7))
    r = nearest_splice(ode, kappa, p + d - d.mean())
    assert r.success and r.iterations <= 5
    assert r.initial_distance > 1e-3 and r.distance < 1e-9 and r.closure < 1e-12
    assert np.max(np.abs(r.positions - p)) < 1e-9
    # the distance is of the shapes: the same curve rotated and translated is at 0
    assert splice_distance(ode, kappa, p) < 1e-12


def _collision(ode, p):
    """The state at the ODE's first collision: positions, the pair's index, the removal."""
    ev = ode.integrate(p, 50.0, rtol=1e-6, max_collisions=0).first_collision
    pc = ev.positions
    i = int(np.argmin(np.diff(np.append(pc, pc[0] + ode.length))))
    q0, _ = remove_pair(pc, np.arange(pc.size), i, ode.length)
    return pc, i, q0


@pytest.fixture(scope="module", params=["facet", "corner"])
def collision(request):
    """A short facet collapsing (the trapezoid) and a corner (a random pentagon)."""
    if request.param == "facet":
        eq = scenario_splice("short-facet", ALPHA, KSTAR)
    else:
        eq = random_polygon(5, 1).splice()
    ode = FrontODE(ALPHA, KSTAR, eq.params["L"], backend="numpy")
    pc, i, q0 = _collision(ode, np.array(eq.params["positions"]))
    kappa = ode.fields(pc).psi
    cut = default_cutoff(q0, ode.length)
    return request.param, ode, pc, i, q0, kappa, cut, nearest_splice(ode, kappa, q0, cutoff=cut)


def test_projection_after_a_collision_is_nearer_and_stationary(collision):
    kind, ode, pc, i, q0, kappa, cut, r = collision
    assert (i % 2 == 1) == (kind == "facet")
    assert r.success and r.closure < 1e-12 and r.iterations <= 6
    assert np.isclose(r.initial_distance, splice_distance(ode, kappa, q0, cutoff=cut))
    assert np.isclose(r.distance, splice_distance(ode, kappa, r.positions, cutoff=cut))
    assert r.distance < 0.9 * r.initial_distance
    # a constrained minimum: the gradient of the squared distance (central differences)
    # lies in the span of dC/dq and of the common shift
    q, n = r.positions, r.positions.size
    h = 1e-5

    def grad(q):
        g = np.empty(n)
        for j in range(n):
            e = np.zeros(n)
            e[j] = h
            g[j] = (splice_distance(ode, kappa, q + e, cutoff=cut) ** 2
                    - splice_distance(ode, kappa, q - e, cutoff=cut) ** 2) / (2 * h)
        return g

    _, J = ode.constraints(q, cut)
    Q, _ = np.linalg.qr(np.vstack([J, np.ones((1, n))]).T)
    tangential = [np.linalg.norm(g - Q @ (Q.T @ g)) for g in (grad(q), grad(q0))]
    assert tangential[0] < 1e-2 * tangential[1]


def test_projection_keeps_the_turning_near_the_collision(collision):
    """The closure after a collapse changes the corners next to it most (as in the flow)."""
    kind, ode, pc, i, q0, kappa, cut, r = collision
    L = ode.length
    kept, _ = remove_pair(pc, np.arange(pc.size), i, L, "uniform")  # the others as they were

    def corners(q):
        return np.diff(np.append(q, q[0] + L))[0::2]

    assert np.isclose(KSTAR * corners(r.positions).sum(), 2 * np.pi, atol=1e-4)  # e:C2
    change = np.abs(corners(r.positions) - corners(kept))
    near = np.sort(change)[::-1][:2 if kind == "corner" else 1]
    assert near.sum() > 0.75 * change.sum()


def test_integrate_restarts_from_the_projection():
    eq = scenario_splice("short-facet", ALPHA, KSTAR)
    ode = FrontODE(ALPHA, KSTAR, eq.params["L"], backend="numpy")
    p = np.array(eq.params["positions"])
    r = ode.integrate(p, 0.08, rtol=1e-6, max_collisions=1)
    ev = r.first_collision
    q0, _ = remove_pair(ev.positions, ev.ids, ev.fronts[0], ode.length)
    proj = nearest_splice(ode, ode.fields(ev.positions, r.segments[0].cutoff).psi, q0)
    start = r.segments[1].p[0]
    assert np.max(np.abs(start - proj.positions)) < 1e-4 * ode.front.width
    plain = ode.integrate(p, 0.08, rtol=1e-6, max_collisions=1, redistribute="local")
    assert np.max(np.abs(plain.segments[1].p[0] - start)) > 0.1 * ode.front.width


def test_bad_input(triangle):
    ode, p = triangle
    with pytest.raises(ValueError, match="kappa"):
        nearest_splice(ode, np.zeros(7), p)
    with pytest.raises(ValueError, match="positions"):
        nearest_splice(ode, ode.fields(p).psi, p[::-1])
