"""Curve diagnostics of the simulations: fronts, symmetry, paired sheets, self-intersection."""

import numpy as np
import pytest

from qsa.flows.analysis import (
    SelfIntersectionMonitor,
    closest_approach,
    count_fronts,
    curvature_shift_defect,
    facet_lengths,
    front_crossings,
    functional_residual,
    paired_sheets,
    rotation_defect,
)
from qsa.resample import resample_closed


def pulses(N, fronts, kstar=5.0, width=0.004):
    """kappa(s) with tanh fronts at the given (sorted, alternating up/down) positions."""
    s = np.arange(N) / N
    k = np.zeros(N)
    for p_up, p_down in zip(fronts[::2], fronts[1::2], strict=True):
        for shift in (-1, 0, 1):
            k += 0.5 * kstar * (np.tanh((s - p_up - shift) / width)
                                - np.tanh((s - p_down - shift) / width))
    return k


def test_front_positions_signs_and_lengths():
    fronts = [0.05, 0.2, 0.4, 0.53, 0.71, 0.9]
    k = pulses(600, fronts)
    s, sign = front_crossings(k, 2.5, 0.5)
    assert np.allclose(s, fronts, atol=1e-4)
    assert list(sign) == [1, -1, 1, -1, 1, -1]
    corners, facets = facet_lengths(s, sign, 3.0)
    assert np.allclose(corners, 3.0 * np.array([0.15, 0.13, 0.19]), atol=1e-3)
    assert np.allclose(facets, 3.0 * np.array([0.2, 0.18, 0.15]), atol=1e-3)
    assert corners.sum() + facets.sum() == pytest.approx(3.0)


def test_front_across_the_periodic_seam_and_hysteresis():
    k = pulses(600, [0.9, 1.1])  # one corner across s = 0
    s, sign = front_crossings(k, 2.5, 0.5)
    assert np.allclose(s, [0.1, 0.9], atol=1e-4) and list(sign) == [-1, 1]
    # noise that wiggles around the level inside the band is not a front
    rng = np.random.default_rng(0)
    flat = 2.5 + 0.3 * rng.standard_normal(600)
    assert count_fronts(flat, 2.5, 1.0) == 0
    assert count_fronts(flat, 2.5, 0.0) > 10
    assert count_fronts(np.zeros(50), 2.5) == 0
    with pytest.raises(ValueError, match="kappa"):
        count_fronts([1.0, np.nan, 2.0, 3.0], 2.5)


def test_functional_residual_is_spread_about_the_mean():
    assert functional_residual(np.full(10, 3.0)) == 0.0
    mu = np.array([0.0, 0.0, 0.0, 4.0])
    assert functional_residual(mu) == pytest.approx(3.0)
    assert functional_residual(mu, weights=[1, 1, 1, 3]) == pytest.approx(2.0)


def polar_nodes(r, N=600, rotate=0.0, shift=(0.0, 0.0)):
    th = 2 * np.pi * np.arange(4 * N) / (4 * N)
    rr = r(th)
    x, y, _ = resample_closed(rr * np.cos(th), rr * np.sin(th), N, method="chord")
    c, s = np.cos(rotate), np.sin(rotate)
    return c * x - s * y + shift[0], s * x + c * y + shift[1]


def test_rotation_defect_of_ellipse_matches_first_order_formula():
    """r = 1 + d cos 2 theta rotated by 120 degrees moves by sqrt(3) d at most."""
    d = 1e-3
    x, y = polar_nodes(lambda t: 1 + d * np.cos(2 * t))
    assert rotation_defect(x, y) == pytest.approx(np.sqrt(3) * d, rel=0.02)
    # invariant under rigid motions
    x2, y2 = polar_nodes(lambda t: 1 + d * np.cos(2 * t), rotate=0.7, shift=(3.0, -1.0))
    assert rotation_defect(x2, y2) == pytest.approx(rotation_defect(x, y), rel=1e-3)


def test_rotation_defect_vanishes_for_symmetric_curves():
    x, y = polar_nodes(lambda t: 1 + 0.2 * np.cos(3 * t), shift=(0.4, 0.2))
    assert rotation_defect(x, y) < 2e-5
    assert rotation_defect(x, y, k=2) > 0.1
    with pytest.raises(ValueError, match="k"):
        rotation_defect(x, y, k=1)


def test_curvature_shift_defect():
    s = np.arange(600) / 600
    assert curvature_shift_defect(2 + np.cos(6 * np.pi * s)) < 1e-12
    assert curvature_shift_defect(2 + np.cos(6 * np.pi * s[:-1] * 600 / 599)) < 1e-10
    assert curvature_shift_defect(2 + np.cos(2 * np.pi * s)) == pytest.approx(
        np.sqrt(3) / 3, rel=1e-6)


