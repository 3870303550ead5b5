"""The paper's scenarios: their parameters are the published ones and their data is right."""

import math
from dataclasses import replace

import numpy as np
import pytest

from qsa.curve import polygon_self_intersects
from qsa.flows import CHA
from qsa.paper import (
    CONVERGENCE,
    SCENARIOS,
    CHAScenario,
    ConvergenceScenario,
    FacetScenario,
    Scenario,
    circle_balance_length,
    front_scenario,
    random_polygon,
    scenario_splice,
    spinodal_radius,
)
from tests.reference import load

PAPER = load("paper_appendix")


def chords(x, y):
    return np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)


def test_facet_initial_data_in_the_spinodal_range():
    sc = FacetScenario()
    x, y = sc.initial()
    c = chords(x, y)
    assert x.size == 600 and np.ptp(c) < 1e-10 * c.mean()
    lo, hi = sc.spinodal_range()
    assert lo < 1 / sc.R < hi
    r = np.hypot(x, y)
    assert np.max(np.abs(r / sc.R - 1)) < 20 * sc.noise


def test_facet_circle_and_length_are_chosen_a_priori():
    from qsa import Curve, Fourier
    from qsa.energies import Faceting, Perimeter
    from qsa.paper.scenarios import circle_growth_rate

    sc = FacetScenario()
    # the circle's fastest-growing mode is k = 9 (18 fronts); the larger of two such circles
    rates = circle_growth_rate(np.arange(2, 30), sc.R, sc.alpha, sc.kstar)
    assert np.argmax(rates) + 2 == 9
    small = spinodal_radius(9, sc.alpha, sc.kstar, "small")
    assert small < 0.5 < sc.R and np.argmax(circle_growth_rate(np.arange(2, 30), small,
                                                              sc.alpha, sc.kstar)) + 2 == 9
    # L* makes the unperturbed circle an equilibrium of the flow (V^n = 0)
    c = Curve.circle(sc.R, Fourier(33))
    E = Faceting(sc.alpha, kstar=sc.kstar) + Perimeter(sc.beta, sc.L_star)
    V = E.normal_velocity(c)
    assert np.max(np.abs(V)) < 1e-10
    Eoff = Faceting(sc.alpha, kstar=sc.kstar) + Perimeter(sc.beta, sc.L_star + 0.01)
    assert np.min(np.abs(Eoff.normal_velocity(c))) > 1e-3
    assert sc.L_star == circle_balance_length(sc.R, sc.alpha, sc.kstar, sc.beta)
    # the paper's clock runs at half the physical time; its figure times as printed
    assert sc.physical_figure_times[0] == pytest.approx(4.4e-4)
    assert sc.figure_times[-1] == 2.0 and sc.spinodal_time > 0
    with pytest.raises(ValueError, match="branch"):
        spinodal_radius(9, 0.1, 5.0, "middle")


def test_random_polygon_is_seeded_and_closes():
    a, b = random_polygon(5, seed=4), random_polygon(5, seed=4)
    assert a == b and a != random_polygon(5, seed=5)
    assert sum(a.angles) == pytest.approx(360.0)
    eq = a.splice()
    assert eq.success and eq.closure < 1e-10
    assert sum(f < 0.33 for f in random_polygon(6, 1, n_short=3).facets) == 3
    with pytest.raises(ValueError, match="n_short"):
        random_polygon(3, 1, n_short=3)


def test_cha_initial_data_is_the_crenellated_curve():
    sc = CHAScenario()
    x, y = sc.initial()
    r, th = np.hypot(x, y), np.arctan2(y, x)
    expected = 0.6 * (1 + 0.4 * np.tanh(3 * np.cos(13 * th)) / math.tanh(3))
    assert np.max(np.abs(r - expected)) < 1e-6
    L = chords(x, y).sum()
    assert L / sc.N < sc.l_star  # the kernel is resolved at the start
    assert sc.rho * L / sc.N < sc.l_star  # ... and at the target length
    assert not polygon_self_intersects(x, y)
    assert sc.pair_separation() == pytest.approx(0.1 * math.sqrt(1.5))
    lit = CHAScenario.literal()  # Table T1 as printed
    assert lit.l_star == 0.01 and lit.N == 2400 and lit.rho * L / lit.N < lit.l_star
    assert replace(lit, l_star=0.1, N=600) == sc


def test_table_t1_kernel_length_is_the_code_parameter_squared():
    from qsa.energies.adhesion import AdhesionKernel

    sc = CHAScenario()
    assert sc.kernel_parameter == pytest.approx(0.01)  # Table T1's printed number
    # the kernel divides the squared distance by l*^2 = the code's parameter
    k = AdhesionKernel(sc.A0, sc.l_star, sc.a)
    ell = np.array([0.0, 0.003, 0.02])
    p = sc.kernel_parameter
    expected = sc.A0 * (1 - ell / (sc.a**2 * p)) * np.exp(-ell / p)
    assert np.allclose(k(ell), expected, rtol=1e-14, atol=0)
    # default nodes: 600 at l* = 0.1, 2400 at the literal 0.01, the spacing resolving l*
    for l_star in (0.1, 0.05, 0.03, 0.01, 0.005):
        N = CHAScenario.nodes_for(l_star)
        assert N >= 600 and N % 100 == 0 and 1.4 * 14.47 / N < l_star
    assert CHAScenario.for_kernel(0.01, N=300, rho=1.2) == replace(CHAScenario.literal(),
                                                                   N=300, rho=1.2)


