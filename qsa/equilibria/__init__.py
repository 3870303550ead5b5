"""Equilibria of the faceting energy: fronts, N-pulses, splices (section "Formal Equilibrium").

``heteroclinic(alpha, well)`` -> the front ``psi_h``; ``npulse(n_pulses, alpha, ...)`` ->
the N-fold symmetric faceted equilibrium; ``splice(positions, alpha, length=...)`` and
``splice_polygon(angles, facets, alpha)`` -> 2N-front quasi-equilibria closed to 1e-12;
``circle(R, alpha, ...)``; ``polish(energy, curve)`` (Newton to the exact discrete
equilibrium) and ``continuation(...)`` (natural / pseudo-arclength, folds). All but
the front return :class:`Equilibrium`. Conventions and the corrected signs follow
MATH.md section 5.
"""

from qsa.equilibria.continuation import Branch, BranchPoint, Fold, continuation
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
    "Branch",
    "BranchPoint",
    "Fold",
    "PolishResult",
    "continuation",
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
