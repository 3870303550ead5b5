"""Reduced against full slow eigenvalues, paired mode by mode, on the regular polygons.

The full eigenvalues are those of the polished N-pulse (an exact equilibrium), from the
factored shift-invert solver with error estimates; the reduced ones from the corrected
and uncorrected front ODE. The reduction's error is set by the smallest spacing of the
fronts -- the facets, or the corners, which turn by 2 pi / n and so are 2 pi / (n kstar)
long: 0.42 for the triangle, 0.157 for the octagon (kstar = 5).
"""

import numpy as np
import pytest

from qsa.paper import Scenario, compare_eigenvalues
from qsa.paper.eigenvalues import polygon_scenario


def _check_pairing(r):
    """Every reduced mode is a combination of computed full ones; non-degenerate pairs
    are the same vector; the full values are certified and not rigid."""
    assert r.equilibrium and r.polish_success and r.spectrum_status == 0
    assert np.all(r.capture > 0.9999)
    lam = r.reduced
    distinct = np.array([np.sum(np.abs(lam - x) < 1e-4 * abs(x)) == 1 for x in lam])
    assert np.all(r.cosine[distinct] > 0.999)
    assert np.all(r.full_errors < 1e-4 * np.abs(r.full))
    assert np.max(np.abs(r.rigid)) < 1e-6 * np.min(np.abs(r.full))


def test_overlap_pairing_skips_the_fast_mode_sorting_by_size_would_take():
    # hexagon, facets 0.4: a fast mode (the perimeter's, ~ -60) lies nearer 0 than the
    # corner modes (~ +140); pairing by overlap never picks it
    r = compare_eigenvalues(6, facet=0.4, correction="newton")
    _check_pairing(r)
    fast = r.full_nonkernel[(r.full_nonkernel < 0) & (r.full_nonkernel > -1e3)]
    assert fast.size == 1 and -70 < fast[0] < -50
    assert fast[0] not in r.full
    by_size = np.sort(r.full_nonkernel[np.argsort(np.abs(r.full_nonkernel))[:r.reduced.size]])
    assert fast[0] in by_size  # what sorting by |lambda| would have compared
    assert np.all(r.full > 0)  # facets and corners attract: all slow modes unstable
    assert r.max_rel_diff < 0.015
    # the uncorrected reduction is 4-6% off (the splice's linear superposition of tails)
    u = compare_eigenvalues(6, facet=0.4)
    assert 0.04 < u.max_rel_diff < 0.08 and np.array_equal(u.full, r.full)


@pytest.mark.parametrize("n, facet", [(3, 0.35), (4, 0.4), (5, 0.35)])
def test_corrected_slow_eigenvalues_within_one_percent(n, facet):
    r = compare_eigenvalues(n, facet=facet, correction="newton")
    _check_pairing(r)
    assert r.reduced.size == 2 * n - 4 and r.max_rel_diff < 0.01
    assert r.summary()["pairing"] == "overlap" and r.summary()["n_corners"] == n


def test_unequal_polygon_is_compared_as_the_operator_at_the_splice():
    # not a rest point: the rigid motions are no longer in the kernel of the operator at
    # the curve (their eigenvalues are of the size of the slow ones), so its slow
    # eigenvalues are not rates of the flow (see qsa.paper.eigenvalues)
    sc = Scenario("t", (130.0, 120.0, 110.0), (0.3, 0.4, 0.5), "unequal triangle", 1.0)
    r = compare_eigenvalues(sc)
    assert not r.equilibrium and np.isnan(r.polish_residual)
    assert np.max(np.abs(r.rigid)) > 0.01 * np.min(np.abs(r.full))
    assert np.all(r.capture > 0.8)


def test_polygon_scenario():
    sc = polygon_scenario(4, 0.3, facets=(0.3, 0.4, 0.3, 0.4))
    assert sc.angles == (90.0,) * 4 and sc.facets == (0.3, 0.4, 0.3, 0.4)
    assert polygon_scenario(5, 0.4) == Scenario.regular(5, 0.4)


@pytest.mark.slow
def test_regular_polygon_family():
    """3 ... 8 corners x facets 0.25 ... 0.5.

    The measured table: docs/guide/reduction.md, "Slow eigenvalues on the regular
    polygon families".
    """
    corr, unc = {}, {}
    for n in range(3, 9):
        for f in (0.25, 0.3, 0.35, 0.4, 0.5):
            r = compare_eigenvalues(n, facet=f, correction="newton", extra=4 * n)
            u = compare_eigenvalues(n, facet=f, extra=4 * n)
            assert np.all(r.capture > 0.999) and np.all(u.capture > 0.999)
            corr[n, f], unc[n, f] = r.max_rel_diff, u.max_rel_diff
    long = [0.35, 0.4, 0.5]
    # corners of 0.25 and longer (n <= 5), facets >= 0.35: within 1%
    assert max(corr[n, f] for n in (3, 4, 5) for f in long) < 0.01
    # hexagon (corners 0.21): within 2%
    assert max(corr[6, f] for f in long) < 0.02
    # overlapping corners (7: 0.18, 8: 0.157): the error grows as the corners shorten,
    # whatever the facets -- a limit of the splice manifold, not of the facets
    for f in long:
        assert corr[6, f] < corr[7, f] < corr[8, f]
        assert 0.03 < corr[7, f] < 0.1 and 0.1 < corr[8, f] < 0.25
    # short facets: the error grows steeply below 0.35 (fronts overlap across the facet)
    for n in (3, 4, 5):
        assert corr[n, 0.35] < corr[n, 0.3] < corr[n, 0.25]
        assert corr[n, 0.25] > 0.08
    # the correction always helps
    assert all(corr[k] < unc[k] for k in corr)