def test_fold_balance_against_the_discrete_adhesion_energy():
    from qsa.energies.adhesion import AdhesionKernel, adhesion_energy

    sc = CHAScenario(l_star=0.05, a=1.3, A0=7.0)
    fb = sc.fold_balance()
    # two straight strands of length 4, spacing h << l*: paired at d minus far apart
    h, n = 0.005, 800
    s = h * np.arange(n)
    d = sc.pair_separation()
    kernel = AdhesionKernel(sc.A0, sc.l_star, sc.a)

    def energy(gap):
        return adhesion_energy(kernel, np.r_[s, s], np.r_[np.zeros(n), np.full(n, gap)], h,
                               method="dense")

    gain = (energy(50 * sc.l_star) - energy(d)) / (n * h)
    # the strand ends lose O(l* / length) of the overlap
    assert gain == pytest.approx(fb.pair_gain_per_length, rel=0.03)
    assert fb.hairpin_energy == pytest.approx(np.pi * sc.eps / d)
    assert fb.fold_length == fb.hairpin_energy / fb.pair_gain_per_length
    assert CHAScenario.literal().fold_balance().fold_length == pytest.approx(64.9, abs=0.1)
    assert CHAScenario().fold_balance().fold_length == pytest.approx(0.649, abs=1e-3)


def test_convergence_scenario_is_the_appendix_example():
    sc = CONVERGENCE
    assert sc == ConvergenceScenario()
    # the appendix: eps = 0.1, beta = 1, rho = 1.5, A0 = 10, l* = 1/2, a = 1 to t = 0.2
    assert sc.model_params() == dict(eps=0.1, beta=1.0, rho=1.5, A0=10.0, l_star=0.5, a=1.0)
    assert (sc.t_final, sc.tol) == (0.2, 1e-4)
    model = sc.model("centred")
    assert isinstance(model, CHA) and model.force_normal == "centred"
    assert sc.model().force_normal == "unit"
    x, y = sc.samples(1000)
    th = 2 * np.pi * np.arange(1000) / 1000
    r = 1 + 0.35 * np.cos(3 * th)
    assert np.array_equal(x, r * np.cos(th) + 0.05 * np.sin(4 * th))
    assert np.array_equal(y, r * np.sin(th))
    assert sc.samples()[0].size == 4000
    # Table ap:t1 and the step counts; second order: ratios near 4
    # the library's copy of the paper's numbers against the transcription in tests/reference
    d = sc.paper_differences
    assert d == PAPER["table_t1"] and sc.paper_steps == PAPER["time_steps"]
    assert all(3.5 < d[n] / d[2 * n] < 5 for n in (100, 200))


def test_front_scenarios_carry_their_parameters():
    tri = SCENARIOS["triangle"]
    assert (tri.alpha, tri.kstar, tri.beta) == (0.1, 5.0, 5.0)
    assert sum(tri.angles) == 360 and sum(SCENARIOS["short-facet"].angles) == 360
    assert front_scenario("triangle") is tri
    changed = front_scenario(tri, alpha=0.2, kstar=None)
    assert (changed.alpha, changed.kstar) == (0.2, 5.0) and changed.facets == tri.facets
    with pytest.raises(ValueError, match="scenario"):
        front_scenario("hexagon")
    with pytest.raises(ValueError, match="scenario"):
        front_scenario(3)
    with pytest.raises(ValueError, match="n_corners"):
        Scenario.regular(1, 0.3)


def test_scenario_splice_closes_the_polygon():
    eq = scenario_splice("short-facet")
    p = np.asarray(eq.params["positions"])
    sc = SCENARIOS["short-facet"]
    assert p.size == 2 * len(sc.angles) and eq.closure < 1e-10
    # each corner turns by its angle: kstar times the corner's arc length
    turn = sc.kstar * (p[1::2] - p[0::2])
    assert np.allclose(np.rad2deg(turn), sc.angles, atol=1e-8)
    # overrides of alpha / kstar are passed on, as by the scenario itself
    a = scenario_splice(sc, 0.12)
    b = front_scenario(sc, alpha=0.12).splice()
    assert np.array_equal(a.params["positions"], b.params["positions"])
    sq = Scenario.regular(4, 0.35).splice()
    gaps = np.diff(np.append(sq.params["positions"], sq.params["positions"][0] + sq.params["L"]))
    assert np.allclose(gaps[1::2], gaps[1], rtol=1e-8)  # equal facets
