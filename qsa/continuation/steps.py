"""The numerical kernels of continuation: the square system in ``(x, p)``, tangents, corrector.

``F(x, p) = 0`` is the square system of :func:`qsa.equilibria.polish`
(:class:`~qsa.equilibria.system.EquilibriumSystem`) with ``x = (kappa, L, a)`` for the
energy ``energy_factory(p)``. The tangent ``t`` of the branch solves
``[F_x, F_p; row] t = e`` (``F_p`` by central differences in ``p``); the corrector is
Newton on ``[F(x, p); <y - y_pred, t>_w] = 0`` with ``<., .>_w`` the grid quadrature on
``kappa`` and plain on ``L`` and ``p``.

The structure of the system (circle or not: with or without the phase condition and
the rotation's unfolding field) is fixed for a whole branch: :meth:`Problem.rebased`
moves the reference point along the branch but keeps it, so the unknowns of every
point of a branch have the same layout.
"""

from __future__ import annotations

import numpy as np

from qsa.continuation.branch import BranchPoint
from qsa.curve import Curve
from qsa.energies import residual_scale
from qsa.equilibria.newton import NewtonRun, at_round_off_floor, polish_result
from qsa.equilibria.system import EquilibriumSystem, assemble_jacobian, bordered_matrix
from qsa.linalg import factorize

__all__ = ["Problem", "tangent", "corrector", "equilibrium", "make_point", "parse_span",
           "SOLVER_ERRORS"]

#: Exceptions a numerical step can raise; continuation turns them into a status.
SOLVER_ERRORS = (np.linalg.LinAlgError, RuntimeError, ValueError, FloatingPointError,
                 ArithmeticError)


class Problem:
    """``F(x, p)`` around a reference point (phase and unfolding fields of that point).

    Parameters
    ----------
    factory : callable
        ``p -> Energy``.
    curve : Curve
        Reference point (constant ``g``).
    p : float
    constraints : sequence, optional
        Extra exact constraints (``FixedLength``, ``FixedArea``) of the system.
    system : EquilibriumSystem, optional
        Use this system (its structure) instead of building one.
    symmetry : BlochSymmetry, optional
        Keep the states in its fixed-point space (:meth:`project`).
    """

    def __init__(self, factory, curve: Curve, p: float, constraints=None, system=None,
                 symmetry=None):
        self.factory = factory
        self.p = p
        self.constraints = constraints
        self.symmetry = symmetry
        self.system = system if system is not None else _system(factory(p), curve, constraints)
        self.N = curve.N
        self.w = curve.grid.weights

    def rebased(self, curve: Curve, p: float) -> Problem:
        """The problem around a new reference point with the same unknowns' layout."""
        new = Problem(self.factory, curve, p, self.constraints, symmetry=self.symmetry)
        if new.system.size != self.system.size or new.system.circle != self.system.circle:
            return Problem(self.factory, curve, p, self.constraints, system=self.system,
                           symmetry=self.symmetry)
        return new

    def with_symmetry(self, symmetry) -> Problem:
        """The same problem keeping the states ``symmetry``-invariant."""
        return Problem(self.factory, self.system.ref, self.p, self.constraints, self.system,
                       symmetry)

    def project(self, y):
        """``y`` with ``kappa`` averaged over the symmetry's shifts (the fixed-point space).

        The equations are equivariant, so a Newton step from a symmetric state is
        symmetric up to round-off; near a symmetry-breaking bifurcation the round-off
        would grow along the critical mode, which the projection removes.
        """
        sym = self.symmetry
        if sym is None or sym.order == 1:
            return y
        y = np.array(y, dtype=float)
        k = y[: self.N]
        if sym.circle:
            y[: self.N] = np.mean(k)
        else:
            y[: self.N] = np.mean(k.reshape(sym.order, sym.shift), axis=0)[
                np.arange(self.N) % sym.shift]
        return y

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
        parts = self.parts(x, p)
        aug = bordered_matrix(parts, self.F_p(x, p), row[:-1], row[-1])
        return aug, assemble_jacobian(*parts)


def _solve_aug(aug, rhs):
    out = factorize(aug).solve(rhs)  # LinAlgError if singular
    if not np.all(np.isfinite(out)):
        raise np.linalg.LinAlgError("non-finite solution")
    return out


def tangent(prob, x, p, prev):
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
    det_sign = factorize(Fx).det_sign()
    return t, det_sign


def corrector(prob, y_pred, t, tol, maxiter):
    """Newton on ``[F(x, p); <y - y_pred, t>_w] = 0``; returns ``(y, ok, iters)``."""
    n = y_pred.size - 1
    wt = prob.weight(n)
    row = t * wt
    y = prob.project(y_pred)
    energy = prob.factory(y[-1])
    scale = residual_scale(energy, prob.system.curve(y[:n]))
    r_prev = None
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
        # a step that no longer gains much: accept the round-off floor (polish's status 1;
        # sixth-order energies on fine grids cannot reach tol = 1e-10)
        if (r_prev is not None and r > 0.5 * r_prev and abs(g) <= tol * 10
                and at_round_off_floor(prob.system, x, F, scale, tol, prob.factory(p))):
            return y, True, it
        r_prev = r
        if it == maxiter:
            break
        try:
            aug, _ = prob.augmented(x, p, row)
            rhs = np.concatenate([F, [g], np.zeros(aug.shape[0] - n - 1)])
            dy = -_solve_aug(aug, rhs)[: n + 1]
        except (np.linalg.LinAlgError, RuntimeError, ValueError):
            return y, False, it
        y = prob.project(y + dy)
    return y, False, maxiter


def equilibrium(prob, y, status=0, history=(), n_newton=0, n_lu=0):
    """The :class:`~qsa.equilibria.PolishResult` of the state ``y = (x, p)``."""
    n = y.size - 1
    energy = prob.factory(y[-1])
    run = NewtonRun(y[:n], status, np.asarray(history, dtype=float), n_newton, n_lu, 0.0)
    return polish_result(energy, prob.system, run)


def make_point(prob, y, dp_ds, det_sign, record=None, status=0, history=(), n_newton=0,
               n_lu=0):
    """A :class:`BranchPoint` at ``y`` with its stability record (or a plain count)."""
    eq = equilibrium(prob, y, status, history, n_newton, n_lu)
    if record is None or isinstance(record, (int, np.integer)):
        return BranchPoint(float(y[-1]), eq, float(dp_ds), int(det_sign), record)
    return BranchPoint(float(y[-1]), eq, float(dp_ds), int(det_sign), record.n_unstable,
                       record.sector_unstable, record.critical)


def parse_span(values):
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




def _system(energy, curve, constraints):
    if not constraints:
        return EquilibriumSystem(energy, curve)
    try:
        return EquilibriumSystem(energy, curve, constraints=constraints)
    except TypeError as exc:
        raise ValueError("constraints=... needs the constrained equilibrium system "
                         "(qsa.constraints), which this installation lacks") from exc
