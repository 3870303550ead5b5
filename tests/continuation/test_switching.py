"""Branch switching: circles (O(2): one branch per mode), D_n points (isotropy directions)."""

import numpy as np
import pytest

from qsa import Fourier
from qsa.continuation import MESSAGES, continuation, switch_branch
from qsa.continuation.detection import switching_directions
from qsa.energies import Faceting, Perimeter
from qsa.equilibria import circle
from tests.helpers import assert_status_convention

K, BETA, ALPHA = 5.0, 5.0, 0.1


def family(L_star):
    return Faceting(ALPHA, K) + Perimeter(BETA, L_star)


@pytest.fixture(scope="module")
def circles():
    eq = circle(0.95, ALPHA, grid=Fourier(33), kstar=K, beta=BETA)
    b = continuation(family, eq.curve, "L_star", (eq.params["L_star"], 5.45, -0.05))
    assert [x.sector for x in b.bifurcations] == [2, 3, 4]
    return b


def test_mode_three_of_a_circle_switches_to_one_triangular_branch(circles):
    bif = circles.bifurcations[1]
    (new,) = switch_branch(circles, bif, span=(5.3, 5.7, 0.02), max_steps=12)
    assert_status_convention(new, MESSAGES)
    assert new.success and new.origin is bif and new.points
    # 3 divides N = 33: the new branch keeps Z_3 with a reflection (D_3)
    assert new.symmetry.order == 3 and new.symmetry.reflection is not None
    p_star = bif.parameter
    for p in new.points:
        assert p.equilibrium.relative_residual < 1e-9
        k = p.curve.kappa
        assert np.ptp(k) > 0 and np.max(np.abs(np.roll(k, -11) - k)) < 1e-12 * np.max(k)
    # a pitchfork: the first point is close to the bifurcation in the parameter (O(eps^2))
    # while its shape is O(eps) away from the circle
    first = new.points[0]
    amp = np.ptp(first.curve.kappa) / np.mean(first.curve.kappa)
    assert abs(first.param - p_star) < 10 * amp**2 * abs(p_star)
    # the new branch is unstable (subcritical): more unstable modes than the circle had
    assert new.n_unstable[0] >= 1
    # the critical mode of the parent is the mode-3 shape of the first point
    s = first.curve.grid.s
    dk = first.curve.kappa - np.mean(first.curve.kappa)
    c3 = np.hypot(np.mean(dk * np.cos(6 * np.pi * s)), np.mean(dk * np.sin(6 * np.pi * s)))
    assert c3 > 0.9 * np.sqrt(np.mean(dk**2)) / np.sqrt(2)


def test_dihedral_double_point_has_two_isotropy_directions(circles):
    tri = switch_branch(circles, circles.bifurcations[1], span=(5.3, 5.7, 0.02), max_steps=12)[0]
    doubles = [x for x in tri.bifurcations if x.kind == "branch" and x.multiplicity == 2]
    assert doubles, tri.message
    x = doubles[0]
    assert x.sector == 1 and {m.parity for m in x.modes} == {1, -1}
    dirs = switching_directions(x, tri.symmetry)
    # D_3 acting on the Bloch-1 plane: k = 3 is odd, so the fixed line of the reflections
    # has two inequivalent orientations, and nothing else
    assert len(dirs) == 2
    assert np.allclose(dirs[0], -dirs[1])
    assert np.allclose(tri.symmetry.reflect(dirs[0]), dirs[0], atol=1e-8)


def test_switching_rejects_folds_and_foreign_objects(circles):
    eq = circle(0.77, ALPHA, grid=Fourier(17), kstar=K, beta=BETA)
    b = continuation(family, eq.curve, "L_star", (eq.params["L_star"], 3.0, -0.1))
    fold = b.bifurcations[0]
    with pytest.raises(ValueError, match="fold"):
        switch_branch(b, fold)
    with pytest.raises(ValueError, match="bifurcation"):
        switch_branch(circles, "mode 2")
    with pytest.raises(ValueError, match="span"):
        switch_branch(circles, circles.bifurcations[0], span=(5.0, 5.0))


def test_isotropy_directions_of_a_four_pulse_pair():
    """D_4 on the Bloch-1 plane (k = 4, even): two classes of reflection axes, 45 degrees
    apart, each direction equivalent to its opposite: two directions."""
    import warnings

    from qsa import FiniteDifference
    from qsa.continuation import Bifurcation
    from qsa.continuation.detection import critical_modes
    from qsa.equilibria import npulse, polish
    from qsa.spectra.symmetry import sector_spectrum

    eq = npulse(4, 0.15, grid=FiniteDifference(200))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        eq = polish(eq.energy, eq.curve)
    s = sector_spectrum(eq.energy, eq.curve)
    i = int(np.flatnonzero((s.sector == 1) & (s.multiplicity == 2))[0])
    modes = critical_modes(s, i, s.symmetry)
    bif = Bifurcation(0.0, 2, "branch", modes, 0, eq, float(s.eigenvalues[i]), 2, None,
                      s.symmetry)
    dirs = switching_directions(bif, s.symmetry)
    assert len(dirs) == 2
    w = eq.curve.dsigma
    c = abs(np.sum(w * dirs[0] * dirs[1]))
    assert c == pytest.approx(np.cos(np.pi / 4), abs=1e-8)  # 45 degrees apart in the plane
    # each is fixed by a reflection of the 4-pulse
    for d in dirs:
        fixed = [np.allclose(np.roll(s.symmetry.reflect(d), -j * 50), d, atol=1e-8)
                 for j in range(4)]
        assert any(fixed)
