"""Pseudo-transient continuation: the globalization of :func:`~qsa.equilibria.polish`.

Newton's method on ``V^n = 0`` converges from guesses close to an equilibrium. A state
a flow left on another grid (finite differences, a coarser ``N``) or before it settled
can be too far: curves with many slow modes (folded sheets that may slide along each
other, long facets) give Newton steps that wander. :func:`pseudo_transient` follows the
gradient flow instead, with steps that grow into Newton steps as the residual falls.

The flow in intrinsic coordinates moves the curvature by ``kappa_t = -(Delta_s +
kappa^2) V^n`` plus a reparameterization (e:Meq); its linearly implicit Euler step of
size ``dt`` on the equilibrium system ``F(x) = 0`` of
:class:`~qsa.equilibria.system.EquilibriumSystem` is ::

    [G J_V + I/dt] dkappa + G J_rest d(L, a) = -G F_V,     (N rows; G = Delta_s + kappa^2)
    closure, phase and constraint rows as in Newton's method,

with ``J = dF/dx``. For small ``dt`` this is a flow step (a stable equilibrium of the
flow attracts it); as ``dt -> infinity`` it is Newton's step (``G`` cancels where it is
invertible). The step grows by switched evolution relaxation -- ``dt`` multiplied by
the ratio of successive residuals, clipped to ``[1/4, 4]`` and at least ``1.25`` after
a step that lowered the residual -- and shrinks by 4 after a step that made the curve
cross itself, lengthened the residual more than twofold or failed; the last word is
Newton's: whenever the flow reaches a state whose relative residual is a new
minimum (by a factor ``attempt_gain`` below the state of the last attempt), a short
Newton solve (:func:`~qsa.equilibria.newton.newton_solve`, ``newton_maxiter`` steps)
is tried from it, and the first that converges ends the run. The residual of the
equilibrium equations is no Lyapunov function of the flow (its maximum over the
curve may rise while the energy falls), so the flow is followed on through such
rises, as long as no single step raises it more than twofold.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from qsa.energies.constrained import residual_scale
from qsa.geometry import laplace_s
from qsa.linalg import factorize

if TYPE_CHECKING:
    from qsa.equilibria.newton import NewtonRun

__all__ = ["TransientRun", "pseudo_transient"]


@dataclass(frozen=True, eq=False)
class TransientRun:
    """The record of :func:`pseudo_transient`.

    Attributes
    ----------
    x : ndarray
        The state with the smallest relative residual met.
    reached : bool
        Whether the flow itself brought the relative residual below ``tol``.
    history : ndarray
        Relative residual after each accepted step (the first entry: at the start).
    dt : ndarray
        Pseudo-time step of each accepted step.
    n_steps, n_rejected, n_lu : int
        Flow steps accepted and rejected; factorizations (flow steps and Newton solves).
    time : float
        Pseudo time travelled.
    newton : NewtonRun or None
        The Newton solve that converged, or the last one tried (``None``: none tried).
    n_attempts : int
        Newton solves tried.
    n_newton : int
        Newton steps of all the solves tried.
    """

    x: np.ndarray
    reached: bool
    history: np.ndarray
    dt: np.ndarray
    n_steps: int
    n_rejected: int
    n_lu: int
    time: float
    newton: NewtonRun | None = None
    n_attempts: int = 0
    n_newton: int = 0

    @property
    def success(self) -> bool:
        """A Newton solve from the flow converged."""
        return self.newton is not None and self.newton.success


def _flow_matrix(system, x, J, dt):
    """``R J + S / dt``: the first ``N`` rows premultiplied by ``G``, ``I/dt`` on kappa."""
    N = system.N
    c = system.curve(x)
    G = laplace_s(c) + system.grid.diag(c.kappa ** 2)
    n = J.shape[0]
    if sp.issparse(J):
        J = sp.csr_matrix(J)
        G = sp.csr_matrix(G)
        top = G @ J[:N] + sp.eye(N, n, format="csr") / dt
        return sp.vstack([top, J[N:]], format="csc"), G
    G = np.asarray(G.toarray() if sp.issparse(G) else G)
    M = np.array(J, dtype=float)
    M[:N] = G @ M[:N]
    M[np.arange(N), np.arange(N)] += 1.0 / dt
    return M, G


def _initial_dt(system, x, G, F):
    """A step that moves ``kappa`` by about 1% of its size in an explicit flow step."""
    N = system.N
    rate = float(np.max(np.abs(G @ F[:N])))
    size = max(float(np.max(np.abs(x[:N]))), 2 * np.pi / abs(x[N]))
    return 0.01 * size / rate if rate > 0 else 1.0


#: The flow stops (unsuccessfully) once rejections have cut the step below this fraction
#: of the first one: from there no step of the flow is accepted (e.g. every step would
#: make the curve touch itself).
MIN_DT_RATIO = 1e-12


def pseudo_transient(system, x0, solve, *, tol=1e-10, maxiter=400, newton_maxiter=12,
                     attempt_gain=0.7, energy=None, dt0=None, check_curve=True,
                     line_search=True) -> TransientRun:
    """Follow the gradient flow from ``x0`` with growing implicit steps (module docstring).

    Parameters
    ----------
    system : EquilibriumSystem
    x0 : ndarray, shape (system.size,)
    solve : callable
        The Newton solver, :func:`~qsa.equilibria.newton.newton_solve` (its signature:
        ``solve(system, x, tol, maxiter, energy=..., line_search=...) -> NewtonRun``).
    tol : float
        Target of the Newton solves (relative residual,
        :meth:`EquilibriumSystem.scaled_norm`).
    maxiter : int
        Accepted plus rejected flow steps at most.
    newton_maxiter : int
        Steps of each Newton solve tried.
    attempt_gain : float
        A Newton solve is tried from a state whose relative residual is below
        ``attempt_gain`` times that of the last state tried (the first: ``x0`` itself
        is not tried, it is where the caller's Newton solve failed).
    energy : Energy, optional
        Another energy on the same system.
    dt0 : float, optional
        First pseudo-time step (default: an explicit flow step would change ``kappa``
        by 1% of ``max|kappa|``).
    check_curve : bool
        Reject steps to curves that cross or touch themselves.
    line_search : bool
        Of the Newton solves (:func:`~qsa.equilibria.newton.newton_solve`).

    Returns
    -------
    TransientRun
        ``success`` when a Newton solve from the flow converged (its state is
        ``newton.x``); never raises for non-convergence. The flow also stops when
        rejected steps have cut the step below :data:`MIN_DT_RATIO` of the first.
    """
    x = np.array(x0, dtype=float)
    N = system.N
    scale = residual_scale(system.energy if energy is None else energy, system.curve(x))
    F = system.residual(x, energy)
    r = system.scaled_norm(F, system.curve(x), scale)
    history, dts = [r], []
    best = (r, x.copy())
    dt = None if dt0 is None else float(dt0)
    first_dt = None
    n_steps = n_rejected = n_lu = 0
    time = 0.0
    last_try = r
    newton, n_attempts, n_newton = None, 0, 0
    while n_steps + n_rejected < maxiter and np.isfinite(r):
        J = system.jacobian(x, energy)
        if dt is None:
            c = system.curve(x)
            G = laplace_s(c) + system.grid.diag(c.kappa ** 2)
            dt = _initial_dt(system, x, G, F)
        if first_dt is None:
            first_dt = dt
        if not dt > MIN_DT_RATIO * first_dt:  # every step from here rejected: stalled
            break
        M, G = _flow_matrix(system, x, J, dt)
        b = np.zeros(M.shape[0])
        b[:F.size] = F
        b[:N] = G @ F[:N]
        try:
            n_lu += 1
            dx = -factorize(M).solve(b)[:F.size]
        except (RuntimeError, np.linalg.LinAlgError, ValueError):
            dx = np.full(F.size, np.nan)
        xt = x + dx
        rt = np.inf
        if np.all(np.isfinite(dx)) and xt[N] > 0:
            try:
                ct = system.curve(xt)
                if not (check_curve and ct.self_intersects()):
                    Ft = system.residual(xt, energy)
                    rt = system.scaled_norm(Ft, ct, scale)
            except ValueError:
                rt = np.inf
        if not np.isfinite(rt) or rt > 2 * r:
            n_rejected += 1
            dt /= 4
            continue
        n_steps += 1
        time += dt
        dts.append(dt)
        factor = float(np.clip(r / rt, 0.25, 4.0))
        if rt < r:
            factor = max(factor, 1.25)
        x, F, r = xt, Ft, rt
        history.append(r)
        if r < best[0]:
            best = (r, x.copy())
        dt *= factor
        if r <= attempt_gain * last_try:
            last_try = r
            n_attempts += 1
            newton = solve(system, x, tol, newton_maxiter, energy=energy,
                           line_search=line_search)
            n_newton += newton.n_newton
            n_lu += newton.n_lu
            if newton.success:
                break
    return TransientRun(best[1], bool(best[0] <= tol), np.array(history), np.array(dts),
                        n_steps, n_rejected, n_lu, time, newton, n_attempts, n_newton)
