"""Implicit time steppers for the DAE curve flows (appendix "Discussion of Numerical Scheme").

Every implicit stage of the methods here is the nonlinear system ::

    G(y) = F(y, (y - psi) c) = 0,    dG/dy = dF/dy + c dF/dydot,

(:mod:`qsa.flows.base`): backward Euler has ``psi = y_n, c = 1/k``; variable-step
BDF2 has ``psi = ((1+w)^2 y_n - w^2 y_{n-1}) / (1+2w)``, ``c = (1+2w)/((1+w) k)``,
``w = k_n / k_{n-1}``.

Pieces (pure kernels first, then the stateful integrator):

* linear solvers for the Newton matrix, built on :func:`qsa.linalg.factorize` and
  :class:`qsa.linalg.LowRankUpdate`: :class:`SparseLU` (SuperLU on the
  node-interleaved ordering, a banded matrix with periodic corners),
  :class:`LowRankUpdateLU` (the local stencil LU plus a dense capacitance
  matrix for the long-range adhesion block: the block only couples the ``N``
  velocity rows to the ``2N`` position columns, so by the Woodbury identity a
  solve costs two banded solves and one ``N x N`` dense solve) and
  :class:`DenseLU` (the reference algorithm of the paper's code);
* :class:`NewtonSolver`: simplified Newton that keeps a small pool of
  factorizations (keyed by ``c``) and reuses them across iterations and
  steps; it refactorizes only when the observed contraction rate is poor;
* :class:`Integrator`: backward Euler with the paper's step doubling
  (``method="be"``) or variable-step BDF2 with a divided-difference error
  estimate (``method="bdf2"``).

Step-size control (``method="be"``, the paper's): a *pass* takes two steps of
size ``k`` and, for the error estimate, one step of size ``2k`` from the same
state; it is accepted when ``max |X_k,k - X_2k|`` over the node positions is at
most ``tol``, advancing physical time by ``2k``; the next ``k`` is
``k * min(1.3, 0.8 sqrt(tol / err))``. A rejected pass or a failed Newton solve
halves the step (as the paper's code does).

NOTE: the paper's code advances its clock by ``k`` per accepted pass while the
state advances by ``2k`` (Conventions and errata, section 7); here the clock is physical time.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from qsa import linalg

__all__ = [
    "SparseLU",
    "LowRankUpdateLU",
    "DenseLU",
    "factorize",
    "interleaved_ordering",
    "NewtonSolver",
    "Integrator",
    "METHODS",
]

#: Time-stepping methods and their orders.
METHODS = {"be": 1, "bdf2": 2}


# ------------------------------------------------------------ linear algebra
def interleaved_ordering(system):
    """Permutation that groups the unknowns of each node together.

    A :class:`~qsa.flows.models.curve_dae.CurveDAE` stacks ``y`` field by field
    (``[x_0..x_{N-1}, y_0.., kappa_0.., ..., L]``); the node-major order
    ``[x_0, y_0, kappa_0, ..., x_1, ...]`` turns the stencil Jacobian into a
    band of width ``~3 n_fields`` plus the periodic corners and the dense ``L``
    row/column, which SuperLU factorizes with O(N) fill.

    Returns
    -------
    ndarray of int, shape (size,)
        ``perm`` such that ``y[perm]`` is node-major.
    """
    N, size = int(system.N), int(system.size)
    nf = size // N
    if nf * N > size or nf == 0:
        return np.arange(size)
    head = (np.arange(nf)[None, :] * N + np.arange(N)[:, None]).ravel()
    return np.concatenate([head, np.arange(nf * N, size)])


class SparseLU:
    """Sparse LU of ``J`` on a symmetric permutation ``perm`` of the unknowns.

    A dense row (the tangential gauge ``h sum Xdot . t = 0`` couples every node)
    is fatal for a banded factorization: partial pivoting may pick it early
    (where a tangent is parallel to an axis its entries win) and then every
    later row fills in. Such rows (more than ``dense_row`` of the columns) are
    replaced by their entries in the first ``keep`` permuted columns (for the
    gauge: pinning the tangential motion of node 0, an equally valid gauge) and
    the difference is added back by the Sherman-Morrison formula: one extra
    solve per factorization, a dot product per solve. More than ``max_dense``
    dense rows (a dense block) are factorized as they are.
    """

    kind = "sparse"

    def __init__(self, J, perm=None, permc_spec="NATURAL", keep=8, dense_row=0.25,
                 max_dense=4):
        J = sp.csc_matrix(J)
        n = J.shape[0]
        self.shape = J.shape
        self.perm = np.arange(n) if perm is None else np.asarray(perm)
        Jp = J[self.perm][:, self.perm].tocsr()
        counts = np.diff(Jp.indptr)
        dense = np.flatnonzero(counts > max(64, dense_row * n))
        if dense.size > max_dense:  # many dense rows (a dense block): plain LU
            dense = dense[:0]
        if dense.size:
            rows = Jp.copy()
            W = []
            for r in dense:
                lo, hi = rows.indptr[r], rows.indptr[r + 1]
                drop = rows.indices[lo:hi] >= keep
                w = np.zeros(n)
                w[rows.indices[lo:hi][drop]] = rows.data[lo:hi][drop]
                rows.data[lo:hi][drop] = 0.0
                W.append(w)
            rows.eliminate_zeros()
            Jp = rows
        self.lu = linalg.factorize(Jp.tocsc(), permc_spec=permc_spec)
        if dense.size:
            # J = J0 + E W^T (E = unit vectors of the dense rows): Woodbury of rank |dense|
            self.lu = linalg.LowRankUpdate(self.lu, dense, np.array(W), store=True)

    def solve(self, b):
        b = np.asarray(b, dtype=float)
        x = np.empty_like(b)
        x[self.perm] = self.lu.solve(np.ascontiguousarray(b[self.perm]))
        return x


class LowRankUpdateLU:
    """Solve ``(J_loc + E_R C E_C^T) x = b`` by the Woodbury identity.

    ``J_nonlocal = E_R C E_C^T`` has its nonzeros in rows ``R`` and columns
    ``C`` only (adhesion: the ``N`` velocity rows and the ``2N`` position
    columns), ``C`` dense. With ``Z = E_C^T J_loc^{-1} E_R`` (``|R|`` banded
    solves) and the capacitance ``S = I + C Z`` (dense LU, ``|R|^3/3`` flops)::

        x0 = J_loc^{-1} b,   w = S^{-1} C x0[C],   x = J_loc^{-1} (b - E_R w).

    The factorization is O(N^2 band + N^3/3) instead of the dense
    ``(5N)^3/3`` of the paper's code; a solve is O(N^2).
    """

    kind = "woodbury"

    def __init__(self, J_local, J_nonlocal, perm=None):
        self.local = SparseLU(J_local, perm)
        Jn = sp.coo_matrix(J_nonlocal)
        rows, cols = np.unique(Jn.row), np.unique(Jn.col)
        C = sp.csr_matrix(J_nonlocal)[rows][:, cols].toarray()
        # |R| = N rows: keep only Z[cols] (two banded solves per solution)
        self.lu = linalg.LowRankUpdate(self.local, rows, C, cols, store=False)

    def solve(self, b):
        return self.lu.solve(b)


class DenseLU:
    """Dense LU of the full Newton matrix (the reference: the paper's algorithm)."""

    kind = "dense"

    def __init__(self, J):
        self.lu = linalg.factorize(J.toarray() if sp.issparse(J) else np.asarray(J))

    def solve(self, b):
        return self.lu.solve(b)


#: Linear-solver strategies accepted by :func:`factorize`.
LINEAR_SOLVERS = ("auto", "sparse", "woodbury", "dense")


def factorize(system, y, ydot, c, strategy="auto", perm=None, dense_fraction=0.2):
    """Factorize the Newton matrix ``dF/dy + c dF/dydot`` at ``(y, ydot)``.

    Parameters
    ----------
    system : DAESystem
    y, ydot : ndarray, shape (size,)
    c : float
    strategy : {"auto", "sparse", "woodbury", "dense"}
        ``"auto"`` uses :class:`LowRankUpdateLU` when the system's nonlocal
        Jacobian block (``jacobian_parts``) fills more than ``dense_fraction``
        of its row x column footprint (a long-range kernel) and a sparse LU of
        the whole matrix otherwise.
    perm : ndarray of int, optional
        Ordering for the sparse LU (default :func:`interleaved_ordering`).

    Returns
    -------
    SparseLU or LowRankUpdateLU or DenseLU
        An object with ``solve(b)``.
    """
    if strategy not in LINEAR_SOLVERS:
        raise ValueError(f"linear_solver must be one of {LINEAR_SOLVERS}, got {strategy!r}")
    if perm is None:
        perm = interleaved_ordering(system)
    if strategy == "dense":
        return DenseLU(system.jacobian(y, ydot, c))
    split = getattr(system, "jacobian_parts", None)
    if strategy == "sparse" or split is None:
        return SparseLU(system.jacobian(y, ydot, c), perm)
    J_local, J_nonlocal = split(y, ydot, c)
    if J_nonlocal.nnz == 0:
        return SparseLU(J_local, perm)
    if strategy == "auto":
        Jn = sp.coo_matrix(J_nonlocal)
        footprint = np.unique(Jn.row).size * np.unique(Jn.col).size
        if J_nonlocal.nnz < dense_fraction * footprint:
            return SparseLU((J_local + J_nonlocal).tocsc(), perm)
    return LowRankUpdateLU(J_local, J_nonlocal, perm)


# ------------------------------------------------------------------ Newton
class NewtonSolver:
    """Simplified Newton for ``F(y, (y - psi) c) = 0`` with a pool of factorizations.

    A factorization made at ``(y_J, c_J)`` is reused for any later system whose
    ``c`` is within a factor ``c_ratio`` of ``c_J`` (and across iterations and
    steps) as long as the iteration contracts at rate ``<= theta_max``;
    otherwise the matrix is refactorized at the current iterate. Convergence is
    declared when the estimated distance to the solution,
    ``theta/(1 - theta) |dy|``, is at most ``tol`` in the max norm over
    ``index`` (the positions and ``L``).

    The pool holds the points ``(y_J, ydot_J, c_J)`` so that a resumed run can
    rebuild exactly the same matrices (:meth:`get_state`, :meth:`set_state`).

    Parameters
    ----------
    system : DAESystem
    tol : float
        Absolute Newton tolerance on ``index`` components.
    index : ndarray of int
        Components measured by the convergence test.
    strategy : str
        Linear solver (:func:`factorize`).
    reuse : bool
        ``False`` gives the full Newton method (a new factorization every
        iteration), for reference.
    """

    def __init__(self, system, tol, index, strategy="auto", reuse=True, max_iter=8,
                 theta_max=0.3, c_ratio=1.5, pool_size=3):
        self.system = system
        self.tol = float(tol)
        self.index = np.asarray(index)
        self.strategy = strategy
        self.reuse = bool(reuse)
        self.max_iter = int(max_iter)
        self.theta_max = float(theta_max)
        self.c_ratio = float(c_ratio)
        self.pool_size = int(pool_size)
        self.perm = interleaved_ordering(system)
        self.pool = []  # dicts: c, y, ydot, lu
        self.n_iterations = 0
        self.n_factorizations = 0
        self.n_solves = 0
        self.n_failures = 0
        #: contraction rate of the last converged solve (tests the first iterate of the next)
        self.theta = 0.5

    # ---------------------------------------------------------- pool
    def _factorize(self, y, ydot, c):
        lu = factorize(self.system, y, ydot, c, self.strategy, self.perm)
        self.n_factorizations += 1
        entry = {"c": float(c), "y": y.copy(), "ydot": ydot.copy(), "lu": lu}
        if self.reuse:
            self.pool = [e for e in self.pool if abs(math.log(e["c"] / c)) > 1e-12]
            self.pool.append(entry)
            del self.pool[: -self.pool_size]
        return entry

    def _pick(self, c):
        if not self.reuse or not self.pool:
            return None
        best = min(self.pool, key=lambda e: abs(math.log(e["c"] / c)))
        return best if abs(math.log(best["c"] / c)) <= math.log(self.c_ratio) else None

    def get_state(self):
        """Arrays describing the pool (points where the matrices were factorized)."""
        n = self.system.size
        return {"pool_c": np.array([e["c"] for e in self.pool]),
                "pool_y": np.array([e["y"] for e in self.pool]).reshape(-1, n),
                "pool_ydot": np.array([e["ydot"] for e in self.pool]).reshape(-1, n),
                "newton_theta": np.array(self.theta)}

    def set_state(self, state):
        """Rebuild the pool (bitwise the same matrices) from :meth:`get_state` arrays."""
        self.pool = []
        self.theta = float(state["newton_theta"])
        for c, y, ydot in zip(state["pool_c"], state["pool_y"], state["pool_ydot"],
                                 strict=True):
            lu = factorize(self.system, y, ydot, c, self.strategy, self.perm)
            self.pool.append({"c": float(c), "y": np.array(y), "ydot": np.array(ydot),
                              "lu": lu})

    # --------------------------------------------------------- solve
    def solve(self, psi, c, guess):
        """Solve ``F(y, (y - psi) c) = 0`` from ``guess``.

        Returns
        -------
        y : ndarray, shape (size,)
        converged : bool
            False also when a Newton matrix is singular (``numpy.linalg.LinAlgError``).
        """
        self.n_solves += 1
        try:
            return self._iterate(psi, c, guess)
        except np.linalg.LinAlgError:
            self.n_failures += 1
            return np.array(guess, dtype=float), False

    def _iterate(self, psi, c, guess):
        sys_, idx = self.system, self.index
        y = np.array(guess, dtype=float)
        entry = self._pick(c)
        fresh = entry is None
        if fresh:
            entry = self._factorize(y, (y - psi) * c, c)
        prev, count = None, 0
        floor = 64 * np.finfo(float).eps * max(1.0, float(np.max(np.abs(y[idx]))))
        while True:
            F = sys_.residual(y, (y - psi) * c)
            dy = entry["lu"].solve(F) if np.all(np.isfinite(F)) else F
            self.n_iterations += 1
            count += 1
            norm = float(np.max(np.abs(dy[idx]))) if np.all(np.isfinite(dy)) else math.inf
            theta = norm / prev if prev else 0.0
            bad = not math.isfinite(norm) or theta >= 1.0 or count > self.max_iter
            if bad or (not fresh and theta > self.theta_max):
                if fresh:
                    self.n_failures += 1
                    return y, False
                # a stale matrix: refactorize here (or at the guess if y blew up)
                if not math.isfinite(norm):
                    y = np.array(guess, dtype=float)
                entry = self._factorize(y, (y - psi) * c, c)
                fresh, prev, count = True, None, 0
                continue
            y -= dy
            if norm <= floor:
                return y, True
            if not self.reuse:  # full Newton: a new matrix at every iterate
                entry = self._factorize(y, (y - psi) * c, c)
            if prev is None:
                # Hairer-Wanner: the first update is judged by the last known rate
                rate = min(max(self.theta, 1e-3) ** 0.8, 0.9)
                if rate / (1.0 - rate) * norm <= self.tol:
                    return y, True
            elif theta / (1.0 - theta) * norm <= self.tol:
                self.theta = theta
                return y, True
            prev = norm


# -------------------------------------------------------------- integrator
class Integrator:
    """Adaptive implicit time stepping of a DAE system (one accepted step per :meth:`step`).

    Parameters
    ----------
    system : DAESystem
    method : {"be", "bdf2"}
        Backward Euler with the paper's step doubling, or variable-step BDF2
        (started by one step-doubling pass of backward Euler) with the local
        error estimate ``|dd3| k^2 (k + k_prev)^2 / (2k + k_prev)``, ``dd3`` the
        third divided difference of the positions through the last four
        states (the exact leading term of the variable-step BDF2 truncation
        error, with ``y''' ~ 6 dd3``).
    tol : float
        Local error tolerance on the node positions (absolute, max norm).
    first_step : float
        Physical time of the first step (for ``"be"`` a pass of two steps of
        ``first_step / 2``).
    min_step, max_step : float
    newton : NewtonSolver
    """

    def __init__(self, system, method, tol, first_step, min_step, max_step, newton,
                 growth=None, safety=None):
        if method not in METHODS:
            raise ValueError(f"method must be one of {tuple(METHODS)}, got {method!r}")
        self.system = system
        self.method = method
        self.tol = float(tol)
        self.min_step = float(min_step)
        self.max_step = float(max_step)
        self.newton = newton
        self.growth = float(growth if growth is not None else (1.3 if method == "be" else 2.0))
        self.safety = float(safety if safety is not None else (0.8 if method == "be" else 0.9))
        self.index = np.asarray(system.error_index)
        self.t = 0.0
        self.y = np.array(system.y0, dtype=float)
        self.h = float(first_step)  # next proposed step (physical time)
        self.history = []  # BDF2: [(t, y)] of the two previous states, oldest first
        self.slope = None  # BE: (y_n - y_{n-1/2}) / k of the last accepted pass
        self.n_steps = 0
        self.n_rejected = 0
        self.n_newton_failures = 0
        self.last_error = 0.0
        self.last_step = 0.0

    # --------------------------------------------------------- state I/O
    def get_state(self):
        """Scalars (JSON) and arrays (npz) that restore the integrator exactly."""
        scalars = {"t": self.t, "h": self.h, "n_steps": self.n_steps,
                   "n_rejected": self.n_rejected, "n_newton_failures": self.n_newton_failures,
                   "last_error": self.last_error, "last_step": self.last_step,
                   "n_iterations": self.newton.n_iterations,
                   "n_factorizations": self.newton.n_factorizations,
                   "n_solves": self.newton.n_solves, "n_failures": self.newton.n_failures}
        arrays = {"y": self.y,
                  "history_t": np.array([t for t, _ in self.history]),
                  "history_y": np.array([y for _, y in self.history]).reshape(
                      len(self.history), self.system.size),
                  "be_slope": (np.zeros((0, self.system.size)) if self.slope is None
                               else self.slope[None, :])}
        arrays.update(self.newton.get_state())
        return scalars, arrays

    def set_state(self, scalars, arrays):
        self.t = float(scalars["t"])
        self.h = float(scalars["h"])
        for name in ("n_steps", "n_rejected", "n_newton_failures"):
            setattr(self, name, int(scalars[name]))
        self.last_error = float(scalars["last_error"])
        self.last_step = float(scalars["last_step"])
        for name in ("n_iterations", "n_factorizations", "n_solves", "n_failures"):
            setattr(self.newton, name, int(scalars[name]))
        self.y = np.array(arrays["y"], dtype=float)
        self.history = [(float(t), np.array(y)) for t, y in
                        zip(arrays["history_t"], arrays["history_y"], strict=True)]
        slope = arrays["be_slope"]
        self.slope = np.array(slope[0]) if slope.shape[0] else None
        self.newton.set_state(arrays)

    # ------------------------------------------------------------ steps
    def _be_pass(self, h):
        """Two backward Euler steps of ``h/2`` and one of ``h``: (y_half, y_new, err) or None."""
        solve, y = self.newton.solve, self.y
        k = 0.5 * h
        guess = y
        if self.slope is not None:  # extrapolate the last substep's velocity
            guess = y + k * self.slope
        ya, ok = solve(y, 1.0 / k, guess)
        if not ok:
            return None
        yb, ok = solve(ya, 1.0 / k, 2 * ya - y)
        if not ok:
            return None
        yc, ok = solve(y, 1.0 / h, yb)
        if not ok:
            return None
        err = float(np.max(np.abs(yb[self.index] - yc[self.index])))
        return ya, yb, err

    def _bdf2_step(self, h):
        """One variable-step BDF2 step: (y_new, err) or None."""
        (t2, y2), (t1, y1) = self.history
        t0, y0 = self.t, self.y
        hp = t0 - t1
        w = h / hp
        psi = ((1 + w) ** 2 * y0 - w * w * y1) / (1 + 2 * w)
        c = (1 + 2 * w) / ((1 + w) * h)
        tn = t0 + h
        # quadratic extrapolation through the last three states (predictor)
        l2 = (tn - t1) * (tn - t0) / ((t2 - t1) * (t2 - t0))
        l1 = (tn - t2) * (tn - t0) / ((t1 - t2) * (t1 - t0))
        l0 = (tn - t2) * (tn - t1) / ((t0 - t2) * (t0 - t1))
        pred = l2 * y2 + l1 * y1 + l0 * y0
        yn, ok = self.newton.solve(psi, c, pred)
        if not ok:
            return None
        # y_n+1 - pred = dd3 (tn - t2)(tn - t1)(tn - t0)
        dd3 = (yn[self.index] - pred[self.index]) / ((tn - t2) * (tn - t1) * h)
        err = float(np.max(np.abs(dd3))) * h * h * (h + hp) ** 2 / (2 * h + hp)
        return yn, err

    def step(self, t_stop):
        """Take one accepted step without passing ``t_stop``.

        Returns
        -------
        status : str
            ``"accepted"``, or ``"failed"`` when Newton fails below ``min_step``
            (the state is left at the last accepted step).
        """
        while True:
            remaining = t_stop - self.t
            h = min(self.h, self.max_step)
            clipped = h >= remaining * (1 - 1e-9)
            if clipped:
                h = remaining
            if h < self.min_step and not clipped:
                return "failed"
            bdf = self.method == "bdf2" and len(self.history) == 2
            out = self._bdf2_step(h) if bdf else self._be_pass(h)
            if out is None:
                self.n_newton_failures += 1
                self.h = 0.5 * h
                if self.h < self.min_step:
                    return "failed"
                continue
            err = out[-1]
            order = 2 if bdf else 1
            factor = self.growth if err == 0 else min(
                self.growth, self.safety * (self.tol / err) ** (1.0 / (order + 1)))
            if err <= self.tol:
                t_new = t_stop if clipped else self.t + h
                if bdf:
                    self.history = [self.history[1], (self.t, self.y)]
                    self.y = out[0]
                elif self.method == "bdf2":  # the starting pass supplies three states
                    self.history = [(self.t, self.y), (self.t + 0.5 * h, out[0])]
                    self.y = out[1]
                else:
                    self.slope = (out[1] - out[0]) / (0.5 * h)
                    self.y = out[1]
                self.t = t_new
                self.n_steps += 1
                self.last_error, self.last_step = err, h
                h_next = h * factor
                if clipped:  # do not let a clipped step shrink the proposal
                    h_next = max(h_next, min(self.h, h * self.growth))
                self.h = h_next
                return "accepted"
            self.n_rejected += 1
            # the paper's code halves a rejected pass; BDF2 uses the usual factor
            self.h = 0.5 * h if not bdf else h * max(factor, 0.2)
