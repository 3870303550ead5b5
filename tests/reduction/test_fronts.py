"""Front detection (sub-grid accuracy, kinds) and tracking (coarsening events)."""

import numpy as np
import pytest

from qsa import Curve, Fourier
from qsa.equilibria import SpliceProfile, heteroclinic
from qsa.reduction import detect_fronts, track_fronts


def sine_profile(N, s0=0.1234, kstar=5.0):
    s = np.arange(N) / N
    return 0.5 * kstar + 2.0 * np.sin(2 * np.pi * (s - s0)), s0


def test_crossings_converge_fourth_order():
    errs, Ns = [], [16, 32, 64, 128]
    for N in Ns:
        k, s0 = sine_profile(N)
        f = detect_fronts(k, 5.0)
        assert f.kinds.tolist() == [1, -1]
        errs.append(np.max(np.abs(f.positions - [s0, s0 + 0.5])))
    slope = np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert slope < -3.5


def test_length_scales_positions_and_gaps():
    k, s0 = sine_profile(64)
    f1 = detect_fronts(k, 5.0)
    f3 = detect_fronts(k, 5.0, length=3.0)
    assert np.allclose(f3.positions, 3.0 * f1.positions)
    assert np.isclose(f3.gaps().sum(), 3.0)
    assert f3.spacing == pytest.approx(3.0 / 64)


def test_splice_profile_fronts_at_positions():
    front = heteroclinic(0.1, kstar=5.0)
    p = np.array([0.3, 0.9, 1.4, 1.8, 2.3, 2.7])
    prof = SpliceProfile(front, p, 3.0, (0.6, 1.0))
    grid = Fourier(1501)
    f = detect_fronts(prof(3.0 * grid.s), 5.0, length=3.0)
    assert f.kinds.tolist() == [1, -1] * 3
    # neighbours' tails shift the crossings by ~exp(-lambda d), d >= 0.4
    assert np.max(np.abs(f.positions - p)) < 1e-4


def test_curve_input_and_no_fronts():
    c = Curve.circle(1.0, Fourier(33))
    assert detect_fronts(c, 5.0).n == 0
    assert detect_fronts(c, 1.5).n == 0  # kappa = 1 > level 0.75 everywhere
    assert detect_fronts(c.with_kappa(c.kappa + 0.3 * np.cos(2 * np.pi * c.grid.s)),
                         2.0).n == 2


@pytest.mark.parametrize("bad", [np.array([1.0, np.nan, 2.0, 3.0, 4.0]), np.ones(3)])
def test_bad_kappa(bad):
    with pytest.raises(ValueError, match="kappa"):
        detect_fronts(bad, 5.0)


def test_bad_length_and_kstar():
    k, _ = sine_profile(32)
    with pytest.raises(ValueError, match="length"):
        detect_fronts(k, 5.0, length=-1.0)
    with pytest.raises(ValueError, match="kstar"):
        detect_fronts(k, 0.0)


def moving_profiles(times, L=3.0, N=801):
    """Six fronts; the facet [p3, p4] closes at speed 0.1 and vanishes at t = 1."""
    front = heteroclinic(0.1, kstar=5.0)
    grid = Fourier(N)
    out = []
    for t in times:
        shift = 0.25 * t  # everything drifts across s = 0 as well
        if t < 1.0:
            d = 0.1 * (1 - t)
            p = np.array([0.3, 0.9, 1.4, 1.75 - d, 1.75 + d + 0.15, 2.7]) + shift
            prof = SpliceProfile(front, p - p[0], L, (0.3, 0.5))
            kap = prof(L * grid.s - p[0])
        else:
            p = np.array([0.3, 0.9, 1.4, 2.7]) + shift
            prof = SpliceProfile(front, p - p[0], L, (0.3, 0.5))
            kap = prof(L * grid.s - p[0])
        out.append(kap)
    return out


def test_tracking_pair_annihilation_and_wraparound():
    times = np.linspace(0, 1.6, 17)
    kap = moving_profiles(times)
    tr = track_fronts(times, kap, 5.0, [3.0] * times.size)
    assert tr.kinds.tolist() == [1, -1] * 3
    assert len(tr.events) == 1 and tr.unmatched == 0
    ev = tr.first_collision
    assert ev.bracket[0] < 1.0 <= ev.bracket[1] + 1e-12
    lost = set(ev.fronts)
    assert len(lost) == 2
    # unwrapped tracks of the survivors move at the drift speed 0.25 across s = 0
    for i in set(range(6)) - lost:
        x = tr.positions[:, i]
        assert np.all(np.isfinite(x))
        assert np.allclose(np.diff(x), 0.25 * np.diff(times), atol=1e-3)
    for i in lost:
        assert np.isnan(tr.positions[-1, i])


def test_tracking_bad_times():
    kap = moving_profiles([0.0, 0.1])
    with pytest.raises(ValueError, match="times"):
        track_fronts([0.1, 0.0], kap, 5.0)


def test_tracking_coarse_snapshots_fast_pair():
    # the closing pair moves by more than a quarter of the gap between snapshots
    times = np.array([0.0, 0.6, 0.95, 1.3])
    tr = track_fronts(times, moving_profiles(times), 5.0, [3.0] * times.size)
    assert len(tr.events) == 1 and tr.unmatched == 0
    assert tr.first_collision.bracket == (0.95, 1.3)
    assert np.all(np.isfinite(tr.positions[2]))
