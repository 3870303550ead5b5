"""Operators of an energy on the closed manifold: ``V^n``, the multipliers ``Lambda``, a scale.

A closed curve satisfies ``C(U) = 0`` (e:C1, e:C2); ``Psi_j = nabla_I C_j``
(:func:`qsa.geometry.constraint_gradients`) span ``ker M-dagger``. For an energy
``E`` these are properties of ``(E, C)`` alone, used by the Newton solver, the
spectra and the continuation alike:

``normal_velocity(energy, curve)``
    ``V^n = -[M-dagger nabla_I E]_1`` (e:L2grad); ``V^n = 0`` is the equilibrium
    equation (e:Abs-CP), since ``M-dagger`` kills exactly ``span Psi``.
``multipliers(energy, curve)``
    ``Lambda`` of ``nabla_I E = Lambda . Psi`` (e:Abs-CP): the projection of
    ``nabla_I E`` on ``span Psi`` in ``<f, h> = int f h dsigma``.
``residual_scale(energy, curve)``
    The largest single term of ``V^n``; ``max|V^n| / residual_scale`` is the
    relative residual every solver reports.
"""

from __future__ import annotations

import numpy as np

from qsa.curve import Curve
from qsa.geometry import apply_laplace_s, constraint_gradients

__all__ = ["normal_velocity", "multipliers", "residual_scale"]


def normal_velocity(energy, curve: Curve) -> np.ndarray:
    """``V^n = -[M-dagger nabla_I E]_1`` of ``energy`` at ``curve`` (e:L2grad), shape (N,).

    Equal to ``energy.normal_velocity(curve)``; for a sum of energies that is the
    sum's fast path (one Laplace-Beltrami application for all the summands that
    use the generic formula, see :class:`~qsa.energies.EnergySum`).

    Parameters
    ----------
    energy : Energy
    curve : Curve

    Returns
    -------
    ndarray, shape (N,)
        Outward normal velocity; ``V^n = 0`` at a constrained critical point.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import CanhamHelfrich
    >>> c = Curve.circle(2.0, Fourier(17))
    >>> bool(np.allclose(normal_velocity(CanhamHelfrich(1.0), c), 1 / 16))  # eps kappa^3 / 2
    True
    """
    return energy.normal_velocity(curve)


def residual_scale(energy, curve: Curve) -> float:
    """Largest single term of ``V^n = Delta_s mu + kappa^2 mu - kappa xi``, split by density.

    ``mu = d_kappa E`` and ``xi = g d_g E`` are taken for every part of
    ``energy.gradient_parts(curve)`` (each density of a local energy, each other
    summand whole). For ``Faceting + Perimeter`` the terms are ``alpha^2 Delta_s^2
    kappa``, ``Delta_s W'(kappa)``, ``kappa^2 mu`` and ``kappa g d_g E``.
    ``max|V^n| / residual_scale`` is the relative residual.

    Parameters
    ----------
    energy : Energy
    curve : Curve

    Returns
    -------
    float
        Positive (1.0 if every term vanishes).

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting
    >>> c = Curve.circle(1.0, Fourier(33))
    >>> round(residual_scale(Faceting(0.1, 5.0), c), 10)  # kappa^2 mu = W'(1) = 6
    6.0
    """
    N = curve.N
    scale = 0.0
    for grad in energy.gradient_parts(curve):
        mu, xi = grad[:N], curve.g * grad[N:]
        for t in (apply_laplace_s(curve, mu), curve.kappa**2 * mu, curve.kappa * xi):
            scale = max(scale, float(np.max(np.abs(t))))
    return scale if scale > 0 else 1.0


def multipliers(energy, curve: Curve, gradient=None) -> np.ndarray:
    """Lagrange multipliers ``Lambda`` of ``nabla_I E = Lambda . Psi`` (e:Abs-CP), shape (3,).

    The least-squares projection of ``nabla_I E`` onto ``span Psi`` in
    ``<f, h> = int f h dsigma``: ``G Lambda = b`` with the Gram matrix
    ``G_ij = <Psi_i, Psi_j>`` and ``b_i = <Psi_i, nabla_I E>``, solved by least
    squares (``rcond = 1e-12``) so that a degenerate Gram matrix is handled.

    Parameters
    ----------
    energy : Energy
    curve : Curve
    gradient : ndarray, shape (2N,), optional
        ``nabla_I E`` in ``<f, h> = int f h dsigma`` if already computed.

    Returns
    -------
    ndarray, shape (3,)
        ``(Lambda_1, Lambda_2, Lambda_3)``; on an equilibrium ``nu1 = -Lambda_3``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> c = Curve.circle(1.0, Fourier(33))  # an equilibrium: beta (L - L*) = W'(1) - W(1) = 2
    >>> E = Faceting(0.1, 5.0) + Perimeter(5.0, 2 * np.pi - 0.4)
    >>> (np.round(multipliers(E, c), 8) + 0.0).tolist()  # (0, 0, W'(1/R))
    [0.0, 0.0, 6.0]
    """
    Psi = constraint_gradients(curve)
    grad = energy.gradient(curve) if gradient is None else gradient
    w = np.concatenate([curve.dsigma, curve.dsigma])
    G = (Psi * w) @ Psi.T
    b = (Psi * w) @ grad
    return np.linalg.lstsq(G, b, rcond=1e-12)[0]
