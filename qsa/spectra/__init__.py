"""Spectra of the linearized flow: Hessians, linearizations, eigen-solvers, kernel checks.

``hessian(energy, curve)`` (e:cF-Hessian) and ``lagrange_hessian(energy, curve)``
(``L_Lambda = nabla^2 E - Lambda . nabla^2 C``, Conventions and errata, section 4);
``linearization(energy, curve, gauge)`` with gauges ``"comoving"``
(``-M M-dagger L_Lambda``), ``"paper"`` (e:FOE-Lin as printed), ``"normal"``
(``J``, dsigma-self-adjoint) and ``"scaled"``; ``spectrum(...)`` -> :class:`Spectrum`
(every eigenvalue with an error estimate; the slow ones from the factored operator,
:mod:`qsa.spectra.factored`, so that they are right at every resolution; kernel,
spurious-mode rejection) and ``kernel_report(...)`` -> :class:`KernelReport`.
"""

from qsa.spectra.eigen import (
    MESSAGES,
    NotEquilibriumWarning,
    UnresolvedEigenvalueWarning,
    certify,
    reject_spurious,
    second_resolution,
    small_cluster,
    spectrum,
)
from qsa.spectra.factored import EigenErrors, FactoredNormalOperator, ShiftInvert
from qsa.spectra.hessian import (
    DENSE_CONSTRAINT_LIMIT,
    LagrangeHessian,
    hessian,
    lagrange_hessian,
)
from qsa.spectra.kernel import kernel_report, operator_norm, rigid_normal_basis
from qsa.spectra.linearization import (
    GAUGES,
    linearization,
    normal_operator,
    scaled_operator,
    symmetric_form,
)
from qsa.spectra.result import KernelReport, Spectrum
from qsa.spectra.solvers import EigenSolution, certified_eigenpairs

__all__ = [
    "DENSE_CONSTRAINT_LIMIT",
    "MESSAGES",
    "EigenErrors",
    "EigenSolution",
    "FactoredNormalOperator",
    "ShiftInvert",
    "UnresolvedEigenvalueWarning",
    "certified_eigenpairs",
    "certify",
    "reject_spurious",
    "rigid_normal_basis",
    "GAUGES",
    "KernelReport",
    "LagrangeHessian",
    "NotEquilibriumWarning",
    "Spectrum",
    "hessian",
    "kernel_report",
    "lagrange_hessian",
    "linearization",
    "normal_operator",
    "operator_norm",
    "scaled_operator",
    "second_resolution",
    "small_cluster",
    "spectrum",
    "symmetric_form",
]
