"""The functionalized curvature energy: a second-order model built on the faceting well (e:LIE).

``FunctionalizedCurvature(alpha, eta, kstar)`` is ::

    E_FC = int 1/2 Z^2 - eta (alpha^2/2 |nabla_s kappa|^2 + W(kappa)) dsigma,
    Z = alpha^2 Delta_s kappa - W'(kappa),

the square of the faceting "chemical potential" (``-Z`` is the first variation of
the faceting energy e:Facet in kappa) minus ``eta`` times the faceting energy — the
functionalized form of a Cahn-Hilliard energy, written for the curvature. It
needs the second-order class: ``F`` depends on ``Delta_s kappa``.

Gradient and normal velocity
----------------------------
With ``F_q = alpha^2 Z``, ``F_p = -eta alpha^2 nabla_s kappa``, ``F_k = -W'' Z - eta W'``
in e:first_var, ::

    mu := d_kappa E = (alpha^2 Delta_s - W''(kappa) + eta) Z,
    g d_g E = Z^2/2 - alpha^2 Z Delta_s kappa + alpha^2 nabla_s Z nabla_s kappa
              + eta (alpha^2/2 |nabla_s kappa|^2 - W(kappa)),

and ``V^n = -G mu - kappa g d_g E`` (e:L2grad).

Faceting pulses are equilibria
------------------------------
A faceting N-pulse with ``nu1 = 0`` (:func:`qsa.equilibria.npulse`) solves ``Z = 0``
with the first integral ``alpha^2/2 |nabla_s kappa|^2 - W = nu2``. There ``mu = 0`` and
``g d_g E = eta nu2``, so with a perimeter penalty
``V^n = -kappa (eta nu2 + beta (L - L*)) = 0`` for ``beta (L - L*) = -eta nu2``:
the pulse is an equilibrium of ``E_FC + Perimeter(beta, L* = L + eta nu2 / beta)``
(Lagrange multipliers 0). Other perimeters move the equilibrium off ``Z = 0``.

The circle
----------
At ``kappa0 = 1/R`` (second-order module docstring, "The circle") the tension is
``kappa0 F_k - F = kappa0 W'(W'' - eta) - W'^2/2 + eta W``: zero at ``kappa0 = kstar``
(``W = W' = 0``), so the circle of radius ``1/kstar`` is a critical circle of E_FC for
every ``alpha`` and ``eta``. With ``F_qq = alpha^4``, ``F_pp = -eta alpha^2``,
``F_qk = -alpha^2 W''`` and ``F_kk = W''^2 + W' W''' - eta W''`` the spectrum of ``J``
factors into the faceting symbol ``Lambda_k = alpha^2 k^2 / R^2 + W''(kappa0)``: ::

    lambda_k = -((k^2 - 1)^2 / R^4) (Lambda_k (Lambda_k - eta) + W'(kappa0) W'''(kappa0))
               - delta_k0 2 pi beta / R,

(``beta`` of an added perimeter penalty; ``k = 1`` the translations, ``k >= 2`` double).
At the critical circle ``W' = 0``: mode ``k`` grows iff ``0 < Lambda_k < eta``, the
band of the functionalized energies' pearling-type instability.

Discretization
--------------
``Z^2/2`` is a :class:`~qsa.energies.second_order.SecondOrderDensity` at the nodes;
``-eta alpha^2/2 |nabla_s kappa|^2`` (edges) and ``-eta W`` (nodes) are the faceting
densities, so ``E_FC = 1/2 int Z^2 dsigma - eta Faceting`` holds discretely too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsa._checks import real_number
from qsa.energies.local import LocalEnergy, curvature_density, quadratic_gradient_density
from qsa.energies.second_order import SecondOrderDensity, _radius, circle_eigenvalues
from qsa.energies.wells import resolve_well

__all__ = ["FunctionalizedCurvature"]


def _fc_well(well, kstar):
    well, _ = resolve_well(well, kstar, equal_depth=False)
    if not callable(getattr(well, "d3W", None)):
        raise ValueError("well must provide a callable d3W as well as W, dW and d2W (the "
                         "Hessian of FunctionalizedCurvature needs W'''); d3W is missing")
    return well


@dataclass(frozen=True)
class _SquaredPotential:
    """``F(q, p, k) = (alpha^2 q - W'(k))^2 / 2`` and its partials."""

    a2: float
    well: object

    def F(self, q, p, k):
        return 0.5 * (self.a2 * q - self.well.dW(k)) ** 2

    def dF(self, q, p, k):
        Z = self.a2 * q - self.well.dW(k)
        return self.a2 * Z, np.zeros_like(Z), -self.well.d2W(k) * Z

    def d2F(self, q, p, k):
        Z = self.a2 * q - self.well.dW(k)
        W2 = self.well.d2W(k)
        zero = np.zeros_like(Z)
        return (np.full_like(Z, self.a2**2), zero, -self.a2 * W2, zero, zero,
                W2**2 - self.well.d3W(k) * Z)


@dataclass(frozen=True)
class FunctionalizedCurvature(LocalEnergy):
    """``int (alpha^2 Delta_s kappa - W')^2/2 - eta (alpha^2/2 |nabla_s kappa|^2 + W) dsigma``.

    See the module docstring for its gradient, its equilibria (faceting pulses) and
    the closed-form circle spectrum.

    Parameters
    ----------
    alpha : float
        Length scale of the fronts, ``> 0``.
    eta : float
        Functionalization parameter (any real; ``eta > 0`` rewards faceting structure).
    kstar : float
        Curvature of the second well, ``> 0`` (used by the default well).
    well : object, optional
        Vectorised ``W``, ``dW``, ``d2W`` and ``d3W``; default
        :class:`~qsa.energies.DoubleWell` ``(kstar)``.

    Raises
    ------
    ValueError
        ``alpha <= 0``, ``kstar <= 0``, a non-finite parameter, or a well without
        ``W, dW, d2W, d3W``.

    Examples
    --------
    The circle of radius ``1/kstar`` is critical; its mode ``k = 2`` grows when
    ``0 < alpha^2 k^2 kstar^2 + kstar^2/2 < eta``:

    >>> from qsa import Curve, Fourier
    >>> E = FunctionalizedCurvature(alpha=0.1, eta=8.8, kstar=4.0)
    >>> c = Curve.circle(0.25, Fourier(33))
    >>> float(E.circle_tension(0.25)), bool(abs(E.normal_velocity(c)).max() < 1e-6)
    (0.0, True)
    >>> lam = E.circle_eigenvalues(0.25, 3)
    >>> bool(lam[2] > 0 and lam[3] < 0)
    True
    """

    alpha: float
    eta: float
    kstar: float
    well: object = None

    def __post_init__(self):
        object.__setattr__(self, "alpha", real_number(self.alpha, "alpha", positive=True))
        object.__setattr__(self, "eta", real_number(self.eta, "eta"))
        object.__setattr__(self, "kstar", real_number(self.kstar, "kstar", positive=True))
        object.__setattr__(self, "well", _fc_well(self.well, self.kstar))

    def densities(self):
        """``Z^2/2`` at the nodes (second order), ``-eta alpha^2/2 |p|^2`` on edges, ``-eta W``."""
        w, a2, eta = self.well, self.alpha**2, self.eta
        sq = _SquaredPotential(a2, w)
        out = (SecondOrderDensity(sq.F, sq.dF, sq.d2F, "node", name="FunctionalizedCurvature"),)
        if eta == 0.0:
            return out
        return out + (quadratic_gradient_density(-eta * a2),
                      curvature_density(lambda k: -eta * w.W(k), lambda k: -eta * w.dW(k),
                                        lambda k: -eta * w.d2W(k)))

    def _well_at(self, R):
        k0 = np.asarray(1.0 / _radius(R))
        w = self.well
        return (float(w.W(k0)), float(w.dW(k0)), float(w.d2W(k0)), float(w.d3W(k0)))

    def circle_tension(self, R) -> float:
        """``kappa0 W'(W'' - eta) - W'^2/2 + eta W`` at ``kappa0 = 1/R``.

        The circle is an equilibrium of ``self + Perimeter(beta, L*)`` iff
        ``beta (2 pi R - L*)`` equals it, and a critical circle of ``self`` iff it is 0.

        Parameters
        ----------
        R : float

        Returns
        -------
        float

        Examples
        --------
        >>> E = FunctionalizedCurvature(alpha=0.1, eta=1.0, kstar=5.0)
        >>> E.circle_tension(0.2), round(E.circle_tension(1.0), 10)  # 6 (0.5 - 1) - 18 + 4
        (0.0, -17.0)
        """
        W, W1, W2, _ = self._well_at(R)
        k0 = 1.0 / R
        return k0 * W1 * (W2 - self.eta) - 0.5 * W1**2 + self.eta * W

    def circle_eigenvalues(self, R, kmax, beta=0.0) -> np.ndarray:
        """``lambda_k``, ``k = 0..kmax``, of ``J`` at the circle of radius ``R`` (module docstring).

        Valid where the circle is an equilibrium (see :meth:`circle_tension`).

        Parameters
        ----------
        R : float
        kmax : int
        beta : float
            Strength of an added ``Perimeter(beta, L*)``.

        Returns
        -------
        ndarray, shape (kmax + 1,)
            ``k >= 2`` double, ``lambda_1 = 0``.

        Examples
        --------
        >>> import numpy as np
        >>> E = FunctionalizedCurvature(alpha=0.1, eta=0.0, kstar=5.0)
        >>> lam = E.circle_eigenvalues(0.2, 2)  # eta = 0: -((k^2-1)^2/R^4) Lambda_k^2
        >>> bool(np.isclose(lam[2], -9 * 5.0**4 * (0.01 * 4 * 25 + 12.5) ** 2))
        True
        """
        _, W1, W2, W3 = self._well_at(R)
        a2, eta = self.alpha**2, self.eta
        return circle_eigenvalues(R, kmax, F_qq=a2**2, F_pp=-eta * a2, F_qk=-a2 * W2,
                                  F_kk=W2**2 + W1 * W3 - eta * W2, beta=beta)

    def __repr__(self):
        return f"FunctionalizedCurvature(alpha={self.alpha}, eta={self.eta}, kstar={self.kstar})"
