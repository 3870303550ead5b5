"""One-parameter continuation of discrete equilibria, with the stability of every point.

For a family of energies ``E_p = energy_factory(p)`` (``p`` = alpha, beta, L*, a
pressure ...), follow the solutions of the square system of
:func:`qsa.equilibria.polish` (:mod:`qsa.continuation.steps`), ``F(x, p) = 0`` with
``x = (kappa, L, a)``:

``method="pseudo-arclength"``
    Keller's predictor-corrector on ``y = (kappa, L, p)``: Euler predictor ``y + ds t``
    along the unit tangent, Newton corrector on ``F = 0`` plus ``<y - y_pred, t>_w = 0``,
    adaptive ``ds``. Passes folds.
``method="natural"``
    March over the given parameter values (Newton from the secant extrapolation of the
    last two points); stops at a fold and says so.

Folds are where ``dp/ds`` changes sign (refined by secant steps on ``dp/ds``). With
``stability=True`` (the default) the unstable eigenvalues of every point are counted per
Bloch sector of the branch's symmetry (:mod:`qsa.continuation.detection`: one
shift-invert factorization per point, every eigenvalue of each sector computed, the
kernel deflated), each change of a sector's count is located to ``ptol`` in the
parameter by regula falsi on the critical eigenvalue (the equilibrium re-polished at
every trial point), and reported as a :class:`~qsa.continuation.branch.Bifurcation`
(``kind="fold"`` when it coincides with a fold of the symmetric sector, ``"branch"``
otherwise; multiplicity 2 for a complex sector). A branch stops with a status at
self-contact of the curve (``stop_at_contact``), at a fold it cannot pass, or at the end
of the range; numerical trouble ends it with a negative status, never an exception.
"""

from __future__ import annotations

import numpy as np

from qsa._checks import integer, real_number
from qsa.constraints import bind_constraints
from qsa.continuation.branch import MESSAGES, Bifurcation, Branch, Fold
from qsa.continuation.detection import (
    count_unstable,
    critical_modes,
    crossing_index,
    keeps_symmetry,
    locate_crossing,
)
from qsa.continuation.steps import (
    SOLVER_ERRORS,
    Problem,
    corrector,
    equilibrium,
    make_point,
    parse_span,
    tangent,
)
from qsa.curve import Curve
from qsa.discretize import Fourier
from qsa.equilibria.newton import newton_solve
from qsa.equilibria.system import equal_arclength
from qsa.linalg import factorize
from qsa.spectra.symmetry import (
    DENSE_SECTOR_LIMIT,
    BlochSymmetry,
    detect_symmetry,
    sector_spectrum,
)

__all__ = ["continuation", "touches_itself"]


class _Stability:
    """Stability of the points of one branch: sector counts (or a user callable)."""

    def __init__(self, stability, symmetry: BlochSymmetry, constraints=None, k=None):
        if not (stability is None or isinstance(stability, bool) or callable(stability)):
            raise ValueError(f"stability must be a bool or a callable (energy, curve) -> int, "
                             f"got {stability!r}")
        self.hook = stability if callable(stability) else None
        self.on = bool(stability)
        self.symmetry = symmetry
        self.constraints = constraints
        self.k = k
        self.n_solves = 0
        self.n_locate = 0
        self.unlocated: list = []  # intervals with a count change that was not located
        self.values: list = []  # per point: {b: eigenvalues of sector b, decreasing}, or None
        self.incomplete = False

    def record(self, energy, curve):
        if not self.on:
            self.values.append(None)
            return None
        if self.hook is not None:
            self.values.append(None)
            return int(self.hook(energy, curve))
        sym = self.symmetry
        if not keeps_symmetry(curve, sym):
            # the branch broke its symmetry numerically: count without sectors
            sym = BlochSymmetry(1, curve.N)
        rec, spec = count_unstable(energy, curve, sym, self.k, self.constraints)
        self.n_solves += 1
        self.incomplete |= not rec.complete
        self.values.append((sym, {b: np.sort(spec.eigenvalues[spec.sector == b])[::-1]
                                  for b in sym.sectors}))
        return rec

    def eigenvalue(self, eq, sym, b, j):
        """The ``j``-th largest eigenvalue of sector ``b`` at ``eq``: ``(lambda, error, spec)``."""
        kk = None if sym.shift <= DENSE_SECTOR_LIMIT else (self.k or 8)
        spec = sector_spectrum(eq.energy, eq.curve, sym, k=kk, sectors=[b],
                               constraints=self.constraints)
        self.n_solves += 1
        self.n_locate += 1
        i = crossing_index(spec, b, j)
        if i is None:
            return None
        return float(spec.eigenvalues[i]), float(spec.errors[i]), (spec, i)


