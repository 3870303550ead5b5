"""Structured matrices of the operator layers: sparse plus low rank, implicit-state Hessians.

``SparsePlusLowRank`` represents ``S + U @ V.T`` with ``S`` sparse and ``U, V``
thin dense factors. Finite-difference Hessians are sparse except for the
perimeter penalty's rank-one term ``(beta / g) int g1 ds``; keeping that term
factored keeps memory and matrix-vector products O(N) at N = 10^6.

``ReducedHessian`` represents the Hessian of a function ``E(U) = E^(Y(U), U)``
whose state ``Y`` is defined implicitly by sparse equations ``c(Y, U) = 0``
(e.g. positions obtained by cumulative integration): dense as a matrix, exact
and O(nnz) in factored form, with shift-invert solves through one sparse
saddle-point system.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["SparsePlusLowRank", "ReducedHessian", "BlockSparse", "to_dense", "is_matrix_like"]


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
        if isinstance(other, ReducedHessian):
            return NotImplemented
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
        if isinstance(other, ReducedHessian):
            return NotImplemented
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


class ReducedHessian:
    """``H = S0 + Lf K Rf + U V^T`` with ``K`` the reduced Hessian of an implicit state.

    ``K = Luu + Lyu^T Z + Z^T Lyu + Z^T Lyy Z``, ``Z = dY/dU = -cY^{-1} cU``, is the
    Hessian of ``E(U) = E^(Y(U), U)`` when the state ``Y(U)`` solves ``c(Y, U) = 0``:
    ``Luu, Lyu, Lyy`` are the second derivatives of the Lagrangian
    ``E^ + lambda . c`` at the adjoint multipliers (``d/dY = 0``) and ``cY, cU`` the
    constraint Jacobians. ``K`` is dense when ``cY^{-1}`` is (a cumulative sum), yet
    every factor is sparse: storage and products cost O(nnz), and ``(H - sigma B) x = b``
    is one sparse saddle-point solve (:meth:`shift_invert`).

    Parameters
    ----------
    Luu : sparse matrix, shape (p, p)
        Symmetric.
    Lyu : sparse matrix, shape (m, p)
    Lyy : sparse matrix, shape (m, m)
        Symmetric.
    cY : sparse matrix, shape (m, m)
        Invertible; a lower-triangular one is factored without fill.
    cU : sparse matrix, shape (m, p)
    left : sparse matrix, shape (n, p), optional
        ``Lf`` (default the identity).
    right : sparse matrix, shape (p, k), optional
        ``Rf`` (default the identity).
    S : sparse matrix, shape (n, k), optional
        ``S0`` (default zero).
    U, V : array_like, shape (n, r) and (k, r), optional
        Low-rank term (default none).

    Notes
    -----
    Sums with sparse, :class:`SparsePlusLowRank` and other ``ReducedHessian``
    matrices, products with sparse matrices on either side, scalar multiples and
    ``.T`` stay in this form; sums with dense arrays become dense.

    Examples
    --------
    ``E(u) = sum_i y_i(u)^2 / 2`` with ``y = C u`` the cumulative sum
    (``c(y, u) = Bd y - u``, ``Bd`` the bidiagonal difference): ``H = C^T C``.

    >>> import numpy as np, scipy.sparse as sp
    >>> n = 5
    >>> Bd = sp.eye(n) - sp.eye(n, k=-1)
    >>> H = ReducedHessian(sp.csr_matrix((n, n)), sp.csr_matrix((n, n)), sp.eye(n),
    ...                    Bd, -sp.eye(n))
    >>> C = np.tril(np.ones((n, n)))
    >>> bool(np.allclose(H.toarray(), C.T @ C))
    True
    >>> b = np.arange(1.0, n + 1)
    >>> bool(np.allclose(H @ (H.shift_invert(0.5) @ b) - 0.5 * (H.shift_invert(0.5) @ b), b))
    True
    """

    __array_ufunc__ = None  # make ndarray @ self and ndarray + self defer to this class

    def __init__(self, Luu, Lyu, Lyy, cY, cU, left=None, right=None, S=None, U=None, V=None):
        self.Luu, self.Lyu, self.Lyy = sp.csr_matrix(Luu), sp.csr_matrix(Lyu), sp.csr_matrix(Lyy)
        self.cY, self.cU = sp.csr_matrix(cY), sp.csr_matrix(cU)
        p, m = self.Luu.shape[0], self.cY.shape[0]
        if (self.Luu.shape != (p, p) or self.Lyu.shape != (m, p) or self.Lyy.shape != (m, m)
                or self.cY.shape != (m, m) or self.cU.shape != (m, p)):
            raise ValueError("ReducedHessian: need Luu (p, p), Lyu (m, p), Lyy (m, m), "
                             "cY (m, m), cU (m, p)")
        self.left = sp.identity(p, format="csr") if left is None else sp.csr_matrix(left)
        self.right = sp.identity(p, format="csr") if right is None else sp.csr_matrix(right)
        if self.left.shape[1] != p or self.right.shape[0] != p:
            raise ValueError(f"ReducedHessian: left must have {p} columns and right {p} rows")
        n, k = self.left.shape[0], self.right.shape[1]
        self.S = sp.csr_matrix((n, k)) if S is None else sp.csr_matrix(S)
        if self.S.shape != (n, k):
            raise ValueError(f"ReducedHessian: S must have shape {(n, k)}, got {self.S.shape}")
        U = np.zeros((n, 0)) if U is None else np.asarray(U, dtype=float).reshape(n, -1)
        V = np.zeros((k, 0)) if V is None else np.asarray(V, dtype=float).reshape(k, -1)
        if U.shape[1] != V.shape[1]:
            raise ValueError("ReducedHessian: U and V must have the same number of columns")
        self.U, self.V = U, V
        # derived from the core (Luu, Lyu, Lyy, cY, cU) alone, shared by every matrix
        # _with makes from this one: the factors of cY ("lu"), the row structure of a
        # triangular cY ("rows", for _solve_cY_many), CSR Lyu^T and cU^T ("transposes",
        # for implicit_state), entrywise absolute values ("abs", for rounding bounds)
        self._core = {}
        # error estimates of approximated parts of K (a compressed two-point term): each
        # f(l, u) estimates |l^T dK u| column by column for l, u in K's domain; sums,
        # multiples and products with sparse matrices carry them (approximation_error)
        self.approximations: tuple = ()
        # state rows of compressed (coarse) blocks: dense, but fewer than the nodes' rows;
        # the shift-invert solvers eliminate the rest onto them (carried like approximations)
        self.coarse_states = 0
        # which state rows (of q) they are: the coarse Schur solver's layout
        self.coarse_index = np.zeros(0, dtype=np.intp)

    # ----------------------------------------------------------------- shape
    @property
    def shape(self):
        """``(n, k)``."""
        return (self.left.shape[0], self.right.shape[1])

    @property
    def nnz(self):
        """Stored nonzeros of all sparse factors (the memory is O(nnz + (n + k) r))."""
        return sum(A.nnz for A in (self.Luu, self.Lyu, self.Lyy, self.cY, self.cU,
                                   self.left, self.right, self.S))

    @property
    def nbytes(self):
        """Bytes held by the sparse factors and the low-rank columns."""
        total = self.U.nbytes + self.V.nbytes
        for A in (self.Luu, self.Lyu, self.Lyy, self.cY, self.cU, self.left, self.right, self.S):
            total += A.data.nbytes + A.indices.nbytes + A.indptr.nbytes
        return total

    def _with(self, **changes):
        args = dict(Luu=self.Luu, Lyu=self.Lyu, Lyy=self.Lyy, cY=self.cY, cU=self.cU,
                    left=self.left, right=self.right, S=self.S, U=self.U, V=self.V)
        args.update(changes)
        out = ReducedHessian(**args)
        if not changes.keys() & {"Luu", "Lyu", "Lyy", "cY", "cU"}:
            out._core = self._core  # same core: share what is derived from it
            out.approximations = self.approximations
            out.coarse_states = self.coarse_states
            out.coarse_index = self.coarse_index
        return out

    def _stacked_coarse(self, other) -> np.ndarray:
        """The coarse state rows of ``self``'s states followed by ``other``'s."""
        return np.concatenate([self.coarse_index, other.coarse_index + self.cY.shape[0]])

    def approximation_error(self, l, u) -> np.ndarray:
        """Estimate of ``|l^T dK u|`` from the approximated parts of ``K`` (zeros if none).

        ``l``, ``u`` are in ``K``'s domain (``Lf^T psi`` and ``Rf psi`` of a form
        ``psi^T H psi``), shape (p,) or (p, k); one estimate per column.
        """
        l = np.asarray(l, dtype=float)
        out = np.zeros(l.shape[1:] if l.ndim > 1 else ())
        for f in self.approximations:
            out = out + f(l, np.asarray(u, dtype=float))
        return out

    def abs_core(self):
        """``|Luu|, |Lyu^T|, |Lyu|, |Lyy|`` (CSR, entrywise), formed once per core."""
        if "abs" not in self._core:
            self._core["abs"] = tuple(sp.csr_matrix(abs(A)) for A in
                                      (self.Luu, self.Lyu.T, self.Lyu, self.Lyy))
        return self._core["abs"]

    # -------------------------------------------------------------- products
    def _solve_cY(self, b, trans="N"):
        if self.cY.shape[0] == 0:  # no implicit state: H = S0 + Lf Luu Rf
            return np.zeros((0,) + np.shape(b)[1:])
        if "lu" not in self._core:
            cY = self.cY.tocsc()
            if sp.triu(cY, 1).nnz == 0:  # lower triangular: natural order, no fill
                self._core["lu"] = spla.splu(cY, permc_spec="NATURAL", diag_pivot_thresh=0.0)
            else:
                self._core["lu"] = spla.splu(cY)
        return self._core["lu"].solve(np.asarray(b, dtype=float), trans=trans)

    def _solve_cY_many(self, B, trans="N", overwrite=False):
        """``cY^{-1} B`` (or ``cY^{-T} B``) for a dense ``B`` with many columns, C-ordered.

        A triangular ``cY`` is solved by substitution row after row, each row a vector
        operation over all the columns (several times faster than SuperLU's column
        loop for a few thousand columns, and without its copies to Fortran order);
        otherwise by its LU factors. ``overwrite`` lets a C-ordered float ``B`` be
        overwritten by the solution.
        """
        if "rows" not in self._core:
            cY = sp.csr_matrix(self.cY)
            lower = sp.triu(cY, 1).nnz == 0
            if not lower:
                self._core["rows"] = False
            else:
                rows = {}
                for name, A in (("N", cY), ("T", sp.csr_matrix(cY.T))):
                    A.sort_indices()
                    ip, ix, dv = A.indptr, A.indices, A.data
                    out = []
                    for i in range(A.shape[0]):
                        cols, vals = ix[ip[i]:ip[i + 1]], dv[ip[i]:ip[i + 1]]
                        on = cols == i
                        out.append((1.0 / vals[on][0], cols[~on], vals[~on]))
                    rows[name] = out
                self._core["rows"] = rows
        if self._core["rows"] is False:
            return np.ascontiguousarray(self._solve_cY(np.asfortranarray(B), trans=trans))
        W = B if overwrite and B.dtype == float and B.flags.c_contiguous else \
            np.array(B, dtype=float, order="C")
        rows = self._core["rows"][trans]
        order = range(len(rows)) if trans == "N" else range(len(rows) - 1, -1, -1)
        for i in order:
            inv, cols, vals = rows[i]
            if cols.size == 1:
                W[i] -= vals[0] * W[cols[0]]
            elif cols.size:
                W[i] -= vals @ W[cols]
            W[i] *= inv
        return W

    def _transposed(self):
        """CSR ``Lyu^T`` and ``cU^T``, formed once per core."""
        if "transposes" not in self._core:
            self._core["transposes"] = (sp.csr_matrix(self.Lyu.T), sp.csr_matrix(self.cU.T))
        return self._core["transposes"]

    def core_matvec(self, u):
        """``K u`` for the reduced Hessian ``K`` alone, ``u`` shape (p,) or (p, j)."""
        return self.implicit_state(np.asarray(u, dtype=float))[0]

    def implicit_state(self, u, b4=0.0, b5=0.0, b6=0.0):
        """``(v, y, mu)`` with ``cU u + cY y = b6``, ``Lyu u + Lyy y + cY^T mu = b5`` and
        ``v = Luu u + Lyu^T y + cU^T mu - b4`` (``v = K u`` when the ``b`` are zero).

        Parameters
        ----------
        u : ndarray, shape (p,) or (p, j)
        b4, b5, b6 : ndarray or float
            Right-hand sides of the ``v``, adjoint and state rows.

        Returns
        -------
        tuple of ndarray
        """
        LyuT, cUT = self._transposed()
        y = self._solve_cY(b6 - self.cU @ u)
        mu = self._solve_cY(b5 - self.Lyu @ u - self.Lyy @ y, trans="T")
        return self.Luu @ u + LyuT @ y + cUT @ mu - b4, y, mu

    def core_matmat(self, Q, block=2048):
        """``K Q`` as a dense ``(p, k)`` array for a sparse ``Q`` with few entries per column.

        ``K Q`` by :meth:`core_matvec` costs ``nnz(Lyy) k`` (the products of the wide
        two-point blocks with the dense ``Z Q``). Here they are taken the other way round:
        ``Lyy Z Q = -(cY^{-T} Lyy)^T (cU Q)`` (``Lyy`` symmetric) and
        ``Lyu^T Z Q = -(cY^{-T} Lyu)^T (cU Q)``, with ``cY^{-T}`` applied to ``block``
        densified columns of ``[Lyy, Lyu]`` at a time: ``O(m (m + p))`` work with a
        triangular ``cY``, ``O(m block + (m + p) k)`` memory.

        Parameters
        ----------
        Q : sparse matrix, shape (p, k)
        block : int
            Columns of ``[Lyy, Lyu]`` densified at a time.

        Returns
        -------
        ndarray, shape (p, k)

        Examples
        --------
        >>> import numpy as np, scipy.sparse as sp
        >>> n = 6
        >>> Bd = sp.eye(n) - sp.eye(n, k=-1)
        >>> Lyy = sp.csr_matrix(np.add.outer(np.arange(n), np.arange(n)) % 3 + np.eye(n))
        >>> K = ReducedHessian(sp.eye(n), sp.eye(n, k=1), Lyy, Bd, -sp.eye(n))
        >>> Q = sp.random(n, 4, density=0.4, random_state=0)
        >>> bool(np.allclose(K.core_matmat(Q, block=4), K.core_matvec(Q.toarray())))
        True
        """
        Q = sp.csr_matrix(Q)
        k = Q.shape[1]
        cUQ = sp.csc_matrix(self.cU @ Q)
        cUQt = sp.csr_matrix(cUQ.T)                             # (k, m)
        LyuT, cUT = self._transposed()
        ty = np.asarray((self.Lyu @ Q).toarray())               # Lyu Q + Lyy Z Q
        tu = np.asarray((self.Luu @ Q).toarray())               # Luu Q + Lyu^T Z Q
        ZQ = None                                               # -Z Q, (m, k), if needed
        # the columns of Lyy (symmetric) and Lyu: the transposes of CSR matrices are CSC
        for cols_of, dest in ((self.Lyy.T, ty), (LyuT.T, tu)):
            # a short column (the local parts of the state) is a sparse row times Z Q;
            # only the wide ones go through cY^{-T}
            length = np.diff(cols_of.indptr)
            short = length <= max(64, k // 8)
            narrow, wide = np.flatnonzero(short & (length > 0)), np.flatnonzero(~short)
            if narrow.size:
                if ZQ is None:
                    ZQ = self._solve_cY_many(cUQ.toarray(order="C"), overwrite=True)
                dest[narrow] -= cols_of[:, narrow].T @ ZQ
            for start in range(0, wide.size, block):
                cols = wide[start:start + block]
                W = self._solve_cY_many(cols_of[:, cols].toarray(order="C"), trans="T",
                                        overwrite=True)
                dest[cols] -= (cUQt @ W).T
        tu -= cUT @ self._solve_cY_many(ty, trans="T", overwrite=True)
        return tu

    def __matmul__(self, other):
        if isinstance(other, ReducedHessian):
            return NotImplemented
        if isinstance(other, SparsePlusLowRank):
            return (self @ other.S) + SparsePlusLowRank(sp.csr_matrix((self.shape[0],
                                                                       other.shape[1])),
                                                        self @ other.U, other.V)
        if sp.issparse(other):
            return self._with(right=self.right @ other, S=self.S @ other,
                              V=np.asarray(other.T @ self.V))
        x = np.asarray(other, dtype=float)
        out = self.S @ x + self.left @ self.core_matvec(self.right @ x)
        if self.U.shape[1]:
            out = out + self.U @ (self.V.T @ x)
        return out

    def __rmatmul__(self, other):
        if isinstance(other, SparsePlusLowRank):
            low = SparsePlusLowRank(sp.csr_matrix((other.shape[0], self.shape[1])), other.U,
                                    self.T @ other.V)
            return (other.S @ self) + low
        if sp.issparse(other):
            return self._with(left=other @ self.left, S=other @ self.S,
                              U=np.asarray(other @ self.U))
        return (self.T @ np.asarray(other, dtype=float).T).T

    @property
    def T(self):
        """Transpose (``K`` is symmetric): again a :class:`ReducedHessian`."""
        return self._with(left=self.right.T, right=self.left.T, S=self.S.T, U=self.V, V=self.U)

    def toarray(self, block=256):
        """Dense ``ndarray`` of shape ``(n, k)``, built ``block`` columns at a time.

        O(n k) memory and ``k`` products; meant for moderate sizes and checks.
        """
        return dense_columns(self, block)

    def aslinearoperator(self):
        """``scipy.sparse.linalg.LinearOperator`` with O(nnz) products."""
        return spla.LinearOperator(self.shape, matvec=self.__matmul__, rmatvec=self.T.__matmul__,
                                   matmat=self.__matmul__, dtype=float)

    # ------------------------------------------------------------ solutions
    def _scalings(self):
        """``(l, r)`` if ``Lf = diag(l)``, ``Rf = diag(r)`` are invertible diagonals, else None."""
        out = []
        for A in (self.left, self.right):
            if A.shape[0] != A.shape[1] or sp.triu(A, 1).nnz or sp.tril(A, -1).nnz:
                return None
            dvec = A.diagonal()
            if np.any(dvec == 0):
                return None
            out.append(dvec)
        return tuple(out)

    def augmented(self, sigma=0.0, mass=None):
        """The sparse saddle-point matrix of ``(H - sigma B - U V^T) x = b``.

        With invertible diagonal ``Lf = diag(l)``, ``Rf = diag(r)`` (the energies'
        case) the unknowns are ``[r x, y, mu]`` (sizes p, m, m), the right-hand side
        ``[b / l, 0, 0]`` and the matrix ::

            [[diag(1/l) (S0 - sigma B) diag(1/r) + Luu, Lyu^T, cU^T],
             [Lyu, Lyy, cY^T],
             [cU, cY, 0]];

        eliminating ``mu`` and ``y = Z (r x)`` leaves ``diag(1/l) (H - sigma B - U V^T) x``.
        Otherwise the unknowns are ``[x, u, y, mu, v]`` (sizes n, p, m, m, p) and the rows ::

            (S0 - sigma B) x + Lf v = b,       Rf x - u = 0,
            Luu u + Lyu^T y + cU^T mu - v = 0, Lyu u + Lyy y + cY^T mu = 0,
            cU u + cY y = 0,

        so that ``y = Z u``, ``v = K u`` and ``(S0 - sigma B + Lf K Rf) x = b``.

        Parameters
        ----------
        sigma : float
        mass : sparse matrix, shape (n, n), optional
            ``B`` (default the identity).

        Returns
        -------
        scipy.sparse.csc_matrix
            Square, of size ``p + 2m`` (diagonal scalings) or ``n + 2p + 2m``.
        """
        n, k = self.shape
        if n != k:
            raise ValueError(f"augmented: the matrix must be square, got shape {self.shape}")
        B = sp.identity(n, format="csr") if mass is None else sp.csr_matrix(mass)
        if B.shape != (n, n):
            raise ValueError(f"mass must have shape {(n, n)}, got {B.shape}")
        p = self.Luu.shape[0]
        scal = self._scalings()
        if scal is not None:
            lv, rv = scal
            top = sp.diags(1.0 / lv) @ (self.S - sigma * B) @ sp.diags(1.0 / rv) + self.Luu
            blocks = [[top, self.Lyu.T, self.cU.T],
                      [self.Lyu, self.Lyy, self.cY.T],
                      [self.cU, self.cY, None]]
            return sp.bmat(blocks, format="csc")
        Ip = sp.identity(p, format="csr")
        if self.cY.shape[0] == 0:  # no implicit state: rows x, u, v only
            blocks = [[self.S - sigma * B, None, self.left],
                      [self.right, -Ip, None],
                      [None, self.Luu, -Ip]]
            return sp.bmat(blocks, format="csc")
        blocks = [
            [self.S - sigma * B, None, None, None, self.left],
            [self.right, -Ip, None, None, None],
            [None, self.Luu, self.Lyu.T, self.cU.T, -Ip],
            [None, self.Lyu, self.Lyy, self.cY.T, None],
            [None, self.cU, self.cY, None, None],
        ]
        return sp.bmat(blocks, format="csc")

    def shift_invert(self, sigma=0.0, mass=None):
        """``(H - sigma B)^{-1}`` as a ``LinearOperator`` (one sparse LU, then O(fill) solves).

        The sparse part is factored through :meth:`augmented`; the low-rank term by the
        Sherman-Morrison-Woodbury formula.

        Parameters
        ----------
        sigma : float
            Shift.
        mass : sparse matrix, shape (n, n), optional
            ``B`` (default the identity).

        Returns
        -------
        scipy.sparse.linalg.LinearOperator, shape (n, n)

        Raises
        ------
        ValueError
            If ``H - sigma B`` is singular (the factorization fails).
        """
        n = self.shape[0]
        try:
            lu = spla.splu(self.augmented(sigma, mass))
        except RuntimeError as err:
            raise ValueError(f"sigma = {sigma}: H - sigma B is singular ({err})") from None
        scal = self._scalings()

        def solve0(b):
            b = np.asarray(b, dtype=float)
            rhs = np.zeros((lu.shape[0],) + b.shape[1:])
            if scal is None:
                rhs[:n] = b
                return lu.solve(rhs)[:n]
            lv, rv = (v.reshape((-1,) + (1,) * (b.ndim - 1)) for v in scal)
            rhs[:n] = b / lv
            return lu.solve(rhs)[:n] / rv

        r = self.U.shape[1]
        if r:
            W = solve0(self.U)
            cap = np.linalg.inv(np.eye(r) + self.V.T @ W)

            def solve(b):
                y = solve0(b)
                return y - W @ (cap @ (self.V.T @ y))
        else:
            solve = solve0
        return spla.LinearOperator((n, n), matvec=solve, matmat=solve, dtype=float)

    # ------------------------------------------------------------- algebra
    def __add__(self, other):
        if isinstance(other, ReducedHessian):
            if other.shape != self.shape:
                raise ValueError(f"shapes {self.shape} and {other.shape} do not match")
            bd = lambda A, B: BlockSparse([[A, None], [None, B]]).tocsr()
            if _same(self.left, other.left) and _same(self.right, other.right):
                # one core on the same unknowns: stack the states, keep Lf and Rf (so a
                # diagonal scaling stays diagonal and augmented() stays compact)
                out = ReducedHessian(self.Luu + other.Luu, sp.vstack([self.Lyu, other.Lyu]),
                                     bd(self.Lyy, other.Lyy), bd(self.cY, other.cY),
                                     sp.vstack([self.cU, other.cU]), self.left, self.right,
                                     self.S + other.S, np.hstack([self.U, other.U]),
                                     np.hstack([self.V, other.V]))
                out.approximations = self.approximations + other.approximations
                out.coarse_states = self.coarse_states + other.coarse_states
                out.coarse_index = self._stacked_coarse(other)
                return out
            out = ReducedHessian(bd(self.Luu, other.Luu), bd(self.Lyu, other.Lyu),
                                 bd(self.Lyy, other.Lyy), bd(self.cY, other.cY),
                                 bd(self.cU, other.cU), sp.hstack([self.left, other.left]),
                                 sp.vstack([self.right, other.right]), self.S + other.S,
                                 np.hstack([self.U, other.U]), np.hstack([self.V, other.V]))
            p = self.Luu.shape[0]  # the stacked domain: self's first, then other's
            out.approximations = (
                tuple(_restricted(f, slice(0, p)) for f in self.approximations)
                + tuple(_restricted(f, slice(p, None)) for f in other.approximations))
            out.coarse_states = self.coarse_states + other.coarse_states
            out.coarse_index = self._stacked_coarse(other)
            return out
        if isinstance(other, SparsePlusLowRank):
            return self._with(S=self.S + other.S, U=np.hstack([self.U, other.U]),
                              V=np.hstack([self.V, other.V]))
        if sp.issparse(other):
            return self._with(S=self.S + other)
        if np.isscalar(other) and other == 0:
            return self
        return self.toarray() + np.asarray(other)

    __radd__ = __add__

    def __mul__(self, c):
        if not np.isscalar(c):
            return NotImplemented
        # the core is unchanged, so _with carries approximations (l = Lf^T psi takes c)
        return self._with(left=c * self.left, S=c * self.S, U=c * self.U)

    __rmul__ = __mul__

    def __neg__(self):
        return self * -1.0

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __repr__(self):
        return (f"ReducedHessian(shape={self.shape}, state={self.cY.shape[0]}, nnz={self.nnz}, "
                f"rank={self.U.shape[1]})")


def _restricted(f, part):
    """``f`` of a stacked domain's part ``part`` (a slice of the rows of ``l`` and ``u``)."""
    return lambda l, u: f(l[part], u[part])


