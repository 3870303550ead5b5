"""Newton homotopy: the last globalization of :func:`~qsa.equilibria.polish`.

Damped Newton stalls where the Jacobian ``J = dF/dx`` of the equilibrium system has a
near-singular direction (a *soft mode*: folded sheets that may slide along each other,
a pulse that may drift): the Newton step is huge along it, every damped step raises the
residual, and the gradient flow (pseudo-transient continuation) creeps along it at the
rate of its tiny eigenvalue. :func:`newton_homotopy` follows instead the curve

    H(x, p) = F(x) - p w = 0,        w = F(x0),

from ``(x0, 1)`` towards ``p = 0`` by pseudo-arclength continuation (Euler predictor,
Newton corrector on the bordered system ``[[J, -w], [t_x^T W, t_p]]``). Along it the
residual keeps the direction of the first one and shrinks with ``p``; its tangent at
``x0`` is the Newton direction, and it goes on through the turning points in ``p``
(where ``J`` is singular, and damped Newton stops). A crossing of ``p = 0`` is an
equilibrium, polished by plain Newton from there. A path that turns back before
``p = 0`` and runs off is the answer that no equilibrium is connected to ``x0`` this
way: its smallest ``p`` measures how close it came (the residual there is ``p w``).

The arclength norm is :meth:`~qsa.equilibria.system.EquilibriumSystem.step_norm`'s
(scaled ``kappa``, ``L`` and unfolding parameters) plus ``p^2``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from qsa.energies.constrained import residual_scale
from qsa.equilibria.system import bordered_matrix
from qsa.linalg import factorize

if TYPE_CHECKING:
    from qsa.equilibria.newton import NewtonRun

__all__ = ["HomotopyRun", "bordered_solve", "newton_homotopy", "state_weights"]

#: Why a path ended (``HomotopyRun.reason``).
REASONS = {
    "crossed": "the path crossed p = 0",
    "turned": "the path turned back and left p <= p_max",
    "stalled": "the step fell below ds_min (the corrector failed from every step)",
    "steps": "maximum number of path steps reached",
}


@dataclass(frozen=True, eq=False, kw_only=True)
class _PathRun:
    """What a globalized Newton solve records along its path of states (the fields
    :class:`HomotopyRun` and :class:`~qsa.equilibria.softmode.SoftModeRun` share)."""

    x: np.ndarray
    reason: str
    history: np.ndarray
    states: np.ndarray
    n_steps: int
    n_rejected: int
    n_lu: int
    newton: NewtonRun | None = None
    n_newton: int = 0

    @property
    def success(self) -> bool:
        """Newton converged from the path."""
        return self.newton is not None and self.newton.success


@dataclass(frozen=True, eq=False, kw_only=True)
class HomotopyRun(_PathRun):
    """The record of :func:`newton_homotopy`.

    Attributes
    ----------
    x : ndarray
        The solution (``newton.x``) when ``success``; else the path point of smallest
        relative residual of ``F``.
    reason : str
        A key of :data:`REASONS`.
    p : ndarray
        Homotopy parameter of each accepted path point (the first: 1 at ``x0``).
    history : ndarray
        Relative residual of ``F`` at each path point (``p`` times that of ``x0`` up to
        the corrector's tolerance).
    arclength : ndarray
        Arclength of each path point from ``x0``.
    states : ndarray, shape (len(p), system.size)
        The path points (the first: ``x0``, or its correction onto the path).
    n_steps, n_rejected, n_lu : int
        Path steps accepted and rejected; factorizations (path and Newton solves).
    newton : NewtonRun or None
        The Newton solve from the crossing of ``p = 0`` (``None``: no crossing).
    n_newton : int
        Newton steps of that solve.
    success : bool
        The path crossed ``p = 0`` and Newton converged from there.
    """

    p: np.ndarray
    arclength: np.ndarray

    @property
    def p_min(self) -> float:
        """Smallest ``p`` met on the path: how close to an equilibrium it came."""
        return float(np.min(self.p))

    @property
    def turning_points(self) -> np.ndarray:
        """Indices of the path points where ``p`` turned (a local extremum of ``p``)."""
        d = np.diff(self.p)
        return np.flatnonzero(d[:-1] * d[1:] < 0) + 1


def state_weights(system, x, scale):
    """Weights ``W`` with ``step_norm(dx) = sqrt(sum W dx^2)`` (the system's state norm).

    Parameters
    ----------
    system : EquilibriumSystem
    x : ndarray, shape (system.size,)
    scale : float
        :func:`~qsa.energies.residual_scale` at ``x``.

    Returns
    -------
    ndarray, shape (system.size,)
    """
    N = system.N
    L = abs(x[N])
    k_scale = max(float(np.max(np.abs(x[:N]))), 2 * np.pi / L)
    W = np.empty(system.size)
    W[:N] = 1.0 / (N * k_scale ** 2)
    W[N] = 1.0 / L ** 2
    W[N + 1:N + 1 + system.n_unfold] = 1.0 / scale ** 2
    if system.m:
        c = system.curve(x)
        n_size = np.array([np.max(np.abs(con.normal_variation(c)))
                           for con in system.constraints])
        W[system.size - system.m:] = (n_size / scale) ** 2
    return W


def bordered_solve(system, x, column, row, corner, head, last, energy=None):
    """Solve ``[[J(x), column], [row, corner]] z = (head, last)``; returns ``z[:size + 1]``.

    ``head`` is the right-hand side of the rows of ``F`` (0 for a tangent); the rows of
    the unknowns the Newton matrix unfolds get 0. Raises ``LinAlgError`` on a singular
    or non-finite solve.
    """
    n = system.size
    M = bordered_matrix(system.jacobian_parts(x, energy), column, row, corner)
    rhs = np.zeros(M.shape[0])
    rhs[:n] = head
    rhs[n] = last
    out = factorize(M).solve(rhs)[:n + 1]
    if not np.all(np.isfinite(out)):
        raise np.linalg.LinAlgError("non-finite solution")
    return out


def _tangent(system, x, w, row, energy):
    """Tangent of the path at ``x``: ``J t_x = w t_p`` with ``<row, t> = 1``."""
    n = system.size
    return bordered_solve(system, x, -w, row[:n], row[n], 0.0, 1.0, energy)


def _correct(system, y_pred, t, w, W, scale, ctol, maxiter, energy, check_curve):
    """Newton on ``[F(x) - p w; <t, y - y_pred>_W] = 0``; returns ``(y, iterations)`` or None."""
    n = system.size
    row = t * W
    y = y_pred.copy()
    for it in range(maxiter + 1):
        x, p = y[:n], y[n]
        if not x[system.N] > 0:
            return None
        try:
            c = system.curve(x)
            H = system.residual(x, energy) - p * w
        except ValueError:
            return None
        g = float(row @ (y - y_pred))
        r = system.scaled_norm(H, c, scale)
        if not np.isfinite(r):
            return None
        if r <= ctol and abs(g) <= ctol:
            if check_curve and c.self_intersects():
                return None
            return y, it
        if it == maxiter:
            return None
        try:
            y = y - bordered_solve(system, x, -w, row[:n], row[n], H, g, energy)
        except (np.linalg.LinAlgError, RuntimeError, ValueError):
            return None
    return None


def newton_homotopy(system, x0, solve, *, tol=1e-10, maxiter=60, newton_maxiter=12,
                    ds0=0.05, ds_max=0.5, ds_min=1e-6, p_max=2.0, ctol=None,
                    corrector_maxiter=6, energy=None, check_curve=True,
                    line_search=True, direction=None) -> HomotopyRun:
    """Follow ``F(x) = p F(x0)`` from ``p = 1`` to ``p = 0`` (module docstring).

    Parameters
    ----------
    system : EquilibriumSystem
    x0 : ndarray, shape (system.size,)
    direction : ndarray, shape (system.size,), optional
        Follow ``F(x) = p w`` for this ``w`` instead of ``F(x0)`` (e.g. the left singular
        vector of ``J``'s smallest singular value: a Lyapunov-Schmidt reduction along a
        soft mode, where ``p(s)`` is the residual left when the other equations hold).
        The path starts from the corrector's point near ``x0``, ``p0 = <w, F(x0)> /
        <w, w>``, and runs towards ``p = 0``; ``p`` in the record is divided by ``p0``.
    solve : callable
        The Newton solver run from the crossing of ``p = 0``,
        :func:`~qsa.equilibria.newton.newton_solve`.
    tol : float
        Target of that Newton solve (relative residual).
    maxiter : int
        Path steps, accepted and rejected, at most.
    newton_maxiter : int
        Steps of the final Newton solve.
    ds0, ds_max, ds_min : float
        First, largest and smallest arclength step (state norm plus ``p``). The step
        doubles after a corrector that converged in at most two iterations and is
        quartered after one that failed.
    p_max : float
        The path is abandoned once ``p`` exceeds this (it turned back).
    ctol : float, optional
        Corrector tolerance (relative residual of ``H``); default
        ``max(tol, 1e-3 r0)`` with ``r0`` the relative residual at ``x0``: the path
        only guides the final Newton solve.
    corrector_maxiter : int
    energy : Energy, optional
        Another energy on the same system.
    check_curve : bool
        Reject path points whose curve crosses or touches itself.
    line_search : bool
        Of the final Newton solve.

    Returns
    -------
    HomotopyRun
        Never raises for non-convergence.
    """
    n = system.size
    x0 = np.array(x0, dtype=float)
    scale = residual_scale(system.energy if energy is None else energy, system.curve(x0))
    F0 = system.residual(x0, energy)
    r0 = system.scaled_norm(F0, system.curve(x0), scale)
    if direction is None:
        w, p0 = F0, 1.0
    else:
        w = np.asarray(direction, dtype=float)
        p0 = float(w @ F0 / (w @ w))
        w = p0 * w          # p = 1 at x0's projection, as for F(x0)
    ctol = max(tol, 1e-3 * r0) if ctol is None else float(ctol)
    W = np.append(state_weights(system, x0, scale), 1.0)
    y = np.append(x0, 1.0)
    ps, hist, arc, states = [1.0], [r0], [0.0], [x0.copy()]
    best = (r0, x0.copy())
    n_steps = n_rejected = n_lu = 0
    reason = "steps"
    newton = None

    def fail(why):
        return HomotopyRun(x=best[1], reason=why, p=np.array(ps), history=np.array(hist),
                           arclength=np.array(arc), states=np.array(states),
                           n_steps=n_steps, n_rejected=n_rejected, n_lu=n_lu)

    try:
        start = np.zeros(n + 1)
        start[n] = 1.0
        n_lu += 1
        t = -_tangent(system, x0, w, start, energy)   # p decreasing
    except (np.linalg.LinAlgError, RuntimeError, ValueError):
        return fail("stalled")
    t /= np.sqrt(W @ t ** 2)
    if direction is not None:   # onto the path, in the plane normal to its tangent
        out = _correct(system, y, t, w, W, scale, ctol, 4 * corrector_maxiter, energy,
                       check_curve)
        if out is None:
            return fail("stalled")
        y = out[0]
        n_lu += out[1]
        F = system.residual(y[:n], energy)
        ps[0], hist[0] = float(y[n]), system.scaled_norm(F, system.curve(y[:n]), scale)
        states[0] = y[:n].copy()
        best = (hist[0], y[:n].copy())
        try:
            n_lu += 1
            t = _tangent(system, y[:n], w, t * W, energy)
        except (np.linalg.LinAlgError, RuntimeError, ValueError):
            return fail("stalled")
        t /= np.sqrt(W @ t ** 2)
        if t[n] > 0:
            t = -t
    ds = float(ds0)
    s = 0.0
    while n_steps + n_rejected < maxiter and np.isfinite(r0):
        if ds < ds_min:
            reason = "stalled"
            break
        out = _correct(system, y + ds * t, t, w, W, scale, ctol, corrector_maxiter, energy,
                       check_curve)
        n_lu += corrector_maxiter if out is None else out[1]
        if out is None:
            n_rejected += 1
            ds /= 4
            continue
        y_new, iters = out
        n_steps += 1
        s += ds
        x_new, p_new = y_new[:n], float(y_new[n])
        F = system.residual(x_new, energy)
        r = system.scaled_norm(F, system.curve(x_new), scale)
        ps.append(p_new)
        hist.append(r)
        arc.append(s)
        states.append(x_new.copy())
        if r < best[0]:
            best = (r, x_new.copy())
        if p_new <= 0:
            reason = "crossed"
            p_old = float(y[n])
            y_star = y + (p_old / (p_old - p_new)) * (y_new - y)
            newton = solve(system, y_star[:n], tol, newton_maxiter, energy=energy,
                           line_search=line_search)
            n_lu += newton.n_lu
            break
        if p_new > p_max:
            reason = "turned"
            break
        try:
            n_lu += 1
            t_new = _tangent(system, x_new, w, t * W, energy)
        except (np.linalg.LinAlgError, RuntimeError, ValueError):
            reason = "stalled"
            break
        t_new /= np.sqrt(W @ t_new ** 2)
        if W @ (t_new * t) < 0:
            t_new = -t_new
        y, t = y_new, t_new
        if iters <= 2:
            ds = min(2 * ds, ds_max)
    x = newton.x if newton is not None and newton.success else best[1]
    return HomotopyRun(x=x, reason=reason, p=np.array(ps), history=np.array(hist),
                       arclength=np.array(arc), states=np.array(states), n_steps=n_steps,
                       n_rejected=n_rejected, n_lu=n_lu, newton=newton,
                       n_newton=0 if newton is None else newton.n_newton)
