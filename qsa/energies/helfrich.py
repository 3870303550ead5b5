"""Canham-Helfrich bending energy ``int eps/2 kappa^2 dsigma`` (e:CHA-Energy, curvature part).

With ``Perimeter(beta, L_star)`` its normal velocity is
``V^n = eps (Delta_s kappa + kappa^3/2) - beta (L - L*) kappa`` (e:NV-CH with the
length penalty in place of the constant surface tension).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsa._checks import real_number
from qsa.energies.local import LocalEnergy, curvature_density

__all__ = ["CanhamHelfrich"]


@dataclass(frozen=True)
class CanhamHelfrich(LocalEnergy):
    """Canham-Helfrich energy ``eps/2 int kappa^2 dsigma``.

    Parameters
    ----------
    eps : float
        Bending rigidity, ``>= 0``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> E = CanhamHelfrich(eps=2.0)
    >>> bool(abs(E.energy(Curve.circle(1.0, Fourier(17))) - 2 * np.pi) < 1e-12)  # eps pi / R
    True
    """

    eps: float

    def __post_init__(self):
        object.__setattr__(self, "eps", real_number(self.eps, "eps", nonnegative=True))

    def densities(self):
        """``eps/2 kappa^2`` on nodes."""
        e = self.eps
        return (curvature_density(lambda k: 0.5 * e * k**2, lambda k: e * k,
                                  lambda k: np.full_like(np.asarray(k, dtype=float), e)),)

    def __repr__(self):
        return f"CanhamHelfrich(eps={self.eps})"
