"""The energy models are frozen dataclasses: immutable, compared by value, same constructors."""

import dataclasses

import numpy as np
import pytest

from qsa import Curve, Fourier
from qsa.energies import Adhesion, CanhamHelfrich, DoubleWell, Faceting, Perimeter, Well


@pytest.mark.parametrize("make, same", [
    (lambda: Faceting(0.1, 5.0), lambda: Faceting(alpha=0.1, kstar=5, well=DoubleWell(5.0))),
    (lambda: CanhamHelfrich(0.3), lambda: CanhamHelfrich(eps=0.3)),
    (lambda: Adhesion(10.0, 0.5), lambda: Adhesion(A0=10, l_star=0.5, a=1.0,
                                                     method="neighbours")),
    (lambda: Perimeter(5.0, 6.0), lambda: Perimeter(beta=5, L_star=6)),
])
def test_frozen_and_equal_by_value(make, same):
    E = make()
    assert dataclasses.is_dataclass(E) and E == same() and hash(E) == hash(same())
    field = dataclasses.fields(E)[0].name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(E, field, 1.0)


def test_parameters_are_converted_and_reported_as_before():
    F = Faceting(alpha=1, kstar=5)
    assert isinstance(F.alpha, float) and F.well == DoubleWell(5.0)
    assert F.params() == {"energy": "Faceting", "alpha": 1.0, "kstar": 5.0}
    assert repr(F) == "Faceting(alpha=1.0, kstar=5.0)"
    assert CanhamHelfrich(1).params() == {"energy": "CanhamHelfrich", "eps": 1.0}
    A = Adhesion(10, 0.5, 2)
    assert A.params() == {"energy": "Adhesion", "A0": 10.0, "l_star": 0.5, "a": 2.0,
                          "method": "neighbours"}
    assert (A.kernel.A0, A.kernel.l_star, A.kernel.a) == (10.0, 0.5, 2.0)
    assert repr(A) == "Adhesion(A0=10.0, l_star=0.5, a=2.0)"
    assert Adhesion(10.0, 0.5) != Adhesion(10.0, 0.5, method="dense")


def test_user_well_is_kept_and_used():
    w = Well(lambda k: 2 * DoubleWell(5.0).W(k), lambda k: 2 * DoubleWell(5.0).dW(k),
             lambda k: 2 * DoubleWell(5.0).d2W(k), kstar=5.0)
    c = Curve.circle(1.0, Fourier(17))
    assert Faceting(0.1, 5.0, w).well is w
    assert Faceting(0.1, 5.0, w).energy(c) == pytest.approx(2 * Faceting(0.1, 5.0).energy(c))
    assert np.isclose(Faceting(0.1, 5.0, w).energy(c), 2 * np.pi * 2 * DoubleWell(5.0).W(1.0))


@pytest.mark.parametrize("make, match", [
    (lambda: Faceting(0.1), "kstar"),
    (lambda: Adhesion(A0=10.0, l_star=0.5, a=0.0), "a must be positive"),
    (lambda: Adhesion(A0="x", l_star=0.5), "A0 must be a positive number"),
    (lambda: CanhamHelfrich(eps=np.inf), "eps must be a non-negative finite number"),
])
def test_bad_arguments(make, match):
    with pytest.raises((ValueError, TypeError), match=match):
        make()
