"""Length- and area-preserving curve flows: Lagrange multipliers in the DAE.

A constraint ``c = c*`` (:class:`qsa.constraints.FixedLength`, :class:`~qsa.constraints.FixedArea`)
adds one unknown, its multiplier ``mu_c``, and one algebraic row to the DAE of
:mod:`qsa.flows.dae`; the normal velocity of the energy is corrected by
``mu_c n_c`` with the normal variation ``n_c`` (``d/dt c = int n_c V dsigma``):

    V - V_E(y) - sum_c mu_c n_c = 0        (the model's velocity rows),
    c(y) - c* = 0                          (one row per constraint),

``n_L = kappa``, ``n_A = 1``. ``c`` is the discrete quantity of the scheme: the length
unknown ``L`` (the equal-chord rows make it the polygon length) and the polygon
area ``A = 1/2 sum_j (x_j y_{j+1} - x_{j+1} y_j)``. The multipliers make the system
index 2 (``mu`` appears in no constraint row; it is fixed by the motion the rows
allow); backward Euler and BDF2 solve it with the constraint exact at every step,
and the local error control measures the positions only.

The constrained velocity is the ``<.,.>``-orthogonal projection of ``V_E`` onto
``{V : int n_c V dsigma = 0}`` up to the time discretization, so the energy still
decreases, ``dE/dt = -int V_E V dsigma = -int V^2 dsigma``. This is the flow whose
linearization at an equilibrium is the constrained operator of
:func:`qsa.spectra.spectrum` with ``constraints=...``.
"""

from __future__ import annotations

import numpy as np

from qsa.constraints import check_constraints

__all__ = ["ConstraintRows", "polygon_area"]


def polygon_area(x, y) -> float:
    """Signed area ``1/2 sum_j (x_j y_{j+1} - x_{j+1} y_j)`` of a closed polygon (> 0 CCW).

    Parameters
    ----------
    x, y : ndarray, shape (N,)

    Returns
    -------
    float

    Examples
    --------
    >>> polygon_area([0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 1.0, 1.0])
    1.0
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    return float(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


class ConstraintRows:
    """The multiplier unknowns and constraint rows of a curve DAE (module docstring).

    Parameters
    ----------
    constraints : sequence of Constraint (or their ``params()`` dicts)
    N : int
        Number of nodes.
    first : int
        Index of the first multiplier unknown and of the first constraint row.

    Attributes
    ----------
    constraints : tuple of Constraint
        Bound once :meth:`bind` has run.
    m : int
    index : ndarray of int, shape (m,)
        The multipliers' positions in ``y`` (and the constraint rows in ``F``).
    """

    def __init__(self, constraints, N, first):
        self.constraints = check_constraints(constraints)
        self.m = len(self.constraints)
        self.N = N
        self.index = first + np.arange(self.m)

    @staticmethod
    def value(con, X, Y, L) -> float:
        """The discrete constrained quantity: ``L``, or the polygon area."""
        return float(L) if con.symbol == "L" else polygon_area(X, Y)

    def bind(self, X, Y, L, rtol=1e-9):
        """Set ``None`` targets to the initial values; refuse targets the data does not meet.

        Raises
        ------
        ValueError
            A given target differing from the initial curve's value (the flow conserves
            the initial value).
        """
        bound = []
        for con in self.constraints:
            v = self.value(con, X, Y, L)
            if con.target is None:
                con = type(con)(v)
            elif abs(v - con.target) > rtol * abs(con.target):
                raise ValueError(
                    f"constraints: {type(con).__name__}({con.target:g}) differs from the "
                    f"initial curve's {con.symbol} = {v:.10g}; a constrained flow keeps the "
                    f"initial value: pass {type(con).__name__}() or rescale the initial curve")
            bound.append(con)
        self.constraints = tuple(bound)

    def params(self) -> list:
        """JSON-serialisable description of the bound constraints."""
        return [con.params() for con in self.constraints]

    def normals(self, kappa) -> np.ndarray:
        """``n_c`` as rows, shape (m, N): ``kappa`` (length), ``1`` (area)."""
        return np.array([kappa if con.symbol == "L" else np.ones(self.N)
                         for con in self.constraints]).reshape(self.m, self.N)

    def multipliers(self, y) -> np.ndarray:
        """The multiplier unknowns of state ``y``, shape (m,)."""
        return np.asarray(y, dtype=float)[self.index]

    def initial_multipliers(self, kappa, V) -> np.ndarray:
        """``mu`` with ``V + mu . n`` orthogonal to every ``n_c`` (uniform weights ``L/N``)."""
        n = self.normals(kappa)
        if self.m == 0:
            return np.zeros(0)
        return -np.linalg.lstsq(n @ n.T, n @ V, rcond=1e-12)[0]

    def velocity_term(self, y, kappa) -> np.ndarray:
        """``sum_c mu_c n_c``, shape (N,)."""
        if self.m == 0:
            return np.zeros(self.N)
        return self.multipliers(y) @ self.normals(kappa)

    def defects(self, X, Y, L) -> np.ndarray:
        """``c(y) - c*`` for every constraint, shape (m,)."""
        return np.array([self.value(con, X, Y, L) - con.target for con in self.constraints])

    def add_jacobian(self, T, y, rows_V, iX, iY, iK, iL):
        """Add the exact derivatives of the velocity and constraint rows to triplets ``T``.

        ``rows_V`` are the rows ``V - V_E - mu . n`` (coefficient ``-n_c`` on ``mu_c``,
        ``-mu_L`` on ``kappa``); the constraint rows get ``dL = 1`` or the polygon-area
        gradient ``dA/dx_j = (y_{j+1} - y_{j-1}) / 2``, ``dA/dy_j = (x_{j-1} - x_{j+1}) / 2``.
        """
        N = self.N
        y = np.asarray(y, dtype=float)
        X, Y, kappa = y[iX], y[iY], y[iK]
        mu = self.multipliers(y)
        n = self.normals(kappa)
        for i, con in enumerate(self.constraints):
            T.add(rows_V, self.index[i], -n[i])
            r = self.index[i]
            if con.symbol == "L":
                T.add(rows_V, iK, -mu[i])
                T.add(np.array([r]), np.array([iL]), np.array([1.0]))
            else:
                T.add(np.full(N, r), iX, 0.5 * (np.roll(Y, -1) - np.roll(Y, 1)))
                T.add(np.full(N, r), iY, 0.5 * (np.roll(X, 1) - np.roll(X, -1)))
