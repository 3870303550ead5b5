"""The two-point invariants (Lemma TP_invar, e:Ad-Invar) at smooth curves, both grids."""

import json

import numpy as np
import pytest

from qsa import Curve, FiniteDifference, Fourier
from qsa.energies import Adhesion, CanhamHelfrich, Perimeter, adhesion_invariants
from qsa.spectra import kernel_report, spectrum
from tests.helpers import fitted_order


def _curve(grid):
    return Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t) + 0.05 * np.sin(5 * t), grid)


@pytest.mark.parametrize("method", ["neighbours", "dense"])
@pytest.mark.parametrize("grid", [Fourier(129), FiniteDifference(400)])
def test_level_set_and_force_forms_vanish_to_round_off(grid, method):
    c = _curve(grid)
    inv = adhesion_invariants(Adhesion(A0=10.0, l_star=0.2, method=method), c, n_levels=40)
    assert inv.rotation_levels.shape == (40,) and inv.translation_levels.shape == (40, 2)
    # nearly every level set up to the cutoff holds node pairs, and each vanishes separately
    assert np.isfinite(inv.rotation_levels).sum() >= 34 and inv.level_set_max < 1e-13
    assert inv.rotation_force < 1e-13 and inv.translation_force < 1e-13


def test_curvature_forms_converge_spectrally_and_at_second_order():
    E = Adhesion(A0=10.0, l_star=0.2)
    four = [adhesion_invariants(E, _curve(Fourier(N))) for N in (129, 257)]
    assert four[1].rotation_curvature < 1e-11 and four[1].translation_curvature < 1e-11
    assert four[1].rotation_curvature < 1e-2 * max(four[0].rotation_curvature, 1e-12)
    Ns = [400, 800, 1600]
    fd = [adhesion_invariants(E, _curve(FiniteDifference(N))) for N in Ns]
    for name in ("rotation_curvature", "translation_curvature"):
        order = fitted_order(Ns, [getattr(r, name) for r in fd])
        assert 1.7 < order < 2.5, (name, order)


def test_a_wrong_force_breaks_the_curvature_form():
    # the curvature form needs the right relation between the force and B
    c = _curve(Fourier(257))
    E = Adhesion(A0=10.0, l_star=0.2)
    B, force = E.fields(c)
    n, tau = c.normal(), c.tangent()
    x, y = c.positions()
    ext = 1.01 * (force[:, 0] * n[0] + force[:, 1] * n[1]) + c.kappa * B
    gt = x * tau[0] + y * tau[1]
    wrong = abs(np.sum(ext * gt * c.dsigma)) / np.sum(np.abs(ext) * np.hypot(x, y) * c.dsigma)
    assert wrong > 1e4 * adhesion_invariants(E, c).rotation_curvature


def test_kernel_report_carries_the_two_point_invariants():
    c = _curve(Fourier(129))
    E = CanhamHelfrich(0.1) + Perimeter(1.0, 1.2 * c.length()) + Adhesion(10.0, 0.2)
    rep = kernel_report(E, c)
    assert rep.two_point is not None and rep.two_point["level_set_max"] < 1e-13
    assert rep.summary()["two_point"]["rotation_force"] < 1e-13
    assert kernel_report(CanhamHelfrich(0.1) + Perimeter(1.0, 7.0), c).two_point is None
    with pytest.warns(UserWarning):
        s = spectrum(E, c, k=6)
    assert s.kernel.two_point["rotation_curvature"] < 1e-6
    assert json.loads(json.dumps(s.kernel.summary()))["two_point"] == s.kernel.two_point


@pytest.mark.parametrize("bad", [0, -3, 2.5, True])
def test_bad_levels_and_energy(bad):
    c = _curve(Fourier(33))
    with pytest.raises(ValueError, match="n_levels"):
        adhesion_invariants(Adhesion(10.0, 0.2), c, n_levels=bad)
    with pytest.raises(ValueError, match="two-point"):
        adhesion_invariants(CanhamHelfrich(0.1), c)
