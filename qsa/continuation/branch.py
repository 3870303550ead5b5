"""Branches of equilibria and their special points: the results of continuation.

A :class:`Branch` is the record of one continuation run (:func:`qsa.continuation.continuation`):
its converged :class:`BranchPoint` s (each a polished equilibrium with the sign of
``det F_x`` of the square system and, with ``stability=True``, its number of unstable
eigenvalues per Bloch sector), the :class:`Fold` s found between them and the
:class:`Bifurcation` s: every located change of the unstable count, folds included,
each with its critical eigenvectors (:class:`CriticalMode`) and their symmetry label.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from qsa.curve import Curve

if TYPE_CHECKING:
    from qsa.equilibria.result import Equilibrium
    from qsa.spectra.symmetry import BlochSymmetry

__all__ = ["Branch", "BranchPoint", "Bifurcation", "CriticalMode", "Fold", "MESSAGES"]

#: Meaning of :attr:`Branch.status` (0 success, positive: success with a caveat,
#: negative: failure); :attr:`Branch.message` starts with the entry.
MESSAGES = {
    0: "range covered",
    -1: "the step size fell below ds_min (corrector failures)",
    -2: "max_steps reached before the end of the range",
    -3: "natural continuation stopped: Newton failed (a fold is likely; use "
        "method='pseudo-arclength')",
    -4: "singular tangent system",
    -5: "numerical failure",
    1: "stopped at self-contact",
    2: "stopped at a fold it cannot pass",
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
class CriticalMode:
    """A critical eigenvector of ``J`` at a bifurcation, with its symmetry label.

    Attributes
    ----------
    vector : ndarray, shape (N,)
        Normal perturbation ``phi`` (``<.,.>``-unit, ``<f, h> = int f h dsigma``); the
        perturbed state is ``U + delta M(phi, 0) = (kappa + delta G phi, g + delta g kappa
        phi)``.
    sector : int
        Bloch index ``b`` (``T phi = exp(2 pi i b / n) phi`` for the complex pair):
        the mode number ``m`` of ``cos m theta`` on a circle.
    label : str
        ``"mode"`` (circle), ``"bloch"`` (an ``n``-pulse or other ``Z_n``-symmetric
        state) or ``"none"`` (no symmetry).
    parity : int
        ``+1`` / ``-1``: even / odd under the state's reflection; 0 if it has none.

    Parameters
    ----------
    The attributes above.
    """

    vector: np.ndarray
    sector: int
    label: str
    parity: int = 0


@dataclass(frozen=True, eq=False)
class Bifurcation:
    """A located change of the number of unstable eigenvalues along a branch, or a fold.

    Attributes
    ----------
    parameter : float
        Where the critical eigenvalue vanishes (secant iteration on it, the equilibrium
        re-polished at every trial point).
    multiplicity : int
        1 for a simple crossing, 2 for a symmetric double one (a complex Bloch sector).
    kind : str
        ``"fold"`` (a limit point: the branch turns back) or ``"branch"`` (a branch
        point: other equilibria bifurcate).
    modes : tuple of CriticalMode
        The critical eigenvectors (``multiplicity`` of them).
    index : int
        It lies between ``branch.points[index]`` and ``points[index + 1]``.
    equilibrium : Equilibrium
        The equilibrium at ``parameter``.
    eigenvalue : float
        The critical eigenvalue there (0 up to the location tolerance).
    change : int
        ``+multiplicity`` if the count of unstable eigenvalues grows in the direction of
        the branch, ``-multiplicity`` if it falls.
    tangent : ndarray, shape (N + 2,)
        Unit tangent ``(d kappa, d L, d p)`` of the branch at the point (weighted norm).
    symmetry : BlochSymmetry or None
        The symmetry of the branch the sectors refer to.

    Parameters
    ----------
    Constructed by :func:`qsa.continuation.continuation`; the fields are the attributes
    above.

    Examples
    --------
    The circles of Faceting + Perimeter lose stability to mode 2, a double crossing:

    >>> import numpy as np
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.continuation import continuation
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17)
    >>> b = continuation(lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls), eq.curve,
    ...                  "L_star", (eq.params["L_star"], 5.2, -0.1))
    >>> bif = b.bifurcations[0]
    >>> bif.kind, bif.multiplicity, [m.sector for m in bif.modes], abs(bif.eigenvalue) < 1e-8
    ('branch', 2, [2, 2], True)
    """

    parameter: float
    multiplicity: int
    kind: str
    modes: tuple
    index: int
    equilibrium: Equilibrium
    eigenvalue: float
    change: int
    tangent: np.ndarray | None = field(repr=False, default=None)
    symmetry: BlochSymmetry | None = None

    @property
    def curve(self) -> Curve:
        """``equilibrium.curve``."""
        return self.equilibrium.curve

    @property
    def sector(self) -> int:
        """The Bloch index (mode number on a circle) of the critical modes."""
        return self.modes[0].sector if self.modes else 0

    def summary(self) -> dict:
        """JSON-serialisable dict (parameter, multiplicity, kind, sector, label, change)."""
        return {"parameter": float(self.parameter), "multiplicity": int(self.multiplicity),
                "kind": self.kind, "index": int(self.index),
                "sector": int(self.sector),
                "label": self.modes[0].label if self.modes else "none",
                "eigenvalue": float(self.eigenvalue), "change": int(self.change),
                "L": float(self.curve.length())}


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
        Number of unstable eigenvalues (with multiplicity, kernel deflated) if
        stability was requested.
    sector_unstable : tuple of int or None
        Unstable eigenvalues per Bloch sector ``b = 0, 1, ...`` (with multiplicity),
        when computed by the symmetry-adapted count.
    critical : ndarray or None, shape (m, 2)
        The eigenvalues nearest 0 of each sector: rows ``(lambda, b)``.

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
    equilibrium: Equilibrium
    dp_ds: float
    det_sign: int
    n_unstable: int | None = None
    sector_unstable: tuple | None = None
    critical: np.ndarray | None = field(default=None, repr=False)

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
        A key of :data:`MESSAGES`: 0 range covered, 1 stopped at self-contact of the
        curve, 2 stopped at a fold it cannot pass (step size below ``ds_min`` where
        ``|dp/ds|`` is small), -1 step size below ``ds_min`` elsewhere (corrector
        failures), -2 ``max_steps`` reached, -3 natural continuation stopped (fold or
        failure), -4 singular tangent system, -5 numerical failure (an exception of a
        solver, its text in the message).
    message : str
        Starts with ``MESSAGES[status]``; then where it stopped, folds and bifurcations.
    n_steps, n_rejected : int
        Accepted continuation steps and rejected (corrector-failed) attempts.
    n_newton : int
        Newton (corrector) iterations over the accepted points.
    bifurcations : tuple of Bifurcation
        Every located change of the unstable count (``stability=True``) and every fold,
        in the order of the branch.
    symmetry : BlochSymmetry or None
        The symmetry kept along the branch (the sectors of ``sector_unstable``).
    n_eigensolves : int
        Shift-invert eigen-solves (one factorization each) spent on stability: one per
        point for the count, plus :attr:`n_locate_solves`.
    n_locate_solves : int
        Those spent locating the crossings (one per trial point).
    energy_factory : callable
        The family ``p -> Energy`` of the branch.
    constraints : tuple
        The exact constraints besides closure.
    origin : Bifurcation or None
        The bifurcation a switched branch starts from (:func:`switch_branch`).

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
    bifurcations: tuple = ()
    symmetry: BlochSymmetry | None = None
    n_eigensolves: int = 0
    n_locate_solves: int = 0
    energy_factory: object = field(default=None, repr=False)
    constraints: tuple = ()
    origin: object = field(default=None, repr=False)
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

    @property
    def stable(self) -> np.ndarray | None:
        """``n_unstable == 0`` per point, or None without stability."""
        nu = self.n_unstable
        return None if nu is None else nu == 0

    @property
    def curves(self) -> tuple:
        """The equilibrium curves of the points."""
        return tuple(p.curve for p in self.points)

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
            "bifurcations": [b.summary() for b in self.bifurcations],
            "n_eigensolves": int(self.n_eigensolves),
            "n_locate_solves": int(self.n_locate_solves),
        }