def continuation(energy_factory, curve: Curve, param: str, values, method="pseudo-arclength",
                 *, constraints=None, tol=1e-10, maxiter=10, max_steps=200, ds_max=None,
                 ds_min=None, stability=True, refine_folds=True, locate=True, ptol=1e-10,
                 stop_at_contact=True, symmetry=None) -> Branch:
    """Follow a branch of equilibria in one parameter of the energy, with its stability.

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
        Natural: the parameter values visited. Pseudo-arclength: the branch starts at
        ``values[0]`` with a first arclength step ``|step|`` toward ``values[-1]`` and ends
        when ``p`` leaves ``[min, max]`` of the values (after any number of folds).
    method : {"pseudo-arclength", "natural"}
    constraints : sequence, optional
        Exact constraints besides closure (``qsa.constraints.FixedLength()`` ...).
    tol : float
        Newton tolerance (relative residual, as in :func:`~qsa.equilibria.polish`).
    maxiter : int
        Newton iterations per point.
    max_steps : int
        Maximum number of continuation steps.
    ds_max, ds_min : float, optional
        Arclength step bounds (default ``10 |step|`` and ``1e-4 |step|``).
    stability : bool or callable
        ``True``: count the unstable eigenvalues of every point per Bloch sector and
        locate every change (:attr:`Branch.bifurcations`); a callable
        ``(energy, curve) -> int`` is used for the counts instead (no location).
    refine_folds : bool
        Locate folds by secant steps on ``dp/ds`` (pseudo-arclength only).
    locate : bool
        Locate the crossings (else only the counts are recorded).
    ptol : float
        Location tolerance of a crossing in the parameter.
    stop_at_contact : bool
        Stop (status 1) when the curve touches itself; the last point is the last
        equilibrium without contact found by bisection of the step.
    symmetry : BlochSymmetry, optional
        The symmetry kept along the branch (default: detected at the first point).

    Returns
    -------
    Branch
        Points (each with its polished equilibrium and unstable counts), folds,
        bifurcations, ``status`` (a key of :data:`~qsa.continuation.branch.MESSAGES`)
        and ``message``. Numerical failures are reported there, never raised.

    Raises
    ------
    ValueError
        ``energy_factory`` not callable, bad ``values``/``method``/``stability``, or a
        first point that does not polish.

    Examples
    --------
    Circles of ``Faceting + Perimeter`` as ``L*`` varies have a fold, where the
    symmetric mode becomes unstable:

    >>> from qsa import Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.equilibria import circle
    >>> eq = circle(0.77, 0.1, grid=Fourier(17))
    >>> b = continuation(lambda Ls: Faceting(0.1, 5.0) + Perimeter(5.0, Ls), eq.curve,
    ...                  "L_star", (eq.params["L_star"], 3.0, -0.1))
    >>> len(b.folds), [(x.kind, x.multiplicity, x.sector) for x in b.bifurcations]
    (1, [('fold', 1, 0)])
    """
    if not callable(energy_factory):
        raise ValueError("energy_factory must be a callable p -> Energy")
    if not isinstance(curve, Curve):
        raise ValueError(f"curve must be a qsa Curve, got {type(curve).__name__}")
    if method not in ("natural", "pseudo-arclength"):
        raise ValueError(f"method must be 'natural' or 'pseudo-arclength', got {method!r}")
    tol = real_number(tol, "tol", positive=True)
    ptol = real_number(ptol, "ptol", positive=True)
    maxiter = integer(maxiter, "maxiter", minimum=0)
    max_steps = integer(max_steps, "max_steps", minimum=0)
    vals, step = parse_span(values)
    p0 = float(vals[0])
    guess = equal_arclength(curve)
    cons = bind_constraints(constraints, guess) or None
    prob = Problem(energy_factory, guess, p0, cons)
    run = newton_solve(prob.system, prob.system.pack(guess), tol, max(maxiter, 30),
                       energy=energy_factory(p0))
    if not run.success:
        raise ValueError(f"curve is not close enough to an equilibrium at {param}={p0}: "
                         f"Newton stopped with relative residual {run.history[-1]:.2e}")
    start = prob.system.curve(run.x)
    if symmetry is not None and not isinstance(symmetry, BlochSymmetry):
        raise ValueError("symmetry must be a qsa.spectra.symmetry.BlochSymmetry")
    sym = detect_symmetry(start) if symmetry is None else symmetry
    prob = prob.with_symmetry(sym)
    x0 = prob.project(np.append(run.x, p0))[:-1]
    if sym.order > 1:  # re-polish in the fixed-point space
        again = newton_solve(prob.system, x0, tol, max(maxiter, 30), energy=energy_factory(p0))
        x0 = prob.project(np.append(again.x, p0))[:-1] if again.success else run.x
    stab = _Stability(stability, sym, cons)
    opts = dict(tol=tol, maxiter=maxiter, ptol=ptol, locate=locate, contact=stop_at_contact)
    if method == "natural":
        return _natural(energy_factory, prob, x0, vals, param, stab, opts)
    return _arclength(energy_factory, prob, x0, vals, step, param, max_steps, ds_max,
                      ds_min, stab, refine_folds, opts)


