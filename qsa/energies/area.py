"""Energies of the enclosed area: a pressure ``-p A`` and an area penalty ``k/2 (A - A*)^2``.

An energy ``E = F(A(U))`` of the enclosed area ``A = 1/2 int gamma . n dsigma``
(:meth:`qsa.curve.Curve.area`) has, in ``<f, h> = int f h dsigma``,

    nabla_I E = F'(A) nabla_I A,
    nabla_I^2 E = F'(A) nabla_I^2 A + F''(A) nabla_I A <nabla_I A, .>,

with the exact discrete derivatives of the area (:func:`qsa.constraints.area_gradient`,
:func:`qsa.constraints.area_hessian`). Its outward normal velocity is a constant:
``A`` moves by ``d/dt A = int V dsigma`` under a normal velocity ``V``, so
``V^n = -F'(A)``; the gradient flow dissipates ``dE/dt = -F'(A)^2 L``. The
normal velocity is returned in this exact form (``-[M-dagger nabla_I E]_1`` equals it
up to the discretization of ``M-dagger``).

* :class:`Pressure` ``(p)``: ``F = -p A``, ``V^n = p`` (``p > 0`` inflates).
* :class:`AreaPenalty` ``(k, A_star)``: ``F = k/2 (A - A*)^2``, ``V^n = -k (A - A*)``.

The Lévy ring, an inextensible elastic ring under pressure, is
``CanhamHelfrich(eps) + Pressure(p)`` with :class:`qsa.constraints.FixedLength`.
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass

import numpy as np

from qsa._checks import real_number
from qsa.energies.base import Energy
from qsa.measures import area_gradient, area_hessian

__all__ = ["AreaEnergy", "Pressure", "AreaPenalty"]


class AreaEnergy(Energy):
    """An energy ``F(A)`` of the enclosed area (see the module docstring).

    Subclasses define ``F``, ``dF`` and ``d2F`` of the area (floats).
    """

    @abstractmethod
    def F(self, A: float) -> float:
        """The energy as a function of the area."""

    @abstractmethod
    def dF(self, A: float) -> float:
        """``F'(A)``."""

    @abstractmethod
    def d2F(self, A: float) -> float:
        """``F''(A)``."""

    def energy(self, c):
        return float(self.F(c.area()))

    def gradient(self, c):
        return self.dF(c.area()) * area_gradient(c)

    def hessian(self, c):
        A = c.area()
        H = self.dF(A) * area_hessian(c)
        k2 = self.d2F(A)
        if k2 != 0.0:
            gA = area_gradient(c)
            H = H + k2 * np.outer(gA, gA * np.concatenate([c.dsigma, c.dsigma]))
        return H

    def normal_velocity(self, c):
        return np.full(c.N, -self.dF(c.area()))

    def velocity_scale(self, c) -> float:
        """``|V^n| = |F'(A)|``: the size of this energy's term in the normal velocity."""
        return abs(self.dF(c.area()))


@dataclass(frozen=True)
class Pressure(AreaEnergy):
    """The pressure energy ``-p A``: outward normal velocity ``V^n = p`` (``p > 0`` inflates).

    Parameters
    ----------
    p : float
        Pressure difference, inside minus outside (any sign).

    Notes
    -----
    ``nabla_I E = -p nabla_I A`` and ``nabla_I^2 E = -p nabla_I^2 A`` with the exact
    derivatives of the discrete area (dense Hessian, also on finite-difference grids).
    A circle of radius ``R`` is an equilibrium of ``CanhamHelfrich(eps) + Pressure(p)``
    with a fixed length for every ``p``; it buckles into mode ``n`` at Lévy's pressure
    ``p_n = -(n^2 - 1) eps / R^3``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(2.0, Fourier(17))
    >>> E = Pressure(0.5)
    >>> round(E.energy(c) / np.pi, 12), float(E.normal_velocity(c)[0])  # -p pi R^2, p
    (-2.0, 0.5)
    """

    p: float

    def __post_init__(self):
        object.__setattr__(self, "p", real_number(self.p, "p"))

    def F(self, A):
        return -self.p * A

    def dF(self, A):
        return -self.p

    def d2F(self, A):
        return 0.0


@dataclass(frozen=True)
class AreaPenalty(AreaEnergy):
    """The area penalty ``k/2 (A - A*)^2``: ``V^n = -k (A - A*)``.

    Parameters
    ----------
    k : float
        Penalty strength, ``>= 0``.
    A_star : float
        Preferred area, ``> 0``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> E = AreaPenalty(k=2.0, A_star=3.0)
    >>> bool(np.isclose(E.energy(c), (np.pi - 3.0) ** 2))
    True
    >>> bool(np.allclose(E.normal_velocity(c), -2.0 * (np.pi - 3.0)))  # shrinks
    True
    """

    k: float
    A_star: float

    def __post_init__(self):
        object.__setattr__(self, "k", real_number(self.k, "k", nonnegative=True))
        object.__setattr__(self, "A_star", real_number(self.A_star, "A_star", positive=True))

    def F(self, A):
        return 0.5 * self.k * (A - self.A_star) ** 2

    def dF(self, A):
        return self.k * (A - self.A_star)

    def d2F(self, A):
        return self.k
