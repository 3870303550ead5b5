"""is_quartic / resolve_well: the closed-form paths are taken only for the quartic itself."""

from types import SimpleNamespace

import numpy as np
import pytest

import qsa.energies as qsa_energies
from qsa.energies import DoubleWell, Well
from qsa.energies.wells import QuarticWell, is_quartic, resolve_well


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


def test_quartic_is_recognised_by_type_not_by_class_name():
    class DoubleWell:  # a user well that only shares the name
        kstar = 5.0

        def W(self, k):
            return np.asarray(k) ** 2 * (np.asarray(k) - 5.0) ** 2  # 4x the quartic

        dW = d2W = W

    assert not is_quartic(DoubleWell(), 5.0)
    assert QuarticWell is qsa_energies.DoubleWell


def test_resolve_well_checks_the_shape_only_when_asked():
    tilted = Well(lambda k: 0.25 * k**2 * (k - 2.0) ** 2 + 0.1 * k,
                  lambda k: 0.5 * k * (k - 2.0) * (2 * k - 2.0) + 0.1,
                  lambda k: 0.5 * (6 * k**2 - 12 * k + 4.0), kstar=2.0)
    with pytest.raises(ValueError, match="not a well"):
        resolve_well(tilted, 2.0)
    assert resolve_well(tilted, 2.0, equal_depth=False) == (tilted, 2.0)
    # energies and flows take any potential with the three callables
    assert qsa_energies.Faceting(0.1, 2.0, well=tilted).well is tilted
    with pytest.raises(ValueError, match="d2W is missing"):
        resolve_well(SimpleNamespace(W=np.sin, dW=np.cos), 2.0, equal_depth=False)
    with pytest.raises(ValueError, match="disagrees"):
        resolve_well(qsa_energies.DoubleWell(4.0), 5.0)
    with pytest.raises(ValueError, match="kstar must be positive"):
        resolve_well(None, -1.0)
    well, kstar = resolve_well(qsa_energies.DoubleWell(4.0), None)
    assert kstar == 4.0 and is_quartic(well, kstar)