def stadium(length, gap, h):
    """Two straight strands ``gap`` apart joined by half circles, nodes about ``h`` apart."""
    r = gap / 2
    n_line = int(round(length / h))
    n_arc = max(int(round(np.pi * r / h)), 4)
    u = np.linspace(0, length, n_line, endpoint=False)
    a = np.linspace(-np.pi / 2, np.pi / 2, n_arc, endpoint=False)
    x = np.concatenate([u, length + r * np.cos(a), length - u, -r * np.cos(a)])
    y = np.concatenate([-r + 0 * u, r * np.sin(a), r + 0 * u, -r * np.sin(a)])
    return x, y


def test_paired_sheets_of_a_stadium():
    gap = 0.0122
    x, y = stadium(0.5, gap, 0.004)
    sheets = paired_sheets(x, y, 0.012247)
    assert sheets.n_pairs == 1
    assert sheets.separation == pytest.approx(gap, rel=1e-6)
    assert sheets.min_separations[0] == pytest.approx(gap, rel=1e-6)
    assert sheets.mid_separations[0] == pytest.approx(gap, rel=1e-6)
    assert sheets.lengths[0] == pytest.approx(0.5, rel=0.1)
    assert sheets.n_stacked == 0
    assert sheets.ratio == pytest.approx(gap / 0.012247)
    # far apart: no pairs
    x, y = stadium(0.5, 0.2, 0.004)
    assert paired_sheets(x, y, 0.012247).n_pairs == 0


def test_mid_separation_is_taken_halfway_along_the_pair():
    # sheets opening linearly from 0.012 to 0.024 along x in [0, 0.5]: the middle of
    # the pair (x = 0.25, spacing 0.018) whatever node the curve starts at
    x, y = stadium(0.5, 0.012, 0.002)
    y = y * (1 + np.clip(x, 0, 0.5) / 0.5)
    for shift in (0, 100, 300):
        sheets = paired_sheets(np.roll(x, shift), np.roll(y, shift), 0.012)
        assert sheets.n_pairs == 1
        assert sheets.mid_separations[0] == pytest.approx(0.018, rel=0.02)
        assert sheets.min_separations[0] == pytest.approx(0.012, rel=0.02)
        arc, d = sheets.profiles[0]
        assert np.all(np.diff(arc) > 0) and arc[0] == 0
        inside = (arc > 0.05) & (arc < 0.45)     # the spacing changes linearly
        assert np.allclose(np.abs(np.diff(d[inside]) / np.diff(arc[inside])), 0.024, rtol=0.05)


def test_closest_approach_and_self_intersection_monitor():
    x, y = stadium(0.5, 0.03, 0.004)
    assert closest_approach(x, y, 0.05) == pytest.approx(0.03, rel=0.05)
    th = 2 * np.pi * np.arange(200) / 200
    eight = (np.sin(2 * th), np.sin(th))  # a figure eight crosses itself
    m = SelfIntersectionMonitor(exclude_arc=0.05)
    m(0.0, np.cos(th), np.sin(th))
    m(0.1, *eight)
    m(0.2, *eight)
    m(0.3, np.cos(th), np.sin(th))
    assert m.intersected and m.crossing_times == [0.1, 0.2]
    assert m.intervals() == [(0.1, 0.2, 2)]
    assert m.summary()["self_intersected"] is True
    # where: the figure eight crosses itself at the origin, half the curve apart
    fc = m.first_crossing
    assert fc["t"] == 0.1 and fc["x"].shape == (200,)
    assert np.allclose(fc["points"], 0.0, atol=1e-12)
    ex, ey = eight
    L = np.sum(np.hypot(np.diff(ex, append=ex[0]), np.diff(ey, append=ey[0])))
    assert np.allclose(fc["arc_gap"], 0.5 * L, rtol=0.02)
    assert m.summary()["first_crossing"]["t"] == 0.1


def test_crossing_point_of_two_segments():
    # a bow tie: segment 0 (0,0)-(1,1) crosses segment 2 (0,1)-(1,0) at (0.5, 0.5)
    m = SelfIntersectionMonitor()
    m(1.0, [0.0, 1.0, 0.0, 1.0], [0.0, 1.0, 1.0, 0.0])
    assert np.allclose(m.first_crossing["points"], [[0.5, 0.5]])
    assert m.first_crossing["segments"].tolist() == [[0, 2]]
