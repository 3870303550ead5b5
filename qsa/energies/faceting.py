"""The faceting energy: Allen-Cahn in curvature (e:Facet), and double-well potentials.

``Faceting(alpha, kstar) = int alpha^2/2 |nabla_s kappa|^2 + W(kappa) dsigma``; add
``Perimeter(beta, L_star)`` for the paper's full E_Fc. With ``mu = d_kappa E =
-alpha^2 Delta_s kappa + W'(kappa)`` and ``g d_g E = -alpha^2/2 |nabla_s kappa|^2 +
W(kappa)``, the normal velocity is e:Facet-NV (printed correctly in the paper).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsa.energies.base import _check_param
from qsa.energies.local import LocalEnergy, curvature_density, quadratic_gradient_density

__all__ = ["DoubleWell", "Well", "Faceting"]


@dataclass(frozen=True)
class DoubleWell:
    """``W(kappa) = kappa^2 (kappa - kstar)^2 / 4`` with wells at 0 and kstar.

    ``W''(0) = W''(kstar) = kstar^2 / 2`` (MATH.md section 1).

    Parameters
    ----------
    kstar : float
        The second well, ``> 0``.

    Examples
    --------
    >>> w = DoubleWell(5.0)
    >>> float(w.W(5.0)), float(w.d2W(0.0))
    (0.0, 12.5)
    >>> abs(float(w.dW(2.5))), float(w.W(2.5))  # the barrier at kstar / 2
    (0.0, 9.765625)
    """

    kstar: float

    def __post_init__(self):
        object.__setattr__(self, "kstar", _check_param(self.kstar, "kstar", positive=True))

    def W(self, k):
        """``W(k) = k^2 (k - kstar)^2 / 4``, shape like ``k``."""
        k = np.asarray(k)
        return 0.25 * k**2 * (k - self.kstar) ** 2

    def dW(self, k):
        """``W'(k) = k (k - kstar)(2k - kstar) / 2``, shape like ``k``."""
        k = np.asarray(k)
        return 0.5 * k * (k - self.kstar) * (2 * k - self.kstar)

    def d2W(self, k):
        """``W''(k) = (6k^2 - 6k kstar + kstar^2) / 2``, shape like ``k``."""
        k = np.asarray(k)
        return 0.5 * (6 * k**2 - 6 * k * self.kstar + self.kstar**2)

    def d3W(self, k):
        """``W'''(k) = 3 (2k - kstar)``, shape like ``k``."""
        k = np.asarray(k)
        return 3.0 * (2 * k - self.kstar)


@dataclass(frozen=True)
class Well:
    """A user double well from callables ``W``, ``dW``, ``d2W`` (vectorised).

    Parameters
    ----------
    W, dW, d2W : callable
    kstar : float, optional
        The non-zero well (for constructions that need it).
    d3W : callable, optional
        ``W'''``, for energies whose Hessian needs it
        (:class:`~qsa.energies.FunctionalizedCurvature`).

    Examples
    --------
    >>> from qsa.energies import Faceting
    >>> w = Well(lambda k: k**2 * (k - 2.0)**2, lambda k: 0 * k, lambda k: 0 * k, kstar=2.0)
    >>> float(w.W(1.0)), Faceting(0.1, 2.0, well=w).well is w
    (1.0, True)
    """

    W: object
    dW: object
    d2W: object
    kstar: float | None = None
    d3W: object = None

    def __post_init__(self):
        for name in ("W", "dW", "d2W"):
            if not callable(getattr(self, name)):
                raise ValueError(f"well.{name} must be callable")
        if self.d3W is not None and not callable(self.d3W):
            raise ValueError("well.d3W must be callable (or None)")


def _as_well(well, kstar):
    if well is None:
        return DoubleWell(kstar)
    for name in ("W", "dW", "d2W"):
        if not callable(getattr(well, name, None)):
            raise ValueError(f"well must provide callables W, dW and d2W; {name} is missing")
    return well


class Faceting(LocalEnergy):
    """Faceting energy ``int alpha^2/2 |nabla_s kappa|^2 + W(kappa) dsigma`` (e:Facet).

    Parameters
    ----------
    alpha : float
        Surface-diffusion length, ``> 0``.
    kstar : float
        Curvature of the second well, ``> 0`` (used by the default well).
    well : object, optional
        Any object with vectorised ``W``, ``dW``, ``d2W``; default
        :class:`DoubleWell` ``(kstar)``.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
    >>> c = Curve.circle(1.0, Fourier(33))
    >>> exact = 2 * np.pi * DoubleWell(5.0).W(1.0) + 2.5 * (2 * np.pi - 6) ** 2
    >>> bool(abs(E.energy(c) - exact) < 1e-12)
    True
    """

    def __init__(self, alpha, kstar, well=None):
        self.alpha = _check_param(alpha, "alpha", positive=True)
        self.kstar = _check_param(kstar, "kstar", positive=True)
        self.well = _as_well(well, self.kstar)

    def densities(self):
        """``alpha^2/2 |p|^2`` on edges and ``W(kappa)`` on nodes."""
        w = self.well
        return (quadratic_gradient_density(self.alpha**2),
                curvature_density(w.W, w.dW, w.d2W))

    def __repr__(self):
        return f"Faceting(alpha={self.alpha}, kstar={self.kstar})"
