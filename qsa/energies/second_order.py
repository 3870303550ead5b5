"""Second-order local energies ``E = int F(Delta_s kappa, nabla_s kappa, kappa) dsigma`` (e:LIE).

Discretization
--------------
With the grid's edge difference ``E`` (nodes -> edges), edge average ``A`` (for
finite differences the midpoints; for Fourier the edges are the nodes and
``A = I``) and quadrature weights ``w``, ::

    g_e = A g,    p = (E kappa) / g_e     (edges: nabla_s kappa, as in local.py),
    q = -(E^T p) / g                      (nodes: Delta_s kappa),

so ``q`` is :func:`qsa.geometry.laplace_s` applied to ``kappa`` (the compact,
dsigma-self-adjoint Laplace-Beltrami operator). A density ``F(q, p, k)`` is
evaluated at one set of points ``(gamma, Q, P, K) = (L_g g, L_Q q, L_P p, L_K kappa)``:

* ``placement="node"`` (default): ``(g, q, A^T p, kappa)`` — ``A^T p`` is the
  mean of the two edge gradients next to a node. ``q`` at the nodes sees the
  highest grid mode, so a density with ``F_qq > 0`` penalises it;
* ``placement="edge"``: ``(g_e, A q, p, A kappa)``; for ``F_q = 0`` this is
  exactly the discrete energy of :class:`~qsa.energies.local.FirstOrderEnergy`.

The discrete energy is ``E = sum_i w_i gamma_i F(Q_i, P_i, K_i)``.

Gradient
--------
Reverse mode through the two nonlinear maps ``p(kappa, g)`` and ``q(p, g)``.
With ``a_gamma = w F``, ``a_Q = w gamma F_q``, ``a_P = w gamma F_p``,
``a_K = w gamma F_k`` (at the evaluation points), ::

    c_q = (L_Q^T a_Q) / g,            c_p = (L_P^T a_P - E c_q) / g_e,
    dE/dkappa = L_K^T a_K + E^T c_p,
    dE/dg     = L_g^T a_gamma - q c_q - A^T (p c_p),

exactly (Euclidean gradient); the ``<f, h> = int f h dsigma`` gradient divides
both rows by ``dsigma = w g``. In the continuum (``A = I``, ``E = d/ds``) this is
e:first_var: ::

    d_kappa E = Delta_s F_q - nabla_s F_p + F_k,
    g d_g E   = F - F_q Delta_s kappa + nabla_s F_q nabla_s kappa - F_p nabla_s kappa,

and the normal velocity is ``V^n = -G d_kappa E - kappa (g d_g E)`` (e:L2grad,
e:LIE_NV with this gradient). The identity e:W-invar,
``d_kappa E nabla_s kappa = nabla_s (g d_g E)``, holds in the continuum for every
``U`` (Lemma l:Wind); discretely it holds to the order of the grid.

Hessian
-------
The first variations ``dp = J_p U1 = (E kappa1 - p A g1) / g_e`` and
``dq = J_q U1 = -(E^T dp + q g1) / g`` (the kappa block of ``J_q`` is
``laplace_s``); along straight lines ``U + delta U1`` the second variations are
``d^2 p = -2 (A g1 / g_e) dp`` and ``d^2 q = -(E^T d^2 p + 2 g1 dq) / g``. Hence
the exact Euclidean Hessian ::

    H = T^T B T - (X_p + X_p^T) - (X_q + X_q^T),
    X_p = R_e^T diag(c_p) J_p,    X_q = R^T diag(c_q) J_q,

with ``T`` the Jacobian of the evaluation points, rows
``(R_gamma, L_Q J_q, L_P J_p, R_K)`` (``R U1 = g1``, ``R_e U1 = A g1``,
``R_gamma = L_g R``, ``R_K U1 = L_K kappa1``), and ``B`` the 4 x 4 block of
diagonals ``w * d^2 (gamma F) / d(gamma, Q, P, K)^2``. ``T`` is banded on
finite-difference grids (every block is a product of 2-point stencils), so ``H``
is sparse with a bandwidth of 2 and costs O(N); on Fourier grids it is dense.
The ``<.,.>`` Hessian divides the rows by ``dsigma``; it is dsigma-self-adjoint.
In the continuum this is the second variation e:2var-2 written as an operator.

The circle
----------
On a circle of radius ``R`` (``kappa0 = 1/R``, ``q = p = 0``) ``mu0 = d_kappa E = F_k`` and
``xi0 = g d_g E = F`` (partials at ``(0, 0, kappa0)``) are constant, and
``V^n = kappa0 (kappa0 F_k - F)``: the circle is an equilibrium of ``E + Perimeter(beta,
L*)`` iff ``beta (2 pi R - L*) = kappa0 F_k - F`` (:meth:`SecondOrderEnergy.circle_tension`),
and a critical circle of ``E`` alone iff that tension is 0. Linearise ``V^n`` along a
normal displacement ``phi`` (``kappa1 = G phi``, ``g1 = g kappa0 phi``): e:W-invar gives
``delta xi = mu0 kappa1`` for zero-mean modes, so ``delta V^n = -G delta mu`` with ::

    delta mu = F_qq Delta_s^2 kappa1 + (2 F_qk - F_pp) Delta_s kappa1 + F_kk kappa1

(``F_qp`` and ``F_pk`` cancel between ``Delta_s nabla_s`` and ``nabla_s Delta_s``). With
``Delta_s cos(k theta) = -(k/R)^2 cos(k theta)`` the normal-velocity linearization ``J``
has the eigenvalues (:func:`circle_eigenvalues`) ::

    lambda_k = -((k^2 - 1)^2 / R^4) (F_qq m^2 + (F_pp - 2 F_qk) m + F_kk) - delta_k0 2 pi beta / R,
    m = k^2 / R^2,

``k = 1`` the translations (0), ``k >= 2`` double. For ``k = 0`` the same follows from
``E(R) = 2 pi R F(0, 0, 1/R) + beta/2 (2 pi R - L*)^2``: ``lambda_0 = -E''(R) / (2 pi R)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from qsa.curve import Curve
from qsa.energies.local import LocalEnergy

__all__ = ["SecondOrderDensity", "SecondOrderEnergy", "circle_eigenvalues"]

_PLACEMENTS = ("node", "edge")
_FIRST = ("F_q", "F_p", "F_k")
_SECOND = ("F_qq", "F_qp", "F_qk", "F_pp", "F_pk", "F_kk")


def _check_callables(owner, **fns):
    for name, fn in fns.items():
        if not callable(fn):
            raise ValueError(f"{owner}: {name} must be a callable {name}(q, p, k), "
                             f"got {type(fn).__name__}")


def _values(owner, label, value, like):
    """``value`` as a float array of ``like``'s shape, or a ``ValueError`` saying why not."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: {label} must be a real array, got "
                         f"{type(value).__name__}") from None
    if arr.shape != like.shape:
        try:
            arr = np.broadcast_to(arr, like.shape)
        except ValueError:
            raise ValueError(f"{owner}: {label} has shape {arr.shape}; it must return one "
                             f"value per point, shape {like.shape}") from None
    return arr


