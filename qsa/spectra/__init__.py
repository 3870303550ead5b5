"""Spectra of the linearized flow: Hessians, linearizations, eigen-solvers, kernel checks.

``hessian(energy, curve)`` (e:cF-Hessian) and ``lagrange_hessian(energy, curve)``
(``L_Lambda = nabla^2 E - Lambda . nabla^2 C``, MATH.md section 4);
``linearization(energy, curve, gauge)`` with gauges ``"comoving"``
(``-M M-dagger L_Lambda``), ``"paper"`` (e:FOE-Lin as printed), ``"normal"``
(``J``, dsigma-self-adjoint) and ``"scaled"``; ``spectrum(...)`` -> :class:`Spectrum`
(dense or shift-invert, kernel tolerance, spurious-mode rejection) and
``kernel_report(...)`` -> :class:`KernelReport`.
"""

from qsa.spectra.eigen import (
    KernelReport,
    NotEquilibriumWarning,
    Spectrum,
    kernel_report,
    operator_norm,
    second_resolution,
    small_cluster,
    spectrum,
)
from qsa.spectra.hessian import (
    DENSE_CONSTRAINT_LIMIT,
    LagrangeHessian,
    hessian,
    lagrange_hessian,
)
from qsa.spectra.linearization import (
    GAUGES,
    linearization,
    normal_operator,
    scaled_operator,
    symmetric_form,
)

__all__ = [
    "DENSE_CONSTRAINT_LIMIT",
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
