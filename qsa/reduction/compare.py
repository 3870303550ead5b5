"""Deprecated location of the front-reduction comparisons: use :mod:`qsa.paper.fronts`.

The names below are aliases of :mod:`qsa.paper` (kept so existing code keeps working).
"""

from qsa.paper.fronts import (
    FrontComparison,
    compare_eigenvalues,
    compare_fronts,
)
from qsa.paper.scenarios import SCENARIOS, Scenario, scenario_splice

__all__ = ["SCENARIOS", "Scenario", "FrontComparison", "scenario_splice", "compare_fronts",
           "compare_eigenvalues"]
