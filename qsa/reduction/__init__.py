"""Front-position reduction of the faceting flow (quasi-steady dynamics of splices).

:mod:`qsa.reduction.fronts` detects and tracks the fronts of any curvature profile.
The front-position ODE ``p' = F(p)`` on the manifold of heteroclinic splices
``psi_N(p)`` is :class:`FrontODE` (:mod:`qsa.reduction.ode`), built of the splice
manifold's fields (:mod:`qsa.reduction.manifold`, with the derivation of the metric),
the optional slow-manifold correction of the force (:mod:`qsa.reduction.correction`)
or the manifold of constrained quasi-steady profiles that replaces the splice
(:mod:`qsa.reduction.quasisteady`),
a numpy or compiled evaluation (:mod:`qsa.reduction.backends`) and the integration
through collisions (:mod:`qsa.reduction.integrate`). :mod:`qsa.reduction.modes` writes
the reduced eigenmodes as normal perturbations of the curve and pairs them with the
full linearization's; :mod:`qsa.reduction.handover` starts the ODE from a curvature
profile (a DAE state); :mod:`qsa.reduction.projection` finds the splice nearest a
curve in the flow's metric (the ODE's restart after a collision). Its validation against the DAE
flow and the full linearization (``qsa reproduce fronts``) is :mod:`qsa.paper.fronts`;
``SCENARIOS``, ``compare_fronts`` and ``compare_eigenvalues`` stay importable from here
as aliases.
"""

import importlib

from qsa.reduction.backends import FrontEvaluation
from qsa.reduction.fronts import (
    CoarseningEvent,
    Fronts,
    FrontTracks,
    detect_fronts,
    track_flow,
    track_fronts,
)
from qsa.reduction.handover import HandOver, hand_over
from qsa.reduction.integrate import (
    FrontODEResult,
    ODECollision,
    ODESegment,
    collision_distance,
    collision_sensitivity,
)
from qsa.reduction.manifold import SpliceFields
from qsa.reduction.modes import ModePairing, ReducedModes, pair_modes, reduced_modes
from qsa.reduction.ode import FrontODE
from qsa.reduction.projection import NearestSplice, nearest_splice, splice_distance
from qsa.reduction.quasisteady import QuasiSteadyProfile, quasisteady_profile

__all__ = ["CoarseningEvent", "Fronts", "FrontTracks", "detect_fronts", "track_flow",
           "track_fronts", "FrontODE", "FrontODEResult", "collision_distance",
           "collision_sensitivity", "SCENARIOS", "compare_fronts", "compare_eigenvalues",
           "FrontEvaluation", "ODECollision", "ODESegment", "SpliceFields", "HandOver",
           "hand_over", "ModePairing", "ReducedModes", "pair_modes", "reduced_modes",
           "NearestSplice", "nearest_splice", "splice_distance", "QuasiSteadyProfile",
           "quasisteady_profile"]

#: aliases of qsa.paper, resolved on first use (qsa.paper imports this package)
_PAPER_ALIASES = {"SCENARIOS": "qsa.paper.scenarios", "compare_fronts": "qsa.paper.fronts",
                  "compare_eigenvalues": "qsa.paper.fronts"}


def __getattr__(name):
    if name in _PAPER_ALIASES:
        return getattr(importlib.import_module(_PAPER_ALIASES[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
