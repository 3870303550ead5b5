"""Detection of every crossing along a branch: circles (closed form), N-pulses (Bloch blocks)."""

import numpy as np
import pytest
from scipy.optimize import brentq

from qsa import Fourier
from qsa.continuation import MESSAGES, Branch, continuation
from qsa.energies import DoubleWell, Faceting, Perimeter
from qsa.equilibria import circle, npulse
from tests.helpers import assert_status_convention

K, BETA, ALPHA = 5.0, 5.0, 0.1
W = DoubleWell(K)


def factory(alpha=ALPHA):
    return lambda L_star: Faceting(alpha, K) + Perimeter(BETA, L_star)


def circle_L_star(k):
    """beta (2 pi R - L*) = k W'(k) - W(k) (the circle's equilibrium condition)."""
    return 2 * np.pi / k - (k * float(W.dW(k)) - float(W.W(k))) / BETA


def crossing_curvature(m, alpha=ALPHA):
    """Mode m of the circle is marginal where alpha^2 m^2 k^2 + W''(k) = 0 (first k > 1)."""
    f = lambda k: alpha**2 * m**2 * k**2 + float(W.d2W(k))  # noqa: E731
    return brentq(f, 1.0, 1.5, xtol=1e-15) if f(1.5) < 0 else np.inf


def circle_unstable_per_mode(k, modes):
    return {m: 2 * int(ALPHA**2 * m**2 * k**2 + float(W.d2W(k)) < 0) for m in modes}


def test_the_faceting_circle_from_R1_to_R09_does_not_raise_and_finds_every_crossing():
    """The crash of a shrinking faceting circle (Fourier(33), R = 1 -> 0.9, in L*)."""
    eq = circle(1.0, ALPHA, grid=Fourier(33), kstar=K, beta=BETA)
    stop = circle_L_star(1 / 0.9)
    b = continuation(factory(), eq.curve, "L_star", (eq.params["L_star"], stop, -0.05))
    assert isinstance(b, Branch) and b.success, b.message
    assert_status_convention(b, MESSAGES)
    assert b.symmetry.circle and b.symmetry.order == 33
    # every point is a circle on the exact branch, its counts per mode the closed form's
    for p in b.points:
        k = p.curve.kappa[0]
        assert np.ptp(p.curve.kappa) == 0.0
        assert p.param == pytest.approx(circle_L_star(k), abs=1e-9)
        exact = circle_unstable_per_mode(k, range(2, 17))
        assert p.sector_unstable[0] == 0 and p.sector_unstable[1] == 0
        assert {m: p.sector_unstable[m] for m in range(2, 17)} == exact
        assert p.n_unstable == sum(exact.values())
    # the crossings between R = 1 and 0.9: modes 2..6, double, in order, at the radii of
    # the closed-form circle spectrum, to 1e-8 in L*
    # (the last point lies a step beyond R = 0.9)
    modes = [m for m in range(2, 17) if crossing_curvature(m) < b.points[-1].curve.kappa[0]]
    assert modes[:5] == [2, 3, 4, 5, 6] and b.points[-1].curve.kappa[0] > 1 / 0.9
    assert [x.sector for x in b.bifurcations] == modes
    for x, m in zip(b.bifurcations, modes[:5], strict=False):
        kc = crossing_curvature(m)
        assert x.kind == "branch" and x.multiplicity == 2 and x.change == 2
        assert [md.sector for md in x.modes] == [m, m]
        assert {md.label for md in x.modes} == {"mode"}
        assert x.parameter == pytest.approx(circle_L_star(kc), abs=1e-8)
        assert x.curve.length() == pytest.approx(2 * np.pi / kc, abs=1e-8)
        # the critical modes are cos and sin of m theta (theta = 2 pi s on a circle)
        s = x.curve.grid.s
        basis = np.column_stack([np.cos(2 * np.pi * m * s), np.sin(2 * np.pi * m * s)])
        for md in x.modes:
            coef = np.linalg.lstsq(basis, md.vector, rcond=None)[0]
            assert np.allclose(basis @ coef, md.vector, atol=1e-10)
    assert "mode 2, double" in b.message
    # one eigen-solve per point, the rest for the location
    assert b.n_eigensolves >= len(b.points)


def test_fold_of_the_circle_branch_is_a_fold_bifurcation():
    eq = circle(0.77, ALPHA, grid=Fourier(17), kstar=K, beta=BETA)
    b = continuation(factory(), eq.curve, "L_star", (eq.params["L_star"], 3.0, -0.1))
    assert b.success, b.message
    (fold,) = b.folds
    folds = [x for x in b.bifurcations if x.kind == "fold"]
    assert len(folds) == 1
    x = folds[0]
    assert x.multiplicity == 1 and x.sector == 0 and x.change == 1
    assert x.parameter == pytest.approx(fold.param, abs=1e-9)
    # the critical mode of the fold is the breathing mode (constant normal velocity)
    v = x.modes[0].vector
    assert np.ptp(v) < 1e-8 * np.max(np.abs(v))


def test_natural_continuation_locates_the_same_crossing():
    eq = circle(1.0, ALPHA, grid=Fourier(33), kstar=K, beta=BETA)
    Ls0 = eq.params["L_star"]
    b = continuation(factory(), eq.curve, "L_star", np.linspace(Ls0, circle_L_star(1 / 0.93), 6),
                     method="natural")
    assert b.success, b.message
    assert [x.sector for x in b.bifurcations] == [2, 3]
    for x in b.bifurcations:
        assert x.multiplicity == 2 and x.tangent is None
        assert x.parameter == pytest.approx(circle_L_star(crossing_curvature(x.sector)), abs=1e-8)


