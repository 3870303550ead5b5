"""Length and area constraints, and area energies, in the polishing system of :func:`polish`.

With constraints ``c_i(U) = c_i*`` (:mod:`qsa.constraints`) the equilibrium equations of
:mod:`qsa.equilibria.newton` gain one multiplier ``mu_i`` and one equation each::

    V^n(kappa, L) + sum_j a_j phi_j + sum_i mu_i n_i = 0      (N)
    C(kappa, L) = 0,  phase                                   (3 + 1)
    c_i(kappa, L) - c_i* = 0                                  (m)

with ``n_L = kappa``, ``n_A = 1`` the normal variations (``d/dt c_i = <n_i, V>``), so
that a solution satisfies ``nabla_I E = Lambda . Psi + sum_i mu_i nabla_I c_i``. In the
scaled-arc-length unknowns (``g = L``) the exact derivatives are

* ``d(mu_L kappa)/dkappa = mu_L I``, ``d/dmu_i = n_i`` (columns);
* rows ``dc_i/dkappa`` and ``dc_i/dL = sum_j dc_i/dg_j`` from the exact Euclidean
  gradient of the discrete ``c_i`` (``L``: ``(0, 1)``; ``A``:
  :func:`qsa.constraints.area_gradient_euclidean`).

Area energies ``F(A)`` (:class:`qsa.energies.AreaEnergy`: ``Pressure``, ``AreaPenalty``)
have the exact constant normal velocity ``-F'(A)``; their rows of the Jacobian are
``dV/dkappa = -F''(A) 1 (dA/dkappa)^T`` (rank one) and ``dV/dL = -F''(A) dA/dL``, not
the generic formula of their (non-local) Hessian, which the rest of the energy uses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsa.constraints import constraint_normals
from qsa.curve import Curve
from qsa.energies import AreaEnergy, EnergySum
from qsa.measures import area_gradient_euclidean

__all__ = ["split_area_energies", "ConstraintJacobian", "constraint_jacobian",
           "area_energy_jacobian"]


def split_area_energies(energy):
    """``(rest, area_terms)``: the energy without its area terms (or None), and those terms.

    Parameters
    ----------
    energy : Energy

    Returns
    -------
    rest : Energy or None
    area_terms : tuple of AreaEnergy

    Examples
    --------
    >>> from qsa.energies import CanhamHelfrich, Pressure
    >>> rest, area = split_area_energies(CanhamHelfrich(0.1) + Pressure(2.0))
    >>> rest, area
    (CanhamHelfrich(eps=0.1), (Pressure(p=2.0),))
    """
    terms = energy.terms()
    area = tuple(t for t in terms if isinstance(t, AreaEnergy))
    rest = tuple(t for t in terms if not isinstance(t, AreaEnergy))
    if not rest:
        return None, area
    return (rest[0] if len(rest) == 1 else EnergySum(rest)), area


def _dU_to_kappa_L(grad_euclidean, N):
    """``(d/dkappa, d/dL)`` of a function of ``U`` at ``g = L`` constant."""
    return grad_euclidean[:N], float(np.sum(grad_euclidean[N:]))


def area_energy_jacobian(area_terms, c: Curve):
    """Derivatives of ``sum -F'(A)`` (the area energies' ``V^n``) in ``(kappa, L)``.

    Parameters
    ----------
    area_terms : sequence of AreaEnergy
    c : Curve
        With constant ``g = L``.

    Returns
    -------
    low : tuple (P, Q) or None
        ``dV/dkappa = P Q^T`` with ``P = -sum F'' 1`` and ``Q = dA/dkappa``, shape (N, 1)
        each (None when every ``F'' = 0``, e.g. a pressure).
    dL : float
        ``dV/dL`` (the same at every node).
    """
    k2 = sum(t.d2F(c.area()) for t in area_terms) if area_terms else 0.0
    if k2 == 0.0:
        return None, 0.0
    dk, dL = _dU_to_kappa_L(area_gradient_euclidean(c), c.N)
    return (np.full((c.N, 1), -k2), dk[:, None]), -k2 * dL


@dataclass(frozen=True, eq=False)
class ConstraintJacobian:
    """The constraint blocks of the polishing Jacobian (see the module docstring).

    Attributes
    ----------
    diagonal : ndarray, shape (N,)
        Added to ``dV/dkappa``: ``mu_L`` for a length constraint.
    columns : ndarray, shape (N, m)
        ``dV/dmu_i = n_i``.
    rows : ndarray, shape (m, N)
        ``dc_i/dkappa``.
    dL : ndarray, shape (m,)
        ``dc_i/dL``.

    Parameters
    ----------
    The attributes above.
    """

    diagonal: np.ndarray
    columns: np.ndarray
    rows: np.ndarray
    dL: np.ndarray


def constraint_jacobian(constraints, c: Curve, mu) -> ConstraintJacobian:
    """The exact constraint blocks at a constant-``g`` curve and multipliers ``mu``.

    Parameters
    ----------
    constraints : sequence of Constraint
    c : Curve
        With constant ``g = L``.
    mu : ndarray, shape (m,)

    Returns
    -------
    ConstraintJacobian
    """
    N = c.N
    diagonal = np.zeros(N)
    rows, dL = [], []
    for con, m in zip(constraints, mu, strict=True):
        if con.symbol == "L":
            diagonal += m  # d(mu kappa)/dkappa
        dk, dl = _dU_to_kappa_L(con.euclidean_gradient(c), N)
        rows.append(dk)
        dL.append(dl)
    return ConstraintJacobian(diagonal, constraint_normals(constraints, c).T,
                              np.array(rows).reshape(-1, N), np.array(dL, dtype=float))
