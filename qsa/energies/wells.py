"""Double-well potentials ``W(kappa)`` of the faceting energy (e:Facet) and their resolver.

A *well* is any object with vectorised callables ``W(k)``, ``dW(k)``, ``d2W(k)``
(and ``d3W(k)`` for :class:`~qsa.energies.FunctionalizedCurvature`).
The default is the quartic :class:`DoubleWell` ``W = k^2 (k - kstar)^2 / 4``
(wells at 0 and ``kstar``, ``W''(0) = W''(kstar) = kstar^2 / 2``), for which the
equilibrium constructions have closed forms; :func:`is_quartic` tells it apart
(by type, or numerically for a user well equal to it). :class:`Well` wraps user
callables. :func:`resolve_well` is the one place where a ``(well, kstar)``
argument pair is checked: the energies and the flows need only the callables,
the equilibrium constructions also need equal-depth minima at 0 and ``kstar``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from qsa._checks import real_number

__all__ = ["DoubleWell", "QuarticWell", "Well", "is_quartic", "resolve_well"]


@dataclass(frozen=True)
class DoubleWell:
    """``W(kappa) = kappa^2 (kappa - kstar)^2 / 4`` with wells at 0 and kstar.

    ``W''(0) = W''(kstar) = kstar^2 / 2``. Also available as ``QuarticWell``.

    Parameters
    ----------
    kstar : float
        The second well, ``> 0``.

    Examples
    --------
    >>> w = DoubleWell(5.0)
    >>> float(w.W(5.0)), float(w.d2W(0.0))
    (0.0, 12.5)
    >>> abs(float(w.dW(2.5))), float(w.W(2.5))  # the barrier at kstar / 2
    (0.0, 9.765625)
    >>> float(w.W(1.0)), float(w.dW(1.0)), float(w.d2W(1.0))
    (4.0, 6.0, 0.5)
    """

    kstar: float

    def __post_init__(self):
        object.__setattr__(self, "kstar", real_number(self.kstar, "kstar", positive=True))

    def W(self, k):
        """``W(k) = k^2 (k - kstar)^2 / 4``, shape like ``k``."""
        k = np.asarray(k)
        return 0.25 * k**2 * (k - self.kstar) ** 2

    def dW(self, k):
        """``W'(k) = k (k - kstar)(2k - kstar) / 2``, shape like ``k``."""
        k = np.asarray(k)
        return 0.5 * k * (k - self.kstar) * (2 * k - self.kstar)

    def d2W(self, k):
        """``W''(k) = (6k^2 - 6k kstar + kstar^2) / 2``, shape like ``k``."""
        k = np.asarray(k)
        return 0.5 * (6 * k**2 - 6 * k * self.kstar + self.kstar**2)

    def d3W(self, k):
        """``W'''(k) = 3 (2k - kstar)``, shape like ``k``."""
        k = np.asarray(k)
        return 3.0 * (2 * k - self.kstar)


#: The quartic double well under the name the equilibrium constructions use.
QuarticWell = DoubleWell


@dataclass(frozen=True)
class Well:
    """A user double well from callables ``W``, ``dW``, ``d2W`` (vectorised).

    Parameters
    ----------
    W, dW, d2W : callable
    kstar : float, optional
        The non-zero well (for constructions that need it).
    d3W : callable, optional
        ``W'''``, for energies whose Hessian needs it
        (:class:`~qsa.energies.FunctionalizedCurvature`).

    Examples
    --------
    >>> from qsa.energies import Faceting
    >>> w = Well(lambda k: k**2 * (k - 2.0)**2, lambda k: 0 * k, lambda k: 0 * k, kstar=2.0)
    >>> float(w.W(1.0)), Faceting(0.1, 2.0, well=w).well is w
    (1.0, True)
    """

    W: Callable[..., Any]
    dW: Callable[..., Any]
    d2W: Callable[..., Any]
    kstar: float | None = None
    d3W: Callable[..., Any] | None = None

    def __post_init__(self):
        for name in ("W", "dW", "d2W"):
            if not callable(getattr(self, name)):
                raise ValueError(f"well.{name} must be callable")
        if self.d3W is not None and not callable(self.d3W):
            raise ValueError("well.d3W must be callable (or None)")


