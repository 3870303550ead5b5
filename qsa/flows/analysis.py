"""Diagnostics of simulated curves: fronts, symmetry, paired sheets, self-intersection.

These measure the quantities the paper reports for its simulations
(figures f:facet, f:facet_energy, f:Snowflake, f:fold):

* ``front_crossings`` / ``count_fronts``: fronts of a faceted state, i.e.
  crossings of ``kappa(s)`` through the mid-level ``kappa*/2`` between the wells
  ``0`` and ``kappa*`` (with a hysteresis band, so noise near the level is not
  counted);
* ``functional_residual``: the paper's ``R_kappa`` -- the spread of the
  chemical potential ``mu = d_kappa E = -alpha^2 Delta_s kappa + W'(kappa)``
  (constant at an equilibrium, Conventions and errata, section 5);
* ``rotation_defect`` and ``curvature_shift_defect``: how far a curve is from
  ``k``-fold rotational symmetry;
* ``paired_sheets``: near-contact pairs of anti-parallel strands of a curve and
  their separation (the optimal separation is ``l* sqrt(a^2 + 1/2)``,
  Conventions and errata, section 6);
* ``closest_approach`` and :class:`SelfIntersectionMonitor`: distance between
  non-neighbouring parts of a curve and polygon crossings along a flow.

All functions take node positions ``x, y`` (shape (N,), counter-clockwise) or
nodal curvatures on the uniform parameter grid ``s_j = j/N``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from qsa.curve import self_intersections

__all__ = [
    "front_crossings",
    "count_fronts",
    "functional_residual",
    "facet_lengths",
    "rotation_defect",
    "curvature_shift_defect",
    "polygon_normals",
    "closest_approach",
    "SheetPairs",
    "paired_sheets",
    "SelfIntersectionMonitor",
]


def _xy(x, y):
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.ndim != 1 or x.shape != y.shape or x.size < 3:
        raise ValueError(f"x and y must be 1-d arrays of equal length >= 3, got {x.shape}, "
                         f"{y.shape}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("x, y contain NaN or inf")
    return x, y


# ------------------------------------------------------------------ fronts
def front_crossings(kappa, level, band=0.1):
    """Fronts of a periodic curvature profile: crossings of ``level`` with hysteresis.

    A node is *high* when ``kappa > level + band`` and *low* when
    ``kappa < level - band``; a front is a change between high and low along the
    periodic grid, placed where the linear interpolant crosses ``level`` (the
    last crossing before the change, so a front that wiggles inside the band is
    counted once).

    Parameters
    ----------
    kappa : array_like, shape (N,)
        Curvature at ``s_j = j/N``.
    level : float
        Mid-level, ``kappa*/2`` for the faceting well.
    band : float
        Half-width of the hysteresis band (absolute), ``>= 0``.

    Returns
    -------
    s : ndarray, shape (n,)
        Front positions in ``[0, 1)``, sorted.
    sign : ndarray of int, shape (n,)
        ``+1`` for an up-front (low to high), ``-1`` for a down-front. Signs
        alternate, so ``n`` is even.
    """
    kappa = np.asarray(kappa, dtype=float)
    if kappa.ndim != 1 or kappa.size < 3 or not np.all(np.isfinite(kappa)):
        raise ValueError("kappa must be a finite 1-d array with at least 3 entries")
    if not band >= 0:
        raise ValueError(f"band must be >= 0, got {band!r}")
    N = kappa.size
    state = np.zeros(N, dtype=int)
    state[kappa > level + band] = 1
    state[kappa < level - band] = -1
    known = np.flatnonzero(state)
    if known.size == 0:
        return np.zeros(0), np.zeros(0, dtype=int)
    # walk once around the loop, starting just after a node of known state
    start = known[0]
    order = (start + np.arange(1, N + 1)) % N
    cur = state[start]
    s_out, sign_out = [], []
    for j in order:
        if state[j] != 0 and state[j] != cur:
            # last crossing of the level between the previous known node and j
            i = j
            while True:
                im = (i - 1) % N
                a, b = kappa[im] - level, kappa[i] - level
                if a == 0 or a * b < 0 or im == start:
                    break
                i = im
            frac = a / (a - b) if a != b else 0.0
            s_out.append(((im + frac) / N) % 1.0)
            sign_out.append(int(state[j]))
            cur = state[j]
    s_out = np.asarray(s_out)
    sign_out = np.asarray(sign_out, dtype=int)
    o = np.argsort(s_out)
    return s_out[o], sign_out[o]


def count_fronts(kappa, level, band=0.1):
    """Number of fronts of ``kappa(s)`` (see :func:`front_crossings`); always even."""
    return int(front_crossings(kappa, level, band)[0].size)


def functional_residual(mu, weights=None):
    """The paper's functional residual ``R_kappa``: spread of ``mu = d_kappa E`` about its mean.

    ``R = max_j |mu_j - <mu>|`` with ``<mu>`` the ``dsigma``-weighted mean. It
    vanishes at an equilibrium of the faceting flow (``mu = -nu1`` constant,
    Conventions and errata, section 5) and is exponentially small between coarsening events.

    Parameters
    ----------
    mu : array_like, shape (N,)
    weights : array_like, shape (N,), optional
        Quadrature weights (uniform by default).
    """
    mu = np.asarray(mu, dtype=float)
    w = np.ones_like(mu) if weights is None else np.asarray(weights, dtype=float)
    return float(np.max(np.abs(mu - np.sum(mu * w) / np.sum(w))))


def facet_lengths(s, sign, L):
    """Arc lengths of the corners (``kappa`` high) and facets (``kappa`` low).

    Parameters
    ----------
    s, sign : ndarray
        Output of :func:`front_crossings` (alternating signs).
    L : float
        Curve length.

    Returns
    -------
    corners, facets : ndarray
        Arc length of each high interval (up-front to the next down-front) and
        each low interval, in the order of their starting fronts.
    """
    s = np.asarray(s, dtype=float)
    sign = np.asarray(sign)
    n = s.size
    if n == 0:
        return np.zeros(0), np.zeros(0)
    gaps = (np.roll(s, -1) - s) % 1.0 * L
    if n == 1:
        gaps = np.array([L])
    return gaps[sign > 0], gaps[sign < 0]


# ---------------------------------------------------------------- symmetry
def _area_centroid(x, y):
    xp, yp = np.roll(x, -1), np.roll(y, -1)
    cross = x * yp - xp * y
    A = 0.5 * np.sum(cross)
    return np.sum((x + xp) * cross) / (6 * A), np.sum((y + yp) * cross) / (6 * A)


def _distance_to_polygon(px, py, x, y):
    """Distance from each point ``(px, py)`` to the closed polygon through ``(x, y)``."""
    N = x.size
    tree = cKDTree(np.column_stack([x, y]))
    _, near = tree.query(np.column_stack([px, py]), k=min(4, N))
    near = np.atleast_2d(near)
    best = np.full(px.size, np.inf)
    for col in range(near.shape[1]):
        for seg in (near[:, col], (near[:, col] - 1) % N):
            ax, ay = x[seg], y[seg]
            bx, by = x[(seg + 1) % N], y[(seg + 1) % N]
            ex, ey = bx - ax, by - ay
            t = np.clip(((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey), 0.0, 1.0)
            best = np.minimum(best, np.hypot(ax + t * ex - px, ay + t * ey - py))
    return best


def rotation_defect(x, y, k=3):
    """Distance of a closed curve from ``k``-fold rotational symmetry, relative to its size.

    The polygon is rotated by ``2 pi / k`` about its area centroid; the defect
    is the largest distance from a rotated node to the unrotated polygon,
    divided by the mean radius ``L / (2 pi)``. Translation and rotation of the
    curve do not change it; it is zero (up to the polygon's O(h^2 kappa)
    sagitta) exactly when the curve is ``k``-fold symmetric.

    Parameters
    ----------
    x, y : array_like, shape (N,)
    k : int
        Order of the rotation, ``>= 2``.

    Returns
    -------
    float
    """
    x, y = _xy(x, y)
    if int(k) != k or k < 2:
        raise ValueError(f"k must be an integer >= 2, got {k!r}")
    cx, cy = _area_centroid(x, y)
    c, s = np.cos(2 * np.pi / k), np.sin(2 * np.pi / k)
    rx = cx + c * (x - cx) - s * (y - cy)
    ry = cy + s * (x - cx) + c * (y - cy)
    L = np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y))
    return float(np.max(_distance_to_polygon(rx, ry, x, y)) / (L / (2 * np.pi)))


def curvature_shift_defect(kappa, k=3):
    """``max_s |kappa(s + 1/k) - kappa(s)| / max |kappa|`` at constant arc length.

    At scaled arc length a ``k``-fold symmetric curve has ``kappa`` periodic
    with period ``1/k`` in ``s`` whatever its starting point, so no phase needs
    fitting. The shift is exact when ``k`` divides ``N`` and uses the
    trigonometric interpolant otherwise. Sharp fronts make this measure
    sensitive: a front displaced by ``delta`` in arc length changes it by
    about ``max|kappa'| delta / max|kappa|``.
    """
    kappa = np.asarray(kappa, dtype=float)
    N = kappa.size
    if int(k) != k or k < 2:
        raise ValueError(f"k must be an integer >= 2, got {k!r}")
    if N % k == 0:
        shifted = np.roll(kappa, -N // k)
    else:
        f = np.fft.rfft(kappa)
        m = np.arange(f.size)
        shifted = np.fft.irfft(f * np.exp(2j * np.pi * m / k), N)
    return float(np.max(np.abs(shifted - kappa)) / np.max(np.abs(kappa)))


# ------------------------------------------------------------ near contact
def polygon_normals(x, y):
    """Outward unit normals at the nodes (centred tangent rotated by ``-pi/2``), shape (2, N)."""
    tx = np.roll(x, -1) - np.roll(x, 1)
    ty = np.roll(y, -1) - np.roll(y, 1)
    t = np.hypot(tx, ty)
    return np.array([ty / t, -tx / t])


def _nonlocal_pairs(x, y, radius, exclude_arc):
    """Node pairs closer than ``radius`` and more than ``exclude_arc`` apart along the curve."""
    N = x.size
    h = np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)) / N
    pairs = cKDTree(np.column_stack([x, y])).query_pairs(radius, output_type="ndarray")
    if pairs.size == 0:
        return np.zeros((0, 2), dtype=np.intp)
    gap = np.abs(pairs[:, 0] - pairs[:, 1])
    gap = np.minimum(gap, N - gap) * h
    return pairs[gap > exclude_arc]


def closest_approach(x, y, exclude_arc):
    """Smallest distance between two nodes more than ``exclude_arc`` apart in arc length.

    Returns ``inf`` when no such pair is closer than ``2 exclude_arc``.
    """
    x, y = _xy(x, y)
    pairs = _nonlocal_pairs(x, y, 2 * exclude_arc, exclude_arc)
    if pairs.size == 0:
        return float("inf")
    return float(np.min(np.hypot(x[pairs[:, 0]] - x[pairs[:, 1]],
                                 y[pairs[:, 0]] - y[pairs[:, 1]])))


@dataclass(frozen=True)
class SheetPairs:
    """Paired sheets of a curve (see :func:`paired_sheets`).

    Attributes
    ----------
    n_pairs : int
        Number of pairs of anti-parallel sheets (a sheet between two others
        belongs to two pairs).
    separations : ndarray, shape (n_pairs,)
        Median separation of each pair.
    lengths : ndarray, shape (n_pairs,)
        Arc length of each pair (along its first sheet).
    runs : list of tuple
        ``(i0, i1, j0, j1)`` node ranges (inclusive, modulo N) of the two sheets.
    separation : float
        Arc-length-weighted median of the separation at every paired node
        (``nan`` without pairs).
    n_stacked : int
        Number of nodes with partners on both sides (middle sheets of stacks of
        three or more layers).
    target : float
        The optimal separation ``l* sqrt(a^2 + 1/2)`` passed in (or ``nan``).
    min_separations : ndarray, shape (n_pairs,)
        Smallest separation of each pair: the local minimum of the distance,
        where the paper's near-contact analysis (s:NSI) places the optimal
        separation. On long flat sheets it equals the median; on short curved
        contacts the median is biased up by the diverging ends.
    mid_separations : ndarray, shape (n_pairs,)
        Separation at the middle of each pair (the node halfway along the paired
        nodes of its first sheet; the mean of the two middle nodes for an even
        count): the spacing of the paired sheets away from the regions where
        they turn apart, which is where the near-contact analysis applies. At the
        ends of a pair the sheets overshoot and diverge, so the minimum and the
        median mix in the turning regions.
    profiles : list of tuple
        ``(arc, separation)`` of each pair: the separation at the paired nodes of its
        first sheet, in order along the curve, against their arc length from the
        first of them (mean chord times the number of nodes between).
    """

    n_pairs: int
    separations: np.ndarray
    lengths: np.ndarray
    runs: list = field(default_factory=list)
    separation: float = float("nan")
    n_stacked: int = 0
    target: float = float("nan")
    min_separations: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mid_separations: np.ndarray = field(default_factory=lambda: np.zeros(0))
    profiles: list = field(default_factory=list, repr=False)

    @property
    def ratio(self) -> float:
        """``separation / target``."""
        return float(self.separation / self.target)

    def to_dict(self):
        return {
            "n_pairs": int(self.n_pairs),
            "separations": [float(v) for v in self.separations],
            "lengths": [float(v) for v in self.lengths],
            "separation": float(self.separation),
            "target": float(self.target),
            "ratio": float(self.separation / self.target) if self.target > 0 else None,
            "n_stacked_nodes": int(self.n_stacked),
            "min_separations": [float(v) for v in self.min_separations],
            "min_ratio": (float(np.min(self.min_separations) / self.target)
                          if self.n_pairs and self.target > 0 else None),
            "max_min_ratio": (float(np.max(self.min_separations) / self.target)
                              if self.n_pairs and self.target > 0 else None),
            "mid_separations": [float(v) for v in self.mid_separations],
        }


def _runs(mask):
    """Maximal runs of True in a periodic boolean array: list of (start, length)."""
    N = mask.size
    if mask.all():
        return [(0, N)]
    if not mask.any():
        return []
    start = int(np.flatnonzero(~mask)[0])
    out, cur = [], None
    for step in range(1, N + 1):
        j = (start + step) % N
        if mask[j]:
            if cur is None:
                cur = [j, 0]
            cur[1] += 1
        elif cur is not None:
            out.append(tuple(cur))
            cur = None
    if cur is not None:
        out.append(tuple(cur))
    return out


def paired_sheets(x, y, separation, *, reach=2.0, min_length=None, cos_max=-0.8):
    """Find near-contact pairs of anti-parallel sheets and measure their separation.

    A node ``i`` is *paired* with the opposite strand when a node ``j`` more
    than ``3 separation`` away along the curve lies within
    ``reach * separation`` with nearly opposite normal (``n_i . n_j < cos_max``);
    its separation is the distance from ``X_i`` to the polygon segments at
    ``j``. Paired nodes form runs along the curve; two runs paired over at
    least ``min_length`` of arc form a sheet pair.

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Counter-clockwise nodes, nearly equal chords.
    separation : float
        Expected separation (``l* sqrt(a^2 + 1/2)``); sets the search radius
        and is stored as ``target``.
    reach : float
        Search radius in units of ``separation``.
    min_length : float, optional
        Shortest sheet pair counted (default ``5 * separation``).
    cos_max : float
        Largest ``n_i . n_j`` of an anti-parallel pair.

    Returns
    -------
    SheetPairs
    """
    x, y = _xy(x, y)
    if not separation > 0:
        raise ValueError(f"separation must be positive, got {separation!r}")
    N = x.size
    min_length = 5 * separation if min_length is None else float(min_length)
    h = np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)) / N
    n = polygon_normals(x, y)
    pairs = _nonlocal_pairs(x, y, reach * separation, 3 * separation)
    empty = SheetPairs(0, np.zeros(0), np.zeros(0), [], float("nan"), 0, float(separation))
    if pairs.size == 0:
        return empty
    i = np.concatenate([pairs[:, 0], pairs[:, 1]])
    j = np.concatenate([pairs[:, 1], pairs[:, 0]])
    keep = n[0, i] * n[0, j] + n[1, i] * n[1, j] < cos_max
    i, j = i[keep], j[keep]
    if i.size == 0:
        return empty
    # perpendicular distance from X_i to the two segments at j
    best = np.full(i.size, np.inf)
    for seg in (j, (j - 1) % N):
        ax, ay = x[seg], y[seg]
        ex, ey = x[(seg + 1) % N] - ax, y[(seg + 1) % N] - ay
        t = np.clip(((x[i] - ax) * ex + (y[i] - ay) * ey) / (ex * ex + ey * ey), 0.0, 1.0)
        best = np.minimum(best, np.hypot(ax + t * ex - x[i], ay + t * ey - y[i]))
    side = np.sign((x[j] - x[i]) * n[0, i] + (y[j] - y[i]) * n[1, i])  # +1 outward partner
    dist = np.full((2, N), np.inf)
    partner = np.full((2, N), -1)
    for k, sgn in enumerate((1.0, -1.0)):
        sel = side == sgn
        order = np.argsort(-best[sel])  # smallest last: it wins the assignment
        ii, jj, dd = i[sel][order], j[sel][order], best[sel][order]
        dist[k, ii] = dd
        partner[k, ii] = jj
    paired = np.isfinite(dist).any(axis=0)
    runs = _runs(paired)
    run_of = np.full(N, -1)
    for r, (s0, ln) in enumerate(runs):
        run_of[(s0 + np.arange(ln)) % N] = r
    # group paired nodes by (own run, partner run, side)
    groups = {}
    for k in range(2):
        nodes = np.flatnonzero(np.isfinite(dist[k]))
        for node in nodes:
            key = (run_of[node], run_of[partner[k, node]], k)
            groups.setdefault(key, []).append(node)
    seps, mins, mids, lens, run_list, seen, profiles = [], [], [], [], [], set(), []
    for (ra, rb, k), nodes in sorted(groups.items()):
        if ra < 0 or rb < 0 or (rb, ra) in seen:
            continue
        nodes = np.asarray(nodes)
        if nodes.size * h < min_length:
            continue
        seen.add((ra, rb))
        seps.append(float(np.median(dist[k, nodes])))
        mins.append(float(np.min(dist[k, nodes])))
        offset = (nodes - runs[ra][0]) % N
        order = np.argsort(offset)                     # in order along the run
        along = nodes[order]
        m = along.size // 2
        mids.append(float(np.mean(dist[k, along[m - 1 + along.size % 2 : m + 1]])))
        profiles.append(((offset[order] - offset[order][0]) * h, dist[k, along]))
        lens.append(float(nodes.size * h))
        partners = partner[k, nodes]
        run_list.append((int(nodes[0]), int(nodes[-1]), int(partners.min()),
                         int(partners.max())))
    all_d = np.concatenate([dist[k][np.isfinite(dist[k])] for k in range(2)])
    stacked = int(np.sum(np.isfinite(dist).all(axis=0)))
    return SheetPairs(len(seps), np.asarray(seps), np.asarray(lens), run_list,
                      float(np.median(all_d)) if seps else float("nan"), stacked,
                      float(separation), np.asarray(mins), np.asarray(mids), profiles)


# --------------------------------------------------------- self-intersection
class SelfIntersectionMonitor:
    """Record polygon self-intersections and the closest approach along a flow.

    Call it with ``(t, x, y)`` after every accepted step. It keeps the times at
    which the node polygon crosses itself (:func:`qsa.curve.self_intersections`),
    where the first crossing happened (the state and the crossing segments),
    and, when ``exclude_arc`` is given, the time series of the closest
    approach of parts of the curve more than ``exclude_arc`` apart.

    Attributes
    ----------
    times : list of float
        Every observed time.
    crossing_times : list of float
        Times at which the polygon crossed itself.
    approach : list of float
        Closest approach at each observed time (when ``exclude_arc`` is set).
    first_crossing : dict or None
        At the first crossing: ``t``, the nodes ``x``, ``y``, the crossing
        segment pairs ``segments`` (shape (K, 2)), their arc-length gap along
        the curve ``arc_gap`` (shape (K,)) and the crossing points ``points``
        (shape (K, 2)).
    """

    def __init__(self, exclude_arc=None):
        self.exclude_arc = exclude_arc
        self.times, self.crossing_times, self.approach = [], [], []
        self.first_crossing = None

    def __call__(self, t, x, y):
        self.times.append(float(t))
        segs = self_intersections(x, y)
        if segs.shape[0]:
            self.crossing_times.append(float(t))
            if self.first_crossing is None:
                self.first_crossing = _crossing_record(t, x, y, segs)
        if self.exclude_arc is not None:
            self.approach.append(closest_approach(x, y, self.exclude_arc))

    @property
    def intersected(self) -> bool:
        return bool(self.crossing_times)

    def intervals(self):
        """Maximal time intervals ``(t_first, t_last, n_steps)`` of consecutive crossings."""
        out = []
        times = np.asarray(self.times)
        cross = np.isin(times, self.crossing_times)
        for s0, ln in _runs_linear(cross):
            out.append((float(times[s0]), float(times[s0 + ln - 1]), int(ln)))
        return out

    def summary(self):
        d = {"self_intersected": self.intersected, "n_steps_observed": len(self.times),
             "n_steps_crossing": len(self.crossing_times), "crossing_intervals": self.intervals()}
        if self.first_crossing is not None:
            fc = self.first_crossing
            d["first_crossing"] = {"t": fc["t"], "points": fc["points"].tolist(),
                                   "arc_gap": fc["arc_gap"].tolist()}
        if self.approach:
            a = np.asarray(self.approach)
            k = int(np.argmin(a))
            d["closest_approach"] = float(a[k])
            d["closest_approach_time"] = float(self.times[k])
        return d


def _crossing_record(t, x, y, segs):
    """State and geometry of a self-intersection (see :class:`SelfIntersectionMonitor`)."""
    x, y = _xy(x, y)
    N = x.size
    i, j = segs[:, 0], segs[:, 1]
    ax, ay = x[i], y[i]
    ex, ey = x[(i + 1) % N] - ax, y[(i + 1) % N] - ay
    bx, by = x[j], y[j]
    fx, fy = x[(j + 1) % N] - bx, y[(j + 1) % N] - by
    den = ex * fy - ey * fx
    safe = np.where(den == 0, 1.0, den)
    u = np.where(den == 0, 0.5, ((bx - ax) * fy - (by - ay) * fx) / safe)  # collinear: midpoint
    u = np.clip(u, 0.0, 1.0)
    points = np.column_stack([ax + u * ex, ay + u * ey])
    seg_len = np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)
    gap = j - i
    arc = np.minimum(gap, N - gap) * seg_len.mean()
    return {"t": float(t), "x": x.copy(), "y": y.copy(), "segments": segs.copy(),
            "arc_gap": arc, "points": points}


def _runs_linear(mask):
    """Runs of True in a (non-periodic) boolean array: list of (start, length)."""
    mask = np.asarray(mask, dtype=bool)
    if mask.size == 0:
        return []
    d = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    return [(int(s), int(e - s)) for s, e in zip(starts, ends, strict=True)]
