"""Closed polygons: crossings of non-adjacent edges (is a sampled curve simple?).

A curve sampled at nodes ``(x_j, y_j)`` is the closed polygon through them;
:func:`self_intersections` lists its crossing segment pairs in O(N log N) (a k-d tree
of the segment midpoints, then exact orientation tests), :func:`polygon_self_intersects`
says whether there is any, and :func:`check_simple` refuses a curve whose polygon crosses
or touches itself, naming the place. :meth:`qsa.Curve.self_intersects`, the flows' input
checks and their self-contact detection, polish and spectrum use them.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["check_simple", "polygon_self_intersects", "self_intersections"]


def polygon_self_intersects(x, y) -> bool:
    """Whether the closed polygon through ``(x_j, y_j)`` has crossing non-adjacent edges.

    Shorthand for ``self_intersections(x, y).shape[0] > 0`` (touching counts as crossing).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Vertices; the polygon closes from the last back to the first.

    Returns
    -------
    bool

    Examples
    --------
    >>> polygon_self_intersects([0, 1, 1, 0], [0, 0, 1, 1])  # a square
    False
    >>> polygon_self_intersects([0, 1, 0, 1], [0, 0, 1, 1])  # a bow tie
    True
    """
    return bool(self_intersections(x, y).shape[0])


def self_intersections(x, y):
    """Pairs of crossing segments of the closed polygon through the nodes.

    Segment ``j`` joins node ``j`` to node ``j+1`` (mod N). Two segments can only
    cross when their midpoints are closer than the sum of their half-lengths,
    so candidates come from a k-d tree query (O(N log N)); each candidate pair
    of non-adjacent segments gets an exact orientation test (touching counts
    as crossing).

    Parameters
    ----------
    x, y : ndarray, shape (N,)

    Returns
    -------
    ndarray of int, shape (K, 2)
        Crossing pairs ``(i, j)``, ``i < j``; empty for a simple polygon.

    Examples
    --------
    >>> import numpy as np
    >>> t = 2 * np.pi * np.arange(40) / 40
    >>> self_intersections(np.cos(t), np.sin(t)).shape
    (0, 2)
    >>> self_intersections(np.sin(t), np.sin(2 * t)).shape[0] > 0   # figure eight
    True
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    N = x.size
    xp, yp = np.roll(x, -1), np.roll(y, -1)
    half = 0.5 * np.hypot(xp - x, yp - y)
    mid = np.column_stack([0.5 * (x + xp), 0.5 * (y + yp)])
    pairs = cKDTree(mid).query_pairs(2 * half.max() * (1 + 1e-9), output_type="ndarray")
    if pairs.size == 0:
        return np.zeros((0, 2), dtype=np.intp)
    i, j = np.minimum(pairs[:, 0], pairs[:, 1]), np.maximum(pairs[:, 0], pairs[:, 1])
    gap = j - i
    keep = (gap != 1) & (gap != N - 1)  # adjacent segments share a node
    i, j = i[keep], j[keep]

    def orient(ax, ay, bx, by, cx, cy):
        return np.sign((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))

    P = (x[i], y[i], xp[i], yp[i])
    Q = (x[j], y[j], xp[j], yp[j])
    o1 = orient(*P, Q[0], Q[1])
    o2 = orient(*P, Q[2], Q[3])
    o3 = orient(*Q, P[0], P[1])
    o4 = orient(*Q, P[2], P[3])
    cross = (o1 * o2 <= 0) & (o3 * o4 <= 0)
    # collinear non-overlapping segments give all-zero orientations: check overlap
    col = (o1 == 0) & (o2 == 0)
    if np.any(col):
        lo = lambda a, b: np.minimum(a, b)
        hi = lambda a, b: np.maximum(a, b)
        ovx = (lo(P[0], P[2]) <= hi(Q[0], Q[2])) & (lo(Q[0], Q[2]) <= hi(P[0], P[2]))
        ovy = (lo(P[1], P[3]) <= hi(Q[1], Q[3])) & (lo(Q[1], Q[3]) <= hi(P[1], P[3]))
        cross = np.where(col, ovx & ovy, cross)
    out = np.column_stack([i[cross], j[cross]]).astype(np.intp)
    return out[np.lexsort((out[:, 1], out[:, 0]))] if out.size else out


def check_simple(c, name="curve", rel=1e-9) -> None:
    """Raise ``ValueError`` if the node polygon of a curve crosses or touches itself.

    A crossing is a pair of non-adjacent segments that intersect
    (:func:`self_intersections`, touching included); a touching pair is two nodes that
    are not neighbours along the curve yet closer than ``rel L``. The message names the
    closest such pair by node index, parameter ``s`` and position, so the user can see
    where the curve meets itself.

    Parameters
    ----------
    c : Curve
        (anything with ``positions()``, ``N``, ``grid.s`` and ``length()``).
    name : str
        The argument named in the message.
    rel : float
        Touching distance relative to the length ``L``.

    Returns
    -------
    None

    Raises
    ------
    ValueError
        The curve crosses or touches itself.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> check_simple(Curve.circle(1.0, Fourier(33)))
    >>> twice = Curve(np.full(129, 1.0), 4 * np.pi, Fourier(129))  # a circle run round twice
    >>> check_simple(twice)
    Traceback (most recent call last):
    ...
    ValueError: curve crosses itself: segments 43 and 108 (s = 0.3333 and 0.8372) meet near ...
    """
    x, y = c.positions()
    N = c.N
    s = c.grid.s
    cross = self_intersections(x, y)
    if cross.shape[0]:
        # the crossing pair whose node midpoints are closest
        i, j = cross[:, 0], cross[:, 1]
        mx = 0.5 * (x[i] + x[(i + 1) % N] - x[j] - x[(j + 1) % N])
        my = 0.5 * (y[i] + y[(i + 1) % N] - y[j] - y[(j + 1) % N])
        k = int(np.argmin(np.hypot(mx, my)))
        a, b = int(i[k]), int(j[k])
        px = 0.25 * (x[a] + x[(a + 1) % N] + x[b] + x[(b + 1) % N])
        py = 0.25 * (y[a] + y[(a + 1) % N] + y[b] + y[(b + 1) % N])
        more = f" ({cross.shape[0]} crossing pairs in all)" if cross.shape[0] > 1 else ""
        raise ValueError(
            f"{name} crosses itself: segments {a} and {b} (s = {s[a]:.4g} and {s[b]:.4g}) "
            f"meet near ({px:.4g}, {py:.4g}){more}; equilibria and spectra need a simple "
            "closed curve")
    L = c.length()
    pairs = cKDTree(np.column_stack([x, y])).query_pairs(rel * L, output_type="ndarray")
    if pairs.size:
        gap = np.abs(pairs[:, 0] - pairs[:, 1])
        pairs = pairs[(gap > 1) & (gap < N - 1)]
    if pairs.size:
        d = np.hypot(x[pairs[:, 0]] - x[pairs[:, 1]], y[pairs[:, 0]] - y[pairs[:, 1]])
        a, b = (int(v) for v in sorted(pairs[int(np.argmin(d))]))
        raise ValueError(
            f"{name} touches itself: nodes {a} and {b} (s = {s[a]:.4g} and {s[b]:.4g}) are "
            f"{d.min():.3g} apart near ({x[a]:.4g}, {y[a]:.4g}); equilibria and spectra need "
            "a simple closed curve")
