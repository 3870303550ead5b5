"""One-parameter continuation of discrete equilibria: natural and pseudo-arclength steps.

For a family of energies ``E_p = energy_factory(p)`` (``p`` = alpha, beta, L*, a
multiplier ...), follow the solutions of the square system of
:func:`qsa.equilibria.polish` (:class:`~qsa.equilibria.newton.EquilibriumSystem`),
``F(x, p) = 0`` with ``x = (kappa, L, a)``:

``method="natural"``
    March over the given parameter values; each point is polished by Newton from
    the secant extrapolation of the last two. Cannot pass a fold: it stops there
    and says so.
``method="pseudo-arclength"``
    Keller's predictor-corrector on ``y = (kappa, L, p)``: tangent ``t`` from
    ``[F_x, F_p] t = 0`` (``F_p`` by central differences in ``p``), Euler predictor
    ``y + ds t``, Newton corrector on ``F = 0`` plus the arclength condition
    ``<y - y_pred, t>_w = 0`` (``<., .>_w``: grid quadrature on kappa, plain on L and
    p), adaptive ``ds``. Passes folds.

Folds are detected where ``dp/ds`` (the p-component of the tangent) changes sign;
their location is refined by secant steps on ``dp/ds`` along the branch. The sign
of ``det F_x`` (of the square bordered system) is recorded at every point: it
changes at folds and at branch points, so a sign change without a fold is
reported as a possible branch point. With ``stability=True`` (or a callable) the
number of unstable eigenvalues is computed at every point (``qsa.spectra``).
"""

from __future__ import annotations

import numpy as np

from qsa import spectra
from qsa._checks import integer, real_number
from qsa.continuation.branch import MESSAGES, Branch, BranchPoint, Fold
from qsa.curve import Curve
from qsa.energies import residual_scale
from qsa.equilibria.newton import (
    EquilibriumSystem,
    NewtonRun,
    _assemble,
    _equal_arclength,
    _Factor,
    newton_solve,
    polish_result,
)

__all__ = ["continuation"]


def _stability_hook(stability):
    if stability is None or stability is False:
        return None
    if callable(stability):
        return stability
    if stability is True:
        return lambda energy, curve: int(spectra.spectrum(energy, curve).n_unstable)
    raise ValueError(f"stability must be a bool or a callable (energy, curve) -> int, "
                     f"got {stability!r}")


class _Problem:
    """``F(x, p)`` around a reference point (phase and unfolding fields of that point)."""

    def __init__(self, factory, curve: Curve, p: float):
        self.factory = factory
        self.p = p
        self.system = EquilibriumSystem(factory(p), curve)
        self.N = curve.N
        self.w = curve.grid.weights

    def F(self, x, p):
        return self.system.residual(x, self.factory(p))

    def F_p(self, x, p):
        h = 1e-6 * max(abs(p), 1.0)
        return (self.F(x, p + h) - self.F(x, p - h)) / (2 * h)

    def parts(self, x, p):
        return self.system.jacobian_parts(x, self.factory(p))

    def weight(self, n):
        """Arclength weights on the full state ``(kappa, L, a, p)`` (``a`` weighted 0)."""
        N = self.N
        wt = np.zeros(n + 1)
        wt[:N] = self.w
        wt[N] = 1.0
        wt[-1] = 1.0
        return wt

    def augmented(self, x, p, row):
        """Factor of ``[[F_x, F_p], [row]]`` (row on ``(x, p)``), and of ``F_x`` alone."""
        A, B, Crows, D, low = self.parts(x, p)
        Fp = self.F_p(x, p)
        N = self.N
        B2 = np.column_stack([B, Fp[:N]])
        C2 = np.vstack([Crows, row[:N]])
        D2 = np.zeros((D.shape[0] + 1, D.shape[1] + 1))
        D2[:-1, :-1] = D
        D2[:-1, -1] = Fp[N:]
        D2[-1, :-1] = row[N:-1]
        D2[-1, -1] = row[-1]
        aug = _assemble(A, B2, C2, D2, low)
        return aug, _assemble(A, B, Crows, D, low)


def _solve_aug(aug, rhs):
    fac = _Factor(aug)
    if fac.singular:
        raise np.linalg.LinAlgError("singular augmented system")
    out = fac.solve(rhs)
    if not np.all(np.isfinite(out)):
        raise np.linalg.LinAlgError("non-finite solution")
    return out


def _pad(v, r):
    return np.concatenate([v, np.zeros(r)]) if r else v


