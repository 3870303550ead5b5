"""Soft-mode Newton: Lyapunov-Schmidt reduction along the near-singular direction of ``J``.

Where the Jacobian ``J = dF/dx`` of the equilibrium system has one singular value far
below the others (a *soft mode*, with right and left singular vectors ``v`` and ``u``:
sheets of a folded curve that may slide along each other), Newton's step is huge along
``v`` and the equilibrium, if there is one, can lie far along it. :func:`soft_mode_newton`
splits the problem. With the soft coordinate ``s = <v, x - x_ref>`` fixed, the bordered
system ::

    F(x) + tau u = 0,      <v, x - x_ref> = s                    (size + 1 equations)

is well conditioned (its smallest singular value is about ``J``'s second smallest),
and Newton's method (:func:`~qsa.equilibria.newton.newton_solve`, with its line search)
solves it for ``(x(s), tau(s))``: every equation but the soft one holds
and ``tau(s)`` is what is left of the residual. The equilibria are the roots of the
scalar ``tau(s)``, found by Newton's method on it (``ds = -tau / tau'``, with ``tau'``
from the tangent ``[[J, u], [v^T, 0]] (x', tau') = (0, 1)``), each step capped in the
state norm and followed along the curve ``x(s)``. ``u`` and ``v`` are recomputed at every
accepted point (inverse iteration on the factorization of ``J``), so the reduction
follows the mode as it changes along the way. A root of ``tau`` ends in a plain Newton
solve; a minimum of ``|tau|`` away from zero (``tau'`` changing sign) says there is no
equilibrium along the soft mode, only a slow flow past the minimum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from qsa.energies.constrained import residual_scale
from qsa.equilibria.homotopy import _PathRun, bordered_solve, state_weights
from qsa.equilibria.system import bordered_matrix

__all__ = ["SoftModeRun", "smallest_singular", "soft_mode_newton"]

#: Why a soft-mode solve ended (``SoftModeRun.reason``).
REASONS = {
    "converged": "Newton converged from a point of the soft curve",
    "extremum": "|tau| has a minimum away from 0 along the soft mode: no equilibrium there",
    "stalled": "the corrector failed from every step, or the reduction broke down",
    "steps": "maximum number of steps reached",
}


@dataclass(frozen=True, eq=False, kw_only=True)
class SoftModeRun(_PathRun):
    """The record of :func:`soft_mode_newton`.

    Attributes
    ----------
    x : ndarray
        The solution (``newton.x``) when ``success``, else the point of the soft curve
        with the smallest relative residual.
    reason : str
        A key of :data:`REASONS`.
    s : ndarray
        Distance travelled along the soft curve (state norm) at each accepted point.
    tau : ndarray
        The soft residual ``tau`` at each point (``F = -tau u``, ``|u| = 1``).
    dtau : ndarray
        ``d tau / ds`` at each point (per unit of ``s``).
    sigma : ndarray, shape (k, 2)
        The two smallest singular values of ``J`` at each point.
    history : ndarray
        Relative residual of ``F`` at ``x0`` and then at each point of the curve.
    states : ndarray
        ``x0`` and the points of the curve.
    n_steps, n_rejected, n_lu : int
    newton : NewtonRun or None
        The last Newton solve tried from the curve.
    n_newton : int
        Newton steps of the solves tried.
    success : bool
        A Newton solve from the soft curve converged.
    """

    s: np.ndarray
    tau: np.ndarray
    dtau: np.ndarray
    sigma: np.ndarray


def smallest_singular(J, v0=None, iterations=4):
    """The two smallest singular values of ``J`` and the singular vectors of the smallest.

    Inverse iteration on ``J^T J`` with one LU factorization of ``J`` (dense or sparse),
    on a block of two vectors (so the second value is seen too).

    Parameters
    ----------
    J : ndarray or sparse matrix, square
    v0 : ndarray, optional
        Start for the right singular vector (e.g. the last one).
    iterations : int

    Returns
    -------
    sigma : ndarray, shape (2,)
        Smallest and second smallest singular values (the second: an upper estimate).
    u, v : ndarray
        Left and right unit singular vectors of the smallest.
    """
    n = J.shape[0]
    if sp.issparse(J):
        lu = spla.splu(sp.csc_matrix(J))

        def solve(b, trans):
            return lu.solve(b, trans="T" if trans else "N")
    else:
        fac = sla.lu_factor(np.asarray(J))

        def solve(b, trans):
            return sla.lu_solve(fac, b, trans=1 if trans else 0)
    rng = np.random.default_rng(0)
    V = rng.normal(size=(n, 2))
    if v0 is not None:
        V[:, 0] = v0
    for _ in range(iterations):
        V = np.column_stack([solve(solve(V[:, j], True), False) for j in range(2)])
        V, _ = np.linalg.qr(V)
    JV = J @ V
    # Rayleigh-Ritz in span V: the singular values of J V
    Uj, sig, Wt = np.linalg.svd(JV, full_matrices=False)
    v = V @ Wt[-1]
    u = Uj[:, -1]
    return sig[::-1], u, v


class _Bordered:
    """The bordered system ``[F(x) + tau u; <v, x> - target]`` in unknowns ``y = (x, tau)``.

    It offers what :func:`~qsa.equilibria.newton.newton_solve` needs of a system, so that
    the corrector is Newton's method with its line search (the natural monotonicity test).
    """

    def __init__(self, system, u, v, target):
        self.system, self.u, self.v, self.target = system, u, v, float(target)
        self.energy = system.energy
        self.N = system.N
        self.size = system.size + 1

    def curve(self, y):
        return self.system.curve(y[:-1])

    def residual(self, y, energy=None):
        x = y[:-1]
        return np.append(self.system.residual(x, energy) + y[-1] * self.u,
                         self.v @ x - self.target)

    def jacobian(self, y, energy=None):
        return bordered_matrix(self.system.jacobian_parts(y[:-1], energy), self.u, self.v, 0.0)

    def scaled_parts(self, F, c, scale):
        parts = self.system.scaled_parts(F[:-1], c, scale)
        return np.append(parts, abs(F[-1]) / max(float(np.max(np.abs(c.kappa))), 1.0))

    def scaled_norm(self, F, c, scale):
        return float(np.max(self.scaled_parts(F, c, scale)))

    def step_norm(self, dy, y, scale):
        return float(np.hypot(self.system.step_norm(dy[:-1], y[:-1], scale), dy[-1] / scale))


def _correct(system, x, tau, u, v, target, maxiter, ctol, solve, energy, check_curve):
    """Newton (``solve``) on ``[F(x) + tau u; <v, x> - target] = 0``.

    Returns ``(x, tau, NewtonRun)``, or ``(None, None, NewtonRun)`` when it failed or
    reached a curve that crosses itself.
    """
    bordered = _Bordered(system, u, v, target)
    run = solve(bordered, np.append(x, tau), ctol, maxiter, energy=energy)
    if not run.success or (check_curve and system.curve(run.x[:-1]).self_intersects()):
        return None, None, run
    return run.x[:-1], float(run.x[-1]), run


def _frame(system, x, v_prev, u_prev, energy):
    """``(sigma, u, v)`` at ``x``: the soft singular pair, each oriented like the last."""
    J = system.jacobian(x, energy)
    n = system.size
    sig, u, v = smallest_singular(J, None if v_prev is None else
                                  np.concatenate([v_prev, np.zeros(J.shape[0] - n)]))
    u, v = u[:n], v[:n]
    # each vector keeps its orientation on its own: where the soft singular value passes
    # through 0 (det J changes sign) one of the pair flips, and tau would jump sign
    if v_prev is not None and v @ v_prev < 0:
        v = -v
    if u_prev is not None and u @ u_prev < 0:
        u = -u
    return sig, u / np.linalg.norm(u), v / np.linalg.norm(v)


def soft_mode_newton(system, x0, solve, *, tol=1e-10, maxiter=30, newton_maxiter=12,
                     step_max=0.05, ctol=None, corrector_maxiter=8, attempt=1e-2,
                     energy=None, check_curve=True, line_search=True) -> SoftModeRun:
    """Newton's method on the soft residual ``tau(s)`` along the soft mode (module docstring).

    Parameters
    ----------
    system : EquilibriumSystem
    x0 : ndarray, shape (system.size,)
    solve : callable
        :func:`~qsa.equilibria.newton.newton_solve`, run from the soft curve.
    tol : float
        Target of the Newton solves (relative residual).
    maxiter : int
        Steps along the soft curve, accepted and rejected, at most.
    newton_maxiter : int
        Steps of each Newton solve tried.
    step_max : float
        Largest step along the curve, in the state norm
        (:meth:`~qsa.equilibria.system.EquilibriumSystem.step_norm`).
    ctol : float, optional
        Corrector tolerance (relative residual of ``F + tau u``); default
        ``max(tol, 1e-4 r0)``, ``r0`` the relative residual at ``x0``.
    corrector_maxiter : int
    attempt : float
        A Newton solve is tried from a point whose relative residual is below
        ``attempt`` times ``r0`` (and below the last point's).
    energy : Energy, optional
    check_curve : bool
        Reject points whose curve crosses or touches itself.
    line_search : bool
        Of the Newton solves.

    Returns
    -------
    SoftModeRun
        Never raises for non-convergence.
    """
    n = system.size
    x0 = np.array(x0, dtype=float)
    scale = residual_scale(system.energy if energy is None else energy, system.curve(x0))
    F0 = system.residual(x0, energy)
    r0 = system.scaled_norm(F0, system.curve(x0), scale)
    ctol = max(tol, 1e-4 * r0) if ctol is None else float(ctol)
    W = state_weights(system, x0, scale)
    rec = {"s": [], "tau": [], "dtau": [], "sigma": [], "history": [r0], "states": [x0]}
    best = (r0, x0.copy())
    n_steps = n_rejected = n_lu = n_newton = 0
    newton = None
    reason = "steps"

    def run(why):
        x = newton.x if newton is not None and newton.success else best[1]
        k = len(rec["s"])
        return SoftModeRun(x=x, reason=why, s=np.array(rec["s"]), tau=np.array(rec["tau"]),
                           dtau=np.array(rec["dtau"]),
                           sigma=np.array(rec["sigma"]).reshape(k, 2),
                           history=np.array(rec["history"]), states=np.array(rec["states"]),
                           n_steps=n_steps, n_rejected=n_rejected, n_lu=n_lu, newton=newton,
                           n_newton=n_newton)

    try:
        n_lu += 2
        sig, u, v = _frame(system, x0, None, None, energy)
    except (np.linalg.LinAlgError, RuntimeError, ValueError):
        return run("stalled")
    x, tau, cr = _correct(system, x0, -float(u @ F0), u, v, float(v @ x0),
                          4 * corrector_maxiter, ctol, solve, energy, check_curve)
    n_lu += cr.n_lu
    if x is None:
        return run("stalled")
    s = 0.0
    last_try = r0
    while True:
        F = system.residual(x, energy)
        r = system.scaled_norm(F, system.curve(x), scale)
        rec["history"].append(r)
        rec["states"].append(x.copy())
        if r < best[0]:
            best = (r, x.copy())
        # the tangent of the soft curve and tau' (frame of this point)
        try:
            n_lu += 2
            sig, u, v = _frame(system, x, v, u, energy)
            tau = -float(u @ F)
            d = bordered_solve(system, x, u, v, 0.0, 0.0, 1.0, energy)
        except (np.linalg.LinAlgError, RuntimeError, ValueError):
            reason = "stalled"
            break
        t, dtau = d[:n], float(d[n])
        size = float(np.sqrt(W @ t ** 2))     # state norm per unit of <v, x>
        rec["s"].append(s)
        rec["tau"].append(tau)
        rec["dtau"].append(dtau / size)
        rec["sigma"].append(sig[:2])
        if r <= attempt * r0 and r < last_try:
            last_try = r
            newton = solve(system, x, tol, newton_maxiter, energy=energy,
                           line_search=line_search)
            n_newton += newton.n_newton
            n_lu += newton.n_lu
            if newton.success:
                reason = "converged"
                break
        k = len(rec["dtau"])
        if k >= 2 and rec["dtau"][-1] * rec["dtau"][-2] < 0 and rec["tau"][-1] * rec["tau"][-2] > 0:
            # tau' changed sign with tau of one sign: |tau| passed its minimum
            if abs(rec["tau"][-1]) > abs(rec["tau"][-2]):
                reason = "extremum"
                break
        if n_steps + n_rejected >= maxiter:
            break
        if not (np.isfinite(dtau) and dtau != 0):
            reason = "stalled"
            break
        ds = -tau / dtau                          # Newton on tau(s), in units of <v, x>
        ds = float(np.clip(ds, -step_max / size, step_max / size))
        accepted = False
        while n_steps + n_rejected < maxiter:
            xc, tc, cr = _correct(system, x + ds * t, tau + ds * dtau, u, v,
                                  float(v @ x) + ds, corrector_maxiter, ctol, solve, energy,
                                  check_curve)
            n_lu += cr.n_lu
            if xc is not None:
                accepted = True
                break
            n_rejected += 1
            ds /= 4
        if not accepted:
            reason = "stalled" if n_rejected else "steps"
            break
        x, tau = xc, tc
        n_steps += 1
        s += abs(ds) * size
    return run(reason)
