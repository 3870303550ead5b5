"""Exact intrinsic gradient and Hessian of the discrete two-point energy (e:AdhE, e:LJ).

The discrete adhesion energy (:func:`~qsa.energies.adhesion.adhesion_energy`) is a
function of the intrinsic unknowns ``U = (kappa, g)`` through the node positions
and the quadrature weights::

    E_A(U) = E^(X, w) = A0 sum_i w_i^2 + 2 sum_{pairs i<j} A(|X_i - X_j|^2) w_i w_j,
    theta = theta0 + C(g kappa),  X = gamma0 + C(g tau),  tau = (cos theta, sin theta),
    w = omega g,

with ``C`` the grid's cumulative-integration matrix (``C f = grid.cumulative(f)``,
so ``D f = C(g f)``, e:D_def), ``omega`` the quadrature weights and the pairs of the
energy (a cutoff neighbour list or all pairs; the diagonal gives ``A0 w_i^2``).
Everything below is the exact derivative of this function (pairs held fixed),
with respect to ``<f, h> = sum f h dsigma``, ``dsigma = omega g``.

First derivatives (reverse sweep)
---------------------------------
With ``F = dE^/dX = w force`` and ``dE^/dw = B`` (the fields of
:func:`~qsa.energies.adhesion.adhesion_fields`) and ``tau' = (-sin theta, cos theta)``: ::

    P = C^T F,   a = P . tau,   p = P . tau',   beta = C^T (g p),
    dE/dkappa = g beta,   dE/dg = a + kappa beta + omega B,

divided by ``dsigma`` for the ``<.,.>`` gradient. In the continuum this is an
intrinsic gradient of e:Adh-In_grad: ``M-dagger nabla_I E = (A.n + kappa B, 0)``
(e:Adh-Ex_grad); it differs from the one orthogonal to ``span Psi`` by a
combination of the closure gradients ``Psi_j`` (the base point ``gamma(0)`` and
angle ``theta(0)`` are held fixed, so the energy is defined off the closed curves too).

Second derivatives (forward over reverse)
-----------------------------------------
Along ``V = (kappa1, g1)``: ::

    theta1 = C(g kappa1 + kappa g1),   X1 = C(g1 tau + g theta1 tau'),   w1 = omega g1,
    (F1, B1) = K (X1, w1),
    P1 = C^T F1,   a1 = P1 . tau + p theta1,   p1 = P1 . tau' - a theta1,
    beta1 = C^T (g1 p + g p1),
    (H V)_kappa = g1 beta + g beta1,   (H V)_g = a1 + kappa1 beta + kappa beta1 + omega B1,

where ``K`` is the Hessian of ``E^`` in ``(x, y, w)``: one stencil per pair, with
``d = X_i - X_j``, ``l = |d|^2``, ``H_ij = 2 A''(l) d d^T + A'(l) I``, ::

    d2E^/dX_i dX_j = -4 w_i w_j H_ij,   d2E^/dX_i dw_j = 4 A'(l) d w_i,
    d2E^/dw_i dw_j = 2 A(l),   (i != j),

diagonal blocks ``4 sum_j w_i w_j H_ij``, ``4 sum_j A'(l_ij) d_ij w_j`` and ``2 A0``.
So ``H = J^T K J`` plus the second derivatives of ``X(U)`` contracted with ``P``:
``-g a`` in ``(theta, theta)``, ``p`` in ``(theta, g)``, ``beta`` in ``(kappa, g)``.
``K`` has O(P) entries for ``P`` pairs, but ``J = dX/dU`` contains ``C`` twice, so
``H`` is dense even for a short-range kernel.

Representations
---------------
* Products :meth:`AdhesionDerivatives.hessian_vector`: four cumulative sums and
  one pass over the pairs, O(N + P) (finite differences; Fourier O(N log N + P)).
* ``"dense"``: ``K`` made dense and integrated on both sides by cumulative sums,
  ``C^T K C``: O(N^2) memory and time on finite differences (O(N^2 log N) Fourier).
* ``"reduced"`` (finite differences): the trapezoid rule is ``C = Bd^{-1} R`` with
  ``Bd`` the lower bidiagonal difference (``(Bd z)_0 = z_0``) and ``R`` the
  trapezoid average (``(R f)_0 = 0``), both sparse. The state ``Y = (theta, x, y)``
  solves the sparse lower-triangular equations ::

      Bd theta = R(g kappa) + theta0 e_0,   Bd x = R(g cos theta) + x0 e_0,
      Bd y = R(g sin theta) + y0 e_0,

  and ``H`` is the :class:`~qsa.linalg.ReducedHessian` of ``E^`` under them, with the
  Lagrangian's second derivatives ::

      L_UU = [[0, beta], [beta, omega K_ww omega]],   L_YU = [[0, p], [0, K_Xw omega]],
      L_YY = diag(-g a, K_XX),

  and the constraint Jacobians ``c_Y``, ``c_U``: O(N + P) nonzeros, products in
  O(N + P) and ``(H - sigma I)^{-1}`` from one sparse LU of an 8N saddle-point system
  (its fill grows like the square of the neighbours per node: for short-range kernels).

The matrix-free product differences the node displacements ``X1_i - X1_j`` before
applying the pair Hessian; the assembled forms store ``K`` with its diagonal blocks
as row sums (translation invariance) and apply it to the displacements themselves,
so along smooth directions their round-off is larger by about the ratio of the
curve's size to the kernel's range.

Exact identities (tests)
------------------------
Besides central differences of the gradient: ``W H`` is symmetric
(``W = diag(dsigma)``); rigid motions of the base point (``theta0``, ``gamma0``)
move ``X`` rigidly, so the extended second variation along them vanishes; and the
dilation ``U(lam) = (kappa / lam, lam g)`` maps ``X - gamma0`` to
``lam (X - gamma0)`` and ``w`` to ``lam w``, so ``E(U(lam)) = lam^2 S(lam^2)``,
``S(mu) = A0 sum w_i^2 + 2 sum A(mu l_ij) w_i w_j``, in closed form.

Examples
--------
>>> import numpy as np
>>> from qsa import Curve, FiniteDifference
>>> from qsa.energies.adhesion import AdhesionKernel, adhesion_pairs
>>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), FiniteDifference(128))
>>> k = AdhesionKernel(A0=10.0, l_star=0.1, a=1.0)
>>> d = adhesion_derivatives(k, c, adhesion_pairs(k, *c.positions()))
>>> H = d.hessian()                                  # factored: finite differences
>>> v = np.sin(2 * np.pi * np.arange(256) / 256)
>>> bool(np.allclose(H @ v, d.hessian_vector(v)))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from qsa.curve import Curve
from qsa.discretize import cumulative_factors
from qsa.linalg import BlockSparse, ReducedHessian
from qsa.linalg.implicit import OperatorPairHessian

__all__ = ["AdhesionDerivatives", "adhesion_derivatives", "adjoint_fields", "cumulative_factors",
           "local_reduced_parts", "position_state_equations", "HESSIAN_FORMS"]

#: The assembled forms of :meth:`AdhesionDerivatives.hessian`.
HESSIAN_FORMS = ("auto", "dense", "reduced")


def pair_vectors(V, N) -> np.ndarray:
    """``V`` as float vectors in the pair Hessian's ordering ``(x, y, w)``: shape (3N,)
    or (3N, m), else a ``ValueError`` naming the expected shape."""
    V = np.asarray(V, dtype=float)
    if V.shape[:1] != (3 * N,) or V.ndim > 2:
        raise ValueError(f"V has shape {V.shape}, expected ({3 * N},) or ({3 * N}, m)")
    return V


def position_state_equations(c: Curve):
    """Jacobians ``(cY, cU)`` of the equations of the state ``Y = (theta, x, y)``.

    On finite-difference grids ``theta = theta0 + C(g kappa)``, ``x = x0 + C(g cos theta)``,
    ``y = y0 + C(g sin theta)`` with ``C = Bd^{-1} R`` (:func:`~qsa.discretize.cumulative_factors`)
    are the sparse lower-triangular equations ``c(Y, U) = 0``

        Bd theta - R(g kappa) = theta0 e_0,   Bd x - R(g cos theta) = x0 e_0,
        Bd y - R(g sin theta) = y0 e_0,

    so a change ``U1`` of ``U = (kappa, g)`` moves the state by ``Y1`` with
    ``cY Y1 + cU U1 = 0``.

    Parameters
    ----------
    c : Curve
        On a finite-difference grid.

    Returns
    -------
    cY : scipy.sparse matrix, shape (3N, 3N)
        Lower triangular.
    cU : scipy.sparse matrix, shape (3N, 2N)

    Examples
    --------
    >>> import numpy as np, scipy.sparse.linalg as spla
    >>> from qsa import Curve, FiniteDifference
    >>> c = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), FiniteDifference(32))
    >>> cY, cU = position_state_equations(c)
    >>> U1 = np.cos(np.arange(64.0))
    >>> Y1 = spla.spsolve(cY.tocsc(), -(cU @ U1))
    >>> h = 1e-6
    >>> dX = (c.with_U(c.U + h * U1).positions() - c.with_U(c.U - h * U1).positions()) / (2 * h)
    >>> bool(np.allclose(Y1[32:], dX.ravel(), atol=1e-8))
    True
    """
    N = c.N
    g, kappa = c.g, c.kappa
    th = c.theta()
    cs, sn = np.cos(th), np.sin(th)
    d = sp.diags
    O = sp.csr_matrix((N, N))
    Bd, R = cumulative_factors(N)
    cY = sp.bmat([[Bd, None, None], [R @ d(g * sn), Bd, None], [R @ d(-g * cs), None, Bd]],
                 format="csr")
    cU = sp.bmat([[R @ d(-g), R @ d(-kappa)], [O, R @ d(-cs)], [O, R @ d(-sn)]], format="csr")
    return cY, cU


def adjoint_fields(c: Curve, F):
    """``(P, a, p, beta)`` of the reverse sweep from ``F = dE^/dX`` (module docstring).

    Parameters
    ----------
    c : Curve
    F : ndarray, shape (N, 2)

    Returns
    -------
    P : ndarray, shape (N, 2)
        ``C^T F``.
    a, p, beta : ndarray, shape (N,)
        ``P . tau``, ``P . tau'``, ``C^T (g p)``.
    """
    grid = c.grid
    th = c.theta()
    cs, sn = np.cos(th), np.sin(th)
    P = grid.cumulative_transpose(F)
    a = P[:, 0] * cs + P[:, 1] * sn
    p = -P[:, 0] * sn + P[:, 1] * cs
    return P, a, p, grid.cumulative_transpose(c.g * p)


def local_reduced_parts(c: Curve, a, p, beta):
    """The local part of the reduced Hessian and the pair term's selections ``Su, Sy``.

    The Lagrangian Hessian of the module docstring splits as ``local + S^T K S`` with
    ``S (u, y) = Su u + Sy y = (y_x, y_y, omega u_g)`` and the local part
    ``L_UU = [[0, beta], [beta, 0]]``, ``L_YU = [[0, p], [0, 0], [0, 0]]``,
    ``L_YY = diag(-g a, 0, 0)`` (finite differences).

    Parameters
    ----------
    c : Curve
        On a finite-difference grid.
    a, p, beta : ndarray, shape (N,)
        The adjoint fields (:func:`adjoint_fields`).

    Returns
    -------
    local : ReducedHessian, shape (2N, 2N)
        With the state equations :func:`position_state_equations` and
        ``left = diag(1 / dsigma)``.
    Su : scipy.sparse.csr_matrix, shape (3N, 2N)
    Sy : scipy.sparse.csr_matrix, shape (3N, 3N)
    """
    N = c.N
    g, om = c.g, c.grid.weights
    d = sp.diags
    Z = sp.csr_matrix((N, N))
    bI = lambda v: d(np.broadcast_to(v, N).astype(float), format="csr")
    grid = lambda blocks: BlockSparse(blocks).tocsr()
    Luu = grid([[Z, bI(beta)], [bI(beta), Z]])
    Lyu = grid([[Z, bI(p)], [Z, Z], [Z, Z]])
    Lyy = grid([[bI(-g * a), Z, Z], [Z, Z, Z], [Z, Z, Z]])
    cY, cU = position_state_equations(c)
    ds = c.dsigma
    local = ReducedHessian(Luu, Lyu, Lyy, cY, cU, left=d(1.0 / np.concatenate([ds, ds])))
    I = sp.identity(N, format="csr")
    Su = grid([[Z, Z], [Z, Z], [Z, bI(om)]])
    Sy = grid([[Z, I, Z], [Z, Z, I], [Z, Z, Z]])
    return local, Su, Sy


class _Entries:
    """Accumulates ``(rows, cols, vals)`` of a sparse matrix (with optional mirror images)."""

    def __init__(self):
        self.rows, self.cols, self.vals = [], [], []

    def add(self, r, c, v, mirror=False):
        self.rows.append(r)
        self.cols.append(c)
        self.vals.append(v)
        if mirror:
            self.rows.append(c)
            self.cols.append(r)
            self.vals.append(v)

    def arrays(self):
        """Concatenated ``(rows, cols, vals)``."""
        return tuple(np.concatenate(parts) for parts in (self.rows, self.cols, self.vals))

    def tocsr(self, shape):
        rows, cols, vals = self.arrays()
        return sp.coo_matrix((vals, (rows, cols)), shape=shape).tocsr()


class _PairPattern:
    """The CSR pattern ``(i, j), (j, i), (n, n)`` of the pairs, shared by the Hessian's blocks.

    Every ``N x N`` block of the reduced Hessian has entries at the pairs, their mirror
    images and the diagonal: the sorting into CSR order is done once and each block's
    values are gathered into it (no COO assembly per block).
    """

    def __init__(self, i, j, N):
        n = np.arange(N, dtype=np.int32)
        rows, cols = np.concatenate([i, j, n]), np.concatenate([j, i, n])
        self.order = np.lexsort((cols, rows))
        self.rows = rows[self.order].astype(np.int32)
        self.indices = cols[self.order].astype(np.int32)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=N))]).astype(
            np.int32 if rows.size < 2**31 else np.int64)
        self.N = N

    def csr(self, values, row_scale=None, column_scale=None):
        """The block with ``values = (upper, lower, diagonal)`` at ``(i, j)``, ``(j, i)`` and
        on the diagonal, optionally scaled by ``diag(row_scale)`` on the left and
        ``diag(column_scale)`` on the right."""
        N = self.N
        upper, lower, diagonal = values
        vals = np.concatenate([np.broadcast_to(upper, (self.order.size - N) // 2),
                               np.broadcast_to(lower, (self.order.size - N) // 2),
                               np.broadcast_to(diagonal, N)])[self.order]
        if row_scale is not None:
            vals *= row_scale[self.rows]
        if column_scale is not None:
            vals *= column_scale[self.indices]
        return sp.csr_matrix((vals, self.indices, self.indptr), shape=(N, N))


@dataclass(frozen=True, eq=False)
class AdhesionDerivatives:
    """The data of the exact first and second derivatives of ``E_A(U)`` at one curve.

    Built by :func:`adhesion_derivatives`; symbols as in the module docstring.

    Parameters
    ----------
    curve : Curve
    A0 : float
        The kernel's ``A(0)`` (the diagonal term).
    i, j : ndarray of intp, shape (P,)
        The pairs, ``i < j``.
    kxx, kxy, kyy : ndarray, shape (P,)
        ``4 w_i w_j H_ij`` entries.
    fx, fy : ndarray, shape (P,)
        ``4 A'(l_ij) d_ij``.
    a2 : ndarray, shape (P,)
        ``2 A(l_ij)``.
    F : ndarray, shape (N, 2)
        ``dE^/dX``.
    B : ndarray, shape (N,)
        ``dE^/dw``.
    P : ndarray, shape (N, 2)
        ``C^T F``.
    a, p, beta : ndarray, shape (N,)
        ``P . tau``, ``P . tau'``, ``C^T (g p)``.
    """

    curve: Curve
    A0: float
    i: np.ndarray
    j: np.ndarray
    kxx: np.ndarray
    kxy: np.ndarray
    kyy: np.ndarray
    fx: np.ndarray
    fy: np.ndarray
    a2: np.ndarray
    F: np.ndarray
    B: np.ndarray
    P: np.ndarray
    a: np.ndarray
    p: np.ndarray
    beta: np.ndarray

    @property
    def n_pairs(self) -> int:
        """Number ``P`` of pairs (``i < j``)."""
        return int(self.i.size)

    # ------------------------------------------------------------- gradient
    def euclidean_gradient(self) -> np.ndarray:
        """``(dE/dkappa_j, dE/dg_j)``: plain partial derivatives, shape (2N,).

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies.adhesion import AdhesionKernel, dense_pairs
        >>> c = Curve.circle(1.0, Fourier(33))
        >>> d = adhesion_derivatives(AdhesionKernel(10.0, 0.5, 1.0), c, dense_pairs(33))
        >>> w = np.concatenate([c.dsigma, c.dsigma])
        >>> bool(np.allclose(d.euclidean_gradient(), d.gradient() * w))
        True
        """
        c = self.curve
        om = c.grid.weights
        return np.concatenate([c.g * self.beta, self.a + c.kappa * self.beta + om * self.B])

    def gradient(self) -> np.ndarray:
        """``nabla_I E_A`` in ``<f, h> = sum f h dsigma``, shape (2N,).

        ``d/d delta E_A(U + delta U1) = <nabla_I E_A, U1>`` exactly (pairs fixed).

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies.adhesion import AdhesionKernel, adhesion_energy, dense_pairs
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
        >>> k = AdhesionKernel(10.0, 0.5, 1.0)
        >>> E = lambda U: adhesion_energy(k, *c.with_U(U).positions(), c.with_U(U).dsigma)
        >>> U1, h = np.cos(np.arange(66.0)), 1e-6
        >>> fd = (E(c.U + h * U1) - E(c.U - h * U1)) / (2 * h)
        >>> G = adhesion_derivatives(k, c, dense_pairs(33)).gradient()
        >>> bool(np.isclose(fd, G @ (U1 * np.concatenate([c.dsigma, c.dsigma])), rtol=1e-7))
        True
        """
        ds = self.curve.dsigma
        return self.euclidean_gradient() / np.concatenate([ds, ds])

    # ------------------------------------------------------ Hessian products
    def pair_product(self, dX, dw):
        """``(F1, B1) = K (X1, w1)``: the pair Hessian applied to position and weight changes.

        Parameters
        ----------
        dX : ndarray, shape (N, 2)
        dw : ndarray, shape (N,)

        Returns
        -------
        F1 : ndarray, shape (N, 2)
        B1 : ndarray, shape (N,)
        """
        N = self.curve.N
        i, j = self.i, self.j
        w = self.curve.dsigma
        ddx = dX[i, 0] - dX[j, 0]
        ddy = dX[i, 1] - dX[j, 1]
        wi, wj, dwi, dwj = w[i], w[j], dw[i], dw[j]
        s = dwi * wj + wi * dwj
        tx = self.kxx * ddx + self.kxy * ddy + self.fx * s
        ty = self.kxy * ddx + self.kyy * ddy + self.fy * s
        F1 = np.empty((N, 2))
        F1[:, 0] = np.bincount(i, tx, N) - np.bincount(j, tx, N)
        F1[:, 1] = np.bincount(i, ty, N) - np.bincount(j, ty, N)
        e = self.fx * ddx + self.fy * ddy
        B1 = (2.0 * self.A0 * dw + np.bincount(i, e * wj + self.a2 * dwj, N)
              + np.bincount(j, e * wi + self.a2 * dwi, N))
        return F1, B1

    def euclidean_hessian_vector(self, v, d_theta0=0.0, d_origin=(0.0, 0.0)) -> np.ndarray:
        """Second derivative of ``E_A`` along ``v``, with optional base-point changes.

        ``sum_k (d^2 E / dU_j dU_k) v_k`` (plain partial derivatives), where the base
        angle and point move by ``d_theta0``, ``d_origin`` as well (their second
        derivatives are zero by rigid invariance; they enter the tests).

        Parameters
        ----------
        v : array_like, shape (2N,) or (2N, m)
        d_theta0 : float
        d_origin : (float, float)

        Returns
        -------
        ndarray, shape like ``v``
        """
        v = np.asarray(v, dtype=float)
        if v.ndim == 2:
            return np.column_stack([self.euclidean_hessian_vector(col, d_theta0, d_origin)
                                    for col in v.T])
        c = self.curve
        grid, N = c.grid, c.N
        if v.shape != (2 * N,):
            raise ValueError(f"v has shape {v.shape}, expected ({2 * N},) or ({2 * N}, m)")
        g, kappa, om = c.g, c.kappa, grid.weights
        th = c.theta()
        cs, sn = np.cos(th), np.sin(th)
        k1, g1 = v[:N], v[N:]
        th1 = grid.cumulative(g * k1 + kappa * g1) + d_theta0
        q1 = np.column_stack([cs * g1 - g * sn * th1, sn * g1 + g * cs * th1])
        X1 = grid.cumulative(q1) + np.asarray(d_origin, dtype=float)[None, :]
        F1, B1 = self.pair_product(X1, om * g1)
        P1 = grid.cumulative_transpose(F1)
        a1 = P1[:, 0] * cs + P1[:, 1] * sn + self.p * th1
        p1 = -P1[:, 0] * sn + P1[:, 1] * cs - self.a * th1
        beta1 = grid.cumulative_transpose(g1 * self.p + g * p1)
        return np.concatenate([g1 * self.beta + g * beta1,
                               a1 + k1 * self.beta + kappa * beta1 + om * B1])

    def hessian_vector(self, v) -> np.ndarray:
        """``nabla_I^2 E_A v`` in ``<f, h> = sum f h dsigma`` without assembling (O(N + P)).

        Parameters
        ----------
        v : array_like, shape (2N,) or (2N, m)

        Returns
        -------
        ndarray, shape like ``v``
            ``(d^2/d delta^2) E_A(U + delta v) = <H v, v>``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies.adhesion import AdhesionKernel, dense_pairs
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
        >>> d = adhesion_derivatives(AdhesionKernel(10.0, 0.5, 1.0), c, dense_pairs(33))
        >>> V = np.random.default_rng(0).standard_normal((66, 2))
        >>> bool(np.allclose(d.hessian_vector(V), d.hessian() @ V))
        True
        """
        ds = self.curve.dsigma
        w2 = np.concatenate([ds, ds])
        out = self.euclidean_hessian_vector(v)
        return out / (w2 if out.ndim == 1 else w2[:, None])

    # ------------------------------------------------------------ assembly
    def _block_values(self):
        """``(upper, lower, diagonal)`` of ``K``'s ``N x N`` blocks: the values at the pairs
        ``(i, j)``, at their mirror images ``(j, i)`` and on the diagonal, keyed by block
        (``"xx", "xy", "yy"`` of ``K_XX``, ``"xw", "yw"`` of ``K_Xw``, ``"ww"``)."""
        N = self.curve.N
        i, j = self.i, self.j
        w = self.curve.dsigma
        wi, wj = w[i], w[j]
        both = lambda v: np.bincount(i, v, N) + np.bincount(j, v, N)
        out = {name: (-kv, -kv, both(kv))
               for name, kv in (("xx", self.kxx), ("xy", self.kxy), ("yy", self.kyy))}
        for name, f in (("xw", self.fx), ("yw", self.fy)):
            out[name] = (f * wi, -f * wj, np.bincount(i, f * wj, N) - np.bincount(j, f * wi, N))
        out["ww"] = (self.a2, self.a2, np.full(N, 2.0 * self.A0))
        return out

    def _pair_blocks(self):
        """Entries of ``K``'s blocks ``K_XX`` (2N, 2N), ``K_Xw`` (2N, N), ``K_ww`` (N, N).

        Each a :class:`_Entries` of block-local ``(rows, cols, vals)``; every position
        occurs once (pairs are unique), so they can be assigned as well as summed.
        """
        N = self.curve.N
        i, j = self.i.astype(np.int32), self.j.astype(np.int32)  # halves the index memory
        n = np.arange(N, dtype=np.int32)
        v = self._block_values()
        XX, XW, WW = _Entries(), _Entries(), _Entries()
        for ro, co, name in ((0, 0, "xx"), (0, N, "xy"), (N, N, "yy")):
            upper, lower, diagonal = v[name]
            mirror = ro != co
            XX.add(ro + i, co + j, upper, mirror)
            XX.add(ro + j, co + i, lower, mirror)
            XX.add(ro + n, co + n, diagonal, mirror)
        for ro, name in ((0, "xw"), (N, "yw")):
            upper, lower, diagonal = v[name]
            XW.add(ro + i, j, upper)
            XW.add(ro + j, i, lower)
            XW.add(ro + n, n, diagonal)
        upper, _, diagonal = v["ww"]  # symmetric
        WW.add(i, j, upper, True)
        WW.add(n, n, diagonal)
        return XX, XW, WW

    def pair_hessian(self):
        """``K``, the Hessian of ``E^(X, w)`` in ``(x, y, w)``: sparse, shape (3N, 3N).

        Returns
        -------
        scipy.sparse.csr_matrix, shape (3N, 3N)
            Symmetric, ``18 P + 9 N`` stored entries at most.
        """
        N = self.curve.N
        XX, XW, WW = (e.tocsr(shape) for e, shape in zip(
            self._pair_blocks(), ((2 * N, 2 * N), (2 * N, N), (N, N)), strict=False))
        return sp.bmat([[XX, XW], [XW.T, WW]], format="csr")

    def _dense_pair_hessian(self):
        N = self.curve.N
        K = np.zeros((3 * N, 3 * N))
        XX, XW, WW = self._pair_blocks()
        for e, ro, co in ((XX, 0, 0), (XW, 0, 2 * N), (WW, 2 * N, 2 * N)):
            for r, cc, v in zip(e.rows, e.cols, e.vals, strict=False):
                K[ro + r, co + cc] = v  # every position occurs once
                if co != ro:
                    K[co + cc, ro + r] = v
        return K

    def dense_hessian(self) -> np.ndarray:
        """``nabla_I^2 E_A`` in ``<.,.>`` as a dense ndarray, shape (2N, 2N).

        ``C^T K C`` by cumulative sums on both sides of the dense pair Hessian:
        O(N^2) memory and time (finite differences), O(N^2 log N) (Fourier).
        """
        c = self.curve
        grid, N = c.grid, c.N
        g, kappa, om = c.g, c.kappa, grid.weights
        th = c.theta()
        cs, sn = np.cos(th), np.sin(th)
        Kt = self._dense_pair_hessian()
        for _ in range(2):  # C-hat^T K C-hat, C-hat = diag(C, C, I); K is symmetric
            Kt[:N] = grid.cumulative_transpose(Kt[:N])
            Kt[N : 2 * N] = grid.cumulative_transpose(Kt[N : 2 * N])
            Kt = Kt.T.copy()
        # (kappa1, g1, theta1) -> (q1x, q1y, w1), q1 = g1 tau + g theta1 tau'
        d = sp.diags
        Z = None
        Lmap = sp.bmat([[Z, d(cs), d(-g * sn)], [Z, d(sn), d(g * cs)],
                        [sp.csr_matrix((N, N)), d(om), sp.csr_matrix((N, N))]], format="csr")
        Phi = Lmap.T @ (Lmap.T @ Kt).T
        del Kt
        idx = np.arange(N)
        Phi[idx, N + idx] += self.beta
        Phi[N + idx, idx] += self.beta
        Phi[N + idx, 2 * N + idx] += self.p
        Phi[2 * N + idx, N + idx] += self.p
        Phi[2 * N + idx, 2 * N + idx] -= g * self.a
        # theta1 = T U1, T = C [diag g, diag kappa]:  T^T X = [g C^T X; kappa C^T X]
        TT = lambda X: np.vstack([g[:, None] * X, kappa[:, None] * X])
        Mx = TT(grid.cumulative_transpose(Phi[2 * N :, : 2 * N]))
        H = Phi[: 2 * N, : 2 * N] + Mx + Mx.T
        H += TT(grid.cumulative_transpose(TT(grid.cumulative_transpose(Phi[2 * N :, 2 * N :])).T))
        ds = c.dsigma
        H /= np.concatenate([ds, ds])[:, None]
        return H

    def reduced_hessian(self) -> ReducedHessian:
        """``nabla_I^2 E_A`` in ``<.,.>`` in factored form (finite differences only).

        See the module docstring: O(N + P) storage, exact.

        Returns
        -------
        ReducedHessian, shape (2N, 2N)

        Raises
        ------
        ValueError
            On a Fourier grid (its cumulative integral has no sparse factors).
        """
        c = self.curve
        if not c.grid.sparse:
            raise ValueError("form='reduced' needs a finite-difference grid (on Fourier grids "
                             "the cumulative integral is dense); use form='dense'")
        N = c.N
        g, om = c.g, c.grid.weights
        d = sp.diags
        # the blocks of K (_block_values) in CSR, one pattern for all of them
        pat = _PairPattern(self.i.astype(np.int32), self.j.astype(np.int32), N)
        v = self._block_values()
        Kxx, Kxy, Kyy = (pat.csr(v[name]) for name in ("xx", "xy", "yy"))
        Kxw, Kyw = (pat.csr(v[name], column_scale=om) for name in ("xw", "yw"))
        Kww = pat.csr(v["ww"], row_scale=om, column_scale=om)
        bI = lambda v: d(np.broadcast_to(v, N).astype(float), format="csr")
        grid = lambda blocks: BlockSparse(blocks).tocsr()
        # L_UU = [[0, beta], [beta, omega K_ww omega]], on (kappa, g)
        Luu = grid([[None, bI(self.beta)], [bI(self.beta), Kww]])
        # L_YU = [[0, p], [0, K_Xw omega]], rows (theta, x, y), columns (kappa, g)
        Lyu = grid([[sp.csr_matrix((N, N)), bI(self.p)], [None, Kxw], [None, Kyw]])
        # L_YY = diag(-g a, K_XX)
        Lyy = grid([[bI(-g * self.a), None, None], [None, Kxx, Kxy], [None, Kxy, Kyy]])
        cY, cU = position_state_equations(c)
        ds = c.dsigma
        return ReducedHessian(Luu, Lyu, Lyy, cY, cU, left=d(1.0 / np.concatenate([ds, ds])))

    def operator_reduced_hessian(self, pair) -> OperatorPairHessian:
        """:meth:`reduced_hessian` with the pair Hessian ``K`` applied by products only.

        The sparse factors hold only the local parts (``beta``, ``p``, ``-g a``); ``K``
        enters as ``S^T K S`` with ``S (u, y) = (y_x, y_y, omega u_g)``
        (:class:`~qsa.linalg.implicit.OperatorPairHessian`).

        Parameters
        ----------
        pair : object
            ``K`` in the order ``(x, y, w)`` of :meth:`pair_hessian`, shape (3N, 3N),
            with ``pair @ X``: the assembled matrix or
            :class:`~qsa.energies.adhesion_far.HierarchicalPairHessian`.

        Returns
        -------
        OperatorPairHessian, shape (2N, 2N)
        """
        c = self.curve
        if not c.grid.sparse:
            raise ValueError("operator_reduced_hessian needs a finite-difference grid")
        N = c.N
        if pair.shape != (3 * N, 3 * N):
            raise ValueError(f"pair must have shape {(3 * N, 3 * N)}, got {pair.shape}")
        local, Su, Sy = local_reduced_parts(c, self.a, self.p, self.beta)
        return OperatorPairHessian(local, pair, Su, Sy)

    def hessian(self, form="auto"):
        """``nabla_I^2 E_A`` in ``<f, h> = sum f h dsigma``, ``dsigma``-self-adjoint.

        Parameters
        ----------
        form : {"auto", "dense", "reduced"}
            ``"dense"``: ndarray (2N, 2N); ``"reduced"``: :class:`~qsa.linalg.ReducedHessian`
            (finite differences). ``"auto"``: reduced on finite-difference grids unless
            more than half of all node pairs interact (a long-range kernel: the dense
            assembly, about 300 N^2 bytes at its peak against about 750 bytes per pair
            for the reduced one, is then the smaller), dense otherwise.

        Returns
        -------
        ndarray or ReducedHessian, shape (2N, 2N)
        """
        if form not in HESSIAN_FORMS:
            raise ValueError(f"form must be one of {HESSIAN_FORMS}, got {form!r}")
        N = self.curve.N
        if form == "auto":
            sparse = self.curve.grid.sparse and self.n_pairs <= N * (N - 1) // 4
            form = "reduced" if sparse else "dense"
        return self.reduced_hessian() if form == "reduced" else self.dense_hessian()


def adhesion_derivatives(kernel, c: Curve, pairs) -> AdhesionDerivatives:
    """Pair data and adjoint fields for the exact derivatives of ``E_A`` at ``c``.

    Parameters
    ----------
    kernel : AdhesionKernel
    c : Curve
    pairs : tuple of ndarray
        ``(i, j)``, ``i < j``: the pairs of the energy
        (:func:`~qsa.energies.adhesion.adhesion_pairs` at ``c``'s positions).

    Returns
    -------
    AdhesionDerivatives

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies.adhesion import AdhesionKernel, adhesion_fields, dense_pairs
    >>> c = Curve.circle(1.0, Fourier(33))
    >>> k = AdhesionKernel(10.0, 0.5, 1.0)
    >>> d = adhesion_derivatives(k, c, dense_pairs(33))
    >>> B, force = adhesion_fields(k, *c.positions(), c.dsigma, method="dense")
    >>> bool(np.allclose(d.B, B)), bool(np.allclose(d.F, c.dsigma[:, None] * force))
    (True, True)
    """
    i, j = (np.asarray(p, dtype=np.intp) for p in pairs)
    N = c.N
    if i.shape != j.shape or (i.size and (i.min() < 0 or j.max() >= N or np.any(i >= j))):
        raise ValueError(f"pairs must be index arrays (i, j) with 0 <= i < j < N = {N}")
    x, y = c.positions()
    w = c.dsigma
    dx, dy = x[i] - x[j], y[i] - y[j]
    A, dA, d2A = kernel.derivatives(dx * dx + dy * dy)
    ww4 = 4.0 * w[i] * w[j]
    t = 2.0 * d2A
    fx, fy = 4.0 * dA * dx, 4.0 * dA * dy
    wiwj = w[i] * w[j]
    F = np.column_stack([np.bincount(i, fx * wiwj, N) - np.bincount(j, fx * wiwj, N),
                         np.bincount(i, fy * wiwj, N) - np.bincount(j, fy * wiwj, N)])
    B = 2.0 * kernel.A0 * w + 2.0 * (np.bincount(i, A * w[j], N) + np.bincount(j, A * w[i], N))
    P, a, p, beta = adjoint_fields(c, F)
    return AdhesionDerivatives(
        curve=c, A0=float(kernel.A0), i=i, j=j,
        kxx=ww4 * (t * dx * dx + dA), kxy=ww4 * t * dx * dy, kyy=ww4 * (t * dy * dy + dA),
        fx=fx, fy=fy, a2=2.0 * A, F=F, B=B, P=P, a=a, p=p, beta=beta)
