"""Front-position reduction of the faceting flow (quasi-steady dynamics of splices).

:mod:`qsa.reduction.fronts` detects and tracks the fronts of any curvature
profile; :mod:`qsa.reduction.ode` is the front-position ODE ``p' = F(p)`` on the
manifold of heteroclinic splices ``psi_N(p)`` (see its docstring for the
derivation of the metric); :mod:`qsa.reduction.compare` validates it against the
DAE flow and the full linearization (``qsa reproduce fronts``).
"""

from qsa.reduction.compare import SCENARIOS, compare_eigenvalues, compare_fronts
from qsa.reduction.fronts import (
    CoarseningEvent,
    Fronts,
    FrontTracks,
    detect_fronts,
    track_flow,
    track_fronts,
)
from qsa.reduction.ode import FrontODE, FrontODEResult, collision_distance, collision_sensitivity

__all__ = ["CoarseningEvent", "Fronts", "FrontTracks", "detect_fronts", "track_flow",
           "track_fronts", "FrontODE", "FrontODEResult", "collision_distance",
           "collision_sensitivity", "SCENARIOS", "compare_fronts", "compare_eigenvalues"]