# --------------------------------------------------------------------------- natural
def _natural(factory, prob, x, vals, param, stab, opts):
    tol, maxiter = opts["tol"], opts["maxiter"]
    det = factorize(prob.system.jacobian(x, factory(vals[0]))).det_sign()
    y0 = np.append(x, vals[0])
    points = [make_point(prob, y0, np.nan, det, stab.record(factory(vals[0]),
                                                            prob.system.curve(x)))]
    states, probs = [y0], [prob]
    status, msg = 0, f"{MESSAGES[0]} (natural continuation in {param})"
    n_rej = n_newton = 0
    try:
        for k in range(1, len(vals)):
            p = float(vals[k])
            prob = prob.rebased(points[-1].curve, float(vals[k - 1]))
            xprev = prob.system.pack(points[-1].curve)
            pred = xprev.copy()
            if len(states) >= 2:
                frac = (p - vals[k - 1]) / (vals[k - 1] - vals[k - 2])
                pred[: prob.N + 1] += frac * (states[-1][: prob.N + 1]
                                              - states[-2][: prob.N + 1])
            e_p = np.zeros(pred.size + 1)
            e_p[-1] = 1.0  # the corrector's hyperplane p = const: Newton at fixed p
            y, ok, its = corrector(prob, np.append(pred, p), e_p, tol, maxiter)
            if not ok:
                n_rej += 1
                status = -3
                msg = (f"{MESSAGES[-3]}: at {param}={p:.8g} (no convergence in {maxiter} "
                       f"Newton steps); the fold lies between {vals[k - 1]:.8g} and {p:.8g}")
                break
            n_newton += its
            c = prob.system.curve(y[:-1])
            if opts["contact"] and touches_itself(c):
                status = 1
                msg = f"{MESSAGES[1]}: between {param}={vals[k - 1]:.8g} and {p:.8g}"
                break
            det = factorize(prob.system.jacobian(y[:-1], factory(p))).det_sign()
            points.append(make_point(prob, y, np.nan, det, stab.record(factory(p), c), 0, (),
                                     its, its))
            states.append(y)
            probs.append(prob)
    except SOLVER_ERRORS as exc:
        status = -5
        msg = f"{MESSAGES[-5]} at {param}={points[-1].param:.8g}: {exc}"

    def solve_at(i):
        ya, yb = states[i], states[i + 1]

        def f(p):
            frac = (p - ya[-1]) / (yb[-1] - ya[-1])
            guess = ya + frac * (yb - ya)
            e_p = np.zeros(guess.size)
            e_p[-1] = 1.0
            yy, ok, _ = corrector(probs[i + 1], guess, e_p, tol, maxiter + 10)
            if not ok:
                return None
            return equilibrium(probs[i + 1], yy), p, yy
        return f, ya[-1], yb[-1]

    bifs = _bifurcations(points, stab, solve_at, (), opts, natural=True)
    bps = tuple(i for i in range(len(points) - 1)
                if points[i].det_sign != points[i + 1].det_sign)
    msg += _describe(param, (), bifs, stab)
    if bps and not stab.on:
        msg += (f"; det F_x changes sign after point(s) {list(bps)} (a fold or branch "
                "point)")
    return Branch(param, tuple(points), (), bps, "natural", status >= 0, status, msg,
                  len(points) - 1, n_rej, n_newton, bifs, stab.symmetry, stab.n_solves,
                  stab.n_locate, factory, tuple(prob.constraints or ()))


