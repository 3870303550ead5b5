"""Linearizations of the gradient flow ``U_t = -M M-dagger nabla_I E`` at an equilibrium.

Four gauges (Conventions and errata, section 4; e:FOE-Lin, e:Meq, e:CVE):

``"comoving"``
    ``calL = -M M-dagger L_Lambda`` on ``(kappa1, g1)``, shape (2N, 2N), with the
    Lagrangian Hessian ``L_Lambda`` of :mod:`qsa.spectra.hessian`. Structure:
    ``calL M(phi, v) = M(J phi, 0)``, so its non-zero eigenvalues are those of ``J``
    and its kernel has dimension ``N + dim ker J`` (reparameterization modes
    ``M(0, v)`` plus the directions outside ``range M``).
``"paper"``
    ``-M M-dagger nabla^2 E`` as printed (e:FOE-Lin), for comparison only.
    # NOTE: it omits the multiplier term ``Lambda . nabla^2 C`` and has spurious
    # positive eigenvalues when ``Lambda != 0`` (Conventions and errata, section 4).
``"normal"``
    ``J = -[M-dagger L_Lambda M(., 0)]_1``, shape (N, N): the linearization of the
    normal velocity under normal perturbations ``phi``. dsigma-self-adjoint, so its
    spectrum is real; its kernel contains the normal components of the rigid motions.
``"scaled"``
    The scaled-arc-length quotient on ``x = (kappa1, g1)`` with ``g1`` spatially
    constant, shape (N + 1, N + 1): ``calL`` followed by the projection along the
    reparameterization modes ``M(0, v)`` (mean-zero ``v``) that keeps ``g``
    constant. Needs a curve with constant ``g``.

Constraints
-----------
With length / area constraints (``constraints=[FixedLength(), FixedArea()]``,
:mod:`qsa.constraints`) the Lagrangian Hessian carries their multiplier terms and the
constrained flow's normal velocity is ``P V^n``, ``P`` the ``<.,.>``-orthogonal
projection onto ``T = {phi : <n_c, phi> = 0}`` (``n_L = kappa``, ``n_A = 1``). So the
normal gauge is ``P J P`` (self-adjoint; ``span n_c`` in its kernel), the comoving
gauge ``-M diag(P, I) M-dagger L`` (``M`` of the projected extrinsic velocity; its
non-zero spectrum is that of ``P J P`` on ``T``) and the scaled gauge projects ``dV``
the same way. With ``R`` the rows of :func:`qsa.constraints.normal_basis`,
``P = I - R^T R W``.

Discrete form: with ``W = diag(dsigma)``, ``W2 = diag(dsigma, dsigma)`` and
``M1 = M[:, :N]`` (the normal columns of ``M``),
``J = -W^{-1} M1^T (W2 L_Lambda) M1``; ``W2 L_Lambda`` is symmetric, so ``W J`` is
symmetric and ``W^{1/2} J W^{-1/2}`` (:func:`normal_operator` with
``symmetric=True``) is the symmetric standard form used by the eigen-solvers.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from qsa import geometry
from qsa.constraints import bind_constraints, normal_basis
from qsa.curve import Curve
from qsa.energies.base import add_matrices
from qsa.linalg import ReducedHessian, SparsePlusLowRank, to_dense
from qsa.spectra.hessian import LagrangeHessian, check_input, lagrange_hessian

__all__ = ["linearization", "normal_operator", "scaled_operator", "symmetric_form",
           "project_operator", "GAUGES"]

#: The gauges accepted by :func:`linearization` and :func:`qsa.spectra.spectrum`.
GAUGES = ("comoving", "paper", "normal", "scaled")


def _check_gauge(gauge):
    if gauge not in GAUGES:
        raise ValueError(f"gauge must be one of {GAUGES}, got {gauge!r}")
    return gauge


def _scale_rows_cols(A, left, right):
    """``diag(left) A diag(right)`` for dense, sparse or sparse-plus-low-rank ``A``."""
    if isinstance(A, SparsePlusLowRank):
        S = sp.diags(left) @ A.S @ sp.diags(right)
        return SparsePlusLowRank(S, left[:, None] * A.U, right[:, None] * A.V)
    if sp.issparse(A):
        return (sp.diags(left) @ A @ sp.diags(right)).tocsr()
    return left[:, None] * np.asarray(A) * right[None, :]


def _symmetrize(A):
    if isinstance(A, SparsePlusLowRank):
        S = 0.5 * (A.S + A.S.T)
        U = np.hstack([A.U, A.V]) * np.sqrt(0.5)
        V = np.hstack([A.V, A.U]) * np.sqrt(0.5)
        return SparsePlusLowRank(S, U, V)
    if sp.issparse(A):
        return (0.5 * (A + A.T)).tocsr()
    return 0.5 * (A + A.T)


def _lagrangian(energy, curve, lagrange, constraints):
    """``(LagrangeHessian, constraints)``: the given one (with its constraints) or a new one."""
    if lagrange is not None:
        if not isinstance(lagrange, LagrangeHessian):
            raise ValueError("lagrange must be a LagrangeHessian from "
                             "qsa.spectra.lagrange_hessian")
        return lagrange, lagrange.constraints
    cons = bind_constraints(constraints, curve)
    return lagrange_hessian(energy, curve, constraints=cons), cons


def _projection_factors(curve, constraints):
    """``(a, b)`` with ``P = I - a b^T`` the ``<.,.>``-projection onto ``T`` (None if none)."""
    Rc = normal_basis(constraints, curve)
    if Rc.shape[0] == 0:
        return None
    return Rc.T, curve.dsigma[:, None] * Rc.T


def project_operator(J, a, b):
    """``P J P`` with ``P = I - a b^T``, in the matrix type of ``J`` plus a low-rank part.

    Parameters
    ----------
    J : matrix, shape (N, N)
        Dense, sparse, :class:`~qsa.linalg.SparsePlusLowRank` or
        :class:`~qsa.linalg.ReducedHessian`.
    a, b : ndarray, shape (N, m)

    Returns
    -------
    matrix, shape (N, N)
        ``J + U V^T`` with ``U = [-a, -J a + a (b^T J a)]``, ``V = [J^T b, b]``.

    Examples
    --------
    >>> import numpy as np
    >>> J = np.diag([1.0, 2.0, 3.0])
    >>> a = b = np.array([[1.0], [1.0], [1.0]]) / np.sqrt(3)
    >>> P = np.eye(3) - a @ b.T
    >>> bool(np.allclose(project_operator(J, a, b), P @ J @ P))
    True
    """
    Ja = J @ a
    U = np.hstack([-a, -Ja + a @ (b.T @ Ja)])
    V = np.hstack([J.T @ b, b])
    return add_matrices(J, SparsePlusLowRank(sp.csr_matrix(J.shape), U, V))


def normal_operator(energy, curve: Curve, symmetric=False, lagrange=None, constraints=None):
    """``J = -[M-dagger L_Lambda M(., 0)]_1``, or its symmetric form ``W^{1/2} J W^{-1/2}``.

    Parameters
    ----------
    energy : Energy
    curve : Curve
    symmetric : bool
        Return ``S = W^{1/2} J W^{-1/2}`` (``W = diag(dsigma)``), symmetric in the
        Euclidean inner product (exactly symmetrised, ``(S + S^T)/2``): same
        eigenvalues as ``J``, eigenvectors ``y = W^{1/2} phi``.
    lagrange : LagrangeHessian, optional
        A precomputed :func:`~qsa.spectra.lagrange_hessian` of this curve (its
        constraints are used).
    constraints : sequence of Constraint, optional
        Length / area constraints: ``P J P`` (module docstring).

    Returns
    -------
    matrix, shape (N, N)
        Dense for Fourier grids; sparse or :class:`~qsa.linalg.SparsePlusLowRank`
        for finite differences. ``J`` is self-adjoint in ``<f, h> = int f h dsigma``.

    Examples
    --------
    The faceting circle (Conventions and errata, section 4): ``lambda_0 = -W''(1) - 2 pi beta``,
    ``lambda_2 = -9 (4 alpha^2 + W''(1))`` (double), ``lambda_1 = 0`` (translations):

    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> J = normal_operator(eq.energy, eq.curve)
    >>> ev = np.sort(np.linalg.eigvals(J).real)[::-1]
    >>> np.round(ev[:5], 6).tolist() == [0.0, 0.0, -4.86, -4.86, round(-0.5 - 10 * np.pi, 6)]
    True
    """
    check_input(energy, curve)
    LH, cons = _lagrangian(energy, curve, lagrange, constraints)
    J = _normal_core(curve, LH.matrix)
    ab = _projection_factors(curve, cons)
    if ab is not None:
        J = project_operator(J, *ab)
    return symmetric_form(curve, J) if symmetric else J


def _normal_core(curve, L):
    N = curve.N
    w = curve.dsigma
    w2 = np.concatenate([w, w])
    M1 = geometry.M(curve)[:, :N]
    # W2 L is symmetric (L is dsigma-self-adjoint); J = -W^{-1} M1^T (W2 L) M1
    WL = _scale_rows_cols(L, w2, np.ones(2 * N))
    core = np.asarray(M1.T @ (WL @ M1)) if not curve.grid.sparse else M1.T @ (WL @ M1)
    return _scale_rows_cols(core, -1.0 / w, np.ones(N))


def symmetric_form(curve: Curve, J):
    """``(S + S^T) / 2`` with ``S = W^{1/2} J W^{-1/2}``, ``W = diag(dsigma)``, shape (N, N).

    Parameters
    ----------
    curve : Curve
        Supplies ``W = diag(dsigma)``.
    J : matrix, shape (N, N)
        Self-adjoint in ``<f, h> = int f h dsigma``.

    Returns
    -------
    matrix, shape (N, N)
        Symmetric in the Euclidean inner product, with the eigenvalues of ``J``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> S = symmetric_form(eq.curve, normal_operator(eq.energy, eq.curve))
    >>> bool(np.allclose(S, S.T)), round(float(np.linalg.eigvalsh(S).max()), 6) + 0.0
    (True, 0.0)
    """
    rw = np.sqrt(curve.dsigma)
    return _symmetrize(_scale_rows_cols(J, rw, 1.0 / rw))


def scaled_operator(energy, curve: Curve, lagrange=None, constraints=None) -> np.ndarray:
    """The scaled-arc-length linearization on ``x = (kappa1, g1)``, shape (N + 1, N + 1).

    ``g1`` is the (spatially constant) perturbation of ``g = L``. With
    ``dV = -[M-dagger L_Lambda (kappa1, g1 1)]_1`` and ``y = M(dV, 0)``, the
    tangential velocity ``v`` (mean zero) restoring constant ``g`` solves
    ``d_s v = y_g - c``, ``c = int y_g ds``, and ``K x = (y_kappa - v nabla_s kappa, c)``.
    Dense (the pseudo-inverse of ``d/ds`` is dense).

    Raises
    ------
    ValueError
        If ``curve.g`` is not constant (reparameterize first, e.g. with
        :func:`qsa.equilibria.polish`).

    Parameters
    ----------
    energy : Energy
    curve : Curve
        With constant ``g``.
    lagrange : LagrangeHessian, optional
        A precomputed :func:`~qsa.spectra.lagrange_hessian` of this curve (its
        constraints are used).
    constraints : sequence of Constraint, optional
        Length / area constraints: ``dV`` is replaced by ``P dV`` (module docstring).

    Returns
    -------
    ndarray, shape (N + 1, N + 1)
        Acts on ``(kappa1, g1)``; self-adjoint in the weights ``(dsigma, L)``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import circle
    >>> eq = circle(1.0, 0.1, grid=17, kstar=5.0)
    >>> K = scaled_operator(eq.energy, eq.curve)
    >>> ev = np.sort(np.linalg.eigvals(K).real)[::-1]
    >>> K.shape, np.round(ev[3:5], 6).tolist()  # 3 kernel modes, then J's spectrum
    ((18, 18), [-4.86, -4.86])
    """
    check_input(energy, curve)
    g = curve.g
    if np.max(np.abs(g - g.mean())) > 1e-10 * g.mean():
        raise ValueError("curve: the scaled gauge needs constant g (scaled arc length); "
                         "reparameterize the curve first (e.g. qsa.equilibria.polish)")
    LH, cons = _lagrangian(energy, curve, lagrange, constraints)
    N = curve.N
    grid = curve.grid
    L = to_dense(_uncompressed(LH, energy, curve))
    Md1 = to_dense(geometry.M_adjoint(curve))[:N]
    M1 = to_dense(geometry.M(curve))[:, :N]
    E = np.zeros((2 * N, N + 1))
    E[:N, :N] = np.eye(N)
    E[N:, N] = 1.0
    dV = -(Md1 @ (L @ E))
    ab = _projection_factors(curve, cons)
    if ab is not None:
        dV = dV - ab[0] @ (ab[1].T @ dV)
    y = M1 @ dV
    yk, yg = y[:N], y[N:]
    c = grid.weights @ yg
    Dpinv = np.linalg.pinv(to_dense(grid.derivative()))
    v = Dpinv @ (yg - c[None, :])
    K = np.empty((N + 1, N + 1))
    K[:N] = yk - curve.grad_s(curve.kappa)[:, None] * v
    K[N] = c
    return K


def _uncompressed(LH, energy, curve):
    """``LH.matrix``, dense and with the exact energy Hessian if the spectra's was compressed.

    The comoving and scaled gauges form their operators densely and estimate errors from
    them alone, so a compressed two-point Hessian (``approximations``) is replaced by the
    exact one, which is affordable wherever the dense operator is.
    """
    H = LH.energy_hessian
    if isinstance(H, ReducedHessian) and H.approximations:
        return to_dense(LH.matrix) - to_dense(H) + to_dense(energy.hessian(curve))
    return LH.matrix


def linearization(energy, curve: Curve, gauge="comoving", lagrange=None, constraints=None):
    """The linearized flow at ``curve`` in the requested gauge (see the module docstring).

    Parameters
    ----------
    energy : Energy
    curve : Curve
        An equilibrium (or quasi-equilibrium); far from one the operators are
        still returned, but only ``"comoving"`` then linearizes the flow.
    gauge : {"comoving", "paper", "normal", "scaled"}
        ``"comoving"``: ``-M M-dagger L_Lambda`` (2N x 2N, the default);
        ``"paper"``: ``-M M-dagger nabla^2 E`` (e:FOE-Lin as printed);
        ``"normal"``: ``J`` (N x N, dsigma-self-adjoint);
        ``"scaled"``: the constant-``g`` quotient (N + 1 x N + 1, dense).
    lagrange : LagrangeHessian, optional
        Reuse a computed :func:`~qsa.spectra.lagrange_hessian` (and its constraints).
    constraints : sequence of Constraint, optional
        Length / area constraints (:mod:`qsa.constraints`): the linearization of the
        constrained flow (module docstring).

    Returns
    -------
    matrix
        Dense ``ndarray`` for Fourier grids (and for ``"scaled"``); ``scipy.sparse``
        or :class:`~qsa.linalg.SparsePlusLowRank` for finite differences.

    Examples
    --------
    >>> from qsa import Fourier
    >>> from qsa.equilibria import circle
    >>> eq = circle(0.7, 0.1, grid=Fourier(33))
    >>> J = linearization(eq.energy, eq.curve, gauge="normal")
    >>> J.shape
    (33, 33)
    """
    check_input(energy, curve)
    _check_gauge(gauge)
    LH, cons = _lagrangian(energy, curve, lagrange, constraints)
    if gauge == "normal":
        return normal_operator(energy, curve, lagrange=LH)
    if gauge == "scaled":
        return scaled_operator(energy, curve, lagrange=LH)
    H = energy.hessian(curve) if gauge == "paper" else _uncompressed(LH, energy, curve)
    if isinstance(H, ReducedHessian):  # the operator is dense in this gauge
        H = to_dense(H)
    out = -(geometry.MMdagger(curve) @ H)
    ab = _projection_factors(curve, cons)
    if ab is None:
        return out
    # -M diag(P, I) M-dagger H = out + M1 a (b^T [M-dagger H]_1)
    N = curve.N
    a, b = ab
    M1a = geometry.M(curve)[:, :N] @ a
    Md1b = geometry.M_adjoint(curve)[:N].T @ b  # (2N, m)
    return add_matrices(out, SparsePlusLowRank(sp.csr_matrix(out.shape), M1a, H.T @ Md1b))
