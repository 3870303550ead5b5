"""Shared fixtures of the reduction tests."""

import numpy as np
import pytest

from qsa.equilibria import splice_polygon
from qsa.reduction.ode import FrontODE

ALPHA, KSTAR = 0.1, 5.0


@pytest.fixture(scope="module")
def triangle():
    eq = splice_polygon(np.deg2rad([130, 120, 110]), [0.3, 0.4, 0.5], ALPHA, kstar=KSTAR)
    p = np.array(eq.params["positions"])
    ode = FrontODE(ALPHA, KSTAR, eq.params["L"], points_per_width=8)
    return ode, p, tuple(eq.params["cutoff"])
