"""The pressurized inextensible elastic ring and the 2-D vesicle (length and area constraints).

CanhamHelfrich(eps) + Pressure(p) with FixedLength(), R = 1: the circle loses stability
at Levy's pressures p_n = -(n^2 - 1) eps / R^3 (n = 2, 3, 4 ...), each a double crossing
(mode n, O(2)); the n = 2 and n = 3 branches, switched there, are followed with their
stability until the ring touches itself. The n = 2 branch is also the branch of the 2-D
vesicle (fixed length and area) from the circle, parameterized by the reduced area
nu = 4 pi A / L^2: its points are equilibria of CanhamHelfrich alone at fixed L and A,
with the pressure as the area's multiplier, and dE/dA = p along it.
"""

import numpy as np
import pytest

from qsa import Curve, Fourier
from qsa.constraints import FixedArea, FixedLength
from qsa.continuation import MESSAGES, continuation, switch_branch
from qsa.energies import CanhamHelfrich, Pressure
from qsa.equilibria import polish
from tests.helpers import assert_status_convention

EPS = 1.0


def family(p):
    return CanhamHelfrich(EPS) + Pressure(p)


@pytest.fixture(scope="module")
def ring():
    """The circle branch (Fourier(75): 3 divides N, so the n = 3 branch keeps Z_3)."""
    b = continuation(family, Curve.circle(1.0, Fourier(75)), "p", (0.0, -16.5, -0.5),
                     constraints=[FixedLength()])
    assert b.success, b.message
    return b


def levy(n):
    return -(n * n - 1) * EPS


def test_levy_pressures_are_double_crossings_located_to_1e_6(ring):
    assert ring.symmetry.circle
    branch = [x for x in ring.bifurcations if x.kind == "branch"]
    assert [x.sector for x in branch] == [2, 3, 4]
    for x in branch:
        assert x.multiplicity == 2 and {m.label for m in x.modes} == {"mode"}
        assert abs(x.parameter - levy(x.sector)) <= 1e-6 * abs(levy(x.sector))
        assert x.curve.length() == pytest.approx(2 * np.pi, rel=1e-12)  # inextensible
    # the counts of every point: mode n is unstable (a pair) exactly below p_n; the
    # length constraint removes the breathing mode, the translations are the kernel
    for p in ring.points:
        assert p.sector_unstable[0] == 0 and p.sector_unstable[1] == 0
        for n in range(2, 8):
            assert p.sector_unstable[n] == 2 * int(p.param < levy(n))


@pytest.fixture(scope="module")
def switched(ring):
    out = {}
    for x in ring.bifurcations:
        if x.sector in (2, 3):
            (b,) = switch_branch(ring, x, span=(-40.0, 0.0, 0.25), ds_max=0.5, max_steps=400)
            out[x.sector] = b
    return out


def test_n2_and_n3_branches_are_followed_with_stability_to_self_contact(switched):
    for n, b in switched.items():
        assert_status_convention(b, MESSAGES)
        assert b.status == 1 and "touches itself" in b.message, b.message
        assert not b.points[-1].curve.self_intersects()
        # every point an equilibrium at the ring's length
        for p in b.points:
            assert p.equilibrium.relative_residual < 1e-8
            assert p.curve.length() == pytest.approx(2 * np.pi, rel=1e-10)
        # pressure control: compression grows monotonically up to contact
        assert np.all(np.diff(b.values) < 0) and b.values[0] < levy(n)
    # the n = 2 (buckled, oval to dumbbell) branch is stable up to contact; the n = 3
    # branch keeps the circle's unstable mode-2 pair (and its own Z_3 symmetry)
    assert np.all(switched[2].n_unstable == 0)
    assert np.all(switched[3].n_unstable >= 2)
    assert switched[3].symmetry.order == 3
    # contact pressures of the buckled ring (Flaherty, Keller & Rubinow 1972: p = -5.247
    # for n = 2, in units eps / R^3), to the resolution of the contact test
    assert switched[2].points[-1].param == pytest.approx(-5.247, rel=2e-3)


def test_vesicle_branch_from_the_circle_energy_against_reduced_area(switched):
    b = switched[2]
    nu = np.array([4 * np.pi * p.curve.area() / p.curve.length() ** 2 for p in b.points])
    E = np.array([CanhamHelfrich(EPS).energy(p.curve) for p in b.points])
    A = np.array([p.curve.area() for p in b.points])
    keep = nu >= 0.6
    assert nu[0] > 0.95 and nu[keep].min() < 0.75 and np.all(np.diff(nu) < 0)
    # bending energy grows as the vesicle deflates from the circle's 2 pi^2 eps / L (nu = 1)
    assert np.all(np.diff(E) > 0) and E[0] > np.pi * EPS
    # each point is an equilibrium of the vesicle problem: CanhamHelfrich alone at fixed
    # length and area, the area's multiplier being the pressure
    for p in [b.points[i] for i in np.flatnonzero(keep)[::2]]:
        v = polish(CanhamHelfrich(EPS), p.curve, constraints=[FixedLength(), FixedArea()])
        assert v.success and v.n_newton <= 2
        assert np.max(np.abs(v.curve.kappa - p.curve.kappa)) < 1e-7
        assert v.params["mu_A"] == pytest.approx(p.param, rel=1e-7)
    # dE/dA = p along the branch (secants against the midpoint pressure)
    dEdA = np.diff(E) / np.diff(A)
    pm = 0.5 * (b.values[1:] + b.values[:-1])
    assert np.allclose(dEdA[keep[1:]], pm[keep[1:]], rtol=2e-2)
