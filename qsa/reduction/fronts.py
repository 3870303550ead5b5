"""Fronts of a faceted curvature profile: detection, tracking, coarsening events.

A *front* is a transition layer of ``kappa`` between the wells 0 (facets) and
``kstar`` (corners) of the faceting energy (section "Formal Equilibrium and
Quasi-Steady Analysis", e:psi_h). Its position is the arc length where
``kappa`` crosses the mid-level ``kstar / 2`` -- for the heteroclinic
``psi_h(0) = kstar / 2`` this is exactly the front centre ``p_i`` of the splice
``psi_N`` (e:psi_N) up to the exponentially small tails of its neighbours.

* :func:`detect_fronts` finds the crossings on uniform periodic samples with
  sub-grid accuracy: a sign change between nodes ``j`` and ``j + 1`` is refined
  on the cubic through nodes ``j - 1 .. j + 2`` (error ``O(h^4)`` for smooth
  ``kappa``). An *up*-front (``kind = +1``) has ``kappa`` increasing (facet to
  corner), a *down*-front (``kind = -1``) decreasing.
* :func:`track_fronts` follows the fronts through a sequence of snapshots
  (nearest front of the same kind, periodic distance, unwrapped positions).
  Fronts of a faceting flow only disappear in pairs: an up- and a down-front
  meet and annihilate when a facet or a corner shrinks away (coarsening). Such
  a pair becomes a :class:`CoarseningEvent`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Fronts", "FrontTracks", "CoarseningEvent", "detect_fronts", "track_fronts",
           "track_flow"]


@dataclass(frozen=True)
class Fronts:
    """Fronts of one curvature profile.

    Attributes
    ----------
    positions : ndarray, shape (n,)
        Arc lengths of the crossings of ``level``, increasing, in ``[0, L)``.
    kinds : ndarray of int, shape (n,)
        ``+1`` up-front (kappa increases), ``-1`` down-front.
    length : float
        Total length ``L``.
    level : float
    spacing : float
        Sample spacing ``L / N``.
    """

    positions: np.ndarray
    kinds: np.ndarray
    length: float
    level: float
    spacing: float = np.nan

    @property
    def n(self) -> int:
        """Number of fronts."""
        return int(self.positions.size)

    def gaps(self) -> np.ndarray:
        """Arc lengths from each front to the next (periodically), shape (n,)."""
        p = self.positions
        return np.diff(np.append(p, p[0] + self.length)) if p.size else p.copy()


def _as_kappa(kappa, length):
    """``(kappa, L)`` from a Curve or from samples plus a length."""
    if hasattr(kappa, "kappa") and hasattr(kappa, "length"):
        return np.asarray(kappa.kappa, dtype=float), float(kappa.length())
    k = np.asarray(kappa, dtype=float)
    if k.ndim != 1 or k.size < 4:
        raise ValueError(f"kappa must be 1-d with at least 4 samples, got shape {k.shape}")
    if not np.all(np.isfinite(k)):
        raise ValueError("kappa contains NaN or inf")
    L = 1.0 if length is None else float(length)
    if not (np.isfinite(L) and L > 0):
        raise ValueError(f"length must be positive, got {length!r}")
    return k, L


def detect_fronts(kappa, kstar, length=None, level=None):
    """Crossings of ``kstar / 2`` by a periodic curvature profile, with sub-grid accuracy.

    Parameters
    ----------
    kappa : ndarray, shape (N,) or Curve
        Samples at ``s_j = j / N`` (uniform in arc length, ``sigma = L s``), or a
        ``Curve`` with constant ``g`` (its ``kappa`` and ``length()`` are used).
    kstar : float
        The corner curvature (second well).
    length : float, optional
        ``L`` for sample input (default 1: positions in ``s``).
    level : float, optional
        Crossing level, default ``kstar / 2``.

    Returns
    -------
    Fronts

    Raises
    ------
    ValueError
        Bad samples, length or kstar.

    Examples
    --------
    >>> import numpy as np
    >>> s = np.arange(200) / 200
    >>> f = detect_fronts(np.where((s > 0.2) & (s < 0.6), 5.0, 0.0) + 0 * s, 5.0)
    >>> f.kinds.tolist()
    [1, -1]
    """
    k, L = _as_kappa(kappa, length)
    if not (np.isfinite(kstar) and kstar > 0):
        raise ValueError(f"kstar must be positive, got {kstar!r}")
    c = 0.5 * kstar if level is None else float(level)
    N = k.size
    f = k - c
    j = np.nonzero((f >= 0) != (np.roll(f, -1) >= 0))[0]
    if j.size == 0:
        return Fronts(np.zeros(0), np.zeros(0, dtype=int), L, c, L / N)
    idx = (j[:, None] + np.arange(-1, 3)) % N
    v = f[idx]  # values at t = -1, 0, 1, 2
    # Lagrange cubic on t in [0, 1]; bisection keeps the bracket of the sign change
    def cubic(t):
        return (-v[:, 0] * t * (t - 1) * (t - 2) / 6 + v[:, 1] * (t + 1) * (t - 1) * (t - 2) / 2
                - v[:, 2] * (t + 1) * t * (t - 2) / 2 + v[:, 3] * (t + 1) * t * (t - 1) / 6)

    lo, hi = np.zeros(j.size), np.ones(j.size)
    sign_lo = v[:, 1] >= 0
    for _ in range(52):
        mid = 0.5 * (lo + hi)
        same = (cubic(mid) >= 0) == sign_lo
        lo = np.where(same, mid, lo)
        hi = np.where(same, hi, mid)
    t = 0.5 * (lo + hi)
    pos = (L / N) * ((j + t) % N)
    kinds = np.where(v[:, 2] > v[:, 1], 1, -1)
    order = np.argsort(pos)
    return Fronts(pos[order], kinds[order].astype(int), L, c, L / N)


@dataclass(frozen=True)
class CoarseningEvent:
    """An up- and a down-front that annihilated between two snapshots.

    Attributes
    ----------
    time : float
        Estimated annihilation time (mid-point of the two snapshots).
    bracket : (float, float)
        Times of the last snapshot with and the first without the pair.
    fronts : (int, int)
        Track indices of the pair.
    position : float
        Mean (unwrapped) arc length of the pair at its last sighting.
    gap : float
        Their distance at the last sighting.
    """

    time: float
    bracket: tuple
    fronts: tuple
    position: float
    gap: float


@dataclass(frozen=True)
class FrontTracks:
    """Front positions through a sequence of snapshots.

    Attributes
    ----------
    t : ndarray, shape (n_t,)
    positions : ndarray, shape (n_t, n_fronts)
        Unwrapped arc lengths (continuous in time); NaN once a front is gone.
    kinds : ndarray of int, shape (n_fronts,)
    lengths : ndarray, shape (n_t,)
        ``L`` at each snapshot.
    events : list of CoarseningEvent
        In time order.
    unmatched : int
        Fronts that disappeared or appeared other than as annihilating pairs
        (0 for a clean coarsening history).
    """

    t: np.ndarray
    positions: np.ndarray
    kinds: np.ndarray
    lengths: np.ndarray
    events: list = field(default_factory=list)
    unmatched: int = 0

    @property
    def first_collision(self):
        """The first :class:`CoarseningEvent`, or None."""
        return self.events[0] if self.events else None

    def alive(self, i) -> np.ndarray:
        """Track indices alive at snapshot ``i``."""
        return np.nonzero(np.isfinite(self.positions[i]))[0]


def _wrapdiff(a, b, L):
    return (a - b + 0.5 * L) % L - 0.5 * L


def _cyclic(cur, kinds, pos, nkinds, L):
    """Best cyclic assignment of ``pos`` to ``cur`` (same count, kinds agree): (shift, cost)."""
    n = len(cur)
    best = (None, np.inf)
    for k in range(n):
        idx = (np.arange(n) + k) % n
        if np.any(nkinds[idx] != kinds):
            continue
        cost = np.max(np.abs(_wrapdiff(pos[idx], cur, L)))
        if cost < best[1]:
            best = (k, cost)
    return best


def _match_in_order(cur, kinds, new, max_jump):
    """Fronts keep their cyclic order: match all, or all but one adjacent annihilated pair.

    Returns ``{a: (b, unwrapped position)}`` for the current fronts ``a`` that survive
    (an annihilated pair is left out), or None when neither case fits.
    """
    n, L = len(cur), new.length
    kinds = np.asarray(kinds)
    cur = np.asarray(cur, dtype=float)
    if n == 0 or new.n not in (n, n - 2):
        return None
    keeps = [np.arange(n)] if new.n == n else [
        np.setdiff1d(np.arange(n), [a, (a + 1) % n]) for a in range(n)
        if kinds[a] != kinds[(a + 1) % n]]
    best = (None, None, np.inf)
    for keep in keeps:
        k, cost = _cyclic(cur[keep], kinds[keep], new.positions, new.kinds, L)
        if k is not None and cost < best[2]:
            best = (keep, k, cost)
    keep, k, cost = best
    if keep is None or (max_jump is not None and cost > max_jump):
        return None
    m = len(keep)
    out = {}
    for j, a in enumerate(keep):
        b = (j + k) % m
        out[int(a)] = (b, cur[a] + _wrapdiff(new.positions[b], cur[a], L))
    return out


def _match_nearest(cur, live, kinds, new, prev, max_jump, taken):
    """Fallback: nearest unclaimed front of the same kind within a jump bound."""
    L = new.length
    jump = max_jump
    if jump is None:
        prev_gaps = prev.gaps()
        jump = 0.25 * prev_gaps.min() if prev_gaps.size else np.inf
        jump = max(jump, 4 * new.spacing)
    matched = {}
    for a, tr in enumerate(live):
        if new.n == 0:
            break
        d = np.where((new.kinds == kinds[tr]) & ~taken,
                     np.abs(_wrapdiff(new.positions, cur[a], L)), np.inf)
        b = int(np.argmin(d))
        if d[b] <= jump:
            taken[b] = True
            matched[tr] = cur[a] + _wrapdiff(new.positions[b], cur[a], L)
    return matched


def track_fronts(times, kappas, kstar, lengths=None, max_jump=None):
    """Follow the fronts of successive curvature profiles.

    Parameters
    ----------
    times : array_like, shape (n_t,)
        Increasing snapshot times.
    kappas : sequence of ndarray (each shape (N_i,)) or of Curve
    kstar : float
    lengths : array_like, shape (n_t,), optional
        ``L`` at each snapshot (sample input; default 1).
    max_jump : float, optional
        Largest move of a front between snapshots that still counts as the same
        front. Fronts keep their cyclic order, so by default an in-order match
        of all fronts, or of all but one adjacent annihilated pair, is accepted
        whatever the moves; other changes fall back to nearest-front matching
        within a quarter of the smallest previous gap.

    Returns
    -------
    FrontTracks

    Raises
    ------
    ValueError
        Times not increasing or lengths of the wrong size.
    """
    t = np.asarray(times, dtype=float)
    if t.ndim != 1 or t.size != len(kappas) or np.any(np.diff(t) <= 0):
        raise ValueError("times must increase strictly and match the number of snapshots")
    if lengths is not None and len(lengths) != t.size:
        raise ValueError("lengths must have one entry per snapshot")
    snaps = [detect_fronts(k, kstar, None if lengths is None else lengths[i])
             for i, k in enumerate(kappas)]
    first = snaps[0]
    kinds = list(first.kinds)
    rows = [list(first.positions)]
    live = list(range(first.n))  # track index of each current front (unwrapped positions)
    cur = np.array(first.positions)
    events, unmatched = [], 0
    for i in range(1, t.size):
        new = snaps[i]
        row = [np.nan] * len(kinds)
        taken = np.zeros(new.n, dtype=bool)
        matched = _match_in_order(cur, [kinds[tr] for tr in live], new, max_jump)
        if matched is not None:
            matched = {live[a]: pos for a, (b, pos) in matched.items()}
            taken[:] = True
        else:
            matched = _match_nearest(cur, live, kinds, new, snaps[i - 1], max_jump, taken)
        lost = [tr for tr in live if tr not in matched]
        # annihilated pairs: lost fronts of opposite kinds that were neighbours
        order = sorted(lost, key=lambda tr: rows[-1][tr])
        paired = set()
        for a in range(len(order)):
            for b in range(a + 1, len(order)):
                ta, tb = order[a], order[b]
                if ta in paired or tb in paired or kinds[ta] == kinds[tb]:
                    continue
                pa, pb = rows[-1][ta], rows[-1][tb]
                gap = abs((pb - pa + 0.5 * snaps[i - 1].length) % snaps[i - 1].length
                          - 0.5 * snaps[i - 1].length)
                paired.update((ta, tb))
                events.append(CoarseningEvent(0.5 * (t[i - 1] + t[i]), (t[i - 1], t[i]),
                                              (min(ta, tb), max(ta, tb)), 0.5 * (pa + pb), gap))
        unmatched += len(lost) - len(paired) + int(np.count_nonzero(~taken))
        for tr, pos in matched.items():
            row[tr] = pos
        rows.append(row)
        live = [tr for tr in live if tr in matched]
        cur = np.array([matched[tr] for tr in live])
    return FrontTracks(t, np.array(rows, dtype=float), np.array(kinds, dtype=int),
                       np.array([s.length for s in snaps]), events, unmatched)


def track_flow(result, kstar, max_jump=None):
    """:func:`track_fronts` on the snapshots of a flow result.

    Parameters
    ----------
    result : FlowResult-like
        With ``t`` and ``states`` (a sequence of ``Curve``), or ``t``, ``kappa``
        (shape (n_t, N)) and ``L`` (shape (n_t,)).
    kstar : float

    Returns
    -------
    FrontTracks
    """
    if hasattr(result, "kappa") and hasattr(result, "L"):
        return track_fronts(result.t, list(np.asarray(result.kappa)), kstar, list(result.L),
                            max_jump)
    states = list(result.states)
    return track_fronts(result.t, states, kstar, None, max_jump)
