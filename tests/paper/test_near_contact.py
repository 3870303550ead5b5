"""Near-contact spacing of polished folded CHA equilibria (s:NSI): d -> l* sqrt(a^2 + 1/2)."""

import numpy as np
import pytest

from qsa.energies import AdhesionKernel
from qsa.energies.adhesion import adhesion_fields
from qsa.paper.near_contact import (
    decay_length,
    dumbbell,
    near_contact_study,
    near_contact_sweep,
    pair_stiffness,
    paired_dumbbell,
    relaxation_length,
    sheet_spacing,
)


def test_dumbbell_is_a_closed_ccw_curve_with_parallel_sheets():
    neck, d, R, r = 2.0, 0.06, 0.25, 0.05
    x, y = dumbbell(neck, d, R, r, 4000)
    chords = np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)
    assert np.ptp(chords) < 1e-4 * chords.mean()          # closed, equal arc length
    phi = np.arccos((d / 2 + r) / (R + r))
    length = 2 * neck + 2 * (2 * r * phi + R * (np.pi + 2 * phi))
    assert chords.sum() == pytest.approx(length, rel=1e-5)  # chords: -h^2 kappa^2 / 24
    area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    assert area > 0                                       # counter-clockwise
    sheet = np.abs(x) < neck / 2
    assert np.allclose(np.abs(y[sheet]), d / 2, atol=1e-12)
    h = x.size // 2                                       # symmetric under the half turn
    assert np.allclose(np.roll(x, h), -x, atol=1e-12) and np.allclose(np.roll(y, h), -y, atol=1e-12)
    with pytest.raises(ValueError, match="radius"):
        dumbbell(neck, d, 0.02, r, 100)
    with pytest.raises(ValueError, match="N"):
        dumbbell(neck, d, R, r, 5)


@pytest.mark.parametrize("a", [0.8, 1.0, 1.5])
def test_pair_stiffness_is_the_derivative_of_the_force_between_strands(a):
    # two straight strands y = 0 and y = D: central differences in D of the normal force
    # on the lower one (outward normal -e_y) at D = d*, where the force vanishes
    A0, l_star = 3.0, 0.05
    k = AdhesionKernel(A0=A0, l_star=l_star, a=a)
    h = l_star / 8
    s = h * np.arange(-320, 321)
    mid = s.size // 2

    def normal_force(D):
        x = np.concatenate([s, s])
        y = np.concatenate([np.zeros_like(s), np.full_like(s, D)])
        return -adhesion_fields(k, x, y, h)[1][mid, 1]

    d, dD = k.pair_separation, 1e-4 * l_star
    assert abs(normal_force(d)) < 1e-10 * A0 / l_star
    fd = (normal_force(d + dD) - normal_force(d - dD)) / (2 * dD)
    assert pair_stiffness(A0, l_star, a) == pytest.approx(fd, rel=1e-6)
    # the relaxation length scales like (eps l* / A0)^(1/4)
    r = relaxation_length(0.08, A0, l_star, a)
    assert relaxation_length(0.08 * 16, A0, l_star, a) == pytest.approx(2 * r)
    assert relaxation_length(0.08, A0, l_star / 16, a) == pytest.approx(r / 2)


def test_decay_length_of_decaying_oscillations_from_both_ends():
    lam, length = 0.07, 2.0
    arc = np.linspace(0, length, 2001)
    x = np.minimum(arc, length - arc)
    d_star = 0.03
    spacing = d_star * (1 + 0.05 * np.exp(-x / lam) * np.cos(x / lam + 0.4))
    assert decay_length(arc, spacing, d_star) == pytest.approx(lam, rel=1e-3)
    assert np.isnan(decay_length(arc, np.full_like(arc, d_star), d_star))