def _check_finite(owner, label, arr, points):
    bad = ~np.isfinite(arr)
    if np.any(bad):
        i = int(np.argmax(bad))
        q, p, k = (float(x[i]) for x in points)
        raise ValueError(f"{owner}: {label} is not finite at {int(bad.sum())} of {arr.size} "
                         f"points (first at q={q:.6g}, p={p:.6g}, k={k:.6g})")
    return arr


def _call(owner, fn, fname, names, points):
    """Evaluate a user callable at ``points = (Q, P, K)``; one array per name in ``names``."""
    out = fn(*points)
    like = points[2]
    if names is None:
        return _check_finite(owner, f"{fname}(q, p, k)",
                             _values(owner, f"{fname}(q, p, k)", out, like), points)
    try:
        n = len(out)
    except TypeError:
        n = None
    if n != len(names):
        got = "a scalar" if n is None else f"{n} values"
        raise ValueError(f"{owner}: {fname}(q, p, k) must return {len(names)} partial "
                         f"derivatives ({', '.join(names)}), got {got}")
    return [_check_finite(owner, f"{fname}(q, p, k)[{i}] ({nm})",
                          _values(owner, f"{fname}(q, p, k)[{i}] ({nm})", v, like), points)
            for i, (nm, v) in enumerate(zip(names, out, strict=True))]