def is_quartic(well, kstar) -> bool:
    """True when ``well`` is (numerically) the default quartic with this ``kstar``.

    A :class:`DoubleWell` is recognised by its type and ``kstar``; any other well
    by comparing ``W`` with the quartic at 17 points of ``[-0.3, 1.3] kstar``
    (relative tolerance 1e-14).

    Parameters
    ----------
    well : object
    kstar : float

    Returns
    -------
    bool

    Examples
    --------
    >>> is_quartic(DoubleWell(5.0), 5.0), is_quartic(DoubleWell(5.0), 4.0)
    (True, False)
    """
    if isinstance(well, DoubleWell) and float(well.kstar) == float(kstar):
        return True
    k = np.linspace(-0.3, 1.3, 17) * kstar
    try:
        W = np.asarray(well.W(k), dtype=float)
    except Exception:  # noqa: BLE001 - a well that cannot take arrays is not the quartic
        return False
    ref = 0.25 * k**2 * (k - kstar) ** 2
    return bool(np.allclose(W, ref, rtol=1e-14, atol=1e-14 * kstar**4))


def _check_callables(well):
    for name in ("W", "dW", "d2W"):
        if not callable(getattr(well, name, None)):
            raise ValueError(f"well must provide callables W, dW and d2W; {name} is missing")


def _check_equal_depth(well, kstar):
    scale = max(abs(float(well.W(0.5 * kstar))), 1e-300)
    for k0 in (0.0, kstar):
        if abs(float(well.W(k0))) > 1e-12 * scale:
            raise ValueError(
                f"well: W({k0}) = {float(well.W(k0))!r}; the wells must have equal depth 0 "
                "at 0 and kstar (add a supporting line, which the curvature constraint allows)"
            )
        if abs(float(well.dW(k0))) > 1e-10 * scale / kstar:
            raise ValueError(f"well: W'({k0}) = {float(well.dW(k0))!r} is not 0 (not a well)")
        if not float(well.d2W(k0)) > 0:
            raise ValueError(f"well: W''({k0}) must be > 0 (non-degenerate well)")
    inner = np.asarray(well.W(np.linspace(0, kstar, 203)[1:-1]), dtype=float)
    if not np.all(inner > 0):
        raise ValueError("well: W must be positive strictly between the wells 0 and kstar")


def resolve_well(well, kstar=None, *, equal_depth=True, default_kstar=5.0):
    """Return ``(well, kstar)`` after checking the pair.

    Parameters
    ----------
    well : object or None
        ``None`` for ``DoubleWell(kstar)``; otherwise an object with vectorised
        ``W``, ``dW``, ``d2W`` and (optionally) a ``kstar`` attribute and, for
        polynomial wells, ``coefficients`` (``numpy.polyval`` order), which lets
        the periodic-orbit construction work exactly near the separatrix.
    kstar : float or None
        The non-zero well. Taken from ``well.kstar`` when not given (else
        ``default_kstar``); when both are given and ``equal_depth`` is set they
        must agree.
    equal_depth : bool
        Also require equal-depth minima at 0 and ``kstar`` (``W = W' = 0`` there,
        ``W'' > 0`` there and ``W > 0`` in between), as the equilibrium
        constructions do. ``False`` checks only the callables (any potential
        defines an energy and a flow).
    default_kstar : float
        ``kstar`` when neither ``kstar`` nor ``well.kstar`` is given.

    Returns
    -------
    well : object
    kstar : float

    Raises
    ------
    ValueError
        Missing callables, a ``kstar`` that is not a positive number or disagrees
        with ``well.kstar``, or (with ``equal_depth``) wells of the wrong shape.

    Examples
    --------
    >>> well, kstar = resolve_well(None, None)
    >>> well, kstar
    (DoubleWell(kstar=5.0), 5.0)
    >>> flat = Well(lambda k: k**2 * (k - 2) ** 2, lambda k: 2 * k * (k - 2) * (2 * k - 2),
    ...             lambda k: 0 * k)  # W''(0) = 0: not a non-degenerate well
    >>> resolve_well(flat, 2.0)
    Traceback (most recent call last):
    ...
    ValueError: well: W''(0.0) must be > 0 (non-degenerate well)
    """
    wk = getattr(well, "kstar", None) if well is not None else None
    if kstar is None:
        kstar = wk if wk is not None else default_kstar
    kstar = real_number(kstar, "kstar", positive=True)
    if well is None:
        return DoubleWell(kstar), kstar
    _check_callables(well)
    if equal_depth:
        if wk is not None and abs(float(wk) - kstar) > 1e-12 * kstar:
            raise ValueError(f"kstar={kstar} disagrees with well.kstar={wk}")
        _check_equal_depth(well, kstar)
    return well, kstar
