"""is_quartic / resolve_well: the closed-form paths are taken only for the quartic itself."""

import numpy as np
import pytest

from qsa.energies import DoubleWell, Well
from qsa.equilibria._wells import QuarticWell, is_quartic, resolve_well


@pytest.mark.parametrize("make", [DoubleWell, QuarticWell])
def test_is_quartic_checks_kstar(make):
    assert is_quartic(make(5.0), 5.0)
    # the same family with another kstar is not "the quartic with this kstar"
    assert not is_quartic(make(5.0), 4.0)


def test_is_quartic_recognises_an_equal_user_well_and_rejects_others():
    k = 3.0
    same = Well(lambda x: 0.25 * x**2 * (x - k) ** 2, lambda x: 0 * x, lambda x: 0 * x, k)
    other = Well(lambda x: x**2 * (x - k) ** 2, lambda x: 0 * x, lambda x: 0 * x, k)
    assert is_quartic(same, k) and not is_quartic(other, k)


def test_resolve_well_default():
    well, kstar = resolve_well(None, None)
    assert kstar == 5.0 and is_quartic(well, kstar)
    assert np.isclose(well.d2W(0.0), kstar**2 / 2)
