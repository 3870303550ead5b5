"""A small variable-step BDF2 driver for the DAE flow models (validation runs only).

Used by :mod:`qsa.commands.reproduce_fronts` and the benchmarks when
``qsa.flows.solve_flow`` is not available. One step solves
``F(y, c (y - psi)) = 0`` (:mod:`qsa.flows.base`) by Newton's method with the
model's sparse Jacobian; the variable-step BDF2 coefficients are
``c = (1 + 2 w) / ((1 + w) k)``, ``psi = ((1 + w)^2 y_n - w^2 y_{n-1}) / (1 + 2 w)``,
``w = k_n / k_{n-1}``. The local error is estimated from the quadratic predictor,
``err ~ 2/11 |y - y_pred|`` on the positions (constant-step constants).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

__all__ = ["DAERun", "integrate_dae"]


@dataclass(frozen=True)
class DAERun:
    """Accepted steps of :func:`integrate_dae`.

    Attributes
    ----------
    t : ndarray, shape (n,)
    kappa : ndarray, shape (n, N)
    L : ndarray, shape (n,)
    y : ndarray, shape (size,)
        Final state.
    success : bool
    message : str
    n_steps, n_rejected, n_newton : int
    elapsed : float
    """

    t: np.ndarray
    kappa: np.ndarray
    L: np.ndarray
    y: np.ndarray
    success: bool
    message: str
    n_steps: int
    n_rejected: int
    n_newton: int
    elapsed: float


def _newton(system, y, psi, c, tol, max_iter=8):
    scale = 1.0 + np.abs(y)
    for it in range(1, max_iter + 1):
        ydot = c * (y - psi)
        r = system.residual(y, ydot)
        if not np.all(np.isfinite(r)):
            return y, False, it
        dy = spla.splu(system.jacobian(y, ydot, c).tocsc()).solve(-r)
        y = y + dy
        if np.max(np.abs(dy[system.error_index]) / scale[system.error_index]) < tol:
            return y, True, it
    return y, False, max_iter


def integrate_dae(system, t_final, tol=1e-6, first_step=1e-5, max_steps=100000,
                  stop=None):
    """Integrate ``system`` (a :class:`qsa.flows.base.DAESystem`) from ``system.y0``.

    Parameters
    ----------
    system : DAESystem
    t_final : float
    tol : float
        Local error tolerance on the positions (absolute).
    first_step : float
    max_steps : int
    stop : callable, optional
        ``stop(t, kappa, L) -> bool``; ends the run after an accepted step.

    Returns
    -------
    DAERun
    """
    start = time.perf_counter()
    y = system.y0.copy()
    N = system.N
    ts, ks, Ls = [0.0], [system.curvature(y)], [system.length(y)]
    hist = [(0.0, y)]
    k = first_step
    t = 0.0
    n_rej = n_newton = 0
    ok, msg = True, "reached t_final"
    idx = system.error_index
    while t < t_final * (1 - 1e-12):
        if len(ts) > max_steps:
            ok, msg = False, f"max_steps={max_steps} reached at t={t:.6g}"
            break
        k = min(k, t_final - t)
        if len(hist) == 1:  # backward Euler start, predictor = current state
            c, psi, pred = 1.0 / k, y, y
        else:
            t1, y1 = hist[-2]
            w = k / (t - t1)
            c = (1 + 2 * w) / ((1 + w) * k)
            psi = ((1 + w) ** 2 * y - w**2 * y1) / (1 + 2 * w)
            if len(hist) >= 3:  # quadratic extrapolation through the last three states
                (ta, ya), (tb, yb), (tc, yc) = hist[-3:]
                tn = t + k
                la = (tn - tb) * (tn - tc) / ((ta - tb) * (ta - tc))
                lb = (tn - ta) * (tn - tc) / ((tb - ta) * (tb - tc))
                lc = (tn - ta) * (tn - tb) / ((tc - ta) * (tc - tb))
                pred = la * ya + lb * yb + lc * yc
            else:
                pred = y + w * (y - y1)
        ynew, conv, it = _newton(system, pred.copy(), psi, c, 1e-3 * tol)
        n_newton += it
        if not conv:
            n_rej += 1
            k *= 0.25
            if k < 1e-14:
                ok, msg = False, f"step size underflow at t={t:.6g}"
                break
            continue
        if len(hist) >= 3:
            err = 2.0 / 11.0 * np.max(np.abs(ynew[idx] - pred[idx]))
        elif len(hist) == 2:
            err = 0.5 * np.max(np.abs(ynew[idx] - pred[idx]))
        else:
            err = 0.5 * np.max(np.abs(ynew[idx] - y[idx]))
        if err > tol and k > 1e-12:
            n_rej += 1
            k *= max(0.2, 0.9 * (tol / err) ** (1 / 3))
            continue
        t += k
        y = ynew
        hist = (hist + [(t, y)])[-3:]
        ts.append(t)
        ks.append(system.curvature(y))
        Ls.append(system.length(y))
        fac = 2.0 if err == 0 else min(2.0, max(0.2, 0.9 * (tol / err) ** (1 / 3)))
        k *= fac
        if stop is not None and stop(t, ks[-1], Ls[-1]):
            msg = f"stopped by callback at t={t:.6g}"
            break
    del N
    return DAERun(np.array(ts), np.array(ks), np.array(Ls), y, ok, msg, len(ts) - 1, n_rej,
                  n_newton, time.perf_counter() - start)
