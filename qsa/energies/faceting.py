"""The faceting energy: Allen-Cahn in curvature (e:Facet).

``Faceting(alpha, kstar) = int alpha^2/2 |nabla_s kappa|^2 + W(kappa) dsigma``; add
``Perimeter(beta, L_star)`` for the paper's full E_Fc. With ``mu = d_kappa E =
-alpha^2 Delta_s kappa + W'(kappa)`` and ``g d_g E = -alpha^2/2 |nabla_s kappa|^2 +
W(kappa)``, the normal velocity is e:Facet-NV (printed correctly in the paper). The
double wells ``W`` live in :mod:`qsa.energies.wells`.
"""

from __future__ import annotations

from dataclasses import dataclass

from qsa._checks import real_number
from qsa.energies.local import LocalEnergy, curvature_density, quadratic_gradient_density
from qsa.energies.wells import DoubleWell, Well, resolve_well

__all__ = ["DoubleWell", "Well", "Faceting"]


@dataclass(frozen=True)
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
        :class:`~qsa.energies.DoubleWell` ``(kstar)``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import DoubleWell, Faceting, Perimeter
    >>> E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
    >>> c = Curve.circle(1.0, Fourier(33))
    >>> exact = 2 * np.pi * DoubleWell(5.0).W(1.0) + 2.5 * (2 * np.pi - 6) ** 2
    >>> bool(abs(E.energy(c) - exact) < 1e-12)
    True
    >>> Faceting(0.1, 5.0).well
    DoubleWell(kstar=5.0)
    """

    alpha: float
    kstar: float
    well: object = None

    def __post_init__(self):
        object.__setattr__(self, "alpha", real_number(self.alpha, "alpha", positive=True))
        object.__setattr__(self, "kstar", real_number(self.kstar, "kstar", positive=True))
        well, _ = resolve_well(self.well, self.kstar, equal_depth=False)
        object.__setattr__(self, "well", well)

    def densities(self):
        """``alpha^2/2 |p|^2`` on edges and ``W(kappa)`` on nodes."""
        w = self.well
        return (quadratic_gradient_density(self.alpha**2),
                curvature_density(w.W, w.dW, w.d2W))

    def __repr__(self):
        return f"Faceting(alpha={self.alpha}, kstar={self.kstar})"
