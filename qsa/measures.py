"""The length and the enclosed area of a closed curve, intrinsic variables, exact derivatives.

With ``D f = int_0^s f dsigma``, ``theta = theta0 + D kappa``, ``tau = (cos theta,
sin theta)``, ``n = (sin theta, -cos theta)`` (outward) and ``gamma = gamma0 + D tau``,
a closed curve encloses ``A = 1/2 int gamma . n dsigma``. Off the closed manifold that
integrand jumps at ``s = 0 == 1`` (``gamma`` and ``theta`` do not close), and a periodic
quadrature of it is only first-order accurate there -- which the second variation sees.
The area used here (:meth:`qsa.curve.Curve.area`) spreads the closure defects linearly
instead: with the excess turning ``K - 2 pi`` (``K = int kappa dsigma``) removed,
``theta_hat = theta - (K - 2 pi) s``, and ``u = g cos theta_hat``, ``v = g sin theta_hat``
(periodic),

    A(U) = 1/2 int (v~ Q u~ - u~ Q v~) ds = 1/2 sum_jk B_jk g_j g_k sin(theta_hat_j - theta_hat_k),

``u~, v~`` the mean-free parts and ``Q`` the periodic antiderivative: the area of the
closed curve ``gamma_hat = Q (g tau_hat)``, equal to ``1/2 int gamma . n dsigma`` on closed
curves, invariant under rotations and translations, and a smooth function of ``U``
with periodic integrands only. Discretely, with the grid's cumulative-integral matrix
``C`` (``D f = C (f g)``), the weights ``w`` and ``P0 = I - 1 w^T`` (mean removal),
``B = P0^T (W C - C^T W) P0 / 2`` (``W = diag(w)``, antisymmetric), and
``theta_hat = theta0 + C_hat (kappa g) + 2 pi s``, ``C_hat = C - s w^T``.

Exact discrete derivatives (``p = B u``, ``q = B v``):

* gradient, O(N) on finite differences: ``a = dA/dtheta_hat = g (cos theta_hat p +
  sin theta_hat q)``, ``beta = dA/dg`` at fixed ``theta_hat`` ``= sin theta_hat p -
  cos theta_hat q``; ``dA/dkappa = g C_hat^T a``, ``dA/dg = beta + kappa C_hat^T a``; the
  ``<.,.>``-gradient divides both by ``dsigma = w g``;
* Hessian: with ``S_jk = sin(theta_hat_j - theta_hat_k)``, ``Co_jk = cos(...)``,
  ``A_thth = -diag(g beta) + diag(g) (B o S) diag(g)``,
  ``A_thg = diag(a / g) + diag(g) (B o Co)``, ``A_gg = B o S``; with
  ``T = dtheta_hat/dU = C_hat [diag(g), diag(kappa)]`` and ``E_g = [0, I]`` the
  Euclidean Hessian is ``T^T A_thth T + T^T A_thg E_g + E_g^T A_thg^T T + E_g^T A_gg E_g
  + [[0, diag(C_hat^T a)], [diag(C_hat^T a), 0]]`` (the last term from the product
  ``kappa g`` in ``theta_hat``), and the ``<.,.>``-Hessian is ``W2^{-1}`` times it,
  ``W2 = diag(dsigma, dsigma)``.

On a closed curve the gradient is, in the continuum,
``(-|gamma~|^2 / 2 + c0, (kappa (-|gamma~|^2 / 2 + c0) + gamma~ . n) / g)`` with
``gamma~ = gamma - int gamma ds`` and ``c0 = int |gamma~|^2 ds / 2``: a curve moving with
outward normal velocity ``V`` changes its area by ``<1, V>``, and
``-[M-dagger nabla_I A]_1 = -1`` (the normal velocity of the energy ``A``). The length
``L = int g ds`` has ``nabla_I L = (0, 1/g)`` and ``nabla_I^2 L = 0`` exactly, and
``-[M-dagger nabla_I L]_1 = -kappa``.

These are the functionals behind :class:`qsa.constraints.FixedLength`,
:class:`qsa.constraints.FixedArea` and the area energies (:mod:`qsa.energies.area`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from qsa.curve import Curve

__all__ = ["area_gradient", "area_gradient_euclidean", "area_hessian", "length_gradient",
           "length_hessian"]


def _apply_B(grid, x):
    """``B x`` with ``B = P0^T (W C - C^T W) P0 / 2`` (module docstring), x of shape (N,)."""
    w = grid.weights
    y = x - w @ x
    z = 0.5 * (w * grid.cumulative(y) - grid.cumulative_transpose(w * y))
    return z - w * np.sum(z)


def _area_parts(c: Curve):
    """``(theta_hat, a, beta)``: the periodized angle, ``dA/dtheta_hat`` and ``dA/dg``."""
    grid = c.grid
    th = c.theta() - (c.kappa @ c.dsigma - 2 * np.pi) * grid.s
    cs, sn = np.cos(th), np.sin(th)
    p = _apply_B(grid, c.g * cs)
    q = _apply_B(grid, c.g * sn)
    return th, c.g * (cs * p + sn * q), sn * p - cs * q


def _C_hat_transpose(grid, a):
    """``C_hat^T a = C^T a - w (s . a)``."""
    return grid.cumulative_transpose(a) - grid.weights * (grid.s @ a)


def area_gradient_euclidean(c: Curve) -> np.ndarray:
    """Exact derivative ``dA/dU`` of the discrete area :meth:`~qsa.curve.Curve.area`, (2N,).

    The plain (Euclidean) gradient, ``A(U + d U1) = A + d (dA/dU) . U1 + O(d^2)``
    (no inner-product weights): the row of a Newton matrix.

    Parameters
    ----------
    c : Curve

    Returns
    -------
    ndarray, shape (2N,)
        Stacked ``[dA/dkappa, dA/dg]``; ``area_gradient(c) * [dsigma, dsigma]``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, FiniteDifference
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), FiniteDifference(32))
    >>> U1 = np.concatenate([np.cos(2 * np.pi * c.grid.s), np.ones(32)])
    >>> d = 1e-6
    >>> fd = (c.with_U(c.U + d * U1).area() - c.with_U(c.U - d * U1).area()) / (2 * d)
    >>> bool(np.isclose(fd, area_gradient_euclidean(c) @ U1, rtol=1e-8))
    True
    """
    _, a, beta = _area_parts(c)
    ca = _C_hat_transpose(c.grid, a)
    return np.concatenate([c.g * ca, beta + c.kappa * ca])


def area_gradient(c: Curve) -> np.ndarray:
    """``nabla_I A`` in ``<f, h> = int f h dsigma``: the exact gradient of the discrete area, (2N,).

    ``d/d delta A(U + delta U1) = <nabla_I A, U1>`` exactly for the discrete area and
    inner product (module docstring, which also gives its continuum form on closed
    curves).

    Parameters
    ----------
    c : Curve

    Returns
    -------
    ndarray, shape (2N,)
        Stacked ``[d_kappa A, d_g A]``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(65))
    >>> V = -(geometry.M_adjoint(c) @ area_gradient(c))[:65]  # the normal velocity of A
    >>> bool(np.allclose(V, -1.0, atol=1e-8))
    True
    """
    w = np.concatenate([c.dsigma, c.dsigma])
    return area_gradient_euclidean(c) / w


def area_hessian(c: Curve) -> np.ndarray:
    """``nabla_I^2 A`` in ``<f, h> = int f h dsigma``: the exact Hessian of the discrete area.

    ``d^2/d delta^2 A(U + delta U1) = <H U1, U1>`` along straight paths, at every ``U``
    (closed or not); the formula is in the module docstring.

    Parameters
    ----------
    c : Curve

    Returns
    -------
    ndarray, shape (2N, 2N)
        Dense (the cumulative integrals couple all nodes); ``W2 H`` is symmetric,
        ``W2 = diag(dsigma, dsigma)``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
    >>> U1 = np.concatenate([np.cos(2 * np.pi * c.grid.s), 0.3 * np.ones(33)])
    >>> A = lambda t: c.with_U(c.U + t * U1).area()
    >>> d, w = 1e-3, np.concatenate([c.dsigma, c.dsigma])
    >>> second = (A(d) - 2 * A(0) + A(-d)) / d**2
    >>> bool(np.isclose(second, (area_hessian(c) @ U1) @ (U1 * w), rtol=1e-5))
    True
    """
    grid = c.grid
    N = c.N
    w, g, k, s = grid.weights, c.g, c.kappa, grid.s
    th, a, beta = _area_parts(c)
    C = grid.cumulative_matrix()
    P0 = np.eye(N) - np.outer(np.ones(N), w)
    B = P0.T @ (0.5 * (w[:, None] * C - C.T * w[None, :])) @ P0
    Ch = C - np.outer(s, w)
    dth = th[:, None] - th[None, :]
    BS = B * np.sin(dth)
    Att = -np.diag(g * beta) + g[:, None] * BS * g[None, :]
    Atg = np.diag(a / g) + g[:, None] * (B * np.cos(dth))
    T = np.hstack([Ch * g[None, :], Ch * k[None, :]])  # d theta_hat / dU, (N, 2N)
    H = T.T @ (Att @ T)
    cross = T.T @ Atg  # (2N, N): the columns acting on g
    H[:, N:] += cross
    H[N:, :] += cross.T
    H[N:, N:] += BS
    ca = Ch.T @ a
    idx = np.arange(N)
    H[idx, N + idx] += ca
    H[N + idx, idx] += ca
    W2 = np.concatenate([c.dsigma, c.dsigma])
    return H / W2[:, None]


# ---------------------------------------------------------------- the length
def length_gradient(c: Curve) -> np.ndarray:
    """``nabla_I L = (0, 1/g)`` in ``<f, h> = int f h dsigma``, ``L = int g ds``, shape (2N,).

    Parameters
    ----------
    c : Curve

    Returns
    -------
    ndarray, shape (2N,)

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(9))
    >>> bool(np.allclose(length_gradient(c)[9:], 1 / (2 * np.pi)))
    True
    """
    return np.concatenate([np.zeros(c.N), 1.0 / c.g])


def length_hessian(c: Curve):
    """``nabla_I^2 L = 0`` (``L`` is linear in ``g``), in the grid's matrix type, (2N, 2N).

    Parameters
    ----------
    c : Curve

    Returns
    -------
    sparse CSR matrix (finite differences) or ndarray (Fourier), shape (2N, 2N)

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> float(abs(length_hessian(Curve.circle(1.0, Fourier(9)))).max())
    0.0
    """
    n = 2 * c.N
    return sp.csr_matrix((n, n)) if c.grid.sparse else np.zeros((n, n))
