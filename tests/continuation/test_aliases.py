"""The old homes of continuation, the wells and the constrained operators keep working."""

import importlib
import sys

import numpy as np
import pytest

import qsa.continuation
import qsa.energies
import qsa.equilibria
from qsa.energies import Faceting, Perimeter
from qsa.equilibria import circle


def _tiny_branch(continuation):
    eq = circle(1.0, 0.1, grid=17)
    return continuation(lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls), eq.curve,
                        "L_star", (eq.params["L_star"], eq.params["L_star"] + 0.1, 0.05),
                        method="natural")


@pytest.fixture
def fresh_equilibria():
    """qsa.equilibria without the alias module (whose import binds "continuation")."""
    saved_attr = vars(qsa.equilibria).pop("continuation", None)
    saved_mod = sys.modules.pop("qsa.equilibria.continuation", None)
    yield
    vars(qsa.equilibria).pop("continuation", None)
    if saved_attr is not None:
        qsa.equilibria.continuation = saved_attr
    if saved_mod is not None:
        sys.modules["qsa.equilibria.continuation"] = saved_mod


@pytest.mark.parametrize("name", ["Branch", "BranchPoint", "Fold", "continuation"])
def test_moved_names_warn_and_are_the_new_objects(name, fresh_equilibria):
    with pytest.warns(DeprecationWarning, match=f"qsa.continuation.{name}"):
        obj = getattr(qsa.equilibria, name)
    assert obj is getattr(qsa.continuation, name)


def test_old_module_warns_on_import_and_reexports(fresh_equilibria):
    with pytest.warns(DeprecationWarning, match="qsa.equilibria.continuation is deprecated"):
        old = importlib.import_module("qsa.equilibria.continuation")
    for name in ("Branch", "BranchPoint", "Fold", "continuation"):
        assert getattr(old, name) is getattr(qsa.continuation, name)
    # "from qsa.equilibria import continuation" now finds the module: it is callable
    from qsa.equilibria import continuation

    b = _tiny_branch(continuation)
    assert isinstance(b, qsa.continuation.Branch) and b.success, b.message
    assert np.allclose(b.values, _tiny_branch(qsa.continuation.continuation).values)


def test_operators_reexported_from_the_equilibria():
    from qsa.equilibria import multipliers, residual_scale
    from qsa.equilibria.newton import normal_velocity

    assert multipliers is qsa.energies.multipliers
    assert residual_scale is qsa.energies.residual_scale
    assert normal_velocity is qsa.energies.normal_velocity


def test_wells_reexported_from_the_equilibria():
    from qsa.equilibria import _wells

    assert _wells.resolve_well is qsa.energies.resolve_well
    assert _wells.is_quartic is qsa.energies.is_quartic
    assert _wells.QuarticWell is qsa.energies.DoubleWell is qsa.energies.QuarticWell
    assert _wells._positive(2, "alpha") == 2.0
    with pytest.raises(ValueError, match="alpha must be positive"):
        _wells._positive(0, "alpha")
