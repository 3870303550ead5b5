"""The paper's DAE curve flows: residuals and analytic sparse Jacobians.

Two models implement the :class:`~qsa.flows.base.FlowModel` contract:

``CHA(eps, beta, rho, A0, l_star, a)``
    Canham-Helfrich + length penalty + adhesion-repulsion (e:CHA-Energy,
    e:CHA-GF), the system of the appendix "Discussion of Numerical Scheme":
    per node ``(x, y, kappa, kss, V)`` plus the length ``L``, ``5N + 1``
    equations.
``FacetingFlow(alpha, kstar, beta, L_star, well=None)``
    The faceting flow (e:Facet-NV) with auxiliary unknowns
    ``mu = -alpha^2 Delta_s kappa + W'(kappa)`` and ``mss = Delta_s mu`` so that
    every row has a compact stencil: per node ``(x, y, kappa, mu, mss, V)``
    plus ``L``, ``6N + 1`` equations, O(N) Jacobian nonzeros.

Both share the geometric rows (scaled arc length, ap:scaledAL, ``g = L``;
``h = 1/N``; ``D1`` the centred difference, ``D2`` the compact second
difference, indices mod N; ``t_j = D1 X_j``, ``t^- = (t_y, -t_x)`` the tangent
rotated by ``-pi/2``, i.e. along the OUTWARD normal):

* normal motion      ``Xdot_j . t^-_j - L V_j = 0``                   (N rows)
* equal chords       ``|X_{j+1} - X_j|^2 / h^2 - L^2 = 0``  (ap:scaled, N rows)
* curvature          ``kappa_j - (t_x D2Y - t_y D2X)_j / L^3 = 0``     (N rows)
* model rows (auxiliary fields and the normal-velocity law)
* tangential gauge   ``h sum_j Xdot_j . t_j = 0``                      (1 row)

Signs follow MATH.md section 3: ``V`` is the OUTWARD normal velocity and a
counter-clockwise circle of radius R has ``kappa = +1/R``.

Notes
-----
NOTE: the appendix writes the normal motion with the tangent rotated by
``+pi/2`` (the inward normal) and ``kappa = -(1/L^3) gamma_ss . gamma_s^perp``;
with outward ``V`` and ``kappa(circle) = +1/R`` both change sign (MATH.md
section 3). NOTE: the appendix's velocity ``eps (kss - kappa^3)`` is wrong; the
gradient flow of e:CHA-Energy has ``eps (kss + kappa^3 / 2)`` (MATH.md
section 3), verified here by the discrete energy-dissipation test.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from qsa.energies.adhesion import AdhesionKernel, adhesion_energy, adhesion_fields, adhesion_pairs
from qsa.energies.adhesion import adhesion_field_derivatives
from qsa.flows.base import DAESystem, FlowModel

__all__ = ["CHA", "FacetingFlow", "CurveDAE", "CHASystem", "FacetingSystem", "equalize_chords"]


# ----------------------------------------------------------------- helpers
def _number(value, name, *, positive=False, nonnegative=False):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if positive and not v > 0:
        raise ValueError(f"{name} must be positive, got {value!r}")
    if nonnegative and not v >= 0:
        raise ValueError(f"{name} must be non-negative, got {value!r}")
    return v


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
    return x, y


def equalize_chords(x, y, *, tol=1e-13, maxiter=30):
    """Project node positions onto equal chords ``|X_{j+1} - X_j| = L/N`` (ap:scaled).

    Minimum-norm Gauss-Newton steps on ``|X_{j+1} - X_j|^2 = (L/N)^2`` with the
    target length ``L`` fixed to the polygon length of the input. Meant for
    inputs that are already resampled to (nearly) equal chords.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
    tol : float
        Relative tolerance on ``max_j | |chord_j|^2 / c^2 - 1 |``.
    maxiter : int

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
    c2 = (np.sum(np.hypot(x[jp] - x, y[jp] - y)) / N) ** 2
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
        lam = spla.splu((J @ J.T).tocsc()).solve(r)
        step = J.T @ lam
        x -= step[:N]
        y -= step[N:]
    else:
        raise ValueError(
            "x, y: could not equalize the chords (resample the curve to equal chords first)"
        )
    return x, y, float(N * math.sqrt(np.mean(ex * ex + ey * ey)))


