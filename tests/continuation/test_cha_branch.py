"""Branches of CHA equilibria (circles) in the adhesion and length parameters."""

import numpy as np
import pytest

from qsa import Curve, Fourier
from qsa.continuation import continuation
from qsa.energies import Adhesion, CanhamHelfrich, CHAEnergy, Perimeter, cha_factory
from qsa.spectra import spectrum


def _critical_base(c, rho=1.5, A0=10.0, l_star=0.3):
    # V^n on a circle is constant and affine in L*: the L* that cancels it, as rho L0
    def v(L_star):
        E = CanhamHelfrich(0.1) + Perimeter(1.0, L_star) + Adhesion(A0, l_star)
        return np.mean(E.normal_velocity(c))

    L = c.length()
    L_star = L - v(L) / (v(L + 1.0) - v(L))
    return CHAEnergy(eps=0.1, beta=1.0, rho=rho, L0=L_star / rho, A0=A0, l_star=l_star)


def test_factory_builds_the_sum_and_refuses_unknown_parameters():
    base = CHAEnergy(eps=0.1, beta=1.0, rho=1.5, L0=4.0, A0=10.0, l_star=0.3)
    c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(65))
    manual = CanhamHelfrich(0.1) + Perimeter(1.0, 1.2 * 4.0) + Adhesion(10.0, 0.3)
    assert cha_factory("rho", base)(1.2).energy(c) == pytest.approx(manual.energy(c), rel=1e-14)
    with pytest.raises(ValueError, match="param"):
        cha_factory("beta", base)
    with pytest.raises(ValueError, match="L0"):
        CHAEnergy(eps=0.1, beta=1.0, rho=1.5, L0=-1.0, A0=10.0, l_star=0.3)


@pytest.mark.parametrize("param, values", [("A0", (10.0, 12.0, 1.0)),
                                           ("rho", (1.5, 1.52, 0.01)),
                                           ("l_star", (0.3, 0.34, 0.02)),
                                           ("a", (1.0, 1.1, 0.05)),
                                           ("eps", (0.1, 0.12, 0.01))])
def test_circle_branch_points_are_equilibria(param, values):
    c = Curve.circle(1.0, Fourier(65))
    base = _critical_base(c)
    br = continuation(cha_factory(param, base), c, param, values, method="natural",
                      stability=False)
    ps = [pt.param for pt in br.points]
    assert np.allclose(ps, np.arange(values[0], values[1] + 1e-12, values[2]))
    for pt in br.points:
        E = cha_factory(param, base)(pt.param)
        eq = pt.equilibrium.curve
        V = E.normal_velocity(eq)
        # relative to the bending term's own velocity, the largest single term
        assert np.abs(V).max() < 1e-8 * np.abs(E.terms()[0].normal_velocity(eq)).max()
        assert np.ptp(eq.kappa) < 1e-8            # still a circle
    # the radius moves with the parameter: the branch is not a single repeated point
    radii = [1.0 / pt.equilibrium.curve.kappa.mean() for pt in br.points]
    assert np.ptp(radii) > 1e-4


def test_circle_branch_in_rho_is_stable_with_the_translations_deflated():
    # the two translations (the normal kernel of a circle) are not counted as unstable
    c = Curve.circle(1.0, Fourier(65))
    base = _critical_base(c)
    br = continuation(cha_factory("rho", base), c, "rho", (1.5, 1.52, 0.01), method="natural")
    assert br.status == 0 and [pt.n_unstable for pt in br.points] == [0, 0, 0]
    s = spectrum(cha_factory("rho", base)(1.5), br.points[0].equilibrium.curve, k=8, sigma=0.0)
    assert s.n_kernel == 2 and s.n_unstable == 0
    assert np.sort(s.eigenvalues.real)[-3] < -0.1        # a gap below the kernel
