"""Solves with the shift-invert core of a two-point energy through an ``N x N`` capacitance.

On a finite-difference grid the shift-invert system of :class:`~qsa.spectra.factored.ShiftInvert`
for an energy with a two-point term has the unknowns ``z = (phi, psi, chi)`` of the local
``3N`` system and the implicit state of the two-point Hessian ``Lf K Rf``
(:class:`~qsa.linalg.ReducedHessian`): ``u`` (``p``), ``v = K u`` (``p``), the state ``y``
and its adjoint ``mu`` (``q`` each). Its rows are ::

    A z + E v = b_z                        (A the local 3N block, E = [-gk Lg; -Lk; 0])
    u - F z = b3                           (F z = Rg gk phi + Rk psi)
    Luu u - v + Lyu^T y + cU^T mu = b4
    Lyu u + Lyy y + cY^T mu = b5
    cU u + cY y = b6

When the kernel's neighbourhoods hold many nodes, ``Lyy`` and ``Lyu`` are wide: a sparse
LU of the whole system fills in like a dense one of size ``~3N`` and each of its solves
reads the whole fill. Eliminated in the order below, the only dense matrix to factor is
``N x N``. The last four rows give ``v = K u + v_b`` (``K`` applied by two triangular
solves with ``cY``); the third row of ``A`` makes ``psi = b_psi + G phi`` for every
solution, so ``F z = Q phi + Rk b_psi`` with the sparse ``Q = Rg gk + Rk G``; then
(Woodbury) ::

    (I + [A^{-1} E K Q]_phi) phi = [A^{-1} (b_z - E V(b3 + Rk b_psi, b4, b5, b6))]_phi,

with ``K Q`` from :meth:`~qsa.linalg.ReducedHessian.core_matmat` (``O(q (q + p))``
work) and ``N`` sparse solves with ``A``. The capacitance ``T = I + [A^{-1} E K Q]_phi``
is factored by LAPACK; one solve is two local sparse solves, two
applications of the implicit state (``O(nnz)``) and ``O(N^2)`` with the factors of ``T``.
The elimination is exact in exact arithmetic; :class:`ShiftInvert` refines every solve
against the residual of the whole sparse system, so its error estimates do not depend on
which factorization is used. ``det`` of the system is ``(-1)^(p + q) det A det T``.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from qsa.linalg.lu import _lapack_sign, factorize

__all__ = ["CapacitanceCore", "use_capacitance"]

# the capacitance route is taken when the rows of Lyy hold at least this many entries on
# average (below it a sparse LU fills in little: measured on CHA states, SuperLU is the
# faster at 40-80 entries per row, 1.5-2.5 times slower at 150-300, six times at ~1200)
WIDE_ROW = 120
# and at least this many nodes (below it SuperLU is fast whatever the fill)
MIN_NODES = 400
# a capacitance whose rcond is not above this is singular (SuperLU takes the system)
MIN_RCOND = 0.0
# solve T by deflated GMRES (qsa.spectra.capacitance_iterative) instead of its LU: off;
# nothing of size N^2 is formed, but each solve costs tens of implicit-state products
ITERATIVE = False
# Ritz vectors of T deflated by the GMRES route, and Arnoldi steps to find them
DEFLATE, ARNOLDI = 200, 300


def use_capacitance(K, N) -> bool:
    """Whether the implicit state's two-point blocks are wide enough for :class:`CapacitanceCore`.

    Parameters
    ----------
    K : ReducedHessian
        The implicit-state part of the (weighted) Lagrangian Hessian.
    N : int
        Nodes.

    Returns
    -------
    bool
        True when ``Lyy`` averages at least ``WIDE_ROW`` entries per row, ``N`` is at
        least ``MIN_NODES`` and more than ``N`` of its rows are wide, not counting the
        coarse states of compressed terms (``K.coarse_states``).
    """
    q = K.cY.shape[0]
    if not (q > 0 and N >= MIN_NODES and K.Lyy.nnz >= WIDE_ROW * q):
        return False
    # the wide rows confined to a block smaller than N, or to the coarse state of a
    # compressed two-point term (qsa.energies.adhesion_interp; dense, but the capacitance
    # would multiply it N times): the sparse LU factors that block as a dense one
    wide = int(np.count_nonzero(np.diff(K.Lyy.indptr) > WIDE_ROW))
    return wide - int(getattr(K, "coarse_states", 0)) > N


class CapacitanceCore:
    """Solutions with the shift-invert core of a two-point energy (module docstring).

    Parameters
    ----------
    local : list of list
        The ``3 x 3`` sparse blocks of the local system ``A`` (``N`` rows each).
    K : ReducedHessian
        The implicit-state part ``Lf K Rf`` (weighted).
    dgk : sparse matrix, shape (N, N)
        ``diag(g kappa)``.
    N : int
    block : int
        Columns densified at a time while forming ``K Q`` and the capacitance.

    Attributes
    ----------
    shape : tuple of int
        The core's shape, ``(3N + 2p + 2q,) * 2``.
    nnz : int
        Stored entries of the factors (local LU and capacitance).
    rcond : float
        LAPACK's estimate of the reciprocal 1-norm condition number of ``T``.
    phi_only : bool
        While True, :meth:`solve` returns only ``phi`` and ``psi`` (the rest zero),
        skipping the second pass over the implicit state: enough for an unrefined
        solve of the bordered system, whose border reads only those rows.

    Raises
    ------
    numpy.linalg.LinAlgError
        The local block or the capacitance is singular to working precision.
    """

    def __init__(self, local, K, dgk, N, block=2048):
        self._setup(local, K, dgk, N)
        KQ = K.core_matmat(self._Q, block=block)                  # (p, N)
        T = np.empty((N, N))                                      # [A^{-1} E K Q]_phi
        for start in range(0, N, block):
            stop = min(N, start + block)
            EKQ = np.asfortranarray(self._E @ KQ[:, start:stop])  # SuperLU solves columns
            T[:, start:stop] = self._A.solve(EKQ)[:N]
        del KQ
        T[np.diag_indices(N)] += 1.0
        if not np.all(np.isfinite(T)):
            raise np.linalg.LinAlgError("the capacitance has non-finite entries")
        anorm = np.abs(T).sum(axis=0).max()
        lu, piv = sla.lu_factor(T, check_finite=False)
        self._T = (lu, piv)
        rcond, info = sla.lapack.dgecon(lu, anorm, norm="1")
        self.rcond = float(rcond)
        if info != 0 or not self.rcond > MIN_RCOND:
            raise np.linalg.LinAlgError(f"ill-conditioned capacitance (rcond {self.rcond:.2e})")
        self.nnz = int(self._A.nnz + N * N)

    def _setup(self, local, K, dgk, N):
        """The local factors and the sparse maps ``E``, ``Q``, ``G`` (module docstring)."""
        self.N, self.K = N, K
        p, q = K.Luu.shape[0], K.cY.shape[0]
        self.p, self.q = p, q
        self.shape = (3 * N + 2 * p + 2 * q,) * 2
        self._A = factorize(sp.bmat(local, format="csc"))
        Lk, Lg = K.left[:N], K.left[N:]
        Rk, Rg = K.right[:, :N], K.right[:, N:]
        G = sp.csr_matrix(local[2][0]) * -1.0  # the third block row is [-G, I, 0]
        self._G = G
        self.phi_only = False
        self._Rk = sp.csr_matrix(Rk)
        self._E = sp.vstack([-(dgk @ Lg), -Lk, sp.csr_matrix((N, p))], format="csr")
        self._Q = sp.csr_matrix(Rg @ dgk + Rk @ G)

    def solve(self, b):
        """``x`` with ``core x = b``; ``b`` of shape (n,) or (n, k)."""
        b = np.asarray(b, dtype=float)
        N, p, q = self.N, self.p, self.q
        cuts = np.cumsum([3 * N, p, p, q])
        bz, b3, b4, b5, b6 = np.split(b, cuts, axis=0)
        u0 = b3 + self._Rk @ bz[2 * N:]  # psi = b_psi + G phi, b_psi in the third rows
        if np.any(u0) or np.any(b4) or np.any(b5) or np.any(b6):
            z0 = self._A.solve(bz - self._E @ self.K.implicit_state(u0, b4, b5, b6)[0])
        else:  # v0 = 0 (a right-hand side in the phi rows only)
            z0 = self._A.solve(bz)
        phi = self._solve_T(z0[:N])
        if self.phi_only:  # phi and psi = b_psi + G phi exact, the other unknowns left 0
            out = np.zeros_like(b)
            out[:N] = phi
            out[N:2 * N] = bz[2 * N:] + self._G @ phi
            return out
        u = u0 + self._Q @ phi
        v, y, mu = self.K.implicit_state(u, b4, b5, b6)
        z = self._A.solve(bz - self._E @ v)
        return np.concatenate([z, u, v, y, mu], axis=0)

    def _solve_T(self, rhs):
        """``T^{-1} rhs`` by the LU factors of ``T``."""
        return sla.lu_solve(self._T, rhs, check_finite=False)

    def det_sign(self) -> int:
        """Sign of the determinant of the core, ``(-1)^(p + q) sign(det A) sign(det T)``."""
        return self._A.det_sign() * _lapack_sign(*self._T) * (-1) ** (self.p + self.q)
