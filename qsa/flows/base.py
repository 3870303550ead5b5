"""The contract between flow models (``dae.py``) and time steppers (``stepper.py``).

A *model* is a frozen dataclass of physical parameters (``CHA``,
``FacetingFlow``). ``model.setup(x, y)`` binds it to initial node positions
(already resampled to equal chords, the paper's ap:scaled) and returns a
:class:`DAESystem`: the implicit differential-algebraic system ::

    F(y, ydot) = 0,

on the stacked unknowns ``y`` (per node: positions, curvature, auxiliary
fields, normal velocity; plus the length L). ``ydot`` enters F linearly and only
in the rows of the normal-motion law and the tangential gauge, so one implicit
step of any BDF/SDIRK-type method with ``ydot = (y - psi) / (gamma k)`` is the
nonlinear system ::

    G(y) = F(y, (y - psi) * c) = 0,   c = 1 / (gamma k),

whose Newton matrix is ``dF/dy + c dF/dydot`` (``DAESystem.jacobian``). Backward
Euler is ``gamma = 1, psi = y_n``; the paper's scheme (appendix, "Discussion of
Numerical Scheme") is exactly that.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

__all__ = ["FlowModel", "DAESystem"]


class DAESystem(ABC):
    """An implicit DAE ``F(y, ydot) = 0`` for a closed curve on ``N`` nodes.

    Attributes
    ----------
    N : int
        Number of nodes.
    size : int
        Length of the unknown vector ``y``.
    y0 : ndarray, shape (size,)
        Consistent initial state (algebraic rows satisfied).
    error_index : ndarray of int
        Components of ``y`` on which local errors are measured (the positions,
        as in the paper's step-doubling control).
    """

    N: int
    size: int
    y0: np.ndarray
    error_index: np.ndarray

    @abstractmethod
    def residual(self, y, ydot) -> np.ndarray:
        """``F(y, ydot)``, shape (size,)."""

    @abstractmethod
    def jacobian(self, y, ydot, c):
        """Sparse (CSC) ``dF/dy + c * dF/dydot`` at ``(y, ydot)``, shape (size, size)."""

    @abstractmethod
    def positions(self, y) -> tuple[np.ndarray, np.ndarray]:
        """Node positions ``(x, y)``, each shape (N,)."""

    @abstractmethod
    def energy(self, y) -> float:
        """The model's discrete energy at state ``y`` (same quadrature as the residual)."""

    @abstractmethod
    def length(self, y) -> float:
        """Curve length L at state ``y``."""

    def normal_velocity(self, y) -> np.ndarray:
        """Normal velocity V^n at the nodes (outward normal), shape (N,)."""
        raise NotImplementedError

    def metadata(self) -> dict:
        """JSON-serialisable description (model name, parameters, N, bound constants)."""
        return {"N": int(self.N)}


class FlowModel(ABC):
    """Physical parameters of a curve flow; ``setup`` binds them to initial positions."""

    name: str = "model"

    @abstractmethod
    def setup(self, x, y) -> DAESystem:
        """Build the DAE system for initial positions ``x, y`` (equal chords), shape (N,)."""

    def min_nodes(self) -> int:
        """Smallest N for which the model is resolved at all (checked by ``solve_flow``)."""
        return 8

    def check_resolution(self, x, y) -> None:
        """Raise ``ValueError`` when the grid is too coarse for the model (e.g. h > l_star)."""
        return None
