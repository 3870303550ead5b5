"""Geometric rows shared by the curve DAEs: positions, equal chords, curvature, gauge.

See :mod:`qsa.flows.dae` for the equations and sign conventions.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from qsa.curve import self_intersections
from qsa.flows.base import DAESystem
from qsa.flows.models.constrained import ConstraintRows, polygon_area
from qsa.linalg import factorize

__all__ = ["CurveDAE", "equalize_chords", "self_intersections"]


# ----------------------------------------------------------------- helpers
def _check_xy(x, y, min_nodes):
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.ndim != 1 or x.shape != y.shape:
        raise ValueError(f"x and y must be 1-d arrays of equal length, got {x.shape}, {y.shape}")
    if x.size < min_nodes:
        raise ValueError(f"x, y have N={x.size} nodes; the model needs N >= {min_nodes}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("x, y contain NaN or inf")
    chords = np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)
    if np.any(chords == 0):
        raise ValueError("x, y contain repeated consecutive nodes (zero chord)")
    area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    if not area > 0:
        raise ValueError(
            "x, y must describe a counter-clockwise closed curve (signed area > 0); "
            "reverse the node order of a clockwise curve"
        )
    crossings = self_intersections(x, y)
    if crossings.shape[0]:
        i, j = crossings[0]
        raise ValueError(
            f"x, y: the polygon intersects itself ({crossings.shape[0]} crossing segment "
            f"pair(s), e.g. segments {i} and {j}); initial data must be a simple curve"
        )
    return x, y


def equalize_chords(x, y, *, tol=1e-13, maxiter=30, max_spread=0.05):
    """Project node positions onto equal chords ``|X_{j+1} - X_j| = L/N`` (ap:scaled).

    Minimum-norm Gauss-Newton steps on ``|X_{j+1} - X_j|^2 = (L/N)^2`` with the
    target length ``L`` fixed to the polygon length of the input. Meant for
    inputs that are already resampled to (nearly) equal chords.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
    tol : float
        Relative tolerance on ``max_j | |chord_j|^2 / c^2 - 1 |``, raised to the
        round-off floor ``16 eps max|X| / c`` when that is larger (large N).
    maxiter : int
    max_spread : float
        Largest accepted relative spread ``ptp(chords) / mean(chords)`` of the
        input; larger spreads raise ``ValueError`` (a projection would visibly
        deform the curve: resample instead).

    Returns
    -------
    x, y : ndarray, shape (N,)
    L : float
        The length ``N |chord|``.
    """
    x = np.array(x, dtype=float)
    y = np.array(y, dtype=float)
    N = x.size
    j = np.arange(N)
    jp = (j + 1) % N
    chords = np.hypot(x[jp] - x, y[jp] - y)
    spread = np.ptp(chords) / np.mean(chords)
    if spread > max_spread:
        raise ValueError(
            f"x, y: chord lengths differ by {100 * spread:.3g}% (> {100 * max_spread:g}%); "
            "resample the curve to equal chords first "
            "(qsa.resample.resample_closed(x, y, N, method='chord'))"
        )
    c2 = np.mean(chords) ** 2
    # round-off floor: a chord is a difference of coordinates of size max|X|
    size = np.max(np.abs(x)) + np.max(np.abs(y))
    tol = max(tol, 16 * np.finfo(float).eps * size / math.sqrt(c2))
    for _ in range(maxiter):
        ex = x[jp] - x
        ey = y[jp] - y
        r = ex * ex + ey * ey - c2
        if np.max(np.abs(r)) <= tol * c2:
            break
        rows = np.concatenate([j, j, j, j])
        cols = np.concatenate([jp, j, N + jp, N + j])
        vals = np.concatenate([2 * ex, -2 * ex, 2 * ey, -2 * ey])
        J = sp.csr_matrix((vals, (rows, cols)), shape=(N, 2 * N))
        lam = factorize((J @ J.T).tocsc()).solve(r)
        step = J.T @ lam
        x -= step[:N]
        y -= step[N:]
    else:
        raise ValueError(
            "x, y: could not equalize the chords (resample the curve to equal chords first)"
        )
    return x, y, float(N * math.sqrt(np.mean(ex * ex + ey * ey)))


class _Triplets:
    """COO accumulator for sparse Jacobian assembly (vectorised blocks).

    ``tocsc`` sums duplicates with one ``bincount`` over a column-major
    (row, col) ordering. The ordering (a sort) is kept in ``pattern`` and reused
    when the next matrix has exactly the same (row, col) list, which is checked
    in full: the local stencil part never changes and a neighbour list changes
    rarely. The values do not depend on whether the pattern was reused.
    """

    def __init__(self, pattern=None):
        self.rows, self.cols, self.vals = [], [], []
        self.pattern = pattern

    def add(self, rows, cols, vals):
        n = max(np.size(rows), np.size(cols), np.size(vals))
        self.rows.append(rows if np.size(rows) == n else np.full(n, rows, dtype=np.intp))
        self.cols.append(cols if np.size(cols) == n else np.full(n, cols, dtype=np.intp))
        self.vals.append(vals if np.size(vals) == n else np.full(n, vals, dtype=float))

    def tocsc(self, n):
        rows = np.concatenate(self.rows).astype(np.intp, copy=False)
        cols = np.concatenate(self.cols).astype(np.intp, copy=False)
        vals = np.concatenate(self.vals).astype(float, copy=False)
        p = self.pattern
        if p is None or not (np.array_equal(p["rows"], rows) and np.array_equal(p["cols"], cols)):
            key = cols * n + rows
            uniq, inverse = np.unique(key, return_inverse=True)
            indptr = np.zeros(n + 1, dtype=np.intp)
            np.cumsum(np.bincount(uniq // n, minlength=n), out=indptr[1:])
            p = {"rows": rows, "cols": cols, "inverse": inverse.ravel(),
                 "indices": (uniq % n).astype(np.intp), "indptr": indptr}
            self.pattern = p
        data = np.bincount(p["inverse"], vals, p["indices"].size)
        J = sp.csc_matrix((data, p["indices"].copy(), p["indptr"].copy()), shape=(n, n))
        J.has_sorted_indices = True
        return J


# ------------------------------------------------------------- the system
class CurveDAE(DAESystem):
    """Geometric part shared by the curve DAEs (positions, chords, curvature, gauge).

    Subclasses define ``fields`` (names of the per-node blocks, positions first
    and ``"kappa"`` third), the model rows (``_model_residual``,
    ``_model_jacobian``) and the energy.

    Layout of ``y``: ``[field_0 (N), field_1 (N), ..., multipliers (m), L]``; rows: normal
    motion (N), chords (N), curvature (N), model rows (N per auxiliary field
    and ``V``), constraint rows (m), gauge (1). The ``m`` multipliers ``mu`` of
    length / area constraints (:mod:`qsa.flows.models.constrained`) are absent
    without constraints.
    """

    fields: tuple = ()

    def __init__(self, x, y, constraints=()):
        self.N = N = x.size
        self.h = 1.0 / N
        nf = len(self.fields) * N
        self.constraint_rows = ConstraintRows(constraints, N, nf)
        m = self.constraint_rows.m
        self.size = nf + m + 1
        self.offset = {name: k * N for k, name in enumerate(self.fields)}
        self.iL = nf + m
        self.error_index = np.arange(2 * N)
        self._j = np.arange(N)
        self._jp = np.roll(self._j, -1)
        self._jm = np.roll(self._j, 1)

    # ------------------------------------------------------------ access
    def unpack(self, y):
        """Named views of the blocks of ``y`` (and ``L`` as a NumPy scalar)."""
        y = np.asarray(y, dtype=float)
        if y.shape != (self.size,):
            raise ValueError(f"y has shape {y.shape}, expected ({self.size},)")
        out = {name: y[k * self.N : (k + 1) * self.N] for k, name in enumerate(self.fields)}
        out["multipliers"] = y[self.constraint_rows.index]
        out["L"] = y[self.iL]  # NumPy scalar: overflow gives inf, not OverflowError
        return out

    @property
    def constraints(self) -> tuple:
        """The bound length / area constraints (empty for an unconstrained flow)."""
        return self.constraint_rows.constraints

    def area(self, y) -> float:
        """Polygon area of the nodes of state ``y`` (the area a ``FixedArea`` conserves)."""
        return polygon_area(*self.positions(y))

    def _finish_setup(self, y0):
        """Bind the constraints to the initial state and add ``mu . n`` to its velocity.

        ``y0`` holds the energy's own velocity ``V_E`` in the ``V`` block; the initial
        multipliers make ``V = V_E + mu . n`` orthogonal to every ``n_c``.
        """
        rows = self.constraint_rows
        if rows.m == 0:
            return y0
        N = self.N
        rows.bind(y0[:N], y0[N:2 * N], y0[self.iL])
        kappa = y0[2 * N:3 * N]
        o = self.offset["V"]
        mu = rows.initial_multipliers(kappa, y0[o:o + N])
        y0 = np.array(y0)
        y0[rows.index] = mu
        y0[o:o + N] += mu @ rows.normals(kappa)
        return y0

    def _constraint_metadata(self) -> dict:
        """``{"constraints": [...]}`` for a constrained flow, ``{}`` otherwise."""
        return {"constraints": self.constraint_rows.params()} if self.constraint_rows.m else {}

    def _stack(self, *blocks, L):
        """``[blocks..., mu = 0, L]``: an initial state in the layout of ``y``."""
        return np.concatenate(list(blocks) + [np.zeros(self.constraint_rows.m), [L]])

    def positions(self, y):
        y = np.asarray(y, dtype=float)
        return y[: self.N].copy(), y[self.N : 2 * self.N].copy()

    def length(self, y):
        return float(y[self.iL])

    def curvature(self, y):
        """The curvature unknowns ``kappa``, shape (N,)."""
        return np.asarray(y, dtype=float)[2 * self.N : 3 * self.N].copy()

    def normal_velocity(self, y):
        o = self.offset["V"]
        return np.asarray(y, dtype=float)[o : o + self.N].copy()

    def dissipation(self, y):
        """Discrete ``int (V^n)^2 dsigma = sum_j V_j^2 L/N``; the energy decays at this rate."""
        V = self.normal_velocity(y)
        return float(np.sum(V * V) * self.length(y) / self.N)

    def bound_constants(self) -> dict:
        """Constants fixed by ``setup`` from the initial data (CHA: ``L0``; the constraints).

        ``model.setup(x, y, **sys.bound_constants())`` rebuilds the same system from
        any later positions (used when resuming a run from a checkpoint).
        """
        return self._constraint_metadata()

    @property
    def differential_rows(self):
        """Rows of ``F`` that contain ``ydot`` (normal motion and gauge); the rest are algebraic."""
        return np.r_[np.arange(self.N), self.size - 1]

    def time_derivative(self, y):
        """The ``ydot`` consistent with the DAE at a state ``y`` that satisfies the algebraic rows.

        Solves the differential rows ``F(y, ydot) = 0`` (linear in ``ydot``)
        together with the time derivatives of the algebraic rows,
        ``dF_alg/dy . ydot = 0`` (one sparse LU). Useful for the first step of
        a multistep method and for instantaneous ``dE/dt``.

        Returns
        -------
        ndarray, shape (size,)

        Raises
        ------
        ValueError
            For a constrained flow: its multipliers make the DAE index 2, and their rate
            is not fixed by these equations.
        """
        if self.constraint_rows.m:
            raise ValueError("time_derivative: a length / area constrained flow is an index 2 "
                             "DAE; the multipliers' rate is not fixed by the first derivatives")
        y = np.asarray(y, dtype=float)
        zero = np.zeros(self.size)
        Jy = self.jacobian(y, zero, 0.0)
        Jd = self.jacobian(y, zero, 1.0) - Jy
        sel = np.zeros(self.size)
        sel[self.differential_rows] = 1.0
        M = (sp.diags(sel) @ Jd + sp.diags(1.0 - sel) @ Jy).tocsc()
        rhs = -self.residual(y, zero) * sel
        return factorize(M).solve(rhs)

    # ---------------------------------------------------------- geometry
    def _geometry(self, X, Y):
        jp, jm, h = self._jp, self._jm, self.h
        tx = (X[jp] - X[jm]) / (2 * h)
        ty = (Y[jp] - Y[jm]) / (2 * h)
        d2x = (X[jp] - 2 * X + X[jm]) / h**2
        d2y = (Y[jp] - 2 * Y + Y[jm]) / h**2
        return tx, ty, d2x, d2y

    def _d2(self, f):
        return (f[self._jp] - 2 * f + f[self._jm]) / self.h**2

    def geometric_curvature(self, X, Y, L):
        """Curvature from positions, ``(t_x D2Y - t_y D2X) / L^3`` (ap:curvature, sign fixed)."""
        tx, ty, d2x, d2y = self._geometry(X, Y)
        return (tx * d2y - ty * d2x) / L**3

    def residual(self, y, ydot):
        """``F(y, ydot)``, shape (size,); non-finite for a diverged (overflowing) iterate."""
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return self._residual(y, ydot)

    def jacobian(self, y, ydot, c):
        """Sparse (CSC) ``dF/dy + c dF/dydot``, shape (size, size); canonical format."""
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return self._jacobian(y, ydot, c)

    def _residual(self, y, ydot):
        y = np.asarray(y, dtype=float)
        ydot = np.asarray(ydot, dtype=float)
        N, h = self.N, self.h
        X, Y = y[:N], y[N : 2 * N]
        Xd, Yd = ydot[:N], ydot[N : 2 * N]
        kappa = y[2 * N : 3 * N]
        L = y[self.iL]
        V = y[self.offset["V"] : self.offset["V"] + N]
        tx, ty, d2x, d2y = self._geometry(X, Y)
        ex = X[self._jp] - X
        ey = Y[self._jp] - Y
        F = np.empty(self.size)
        F[:N] = Xd * ty - Yd * tx - L * V
        F[N : 2 * N] = (ex * ex + ey * ey) / h**2 - L * L
        F[2 * N : 3 * N] = kappa - (tx * d2y - ty * d2x) / L**3
        rows = self.constraint_rows
        F[3 * N : rows.index[0] if rows.m else self.iL] = self._model_residual(y, tx, ty)
        if rows.m:
            o = self.offset["V"]
            F[o:o + N] -= rows.velocity_term(y, kappa)
            F[rows.index] = rows.defects(X, Y, L)
        F[-1] = h * np.sum(Xd * tx + Yd * ty)
        return F

    def jacobian_parts(self, y, ydot, c):
        """The Newton matrix split as ``J = J_local + J_nonlocal``.

        ``J_local`` holds every stencil (index-local) entry, O(N) nonzeros; its
        sparse LU is cheap. ``J_nonlocal`` holds the adhesion couplings between
        nodes more than one index apart (CHA only; empty otherwise), dense for a
        long-range kernel. ``J_local``'s LU is an effective preconditioner for
        Krylov solves with the full matrix: for the appendix example
        (``l* = 1/2``) GMRES needs 6-35 iterations for ``c = 1/k``,
        ``k = 1e-4 .. 1e-2`` (N = 100 .. 800), 5-40x cheaper than a sparse LU of
        the full matrix at N = 400 .. 800 (benchmarks/bench_dae_models.py).

        Returns
        -------
        J_local, J_nonlocal : scipy.sparse.csc_matrix, shape (size, size)
        """
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return self._jacobian(y, ydot, c, split=True)

    def _jacobian(self, y, ydot, c, split=False):
        y = np.asarray(y, dtype=float)
        ydot = np.asarray(ydot, dtype=float)
        c = float(c)
        N, h = self.N, self.h
        j, jp, jm = self._j, self._jp, self._jm
        X, Y = y[:N], y[N : 2 * N]
        Xd, Yd = ydot[:N], ydot[N : 2 * N]
        L = y[self.iL]
        iV = self.offset["V"] + j
        V = y[iV]
        iX, iY, iK, iL = j, N + j, 2 * N + j, self.iL
        tx, ty, d2x, d2y = self._geometry(X, Y)
        patterns = getattr(self, "_patterns", {})
        T = _Triplets(patterns.get("local" if split else "full"))
        # normal motion: Xd ty - Yd tx - L V
        r = j
        T.add(r, iX[jp], -Yd / (2 * h))
        T.add(r, iX[jm], Yd / (2 * h))
        T.add(r, iY[jp], Xd / (2 * h))
        T.add(r, iY[jm], -Xd / (2 * h))
        T.add(r, iV, -L)
        T.add(r, iL, -V)
        T.add(r, iX, c * ty)
        T.add(r, iY, -c * tx)
        # chords: |X_{j+1} - X_j|^2 / h^2 - L^2
        r = N + j
        ex = (X[jp] - X) * (2 / h**2)
        ey = (Y[jp] - Y) * (2 / h**2)
        T.add(r, iX[jp], ex)
        T.add(r, iX, -ex)
        T.add(r, iY[jp], ey)
        T.add(r, iY, -ey)
        T.add(r, iL, -2 * L)
        # curvature: kappa - C / L^3, C = tx d2y - ty d2x
        r = 2 * N + j
        s = -1.0 / L**3
        C = tx * d2y - ty * d2x
        T.add(r, iK, 1.0)
        T.add(r, iX[jp], s * (d2y / (2 * h) - ty / h**2))
        T.add(r, iX[jm], s * (-d2y / (2 * h) - ty / h**2))
        T.add(r, iX, s * (2 * ty / h**2))
        T.add(r, iY[jp], s * (tx / h**2 - d2x / (2 * h)))
        T.add(r, iY[jm], s * (tx / h**2 + d2x / (2 * h)))
        T.add(r, iY, s * (-2 * tx / h**2))
        T.add(r, iL, 3 * C / L**4)
        # gauge: h sum (Xd tx + Yd ty)
        r = self.size - 1
        T.add(r, iX[jp], Xd / 2)
        T.add(r, iX[jm], -Xd / 2)
        T.add(r, iY[jp], Yd / 2)
        T.add(r, iY[jm], -Yd / 2)
        T.add(r, iX, c * h * tx)
        T.add(r, iY, c * h * ty)
        if self.constraint_rows.m:
            self.constraint_rows.add_jacobian(T, y, iV, iX, iY, iK, iL)
        if not split:
            self._model_jacobian(T, y, tx, ty)
            J = T.tocsc(self.size)
            self._patterns = {**patterns, "full": T.pattern}
            return J
        TN = _Triplets(patterns.get("nonlocal"))
        self._model_jacobian(T, y, tx, ty, TN)
        TN.add(np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp), np.zeros(0))
        J, JN = T.tocsc(self.size), TN.tocsc(self.size)
        self._patterns = {**patterns, "local": T.pattern, "nonlocal": TN.pattern}
        return J, JN

    # ------------------------------------------------------- model hooks
    def _model_residual(self, y, tx, ty):  # pragma: no cover - abstract
        raise NotImplementedError

    def _model_jacobian(self, T, y, tx, ty, TN=None):  # pragma: no cover - abstract
        raise NotImplementedError
