"""Front-position reduction of the faceting flow (quasi-steady dynamics of splices).

:mod:`qsa.reduction.fronts` detects and tracks the fronts of any curvature profile.
The front-position ODE ``p' = F(p)`` on the manifold of heteroclinic splices
``psi_N(p)`` is :class:`FrontODE` (:mod:`qsa.reduction.ode`), built of the splice
manifold's fields (:mod:`qsa.reduction.manifold`, with the derivation of the metric),
the optional slow-manifold correction of the force (:mod:`qsa.reduction.correction`),
a numpy or compiled evaluation (:mod:`qsa.reduction.backends`) and the integration
through collisions (:mod:`qsa.reduction.integrate`); :mod:`qsa.reduction.compare`
validates it against the DAE flow and the full linearization (``qsa reproduce fronts``).
"""

from qsa.reduction.backends import FrontEvaluation
from qsa.reduction.compare import SCENARIOS, compare_eigenvalues, compare_fronts
from qsa.reduction.fronts import (
    CoarseningEvent,
    Fronts,
    FrontTracks,
    detect_fronts,
    track_flow,
    track_fronts,
)
from qsa.reduction.integrate import (
    FrontODEResult,
    ODECollision,
    ODESegment,
    collision_distance,
    collision_sensitivity,
)
from qsa.reduction.manifold import SpliceFields
from qsa.reduction.ode import FrontODE

__all__ = ["CoarseningEvent", "Fronts", "FrontTracks", "detect_fronts", "track_flow",
           "track_fronts", "FrontODE", "FrontODEResult", "collision_distance",
           "collision_sensitivity", "SCENARIOS", "compare_fronts", "compare_eigenvalues",
           "FrontEvaluation", "ODECollision", "ODESegment", "SpliceFields"]