# ------------------------------------------------------------------ pseudo-arclength
def _arclength(factory, prob, x, vals, step, param, max_steps, ds_max, ds_min, stab,
               refine_folds, opts, p0=None, prev=None):
    tol, maxiter = opts["tol"], opts["maxiter"]
    lo, hi = float(np.min(vals)), float(np.max(vals))
    ds = abs(step)
    ds_max = 10 * ds if ds_max is None else real_number(ds_max, "ds_max", positive=True)
    ds_min = 1e-4 * ds if ds_min is None else real_number(ds_min, "ds_min", positive=True)
    n = x.size
    y = np.append(x, vals[0] if p0 is None else p0)
    if prev is None:
        prev = np.zeros(n + 1)
        prev[-1] = np.sign(vals[-1] - vals[0])
    t, det = tangent(prob, x, y[-1], prev)
    points = [make_point(prob, y, t[-1], det, stab.record(factory(y[-1]),
                                                          prob.system.curve(x)))]
    tangents, probs, states = [t], [prob], [y]
    status, n_rej, steps, n_newton = -2, 0, 0, 0
    msg = ""
    try:
        while steps < max_steps:
            y_new, ok, its = corrector(prob, y + ds * t, t, tol, maxiter)
            if not ok:
                n_rej += 1
                ds *= 0.5
                if ds < ds_min:
                    near_fold = abs(t[-1]) < 0.05
                    status = 2 if near_fold else -1
                    msg = (f"{MESSAGES[status]}: ds < ds_min={ds_min:.2e} at {param}="
                           f"{y[-1]:.8g}" + (f" (dp/ds = {t[-1]:.2e})" if near_fold else ""))
                    break
                continue
            cnew = prob.system.curve(y_new[:n])
            if opts["contact"] and touches_itself(cnew):
                y_c, its_c, p_in = _last_before_contact(prob, y, t, ds, tol, maxiter)
                if y_c is not None:
                    prob = prob.rebased(prob.system.curve(y_c[:n]), float(y_c[-1]))
                    y_c = np.concatenate([prob.system.pack(prob.system.curve(y_c[:n])),
                                          [y_c[-1]]])
                    t_c, det = tangent(prob, y_c[:n], y_c[-1], t)
                    c = prob.system.curve(y_c[:n])
                    points.append(make_point(prob, y_c, t_c[-1], det,
                                             stab.record(factory(y_c[-1]), c), 0, (), its_c,
                                             its_c))
                    tangents.append(t_c)
                    probs.append(prob)
                    states.append(y_c)
                    steps += 1
                status = 1
                p_in = y_new[-1] if not np.isfinite(p_in) else p_in
                msg = (f"{MESSAGES[1]}: the curve touches itself between {param}="
                       f"{points[-1].param:.10g} and {p_in:.10g}")
                break
            steps += 1
            prob = prob.rebased(cnew, float(y_new[-1]))
            y_new = np.concatenate([prob.system.pack(cnew), [y_new[-1]]])
            try:
                t_new, det = tangent(prob, y_new[:n], y_new[-1], t)
            except (np.linalg.LinAlgError, RuntimeError):
                status = -4
                msg = f"{MESSAGES[-4]} at {param}={y_new[-1]:.8g}"
                break
            y, t = y_new, t_new
            n_newton += its
            points.append(make_point(prob, y, t[-1], det, stab.record(factory(y[-1]), cnew),
                                     0, (), its, its))
            tangents.append(t)
            probs.append(prob)
            states.append(y)
            if its <= 3:
                ds = min(1.5 * ds, ds_max)
            if not (lo - 1e-12 <= y[-1] <= hi + 1e-12):
                status = 0
                msg = (f"{MESSAGES[0]} (pseudo-arclength continuation in {param}: left "
                       f"[{lo:.6g}, {hi:.6g}])")
                break
    except SOLVER_ERRORS as exc:
        status = -5
        msg = f"{MESSAGES[-5]} at {param}={points[-1].param:.8g}: {exc}"
    if status == -2:
        msg = f"{MESSAGES[-2]}: max_steps={max_steps} at {param}={y[-1]:.8g}"
    folds = []
    for i in range(len(points) - 1):
        if points[i].dp_ds * points[i + 1].dp_ds < 0:
            try:
                folds.append(_locate_fold(probs[i], states[i], points[i], points[i + 1],
                                          tangents[i], i, tol, maxiter, refine_folds))
            except SOLVER_ERRORS:
                folds.append(Fold(points[i + 1].param, i, points[i + 1].curve,
                                  points[i + 1].curve.length(), points[i + 1].dp_ds))

    def solve_at(i):
        ya, ta = states[i], tangents[i]
        wt = probs[i].weight(n)
        s_b = float(np.sum(wt * ta * (states[i + 1] - ya)))

        def f(s):
            yy, ok, _ = corrector(probs[i], ya + s * ta, ta, tol, maxiter + 10)
            if not ok:
                return None
            return equilibrium(probs[i], yy), float(yy[-1]), yy
        return f, 0.0, s_b

    bifs = _bifurcations(points, stab, solve_at, folds, opts, natural=False,
                         probs=probs, tangents=tangents)
    bps = tuple(i for i in range(len(points) - 1)
                if points[i].det_sign != points[i + 1].det_sign
                and i not in {f.index for f in folds})
    msg += _describe(param, folds, bifs, stab)
    if bps and not stab.on:
        msg += f"; det F_x changes sign without a fold after point(s) {list(bps)}"
    return Branch(param, tuple(points), tuple(folds), bps, "pseudo-arclength", status >= 0,
                  status, msg, steps, n_rej, n_newton, bifs, stab.symmetry, stab.n_solves,
                  stab.n_locate, factory, tuple(prob.constraints or ()))


