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
import scipy.linalg as sla
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
        Krylov vectors of one GMRES cycle; at most three cycles (a restart continues
        from the last iterate when the true residual is still above ``rtol``).
    deflate : int
        Ritz vectors of ``T`` deflated (0: none). An Arnoldi run of ``arnoldi`` steps
        from a random vector, done once here, gives the Ritz pairs of ``T`` farthest
        from 1; their real span ``U`` (orthonormal, with ``T_U = U^T T U`` from the
        Arnoldi relation) makes the right preconditioner
        ``M^{-1} = I + U (T_U^{-1} - I) U^T``, which maps an exact invariant subspace's
        eigenvalues to 1. It changes the iterations, not the solution (GMRES runs to
        ``rtol`` on the true residual either way).
    arnoldi : int, optional
        Arnoldi steps for the deflation (default ``2 deflate``).

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

    def __init__(self, local, K, dgk, N, rtol=1e-12, maxiter=400, deflate=0, arnoldi=None):
        if not 0.0 < rtol < 1.0:
            raise ValueError(f"rtol must be in (0, 1), got {rtol}")
        if int(maxiter) < 1:
            raise ValueError(f"maxiter must be a positive integer, got {maxiter}")
        arnoldi = 2 * int(deflate) if arnoldi is None else int(arnoldi)
        if int(deflate) < 0 or (deflate and not int(deflate) < arnoldi <= N):
            raise ValueError(f"need 0 <= deflate < arnoldi <= N, got deflate={deflate}, "
                             f"arnoldi={arnoldi}, N={N}")
        self._setup(local, K, dgk, N)
        self.rtol, self.maxiter = float(rtol), int(maxiter)
        self.iterations: list = []
        self.failures = 0
        self.nnz = int(self._A.nnz)
        self.rcond = np.nan
        self._U = np.zeros((N, 0))
        self._TU = None
        if deflate:
            self._deflation(int(deflate), arnoldi)

    def _deflation(self, k, m, seed=0):
        """``U`` and the LU of ``T_U`` from ``m`` Arnoldi steps (class docstring)."""
        N = self.N
        V = np.zeros((N, m + 1))
        Hb = np.zeros((m + 1, m))
        v = np.random.default_rng(seed).standard_normal(N)
        V[:, 0] = v / np.linalg.norm(v)
        for j in range(m):
            w = self.capacitance_matvec(V[:, j])
            h = V[:, :j + 1].T @ w
            w -= V[:, :j + 1] @ h
            h2 = V[:, :j + 1].T @ w  # twice is enough
            w -= V[:, :j + 1] @ h2
            Hb[:j + 1, j] = h + h2
            Hb[j + 1, j] = np.linalg.norm(w)
            if not Hb[j + 1, j] > 1e-14 * np.linalg.norm(Hb[:j + 2, j]):
                m = j + 1  # an invariant subspace: T V_m = V_m H_m
                V, Hb = V[:, :m + 1], Hb[:m + 1, :m]
                break
            V[:, j + 1] = w / Hb[j + 1, j]
        theta, Y = np.linalg.eig(Hb[:m, :m])
        far = np.argsort(-np.abs(theta - 1.0))[:min(k, m - 1)]
        Yr = np.linalg.qr(np.hstack([Y[:, far].real, Y[:, far].imag]))[0]
        # drop the directions the imaginary parts did not add (real Ritz vectors)
        s = np.linalg.svd(np.hstack([Y[:, far].real, Y[:, far].imag]), compute_uv=False)
        Yr = Yr[:, :int(np.sum(s > 1e-10 * s[0]))]
        self._U = V[:, :m] @ Yr
        self._TU = sla.lu_factor(Yr.T @ Hb[:m] @ Yr)  # U^T T U = Y^T H_m Y

    def _precondition(self, y):
        """``M^{-1} y`` (``y`` itself without deflation)."""
        if self._TU is None:
            return y
        c = self._U.T @ y
        return y + self._U @ (sla.lu_solve(self._TU, c, check_finite=False) - c)

    @property
    def deflated(self) -> int:
        """Columns of the deflated basis ``U``."""
        return int(self._U.shape[1])

    def capacitance_matvec(self, phi):
        """``T phi``, ``phi`` of shape (N,) or (N, k)."""
        phi = np.asarray(phi, dtype=float)
        KQ = self.K.core_matvec(self._Q @ phi)
        return phi + self._A.solve(np.asfortranarray(self._E @ KQ))[:self.N]

    def _solve_T(self, rhs):
        rhs = np.asarray(rhs, dtype=float)
        TM = spla.LinearOperator((self.N, self.N), dtype=float,
                                 matvec=lambda y: self.capacitance_matvec(self._precondition(y)))
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

            y, info = spla.gmres(TM, b, rtol=self.rtol, atol=0.0, restart=self.maxiter,
                                 maxiter=3, callback=step, callback_type="pr_norm")
            self.iterations.append(count[0])
            self.failures += int(info != 0)
            out[:, j] = self._precondition(y)
        return out.reshape(rhs.shape)

    def det_sign(self) -> int:
        """Not available without the factors of ``T``.

        Raises
        ------
        NotImplementedError
        """
        raise NotImplementedError("the iterative capacitance has no determinant; use "
                                  "CapacitanceCore (the LU of T) for the determinant's sign")
