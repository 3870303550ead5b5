"""Branches of equilibria and their special points: the results of continuation.

A :class:`Branch` is the record of one continuation run (:func:`qsa.continuation.continuation`):
its converged :class:`BranchPoint` s (each a polished equilibrium with the sign of
``det F_x`` of the square system and, optionally, its number of unstable
eigenvalues) and the :class:`Fold` s found between them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsa.curve import Curve

__all__ = ["Branch", "BranchPoint", "Fold", "MESSAGES"]

#: Meaning of :attr:`Branch.status` (0 success, positive: success with a caveat,
#: negative: failure); :attr:`Branch.message` starts with the entry.
MESSAGES = {
    0: "range covered",
    -1: "the step size fell below ds_min (corrector failures)",
    -2: "max_steps reached before the end of the range",
    -3: "natural continuation stopped: Newton failed (a fold is likely; use "
        "method='pseudo-arclength')",
    -4: "singular tangent system",
}


@dataclass(frozen=True, eq=False)
class Fold:
    """A fold (limit point) of a branch.

    Attributes
    ----------
    param : float
        Parameter value at the fold (refined by secant steps on ``dp/ds``).
    index : int
        The fold lies between ``branch.points[index]`` and ``points[index + 1]``.
    curve : Curve
        The equilibrium at the refined location.
    L : float
        Its length.
    dp_ds : float
        The remaining ``dp/ds`` at the refined location (0 at an exact fold).

    Parameters
    ----------
    Constructed by :func:`continuation`; the fields are the attributes above.

    Examples
    --------
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.continuation import continuation
    >>> from qsa.equilibria import circle
    >>> eq = circle(0.77, 0.1, grid=17)
    >>> b = continuation(lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls), eq.curve,
    ...                  "L_star", (eq.params["L_star"], 3.0, -0.1))
    >>> fold = b.folds[0]
    >>> bool(abs(fold.dp_ds) < 1e-6), bool(3.0 < fold.param < eq.params["L_star"])
    (True, True)
    """

    param: float
    index: int
    curve: Curve
    L: float
    dp_ds: float


@dataclass(frozen=True, eq=False)
class BranchPoint:
    """One converged point of a branch.

    Attributes
    ----------
    param : float
    equilibrium : Equilibrium
        ``polish``-type result at this point (residual, closure, multipliers ...).
    dp_ds : float
        Parameter component of the unit tangent (NaN for natural continuation).
    det_sign : int
        Sign of ``det F_x`` of the square system at this point.
    n_unstable : int or None
        Number of unstable eigenvalues if stability was requested.

    Parameters
    ----------
    Constructed by :func:`continuation`; the fields are the attributes above.

    Examples
    --------
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.continuation import continuation
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17)
    >>> b = continuation(lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls), eq.curve,
    ...                  "L_star", (eq.params["L_star"], 6.0, 0.05), method="natural")
    >>> pt = b.points[0]
    >>> bool(pt.equilibrium.success), bool(pt.param == eq.params["L_star"])
    (True, True)
    """

    param: float
    equilibrium: object
    dp_ds: float
    det_sign: int
    n_unstable: int | None = None

    @property
    def curve(self) -> Curve:
        """``equilibrium.curve``."""
        return self.equilibrium.curve


@dataclass(frozen=True, eq=False)
class Branch:
    """A branch of equilibria in one parameter.

    Attributes
    ----------
    param : str
        Name of the parameter.
    points : tuple of BranchPoint
    folds : tuple of Fold
    branch_points : tuple of int
        Indices ``i`` where ``det F_x`` changes sign between points ``i`` and
        ``i + 1`` without a fold (possible bifurcations).
    method : str
    success : bool
        Whether the requested range was covered (``status >= 0``).
    status : int
        A key of :data:`MESSAGES`: 0 range covered, -1 step size below ``ds_min``
        (corrector failures), -2 ``max_steps`` reached, -3 natural continuation
        stopped (fold or failure), -4 singular tangent system.
    message : str
        Starts with ``MESSAGES[status]``; then where it stopped, folds and sign changes.
    n_steps, n_rejected : int
        Accepted continuation steps and rejected (corrector-failed) attempts.
    n_newton : int
        Newton (corrector) iterations over the accepted points.

    Parameters
    ----------
    Constructed by :func:`continuation`; the fields are the attributes above.

    Examples
    --------
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.continuation import continuation
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17)
    >>> b = continuation(lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls), eq.curve,
    ...                  "L_star", (eq.params["L_star"], 6.0, 0.05), method="natural")
    >>> bool(b.success), b.values.shape == b.lengths.shape == b.residuals.shape
    (True, True)
    """

    param: str
    points: tuple
    folds: tuple
    branch_points: tuple
    method: str
    success: bool
    status: int
    message: str
    n_steps: int = 0
    n_rejected: int = 0
    n_newton: int = 0
    extra: dict = field(default_factory=dict, repr=False)

    @property
    def values(self) -> np.ndarray:
        """Parameter values, shape (n_points,)."""
        return np.array([p.param for p in self.points])

    @property
    def lengths(self) -> np.ndarray:
        """Curve lengths L, shape (n_points,)."""
        return np.array([p.equilibrium.params["L"] for p in self.points])

    @property
    def residuals(self) -> np.ndarray:
        """``max|V^n|`` at each point."""
        return np.array([p.equilibrium.residual for p in self.points])

    @property
    def n_unstable(self) -> np.ndarray | None:
        """Unstable counts per point, shape (n_points,), or None without ``stability=True``."""
        if any(p.n_unstable is None for p in self.points):
            return None
        return np.array([p.n_unstable for p in self.points], dtype=int)

    def energies(self) -> np.ndarray:
        """Energy of each point (evaluated with its own parameter value)."""
        return np.array([p.equilibrium.energy.energy(p.curve) for p in self.points])

    def summary(self) -> dict:
        """JSON-serialisable summary (parameter values, lengths, residuals, folds ...)."""
        return {
            "param": self.param, "method": self.method, "success": bool(self.success),
            "status": int(self.status), "message": self.message,
            "n_steps": int(self.n_steps), "n_rejected": int(self.n_rejected),
            "n_newton": int(self.n_newton),
            "values": [float(v) for v in self.values],
            "L": [float(v) for v in self.lengths],
            "folds": [{"param": float(f.param), "index": int(f.index), "L": float(f.L)}
                      for f in self.folds],
            "branch_points": [int(i) for i in self.branch_points],
            "n_unstable": None if self.n_unstable is None else
            [int(n) for n in self.n_unstable],
        }