def _radius(R):
    R = float(R)
    if not (np.isfinite(R) and R > 0):
        raise ValueError(f"R must be a positive radius, got {R}")
    return R


def _apply(L, x):
    """``L x``; ``L = None`` is the identity."""
    return x if L is None else L @ x


def _apply_T(L, x):
    """``L^T x``; ``L = None`` is the identity."""
    return x if L is None else L.T @ x


def circle_eigenvalues(R, kmax, F_qq, F_pp, F_qk, F_kk, beta=0.0) -> np.ndarray:
    """Eigenvalues ``lambda_k`` of ``J`` at an equilibrium circle (module docstring, "The circle").

    Parameters
    ----------
    R : float
        Radius, ``> 0``.
    kmax : int
        Largest wavenumber, ``>= 0``.
    F_qq, F_pp, F_qk, F_kk : float
        Second partials of the density at ``(q, p, k) = (0, 0, 1/R)``.
    beta : float
        Strength of an added ``Perimeter(beta, L*)`` (it shifts ``lambda_0`` only).

    Returns
    -------
    ndarray, shape (kmax + 1,)
        ``lambda_k`` for the normal modes ``cos(k theta)``, ``sin(k theta)``
        (``k >= 1`` double; ``lambda_1 = 0``).

    Examples
    --------
    Faceting (``F_pp = alpha^2``, ``F_kk = W''``): ``-((k^2-1)^2/R^4)(alpha^2 k^2/R^2 + W'')``.

    >>> lam = circle_eigenvalues(1.0, 2, F_qq=0.0, F_pp=0.01, F_qk=0.0, F_kk=0.5)
    >>> [round(float(x), 12) for x in lam]
    [-0.5, 0.0, -4.86]
    """
    R = _radius(R)
    if isinstance(kmax, bool) or not isinstance(kmax, (int, np.integer)) or kmax < 0:
        raise ValueError(f"kmax must be a non-negative integer, got {kmax!r}")
    k = np.arange(int(kmax) + 1, dtype=float)
    m = (k / R) ** 2
    lam = -((k**2 - 1) ** 2 / R**4) * (F_qq * m**2 + (F_pp - 2 * F_qk) * m + F_kk)
    lam[0] -= 2 * np.pi * beta / R
    return lam + 0.0


@dataclass(frozen=True, eq=False)
class _Maps:
    """The discrete ``p``, ``q`` and the evaluation points of one density at one curve."""

    E: Any           # edge difference (N, N)
    A: Any           # edge average, None for the identity (Fourier)
    L_g: Any         # evaluation maps (None = identity)
    L_Q: Any
    L_P: Any
    L_K: Any
    w: np.ndarray    # quadrature weights
    g: np.ndarray
    ge: np.ndarray   # edge values of g
    p: np.ndarray    # nabla_s kappa on edges
    q: np.ndarray    # Delta_s kappa at nodes
    gam: np.ndarray  # evaluation points (gamma, Q, P, K)
    Q: np.ndarray
    P: np.ndarray
    K: np.ndarray