def test_spacing_of_a_polished_dumbbell_tends_to_d_star():
    # a dumbbell polished at l* = 0.1 (Table T1's eps, beta, A0, a) and followed to
    # l* = 0.2: the sheets sit at l* sqrt(a^2 + 1/2) in the middle of the pair, the
    # deviation decreasing with l*; l* sqrt(a^2 + 1) (the kernel's minimum) is 15% off
    start = paired_dumbbell(0.1, N=201, t_flow=0.5)
    assert start.polished.success and start.relative_residual <= 1e-9
    sw = near_contact_sweep(start, [0.2, 0.1], nodes_per_l_star=4, N_min=201)
    assert sw.success, sw.message
    p02, p01 = sw.points
    for p in sw.points:
        assert p.relative_residual <= 1e-9 and p.n_pairs == 1
        assert p.target == pytest.approx(p.l_star * np.sqrt(1.5))
        assert p.grid_change < 1e-6                        # N vs 2N - 1
        assert p.pair_length > 10 * p.target               # a long pair, not a contact
        assert abs(p.spacing / (p.l_star * np.sqrt(2.0)) - 1) > 0.1
    assert abs(p02.relative_error) < 1e-4
    assert abs(p01.relative_error) < abs(p02.relative_error) / 10
    assert sw.order > 1
    # where the sheets turn apart into the lobes the spacing dips below d*
    assert -0.1 < p01.minimum / p01.target - 1 < -0.005
    # and relaxes to d* along the pair on the length of the linearized bending-adhesion balance
    assert p01.decay == pytest.approx(p01.predicted_decay, rel=0.1)
    # the measurement itself: the polished curve's pair, d* from the kernel
    sp = sheet_spacing(sw.curves[1], 0.1)
    assert sp.target == AdhesionKernel(40.0, 0.1, 1.0).pair_separation
    assert sp.mid_separations[0] == p01.spacing
    arc, d = sw.profiles()[1]
    assert np.array_equal(d, sp.profiles[0][1])
    assert arc[-1] == pytest.approx(p01.pair_length, rel=0.01)
    assert {"order", "decay_order", "points", "params"} <= set(sw.summary())
    assert sw.table().count("\n") == 3


class Unpolished:
    """A starting state whose polish failed."""

    params = {"eps": 0.08, "beta": 60.0, "A0": 40.0, "a": 1.0, "L_star": 7.0, "l_star": 0.1}

    class polished:
        success = False
        message = "maximum number of Newton iterations reached"


def test_sweep_refuses_an_unpolished_start_and_the_study_reports_it(monkeypatch):
    with pytest.raises(ValueError, match="start"):
        near_contact_sweep(Unpolished(), [0.1])
    class Polished(Unpolished):
        class polished:
            success = True

    with pytest.raises(ValueError, match="l_stars"):
        near_contact_sweep(Polished(), [])
    with pytest.raises(ValueError, match="max_ratio"):
        near_contact_sweep(Polished(), [0.1], max_ratio=1.0)
    import qsa.paper.near_contact as nc

    monkeypatch.setattr(nc, "paired_dumbbell", lambda *a, **k: Unpolished())
    sw = near_contact_study([0.1])
    assert not sw.success and sw.points == () and "did not polish" in sw.message


@pytest.mark.slow
def test_near_contact_sweep_from_l_star_0_2_to_0_025():
    # the documented sweep (docs/paper-results.md): Table T1's eps, beta, A0, a, a fixed
    # perimeter target, 10 nodes per l*, each state checked on Fourier(2N - 1)
    sw = near_contact_study()
    assert sw.success, sw.message
    assert [p.l_star for p in sw.points] == [0.2, 0.1, 0.05, 0.025]
    err = np.array([abs(p.relative_error) for p in sw.points])
    for p in sw.points:
        assert p.relative_residual <= 1e-9 and p.n_pairs == 1
        assert p.grid_change < 1e-6
        assert p.N >= 10 * 7.0 / p.l_star
    assert err[0] < 1e-4 and np.all(err[1:] < err[0] / 10)
    assert np.all(err[1:] < 1e-6)
    # the tails relax on the predicted length, better and better as l* shrinks
    # (measured 0.36, 0.042, 0.012, 0.0015)
    decay = np.array([abs(p.decay_error) for p in sw.points])
    assert np.all(np.diff(decay) < 0) and decay[1] < 0.06 and decay[-1] < 0.005
    assert sw.decay_order > 1.5
