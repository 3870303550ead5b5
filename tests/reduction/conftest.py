"""Shared fixtures of the reduction tests."""

import numpy as np
import pytest

from qsa.paper import scenario_splice
from qsa.reduction.ode import FrontODE

ALPHA, KSTAR = 0.1, 5.0


@pytest.fixture(scope="module")
def triangle():
    eq = scenario_splice("triangle", ALPHA, KSTAR)
    p = np.array(eq.params["positions"])
    ode = FrontODE(ALPHA, KSTAR, eq.params["L"], points_per_width=8)
    return ode, p, tuple(eq.params["cutoff"])