def _maps(c: Curve, placement: str) -> _Maps:
    grid = c.grid
    E = grid.edge_difference()
    A = grid.edge_average() if grid.sparse else None
    ge = c.g if A is None else A @ c.g
    p = (E @ c.kappa) / ge
    q = -(E.T @ p) / c.g
    if placement == "node" or A is None:
        L_g, L_Q, L_P, L_K = None, None, None if A is None else A.T.tocsr(), None
    else:
        L_g, L_Q, L_P, L_K = A, A, None, A
    return _Maps(E, A, L_g, L_Q, L_P, L_K, grid.weights, c.g, ge, p, q, _apply(L_g, c.g),
                 _apply(L_Q, q), _apply(L_P, p), _apply(L_K, c.kappa))


@dataclass(frozen=True)
class SecondOrderDensity:
    """A density ``F(q, p, k)`` of ``q = Delta_s kappa``, ``p = nabla_s kappa``, ``k = kappa``.

    It evaluates its own exact discrete energy, Euclidean gradient and Euclidean
    Hessian (module docstring), so it can be a term of any
    :class:`~qsa.energies.local.LocalEnergy`.

    Parameters
    ----------
    F : callable
        ``F(q, p, k)``, vectorised: arrays of shape (N,) in, shape (N,) (or a
        scalar) out.
    dF : callable
        ``dF(q, p, k) -> (F_q, F_p, F_k)``.
    d2F : callable
        ``d2F(q, p, k) -> (F_qq, F_qp, F_qk, F_pp, F_pk, F_kk)``.
    placement : {"node", "edge"}
        Where the density is evaluated (module docstring); the same on Fourier grids.
    name : str
        Used in error messages.

    Raises
    ------
    ValueError
        A non-callable ``F``, ``dF`` or ``d2F``, an unknown placement; at evaluation,
        callables that return the wrong number of partials, the wrong shape, or
        values that are not finite.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> d = SecondOrderDensity(lambda q, p, k: 0.5 * q**2,
    ...                        lambda q, p, k: (q, 0 * p, 0 * k),
    ...                        lambda q, p, k: (1 + 0 * q,) + (0 * q,) * 5)
    >>> R = 2.0
    >>> c = Curve.circle(R, Fourier(17)).with_kappa(np.cos(2 * np.pi * Fourier(17).s))
    >>> # q = -(1/R^2) cos: E = 1/2 int q^2 dsigma = pi R / (2 R^4)
    >>> bool(np.isclose(d.energy(c), np.pi / (2 * R**3)))
    True
    """

    F: object
    dF: object
    d2F: object
    placement: str = "node"
    name: str = "SecondOrderDensity"

    def __post_init__(self):
        _check_callables(self.name, F=self.F, dF=self.dF, d2F=self.d2F)
        if self.placement not in _PLACEMENTS:
            raise ValueError(f"{self.name}: placement must be 'node' or 'edge', "
                             f"got {self.placement!r}")

    def energy(self, c: Curve) -> float:
        """The discrete energy ``sum_i w_i gamma_i F(Q_i, P_i, K_i)``.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        float
        """
        m = _maps(c, self.placement)
        f = _call(self.name, self.F, "F", None, (m.Q, m.P, m.K))
        return float(np.sum(m.w * m.gam * f))

    def _adjoints(self, m: _Maps, f, fq, fp, fk):
        """``(d_kappa, d_g, c_q, c_p)`` of the module docstring."""
        wg = m.w * m.gam
        c_q = _apply_T(m.L_Q, wg * fq) / m.g
        c_p = (_apply_T(m.L_P, wg * fp) - m.E @ c_q) / m.ge
        dk = _apply_T(m.L_K, wg * fk) + m.E.T @ c_p
        dg = _apply_T(m.L_g, m.w * f) - m.q * c_q - _apply_T(m.A, m.p * c_p)
        return dk, dg, c_q, c_p

    def euclidean_gradient(self, c: Curve) -> np.ndarray:
        """``(dE/dkappa_j, dE/dg_j)``, plain partial derivatives of the discrete energy.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray, shape (2N,)
            Stacked; divided by ``[dsigma, dsigma]`` it is ``nabla_I E`` in
            ``<f, h> = int f h dsigma`` (continuum e:first_var).
        """
        m = _maps(c, self.placement)
        pts = (m.Q, m.P, m.K)
        f = _call(self.name, self.F, "F", None, pts)
        fq, fp, fk = _call(self.name, self.dF, "dF", _FIRST, pts)
        dk, dg, _, _ = self._adjoints(m, f, fq, fp, fk)
        return np.concatenate([dk, dg])

    def euclidean_hessian(self, c: Curve):
        """Second partial derivatives of the discrete energy (module docstring).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        sparse CSR matrix (finite differences, bandwidth 2 in each block) or ndarray
        (Fourier), shape (2N, 2N)
            Symmetric: ``d^2/d delta^2 E(U + delta U1) = U1^T H U1``.
        """
        Y, KK, T2, _, BT2 = self._hessian_terms(c)
        H = T2.T @ BT2 + Y + Y.T
        if c.grid.sparse:
            Z = sp.csr_matrix((c.N, c.N))
            return (H + sp.bmat([[KK, Z], [Z, Z]])).tocsr()
        H[: c.N, : c.N] += KK
        return H

    def euclidean_hessian_parts(self, c: Curve):
        """``(H_rest, T2, B2)`` with ``euclidean_hessian(c) = H_rest + T2^T B2 T2``.

        ``T2`` holds the rows ``Q`` and ``P`` of the evaluation points' Jacobian ``T``
        (``Delta_s kappa`` and ``nabla_s kappa``: of order 2 and 1) and ``B2`` the
        weighted second derivatives ``w gamma F_qq, F_qp, F_pp`` as a 2 x 2 block of
        diagonals; ``H_rest`` (the other rows of ``T``, and ``X_p, X_q``) is of
        order 2. The product ``T2^T B2 T2`` is of order 4: formed, its entries are of
        size ``h^-4`` and their rounding adds up coherently over a row, so spectral
        solvers keep it as these factors (:meth:`LocalEnergy.factored_hessian`).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        H_rest : sparse CSR matrix or ndarray, shape (2N, 2N)
            Symmetric.
        T2 : sparse CSR matrix or ndarray, shape (2N, 2N)
        B2 : sparse CSR matrix or ndarray, shape (2N, 2N)
            Symmetric (diagonal blocks).

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, FiniteDifference
        >>> from qsa.energies import FunctionalizedCurvature
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), FiniteDifference(64))
        >>> d = FunctionalizedCurvature(0.1, 8.0, kstar=4.0).densities()[0]
        >>> rest, T2, B2 = d.euclidean_hessian_parts(c)
        >>> bool(abs(rest + T2.T @ B2 @ T2 - d.euclidean_hessian(c)).max() < 1e-8 * abs(rest).max())
        True
        """
        Y, KK, T2, B2, _ = self._hessian_terms(c)
        rest = Y + Y.T
        if c.grid.sparse:
            Z = sp.csr_matrix((c.N, c.N))
            return (rest + sp.bmat([[KK, Z], [Z, Z]])).tocsr(), T2.tocsr(), B2
        rest = np.array(rest)
        rest[: c.N, : c.N] += KK
        return rest, T2, B2

    def _hessian_terms(self, c: Curve):
        """``(Y, KK, T2, B2, B2 T2)`` of the module docstring's Hessian."""
        grid = c.grid
        m = _maps(c, self.placement)
        pts = (m.Q, m.P, m.K)
        f = _call(self.name, self.F, "F", None, pts)
        fq, fp, fk = _call(self.name, self.dF, "dF", _FIRST, pts)
        fqq, fqp, fqk, fpp, fpk, fkk = _call(self.name, self.d2F, "d2F", _SECOND, pts)
        _, _, c_q, c_p = self._adjoints(m, f, fq, fp, fk)
        S = grid.sandwich  # S(X, b, Y) = X^T diag(b) Y, None = identity
        E, A, g, ge = m.E, m.A, m.g, m.ge
        hstack, vstack = (sp.hstack, sp.vstack) if grid.sparse else (np.hstack, np.vstack)
        # Jacobians (N x 2N) of p (edges) and q (nodes)
        Jpk = grid.scale_rows(1.0 / ge, E)
        Jpg = -(grid.diag(m.p / ge) if A is None else grid.scale_rows(m.p / ge, A))
        Jp = hstack([Jpk, Jpg])
        Jq = hstack([-grid.scale_rows(1.0 / g, E.T @ Jpk),
                     grid.scale_rows(1.0 / g, S(E, m.p / ge, A)) - grid.diag(m.q / g)])
        Qrow, Prow = _apply(m.L_Q, Jq), _apply(m.L_P, Jp)  # rows Q and P of T
        w, wg = m.w, m.w * m.gam
        LK, Lg = m.L_K, m.L_g
        # the rows (Q, P) of T and their 2 x 2 block of weighted second derivatives
        T2 = vstack([Qrow, Prow])
        BT2 = vstack([grid.scale_rows(wg * fqq, Qrow) + grid.scale_rows(wg * fqp, Prow),
                      grid.scale_rows(wg * fqp, Qrow) + grid.scale_rows(wg * fpp, Prow)])
        if grid.sparse:
            B2 = sp.bmat([[sp.diags(wg * fqq), sp.diags(wg * fqp)],
                          [sp.diags(wg * fqp), sp.diags(wg * fpp)]], format="csr")
        else:
            B2 = np.block([[np.diag(wg * fqq), np.diag(wg * fqp)],
                           [np.diag(wg * fqp), np.diag(wg * fpp)]])
        # the rows R_K (kappa) and R_gamma (g) against (Q, P), and the second-order terms
        # X_p, X_q: Y collects them and enters as Y + Y^T
        YK = S(LK, wg * fqk, Qrow) + S(LK, wg * fpk, Prow)
        Yg = (S(Lg, w * fq, Qrow) + S(Lg, w * fp, Prow) - S(A, c_p, Jp) - S(None, c_q, Jq)
              + hstack([S(Lg, w * fk, LK), grid.diag(np.zeros(c.N))]))
        Y = vstack([YK, Yg])
        KK = S(LK, wg * fkk, LK)
        return Y, KK, T2, B2, BT2


