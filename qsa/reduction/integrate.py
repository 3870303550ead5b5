r"""Integration of the front-position ODE through collisions, and its result types.

:func:`integrate_fronts` (behind :meth:`qsa.reduction.FrontODE.integrate`) integrates
``p' = F(p)`` with :func:`scipy.integrate.solve_ivp` until a pair of neighbouring
fronts collides, removes the pair, closes the remaining positions again and goes on.

*Collisions.* When two neighbouring fronts come within ``d_c`` -- the spacing at which
the superposed pair no longer crosses ``kstar / 2`` (:func:`collision_distance`,
``2 ln 3 / lambda`` for the quartic well) -- the splice manifold ends: the pair is
removed, its turning is given to the neighbouring corners (:func:`remove_pair`: the
total turning is conserved and, as in the flow, stays where it was), and by default
(``redistribute="project"``) the ODE restarts from the closed splice of the surviving
fronts nearest the curve at the collision in the flow's metric, the ``L^2(dsigma)``
norm of the normal displacement modulo rigid motions
(:func:`qsa.reduction.projection.nearest_splice`, a few Gauss-Newton steps from the
removal's positions): the curve then is not a splice of the surviving fronts, and
the flow relaxes it onto the slow manifold along directions orthogonal to the
manifold in that metric. The remaining positions are closed again (minimum-norm
Gauss-Newton, :func:`qsa.equilibria.close_positions`) and the integration continues.
On f:facet (12 -> 6 fronts from the DAE's first quasi-steady state) the restart by
projection puts the three events at +2.8%, -0.7% and +1.2% of the DAE's times
(N = 1200; the first is before any restart), against +2.8%, -14% and -5.7% for the
removal alone (``"local"``).

*Validity.* The reduction neglects the slaving of the fast modes (the perimeter mode,
rate ``~ 2 pi beta / R``, is the slowest of them) and the deviation of the true slow
manifold from the splices. A relative error ``eps`` of the interaction rate is
exponentially amplified near a collision: a pair closing as ``d' = -c exp(-lambda d)``,
i.e. ``exp(lambda d(t)) = exp(lambda d_0) - lambda c t`` and
``t_c = (exp(lambda d_0) - 1) / (lambda c)``, with rate ``c (1 + eps)`` is off by ::

    (eps / lambda) (t / t_c) / (1 - t / t_c)

at time ``t`` (first order in ``eps``; :func:`collision_sensitivity`, tested against
the exact pair law), finite for ``t < t_c`` but unbounded at the collision itself.
Position agreement *up to* the collision therefore needs ``eps`` far below 1%; a few
per cent of rate error is already a several-per-cent collision-time error and, at
``t -> t_c``, an O(facet) position error -- the DAE itself shows it between
resolutions.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from qsa.equilibria.splice import close_positions, default_cutoff
from qsa.reduction.projection import nearest_splice

__all__ = ["FrontODEResult", "ODECollision", "ODESegment", "collision_distance",
           "collision_sensitivity", "integrate_fronts", "remove_pair", "STIFF_AUTO",
           "MESSAGES"]

#: Meaning of :attr:`FrontODEResult.status` (0 success, positive: success with a caveat,
#: negative: failure); :attr:`FrontODEResult.message` starts with the entry.
MESSAGES = {
    0: "reached t_final",
    1: "stopped after collision: fewer than 4 fronts left, or max_collisions reached",
    -1: "solve_ivp failed",
}


#: ``method="auto"`` of :func:`integrate_fronts` switches to Radau above this
#: ``|dL'/dL| * interval`` (RK45's stability limit makes it take ``~|mu| T / 3.3`` steps).
STIFF_AUTO = 100.0


def collision_distance(front):
    """Spacing ``d_c`` at which a superposed pair of opposite fronts stops crossing ``kstar/2``.

    Solves ``psi_h(d/2) - psi_h(-d/2) = kstar / 2`` (the profile at the midpoint
    of the pair); ``2 ln 3 / lambda`` for the quartic well.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import heteroclinic
    >>> front = heteroclinic(0.1, kstar=5.0)
    >>> bool(np.isclose(collision_distance(front), 2 * np.log(3) / front.decay_rate))
    True
    """
    k = front.kstar
    return brentq(lambda d: front(0.5 * d) - front(-0.5 * d) - 0.5 * k, 1e-12 * front.width,
                  50 * front.width, xtol=1e-14 * front.width)


def collision_sensitivity(eps, t, t_c, lam):
    """Position error ``(eps / lam) (t/t_c) / (1 - t/t_c)`` from a relative rate error ``eps``.

    For a pair closing as ``d' = -c exp(-lam d)`` (``t_c`` its collision time), a
    model with rate ``c (1 + eps)`` is off by this much at time ``t`` (first order
    in ``eps``).
    """
    x = np.asarray(t, dtype=float) / t_c
    return eps / lam * x / (1 - x)


@dataclass(frozen=True)
class ODESegment:
    """A piece of a :class:`FrontODEResult` between collisions.

    Attributes
    ----------
    t : ndarray, shape (n_t,)
    p : ndarray, shape (n_t, n_fronts)
        Positions of the fronts alive in this segment.
    ids : ndarray of int, shape (n_fronts,)
        Track indices (positions in the initial ``p0``) of the columns of ``p``.
    cutoff : (float, float)
        The cutoff used in this segment.
    L : ndarray, shape (n_t,)
        The length (constant at a fixed length).
    """

    t: np.ndarray
    p: np.ndarray
    ids: np.ndarray
    cutoff: tuple
    L: np.ndarray


@dataclass(frozen=True)
class ODECollision:
    """A pair removed by :meth:`FrontODE.integrate`.

    Attributes
    ----------
    time : float
    fronts : (int, int)
        Track indices (positions in the initial ``p0``) of the pair.
    gap : float
        Their spacing at removal (``= d_c``).
    positions : ndarray
        All positions at the collision.
    ids : ndarray
        Track indices of ``positions``.
    """

    time: float
    fronts: tuple
    gap: float
    positions: np.ndarray
    ids: np.ndarray


@dataclass(frozen=True)
class FrontODEResult:
    """Result of :meth:`FrontODE.integrate`.

    Attributes
    ----------
    segments : list of ODESegment
        Pieces between collisions.
    events : list of ODECollision
    success : bool
        ``status >= 0``.
    status : int
        A key of :data:`MESSAGES`: 0 reached ``t_final``; 1 stopped after a collision
        left < 4 fronts (or after ``max_collisions``); -1 failed.
    message : str
        Starts with ``MESSAGES[status]``.
    n_rhs : int
        Evaluations of ``F`` (also those for the Jacobian of an implicit method;
        ``nfev`` is a read-only alias).
    elapsed : float
        Wall time in seconds.
    n_lu : int
        LU factorizations of an implicit method (0 for the explicit ones).
    """

    segments: list
    events: list
    success: bool
    status: int
    message: str
    n_rhs: int
    elapsed: float
    n_lu: int = 0

    @property
    def nfev(self) -> int:
        """Read-only alias of :attr:`n_rhs` (the former name)."""
        return self.n_rhs

    @property
    def t(self):
        """All output times, shape (n_t,)."""
        return np.concatenate([s.t for s in self.segments])

    @property
    def n_fronts(self):
        """Number of initial fronts."""
        return self.segments[0].p.shape[1]

    @property
    def positions(self):
        """Positions by initial track index, NaN after removal, shape (n_t, 2N)."""
        rows = []
        for s in self.segments:
            P = np.full((s.t.size, self.n_fronts), np.nan)
            P[:, s.ids] = s.p
            rows.append(P)
        return np.vstack(rows)

    @property
    def first_collision(self):
        """The first :class:`ODECollision`, or None."""
        return self.events[0] if self.events else None


def remove_pair(p, ids, i, length, redistribute="local"):
    """Positions after the pair ``(i, i + 1)`` (cyclically) annihilated.

    The pair is removed. Its turning, ``kstar (p_{i+1} - p_i)`` on the splice when it
    is a corner (an up-front followed by a down-front) and ``kstar`` times the
    facet's length when it is a facet (the two corners then merge into one that
    spans it), does not vanish: the total turning ``2 pi`` (e:C2) is conserved.
    With ``redistribute="local"`` it stays where it was, as in the flow, whose
    fast relaxation moves turning along the curve only over a few front widths: a
    collapsed corner's turning is added to the two neighbouring corners (half each,
    each lengthened about its centre), a merged corner is shortened about its centre
    by the facet's length. ``"uniform"`` leaves the deficit to the closure that
    follows (:func:`qsa.equilibria.close_positions`, minimum norm: spread over all
    fronts). The closure conditions still have to be re-imposed afterwards.

    Parameters
    ----------
    p : ndarray, shape (2N,)
        Positions (up, down, up, ...), increasing, spanning less than ``length``.
    ids : ndarray of int, shape (2N,)
        Track indices.
    i : int
        The pair is ``(i, (i + 1) % 2N)``.
    length : float
    redistribute : {"local", "uniform"}

    Returns
    -------
    q : ndarray, shape (2N - 2,)
        Positions, again starting with an up-front.
    qids : ndarray of int, shape (2N - 2,)

    Examples
    --------
    >>> import numpy as np
    >>> p = np.array([0.0, 0.2, 0.5, 0.52, 1.0, 1.2])  # the corner (0.5, 0.52) collapses
    >>> q, qids = remove_pair(p, np.arange(6), 2, 2.0)
    >>> np.round(q, 3).tolist(), qids.tolist()
    ([-0.005, 0.205, 0.995, 1.205], [0, 1, 4, 5])
    """
    n = p.size
    j = (i + 1) % n
    gap = (p[j] - p[i]) % length
    P = np.asarray(p, dtype=float).copy()
    if redistribute == "local":
        if i % 2 == 0:  # a corner collapses: its neighbours (up, up + 1) take its turning
            for up in ((i - 2) % n, (i + 2) % n):
                P[up] -= 0.25 * gap
                P[(up + 1) % n] += 0.25 * gap
        else:  # a facet collapses: the merged corner (i - 1, j + 1) loses the facet's length
            P[(i - 1) % n] += 0.5 * gap
            P[(j + 1) % n] -= 0.5 * gap
    keep = np.ones(n, dtype=bool)
    keep[[i, j]] = False
    q, qids = P[keep], np.asarray(ids)[keep]
    if j == 0:  # the pair straddled s = 0: the first kept front is a down-front
        q = np.append(q[1:], q[0] + length)
        qids = np.append(qids[1:], qids[0])
    return q, qids


def _is_closed(ode, p, cut, L):
    """The compiled backend checks ``C`` on its own grid first: closing an already
    closed ``p`` (:func:`close_positions` on its finer grid) is then spared."""
    if ode.backend_used != "numba":
        return False
    C = ode.evaluator.evaluate(p, cut, L, False).closure
    return np.linalg.norm(C) <= 1e-12


def integrate_fronts(ode, p0, t_final, t_eval=None, rtol=1e-8, atol=None, method="auto",
                     max_collisions=10, close=True, redistribute="project"):
    """Integrate ``p' = F(p)`` of ``ode`` from ``p0``, removing colliding pairs.

    Parameters
    ----------
    ode : FrontODE
    p0 : ndarray, shape (2N,)
        Initial positions (valid; closed to ``1e-12`` first when ``close``).
    t_final : float
    t_eval : array_like, optional
        Output times (default: the solver's steps).
    rtol, atol, method
        Passed to :func:`scipy.integrate.solve_ivp` (``atol`` default
        ``1e-9 * width``). With a variable length the implicit methods ("Radau",
        "BDF", "LSODA") get the Jacobian's length column only (one evaluation; the
        perimeter mode is the only stiff one). ``"auto"`` (default): RK45 at fixed
        length; with a variable length RK45 when the perimeter mode's rate ``mu``
        (``dL'/dL``, measured at the start of each segment) is mild over the interval,
        ``|mu| (t_final - t0) <=`` :data:`STIFF_AUTO` (e.g. the short facet), Radau
        otherwise (e.g. the triangle): explicit steps would be limited by stability to
        ``~ 3.3 / |mu|``.
    max_collisions : int
    close : bool
        Project ``p0`` and the positions after each collision onto ``C = 0``.
    redistribute : {"project", "local", "uniform"}
        The restart after a collision. ``"project"`` (default): the splice of the
        surviving fronts nearest the curve at the collision
        (:func:`qsa.reduction.projection.nearest_splice`, started from the ``"local"``
        removal). Otherwise the removal of :func:`remove_pair` alone: the pair's turning
        goes to the neighbouring corners (``"local"``), or wherever the minimum-norm
        closure puts it (``"uniform"``, spread over all fronts).

    Returns
    -------
    FrontODEResult
    """
    if redistribute not in ("project", "local", "uniform"):
        raise ValueError("redistribute must be 'project', 'local' or 'uniform', got "
                         f"{redistribute!r}")
    start = time.perf_counter()
    p = p0
    var = ode.beta is not None
    L = float(ode.length)
    ids = np.arange(p.size)  # track index of each current front
    t0, segments, events, n_rhs, n_lu = 0.0, [], [], 0, 0
    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=float)
    atol = 1e-9 * ode.front.width if atol is None else atol
    dc = ode.collision_distance
    status, message = 0, MESSAGES[0]
    while True:
        cut = ode.cutoff or default_cutoff(p, L)
        if close and not _is_closed(ode, p, cut, L if var else None):
            p, _, _ = close_positions(p, ode.front, L, cut)

        last = {}  # the latest evaluation (the implicit methods' Jacobian reuses it)
        count = [0]

        def rhs(t, y, cut=cut, last=last, count=count):
            key = y.tobytes()
            if key in last:
                return last[key]
            count[0] += 1
            try:
                v = ode.rhs(y, cut)
            except np.linalg.LinAlgError:
                v = None
            # a wild trial stage (fronts overrun near a collision): NaN makes the
            # Runge-Kutta error estimate reject the step and shrink it
            if v is None or not np.all(np.isfinite(v)):
                v = np.full(y.size, np.nan)
            last.clear()
            last[key] = v
            return v

        def jac(t, y, cut=cut, rhs=rhs, count=count):
            # Only the length column: the stiffness of the variable-length flow is the
            # perimeter mode (eigenvalue ~ -2 pi beta / R), the positions are slow
            # (|dF/dp| ~ 1/t_c); a difference Jacobian would cost 2N + 1 evaluations.
            f0 = rhs(t, y)
            h = 1e-7 * y[-1]
            count[0] += 1
            J = np.zeros((y.size, y.size))
            J[:, -1] = (ode.rhs(np.append(y[:-1], y[-1] + h), cut) - f0) / h
            return J

        def gap_event(t, y, L=L):
            q, Lq = (y[:-1], y[-1]) if var else (y, L)
            return np.min(np.diff(np.append(q, q[0] + Lq))) - dc

        gap_event.terminal = True
        gap_event.direction = -1
        te = None if t_eval is None else t_eval[(t_eval >= t0) & (t_eval <= t_final)]
        y0 = np.append(p, L) if var else p
        meth = method
        if method == "auto":
            meth = "RK45"
            if var:
                mu = jac(t0, y0)[-1, -1]
                meth = "Radau" if abs(mu) * (t_final - t0) > STIFF_AUTO else "RK45"
        implicit = var and meth in ("Radau", "BDF", "LSODA")
        sol = solve_ivp(rhs, (t0, t_final), y0, method=meth, t_eval=te, rtol=rtol,
                        atol=atol, events=gap_event, **({"jac": jac} if implicit else {}))
        n_rhs += count[0]
        n_lu += int(sol.nlu)
        Y = np.asarray(sol.y, dtype=float).reshape(y0.size, -1).T
        Ls = Y[:, -1] if var else np.full(Y.shape[0], L)
        segments.append(ODESegment(np.asarray(sol.t, dtype=float), Y[:, : p.size],
                                   ids.copy(), cut, Ls))
        if sol.status == -1:
            status, message = -1, f"{MESSAGES[-1]}: {sol.message}"
            break
        if sol.status == 0:
            break
        tc, yc = float(sol.t_events[0][0]), sol.y_events[0][0]
        pc = yc[: p.size]
        if var:
            L = float(yc[-1])
        gaps = np.diff(np.append(pc, pc[0] + L))
        i = int(np.argmin(gaps))
        j = (i + 1) % pc.size
        events.append(ODECollision(tc, (int(ids[i]), int(ids[j])), float(gaps[i]),
                                   pc.copy(), ids.copy()))
        q, qids = remove_pair(pc, ids, i, L, "local" if redistribute == "project"
                              else redistribute)
        if redistribute == "project" and q.size >= 4:
            kappa = ode._reference.fields(pc, cut, L).psi  # the curve at the collision
            q = nearest_splice(ode, kappa, q, L, ode.cutoff or default_cutoff(q, L)).positions
        if q.size < 4 or len(events) > max_collisions:
            status, message = 1, (f"{MESSAGES[1]} (collision at t={tc:.6g}, "
                                  f"{q.size} fronts left)")
            break
        p, ids, t0 = q, qids, tc
    return FrontODEResult(segments, events, status >= 0, status, message, n_rhs,
                          time.perf_counter() - start, n_lu)
