"""Deprecated location of the paper's simulation scenarios: use :mod:`qsa.paper.scenarios`.

The names below are aliases of :mod:`qsa.paper` (kept so existing code keeps working).
"""

from qsa.paper.scenarios import (
    CHAScenario,
    FacetScenario,
    crenellated_radius,
    perturbed_circle_radius,
)

__all__ = ["FacetScenario", "CHAScenario", "crenellated_radius", "perturbed_circle_radius"]
