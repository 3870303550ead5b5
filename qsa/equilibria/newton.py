"""Newton polishing of discrete equilibria: :func:`polish` and its result :class:`PolishResult`.

:func:`polish` solves the square system ``F(x) = 0`` of
:class:`~qsa.equilibria.system.EquilibriumSystem` -- ``V^n = 0`` (e:L2grad, e:Abs-CP)
with closure (e:C1, e:C2) in scaled arc length, the rigid motions fixed by a phase
condition and unfolding parameters -- by damped Newton steps with the exact Jacobian
(:func:`newton_solve`), and reports the result with the residuals, the multipliers and
the Newton record. A solve that does not converge is reported (``success=False``, a
negative ``status``, a key of :data:`MESSAGES`) with the best state found.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from qsa._checks import integer, real_number
from qsa.constraints import bind_constraints, constraint_normals
from qsa.curve import Curve, check_simple
from qsa.energies import Energy
from qsa.energies.constrained import multipliers, normal_velocity, residual_scale
from qsa.equilibria.result import Equilibrium
from qsa.equilibria.softmode import REASONS as SOFT_REASONS
from qsa.equilibria.softmode import smallest_singular, soft_mode_newton
from qsa.equilibria.system import EquilibriumSystem, equal_arclength
from qsa.equilibria.transient import pseudo_transient
from qsa.linalg import factorize

# multipliers, normal_velocity and residual_scale are properties of the energy on the
# closed manifold (qsa.energies.constrained), EquilibriumSystem has its own module; they
# are re-exported here for old imports.
__all__ = ["polish", "PolishResult", "MESSAGES", "NewtonRun", "newton_solve", "polish_result",
           "EquilibriumSystem", "multipliers", "residual_scale", "normal_velocity"]

_EPS = np.finfo(float).eps

#: Meaning of :attr:`PolishResult.status` (0 success, positive: success with a caveat,
#: negative: failure); :attr:`PolishResult.message` starts with the entry.
MESSAGES = {
    0: "converged: relative residual below tol",
    1: "converged to the round-off floor (tol is below what this grid can resolve)",
    -1: "maximum number of Newton iterations reached",
    -2: "singular or non-finite Newton system",
    -3: "line search failed: the residual does not decrease along the Newton direction",
}
#: Deprecated name of :data:`MESSAGES` (the failure codes were 2, 3, 4; now -1, -2, -3).
STATUS_MESSAGES = MESSAGES


@dataclass(frozen=True, eq=False)
class PolishResult(Equilibrium):
    """An :class:`Equilibrium` from :func:`polish`, with the Newton record.

    Besides the attributes of :class:`Equilibrium`:

    Attributes
    ----------
    status : int
        A key of :data:`MESSAGES`: 0 converged to ``tol``, 1 converged to the round-off
        floor, -1 ``maxiter`` reached, -2 singular system, -3 line search failed.
        ``success = status >= 0``.
    n_newton : int
        Newton steps taken (``n_iter`` is a read-only alias).
    n_lu : int
        Factorizations of the Newton matrix.
    history : ndarray, shape (n_newton + 1,)
        Relative residual of the square system before each step and at the end:
        ``max(max|V^n + a.phi| / scale, |C| / L)``.
    unfolding : ndarray, shape (3,)
        Final unfolding parameters ``a`` (zero up to round-off at a true equilibrium).
    noise_floor : float
        Estimated round-off level of the relative residual on this grid.
    constraints : tuple of Constraint
        The bound length / area constraints of the solve (empty without).
    constraint_multipliers : ndarray, shape (m,)
        Their multipliers ``mu_i``: ``nabla_I E = Lambda . Psi + sum_i mu_i nabla_I c_i``.

    Parameters
    ----------
    Constructed by :func:`polish`; the fields are the attributes above.

    Examples
    --------
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, kstar=5.0)
    >>> res = polish(eq.energy, eq.curve)
    >>> bool(res.success), res.status, res.n_newton <= 2
    (True, 0, True)
    """

    status: int = 0
    n_newton: int = 0
    n_lu: int = 0
    history: np.ndarray = field(default_factory=lambda: np.zeros(0))
    unfolding: np.ndarray = field(default_factory=lambda: np.zeros(3))
    noise_floor: float = 0.0
    constraints: tuple = ()
    constraint_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def n_iter(self) -> int:
        """Read-only alias of :attr:`n_newton` (the former name)."""
        return self.n_newton

    def summary(self) -> dict:
        """The :meth:`Equilibrium.summary` plus the Newton record (status, counters, history)."""
        out = super().summary()
        out.update(status=int(self.status), n_newton=int(self.n_newton), n_lu=int(self.n_lu),
                   history=[float(h) for h in self.history],
                   unfolding=[float(a) for a in self.unfolding],
                   noise_floor=float(self.noise_floor),
                   constraints=[k.params() for k in self.constraints],
                   constraint_multipliers=[float(m) for m in self.constraint_multipliers])
        return out


def _noise_floor(system, x, scale, energy=None, seed=0):
    """Relative residual change under a perturbation of x at the rounding level."""
    rng = np.random.default_rng(seed)
    F0 = system.residual(x, energy)
    x1 = x * (1 + _EPS * rng.choice([-1.0, 1.0], size=x.size))
    F1 = system.residual(x1, energy)
    return system.scaled_parts(F1 - F0, system.curve(x), scale)


def _at_floor(system, x, F, scale, tol, floor):
    """Every part of the residual is below ``max(tol, 100 x its round-off floor)``."""
    parts = system.scaled_parts(F, system.curve(x), scale)
    return bool(np.all(parts <= np.maximum(tol, 100 * floor)))


def at_round_off_floor(system, x, F, scale, tol, energy=None) -> bool:
    """Whether the residual ``F`` at ``x`` is as small as rounding lets it be.

    Every part of :meth:`EquilibriumSystem.scaled_parts` is below ``max(tol, 100 x``
    its change under a perturbation of ``x`` by one rounding unit``)``: the test by
    which :func:`newton_solve` reports status 1 (converged to the round-off floor), for
    solvers that run their own Newton iteration (the continuation's corrector).

    Parameters
    ----------
    system : EquilibriumSystem
    x : ndarray, shape (system.size,)
    F : ndarray, shape (system.size,)
        ``system.residual(x, energy)``.
    scale : float
        :func:`residual_scale` at ``x``.
    tol : float
    energy : Energy, optional

    Returns
    -------
    bool
    """
    return _at_floor(system, x, F, scale, tol, _noise_floor(system, x, scale, energy))


def _check_curve(energy, curve):
    if not isinstance(curve, Curve):
        raise ValueError(f"curve must be a qsa Curve, got {type(curve).__name__}")
    if not isinstance(energy, Energy):
        raise ValueError(f"energy must be a qsa Energy, got {type(energy).__name__}")


@dataclass(frozen=True, eq=False)
class NewtonRun:
    """The record of :func:`newton_solve`.

    Attributes
    ----------
    x : ndarray, shape (system.size,)
        The best state found (the last one unless a later step was worse).
    status : int
        A key of :data:`MESSAGES`.
    history : ndarray, shape (n_newton + 1,)
        Relative residual before each step and at the end.
    n_newton, n_lu : int
        Newton steps taken and factorizations of the Newton matrix.
    noise_floor : float
        Estimated round-off level of the relative residual.
    """

    x: np.ndarray
    status: int
    history: np.ndarray
    n_newton: int
    n_lu: int
    noise_floor: float

    @property
    def success(self) -> bool:
        """``status >= 0``."""
        return self.status >= 0


def newton_solve(system, x0, tol=1e-10, maxiter=30, energy=None, line_search=True) -> NewtonRun:
    """Damped Newton on ``system.residual`` from ``x0``.

    Step control (``line_search=True``): a trial step ``x + t dx`` (``t = 1, 1/2, ...``,
    at most 10 halvings) is accepted when the relative residual decreases, or when it
    passes the *natural monotonicity test*

        ||J(x)^{-1} F(x + t dx)|| <= (1 - t/4) ||dx||

    in the state norm :meth:`EquilibriumSystem.step_norm` (one more solve with the
    factorization of ``J(x)``). The residual itself is a poor merit for the
    equilibrium equations: ``V^n`` is a differential operator of order 4 (faceting)
    or 6 (second-order energies) in ``kappa``, so the quadratic error of a good
    Newton step, being rough, can raise ``max|V^n|`` a hundredfold although the state
    moved towards the solution. The natural test measures the residual in the norm of
    the Newton corrections instead (it is invariant under any rescaling of the
    equations), so full steps are taken wherever Newton converges. Never raises for
    non-convergence: the best state (smallest relative residual, never worse than
    ``x0``) is returned with a status code (a key of :data:`MESSAGES`).

    Parameters
    ----------
    system : EquilibriumSystem
    x0 : ndarray, shape (system.size,)
    tol : float
        Target of :meth:`EquilibriumSystem.scaled_norm`.
    maxiter : int
    energy : Energy, optional
        Another energy on the same system (default the system's).
    line_search : bool

    Returns
    -------
    NewtonRun
    """
    x = np.array(x0, dtype=float)
    scale = residual_scale(system.energy if energy is None else energy, system.curve(x))
    F = system.residual(x, energy)
    r = system.scaled_norm(F, system.curve(x), scale)
    history = [r]
    best = (r, x.copy())
    status = -1
    floor = None
    n_newton = n_lu = 0
    for it in range(maxiter + 1):
        if not np.isfinite(r):
            status = -2
            break
        if r <= tol:
            status = 0
            break
        if it == maxiter:
            status = -1
            break
        try:
            n_lu += 1
            fac = factorize(system.jacobian(x, energy))
            dx = -_solve(fac, F)
        except (RuntimeError, np.linalg.LinAlgError, ValueError):
            status = -2
            break
        if not np.all(np.isfinite(dx)):
            status = -2
            break
        size = system.step_norm(dx, x, scale)
        t = 1.0
        accepted = False
        for _ in range(11 if line_search else 1):
            xt = x + t * dx
            if xt[system.N] > 0:
                try:
                    Ft = system.residual(xt, energy)
                    rt = system.scaled_norm(Ft, system.curve(xt), scale)
                except ValueError:
                    rt = np.inf
                if np.isfinite(rt) and (not line_search or rt < r
                                        or _natural_test(system, fac, Ft, x, scale, size, t)):
                    accepted = True
                    break
            t *= 0.5
        n_newton += 1
        if not accepted:
            # At the round-off floor no step can decrease the residual any more.
            floor = _noise_floor(system, x, scale, energy)
            status = 1 if _at_floor(system, x, F, scale, tol, floor) else -3
            break
        x, F, r = xt, Ft, rt
        history.append(r)
        if r < best[0]:
            best = (r, x.copy())
        # Stagnation at the round-off floor: a step that no longer gains much.
        if len(history) >= 3 and r > 0.5 * history[-2]:
            floor = _noise_floor(system, x, scale, energy)
            if _at_floor(system, x, F, scale, tol, floor):
                status = 1 if r > tol else 0
                break
    if best[0] < r:
        x, r = best[1], best[0]
    if floor is None:
        floor = _noise_floor(system, x, scale, energy)
    return NewtonRun(x, status, np.array(history), n_newton, n_lu, float(np.max(floor)))


def _solve(fac, F):
    """``J^{-1} F`` for the unknowns of ``F``: the Newton matrix may carry extra unknowns
    (low-rank unfoldings, implicit states) after them, whose rows have zero residual."""
    b = np.zeros(fac.shape[0])
    b[:F.size] = F
    return fac.solve(b)[:F.size]


def _natural_test(system, fac, Ft, x, scale, size, t) -> bool:
    """``||J(x)^{-1} F(x + t dx)|| <= (1 - t/4) ||dx||`` (restricted monotonicity test)."""
    try:
        dxbar = _solve(fac, Ft)
    except (RuntimeError, ValueError):
        return False
    return bool(np.all(np.isfinite(dxbar))
                and system.step_norm(dxbar, x, scale) <= (1 - t / 4) * size)


def _params(energy, curve, Lambda, constraints=(), mu=()):
    params = {"L": curve.length(), "A": curve.area()}
    for t in energy.terms():  # every term's scalar parameters (the first term's win)
        for name, v in t.params().items():
            if (isinstance(v, (int, float)) and not isinstance(v, bool)
                    and name not in params):
                params[name] = float(v)
    if "beta" in params and "L_star" in params:
        params["nu2"] = params["beta"] * (params["L"] - params["L_star"])
    params["nu1"] = float(-Lambda[2])
    for con, m in zip(constraints, mu, strict=True):
        params[f"mu_{con.symbol}"] = float(m)
    return params


def polish(energy, curve: Curve, tol=1e-10, maxiter=30, *, line_search=True,
           constraints=None, globalize=True) -> PolishResult:
    """Polish an approximate equilibrium by Newton's method on ``V^n = 0`` with closure.

    Parameters
    ----------
    energy : Energy
        E.g. ``Faceting(alpha, kstar) + Perimeter(beta, L_star)``.
    curve : Curve
        Initial guess (an N-pulse, a splice, a relaxed flow state...). If its ``g``
        is not constant it is first reparameterized to constant ``g`` (same base
        point, same base angle).
    tol : float
        Target for the relative residual ``max(max|V^n| / scale, |C(U)| / L)``,
        ``scale`` = the largest single term of ``V^n`` (:func:`residual_scale`).
    maxiter : int
        Maximum number of Newton steps.
    line_search : bool
        Damp the Newton step (default True): halve it until the relative residual
        decreases or the natural monotonicity test in state space passes (see
        :func:`newton_solve`); full steps are taken wherever Newton converges.
    constraints : sequence of Constraint, optional
        Exact constraints besides closure, e.g. ``[FixedLength(), FixedArea()]``
        (:mod:`qsa.constraints`; a ``None`` target is the value of ``curve``). The
        equations become ``V^n + sum_i mu_i n_i = 0`` with ``c_i = c_i*`` (``n_L = kappa``,
        ``n_A = 1``), the multipliers ``mu_i`` unknowns of the Newton system
        (:mod:`qsa.equilibria.constraint_terms`).
    globalize : bool
        When Newton's method from the guess fails (default True): if the Jacobian at
        the guess has a soft mode (its smallest singular value below
        :data:`SOFT_RATIO` of the next), solve the other equations with the soft
        coordinate fixed and Newton's method on the soft residual
        (:func:`~qsa.equilibria.softmode.soft_mode_newton`); else, or if that fails,
        follow the gradient flow by pseudo-transient continuation
        (:func:`~qsa.equilibria.transient.pseudo_transient`, at most ``10 maxiter``
        implicit flow steps growing into Newton steps) and try Newton again from the
        states it reaches. The message says which and how many steps it took.

    Returns
    -------
    PolishResult
        An :class:`Equilibrium` (``kind="polished"``) with ``residual = max|V^n|``
        (``max|V^n + sum_i mu_i n_i|`` with constraints),
        ``closure = |C(U)|``, ``multipliers`` (Lambda, by projection of
        ``nabla_I E`` on ``span Psi`` in ``<f, h> = int f h dsigma``), ``params``
        (``L``, the energy's parameters, ``nu1 = -Lambda_3``, ``nu2 = beta (L - L*)``
        when a perimeter term is present), plus ``status``, ``n_newton``, ``n_lu``, ``history``
        (relative residual per iteration), ``unfolding``, ``noise_floor``, and the
        bound ``constraints`` with their ``constraint_multipliers`` (also in ``params``
        as ``mu_L``, ``mu_A``: ``mu_A`` is the pressure holding the shape). A solve
        that does not converge returns ``success=False`` with the best state found.

    Raises
    ------
    ValueError
        ``energy``/``curve`` of the wrong type, a curve that crosses or touches itself
        (the message names the closest pair of nodes), ``tol <= 0``, ``maxiter < 0`` or
        bad ``constraints``.

    Notes
    -----
    The square system, its gauge and its exact Jacobian are described in the
    module docstring (e:L2grad, e:Abs-CP, e:C1, e:C2). On a finite-difference
    grid the Newton matrix is sparse with four dense borders (sparse LU, O(N)
    per step); on a Fourier grid it is dense.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> from qsa.equilibria import npulse
    >>> eq = npulse(3, 0.15, grid=Fourier(127))
    >>> res = polish(eq.energy, eq.curve)
    >>> bool(res.success), res.residual < 1e-8 * res.residual_scale
    (True, True)

    An inextensible ring under pressure relaxes to the circle of its length, with
    ``mu_L = -R (p + eps / (2 R^3))`` (here ``R = 1``):

    >>> import numpy as np
    >>> from qsa.constraints import FixedLength
    >>> from qsa.energies import CanhamHelfrich, Pressure
    >>> c = Curve.polar(lambda t: 1 + 0.01 * np.cos(2 * t), Fourier(33))
    >>> res = polish(CanhamHelfrich(1.0) + Pressure(-1.0), c,
    ...              constraints=[FixedLength(2 * np.pi)])
    >>> bool(res.success), round(res.params["L"] / np.pi, 10), round(res.params["mu_L"], 8)
    (True, 2.0, 0.5)
    """
    _check_curve(energy, curve)
    check_simple(curve)
    tol = real_number(tol, "tol", positive=True)
    maxiter = integer(maxiter, "maxiter", minimum=0)
    cons = bind_constraints(constraints, curve)
    guess = equal_arclength(curve)
    system = EquilibriumSystem(energy, guess, cons)
    x0 = system.pack(guess)
    run = newton_solve(system, x0, tol, maxiter, line_search=line_search)
    note = ""
    if not run.success and globalize and maxiter > 0:
        run, note = _globalized(system, x0, run, tol, maxiter, line_search)
    res = polish_result(energy, system, run, reparameterized=curve is not guess)
    if note:
        res = replace(res, message=res.message + note)
    return res


#: A Jacobian whose smallest singular value is below this fraction of the next one has a
#: soft mode: a failed Newton solve is first retried by :func:`soft_mode_newton`.
SOFT_RATIO = 0.05


def _soft_stage(system, x0, first: NewtonRun, tol, maxiter, line_search):
    """:func:`soft_mode_newton` from ``x0`` when ``J(x0)`` has a soft mode.

    Returns ``(run, note, n_newton, n_lu)``: the converged :class:`NewtonRun` (or None),
    the message's note and the work done; ``(None, "", 0, 0)`` without a soft mode (or
    when ``J`` cannot be factored).
    """
    try:
        sig = smallest_singular(system.jacobian(x0))[0]
    except (RuntimeError, np.linalg.LinAlgError, ValueError):
        return None, "", 0, 1
    if not sig[0] <= SOFT_RATIO * sig[1]:
        return None, "", 0, 1
    sm = soft_mode_newton(system, x0, newton_solve, tol=tol, maxiter=min(maxiter, 30),
                          newton_maxiter=min(maxiter, 12), line_search=line_search)
    tau = f", soft residual tau {sm.tau[-1]:.2g}" if sm.tau.size else ""
    note = (f"; soft-mode Newton (smallest singular values of J {sig[0]:.2g} and "
            f"{sig[1]:.2g}): {sm.n_steps} steps along the soft mode{tau}, "
            f"{SOFT_REASONS[sm.reason]}, after the first Newton solve failed "
            f"({MESSAGES[first.status]})")
    nr = sm.newton
    if nr is None or not nr.success:
        return None, note, sm.n_newton, sm.n_lu + 1
    return NewtonRun(nr.x, nr.status, nr.history, first.n_newton + sm.n_newton,
                     first.n_lu + sm.n_lu + 1, nr.noise_floor), note, sm.n_newton, sm.n_lu + 1


def _globalized(system, x0, first: NewtonRun, tol, maxiter, line_search):
    """The rescue of a failed Newton solve, as one :class:`NewtonRun`: soft-mode Newton
    when ``J`` has a soft mode, else (or when it fails) pseudo-transient continuation."""
    soft, soft_note, soft_newton, soft_lu = _soft_stage(system, x0, first, tol, maxiter,
                                                         line_search)
    if soft is not None:
        return soft, soft_note
    tr = pseudo_transient(system, x0, newton_solve, tol=tol, maxiter=10 * maxiter,
                          newton_maxiter=min(maxiter, 12), line_search=line_search)
    n_newton = first.n_newton + soft_newton + tr.n_newton
    n_lu = first.n_lu + soft_lu + tr.n_lu
    flow = (f"{soft_note}; {tr.n_steps} pseudo-transient flow steps ({tr.n_rejected} "
            f"rejected, pseudo time {tr.time:.3g}) and {tr.n_attempts} Newton solves after "
            f"the first failed ({MESSAGES[first.status]})")
    nr = tr.newton
    if tr.success and nr is not None:
        return NewtonRun(nr.x, nr.status, nr.history, n_newton, n_lu, nr.noise_floor), flow
    if tr.history.size and tr.history.min() < first.history.min():
        scale = residual_scale(system.energy, system.curve(tr.x))
        floor = float(np.max(_noise_floor(system, tr.x, scale)))
        return NewtonRun(tr.x, first.status, np.append(first.history, tr.history.min()),
                         n_newton, n_lu, floor), flow
    return NewtonRun(first.x, first.status, first.history, n_newton, n_lu,
                     first.noise_floor), flow


def polish_result(energy, system, run: NewtonRun, reparameterized=False) -> PolishResult:
    """The :class:`PolishResult` of a Newton run on ``system`` (residuals, multipliers, message).

    Parameters
    ----------
    energy : Energy
        The energy the state is an equilibrium of.
    system : EquilibriumSystem
    run : NewtonRun
    reparameterized : bool
        Say in the message that the guess was reparameterized to constant ``g``.

    Returns
    -------
    PolishResult
    """
    x, status = run.x, run.status
    c = system.curve(x)
    cons = system.constraints
    mu = np.array(system.constraint_multipliers(x), dtype=float)
    V = normal_velocity(energy, c)
    if cons:
        V = V + mu @ constraint_normals(cons, c)
    scale = residual_scale(energy, c)
    res = float(np.max(np.abs(V)))
    clo = float(np.linalg.norm(c.closure()))
    Lambda = multipliers(energy, c, constraints=cons)[:3]
    name = "max|V^n + mu.n|" if cons else "max|V^n|"
    msg = (f"{MESSAGES[status]}; {run.n_newton} Newton steps, {name} = {res:.2e} "
           f"({res / scale:.1e} of the largest term), |C(U)| = {clo:.2e}, "
           f"round-off floor ~{run.noise_floor:.1e}")
    if cons:
        msg += "; " + ", ".join(f"{k.symbol} = {k.value(c):.10g} (mu_{k.symbol} = {m:.6g})"
                                for k, m in zip(cons, mu, strict=True))
    if reparameterized:
        msg += "; the guess was reparameterized to constant g"
    a = np.array(system.unfolding(x), dtype=float)
    unfolding = a if a.size == 3 else np.concatenate([a, [0.0]])
    if len(run.history) and res > 10 * run.history[-1] * scale:
        msg += (f"; max|V^n| is the unfolding's (|a| = {np.abs(a).max():.1e}): the three "
                "rigid-motion identities of V^n hold on this grid only to its accuracy "
                "(two-point energies on finite differences, or a Fourier grid too coarse "
                "for the state), so V^n = -a.phi is the discrete equilibrium")
    return PolishResult(c, energy, _params(energy, c, Lambda, cons, mu), Lambda, res, clo, scale,
                        kind="polished", success=status >= 0, message=msg, status=status,
                        n_newton=run.n_newton, n_lu=run.n_lu,
                        history=np.asarray(run.history, dtype=float), unfolding=unfolding,
                        noise_floor=float(run.noise_floor), constraints=cons,
                        constraint_multipliers=mu)
