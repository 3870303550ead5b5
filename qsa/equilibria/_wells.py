"""Double-well potentials as the equilibrium constructions need them.

A *well* is any object with vectorised callables ``W(k)``, ``dW(k)``, ``d2W(k)``
and equal-depth minima ``W(0) = W(kstar) = 0``. The default is the quartic
``W = k^2 (k - kstar)^2 / 4`` (MATH.md section 1), for which several
constructions have closed forms; :func:`resolve_well` tells them apart.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsa._checks import real_number

__all__ = ["QuarticWell", "resolve_well", "is_quartic"]


@dataclass(frozen=True)
class QuarticWell:
    """``W(k) = k^2 (k - kstar)^2 / 4``: the default double well (wells at 0, kstar).

    Parameters
    ----------
    kstar : float

    Examples
    --------
    >>> w = QuarticWell(5.0)
    >>> float(w.W(1.0)), float(w.dW(1.0)), float(w.d2W(1.0))
    (4.0, 6.0, 0.5)
    """

    kstar: float

    def W(self, k):
        """``W(k)``, shape like ``k``."""
        return 0.25 * k**2 * (k - self.kstar) ** 2

    def dW(self, k):
        """``W'(k)``, shape like ``k``."""
        return 0.5 * k * (k - self.kstar) * (2 * k - self.kstar)

    def d2W(self, k):
        """``W''(k)``, shape like ``k``."""
        return 0.5 * (6 * k**2 - 6 * k * self.kstar + self.kstar**2)


def _default_well(kstar):
    try:  # the energies' own double well, so results carry the object users know
        from qsa.energies.faceting import DoubleWell
    except ImportError:  # pragma: no cover - only before the energies exist
        return QuarticWell(kstar)
    return DoubleWell(kstar)


def _positive(x, name):
    return real_number(x, name, positive=True)


def is_quartic(well, kstar) -> bool:
    """True when ``well`` is (numerically) the default quartic with this ``kstar``.

    Parameters
    ----------
    well : object
    kstar : float

    Returns
    -------
    bool

    Examples
    --------
    >>> from qsa.energies import DoubleWell
    >>> is_quartic(DoubleWell(5.0), 5.0), is_quartic(DoubleWell(5.0), 4.0)
    (True, False)
    """
    if ((isinstance(well, QuarticWell) or type(well).__name__ == "DoubleWell")
            and float(well.kstar) == float(kstar)):
        return True
    k = np.linspace(-0.3, 1.3, 17) * kstar
    try:
        W = np.asarray(well.W(k), dtype=float)
    except Exception:  # noqa: BLE001 - a well that cannot take arrays is not the quartic
        return False
    ref = 0.25 * k**2 * (k - kstar) ** 2
    return bool(np.allclose(W, ref, rtol=1e-14, atol=1e-14 * kstar**4))


def resolve_well(well, kstar, *, default_kstar=5.0):
    """Return ``(well, kstar)`` after checking the well's shape.

    Parameters
    ----------
    well : object or None
        ``None`` for the default quartic; otherwise an object with vectorised
        ``W``, ``dW``, ``d2W`` and (optionally) a ``kstar`` attribute and, for
        polynomial wells, ``coefficients`` (``numpy.polyval`` order), which lets
        the periodic-orbit construction work exactly near the separatrix.
    kstar : float or None
        The non-zero well. Taken from ``well.kstar`` when not given; when both
        are given they must agree.

    Raises
    ------
    ValueError
        Missing callables, inconsistent or missing ``kstar``, or wells that are
        not equal-depth minima at 0 and ``kstar`` (``W = W' = 0`` there,
        ``W'' > 0`` there and ``W > 0`` in between).

    Returns
    -------
    well : object
    kstar : float

    Examples
    --------
    >>> well, kstar = resolve_well(None, None)
    >>> type(well).__name__, kstar
    ('DoubleWell', 5.0)
    """
    wk = getattr(well, "kstar", None) if well is not None else None
    if kstar is None:
        kstar = wk if wk is not None else default_kstar
    kstar = _positive(kstar, "kstar")
    if wk is not None and abs(float(wk) - kstar) > 1e-12 * kstar:
        raise ValueError(f"kstar={kstar} disagrees with well.kstar={wk}")
    if well is None:
        return _default_well(kstar), kstar
    for name in ("W", "dW", "d2W"):
        if not callable(getattr(well, name, None)):
            raise ValueError(f"well must provide callables W, dW and d2W; {name} is missing")
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
    return well, kstar
