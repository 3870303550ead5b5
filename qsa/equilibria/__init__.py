"""Equilibria of the faceting energy: fronts, N-pulses, splices (section "Formal Equilibrium").

``heteroclinic(alpha, well)`` -> the front ``psi_h``; ``npulse(n_pulses, alpha, ...)`` ->
the N-fold symmetric faceted equilibrium; ``splice(positions, alpha, length=...)`` and
``splice_polygon(angles, facets, alpha)`` -> 2N-front quasi-equilibria closed to 1e-12;
``circle(R, alpha, ...)``; ``polish(energy, curve)`` (Newton to the exact discrete
equilibrium). All but the front return :class:`Equilibrium`. Conventions and the
corrected signs follow Conventions and errata, section 5. Continuation of equilibria is
:mod:`qsa.continuation` (``qsa.equilibria.continuation``, ``Branch``, ``BranchPoint``
and ``Fold`` remain here as deprecated aliases).
"""

import importlib
import warnings

from qsa.equilibria.heteroclinic import Heteroclinic, heteroclinic
from qsa.equilibria.newton import PolishResult, multipliers, polish, residual_scale
from qsa.equilibria.npulse import circle, npulse, resolving_size
from qsa.equilibria.orbit import PeriodicOrbit, periodic_orbit, periodic_range
from qsa.equilibria.result import Equilibrium
from qsa.equilibria.splice import (
    SpliceProfile,
    close_positions,
    default_cutoff,
    splice,
    splice_closure,
    splice_polygon,
)

__all__ = [
    "PolishResult",
    "multipliers",
    "polish",
    "residual_scale",
    "Equilibrium",
    "Heteroclinic",
    "PeriodicOrbit",
    "circle",
    "heteroclinic",
    "npulse",
    "periodic_orbit",
    "periodic_range",
    "resolving_size",
    "splice",
    "splice_polygon",
    "SpliceProfile",
    "close_positions",
    "default_cutoff",
    "splice_closure",
]

_MOVED = ("Branch", "BranchPoint", "Fold", "continuation")


def __getattr__(name):
    # continuation stands above the equilibria (it needs the spectra too), so the
    # deprecated names are looked up lazily instead of imported here.
    if name in _MOVED:
        warnings.warn(f"qsa.equilibria.{name} is deprecated; use qsa.continuation.{name}",
                      DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module("qsa.continuation"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
