"""Small linear-algebra helpers shared by the operator layers.

``SparsePlusLowRank`` represents ``S + U @ V.T`` with ``S`` sparse and ``U, V``
thin dense factors. Finite-difference Hessians are sparse except for the
perimeter penalty's rank-one term ``(beta / g) int g1 ds``; keeping that term
factored keeps memory and matrix-vector products O(N) at N = 10^6.

:func:`factorize` is the one LU factorization of the package: dense (LAPACK),
sparse (SuperLU) or either with a thin dense border, solved by block elimination.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["SparsePlusLowRank", "to_dense", "is_matrix_like", "factorize", "Factorization"]


class SparsePlusLowRank:
    """The matrix ``S + U @ V.T`` (``S`` sparse, shape (n, m); ``U`` (n, r); ``V`` (m, r)).

    Supports ``@`` with vectors, dense matrices, sparse matrices and other
    instances, ``+``/``-`` with sparse or dense matrices, scalar ``*``,
    ``.T``, ``toarray()`` and ``aslinearoperator()``.

    Parameters
    ----------
    S : sparse matrix or array_like, shape (n, m)
    U : array_like, shape (n, r) or (n,)
    V : array_like, shape (m, r) or (m,)

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> A = SparsePlusLowRank(sp.identity(3), np.ones((3, 1)), np.ones((3, 1)))
    >>> A @ np.array([1.0, 0.0, 0.0])
    array([2., 1., 1.])
    >>> A.shape, A.rank, bool(np.allclose((A @ A).toarray(), A.toarray() @ A.toarray()))
    ((3, 3), 1, True)
    """

    __array_ufunc__ = None  # make ndarray @ self defer to __rmatmul__

    def __init__(self, S, U, V):
        S = sp.csr_matrix(S)
        U = np.asarray(U, dtype=float).reshape(S.shape[0], -1)
        V = np.asarray(V, dtype=float).reshape(S.shape[1], -1)
        if U.shape[1] != V.shape[1]:
            raise ValueError("U and V must have the same number of columns")
        self.S, self.U, self.V = S, U, V

    @property
    def shape(self):
        """``(n, m)``."""
        return self.S.shape

    @property
    def rank(self):
        """Number ``r`` of columns of the low-rank factors (an upper bound of the rank)."""
        return self.U.shape[1]

    @property
    def T(self):
        """Transpose ``S.T + V @ U.T``, again a :class:`SparsePlusLowRank`."""
        return SparsePlusLowRank(self.S.T, self.V, self.U)

    def toarray(self):
        """Dense ``ndarray`` of shape ``(n, m)`` (O(n m) memory)."""
        return self.S.toarray() + self.U @ self.V.T

    def aslinearoperator(self):
        """``scipy.sparse.linalg.LinearOperator`` with O(nnz + (n + m) r) products."""
        return spla.LinearOperator(self.shape, matvec=self.__matmul__, rmatvec=self.T.__matmul__,
                                   matmat=self.__matmul__, dtype=float)

    def __matmul__(self, other):
        if isinstance(other, SparsePlusLowRank):
            # (S + U V^T)(S2 + U2 V2^T) = S S2 + [U, (S + U V^T) U2] [S2^T V, V2]^T
            left = np.hstack([self.U, self @ other.U])
            right = np.hstack([other.S.T @ self.V, other.V])
            return SparsePlusLowRank(self.S @ other.S, left, right)
        if sp.issparse(other):
            return SparsePlusLowRank(self.S @ other, self.U, other.T @ self.V)
        other = np.asarray(other)
        return self.S @ other + self.U @ (self.V.T @ other)

    def __rmatmul__(self, other):
        if sp.issparse(other):
            return SparsePlusLowRank(other @ self.S, other @ self.U, self.V)
        other = np.asarray(other)
        return other @ self.S + (other @ self.U) @ self.V.T

    def __add__(self, other):
        if isinstance(other, SparsePlusLowRank):
            return SparsePlusLowRank(self.S + other.S, np.hstack([self.U, other.U]),
                                     np.hstack([self.V, other.V]))
        if sp.issparse(other):
            return SparsePlusLowRank(self.S + other, self.U, self.V)
        if np.isscalar(other) and other == 0:
            return self
        return self.toarray() + np.asarray(other)

    __radd__ = __add__

    def __neg__(self):
        return SparsePlusLowRank(-self.S, -self.U, self.V)

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, c):
        if not np.isscalar(c):
            return NotImplemented
        return SparsePlusLowRank(c * self.S, c * self.U, self.V)

    __rmul__ = __mul__

    def __repr__(self):
        return f"SparsePlusLowRank(shape={self.shape}, nnz={self.S.nnz}, rank={self.rank})"


def to_dense(A) -> np.ndarray:
    """Dense ``ndarray`` copy of a dense, sparse or :class:`SparsePlusLowRank` matrix.

    Parameters
    ----------
    A : ndarray, sparse matrix or SparsePlusLowRank, shape (n, m)

    Returns
    -------
    ndarray, shape (n, m)
        A new float array (never a view of ``A``).

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> to_dense(sp.identity(2)).tolist()
    [[1.0, 0.0], [0.0, 1.0]]
    """
    if isinstance(A, SparsePlusLowRank) or sp.issparse(A):
        return A.toarray()
    return np.array(A, dtype=float)


def is_matrix_like(A) -> bool:
    """Whether ``A`` is a matrix the operator layers accept.

    Parameters
    ----------
    A : object

    Returns
    -------
    bool
        True for ``ndarray``, ``scipy.sparse`` matrices and :class:`SparsePlusLowRank`.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> is_matrix_like(np.eye(2)), is_matrix_like(sp.eye(2)), is_matrix_like([[1.0]])
    (True, True, False)
    """
    return isinstance(A, (np.ndarray, SparsePlusLowRank)) or sp.issparse(A)


class Factorization:
    """LU factors of ``[[C, B1], [B2, D]]`` with a dense or sparse core ``C`` and a thin border.

    Built by :func:`factorize`. The border (``p`` extra rows and columns, ``p`` small)
    is eliminated by the Schur complement ``S = D - B2 C^{-1} B1``; ``C`` is factored
    once (LAPACK ``getrf`` for dense, SuperLU with COLAMD for sparse cores).

    Attributes
    ----------
    shape : tuple of int
        ``(n + p, n + p)``.
    nnz : int
        Number of stored entries of the factors of ``C`` (``n^2`` for dense).
    """

    def __init__(self, C, B1=None, B2=None, D=None, _core=None):
        n = C.shape[0]
        if _core is not None:
            self._solve, self.nnz = _core
        elif sp.issparse(C):
            try:
                lu = spla.splu(sp.csc_matrix(C), permc_spec="COLAMD")
            except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
                raise np.linalg.LinAlgError(f"singular matrix: {exc}") from None
            self._solve = lu.solve
            self.nnz = int(lu.L.nnz + lu.U.nnz)
        else:
            C = np.asarray(C, dtype=float)
            lu, piv = sla.lu_factor(C, check_finite=True)
            if np.any(np.diag(lu) == 0):
                raise np.linalg.LinAlgError("singular matrix: zero pivot in LU")
            self._solve = lambda b: sla.lu_solve((lu, piv), b, check_finite=False)
            self.nnz = n * n
        p = 0 if B1 is None else np.asarray(B1).shape[1]
        self._n, self._p = n, p
        self.shape = (n + p, n + p)
        if p:
            self._B1 = np.asarray(B1, dtype=float)
            self._B2 = np.asarray(B2, dtype=float)
            self._Z = self._solve(self._B1)
            schur = np.asarray(D, dtype=float) - self._B2 @ self._Z
            self._schur = sla.lu_factor(schur)

    def with_border(self, B1=None, B2=None, D=None) -> Factorization:
        """The same core ``C`` (not factored again) with another border.

        Parameters
        ----------
        B1 : ndarray, shape (n, p), optional
        B2 : ndarray, shape (p, n), optional
        D : ndarray, shape (p, p), optional

        Returns
        -------
        Factorization
        """
        return Factorization(_Shape(self._n), B1, B2, D, _core=(self._solve, self.nnz))

    def solve(self, b):
        """``x`` with ``[[C, B1], [B2, D]] x = b``, shape (n + p,) (or (n,) without border)."""
        b = np.asarray(b, dtype=float)
        n, p = self._n, self._p
        if not p:
            return self._solve(b)
        f, g = b[:n], b[n:]
        y0 = self._solve(f)
        y = sla.lu_solve(self._schur, g - self._B2 @ y0)
        return np.concatenate([y0 - self._Z @ y, y])


class _Shape:
    """Stand-in for a core that is already factored (only its shape is read)."""

    def __init__(self, n):
        self.shape = (n, n)


def factorize(C, B1=None, B2=None, D=None) -> Factorization:
    """LU factorization of ``C`` (dense or sparse), optionally bordered by ``B1, B2, D``.

    Parameters
    ----------
    C : ndarray or sparse matrix, shape (n, n)
    B1 : ndarray, shape (n, p), optional
    B2 : ndarray, shape (p, n), optional
    D : ndarray, shape (p, p), optional

    Returns
    -------
    Factorization
        ``.solve(b)`` for the bordered system ``[[C, B1], [B2, D]]``.

    Raises
    ------
    numpy.linalg.LinAlgError
        ``C`` is exactly singular.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> C = sp.diags([2.0, 3.0, 4.0]).tocsc()
    >>> F = factorize(C, np.ones((3, 1)), np.ones((1, 3)), np.zeros((1, 1)))
    >>> A = np.block([[C.toarray(), np.ones((3, 1))], [np.ones((1, 3)), np.zeros((1, 1))]])
    >>> b = np.arange(4.0)
    >>> bool(np.allclose(A @ F.solve(b), b))
    True
    """
    return Factorization(C, B1, B2, D)
