"""The normal-velocity linearization ``J`` kept as its factors, and solves with ``J - sigma``.

``J = -[M-dagger L_Lambda M(., 0)]_1`` is a differential operator of order 6 for the
faceting energy (4 for Canham-Helfrich): formed as a matrix, its entries are sums of
terms of size ``|J| ~ h^-6`` that cancel, so every eigenvalue computed from the formed
matrix carries an absolute round-off error of order ``eps |J|`` -- at ``N = 10^4`` on
finite differences that is larger than the slow eigenvalues themselves. The factors
are of order 2 each. With ``W = diag(dsigma)``, ``W2 = diag(dsigma, dsigma)``,
``H = W2 L_Lambda`` (symmetric) and the normal columns of ``M``,
``M1 = [G; diag(g kappa)]`` (``G = -Delta_s - kappa^2``), ::

    W J = -M1^T H M1,

so ``J`` is self-adjoint in ``<f, h> = int f h dsigma`` and ``(W J) phi = lambda W phi``
is a symmetric-definite pencil. Its eigenvalues nearest a shift ``sigma`` are the
largest of ``(W J - sigma W)^{-1} W``, and that inverse is applied without forming
``J``: with ``psi = G phi`` and ``chi = H_kk psi + H_kg (g kappa phi)`` the system
``(W J - sigma W) phi = b`` is the sparse (finite differences) or dense (Fourier)
``3N x 3N`` system ::

    [ -sigma W - gk H_gg gk    -gk H_gk    -G^T ] [phi]   [b]
    [ -H_kg gk                 -H_kk        I   ] [psi] = [0]        (gk = diag(g kappa))
    [ -G                        I           0   ] [chi]   [0]

whose blocks are the order-2 factors themselves. When ``H`` holds the Hessian of a
two-point energy on a finite-difference grid (:class:`~qsa.linalg.ReducedHessian`: the
Hessian through an implicit state, the node positions), that state and its adjoint are
further sparse unknowns of the same system. Two kinds of dense columns are bordered on
by block elimination: the low-rank part ``U V^T`` of ``H`` (the perimeter penalty's
rank-one term on finite-difference grids), and the deflation of the rigid motions --
the solution is kept ``<.,.>``-orthogonal to the normal components ``R`` of the rigid
motions (exactly in ``ker J`` in the continuum, and an invariant subspace at an
equilibrium), so the pencil is solved on their orthogonal complement; the rigid Ritz
values are computed separately, by Rayleigh-Ritz of the inverse on ``span R``
(:meth:`ShiftInvert.kernel_ritz`). Every solve is refined once with the residual of
the whole bordered system; when a probe shows that working-precision refinement stalls
(the shifted core nearly singular), the residual is accumulated in extended precision
(``np.longdouble``), which brings the forward error down to the rounding of the solution
itself. The forward-error estimate is one more correction, not applied, with the
residual in extended precision; where the probe shows that the working-precision
rounding of the wide two-point blocks (most of the entries, and of the cost) is at most
half the error being estimated, those blocks are taken in working precision and twice
their measured noise is added (:mod:`qsa.spectra.refinement`).

Round-off then enters through the factors: the error of a slow eigenvalue scales with
the order-2 blocks applied to its (smooth) eigenvector, not with ``|J|``.

Error estimates (absolute, per eigenvalue ``lambda`` with ``<.,.>``-unit eigenvector
``phi``, ``nu = 1/(lambda - sigma)``):

* the residual of the inverse problem, ``r = |K phi - nu phi|``, ``K = (W J - sigma W)^{-1} W``
  (self-adjoint in ``<.,.>``: an eigenvalue of ``K`` lies within ``r`` of ``nu``),
  plus the solve's own forward error ``d`` (the size of the iterative-refinement
  correction): ``|lambda - lambda_true| <= (r + d) / (|nu| (|nu| - r - d))``;
* the rounding of the factors' entries (relative ``eps`` each): the first-order
  change of ``lambda = -(M1 phi)^T H (M1 phi)`` is bounded by
  ``eps (sum_ij |H_ij psi_i psi_j| + 2 sum_ij |chi_i M1_ij phi_j|)`` with
  ``psi = M1 phi``, ``chi = H psi`` (and the same sums over the factors of the
  implicit-state part). A worst-case sum, not a statistical one: on uniform grids
  every row holds the same stencil values, rounded the same way, so the errors add up
  coherently over the ``N`` rows. ``chi`` is taken from the solve's own unknowns;
  formed as a product it would carry the rounding noise of the computed eigenvector's
  rough modes, amplified like ``h^-6``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from qsa import geometry
from qsa.curve import Curve
from qsa.linalg import BlockSparse, Factorization, ReducedHessian, SparsePlusLowRank, factorize
from qsa.spectra import capacitance
from qsa.spectra.capacitance import CapacitanceCore, use_capacitance
from qsa.spectra.capacitance_iterative import IterativeCapacitanceCore
from qsa.spectra.coarse import CoarseSchurCore
from qsa.spectra.refinement import BorderedSystem, Probe, column_norms, probe, refined_solve

__all__ = ["FactoredNormalOperator", "ShiftInvert", "EigenErrors"]

_EPS = np.finfo(float).eps


def _split(L):
    """``(S, U, V, K)`` with ``L = S + U V^T + K``, ``K`` the implicit-state part or None."""
    n = L.shape[0]
    if isinstance(L, ReducedHessian):
        K = L._with(S=sp.csr_matrix(L.shape), U=np.zeros((n, 0)), V=np.zeros((n, 0)))
        return L.S, L.U, L.V, K
    if isinstance(L, SparsePlusLowRank):
        return L.S, L.U, L.V, None
    return L, np.zeros((n, 0)), np.zeros((n, 0)), None


@dataclass(frozen=True, eq=False)
class FactoredNormalOperator:
    """``J = -W^{-1} M1^T H M1`` held as its order-2 factors (see the module docstring).

    Attributes
    ----------
    curve : Curve
    G : matrix, shape (N, N)
        ``-Delta_s - kappa^2`` (sparse for finite differences, dense for Fourier).
    gk : ndarray, shape (N,)
        ``g kappa`` (the lower block of ``M1``).
    H : matrix, shape (2N, 2N)
        ``W2 S`` with ``S`` the sparse (or dense) part of ``L_Lambda``; symmetric.
    U, V : ndarray, shape (2N, r)
        The low-rank part of ``W2 L_Lambda`` is ``U V^T`` (``U`` already scaled by ``W2``).
    w : ndarray, shape (N,)
        ``dsigma``.
    reduced : ReducedHessian or None
        The part of ``W2 L_Lambda`` that is the Hessian through an implicit state (the
        two-point energies on finite-difference grids, :class:`~qsa.linalg.ReducedHessian`):
        ``Lf K Rf`` with sparse factors; its implicit state becomes extra sparse unknowns
        of the shift-invert system.
    approximated : ReducedHessian or None
        ``W2`` times a compressed part of ``L_Lambda`` that a dense term made dense (e.g.
        a compressed two-point energy with an area constraint): kept for its error
        estimate (:meth:`~qsa.linalg.ReducedHessian.approximation_error`) alone.

    Parameters
    ----------
    Built by :meth:`from_lagrangian`.

    Examples
    --------
    The factored product equals the formed ``J`` where the latter is accurate:

    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> from qsa.spectra import lagrange_hessian, normal_operator
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> LH = lagrange_hessian(eq.energy, eq.curve).matrix
    >>> op = FactoredNormalOperator.from_lagrangian(eq.curve, LH)
    >>> phi = np.cos(2 * np.pi * 2 * eq.curve.grid.s)
    >>> bool(np.allclose(op.matvec(phi), normal_operator(eq.energy, eq.curve) @ phi))
    True
    """

    curve: Curve
    G: Any  # sparse or dense
    gk: np.ndarray
    H: Any  # sparse or dense
    U: np.ndarray
    V: np.ndarray
    w: np.ndarray
    reduced: Any = None
    approximated: Any = None

    @classmethod
    def from_lagrangian(cls, curve: Curve, L, approximated=None) -> FactoredNormalOperator:
        """The factors of ``J`` for the Lagrangian Hessian ``L`` (dsigma-self-adjoint).

        Parameters
        ----------
        curve : Curve
        L : matrix, shape (2N, 2N)
            ``L_Lambda``: dense, sparse, :class:`~qsa.linalg.SparsePlusLowRank` or
            :class:`~qsa.linalg.ReducedHessian`.
        approximated : matrix, optional
            The part of ``L`` that may be compressed (the energy's Hessian,
            :attr:`LagrangeHessian.energy_hessian <qsa.spectra.LagrangeHessian>`): when
            ``L`` is not a :class:`~qsa.linalg.ReducedHessian` but this one is and carries
            approximations, their error estimates still join the eigenvalues' errors.

        Returns
        -------
        FactoredNormalOperator
        """
        w = curve.dsigma
        w2 = np.concatenate([w, w])
        S, U, V, K = _split(L)
        if curve.grid.sparse:
            H = (sp.diags(w2) @ sp.csr_matrix(S)).tocsr()
        else:
            H = w2[:, None] * np.asarray(S.toarray() if sp.issparse(S) else S)
            if K is not None:  # dense grids: no implicit state needed
                H = H + w2[:, None] * K.toarray()
                K = None
        if K is not None:
            K = sp.diags(w2) @ K
        kept = None
        if (K is None and isinstance(approximated, ReducedHessian)
                and approximated.approximations):
            kept = sp.diags(w2) @ approximated
        return cls(curve, geometry.helmholtz(curve), curve.g * curve.kappa, H,
                   w2[:, None] * U, V, w, K, kept)

    @property
    def N(self) -> int:
        """Number of nodes."""
        return self.curve.N

    @property
    def rank(self) -> int:
        """Number of columns of the low-rank part."""
        return self.U.shape[1]

    # -------------------------------------------------------------- products
    def normal_map(self, phi):
        """``M1 phi = (G phi, g kappa phi)``, shape (2N,) or (2N, k)."""
        phi = np.asarray(phi, dtype=float)
        gk = self.gk if phi.ndim == 1 else self.gk[:, None]
        return np.concatenate([self.G @ phi, gk * phi], axis=0)

    def weighted_hessian(self, psi):
        """``H psi + U (V^T psi)`` (the full ``W2 L_Lambda`` applied)."""
        out = self.H @ psi
        if self.reduced is not None:
            out = out + self.reduced @ psi
        if self.rank:
            out = out + self.U @ (self.V.T @ psi)
        return out

    def matvec(self, phi):
        """``J phi`` through the factors, shape like ``phi`` ((N,) or (N, k)).

        The product of three order-2 operators: its round-off is ``eps`` times the
        size of the intermediate results, so for rough vectors it is as large as for
        the formed matrix; use the solves for eigenvalues.
        """
        psi = self.normal_map(phi)
        chi = self.weighted_hessian(psi)
        N = self.N
        gk = self.gk if np.ndim(phi) == 1 else self.gk[:, None]
        w = self.w if np.ndim(phi) == 1 else self.w[:, None]
        return -(self.G.T @ chi[:N] + gk * chi[N:]) / w

    def quadratic(self, X, Y=None):
        """``Y^T W J X = -(M1 Y)^T (W2 L) (M1 X)``, computed without forming ``J``.

        Parameters
        ----------
        X : ndarray, shape (N, k)
        Y : ndarray, shape (N, m), optional
            Default ``X``.

        Returns
        -------
        ndarray, shape (m, k)
        """
        X = np.asarray(X, dtype=float).reshape(self.N, -1)
        PX = self.normal_map(X)
        PY = PX if Y is None else self.normal_map(np.asarray(Y, dtype=float).reshape(self.N, -1))
        return -(PY.T @ self.weighted_hessian(PX))

    def form(self):
        """The matrix ``J`` (dense for Fourier; sparse, :class:`SparsePlusLowRank` or
        :class:`ReducedHessian` for finite differences).

        Its eigenvalues carry an absolute round-off error of order ``eps |J|``.
        """
        if self.curve.grid.sparse:
            M1 = sp.vstack([sp.csr_matrix(self.G), sp.diags(self.gk)]).tocsr()
            Winv = sp.diags(1.0 / self.w)
            core = (Winv @ -(M1.T @ (self.H @ M1))).tocsr()
            if self.reduced is not None:
                core = (Winv @ (M1.T @ (self.reduced @ M1))) * -1.0 + core
            if self.rank:
                core = core + SparsePlusLowRank(sp.csr_matrix(core.shape),
                                                -(M1.T @ self.U) / self.w[:, None], M1.T @ self.V)
            return core
        M1 = np.vstack([np.asarray(self.G), np.diag(self.gk)])
        out = -(M1.T @ (self.H @ M1 + self.U @ (self.V.T @ M1)))
        return out / self.w[:, None]

    # ---------------------------------------------------------------- solves
    def shift_invert(self, sigma=0.0, deflate=None, constrain=None) -> ShiftInvert:
        """The bordered factorization applying ``(W J - sigma W)^{-1}`` (:class:`ShiftInvert`)."""
        return ShiftInvert(self, float(sigma), deflate, constrain)

    def ritz(self, R):
        """Ritz values, vectors and errors of ``J`` on ``span R`` (rows ``<.,.>``-orthonormal).

        The Rayleigh quotients come from the factored quadratic form, so their error is
        the rounding of the factors (:meth:`rounding_error`), not ``eps |J|``.

        Parameters
        ----------
        R : ndarray, shape (m, N)

        Returns
        -------
        values : ndarray, shape (m,)
        vectors : ndarray, shape (N, m)
        errors : ndarray, shape (m,)
        """
        vals, vecs = self._rayleigh_ritz(R)
        return vals, vecs, self.rounding_error(vecs) + _EPS * np.abs(vals)

    def ritz_values(self, R):
        """The Ritz values of :meth:`ritz` alone, without their error estimates.

        Enough where they only place a shift (the rounding bound costs more passes
        over the factors than the values).

        Parameters
        ----------
        R : ndarray, shape (m, N)

        Returns
        -------
        ndarray, shape (m,)
        """
        return self._rayleigh_ritz(R)[0]

    def _rayleigh_ritz(self, R):
        R = np.asarray(R, dtype=float).reshape(-1, self.N)
        if R.shape[0] == 0:
            return np.zeros(0), np.zeros((self.N, 0))
        B = self.quadratic(R.T)
        vals, Q = np.linalg.eigh(0.5 * (B + B.T))
        return vals, R.T @ Q

    # ------------------------------------------------------ rounding estimate
    def rounding_error(self, phi, chi=None):
        """A first-order bound on the change of ``phi^T W J phi`` from rounding the factors.

        ``phi`` has unit ``<.,.>`` norm (columns of an (N, k) array are treated
        separately). See the module docstring.

        Parameters
        ----------
        phi : ndarray, shape (N,) or (N, k)
        chi : ndarray, shape (2N, k), optional
            ``(W2 L) M1 phi``. By default it is computed by products; a computed
            eigenvector carries rounding noise of relative size ``eps`` in its rough
            modes, which these products amplify like ``h^-6`` (``h^-8`` with a
            second-order energy), so solvers pass the ``chi`` of their own solve
            (:meth:`ShiftInvert.errors`), which is smooth.

        Returns
        -------
        ndarray, shape (k,)
        """
        phi = np.asarray(phi, dtype=float).reshape(self.N, -1)
        psi = self.normal_map(phi)
        chi = self.weighted_hessian(psi) if chi is None else np.asarray(chi).reshape(2 * self.N, -1)
        apsi, aphi = np.abs(psi), np.abs(phi)
        M1phi = np.concatenate([abs(self.G) @ aphi, np.abs(self.gk[:, None] * phi)], axis=0)
        total = np.sum(apsi * (abs(self.H) @ apsi), axis=0) + 2.0 * np.sum(np.abs(chi) * M1phi,
                                                                          axis=0)
        approx = 0.0
        if self.reduced is not None:
            total = total + _reduced_rounding(self.reduced, psi)
        # a compressed two-point term: its own error estimate, not a rounding
        for K in (self.reduced, self.approximated):
            if K is not None:
                approx = approx + K.approximation_error(K.left.T @ psi, K.right @ psi)
        return _EPS * total + approx


def _reduced_rounding(K, psi):
    """``sum |entry x products|`` of the reduced quadratic form ``psi^T Lf K Rf psi``.

    With ``u = Rf psi``, ``z = Z u`` and ``l = Lf^T psi`` (columns separately), the form
    is ``l^T (Luu u + Lyu^T z) + (Z^T l)^T (Lyu u + Lyy z)``; every sparse factor's
    entries carry a relative rounding of at most ``eps``, those of ``Rf`` and ``Lf``
    included (``(K l)_i Rf_ij psi_j`` and ``(K u)_i Lf_ji psi_j``).
    """
    u = K.right @ psi
    l = K.left.T @ psi
    z = -K._solve_cY(K.cU @ u)
    zl = -K._solve_cY(K.cU @ l)
    al, au, az, azl = np.abs(l), np.abs(u), np.abs(z), np.abs(zl)
    Auu, AyuT, Ayu, Ayy = K.abs_core()
    out = (np.sum(al * (Auu @ au), axis=0) + np.sum(al * (AyuT @ az), axis=0)
           + np.sum(azl * (Ayu @ au), axis=0) + np.sum(azl * (Ayy @ az), axis=0))
    apsi = np.abs(psi)
    return (out + np.sum(np.abs(K.core_matvec(l)) * (abs(K.right) @ apsi), axis=0)
            + np.sum(np.abs(K.core_matvec(u)) * (abs(K.left.T) @ apsi), axis=0))


@dataclass(frozen=True)
class EigenErrors:
    """Error estimates of computed eigenpairs (absolute, in the eigenvalue).

    Attributes
    ----------
    residual : ndarray, shape (k,)
        From the residual of the inverse problem and the solve's forward error.
    rounding : ndarray, shape (k,)
        From rounding the factors' entries (three standard deviations), plus the
        estimated error of approximated parts of the Hessian (a compressed two-point
        term, :meth:`~qsa.linalg.ReducedHessian.approximation_error`).
    total : ndarray, shape (k,)
        ``residual + rounding + eps |lambda|``.

    Parameters
    ----------
    The attributes above.
    """

    residual: np.ndarray
    rounding: np.ndarray
    total: np.ndarray


def _with_implicit_state(blocks, K, dgk, N):
    """Append the implicit state of ``Lf K Rf`` to the 3N block system.

    Unknowns ``u = Rf psi_full`` (``psi_full = (psi, g kappa phi)``), ``v = K u`` and the
    state and adjoint ``(y, mu)``: rows ``u - Rf psi_full = 0``,
    ``Luu u + Lyu^T y + cU^T mu - v = 0``, ``Lyu u + Lyy y + cY^T mu = 0``,
    ``cU u + cY y = 0``; ``Lf v`` joins ``H psi_full`` in the first two block rows.
    """
    p, q = K.Luu.shape[0], K.cY.shape[0]
    Lk, Lg = K.left[:N], K.left[N:]
    Rk, Rg = K.right[:, :N], K.right[:, N:]
    Ip = sp.identity(p, format="csr")
    out = [row + [None, None, None, None] for row in blocks]
    out[0][4] = -(dgk @ Lg)
    out[1][4] = -Lk
    out.append([-(Rg @ dgk), -Rk, None, Ip, None, None, None])
    if q == 0:  # no implicit state (factored second-order blocks): v = Luu u
        out[-1] = out[-1][:5]
        out = [row[:5] for row in out]
        out.append([None, None, None, K.Luu, -Ip])
        return out
    out.append([None, None, None, K.Luu, -Ip, K.Lyu.T, K.cU.T])
    out.append([None, None, None, K.Lyu, None, K.Lyy, K.cY.T])
    out.append([None, None, None, K.cU, None, K.cY, None])
    return out


def local_blocks(op: FactoredNormalOperator, sigma: float):
    """The ``3 x 3`` sparse blocks of the local system (module docstring), finite differences.

    Parameters
    ----------
    op : FactoredNormalOperator
    sigma : float

    Returns
    -------
    list of list
        Sparse blocks (``None`` for zero), ``N`` rows each.
    """
    N, w, gk, G, H = op.N, op.w, op.gk, op.G, op.H
    Hkk, Hkg = H[:N, :N], H[:N, N:]
    Hgk, Hgg = H[N:, :N], H[N:, N:]
    I = sp.identity(N, format="csr")
    dgk = sp.diags(gk)
    A11 = -sigma * sp.diags(w) - dgk @ Hgg @ dgk
    return [[A11, -(dgk @ Hgk), -G.T],
            [-(Hkg @ dgk), -Hkk, I],
            [-G, I, None]]


class ShiftInvert:
    """``(W J - sigma W)^{-1}`` on the ``<.,.>``-complement of the deflated span, never forming J.

    The ``3N`` system of the module docstring is factored once (sparse LU on finite
    differences, dense LU on Fourier grids); the low-rank part of ``H`` and the
    orthogonality rows -- the length / area constraints ``Rc W phi = 0`` and the
    deflation ``R W phi = 0``, with multipliers ``W Rc^T mu_c + W R^T mu`` in the first
    block row -- are bordered on by block elimination. Every solve is followed by one
    step of iterative refinement with the residual of the whole bordered system; the
    size of that correction estimates the forward error (:attr:`last_correction`).

    The constraint rows make the solve that of the constrained operator: for ``b`` in
    ``W T``, ``T = {phi : Rc W phi = 0}``, the solution ``phi`` is in ``T`` and
    ``(P J P - sigma) phi = W^{-1} b`` with ``P`` the ``<.,.>``-orthogonal projection
    onto ``T`` -- the linearization of the constrained gradient flow
    (:mod:`qsa.constraints`). They stay in :meth:`solve_free`, which drops only the
    deflation.

    Parameters
    ----------
    op : FactoredNormalOperator
    sigma : float
    deflate : ndarray, shape (m, N), optional
        Rows ``<.,.>``-orthonormal; the solution is kept orthogonal to them.
    constrain : ndarray, shape (mc, N), optional
        ``<.,.>``-orthonormal rows spanning the constraints' normal variations
        (orthogonal to ``deflate``): the problem is posed on their complement.

    Attributes
    ----------
    core_solver : str
        How the core system is solved: ``"dense"`` (LAPACK, Fourier grids),
        ``"superlu"`` (sparse LU) or ``"capacitance"`` (a two-point energy with wide
        neighbourhoods on a finite-difference grid, eliminated onto an ``N x N``
        capacitance matrix: :class:`~qsa.spectra.capacitance.CapacitanceCore`), or
        ``"gmres"`` (the same capacitance solved by deflated GMRES, never formed:
        :class:`~qsa.spectra.capacitance_iterative.IterativeCapacitanceCore`; only when
        ``qsa.spectra.capacitance.ITERATIVE`` is set, off by default), or ``"coarse"`` (a
        compressed two-point term's coarse state: the rest eliminated onto it, then
        LAPACK; :class:`~qsa.spectra.coarse.CoarseSchurCore`).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> from qsa.spectra import lagrange_hessian
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> LH = lagrange_hessian(eq.energy, eq.curve).matrix
    >>> op = FactoredNormalOperator.from_lagrangian(eq.curve, LH)
    >>> si = op.shift_invert(sigma=1.0)
    >>> phi = np.cos(2 * np.pi * 2 * eq.curve.grid.s)  # lambda_2 = -4.86
    >>> bool(np.allclose(si.solve(eq.curve.dsigma * phi), phi / (-4.86 - 1.0)))
    True
    """

    def __init__(self, op: FactoredNormalOperator, sigma: float, deflate=None, constrain=None):
        self.op = op
        self.sigma = sigma
        N = op.N
        R = np.zeros((0, N)) if deflate is None else np.asarray(deflate, dtype=float)
        Rc = (np.zeros((0, N)) if constrain is None
              else np.asarray(constrain, dtype=float).reshape(-1, N))
        self.R, self.Rc = R, Rc
        sparse = op.curve.grid.sparse
        core: Any  # BlockSparse (finite differences) or ndarray (Fourier)
        w, gk, G, H = op.w, op.gk, op.G, op.H
        Hkk, Hkg = H[:N, :N], H[:N, N:]
        Hgk, Hgg = H[N:, :N], H[N:, N:]
        if sparse:
            dgk = sp.diags(gk)
            blocks = local_blocks(op, sigma)
            local = blocks
            if op.reduced is not None:
                blocks = _with_implicit_state(blocks, op.reduced, dgk, N)
            core = BlockSparse(blocks)  # assembled only for a sparse LU
        else:
            I = np.eye(N)
            A11 = -sigma * np.diag(w) - gk[:, None] * Hgg * gk[None, :]
            core = np.block([[A11, -gk[:, None] * Hgk, -np.asarray(G).T],
                             [-Hkg * gk[None, :], -Hkk, I],
                             [-np.asarray(G), I, np.zeros((N, N))]])
        self._core = core
        r = op.rank
        rows = np.vstack([Rc, R])  # constraints first: solve_free keeps them
        m = rows.shape[0]
        n = core.shape[0]
        # border columns B1 (n, r + m), rows B2 (r + m, n), corner D
        B1 = np.zeros((n, r + m))
        B2 = np.zeros((r + m, n))
        if r:
            B1[:N, :r] = -gk[:, None] * op.U[N:]
            B1[N:2 * N, :r] = -op.U[:N]
            B2[:r, :N] = -(op.V[N:] * gk[:, None]).T
            B2[:r, N:2 * N] = -op.V[:N].T
        if m:
            WR = (rows * w[None, :]).T
            B1[:N, r:] = WR
            B2[r:, :N] = WR.T
        D = np.zeros((r + m, r + m))
        D[:r, :r] = np.eye(r)
        self._B1, self._B2, self._D = B1, B2, D
        self._lu = None
        self._capacitance = None
        self.core_solver = "dense" if not sparse else "superlu"
        if sparse and op.reduced is not None and use_capacitance(op.reduced, N):
            try:
                cap: CapacitanceCore | IterativeCapacitanceCore
                if capacitance.ITERATIVE:
                    k = min(capacitance.DEFLATE, N // 4)
                    cap = IterativeCapacitanceCore(local, op.reduced, dgk, N, deflate=k,
                                                   arnoldi=min(capacitance.ARNOLDI, N // 2))
                else:
                    cap = CapacitanceCore(local, op.reduced, dgk, N)
            except np.linalg.LinAlgError:
                pass  # a singular local block or capacitance: the whole system by SuperLU
            else:
                self._lu = Factorization.from_solver(cap, B1, B2, D)
                self._capacitance = cap
                self.core_solver = "gmres" if capacitance.ITERATIVE else "capacitance"
        reduced = op.reduced
        if (self._lu is None and sparse and reduced is not None
                and reduced.coarse_index.size):
            try:
                coarse = CoarseSchurCore(core.tocsr(), N, reduced.Luu.shape[0],
                                         reduced.cY.shape[0], reduced.coarse_index)
            except (ValueError, np.linalg.LinAlgError):
                pass  # not of that structure, or a singular block: SuperLU takes it whole
            else:
                self._lu = Factorization.from_solver(coarse, B1, B2, D)
                self.core_solver = "coarse"
        if self._lu is None:
            self._lu = factorize(core.tocsc() if sparse else core, B1, B2, D)
        self._free = None
        self._system = BorderedSystem(core, B1, B2, D)
        self._probes: dict = {}
        self.last_correction = np.zeros(0)

    @property
    def shape(self):
        """``(N, N)``: the operator acts on nodal vectors."""
        return (self.op.N, self.op.N)

    def _probe(self, lu, p) -> Probe:
        """The refinement probe of these factors (:func:`~qsa.spectra.refinement.probe`)."""
        key = (id(lu), p)
        if key not in self._probes:
            self._probes[key] = probe(lu.solve, self._system, p, self.op.w)
        return self._probes[key]

    def _refined(self, lu, p, b, refine, estimate):
        N = self.op.N
        b = np.asarray(b, dtype=float)
        rhs = np.zeros((self._system.n + p,) + b.shape[1:])
        rhs[:N] = b
        if refine == 0 and not estimate and self._capacitance is not None:
            # phi alone is wanted, and the border reads only the phi and psi rows
            self._capacitance.phi_only = True
            try:
                return lu.solve(rhs)[:N]
            finally:
                self._capacitance.phi_only = False
        x, dx, noise = refined_solve(lu.solve, self._system, p, rhs, refine,
                                     self._probe(lu, p), self.op.w, estimate)
        if estimate:
            self._last_dx, self._last_noise = dx, noise
            self.last_correction = (column_norms(dx, self.op.w)
                                    + noise * column_norms(x, self.op.w))
        self._last_core = x[: self._system.n]
        return x[:N]

    def _solution_chi(self):
        """``chi = (W2 L) psi_full`` of the last solve, from its own unknowns.

        The ``kappa`` rows are an unknown of the bordered system; the ``g`` rows follow
        from the solved ``psi`` (and the implicit state's ``v``) by order-2 products, so
        neither carries the amplified rounding noise of a product ``H M1 phi``.
        """
        op = self.op
        N = op.N
        x = self._last_core.reshape(self._last_core.shape[0], -1)
        phi, psi, chik = x[:N], x[N:2 * N], x[2 * N:3 * N]
        psi_full = np.concatenate([psi, op.gk[:, None] * phi], axis=0)
        chig = op.H[N:] @ psi_full
        if op.reduced is not None:
            p = op.reduced.Luu.shape[0]
            chig = chig + op.reduced.left[N:] @ x[3 * N + p:3 * N + 2 * p]
        if op.rank:
            chig = chig + op.U[N:] @ (op.V.T @ psi_full)
        return np.concatenate([chik, chig], axis=0)

    def unrefined_error(self) -> float:
        """Relative forward error of an unrefined :meth:`solve`, as measured by the probe
        (:attr:`~qsa.spectra.refinement.Probe.unrefined`)."""
        return self._probe(self._lu, self._B1.shape[1]).unrefined

    def solve(self, b, refine=1, estimate=False):
        """``phi`` with ``(W J - sigma W) phi + W [Rc; R]^T mu = b``, ``[Rc; R] W phi = 0``.

        ``b`` has shape (N,) or (N, k) (columns solved together). ``refine`` steps of
        iterative refinement follow the block-elimination solve (the residual of the
        whole bordered system, in working precision; one step makes block elimination
        accurate even when the core is nearly singular). With ``estimate=True`` one
        further correction is computed but not applied; its ``<.,.>`` norm (per column),
        an estimate of the forward error of the returned ``phi``, is stored in
        :attr:`last_correction`.
        """
        return self._refined(self._lu, self._B1.shape[1], b, refine, estimate)

    def solve_free(self, b, refine=1, estimate=False):
        """As :meth:`solve`, with the same factors but without the deflation (constraints kept)."""
        r = self.op.rank + self.Rc.shape[0]
        if self._free is None:
            self._free = self._lu.with_border(self._B1[:, :r], self._B2[:r], self._D[:r, :r])
        return self._refined(self._free, r, b, refine, estimate)

    def kernel_ritz(self, R):
        """Ritz values of ``J`` on ``span R`` from the inverse, with error estimates.

        Rayleigh-Ritz for ``K = (W J - sigma W)^{-1} W`` (without the deflation; with the
        constraints, ``R`` in their complement) on the span of the ``<.,.>``-orthonormal
        rows ``R`` (:meth:`ritz_pairs`): ``K`` smooths, so the rounding noise
        of the rigid fields (computed from the node positions) does not enter, as it
        does in the direct quadratic form (:meth:`FactoredNormalOperator.ritz`), whose
        error grows like ``eps^2 |J|``.

        Parameters
        ----------
        R : ndarray, shape (m, N)

        Returns
        -------
        values : ndarray, shape (m,)
        vectors : ndarray, shape (N, m)
        errors : ndarray, shape (m,)
        """
        if R.shape[0] == 0:
            return np.zeros(0), np.zeros((self.op.N, 0)), np.zeros(0)
        vals, vecs, err = self.ritz_pairs(R.T, free=True)
        return vals, vecs, err.total

    def ritz_pairs(self, X, free=False):
        """Rayleigh-Ritz of ``K = (W J - sigma W)^{-1} W`` on ``span X``, with error estimates.

        One refined solve of the columns with its forward-error estimate: the Ritz
        vectors ``X Q`` (``Q`` the orthogonal eigenvectors of ``X^T W K X``) have the
        products ``(K X) Q``, the corrections and the solution's ``chi`` of the same
        combinations, so their errors (:meth:`errors`) need no second solve.

        Parameters
        ----------
        X : ndarray, shape (N, k)
            ``<.,.>``-orthonormal columns.
        free : bool
            Solve without the deflation (:meth:`solve_free`).

        Returns
        -------
        values : ndarray, shape (j,)
            ``sigma + 1 / nu`` for the Ritz values ``nu != 0`` of ``K``.
        vectors : ndarray, shape (N, j)
            ``<.,.>``-normalised.
        errors : EigenErrors
        """
        w = self.op.w
        KX = (self.solve_free if free else self.solve)(w[:, None] * X, estimate=True)
        A = X.T @ (w[:, None] * KX)
        nu, Q = np.linalg.eigh(0.5 * (A + A.T))
        keep = nu != 0
        nu, Q = nu[keep], Q[:, keep]
        vecs = X @ Q
        scale = 1.0 / column_norms(vecs, w)
        Q = Q * scale[None, :]
        vecs = vecs * scale[None, :]
        correction = (column_norms(self._last_dx @ Q, w)
                      + self._last_noise * column_norms(self._last_core[:self.op.N] @ Q, w))
        chi = self._solution_chi() @ Q
        vals = self.sigma + 1.0 / nu
        return vals, vecs, self._errors(vals, vecs, KX @ Q, correction, chi)

    def operator(self):
        """``K = (W J - sigma W)^{-1} W`` as a ``scipy.sparse.linalg.LinearOperator``."""
        w = self.op.w
        return spla.LinearOperator(self.shape, matvec=lambda x: self.solve(w * x), dtype=float)

    def errors(self, eigenvalues, vectors) -> EigenErrors:
        """Error estimates of eigenpairs of the pencil (module docstring).

        Parameters
        ----------
        eigenvalues : ndarray, shape (k,)
        vectors : ndarray, shape (N, k)
            ``<.,.>``-normalised.

        Returns
        -------
        EigenErrors
        """
        lam = np.asarray(eigenvalues, dtype=float)
        KV = self.solve(self.op.w[:, None] * vectors, estimate=True)
        return self._errors(lam, vectors, KV, self.last_correction, self._solution_chi())

    def _errors(self, lam, vectors, KV, correction, chi):
        """:class:`EigenErrors` from ``K V`` (a solve with forward error ``correction``)
        and the solve's ``chi`` for ``K V``."""
        w = self.op.w
        nu = 1.0 / (lam - self.sigma)
        r = KV - nu[None, :] * vectors
        rn = np.sqrt(np.sum(w[:, None] * r * r, axis=0)) + correction
        den = np.abs(nu) * (np.abs(nu) - rn)
        res = np.where(den > 0, rn / np.where(den > 0, den, 1.0), np.inf)
        rnd = self.op.rounding_error(vectors, chi / nu[None, :])
        return EigenErrors(res, rnd, res + rnd + _EPS * np.abs(lam))