def test_profile_manifold_octagon_within_a_tenth_of_a_percent():
    """Corners of 0.157 (their fronts overlap: lambda c = 5.6), facets 0.35: the
    Newton-corrected splice is 16% off, the quasi-steady profiles with the lag 0.07%.

    Both linearizations at the same rest point (``length="equilibrium"``: the N-pulse
    is 1.7e-3 longer than the splice, which alone moves the facet modes by 0.7%).
    """
    r = compare_eigenvalues(8, facet=0.35, correction="profile-lag", length="equilibrium")
    _check_pairing(r)
    assert r.reduced.size == 12 and r.length == "equilibrium"
    assert r.max_rel_diff < 0.002
    # without the lag the corner modes are 1-3% low: the profile lags behind the fronts
    q = compare_eigenvalues(8, facet=0.35, correction="profile", length="equilibrium")
    assert np.allclose(q.full, r.full, rtol=1e-9)
    assert 0.02 < q.max_rel_diff < 0.035 and np.all(q.reduced < r.reduced + 1e-9)


def test_length_option_is_checked():
    with pytest.raises(ValueError, match="length must be"):
        compare_eigenvalues(3, facet=0.4, length="full")
    sc = Scenario("t", (130.0, 120.0, 110.0), (0.3, 0.4, 0.5), "unequal triangle", 1.0)
    with pytest.raises(ValueError, match="regular polygon"):
        compare_eigenvalues(sc, length="equilibrium")


@pytest.mark.slow
def test_regular_polygon_family_on_the_profile_manifold():
    """3 ... 8 corners x facets 0.25 ... 0.5, ``correction="profile-lag"`` at the
    N-pulse's length: within 0.5% everywhere (measured: <= 0.07% up to facets 0.35,
    max 0.31% for the octagon with facets 0.5, where the lag's next order shows).

    The table: docs/guide/reduction.md, "Slow eigenvalues on the regular polygon
    families".
    """
    for n in range(3, 9):
        for f in (0.25, 0.3, 0.35, 0.4, 0.5):
            r = compare_eigenvalues(n, facet=f, correction="profile-lag",
                                    length="equilibrium", extra=4 * n)
            assert np.all(r.capture > 0.999)
            assert r.max_rel_diff < 0.005, (n, f, r.max_rel_diff)


def test_length_free_profile_reduction_rests_at_the_n_pulse():
    """With the length an unknown (the full problem's beta = 5) the quasi-steady
    profiles' reduction rests at the N-pulse's own length (measured 2e-13 off), so the
    default ``length="splice"`` compares at the same rest point; its perimeter mode
    (-51.07) is paired too (8e-7 off) and the 12 slow modes are as at the
    N-pulse's length (0.066%). The Newton-corrected splice rests 2.2e-3 shorter."""
    r = compare_eigenvalues(8, facet=0.35, correction="profile-lag", variable_length=True)
    assert r.variable_length and r.reduced.size == 13
    assert abs(r.length_offset) < 1e-9
    i = r.perimeter_index
    assert r.reduced[i] < -40 and r.rel_diff[i] < 1e-5
    slow = np.delete(r.rel_diff, i)
    assert slow.max() < 0.002
    fixed = compare_eigenvalues(8, facet=0.35, correction="profile-lag", length="equilibrium")
    np.testing.assert_allclose(np.delete(r.reduced, i), fixed.reduced, rtol=1e-5)


@pytest.mark.slow
def test_regular_polygon_family_length_free_on_the_profile_manifold():
    """6 ... 8 corners x facets 0.35, 0.5, ``correction="profile-lag"`` with the length
    free at the reduction's own rest point, which is the N-pulse's (measured: slow
    modes within 0.003-0.35%, the perimeter mode within 8e-7, lengths within 5e-11).

    The table: docs/guide/reduction.md, "Slow eigenvalues on the regular polygon
    families", length free.
    """
    for n in (6, 7, 8):
        for f in (0.35, 0.5):
            r = compare_eigenvalues(n, facet=f, correction="profile-lag",
                                    variable_length=True, extra=4 * n)
            assert np.all(r.capture > 0.999)
            assert abs(r.length_offset) < 1e-9, (n, f, r.length_offset)
            i = r.perimeter_index
            assert r.rel_diff[i] < 1e-5, (n, f, r.rel_diff[i])
            assert np.delete(r.rel_diff, i).max() < 0.005, (n, f, r.max_rel_diff)