def test_no_stability_no_branch_points_but_folds():
    eq = circle(0.77, ALPHA, grid=Fourier(17), kstar=K, beta=BETA)
    b = continuation(factory(), eq.curve, "L_star", (eq.params["L_star"], 3.0, -0.1),
                     stability=False)
    assert b.n_unstable is None and b.n_eigensolves == 0
    assert [(x.kind, x.modes) for x in b.bifurcations] == [("fold", ())]
    assert b.bifurcations[0].parameter == b.folds[0].param


def test_three_pulse_family_in_alpha_stability_per_bloch_block():
    """3-pulses at fixed L*: the coarsening pair (Bloch index 1, double) is unstable all
    along; at the fold in alpha the symmetric block (index 0) gains an unstable mode."""
    from qsa.spectra import spectrum

    eq = npulse(3, 0.2, grid=Fourier(99), kstar=K, beta=BETA)
    Ls = eq.params["L_star"]
    b = continuation(lambda a: Faceting(a, K) + Perimeter(BETA, Ls), eq.curve, "alpha",
                     (0.2, 0.3, 0.01))
    assert b.success, b.message
    assert b.symmetry.order == 3 and b.symmetry.reflection is not None
    (fold,) = b.folds
    i = fold.index
    for j, p in enumerate(b.points):
        assert p.sector_unstable == ((0, 2) if j <= i else (1, 2))
        ref = spectrum(p.equilibrium.energy, p.curve, reject_spurious=False)
        assert ref.n_unstable == p.n_unstable
        # the Bloch index 1 block holds the double eigenvalues: exact pairs in the full solve
        lam = ref.unstable
        assert np.sum(np.isclose(lam, lam.max(), rtol=1e-8)) == 2 or j > i
    (x,) = b.bifurcations
    assert x.kind == "fold" and x.sector == 0 and x.multiplicity == 1 and x.change == 1
    assert x.modes[0].label == "bloch" and x.modes[0].parity == 1
    assert x.parameter == pytest.approx(fold.param, abs=1e-8)


def test_numerical_trouble_is_a_status_not_an_exception():
    eq = circle(1.0, ALPHA, grid=Fourier(17), kstar=K, beta=BETA)
    Ls0 = eq.params["L_star"]

    def fragile(L_star):
        if L_star < Ls0 - 0.25:
            raise np.linalg.LinAlgError("injected failure")
        return factory()(L_star)

    for method in ("pseudo-arclength", "natural"):
        b = continuation(fragile, eq.curve, "L_star", (Ls0, Ls0 - 1.0, -0.1), method=method)
        assert not b.success and b.status == -5 and "injected failure" in b.message
        assert_status_convention(b, MESSAGES)
        assert b.points and b.points[-1].param >= Ls0 - 0.25


def test_a_point_exactly_on_the_crossing_still_brackets_it():
    eq = circle(1.0, ALPHA, grid=Fourier(33), kstar=K, beta=BETA)
    Ls0 = eq.params["L_star"]
    Lc = circle_L_star(crossing_curvature(2))
    b = continuation(factory(), eq.curve, "L_star", [Ls0, 0.5 * (Ls0 + Lc), Lc, Lc - 0.02],
                     method="natural")
    assert b.success, b.message
    assert b.points[2].param == Lc and b.points[2].sector_unstable[2] == 0  # zero: not counted
    (x,) = [x for x in b.bifurcations if x.sector == 2]
    assert x.parameter == pytest.approx(Lc, abs=1e-8) and x.multiplicity == 2


def test_bifurcation_diagram_draws_stability_and_markers():
    from qsa.plotting import bifurcation_diagram

    eq = circle(0.95, ALPHA, grid=Fourier(33), kstar=K, beta=BETA)
    b = continuation(factory(), eq.curve, "L_star", (eq.params["L_star"], 5.45, -0.05))
    ax = bifurcation_diagram(b, measure="L")
    styles = [ln.get_linestyle() for ln in ax.lines if len(ln.get_xdata()) > 1]
    assert styles[0] == "-" and "--" in styles  # stable, then unstable past mode 2
    markers = [ln for ln in ax.lines if len(ln.get_xdata()) == 1]
    assert len(markers) == len(b.bifurcations) == 3
    assert {t.get_text() for t in ax.texts} == {"m=2", "m=3", "m=4"}
    # the stable run ends exactly at the located mode-2 crossing
    first = [ln for ln in ax.lines if len(ln.get_xdata()) > 1][0]
    assert first.get_xdata()[-1] == b.bifurcations[0].parameter
    with pytest.raises(ValueError, match="measure"):
        bifurcation_diagram(b, measure="area2")


def test_without_the_grid_symmetry_a_double_crossing_is_two_coincident_ones_merged():
    from qsa.spectra.symmetry import BlochSymmetry

    eq = circle(0.95, ALPHA, grid=Fourier(33), kstar=K, beta=BETA)
    b = continuation(factory(), eq.curve, "L_star", (eq.params["L_star"], 5.45, -0.05),
                     symmetry=BlochSymmetry(1, 33))
    assert [(x.multiplicity, x.sector, x.change) for x in b.bifurcations] == [(2, 0, 2)] * 3
    for x, m in zip(b.bifurcations, (2, 3, 4), strict=True):
        assert x.parameter == pytest.approx(circle_L_star(crossing_curvature(m)), abs=1e-7)
        assert len(x.modes) == 2 and {md.label for md in x.modes} == {"none"}