class _Triplets:
    """COO accumulator for sparse Jacobian assembly (vectorised blocks)."""

    def __init__(self):
        self.rows, self.cols, self.vals = [], [], []

    def add(self, rows, cols, vals):
        rows, cols, vals = np.broadcast_arrays(rows, cols, vals)
        self.rows.append(rows.ravel())
        self.cols.append(cols.ravel())
        self.vals.append(np.asarray(vals, dtype=float).ravel())

    def tocsc(self, n):
        return sp.csc_matrix(
            (np.concatenate(self.vals), (np.concatenate(self.rows), np.concatenate(self.cols))),
            shape=(n, n),
        )


# ------------------------------------------------------------- the system
class CurveDAE(DAESystem):
    """Geometric part shared by the curve DAEs (positions, chords, curvature, gauge).

    Subclasses define ``fields`` (names of the per-node blocks, positions first
    and ``"kappa"`` third), the model rows (``_model_residual``,
    ``_model_jacobian``) and the energy.

    Layout of ``y``: ``[field_0 (N), field_1 (N), ..., L]``; rows: normal
    motion (N), chords (N), curvature (N), model rows (N per auxiliary field
    and ``V``), gauge (1).
    """

    fields: tuple = ()

    def __init__(self, x, y):
        self.N = N = x.size
        self.h = 1.0 / N
        self.size = len(self.fields) * N + 1
        self.offset = {name: k * N for k, name in enumerate(self.fields)}
        self.iL = len(self.fields) * N
        self.error_index = np.arange(2 * N)
        self._j = np.arange(N)
        self._jp = np.roll(self._j, -1)
        self._jm = np.roll(self._j, 1)

    # ------------------------------------------------------------ access
    def unpack(self, y):
        """Named views of the blocks of ``y`` (and ``L`` as a float)."""
        y = np.asarray(y, dtype=float)
        if y.shape != (self.size,):
            raise ValueError(f"y has shape {y.shape}, expected ({self.size},)")
        out = {name: y[k * self.N : (k + 1) * self.N] for k, name in enumerate(self.fields)}
        out["L"] = float(y[self.iL])
        return out

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
        """
        y = np.asarray(y, dtype=float)
        zero = np.zeros(self.size)
        Jy = self.jacobian(y, zero, 0.0)
        Jd = self.jacobian(y, zero, 1.0) - Jy
        sel = np.zeros(self.size)
        sel[self.differential_rows] = 1.0
        M = (sp.diags(sel) @ Jd + sp.diags(1.0 - sel) @ Jy).tocsc()
        rhs = -self.residual(y, zero) * sel
        return spla.splu(M).solve(rhs)

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
        F[3 * N : self.size - 1] = self._model_residual(y, tx, ty)
        F[-1] = h * np.sum(Xd * tx + Yd * ty)
        return F

    def jacobian(self, y, ydot, c):
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
        T = _Triplets()
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
        self._model_jacobian(T, y, tx, ty)
        return T.tocsc(self.size)

    # ------------------------------------------------------- model hooks
    def _model_residual(self, y, tx, ty):  # pragma: no cover - abstract
        raise NotImplementedError

    def _model_jacobian(self, T, y, tx, ty):  # pragma: no cover - abstract
        raise NotImplementedError


# ===================================================================== CHA
class CHASystem(CurveDAE):
    """The CHA DAE bound to initial positions (see :class:`CHA`)."""

    fields = ("x", "y", "kappa", "kss", "V")

    def __init__(self, model, x, y, *, adhesion_method="neighbours"):
        super().__init__(x, y)
        self.model = model
        self.kernel = model.kernel
        self.adhesion_method = adhesion_method
        x, y, L = equalize_chords(x, y)
        self.L0 = L
        kappa = self.geometric_curvature(x, y, L)
        kss = self._d2(kappa) / L**2
        y0 = np.concatenate([x, y, kappa, kss, np.zeros(self.N), [L]])
        y0[self.offset["V"] : self.offset["V"] + self.N] = self._velocity(y0, *self._geometry(x, y)[:2])
        self.y0 = y0

    def _adhesion(self, X, Y, L):
        """Pairs, ``B`` and the force at weights ``w = L/N`` (or zeros without adhesion)."""
        if self.kernel is None:
            return None, np.zeros(self.N), np.zeros((self.N, 2))
        pairs = adhesion_pairs(self.kernel, X, Y, method=self.adhesion_method)
        B, force = adhesion_fields(self.kernel, X, Y, L / self.N, pairs=pairs)
        return pairs, B, force

    def adhesion_fields(self, y):
        """``(B, force)`` at state ``y`` (zeros when ``A0 = 0``)."""
        X, Y = self.positions(y)
        return self._adhesion(X, Y, self.length(y))[1:]

    def _velocity(self, y, tx, ty):
        m, N = self.model, self.N
        u = self.unpack(y)
        kappa, kss, L = u["kappa"], u["kss"], u["L"]
        _, B, force = self._adhesion(u["x"], u["y"], L)
        tn = np.hypot(tx, ty)
        An = (force[:, 0] * ty - force[:, 1] * tx) / tn
        return m.eps * (kss + 0.5 * kappa**3) - (B + m.beta * (L - m.rho * self.L0)) * kappa - An

    def _model_residual(self, y, tx, ty):
        N = self.N
        u = self.unpack(y)
        F = np.empty(2 * N)
        F[:N] = u["kss"] - self._d2(u["kappa"]) / u["L"] ** 2
        F[N:] = u["V"] - self._velocity(y, tx, ty)
        return F

    def _model_jacobian(self, T, y, tx, ty):
        m, N, h = self.model, self.N, self.h
        j, jp, jm = self._j, self._jp, self._jm
        u = self.unpack(y)
        X, Y, kappa, L = u["x"], u["y"], u["kappa"], u["L"]
        iX, iY, iK, iS, iV, iL = j, N + j, 2 * N + j, 3 * N + j, 4 * N + j, self.iL
        # kss - D2 kappa / L^2
        r = 3 * N + j
        T.add(r, iS, 1.0)
        T.add(r, iK[jp], -1.0 / (h * L) ** 2)
        T.add(r, iK[jm], -1.0 / (h * L) ** 2)
        T.add(r, iK, 2.0 / (h * L) ** 2)
        T.add(r, iL, 2.0 * self._d2(kappa) / L**3)
        # V - eps (kss + kappa^3/2) + (B + beta (L - rho L0)) kappa + force . n
        r = 4 * N + j
        pairs, B, force = self._adhesion(X, Y, L)
        tn = np.hypot(tx, ty)
        nx, ny = ty / tn, -tx / tn
        An = force[:, 0] * nx + force[:, 1] * ny
        At = (force[:, 0] * tx + force[:, 1] * ty) / tn
        T.add(r, iV, 1.0)
        T.add(r, iS, -m.eps)
        T.add(r, iK, -1.5 * m.eps * kappa**2 + B + m.beta * (L - m.rho * self.L0))
        T.add(r, iL, m.beta * kappa + (kappa * B + An) / L)
        # d(force . n)/dt = -(force . t^) n / |t|, t = D1 X
        gx, gy = -At * nx / tn, -At * ny / tn
        T.add(r, iX[jp], gx / (2 * h))
        T.add(r, iX[jm], -gx / (2 * h))
        T.add(r, iY[jp], gy / (2 * h))
        T.add(r, iY[jm], -gy / (2 * h))
        if pairs is not None:
            p, q, dB, dF, dBd, dFd = adhesion_field_derivatives(
                self.kernel, X, Y, L / N, pairs=pairs
            )
            # row p, column X_q: kappa_p dB_p/dX_q + n_p^T dforce_p/dX_q
            vx = kappa[p] * dB[:, 0] + nx[p] * dF[:, 0, 0] + ny[p] * dF[:, 1, 0]
            vy = kappa[p] * dB[:, 1] + nx[p] * dF[:, 0, 1] + ny[p] * dF[:, 1, 1]
            T.add(4 * N + p, q, vx)
            T.add(4 * N + p, N + q, vy)
            vx = kappa * dBd[:, 0] + nx * dFd[:, 0, 0] + ny * dFd[:, 1, 0]
            vy = kappa * dBd[:, 1] + nx * dFd[:, 0, 1] + ny * dFd[:, 1, 1]
            T.add(r, iX, vx)
            T.add(r, iY, vy)

    def energy(self, y):
        """``E = eps/2 sum kappa^2 w + beta/2 (L - rho L0)^2 + E_A``, ``w = L/N`` (e:CHA-Energy)."""
        m = self.model
        u = self.unpack(y)
        L = u["L"]
        w = L / self.N
        E = 0.5 * m.eps * np.sum(u["kappa"] ** 2) * w + 0.5 * m.beta * (L - m.rho * self.L0) ** 2
        if self.kernel is not None:
            E += adhesion_energy(
                self.kernel, u["x"], u["y"], w, method=self.adhesion_method
            )
        return float(E)

    def normal_velocity(self, y):
        return self.unpack(y)["V"].copy()

    def metadata(self):
        m = self.model
        return {
            "model": "CHA",
            "N": int(self.N),
            "eps": m.eps,
            "beta": m.beta,
            "rho": m.rho,
            "A0": m.A0,
            "l_star": m.l_star,
            "a": m.a,
            "L0": float(self.L0),
            "adhesion_method": self.adhesion_method,
            "unknowns": list(self.fields) + ["L"],
        }


@dataclass(frozen=True)
class CHA(FlowModel):
    """Canham-Helfrich + length penalty + adhesion-repulsion flow (e:CHA-Energy, e:CHA-GF).

    Energy (``L0`` = initial length, bound by :meth:`setup`)::

        E = eps/2 int kappa^2 dsigma + beta/2 (L - rho L0)^2 + E_A,

    outward normal velocity (MATH.md section 3)::

        V = eps (Delta_s kappa + kappa^3/2) - (B + beta (L - rho L0)) kappa - force . n.

    Parameters
    ----------
    eps : float
        Bending rigidity, ``eps >= 0``.
    beta : float
        Length-penalty strength (the sigma of e:CHA-GF), ``beta >= 0``.
    rho : float
        Precompression factor, ``rho > 0``.
    A0, l_star, a : float
        Kernel e:LJ; ``A0 = 0`` switches adhesion off (then ``l_star, a`` are
        ignored).
    adhesion_method : {"neighbours", "dense"}
        Cutoff neighbour list (default, O(N) for short kernels) or all pairs
        (exact, for validation).

    Examples
    --------
    >>> import numpy as np
    >>> th = 2 * np.pi * np.arange(64) / 64
    >>> sys = CHA(eps=0.1, beta=1.0, rho=1.5, A0=10.0, l_star=0.5, a=1.0).setup(
    ...     np.cos(th), np.sin(th))
    >>> sys.size
    321
    """

    eps: float
    beta: float
    rho: float
    A0: float = 0.0
    l_star: float = 1.0
    a: float = 1.0
    adhesion_method: str = "neighbours"
    name: str = field(default="CHA", init=False)

    def __post_init__(self):
        object.__setattr__(self, "eps", _number(self.eps, "eps", nonnegative=True))
        object.__setattr__(self, "beta", _number(self.beta, "beta", nonnegative=True))
        object.__setattr__(self, "rho", _number(self.rho, "rho", positive=True))
        object.__setattr__(self, "A0", _number(self.A0, "A0", nonnegative=True))
        object.__setattr__(self, "l_star", _number(self.l_star, "l_star", positive=True))
        object.__setattr__(self, "a", _number(self.a, "a", positive=True))
        if self.adhesion_method not in ("neighbours", "dense"):
            raise ValueError(
                f"adhesion_method must be 'neighbours' or 'dense', got {self.adhesion_method!r}"
            )

    @property
    def kernel(self):
        """The :class:`AdhesionKernel`, or ``None`` when ``A0 = 0``."""
        return AdhesionKernel(self.A0, self.l_star, self.a) if self.A0 > 0 else None

    def check_resolution(self, x, y):
        """Raise ``ValueError`` for NaN, too few nodes, a clockwise curve, or ``L/N > l_star``."""
        x, y = _check_xy(x, y, self.min_nodes())
        if self.A0 > 0:
            L = float(np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)))
            if L / x.size > self.l_star:
                raise ValueError(
                    f"N={x.size}: node spacing L/N = {L / x.size:.4g} exceeds l_star = "
                    f"{self.l_star:g}; the adhesion kernel is unresolved, use "
                    f"N >= {math.ceil(L / self.l_star)}"
                )

    def setup(self, x, y):
        """Bind to initial positions (projected to equal chords); ``L0`` = their length."""
        self.check_resolution(x, y)
        return CHASystem(self, np.asarray(x, float), np.asarray(y, float),
                         adhesion_method=self.adhesion_method)


# ================================================================ faceting
class _QuarticWell:
    """The default double well ``W = k^2 (k - k*)^2 / 4`` (MATH.md section 1)."""

    def __init__(self, kstar):
        self.kstar = float(kstar)

    def W(self, k):
        return 0.25 * k**2 * (k - self.kstar) ** 2

    def dW(self, k):
        return 0.5 * k * (k - self.kstar) * (2 * k - self.kstar)

    def d2W(self, k):
        ks = self.kstar
        return 0.5 * (6 * k**2 - 6 * k * ks + ks**2)

    def __repr__(self):
        return f"DoubleWell(kstar={self.kstar:g})"


class FacetingSystem(CurveDAE):
    """The faceting DAE bound to initial positions (see :class:`FacetingFlow`)."""

    fields = ("x", "y", "kappa", "mu", "mss", "V")

    def __init__(self, model, x, y):
        super().__init__(x, y)
        self.model = model
        self.well = model.well if model.well is not None else _QuarticWell(model.kstar)
        x, y, L = equalize_chords(x, y)
        kappa = self.geometric_curvature(x, y, L)
        mu = -(model.alpha**2) * self._d2(kappa) / L**2 + self.well.dW(kappa)
        mss = self._d2(mu) / L**2
        y0 = np.concatenate([x, y, kappa, mu, mss, np.zeros(self.N), [L]])
        o = self.offset["V"]
        y0[o : o + self.N] = self._velocity(y0)
        self.y0 = y0

    def _edges(self, kappa, L):
        """``e_{j+1/2} = (kappa_{j+1} - kappa_j)/(h L)`` and the nodal ``q_j = (e_{j-1/2}^2 + e_{j+1/2}^2)/2``."""
        e = (kappa[self._jp] - kappa) / (self.h * L)
        return e, 0.5 * (e * e + e[self._jm] ** 2)

    def _velocity(self, y):
        """``V = Delta_s mu + kappa^2 mu - kappa (-alpha^2/2 |grad kappa|^2 + W + beta (L - L*))``."""
        m = self.model
        u = self.unpack(y)
        kappa, L = u["kappa"], u["L"]
        _, q = self._edges(kappa, L)
        gE = -0.5 * m.alpha**2 * q + self.well.W(kappa) + m.beta * (L - m.L_star)
        return u["mss"] + kappa**2 * u["mu"] - kappa * gE

    def _model_residual(self, y, tx, ty):
        m, N = self.model, self.N
        u = self.unpack(y)
        kappa, mu, L = u["kappa"], u["mu"], u["L"]
        F = np.empty(3 * N)
        F[:N] = mu + m.alpha**2 * self._d2(kappa) / L**2 - self.well.dW(kappa)
        F[N : 2 * N] = u["mss"] - self._d2(mu) / L**2
        F[2 * N :] = u["V"] - self._velocity(y)
        return F

    def _model_jacobian(self, T, y, tx, ty):
        m, N, h = self.model, self.N, self.h
        j, jp, jm = self._j, self._jp, self._jm
        u = self.unpack(y)
        kappa, mu, L = u["kappa"], u["mu"], u["L"]
        a2 = m.alpha**2
        iK, iM, iS, iV, iL = 2 * N + j, 3 * N + j, 4 * N + j, 5 * N + j, self.iL
        s2 = 1.0 / (h * L) ** 2
        # mu + alpha^2 D2 kappa / L^2 - W'(kappa)
        r = 3 * N + j
        T.add(r, iM, 1.0)
        T.add(r, iK[jp], a2 * s2)
        T.add(r, iK[jm], a2 * s2)
        T.add(r, iK, -2 * a2 * s2 - self.well.d2W(kappa))
        T.add(r, iL, -2 * a2 * self._d2(kappa) / L**3)
        # mss - D2 mu / L^2
        r = 4 * N + j
        T.add(r, iS, 1.0)
        T.add(r, iM[jp], -s2)
        T.add(r, iM[jm], -s2)
        T.add(r, iM, 2 * s2)
        T.add(r, iL, 2 * self._d2(mu) / L**3)
        # V - mss - kappa^2 mu + kappa (-alpha^2/2 q + W + beta (L - L*))
        r = 5 * N + j
        e, q = self._edges(kappa, L)
        em = e[jm]
        gE = -0.5 * a2 * q + self.well.W(kappa) + m.beta * (L - m.L_star)
        hl = h * L
        T.add(r, iV, 1.0)
        T.add(r, iS, -1.0)
        T.add(r, iM, -(kappa**2))
        T.add(r, iK, -2 * kappa * mu + gE + kappa * self.well.dW(kappa)
              - 0.5 * a2 * kappa * (em - e) / hl)
        T.add(r, iK[jp], -0.5 * a2 * kappa * e / hl)
        T.add(r, iK[jm], 0.5 * a2 * kappa * em / hl)
        T.add(r, iL, kappa * (a2 * q / L + m.beta))

    def energy(self, y):
        """``E = sum_j w (alpha^2/2 e_{j+1/2}^2 + W(kappa_j)) + beta/2 (L - L*)^2``, ``w = L/N``."""
        m = self.model
        u = self.unpack(y)
        L = u["L"]
        e, _ = self._edges(u["kappa"], L)
        bulk = np.sum(0.5 * m.alpha**2 * e * e + self.well.W(u["kappa"])) * L / self.N
        return float(bulk + 0.5 * m.beta * (L - m.L_star) ** 2)

    def metadata(self):
        m = self.model
        return {
            "model": "FacetingFlow",
            "N": int(self.N),
            "alpha": m.alpha,
            "kstar": m.kstar,
            "beta": m.beta,
            "L_star": m.L_star,
            "well": repr(self.well),
            "unknowns": list(self.fields) + ["L"],
        }


@dataclass(frozen=True)
class FacetingFlow(FlowModel):
    """The faceting gradient flow (e:Facet-NV) of ``E = int alpha^2/2 |grad_s kappa|^2 + W(kappa) dsigma + beta/2 (L - L*)^2``.

    Outward normal velocity (MATH.md section 3, e:Facet-NV)::

        V = -G(mu) - kappa (g d_g E),   G = -Delta_s - kappa^2,
        mu = -alpha^2 Delta_s kappa + W'(kappa),
        g d_g E = -alpha^2/2 |grad_s kappa|^2 + W(kappa) + beta (L - L*).

    Parameters
    ----------
    alpha : float
        Front width, ``alpha > 0``.
    kstar : float
        Second well of the default double well ``W = k^2 (k - kstar)^2 / 4``.
    beta : float
        Length-penalty strength, ``beta >= 0``.
    L_star : float
        Preferred length, ``L_star > 0``.
    well : object, optional
        A well with callables ``W(k)``, ``dW(k)``, ``d2W(k)`` (vectorised);
        default the quartic double well.
    """

    alpha: float
    kstar: float
    beta: float
    L_star: float
    well: object = None
    name: str = field(default="FacetingFlow", init=False)

    def __post_init__(self):
        object.__setattr__(self, "alpha", _number(self.alpha, "alpha", positive=True))
        object.__setattr__(self, "kstar", _number(self.kstar, "kstar"))
        object.__setattr__(self, "beta", _number(self.beta, "beta", nonnegative=True))
        object.__setattr__(self, "L_star", _number(self.L_star, "L_star", positive=True))
        if self.well is not None:
            for attr in ("W", "dW", "d2W"):
                if not callable(getattr(self.well, attr, None)):
                    raise ValueError(f"well must provide a callable {attr}(k)")

    def check_resolution(self, x, y):
        """Raise ``ValueError`` for NaN, too few nodes or a clockwise curve."""
        _check_xy(x, y, self.min_nodes())

    def setup(self, x, y):
        """Bind to initial positions (projected to equal chords)."""
        self.check_resolution(x, y)
        return FacetingSystem(self, np.asarray(x, float), np.asarray(y, float))
