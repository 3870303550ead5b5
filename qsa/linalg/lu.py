"""LU factorizations: the one way the package factors a matrix.

:func:`factorize` factors a dense (LAPACK ``getrf``) or sparse (SuperLU) matrix ``C``,
optionally bordered by a thin dense border ``[[C, B1], [B2, D]]`` that is eliminated
through its Schur complement ``D - B2 C^{-1} B1``. :meth:`Factorization.det_sign` is the
sign of the determinant (how a continuation sees folds and branch points).
:class:`LowRankUpdate` solves with a factored matrix plus a dense block supported on a
few rows, ``A + E_R C E_K^T``, by the Woodbury identity (the flows' long-range adhesion
block, the dense gauge row of their Newton matrix).

A singular or non-finite matrix raises ``numpy.linalg.LinAlgError``.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["factorize", "Factorization", "LowRankUpdate", "permutation_parity"]


def permutation_parity(p) -> int:
    """Sign (+1 or -1) of the permutation ``i -> p[i]``.

    Parameters
    ----------
    p : array_like of int, shape (n,)
        A permutation of ``0 .. n-1``.

    Returns
    -------
    int

    Examples
    --------
    >>> permutation_parity([0, 1, 2]), permutation_parity([1, 0, 2]), permutation_parity([1, 2, 0])
    (1, -1, 1)
    """
    p = np.asarray(p)
    seen = np.zeros(p.size, dtype=bool)
    parity = 0
    for i in range(p.size):
        if not seen[i]:
            j, length = i, 0
            while not seen[j]:
                seen[j] = True
                j = p[j]
                length += 1
            parity += length - 1
    return -1 if parity % 2 else 1


def _superlu_sign(lu) -> int:
    # Pr A Pc = L U with unit lower L: det A = sign(Pr) sign(Pc) prod diag U
    s = int(np.prod(np.sign(lu.U.diagonal())))
    return s * permutation_parity(lu.perm_r) * permutation_parity(lu.perm_c)


def _lapack_sign(lu, piv) -> int:
    # A = P L U, piv[i] the row swapped with i
    s = int(np.prod(np.sign(np.diag(lu))))
    return s * (-1) ** int(np.sum(piv != np.arange(piv.size)))


class Factorization:
    """LU factors of ``[[C, B1], [B2, D]]`` with a dense or sparse core ``C`` and a thin border.

    Built by :func:`factorize`. The border (``p`` extra rows and columns, ``p`` small)
    is eliminated by the Schur complement ``S = D - B2 C^{-1} B1``; ``C`` is factored
    once (LAPACK ``getrf`` for dense, SuperLU for sparse cores).

    Attributes
    ----------
    shape : tuple of int
        ``(n + p, n + p)``.
    nnz : int
        Number of stored entries of the factors of ``C`` (``n^2`` for dense).
    """

    def __init__(self, C, B1=None, B2=None, D=None, *, permc_spec="COLAMD", _core=None):
        n = C.shape[0]
        if _core is not None:
            self._solve, self.nnz, self._core_sign = _core
        elif sp.issparse(C):
            C = sp.csc_matrix(C)
            if not np.all(np.isfinite(C.data)):
                raise np.linalg.LinAlgError("the matrix has non-finite entries")
            try:
                lu = spla.splu(C, permc_spec=permc_spec)
            except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
                raise np.linalg.LinAlgError(f"singular matrix: {exc}") from None
            self._solve = lu.solve
            self.nnz = int(lu.L.nnz + lu.U.nnz)
            self._core_sign = functools.partial(_superlu_sign, lu)
        else:
            C = np.asarray(C, dtype=float)
            if not np.all(np.isfinite(C)):
                raise np.linalg.LinAlgError("the matrix has non-finite entries")
            with warnings.catch_warnings():  # an exact zero pivot is raised below
                warnings.simplefilter("ignore", sla.LinAlgWarning)
                lu, piv = sla.lu_factor(C, check_finite=False)
            if np.any(np.diag(lu) == 0):
                raise np.linalg.LinAlgError("singular matrix: zero pivot in LU")
            self._solve = lambda b: sla.lu_solve((lu, piv), b, check_finite=False)
            self.nnz = n * n
            self._core_sign = functools.partial(_lapack_sign, lu, piv)
        p = 0 if B1 is None else np.asarray(B1).shape[1]
        self._n, self._p = n, p
        self.shape = (n + p, n + p)
        if p:
            self._B1 = np.asarray(B1, dtype=float)
            self._B2 = np.asarray(B2, dtype=float)
            self._Z = self._solve(self._B1)
            schur = np.asarray(D, dtype=float) - self._B2 @ self._Z
            self._schur = sla.lu_factor(schur)

    @classmethod
    def from_solver(cls, solver, B1=None, B2=None, D=None) -> Factorization:
        """A bordered factorization around a core that is solved by other means.

        Parameters
        ----------
        solver : object
            With ``shape`` (square), ``nnz``, ``solve(b)`` (``b`` of shape (n,) or
            (n, k)) and ``det_sign()``.
        B1, B2, D : ndarray, optional
            The border, as in :func:`factorize`.

        Returns
        -------
        Factorization
        """
        return cls(_Shape(solver.shape[0]), B1, B2, D,
                   _core=(solver.solve, int(solver.nnz), solver.det_sign))

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
        return Factorization(_Shape(self._n), B1, B2, D,
                             _core=(self._solve, self.nnz, self._core_sign))

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

    def det_sign(self) -> int:
        """Sign of the determinant of the factored matrix (+1 or -1).

        ``det [[C, B1], [B2, D]] = det C det S``; each sign is read off the diagonal of
        the triangular factor and the parities of the pivoting permutations.

        Returns
        -------
        int

        Examples
        --------
        >>> import numpy as np, scipy.sparse as sp
        >>> A = np.array([[0.0, 2.0], [3.0, 1.0]])  # det = -6
        >>> factorize(A).det_sign(), factorize(sp.csc_matrix(A)).det_sign()
        (-1, -1)
        """
        s = self._core_sign()
        if self._p:
            s *= _lapack_sign(*self._schur)
        return int(s)


class _Shape:
    """Stand-in for a core that is already factored (only its shape is read)."""

    def __init__(self, n):
        self.shape = (n, n)


def factorize(C, B1=None, B2=None, D=None, *, permc_spec="COLAMD") -> Factorization:
    """LU factorization of ``C`` (dense or sparse), optionally bordered by ``B1, B2, D``.

    Parameters
    ----------
    C : ndarray or sparse matrix, shape (n, n)
    B1 : ndarray, shape (n, p), optional
    B2 : ndarray, shape (p, n), optional
    D : ndarray, shape (p, p), optional
    permc_spec : str
        SuperLU's column ordering of a sparse ``C`` (``"COLAMD"``, or ``"NATURAL"`` for
        a matrix already ordered for little fill, e.g. banded).

    Returns
    -------
    Factorization
        ``.solve(b)`` for the bordered system ``[[C, B1], [B2, D]]``, ``.det_sign()``.

    Raises
    ------
    numpy.linalg.LinAlgError
        ``C`` is exactly singular or has non-finite entries.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> C = sp.diags([2.0, 3.0, 4.0]).tocsc()
    >>> F = factorize(C, np.ones((3, 1)), np.ones((1, 3)), np.zeros((1, 1)))
    >>> A = np.block([[C.toarray(), np.ones((3, 1))], [np.ones((1, 3)), np.zeros((1, 1))]])
    >>> b = np.arange(4.0)
    >>> bool(np.allclose(A @ F.solve(b), b)), F.det_sign() == int(np.sign(np.linalg.det(A)))
    (True, True)
    """
    return Factorization(C, B1, B2, D, permc_spec=permc_spec)


class LowRankUpdate:
    """Solutions with ``A + E_R C E_K^T`` from a factorization of ``A`` (Woodbury identity).

    ``E_R`` and ``E_K`` are the columns of the identity at ``rows`` (``r`` of them) and
    ``cols``: the update is the dense block ``C`` in those rows and columns. With
    ``Z = A^{-1} E_R`` (``r`` solves) and the capacitance ``S = I + C Z[cols]`` (dense
    LU, ``r^3/3`` flops), ::

        x0 = A^{-1} b,   w = S^{-1} C x0[cols],   x = x0 - Z w = A^{-1} (b - E_R w).

    ``store=True`` keeps ``Z`` (n x r) and takes the first form (one solve with ``A``
    per solution: for a few rows); ``store=False`` keeps only ``Z[cols]`` and takes the
    second (two solves: for many rows, e.g. a long-range block of ``N`` rows).

    Parameters
    ----------
    base : object with ``solve(b)`` and ``shape``
        The factorization of ``A`` (a :class:`Factorization`, or any solver).
    rows : array_like of int, shape (r,)
    C : ndarray, shape (r, k)
        ``k = len(cols)``, or ``n`` when ``cols`` is None (all columns).
    cols : array_like of int, shape (k,), optional
    store : bool

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> A = sp.diags([2.0, 3.0, 4.0, 5.0]).tocsc()
    >>> C = np.array([[1.0, 1.0, 1.0, 1.0]])  # a dense first row
    >>> M = A.toarray(); M[0] += C[0]
    >>> b = np.arange(1.0, 5.0)
    >>> x = LowRankUpdate(factorize(A), [0], C).solve(b)
    >>> y = LowRankUpdate(factorize(A), [0], C, store=False).solve(b)
    >>> bool(np.allclose(M @ x, b)), bool(np.allclose(x, y))
    (True, True)
    """

    def __init__(self, base, rows, C, cols=None, store=True):
        n = base.shape[0]
        self.base = base
        self.rows = np.asarray(rows, dtype=int)
        self.cols = None if cols is None else np.asarray(cols, dtype=int)
        self.C = np.asarray(C, dtype=float)
        r = self.rows.size
        if self.C.shape != (r, n if cols is None else self.cols.size):
            raise ValueError(f"C must have shape (len(rows), len(cols)), got {self.C.shape}")
        self.shape = base.shape
        self.store = bool(store)
        E = np.zeros((n, r))
        E[self.rows, np.arange(r)] = 1.0
        Z = base.solve(E)
        Zc = Z if cols is None else Z[self.cols]
        self._Z = Z if self.store else None
        self._S = sla.lu_factor(np.eye(r) + self.C @ Zc, check_finite=False)

    def solve(self, b):
        """``x`` with ``(A + E_R C E_K^T) x = b``; ``b`` of shape (n,) or (n, m)."""
        b = np.asarray(b, dtype=float)
        x0 = self.base.solve(b)
        w = sla.lu_solve(self._S, self.C @ (x0 if self.cols is None else x0[self.cols]),
                         check_finite=False)
        if self.store:
            return x0 - self._Z @ w
        rhs = b.copy()
        rhs[self.rows] -= w
        return self.base.solve(rhs)