def touches_itself(curve: Curve, refine=4) -> bool:
    """Whether the curve crosses or touches itself (its polygon, on a finer grid for Fourier).

    On a Fourier grid the curve is resampled to about ``refine`` times the nodes first, so
    that the chords of the polygon follow the smooth curve closely (their distance to it
    is ``h^2 kappa / 8``).
    """
    if isinstance(curve.grid, Fourier) and refine > 1:
        curve = curve.on_grid(Fourier(refine * curve.N + (refine * curve.N + 1) % 2))
    return curve.self_intersects()


def _last_before_contact(prob, y, t, ds, tol, maxiter, rtol=1e-9, max_bisections=40):
    """Bisection of the step ``ds`` for the last state without self-contact.

    Returns ``(y_last, iterations, p_contact)``: the last contact-free state found, its
    corrector iterations, and the parameter of the first state found in contact.
    """
    n = y.size - 1
    a, b = 0.0, ds
    best, best_its, p_in = None, 0, np.nan
    for _ in range(max_bisections):
        if b - a <= rtol * ds:
            break
        m = 0.5 * (a + b)
        ym, ok, its = corrector(prob, y + m * t, t, tol, maxiter)
        if not ok:
            b = m
            continue
        if touches_itself(prob.system.curve(ym[:n])):
            b, p_in = m, float(ym[-1])
        else:
            a, best, best_its = m, ym, its
    return best, best_its, p_in


