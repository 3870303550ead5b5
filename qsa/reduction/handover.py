"""Hand-over from a curvature profile (a DAE state) to the front-position ODE.

The ODE's state is the splice parameters ``p`` (e:psi_N), which are the ``kstar/2``
crossings of the splice only up to the neighbours' tails. :func:`hand_over` finds the
``p`` whose splice has the crossings of the given profile: it detects the fronts
(:func:`qsa.reduction.detect_fronts`), orders them to start with an up-front, solves
``crossings(p) = crossings(kappa)`` by fixed-point steps (the map ``p -> crossings(p)``
is the identity up to exponentially small tails, so each step gains their size), and
closes the result (e:C1, e:C2; :func:`qsa.equilibria.close_positions`, minimum norm).
The ODE must have the profile's length (``FrontODE(length=L)``; with a variable length
its ``L_star`` is the flow's).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qsa.equilibria.splice import close_positions, default_cutoff
from qsa.reduction.fronts import detect_fronts

__all__ = ["HandOver", "hand_over"]


@dataclass(frozen=True)
class HandOver:
    """Splice positions for a curvature profile (:func:`hand_over`).

    Attributes
    ----------
    positions : ndarray, shape (2N,)
        Closed splice positions ``p`` (up, down, ...), increasing.
    order : ndarray of int, shape (2N,)
        Index of each ``p_j`` among the profile's fronts as detected (sorted by arc
        length from the base point): the map from the ODE's front indices to the
        detector's (and a tracker's).
    crossings : ndarray, shape (2N,)
        The profile's crossings in the order of ``positions`` (unwrapped).
    length : float
    mismatch : float
        ``max |crossings(p) - crossings(kappa)|`` after the closure (the closure's
        change of the crossings; the inversion itself is converged).
    """

    positions: np.ndarray
    order: np.ndarray
    crossings: np.ndarray
    length: float
    mismatch: float


def hand_over(ode, kappa, length, iterations=4):
    """Splice positions whose crossings are those of ``kappa`` (see the module docstring).

    Parameters
    ----------
    ode : FrontODE
        With ``ode.length == length``.
    kappa : ndarray, shape (n,)
        Curvature samples on ``sigma_i = L i / n``.
    length : float
        ``L``.
    iterations : int
        Fixed-point steps of the inversion.

    Returns
    -------
    HandOver

    Raises
    ------
    ValueError
        Fewer than four fronts, or an ODE of another length.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import splice_polygon
    >>> from qsa.reduction import FrontODE
    >>> eq = splice_polygon(np.radians([130, 120, 110]), [0.3, 0.4, 0.5], 0.1, kstar=5.0)
    >>> ode = FrontODE(0.1, 5.0, eq.params["L"], backend="numpy")
    >>> p = np.array(eq.params["positions"])
    >>> h = hand_over(ode, ode.profile(p)(ode.sigma), ode.length)
    >>> bool(np.max(np.abs(h.positions - p)) < 1e-8), h.order.tolist()
    (True, [0, 1, 2, 3, 4, 5])
    """
    L = float(length)
    if abs(L - ode.length) > 1e-12 * L:
        raise ValueError(f"the ODE's length {ode.length!r} is not the profile's {L!r}: "
                         "build FrontODE(length=L)")
    f = detect_fronts(np.asarray(kappa, dtype=float), ode.front.kstar, L)
    if f.n < 4:
        raise ValueError(f"need at least 4 fronts to hand over, found {f.n}")
    c = f.positions.copy()
    order = np.arange(f.n)
    if f.kinds[0] == -1:  # start with an up-front: the first down-front goes to the end
        c = np.append(c[1:], c[0] + L)
        order = np.append(order[1:], 0)
    p = c.copy()
    for _ in range(int(iterations)):
        p = p + (c - _crossings_of(ode, p, L))
    p, _, _ = close_positions(p, ode.front, L, default_cutoff(p, L))
    return HandOver(p, order, c, L, float(np.max(np.abs(_crossings_of(ode, p, L) - c))))


def _crossings_of(ode, p, L):
    """The splice's crossings, each next to its ``p_j`` (unwrapped like ``p``)."""
    cr = ode.crossings(p)
    d = (cr[None, :] - p[:, None] + 0.5 * L) % L - 0.5 * L
    return p + d[np.arange(p.size), np.argmin(np.abs(d), axis=1)]