def _tangent(prob, x, p, prev):
    """Unit tangent (in the weighted norm) of the branch at (x, p), oriented like ``prev``.

    Also returns ``sign det F_x``.
    """
    n = x.size
    wt = prob.weight(n)
    row = prev * wt
    aug, Fx = prob.augmented(x, p, row)
    rhs = np.zeros(aug.shape[0])
    rhs[n] = 1.0  # the row of ``row`` sits after the n rows of F (closure rows included)
    t = _solve_aug(aug, rhs)[: n + 1]
    t /= np.sqrt(np.sum(wt * t * t))
    if np.sum(wt * t * prev) < 0:
        t = -t
    det_sign = _Factor(Fx).det_sign()
    return t, det_sign


def _corrector(prob, y_pred, t, tol, maxiter):
    """Newton on ``[F(x, p); <y - y_pred, t>_w] = 0``; returns ``(y, ok, iters)``."""
    n = y_pred.size - 1
    wt = prob.weight(n)
    row = t * wt
    y = y_pred.copy()
    energy = prob.factory(y[-1])
    scale = residual_scale(energy, prob.system.curve(y[:n]))
    for it in range(maxiter + 1):
        x, p = y[:-1], y[-1]
        if x[prob.N] <= 0:
            return y, False, it
        try:
            F = prob.F(x, p)
        except ValueError:
            return y, False, it
        g = np.sum(row * (y - y_pred))
        r = prob.system.scaled_norm(F, prob.system.curve(x), scale)
        if not np.isfinite(r):
            return y, False, it
        if r <= tol and abs(g) <= tol * 10:
            return y, True, it
        if it == maxiter:
            break
        try:
            aug, _ = prob.augmented(x, p, row)
            rhs = np.concatenate([F, [g], np.zeros(aug.shape[0] - n - 1)])
            dy = -_solve_aug(aug, rhs)[: n + 1]
        except (np.linalg.LinAlgError, RuntimeError, ValueError):
            return y, False, it
        y = y + dy
    return y, False, maxiter


def _point(prob, y, dp_ds, det_sign, hook, status=0, history=(), n_newton=0, n_lu=0):
    n = y.size - 1
    energy = prob.factory(y[-1])
    run = NewtonRun(y[:n], status, np.asarray(history, dtype=float), n_newton, n_lu, 0.0)
    eq = polish_result(energy, prob.system, run)
    nu = hook(energy, eq.curve) if hook is not None else None
    return BranchPoint(float(y[-1]), eq, float(dp_ds), int(det_sign), nu)


def _values(values):
    if isinstance(values, tuple) and len(values) == 3:
        start, stop, step = (float(v) for v in values)
        if not np.all(np.isfinite([start, stop, step])) or step == 0:
            raise ValueError(f"values=(start, stop, step) needs finite numbers and step != 0, "
                             f"got {values!r}")
        if (stop - start) * step < 0:
            raise ValueError(f"values=(start, stop, step): step {step} points away from stop")
        n = int(np.floor((stop - start) / step + 1e-9)) + 1
        vals = start + step * np.arange(n)
        if abs(vals[-1] - stop) > 1e-9 * max(abs(stop), 1.0):
            vals = np.append(vals, stop)
        return vals, step
    vals = np.asarray(values, dtype=float).ravel()
    if vals.size < 2 or not np.all(np.isfinite(vals)):
        raise ValueError("values must be (start, stop, step) or at least two finite values")
    d = np.diff(vals)
    if not (np.all(d > 0) or np.all(d < 0)):
        raise ValueError("values must be strictly monotone")
    return vals, float(d[0])