class BlockSparse:
    """A block matrix of sparse blocks, multiplied block by block and assembled on demand.

    Products cost the blocks' ``nnz`` and need no assembled copy of the whole matrix
    (for large blocks, assembling it costs more than many products); :meth:`tocsc`
    assembles it for a sparse LU.

    Parameters
    ----------
    blocks : list of list
        Rows of sparse matrices or ``None`` (a zero block), as for ``scipy.sparse.bmat``;
        every block row and block column holds at least one matrix.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> B = BlockSparse([[sp.eye(2), None], [sp.csr_matrix(np.ones((1, 2))), sp.eye(1)]])
    >>> (B @ np.array([1.0, 2.0, 3.0])).tolist(), B.shape
    ([1.0, 2.0, 6.0], (3, 3))
    >>> bool(np.allclose(B.tocsc().toarray() @ np.ones(3), B @ np.ones(3)))
    True
    """

    __array_ufunc__ = None

    def __init__(self, blocks):
        rows = [next((b.shape[0] for b in row if b is not None), None) for row in blocks]
        cols = [next((row[j].shape[1] for row in blocks if row[j] is not None), None)
                for j in range(len(blocks[0]))]
        if None in rows or None in cols:
            raise ValueError("BlockSparse: every block row and column needs a matrix")
        self._rows = np.concatenate([[0], np.cumsum(rows)]).astype(int)
        self._cols = np.concatenate([[0], np.cumsum(cols)]).astype(int)
        self.blocks = [[None if b is None else
                        (b if getattr(b, "format", None) in ("csr", "csc") else sp.csr_matrix(b))
                        for b in row] for row in blocks]

    @property
    def shape(self):
        """``(n, m)``."""
        return (int(self._rows[-1]), int(self._cols[-1]))

    @property
    def nnz(self):
        """Stored entries of all blocks."""
        return sum(b.nnz for row in self.blocks for b in row if b is not None)

    def __matmul__(self, x):
        return self.product(x)

    def product(self, x, mask=None):
        """``self @ x`` over the blocks where ``mask`` (block rows x block columns) is True.

        The result has the type of ``x`` and the blocks (float64 entries are widened
        exactly for an ``np.longdouble`` ``x``). Default: every block.
        """
        x = np.asarray(x)
        out = np.zeros((self.shape[0],) + x.shape[1:],
                       dtype=np.result_type(x.dtype, *(b.dtype for row in self.blocks
                                                       for b in row if b is not None)))
        for i, row in enumerate(self.blocks):
            r0, r1 = self._rows[i], self._rows[i + 1]
            for j, b in enumerate(row):
                if b is not None and (mask is None or mask[i][j]):
                    out[r0:r1] += b @ x[self._cols[j]:self._cols[j + 1]]
        return out

    def wide(self, entries_per_row=16):
        """Which blocks hold at least ``entries_per_row`` stored entries per row on average.

        Returns
        -------
        ndarray of bool, shape (block rows, block columns)
        """
        rows = np.diff(self._rows)
        return np.array([[b is not None and b.nnz >= entries_per_row * r for b in row]
                         for row, r in zip(self.blocks, rows, strict=True)], dtype=bool)

    def astype(self, dtype):
        """The same blocks with entries of ``dtype`` (e.g. ``np.longdouble``)."""
        return BlockSparse([[None if b is None else b.astype(dtype) for b in row]
                            for row in self.blocks])

    def _assembled(self, fmt):
        # with every block in the target format (zero blocks as empty ones), scipy joins
        # the blocks' arrays instead of assembling through COO
        convert = sp.csr_matrix if fmt == "csr" else sp.csc_matrix
        rows, cols = np.diff(self._rows), np.diff(self._cols)
        full = [[convert((int(r), int(c))) if b is None else convert(b)
                 for b, c in zip(row, cols, strict=True)]
                for row, r in zip(self.blocks, rows, strict=True)]
        return sp.bmat(full, format=fmt)

    def tocsc(self):
        """The assembled matrix (``scipy.sparse`` CSC)."""
        return self._assembled("csc")

    def tocsr(self):
        """The assembled matrix (``scipy.sparse`` CSR)."""
        return self._assembled("csr")


def dense_columns(A, block=256) -> np.ndarray:
    """``A`` as a dense array from products ``A @ E`` with ``block`` unit columns at a time."""
    n, k = A.shape
    out = np.empty((n, k))
    for start in range(0, k, block):
        stop = min(k, start + block)
        E = np.zeros((k, stop - start))
        E[np.arange(start, stop), np.arange(stop - start)] = 1.0
        out[:, start:stop] = A @ E
    return out


def _same(A, B) -> bool:
    """Whether two sparse matrices are equal entry by entry."""
    return A.shape == B.shape and (A != B).nnz == 0


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
    if isinstance(A, (SparsePlusLowRank, ReducedHessian)) or sp.issparse(A):
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
        True for ``ndarray``, ``scipy.sparse`` matrices, :class:`SparsePlusLowRank` and
        :class:`ReducedHessian`.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> is_matrix_like(np.eye(2)), is_matrix_like(sp.eye(2)), is_matrix_like([[1.0]])
    (True, True, False)
    """
    return isinstance(A, (np.ndarray, SparsePlusLowRank, ReducedHessian)) or sp.issparse(A)
