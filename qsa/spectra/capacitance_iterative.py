"""The capacitance solve of :mod:`qsa.spectra.capacitance` by GMRES, without forming ``T``.

``T = I + [A^{-1} E K Q]_phi`` is applied by products: one implicit-state product
``K (Q phi)`` (:meth:`~qsa.linalg.ReducedHessian.implicit_state`, or one product with a
compressed pair Hessian through :class:`~qsa.linalg.implicit.OperatorPairHessian`) and
one solve with the local sparse factors of ``A``. Nothing of size ``N^2`` is stored, so
this works where neither the two-point blocks nor ``T`` would fit. ``T - I`` is
numerically of full rank, yet its spectrum clusters at 1 with a few outliers: GMRES
converges in a number of iterations that does not grow with ``N``.

Every solve of the bordered shift-invert system is still refined against the residual
of the whole system by its caller, so the GMRES tolerance sets the cost of a solve, not
the accuracy of the result. The sign of ``det T`` is not available; the spectrum
solvers never ask for it (:meth:`IterativeCapacitanceCore.det_sign` raises).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from qsa.spectra.capacitance import CapacitanceCore

__all__ = ["IterativeCapacitanceCore"]


class IterativeCapacitanceCore(CapacitanceCore):
    """:class:`~qsa.spectra.capacitance.CapacitanceCore` with ``T`` solved by GMRES.

    Parameters
    ----------
    local : list of list
        The ``3 x 3`` sparse blocks of the local system ``A``.
    K : ReducedHessian or OperatorPairHessian
        The implicit-state part ``Lf K Rf`` (weighted).
    dgk : sparse matrix, shape (N, N)
    N : int
    rtol : float
        GMRES relative residual tolerance of each column.
    maxiter : int
        Iterations (one Krylov cycle of at most ``maxiter`` vectors; no restarts).

    Attributes
    ----------
    iterations : list of int
        GMRES iterations of every column solved so far.
    failures : int
        Columns whose GMRES stopped above ``rtol`` (their solution is returned
        as found; the caller's refinement against the whole system measures it).
    nnz : int
        Stored entries of the local factors.
    """

    def __init__(self, local, K, dgk, N, rtol=1e-12, maxiter=400):
        if not 0.0 < rtol < 1.0:
            raise ValueError(f"rtol must be in (0, 1), got {rtol}")
        if int(maxiter) < 1:
            raise ValueError(f"maxiter must be a positive integer, got {maxiter}")
        self._setup(local, K, dgk, N)
        self.rtol, self.maxiter = float(rtol), int(maxiter)
        self.iterations: list = []
        self.failures = 0
        self.nnz = int(self._A.nnz)
        self.rcond = np.nan

    def capacitance_matvec(self, phi):
        """``T phi``, ``phi`` of shape (N,) or (N, k)."""
        phi = np.asarray(phi, dtype=float)
        KQ = self.K.core_matvec(self._Q @ phi)
        return phi + self._A.solve(np.asfortranarray(self._E @ KQ))[:self.N]

    def _solve_T(self, rhs):
        rhs = np.asarray(rhs, dtype=float)
        T = spla.LinearOperator((self.N, self.N), matvec=self.capacitance_matvec, dtype=float)
        cols = rhs.reshape(self.N, -1)
        out = np.empty_like(cols)
        for j in range(cols.shape[1]):
            b = cols[:, j]
            if not np.any(b):
                out[:, j] = 0.0
                continue
            count = [0]

            def step(_, count=count):
                count[0] += 1

            x, info = spla.gmres(T, b, rtol=self.rtol, atol=0.0, restart=self.maxiter,
                                 maxiter=1, callback=step, callback_type="pr_norm")
            self.iterations.append(count[0])
            self.failures += int(info != 0)
            out[:, j] = x
        return out.reshape(rhs.shape)

    def det_sign(self) -> int:
        """Not available without the factors of ``T``.

        Raises
        ------
        NotImplementedError
        """
        raise NotImplementedError("the iterative capacitance has no determinant; use "
                                  "CapacitanceCore (the LU of T) for the determinant's sign")