def continuation(energy_factory, curve: Curve, param: str, values, method="pseudo-arclength",
                 *, tol=1e-10, maxiter=10, max_steps=200, ds_max=None, ds_min=None,
                 stability=False, refine_folds=True) -> Branch:
    """Follow a branch of equilibria in one parameter of the energy.

    Parameters
    ----------
    energy_factory : callable
        ``energy_factory(p) -> Energy``, e.g.
        ``lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls)``.
    curve : Curve
        An (approximate) equilibrium at the first parameter value; polished first.
    param : str
        Name of the parameter (for reports).
    values : (start, stop, step) or array_like
        Natural: the parameter values visited. Pseudo-arclength: the branch starts
        at ``values[0]`` with a first step of ``|step|`` (initial arclength step)
        toward ``values[-1]`` and ends when ``p`` leaves ``[min, max]`` of the
        values (after any number of folds) or after ``max_steps``.
    method : {"pseudo-arclength", "natural"}
    tol : float
        Newton tolerance (relative residual, as in :func:`polish`).
    maxiter : int
        Newton iterations per point.
    max_steps : int
        Maximum number of continuation steps.
    ds_max, ds_min : float, optional
        Arclength step bounds (default ``10 |step|`` and ``1e-4 |step|``).
    stability : bool or callable
        ``True``: number of unstable eigenvalues at every point with
        ``qsa.spectra.spectrum(energy, curve).n_unstable``;
        a callable ``(energy, curve) -> int`` is used instead if given.
    refine_folds : bool
        Locate folds by secant steps on ``dp/ds`` (pseudo-arclength only).

    Returns
    -------
    Branch
        Points (each with its polished :class:`~qsa.equilibria.result.Equilibrium`),
        folds, possible branch points, success/status/message. Failures are
        reported in the result, never raised.

    Raises
    ------
    ValueError
        ``energy_factory`` not callable, bad ``values``, unknown ``method``, or a
        first point that does not polish.

    Examples
    --------
    Circles of ``Faceting + Perimeter`` as ``L*`` varies have a fold:

    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.equilibria import circle
    >>> eq = circle(0.77, 0.1, grid=Fourier(17))
    >>> b = continuation(lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls), eq.curve,
    ...                  "L_star", (eq.params["L_star"], 3.0, -0.1))
    >>> len(b.folds)
    1
    """
    if not callable(energy_factory):
        raise ValueError("energy_factory must be a callable p -> Energy")
    if not isinstance(curve, Curve):
        raise ValueError(f"curve must be a qsa Curve, got {type(curve).__name__}")
    if method not in ("natural", "pseudo-arclength"):
        raise ValueError(f"method must be 'natural' or 'pseudo-arclength', got {method!r}")
    tol = real_number(tol, "tol", positive=True)
    maxiter = integer(maxiter, "maxiter", minimum=0)
    max_steps = integer(max_steps, "max_steps", minimum=0)
    vals, step = _values(values)
    hook = _stability_hook(stability)
    p0 = float(vals[0])
    guess = _equal_arclength(curve)
    prob = _Problem(energy_factory, guess, p0)
    run = newton_solve(prob.system, prob.system.pack(guess), tol, max(maxiter, 30),
                       energy=energy_factory(p0))
    if not run.success:
        raise ValueError(f"curve is not close enough to an equilibrium at {param}={p0}: "
                         f"Newton stopped with relative residual {run.history[-1]:.2e}")
    if method == "natural":
        return _natural(energy_factory, prob, run.x, vals, param, tol, maxiter, hook)
    return _arclength(energy_factory, prob, run.x, vals, step, param, tol, maxiter, max_steps,
                      ds_max, ds_min, hook, refine_folds)


def _natural(factory, prob, x, vals, param, tol, maxiter, hook):
    points = []
    det = _Factor(prob.system.jacobian(x, factory(vals[0]))).det_sign()
    points.append(_point(prob, np.append(x, vals[0]), np.nan, det, hook))
    xs = [x]
    status, msg = 0, f"{MESSAGES[0]} (natural continuation in {param})"
    n_rej = n_newton = 0
    for k in range(1, len(vals)):
        p = float(vals[k])
        prob = _Problem(factory, points[-1].curve, float(vals[k - 1]))
        xprev = prob.system.pack(points[-1].curve)
        if len(xs) >= 2:
            frac = (p - vals[k - 1]) / (vals[k - 1] - vals[k - 2])
            pred = xprev.copy()
            pred[: prob.N + 1] += frac * (xs[-1][: prob.N + 1] - xs[-2][: prob.N + 1])
        else:
            pred = xprev
        run = newton_solve(prob.system, pred, tol, maxiter, energy=factory(p))
        if not run.success:
            n_rej += 1
            status = -3
            msg = (f"{MESSAGES[-3]}: at {param}={p:.8g} (relative residual "
                   f"{run.history.min():.2e}); the fold lies between {vals[k - 1]:.8g} "
                   f"and {p:.8g}")
            break
        n_newton += run.n_newton
        xn = run.x
        det = _Factor(prob.system.jacobian(xn, factory(p))).det_sign()
        points.append(_point(prob, np.append(xn, p), np.nan, det, hook, run.status,
                             run.history, run.n_newton, run.n_lu))
        xs.append(xn)
    bps = tuple(i for i in range(len(points) - 1)
                if points[i].det_sign != points[i + 1].det_sign)
    if bps:
        msg += (f"; det F_x changes sign after point(s) {list(bps)} (a fold or branch "
                "point)")
    return Branch(param, tuple(points), (), bps, "natural", status >= 0, status, msg,
                  len(points) - 1, n_rej, n_newton)


