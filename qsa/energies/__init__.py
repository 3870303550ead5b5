"""Energies of closed curves: protocol, local first- and second-order energies, the models.

Each energy provides ``energy``, ``gradient`` (nabla_I E in <f,h> = int f h dsigma),
``normal_velocity`` (outward V^n) and ``hessian`` (nabla_I^2 E); energies add with ``+``.
"""

from qsa.energies.adhesion import Adhesion, AdhesionKernel
from qsa.energies.base import Energy, EnergySum, Perimeter
from qsa.energies.faceting import DoubleWell, Faceting, Well
from qsa.energies.functionalized import FunctionalizedCurvature
from qsa.energies.helfrich import CanhamHelfrich
from qsa.energies.local import Density, FirstOrderEnergy, LocalEnergy
from qsa.energies.second_order import SecondOrderDensity, SecondOrderEnergy

__all__ = [
    "Adhesion",
    "AdhesionKernel",
    "Energy",
    "EnergySum",
    "Perimeter",
    "DoubleWell",
    "Well",
    "Faceting",
    "FunctionalizedCurvature",
    "CanhamHelfrich",
    "Density",
    "FirstOrderEnergy",
    "LocalEnergy",
    "SecondOrderDensity",
    "SecondOrderEnergy",
]