def _locate_fold(prob, ya, pa, pb, ta, index, tol, maxiter, refine):
    """Secant iteration on ``dp/ds`` along the branch between two points."""
    n = prob.system.size
    yb = np.append(prob.system.pack(pb.curve), pb.param)
    wt = prob.weight(n)
    s_b = float(np.sum(wt * ta * (yb - ya)))
    s0, f0 = 0.0, pa.dp_ds
    s1, f1 = s_b, pb.dp_ds
    best = (abs(f1), pb.param, pb.curve, pb.curve.length(), f1)
    if abs(f0) < best[0]:
        best = (abs(f0), pa.param, pa.curve, pa.curve.length(), f0)
    for _ in range(8 if refine else 0):
        if f1 == f0:
            break
        s = s1 - f1 * (s1 - s0) / (f1 - f0)
        y, ok, _ = corrector(prob, ya + s * ta, ta, tol, maxiter)
        if not ok:
            break
        c = prob.system.curve(y[:n])
        p2 = prob.rebased(c, float(y[-1]))
        try:
            t, _ = tangent(p2, p2.system.pack(c), y[-1], ta)
        except (np.linalg.LinAlgError, RuntimeError):
            break
        f = float(t[-1])
        if abs(f) < best[0]:
            best = (abs(f), float(y[-1]), c, c.length(), f)
        s0, f0, s1, f1 = s1, f1, s, f
        if abs(f) < 1e-10:
            break
    return Fold(best[1], index, best[2], best[3], best[4])


# ------------------------------------------------------------------- bifurcations
def _bifurcations(points, stab, solve_at, folds, opts, natural, probs=None, tangents=None):
    """Locate every change of a sector's unstable count; add the folds not among them."""
    out = []
    fold_at = {f.index: f for f in folds}
    located_folds = set()
    for i in range(len(points) - 1):
        ra, rb = stab.values[i], stab.values[i + 1]
        if ra is None or rb is None or ra[0] != rb[0]:
            continue
        sym = ra[0]
        ca, cb = points[i].sector_unstable, points[i + 1].sector_unstable
        for b in sym.sectors:
            if ca[b] == cb[b]:
                continue
            mult = sym.multiplicity(b)
            ea, eb = ca[b] // mult, cb[b] // mult
            for j in range(min(ea, eb), max(ea, eb)):
                bif = _one_crossing(points, stab, solve_at, i, sym, b, j, mult,
                                    1 if eb > ea else -1, fold_at, opts, natural, probs,
                                    tangents)
                if bif is None:
                    if opts["locate"]:
                        stab.unlocated.append(i)
                else:
                    out.append(bif)
                    if bif[1].kind == "fold":
                        located_folds.add(i)
    for f in folds:
        if f.index not in located_folds:
            prob = probs[f.index].rebased(f.curve, f.param)
            y = np.append(prob.system.pack(f.curve), f.param)
            pos = (f.param - points[f.index].param) * (1.0 if natural else 0.0)
            out.append((pos, Bifurcation(f.param, 1, "fold", (), f.index, equilibrium(prob, y),
                                         np.nan, 0, None, stab.symmetry)))
    out.sort(key=lambda x: (x[1].index, x[0]))
    return _merge_coincident(tuple(b for _, b in out), points, opts["ptol"])


