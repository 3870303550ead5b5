"""Constraints of a closed curve: closure (always), a fixed length, a fixed enclosed area.

Closure ``C(U) = 0`` (e:C1, e:C2) is part of every problem; its gradients ``Psi_j``
and Hessians are :func:`qsa.geometry.constraint_gradients` and
:func:`qsa.geometry.constraint_hessians`. This module adds the two optional scalar
constraints of the bifurcation problems, each with its value, its gradient and
Hessian in ``<f, h> = int f h dsigma``, and its *normal variation* ``n_c``: the
first variation of ``c`` when the curve moves with outward normal velocity ``V``,

    d/dt c = <n_c, V>,        n_L = kappa,        n_A = 1.

``FixedLength(L=None)``, ``FixedArea(A=None)``
    Exact constraints ``c(U) = c*`` with Lagrange multipliers ``mu_c`` next to the
    closure multipliers ``Lambda``: constrained equilibria satisfy

        nabla_I E = Lambda . Psi + sum_c mu_c nabla_I c,

    equivalently ``V^n + sum_c mu_c n_c = 0`` (``V^n`` the energy's outward normal
    velocity), so ``mu_A`` is the pressure that holds the shape (an equilibrium of
    ``E + Pressure(p)`` is one of ``E`` at fixed area with ``mu_A = p``) and
    ``-mu_L`` the line tension. ``None`` takes the value of the curve the
    constraint is first bound to (:func:`bind_constraints`).

The enclosed area and the length, with their exact discrete gradients and Hessians, are
:mod:`qsa.measures` (re-exported here).

The constrained linearization
-----------------------------
With all multipliers, the second variation is that of the Lagrangian,
``L_full = nabla^2 E - Lambda . nabla^2 C - sum_c mu_c nabla^2 c``, and the
constrained gradient flow ``V = V^n(U) + sum_c mu_c(t) n_c`` chooses ``mu_c(t)`` so
that ``<n_c, V> = 0`` (each constraint conserved): ``V`` is the
``<.,.>``-orthogonal projection of ``V^n`` onto ``T = {phi : <n_c, phi> = 0}``. Its
linearization at an equilibrium is ``P J P`` on ``T``, ``P`` that projection and
``J = -[M-dagger L_full M(., 0)]_1``: self-adjoint on ``T``, so its spectrum is real.
The directions ``n_c`` are excluded from the problem, not reported as eigenvalues.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from qsa._checks import real_number
from qsa.curve import Curve
from qsa.measures import (
    area_gradient,
    area_gradient_euclidean,
    area_hessian,
    length_gradient,
    length_hessian,
)

__all__ = [
    "Constraint",
    "FixedLength",
    "FixedArea",
    "bind_constraints",
    "check_constraints",
    "constraint_normals",
    "normal_basis",
    "flow_multipliers",
    "project_velocity",
    "area_gradient",
    "area_gradient_euclidean",
    "area_hessian",
    "length_gradient",
    "length_hessian",
]


class Constraint(ABC):
    """A scalar constraint ``c(U) = target`` on a closed curve (see the module docstring).

    Subclasses are frozen dataclasses with one field, the target (``None``: the
    value of the curve it is bound to), and implement :meth:`value`,
    :meth:`gradient`, :meth:`hessian` and :meth:`normal_variation`.
    """

    #: short name of the constrained quantity (``"L"``, ``"A"``)
    symbol = ""
    #: name of the dataclass field holding the target (``"L"``, ``"A"``)
    _field: ClassVar[str] = ""

    @property
    @abstractmethod
    def target(self):
        """The prescribed value, or ``None`` until bound (:meth:`bind`)."""

    @abstractmethod
    def value(self, c: Curve) -> float:
        """The constrained quantity at ``c``."""

    @abstractmethod
    def gradient(self, c: Curve) -> np.ndarray:
        """Its gradient in ``<f, h> = int f h dsigma``, shape (2N,)."""

    @abstractmethod
    def hessian(self, c: Curve):
        """Its Hessian in ``<f, h> = int f h dsigma``, shape (2N, 2N)."""

    @abstractmethod
    def normal_variation(self, c: Curve) -> np.ndarray:
        """``n_c`` with ``d/dt c = <n_c, V>`` under outward normal velocity ``V``, shape (N,)."""

    def euclidean_gradient(self, c: Curve) -> np.ndarray:
        """``dc/dU`` without inner-product weights (a Newton row), shape (2N,)."""
        return self.gradient(c) * np.concatenate([c.dsigma, c.dsigma])

    def bind(self, c: Curve) -> Constraint:
        """This constraint with ``target = value(c)`` if it was ``None``."""
        if self.target is not None:
            return self
        return replace(self, **{self._field: self.value(c)})  # type: ignore[type-var]

    def defect(self, c: Curve) -> float:
        """``value(c) - target`` (the constraint must be bound)."""
        if self.target is None:
            raise ValueError(f"{type(self).__name__}: bind the constraint to a curve first "
                             "(bind_constraints)")
        return self.value(c) - self.target

    def params(self) -> dict:
        """JSON-serialisable description, e.g. ``{"constraint": "FixedArea", "A": 3.14}``."""
        return {"constraint": type(self).__name__, self._field: self.target}


def _target(value, name):
    return None if value is None else real_number(value, name, positive=True)


@dataclass(frozen=True)
class FixedLength(Constraint):
    """The exact constraint ``L(U) = int g ds = L`` with a Lagrange multiplier.

    Parameters
    ----------
    L : float, optional
        Prescribed length, ``> 0``; ``None``: the length of the curve it is bound to.

    Notes
    -----
    ``nabla_I L = (0, 1/g)``, ``nabla_I^2 L = 0`` and the normal variation is
    ``n_L = kappa`` (``d/dt L = int kappa V dsigma``, exactly also for the discrete
    length under ``U_t = M(V, 0)``, since ``g_t = g kappa V``).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> con = FixedLength().bind(c)
    >>> round(con.target / np.pi, 12), round(con.defect(c), 12)
    (2.0, 0.0)
    """

    L: float | None = None
    symbol = "L"
    _field = "L"

    def __post_init__(self):
        object.__setattr__(self, "L", _target(self.L, "L"))

    @property
    def target(self):
        return self.L

    def value(self, c):
        return c.length()

    def gradient(self, c):
        return length_gradient(c)

    def hessian(self, c):
        return length_hessian(c)

    def normal_variation(self, c):
        return np.array(c.kappa)


@dataclass(frozen=True)
class FixedArea(Constraint):
    """The exact constraint ``A(U) = 1/2 int gamma·n dsigma = A`` with a Lagrange multiplier.

    Parameters
    ----------
    A : float, optional
        Prescribed enclosed area, ``> 0``; ``None``: the area of the curve it is bound to.

    Notes
    -----
    Gradient and Hessian are the exact derivatives of the discrete area
    (:func:`area_gradient`, :func:`area_hessian`); the normal variation is ``n_A = 1``
    (``d/dt A = int V dsigma``). The multiplier is the pressure holding the shape.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(2.0, Fourier(17))
    >>> round(FixedArea().bind(c).target / np.pi, 12)
    4.0
    """

    A: float | None = None
    symbol = "A"
    _field = "A"

    def __post_init__(self):
        object.__setattr__(self, "A", _target(self.A, "A"))

    @property
    def target(self):
        return self.A

    def value(self, c):
        return c.area()

    def gradient(self, c):
        return area_gradient(c)

    def euclidean_gradient(self, c):
        return area_gradient_euclidean(c)

    def hessian(self, c):
        return area_hessian(c)

    def normal_variation(self, c):
        return np.ones(c.N)


def check_constraints(constraints) -> tuple:
    """Validate a list of constraints (without binding them); ``None`` is no constraint.

    Parameters
    ----------
    constraints : sequence of Constraint, a Constraint, or None
        Entries may also be the dicts of :meth:`Constraint.params` (as stored in files).

    Returns
    -------
    tuple of Constraint

    Raises
    ------
    ValueError
        An entry that is not a :class:`Constraint`, or the same kind twice.

    Examples
    --------
    >>> check_constraints([{"constraint": "FixedArea", "A": 2.0}])
    (FixedArea(A=2.0),)
    >>> check_constraints([FixedLength(), FixedLength(6.0)])
    Traceback (most recent call last):
    ...
    ValueError: constraints: FixedLength is given twice; pass each constraint at most once
    """
    if constraints is None:
        return ()
    if isinstance(constraints, (Constraint, dict)):
        constraints = (constraints,)
    try:
        items = tuple(constraints)
    except TypeError:
        raise ValueError("constraints must be a list of FixedLength() / FixedArea(), "
                         f"got {type(constraints).__name__}") from None
    kinds = {"FixedLength": FixedLength, "FixedArea": FixedArea}
    seen = set()
    out = []
    for con in items:
        if isinstance(con, dict) and con.get("constraint") in kinds:
            cls = kinds[con["constraint"]]
            con = cls(con.get(cls._field))
        if not isinstance(con, Constraint):
            raise ValueError("constraints must contain qsa.constraints.FixedLength / FixedArea "
                             f"objects, got {type(con).__name__}")
        kind = type(con).__name__
        if kind in seen:
            raise ValueError(f"constraints: {kind} is given twice; pass each constraint at "
                             "most once")
        seen.add(kind)
        out.append(con)
    return tuple(out)


def bind_constraints(constraints, curve: Curve) -> tuple:
    """Validate ``constraints`` and bind each to ``curve`` (``None`` targets -> its values).

    Parameters
    ----------
    constraints : sequence of Constraint or None
        E.g. ``[FixedLength(), FixedArea(A=3.0)]``; ``None`` or empty: no constraint.
    curve : Curve

    Returns
    -------
    tuple of Constraint
        Bound copies, in the order given.

    Raises
    ------
    ValueError
        See :func:`check_constraints`.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> [type(k).__name__ for k in bind_constraints([FixedArea(), FixedLength()], c)]
    ['FixedArea', 'FixedLength']
    """
    return tuple(con.bind(curve) for con in check_constraints(constraints))


def constraint_normals(constraints, curve: Curve) -> np.ndarray:
    """The normal variations ``n_c`` of the constraints as rows, shape (m, N).

    Parameters
    ----------
    constraints : sequence of Constraint
    curve : Curve

    Returns
    -------
    ndarray, shape (m, N)
        ``d/dt c = <n_c, V>`` for outward normal velocity ``V``.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(2.0, Fourier(9))
    >>> constraint_normals([FixedLength(), FixedArea()], c)[:, 0].tolist()
    [0.5, 1.0]
    """
    return np.array([con.normal_variation(curve) for con in constraints]).reshape(-1, curve.N)


def normal_basis(constraints, curve: Curve, rtol=1e-8) -> np.ndarray:
    """``<.,.>``-orthonormal basis of the constraints' normal variations, shape (m', N).

    ``m' <= m``: dependent normals are dropped (a circle with a length and an area
    constraint has ``n_L = kappa`` constant, parallel to ``n_A = 1``).

    Parameters
    ----------
    constraints : sequence of Constraint
    curve : Curve
    rtol : float
        Singular values below ``rtol`` times the largest count as dependent.

    Returns
    -------
    ndarray, shape (m', N)
        Rows ``r`` with ``sum(r_i r_j dsigma) = delta_ij``; the ``<.,.>``-orthogonal
        projection onto ``T = {phi : <n_c, phi> = 0}`` is ``phi - R^T (R (dsigma phi))``.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> normal_basis([FixedLength(), FixedArea()], c).shape
    (1, 17)
    """
    n = constraint_normals(constraints, curve)
    if n.shape[0] == 0:
        return np.zeros((0, curve.N))
    rw = np.sqrt(curve.dsigma)
    U, sv, _ = np.linalg.svd((n * rw).T, full_matrices=False)
    keep = int(np.sum(sv > rtol * sv[0])) if sv[0] > 0 else 0
    return (U[:, :keep] / rw[:, None]).T


def flow_multipliers(constraints, curve: Curve, V) -> np.ndarray:
    """The multipliers ``mu`` of the constrained gradient flow: ``<n_i, V + mu·n> = 0``, (m,).

    ``V + sum_i mu_i n_i`` is the ``<.,.>``-orthogonal projection of ``V`` onto
    ``T = {phi : <n_i, phi> = 0}`` (``mu`` minimises ``|V + mu . n|``): the normal velocity
    that conserves every constraint (``d/dt c_i = <n_i, V + mu . n> = 0``). At an
    equilibrium these are the Lagrange multipliers of the module docstring. A
    degenerate set of normals (a circle with both constraints: ``kappa`` is constant)
    is handled by least squares.

    Parameters
    ----------
    constraints : sequence of Constraint
    curve : Curve
    V : ndarray, shape (N,)
        Outward normal velocity of the energy.

    Returns
    -------
    ndarray, shape (m,)

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(9))
    >>> flow_multipliers([FixedArea()], c, np.full(9, 0.25)).round(12).tolist()
    [-0.25]
    """
    n = constraint_normals(constraints, curve)
    if n.shape[0] == 0:
        return np.zeros(0)
    w = curve.dsigma
    G = (n * w) @ n.T
    return -np.linalg.lstsq(G, (n * w) @ np.asarray(V, dtype=float), rcond=1e-12)[0]


def project_velocity(constraints, curve: Curve, V) -> np.ndarray:
    """``V + mu·n`` with the :func:`flow_multipliers`: the constrained normal velocity, (N,).

    Parameters
    ----------
    constraints : sequence of Constraint
    curve : Curve
    V : ndarray, shape (N,)

    Returns
    -------
    ndarray, shape (N,)
        ``<.,.>``-orthogonal to every ``n_i``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(9))
    >>> V = project_velocity([FixedArea()], c, 1 + np.cos(2 * np.pi * c.grid.s))
    >>> bool(abs(V @ c.dsigma) < 1e-12), bool(np.allclose(V, np.cos(2 * np.pi * c.grid.s)))
    (True, True)
    """
    V = np.asarray(V, dtype=float)
    if not constraints:
        return V
    return V + flow_multipliers(constraints, curve, V) @ constraint_normals(constraints, curve)