@dataclass(frozen=True)
class SecondOrderEnergy(LocalEnergy):
    """A user-defined energy ``int F(Delta_s kappa, nabla_s kappa, kappa) dsigma`` (e:LIE).

    Energy, ``nabla_I E`` (e:first_var), ``V^n`` (e:L2grad) and ``nabla_I^2 E`` are
    those of the discrete energy, exactly (derivation in the module docstring):
    sparse O(N) Hessians on finite-difference grids, dense on Fourier grids.

    Parameters
    ----------
    F : callable
        ``F(q, p, k)`` with ``q = Delta_s kappa``, ``p = nabla_s kappa``, ``k = kappa``;
        vectorised (arrays of shape (N,)).
    dF : callable
        ``dF(q, p, k) -> (F_q, F_p, F_k)``, the three first partials.
    d2F : callable
        ``d2F(q, p, k) -> (F_qq, F_qp, F_qk, F_pp, F_pk, F_kk)``, the six second partials.
    placement : {"node", "edge"}
        Where ``F`` is evaluated on finite-difference grids (module docstring); the
        default "node" sees the highest grid mode through ``q``. "edge" with a
        ``q``-independent ``F`` reproduces :class:`~qsa.energies.FirstOrderEnergy`.

    Raises
    ------
    ValueError
        Non-callable ``F``, ``dF`` or ``d2F``, or an unknown ``placement``; when
        evaluated, partials of the wrong number or shape, or non-finite values.

    Examples
    --------
    ``F = q^2 / 2``: on a circle of radius R perturbed by ``kappa1 = cos(k theta)`` the
    energy is ``int (k^2/R^2 cos)^2 / 2 dsigma = pi k^4 / (2 R^3)``:

    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> E = SecondOrderEnergy(F=lambda q, p, k: 0.5 * q**2,
    ...                       dF=lambda q, p, k: (q, 0 * p, 0 * k),
    ...                       d2F=lambda q, p, k: (1 + 0 * q, 0 * q, 0 * q, 0 * q, 0 * q, 0 * q))
    >>> grid = Fourier(17)
    >>> c = Curve.circle(2.0, grid).with_kappa(np.cos(2 * np.pi * 3 * grid.s))
    >>> bool(np.isclose(E.energy(c), np.pi * 3**4 / (2 * 2.0**3)))
    True
    """

    F: object
    dF: object
    d2F: object
    placement: str = "node"

    def __post_init__(self):
        # validates the callables and the placement
        object.__setattr__(self, "_density", SecondOrderDensity(
            self.F, self.dF, self.d2F, self.placement, name="SecondOrderEnergy"))

    def densities(self):
        """``(SecondOrderDensity(F, dF, d2F, placement),)``."""
        return (self._density,)

    def _at_circle(self, R):
        pts = (np.zeros(1), np.zeros(1), np.full(1, 1.0 / _radius(R)))
        f = float(_call("SecondOrderEnergy", self.F, "F", None, pts)[0])
        first = [float(v[0]) for v in _call("SecondOrderEnergy", self.dF, "dF", _FIRST, pts)]
        second = [float(v[0]) for v in _call("SecondOrderEnergy", self.d2F, "d2F", _SECOND, pts)]
        return f, first, second

    def circle_tension(self, R) -> float:
        """``kappa0 F_k - F`` at ``(0, 0, kappa0 = 1/R)``: ``V^n = kappa0 x`` this on the circle.

        The circle of radius ``R`` is an equilibrium of ``self + Perimeter(beta, L*)`` iff
        ``beta (2 pi R - L*)`` equals it, and a critical circle of ``self`` iff it is 0.

        Parameters
        ----------
        R : float

        Returns
        -------
        float

        Examples
        --------
        >>> E = SecondOrderEnergy(lambda q, p, k: 0.5 * k**2, lambda q, p, k: (0 * q, 0 * p, k),
        ...                       lambda q, p, k: (0 * q,) * 5 + (1 + 0 * q,))
        >>> E.circle_tension(2.0)  # Canham-Helfrich: kappa0^2 / 2
        0.125
        """
        f, (_, _, fk), _ = self._at_circle(R)
        return fk / _radius(R) - f

    def circle_eigenvalues(self, R, kmax, beta=0.0) -> np.ndarray:
        """Closed-form spectrum of ``J`` at the circle of radius ``R`` (:func:`circle_eigenvalues`).

        Valid where the circle is an equilibrium: of ``self + Perimeter(beta, L*)`` with
        ``beta (2 pi R - L*) =`` :meth:`circle_tension`, or of ``self`` when that is 0.

        Parameters
        ----------
        R : float
        kmax : int
        beta : float

        Returns
        -------
        ndarray, shape (kmax + 1,)

        Examples
        --------
        >>> E = SecondOrderEnergy(lambda q, p, k: 0.5 * k**2, lambda q, p, k: (0 * q, 0 * p, k),
        ...                       lambda q, p, k: (0 * q,) * 5 + (1 + 0 * q,))
        >>> E.circle_eigenvalues(1.0, 2).tolist()  # Canham-Helfrich, eps = 1: -(k^2 - 1)^2
        [-1.0, 0.0, -9.0]
        """
        _, _, (qq, _, qk, pp, _, kk) = self._at_circle(R)
        return circle_eigenvalues(R, kmax, qq, pp, qk, kk, beta)

    def __repr__(self):
        return f"SecondOrderEnergy(placement={self.placement!r})"