def _merge_coincident(bifs, points, ptol, rtol=1e-5):
    """One bifurcation for crossings of the same sector at the same parameter.

    Without a grid symmetry (e.g. an n-pulse on a grid whose size n does not divide) a
    symmetric double eigenvalue is two eigenvalues of one sector crossing together: they
    are located separately, at the same parameter within the location tolerance, and
    reported as one bifurcation of multiplicity 2. Coincident means within ``rtol`` of
    the step between the bracketing points (the pair splits by the round-off the
    equations without the symmetry let grow along the critical modes).
    """
    out = []
    for b in bifs:
        prev = out[-1] if out else None
        step = abs(points[b.index + 1].param - points[b.index].param)
        if (prev is not None and prev.kind == b.kind == "branch" and prev.index == b.index
                and prev.sector == b.sector and np.sign(prev.change) == np.sign(b.change)
                and abs(prev.parameter - b.parameter) <= max(100 * ptol, rtol * step)):
            out[-1] = Bifurcation(prev.parameter, prev.multiplicity + b.multiplicity, "branch",
                                  prev.modes + b.modes, prev.index, prev.equilibrium,
                                  prev.eigenvalue, prev.change + b.change, prev.tangent,
                                  prev.symmetry)
        else:
            out.append(b)
    return tuple(out)


def _one_crossing(points, stab, solve_at, i, sym, b, j, mult, sign, fold_at, opts, natural,
                  probs, tangents):
    fa = stab.values[i][1][b][j]
    fb = stab.values[i + 1][1][b][j]
    kind = "fold" if (i in fold_at and b == 0) else "branch"
    if not opts["locate"] or (fa == 0 and fb == 0):
        return None
    if not fa * fb < 0:
        # an end is zero within its error (not counted as unstable): the crossing is there
        if abs(fa) <= abs(fb):
            fa = -np.sign(fb) * max(abs(fa), 1e-300)
        else:
            fb = -np.sign(fa) * max(abs(fb), 1e-300)
    f, t0, t1 = solve_at(i)
    try:
        best = locate_crossing(f, lambda eq: stab.eigenvalue(eq, sym, b, j), t0, t1, fa, fb,
                               opts["ptol"])
    except SOLVER_ERRORS:
        best = None
    if best is None:
        return None
    pos, eq, p, lam, spec_i, yy = best
    if natural:
        pos = (p - points[i].param) * np.sign(points[i + 1].param - points[i].param)
    spec, idx = spec_i
    modes = critical_modes(spec, idx, sym)
    tan = None
    if not natural:
        try:
            prob = probs[i].rebased(eq.curve, p)
            tan, _ = tangent(prob, prob.system.pack(eq.curve), p, tangents[i])
        except SOLVER_ERRORS:
            tan = tangents[i]
    return pos, Bifurcation(float(p), mult, kind, modes, i, eq, float(lam), sign * mult, tan,
                            sym)


def _describe(param, folds, bifs, stab):
    msg = ""
    if folds:
        msg += "; folds at " + ", ".join(f"{param}={f.param:.10g}" for f in folds)
    br = [b for b in bifs if b.kind == "branch"]
    if br:
        lab = {"mode": "mode", "bloch": "Bloch index", "none": "sector"}
        msg += "; branch points at " + ", ".join(
            f"{param}={b.parameter:.10g} ({lab[b.modes[0].label]} {b.sector}"
            f"{', double' if b.multiplicity == 2 else ''})" for b in br)
    if stab.unlocated:
        msg += ("; the unstable count changes without a located crossing after point(s) "
                f"{sorted(set(stab.unlocated))} (see BranchPoint.sector_unstable)")
    if stab.incomplete:
        msg += ("; the unstable counts are of the eigenvalues nearest 0 per sector (sectors "
                "too large for the complete count)")
    return msg
