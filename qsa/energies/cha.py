"""The CHA curve energy (e:CHA-GF): Canham-Helfrich + perimeter penalty + adhesion.

``E = eps/2 int kappa^2 dsigma + beta/2 (L - rho L0)^2 + E_A`` with the two-point energy
of kernel e:LJ (``A0, l_star, a``). :func:`cha_factory` gives the energy as a function of
one parameter (``rho``, ``A0``, ``l_star``, ``a`` or ``eps``), the form
:func:`qsa.continuation.continuation` follows branches in.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from qsa._checks import real_number
from qsa.energies.adhesion import Adhesion
from qsa.energies.base import Perimeter
from qsa.energies.helfrich import CanhamHelfrich

__all__ = ["CHAEnergy", "cha_factory"]

#: the parameters a CHA branch can be followed in
CONTINUATION_PARAMETERS = ("rho", "A0", "l_star", "a", "eps")


@dataclass(frozen=True)
class CHAEnergy:
    """Parameters of the CHA energy; :meth:`energy` builds it.

    Parameters
    ----------
    eps : float
        Bending modulus, ``> 0``.
    beta : float
        Perimeter penalty, ``> 0``.
    rho : float
        Target length ratio: ``L* = rho L0``.
    L0 : float
        Reference length (the flow's initial length).
    A0, l_star, a : float
        Adhesion kernel (e:LJ).
    method : {"neighbours", "dense"}
        Pair search of the adhesion term.
    """

    eps: float
    beta: float
    rho: float
    L0: float
    A0: float
    l_star: float
    a: float = 1.0
    method: str = "neighbours"

    def __post_init__(self):
        for name in ("eps", "beta", "rho", "L0"):
            real_number(getattr(self, name), name, positive=True)

    def energy(self):
        """The :class:`~qsa.energies.base.EnergySum` of the three terms."""
        return (CanhamHelfrich(self.eps) + Perimeter(self.beta, self.rho * self.L0)
                + Adhesion(self.A0, self.l_star, self.a, method=self.method))


def cha_factory(param: str, base: CHAEnergy):
    """``p -> Energy``: the CHA energy of ``base`` with ``param`` set to ``p``.

    Parameters
    ----------
    param : {"rho", "A0", "l_star", "a", "eps"}
    base : CHAEnergy
        The other parameters.

    Returns
    -------
    callable
        ``factory(p) -> EnergySum``, for :func:`qsa.continuation.continuation`.

    Raises
    ------
    ValueError
        If ``param`` is not one of the five.

    Examples
    --------
    >>> base = CHAEnergy(eps=0.1, beta=1.0, rho=1.5, L0=4.0, A0=10.0, l_star=0.3)
    >>> f = cha_factory("A0", base)
    >>> f(12.0).terms()[-1]
    Adhesion(A0=12.0, l_star=0.3, a=1.0)
    """
    if param not in CONTINUATION_PARAMETERS:
        raise ValueError(f"param must be one of {', '.join(CONTINUATION_PARAMETERS)}, "
                         f"got {param!r}")

    def factory(p):
        return replace(base, **{param: float(p)}).energy()

    return factory