def _arclength(factory, prob, x, vals, step, param, tol, maxiter, max_steps, ds_max, ds_min,
               hook, refine_folds):
    lo, hi = float(np.min(vals)), float(np.max(vals))
    ds = abs(step)
    ds_max = 10 * ds if ds_max is None else real_number(ds_max, "ds_max", positive=True)
    ds_min = 1e-4 * ds if ds_min is None else real_number(ds_min, "ds_min", positive=True)
    n = x.size
    y = np.append(x, vals[0])
    prev = np.zeros(n + 1)
    prev[-1] = np.sign(vals[-1] - vals[0])
    t, det = _tangent(prob, x, y[-1], prev)
    points = [_point(prob, y, t[-1], det, hook)]
    tangents = [t]
    probs = [prob]
    status, n_rej, steps, n_newton = -2, 0, 0, 0
    msg = ""
    while steps < max_steps:
        y_pred = y + ds * t
        y_new, ok, its = _corrector(prob, y_pred, t, tol, maxiter)
        if not ok:
            n_rej += 1
            ds *= 0.5
            if ds < ds_min:
                status = -1
                msg = f"{MESSAGES[-1]}: ds_min={ds_min:.2e} at {param}={y[-1]:.8g}"
                break
            continue
        steps += 1
        # new reference system at the new point (phase and unfolding fields follow the branch)
        cnew = prob.system.curve(y_new[:n])
        prob = _Problem(factory, cnew, float(y_new[-1]))
        y_new = np.concatenate([prob.system.pack(cnew), [y_new[-1]]])
        try:
            t_new, det = _tangent(prob, y_new[:n], y_new[-1], t)
        except (np.linalg.LinAlgError, RuntimeError):
            status = -4
            msg = f"{MESSAGES[-4]} at {param}={y_new[-1]:.8g}"
            break
        y, t = y_new, t_new
        n_newton += its
        points.append(_point(prob, y, t[-1], det, hook, 0, (), its, its))
        tangents.append(t)
        probs.append(prob)
        if its <= 3:
            ds = min(1.5 * ds, ds_max)
        if not (lo - 1e-12 <= y[-1] <= hi + 1e-12):
            status = 0
            msg = (f"{MESSAGES[0]} (pseudo-arclength continuation in {param}: left "
                   f"[{lo:.6g}, {hi:.6g}])")
            break
    if status == -2:
        msg = f"{MESSAGES[-2]}: max_steps={max_steps} at {param}={y[-1]:.8g}"
    folds = []
    for i in range(len(points) - 1):
        a, b = points[i].dp_ds, points[i + 1].dp_ds
        if a * b < 0:
            folds.append(_locate_fold(probs[i], points[i], points[i + 1], tangents[i],
                                      i, tol, maxiter, refine_folds))
    fold_idx = {f.index for f in folds}
    bps = tuple(i for i in range(len(points) - 1)
                if points[i].det_sign != points[i + 1].det_sign and i not in fold_idx)
    if folds:
        msg += "; folds at " + ", ".join(f"{param}={f.param:.10g}" for f in folds)
    if bps:
        msg += f"; det F_x changes sign without a fold after point(s) {list(bps)}"
    return Branch(param, tuple(points), tuple(folds), bps, "pseudo-arclength", status >= 0,
                  status, msg, steps, n_rej, n_newton)


def _locate_fold(prob, pa, pb, ta, index, tol, maxiter, refine):
    """Secant iteration on ``dp/ds`` along the branch between two points."""
    n = prob.system.size
    ya = np.append(prob.system.pack(pa.curve), pa.param)
    yb = np.append(prob.system.pack(pb.curve), pb.param)
    wt = prob.weight(n)
    s_b = float(np.sum(wt * ta * (yb - ya)))
    s0, f0 = 0.0, pa.dp_ds
    s1, f1 = s_b, pb.dp_ds
    best = (abs(f1), pb.param, pb.curve, pb.equilibrium.params["L"], f1)
    if abs(f0) < best[0]:
        best = (abs(f0), pa.param, pa.curve, pa.equilibrium.params["L"], f0)
    for _ in range(8 if refine else 0):
        if f1 == f0:
            break
        s = s1 - f1 * (s1 - s0) / (f1 - f0)
        y, ok, _ = _corrector(prob, ya + s * ta, ta, tol, maxiter)
        if not ok:
            break
        c = prob.system.curve(y[:n])
        p2 = _Problem(prob.factory, c, float(y[-1]))
        try:
            t, _ = _tangent(p2, p2.system.pack(c), y[-1], ta)
        except (np.linalg.LinAlgError, RuntimeError):
            break
        f = float(t[-1])
        if abs(f) < best[0]:
            best = (abs(f), float(y[-1]), c, c.length(), f)
        s0, f0, s1, f1 = s1, f1, s, f
        if abs(f) < 1e-10:
            break
    return Fold(best[1], index, best[2], best[3], best[4])
