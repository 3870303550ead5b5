"""Energies of closed curves: protocol, local first- and second-order energies, the models.

Each energy provides ``energy``, ``gradient`` (nabla_I E in <f,h> = int f h dsigma),
``normal_velocity`` (outward V^n) and ``hessian`` (nabla_I^2 E); energies add with ``+``.
Energies of the enclosed area (``Pressure``, ``AreaPenalty``) are in :mod:`qsa.energies.area`.
On the closed manifold, ``normal_velocity``, ``multipliers`` (Lambda of
``nabla_I E = Lambda . Psi``) and ``residual_scale`` are functions of the energy
(:mod:`qsa.energies.constrained`); the double wells are in :mod:`qsa.energies.wells`.
"""

from qsa.energies.adhesion import Adhesion, AdhesionKernel
from qsa.energies.adhesion_invariants import TwoPointInvariants, adhesion_invariants
from qsa.energies.area import AreaEnergy, AreaPenalty, Pressure
from qsa.energies.base import Energy, EnergySum, Perimeter
from qsa.energies.cha import CHAEnergy, cha_factory
from qsa.energies.constrained import multipliers, normal_velocity, residual_floor, residual_scale
from qsa.energies.faceting import Faceting
from qsa.energies.functionalized import FunctionalizedCurvature
from qsa.energies.helfrich import CanhamHelfrich
from qsa.energies.local import Density, FirstOrderEnergy, LocalEnergy
from qsa.energies.second_order import SecondOrderDensity, SecondOrderEnergy
from qsa.energies.wells import DoubleWell, QuarticWell, Well, is_quartic, resolve_well

__all__ = [
    "Adhesion",
    "AdhesionKernel",
    "TwoPointInvariants",
    "adhesion_invariants",
    "CHAEnergy",
    "cha_factory",
    "AreaEnergy",
    "AreaPenalty",
    "Pressure",
    "Energy",
    "EnergySum",
    "Perimeter",
    "DoubleWell",
    "QuarticWell",
    "Well",
    "is_quartic",
    "resolve_well",
    "Faceting",
    "FunctionalizedCurvature",
    "CanhamHelfrich",
    "Density",
    "FirstOrderEnergy",
    "LocalEnergy",
    "SecondOrderDensity",
    "SecondOrderEnergy",
    "multipliers",
    "normal_velocity",
    "residual_floor",
    "residual_scale",
]
