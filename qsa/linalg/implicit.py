"""A reduced Hessian whose two-point term is applied as an operator (never assembled).

:class:`~qsa.linalg.ReducedHessian` holds the second derivatives ``Luu, Lyu, Lyy`` of the
Lagrangian as sparse matrices. For a two-point energy they hold one entry per pair of
interacting nodes, and the pairs grow like ``N^2`` for folded curves. Here the Lagrangian
Hessian is split as ::

    [[Luu, Lyu^T], [Lyu, Lyy]] = (local sparse part) + S^T P S,    S = [Su, Sy],

with ``S`` a sparse selection / scaling (a few entries per row) and ``P`` the pair
Hessian applied by products only (e.g. the hierarchical form of
:mod:`qsa.energies.adhesion_far`). The implicit state is solved as in
:meth:`ReducedHessian.implicit_state`, with one product by ``P`` per call.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from qsa.linalg.structured import ReducedHessian, dense_columns

__all__ = ["OperatorPairHessian"]


class OperatorPairHessian:
    """``H = Lf K Rf`` with ``K`` the reduced Hessian of ``local + S^T P S`` (module docstring).

    Parameters
    ----------
    local : ReducedHessian
        The local part: its ``Luu, Lyu, Lyy`` without the pair term, its state equations
        ``cY, cU`` and its ``left``, ``right`` (``S``, ``U``, ``V`` must be zero).
    pair : object
        Square operator with ``pair @ X`` for ``X`` of shape (k,) or (k, j); symmetric.
    Su : sparse matrix, shape (k, p)
    Sy : sparse matrix, shape (k, m)

    Attributes
    ----------
    products : int
        Columns multiplied by ``pair`` so far (a cost counter).

    Examples
    --------
    With the pair term assembled, the result is the :class:`ReducedHessian` of the sum:

    >>> import numpy as np, scipy.sparse as sp
    >>> n = 5
    >>> Bd = sp.eye(n) - sp.eye(n, k=-1)
    >>> P = sp.csr_matrix(np.add.outer(np.arange(n), np.arange(n)) % 3 + 0.0)
    >>> Z = sp.csr_matrix((n, n))
    >>> H = OperatorPairHessian(ReducedHessian(sp.eye(n), Z, Z, Bd, -sp.eye(n)), P,
    ...                         Z, sp.eye(n))
    >>> R = ReducedHessian(sp.eye(n), Z, P, Bd, -sp.eye(n))
    >>> bool(np.allclose(H.toarray(), R.toarray()))
    True
    """

    __array_ufunc__ = None

    def __init__(self, local: ReducedHessian, pair, Su, Sy):
        if not isinstance(local, ReducedHessian):
            raise ValueError("local must be a ReducedHessian")
        if local.S.nnz or local.U.shape[1]:
            raise ValueError("local must have no S and no low-rank term (S = 0, U = V = None)")
        self.local = local
        self.pair = pair
        self.Su, self.Sy = sp.csr_matrix(Su), sp.csr_matrix(Sy)
        p, m = local.Luu.shape[0], local.cY.shape[0]
        k = pair.shape[0]
        if pair.shape != (k, k) or self.Su.shape != (k, p) or self.Sy.shape != (k, m):
            raise ValueError(f"need pair (k, k), Su (k, {p}), Sy (k, {m}); got {pair.shape}, "
                             f"{self.Su.shape}, {self.Sy.shape}")
        self._SuT, self._SyT = sp.csr_matrix(self.Su.T), sp.csr_matrix(self.Sy.T)
        self.products = 0

    # the parts the capacitance solver reads
    @property
    def Luu(self):
        """The local ``Luu`` (its shape is that of the whole one)."""
        return self.local.Luu

    @property
    def cY(self):
        return self.local.cY

    @property
    def cU(self):
        return self.local.cU

    @property
    def left(self):
        return self.local.left

    @property
    def right(self):
        return self.local.right

    @property
    def shape(self):
        return self.local.shape

    def with_left(self, left) -> OperatorPairHessian:
        """The same ``K`` and ``Rf`` with the left factor ``left`` (sparse, (n', p))."""
        return OperatorPairHessian(self.local._with(left=sp.csr_matrix(left),
                                                    S=sp.csr_matrix((left.shape[0],
                                                                     self.shape[1])),
                                                    U=np.zeros((left.shape[0], 0))),
                                   self.pair, self.Su, self.Sy)

    def implicit_state(self, u, b4=0.0, b5=0.0, b6=0.0):
        """``(v, y, mu)`` as :meth:`ReducedHessian.implicit_state`, one product by ``pair``."""
        L = self.local
        u = np.asarray(u, dtype=float)
        LyuT, cUT = L._transposed()
        y = L._solve_cY(b6 - L.cU @ u)
        z = self.pair @ (self.Su @ u + self.Sy @ y)
        self.products += 1 if z.ndim == 1 else z.shape[1]
        mu = L._solve_cY(b5 - L.Lyu @ u - L.Lyy @ y - self._SyT @ z, trans="T")
        v = L.Luu @ u + LyuT @ y + self._SuT @ z + cUT @ mu - b4
        return v, y, mu

    def core_matvec(self, u):
        """``K u``, ``u`` shape (p,) or (p, j)."""
        return self.implicit_state(np.asarray(u, dtype=float))[0]

    def core_matmat(self, Q, block=256):
        """``K Q`` as a dense array, ``block`` columns of the sparse ``Q`` at a time."""
        Q = sp.csc_matrix(Q)
        out = np.empty((Q.shape[0], Q.shape[1]))
        for start in range(0, Q.shape[1], block):
            stop = min(Q.shape[1], start + block)
            out[:, start:stop] = self.core_matvec(Q[:, start:stop].toarray())
        return out

    def __matmul__(self, x):
        x = np.asarray(x, dtype=float)
        return self.left @ self.core_matvec(self.right @ x)

    def toarray(self, block=256):
        """Dense ``ndarray`` (``k`` products; for checks at moderate sizes)."""
        return dense_columns(self, block)

    def aslinearoperator(self):
        """``scipy.sparse.linalg.LinearOperator`` (``K`` symmetric, ``Lf``, ``Rf`` as given)."""
        return spla.LinearOperator(self.shape, matvec=self.__matmul__, matmat=self.__matmul__,
                                   dtype=float)

    def __repr__(self):
        return (f"OperatorPairHessian(shape={self.shape}, state={self.cY.shape[0]}, "
                f"pair={self.pair.shape}, products={self.products})")
