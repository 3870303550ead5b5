"""Operators of the intrinsic formulation: M, its dsigma-adjoint, kernels, constraint Hessians.

All adjoints are taken in ``<f, h> = int f h dsigma`` (Conventions and errata, section 1); the
discrete adjoint of a matrix ``A`` is ``W^{-1} A^T W`` with ``W = diag(dsigma)``
(block-diagonal on stacked ``[kappa, g]``).

Discrete operators (finite differences use the paper's second-order stencils):

* ``grad_s = diag(1/g) d/ds`` (skew in dsigma: d/ds is skew-symmetric);
* ``laplace_s = -diag(1/g) E^T diag(1/g_e) E`` with the grid's edge difference
  ``E`` and edge values ``g_e`` of g: compact, dsigma-self-adjoint, and for
  constant g the usual 3-point (FD) or spectral (Fourier) second derivative;
* ``G = -laplace_s - kappa^2`` (the surface Helmholtz operator);
* ``M = [[G, diag(grad_s kappa)], [diag(g kappa), diag(g) grad_s]]`` (e:Meq).

Notes
-----
Equations: e:Meq, e:FSFF (M), e:CVE (M-dagger), lem:kerM (rigid motions),
e:Psi1-e:Psi3 (Psi, in the position form of Conventions and errata, section 2), e:cC-Hessian
and e:cC-Hessian3 (constraint Hessians; the printed ones are wrong, see the
NOTE in :func:`constraint_hessians`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from qsa.closure import closure_hessian, curvature_closure_hessian
from qsa.curve import Curve

__all__ = [
    "grad_s",
    "laplace_s",
    "helmholtz",
    "apply_laplace_s",
    "M",
    "M_adjoint",
    "MMdagger",
    "periodic_positions",
    "adjoint",
    "rigid_motions",
    "constraint_gradients",
    "constraint_hessians",
    "D_matrix",
    "D_adjoint_matrix",
    "reparameterization_mode",
]


def _bmat(blocks, grid):
    if grid.sparse:
        return sp.bmat(blocks, format="csr")
    return np.block([[b if b is not None else np.zeros((grid.N, grid.N)) for b in row]
                     for row in blocks])


def grad_s(c: Curve):
    """``nabla_s = (1/g) d/ds`` as a matrix; skew-adjoint in ``<f, h> = int f h dsigma``.

    Parameters
    ----------
    c : Curve

    Returns
    -------
    sparse CSR matrix (finite differences) or ndarray (Fourier), shape (N, N)

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.circle(2.0, Fourier(17))
    >>> x, y = c.positions()
    >>> bool(np.allclose(geometry.grad_s(c) @ x, c.tangent()[0]))  # d gamma/d sigma = tau
    True
    """
    return c.grid.scale_rows(1.0 / c.g, c.grid.derivative())


def laplace_s(c: Curve):
    """Laplace-Beltrami ``Delta_s = nabla_s nabla_s``, compact and dsigma-self-adjoint.

    Parameters
    ----------
    c : Curve

    Returns
    -------
    sparse CSR matrix or ndarray, shape (N, N)
        ``-diag(1/g) E^T diag(1/g_e) E`` (module docstring); self-adjoint and
        non-positive in ``<f, h> = int f h dsigma``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.circle(1.0, Fourier(33))
    >>> c = c.with_g(2 * np.pi * (1 + 0.2 * np.cos(2 * np.pi * c.grid.s)))
    >>> A = c.dsigma[:, None] * geometry.laplace_s(c)  # W Delta_s
    >>> bool(np.allclose(A, A.T)), bool(np.linalg.eigvalsh(A).max() < 1e-8)
    (True, True)
    """
    grid = c.grid
    E = grid.edge_difference()
    ge = grid.edge_average() @ c.g
    return -grid.scale_rows(1.0 / c.g, grid.sandwich(E, 1.0 / ge, E))


def apply_laplace_s(c: Curve, f) -> np.ndarray:
    """``Delta_s f`` without forming the matrix (three sparse/dense products).

    Parameters
    ----------
    c : Curve
    f : ndarray, shape (N,)

    Returns
    -------
    ndarray, shape (N,)
        ``laplace_s(c) @ f``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, FiniteDifference, geometry
    >>> c = Curve.circle(1.0, FiniteDifference(32))
    >>> f = np.cos(2 * np.pi * c.grid.s)
    >>> bool(np.allclose(geometry.apply_laplace_s(c, f), geometry.laplace_s(c) @ f))
    True
    """
    grid = c.grid
    E = grid.edge_difference()
    ge = grid.edge_average() @ c.g
    return -(E.T @ ((E @ f) / ge)) / c.g


def helmholtz(c: Curve):
    """``G = -Delta_s - kappa^2``, the surface Helmholtz operator (block (1,1) of M).

    Parameters
    ----------
    c : Curve

    Returns
    -------
    sparse CSR matrix or ndarray, shape (N, N)
        Self-adjoint in ``<f, h> = int f h dsigma``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> x, y = c.positions()
    >>> bool(np.allclose(geometry.helmholtz(c) @ x, 0))  # G kills cos(theta), sin(theta)
    True
    """
    return -laplace_s(c) - c.grid.diag(c.kappa**2)


def M(c: Curve):
    """The map from extrinsic velocities (V^n, V^tau) to U_t = (kappa_t, g_t) (e:Meq).

    ``M = [[G, diag(nabla_s kappa)], [diag(g kappa), diag(g) nabla_s]]``; its kernel
    holds the rigid motions (lem:kerM).

    Parameters
    ----------
    c : Curve

    Returns
    -------
    matrix, shape (2N, 2N)
        Sparse CSR for finite differences, dense for Fourier; acts on stacked
        ``[V^n, V^tau]`` and returns stacked ``[kappa_t, g_t]``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(65))
    >>> R = geometry.rigid_motions(c)
    >>> bool(np.abs(geometry.M(c) @ R.T).max() < 1e-6 * np.abs(geometry.M(c)).max())
    True
    """
    grid = c.grid
    ks = c.grad_s(c.kappa)
    return _bmat([[helmholtz(c), grid.diag(ks)],
                  [grid.diag(c.g * c.kappa), grid.scale_rows(c.g, grad_s(c))]], grid)


def adjoint(c: Curve, A):
    """dsigma-adjoint ``W^{-1} A^T W`` of a (2N, 2N) or (N, N) matrix ``A``.

    Parameters
    ----------
    c : Curve
        Supplies ``W = diag(dsigma)`` (block-diagonal on stacked ``[kappa, g]``).
    A : sparse matrix or ndarray, shape (N, N) or (2N, 2N)

    Returns
    -------
    sparse CSR matrix or ndarray, shape like ``A``
        ``A-dagger`` with ``<A f, h> = <f, A-dagger h>`` in ``<f, h> = int f h dsigma``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.circle(1.0, Fourier(17)).with_g(1 + np.arange(17) / 17)
    >>> A = np.random.default_rng(0).standard_normal((17, 17))
    >>> f, h = np.ones(17), np.arange(17.0)
    >>> lhs, rhs = (A @ f) @ (h * c.dsigma), f @ (geometry.adjoint(c, A) @ h * c.dsigma)
    >>> bool(np.isclose(lhs, rhs))
    True
    """
    w = c.dsigma
    if A.shape[0] == 2 * c.N:
        w = np.concatenate([w, w])
    if sp.issparse(A):
        return (sp.diags(1.0 / w) @ A.T @ sp.diags(w)).tocsr()
    return (A.T * w[None, :]) / w[:, None]


def M_adjoint(c: Curve):
    """dsigma-adjoint of :func:`M`: ``[[G, g kappa], [grad_s kappa, -grad_s(g .)]]`` (e:CVE).

    Adjoint in ``<f, h> = int f h dsigma``; its kernel is spanned by the constraint
    gradients ``Psi_1..Psi_3`` (:func:`constraint_gradients`).

    Parameters
    ----------
    c : Curve

    Returns
    -------
    matrix, shape (2N, 2N)
        Sparse CSR for finite differences, dense for Fourier.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(65))
    >>> Md, Psi = geometry.M_adjoint(c), geometry.constraint_gradients(c)
    >>> bool(np.abs(Md @ Psi.T).max() < 1e-6 * np.abs(Md).max())
    True
    """
    return adjoint(c, M(c))


def MMdagger(c: Curve):
    """The geometric prefactor ``M M-dagger`` built as the product.

    # NOTE: the paper's printed MM-dagger display has wrong (2,1) and (2,2)
    # entries (Conventions and errata, section 2); the product is exact by construction.

    Parameters
    ----------
    c : Curve

    Returns
    -------
    matrix, shape (2N, 2N)
        Self-adjoint and non-negative in ``<f, h> = int f h dsigma``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> A = np.concatenate([c.dsigma] * 2)[:, None] * geometry.MMdagger(c)
    >>> bool(np.allclose(A, A.T)), bool(np.linalg.eigvalsh(A).min() > -1e-8)
    (True, True)
    """
    return M(c) @ M_adjoint(c)


def periodic_positions(c: Curve) -> np.ndarray:
    """Node positions with the closure gap spread linearly: ``gamma - s (int tau dsigma)``.

    ``gamma = gamma0 + D tau`` misses closing by ``int tau dsigma`` (quadrature error of
    the cumulative integral on finite-difference grids, O(h^2) for a closed curve). Left
    at the seam, that gap is a jump which second differences amplify by 1/h^2 into an
    O(1) defect of ``M rigid`` and ``M-dagger Psi`` at the last node; spread over
    ``s in [0, 1)`` it is a smooth O(h^2) change.

    Parameters
    ----------
    c : Curve

    Returns
    -------
    ndarray, shape (2, N)

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, FiniteDifference, geometry
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), FiniteDifference(64))
    >>> gap = np.linalg.norm(c.closure()[:2])
    >>> shift = np.abs(geometry.periodic_positions(c) - c.positions()).max()
    >>> bool(shift <= gap), bool(gap < 1e-2)
    (True, True)
    """
    gap = c.closure()[:2]
    return c.positions() - gap[:, None] * c.grid.s[None, :]


def rigid_motions(c: Curve) -> np.ndarray:
    """Extrinsic fields of the rigid motions (lem:kerM), shape (3, 2N).

    Rows: translation along e1 ``(e1.n, e1.tau)``, along e2 ``(e2.n, e2.tau)``,
    and rotation about the origin ``(gamma.tau, -gamma.n)``.

    Parameters
    ----------
    c : Curve

    Returns
    -------
    ndarray, shape (3, 2N)
        Stacked ``[V^n, V^tau]`` per row; ``M(c) @ rigid_motions(c).T ~= 0``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> R = geometry.rigid_motions(c)
    >>> R.shape, bool(np.allclose(R[2, :17], 0.0)), bool(np.allclose(R[2, 17:], -1.0))
    ((3, 34), True, True)
    """
    tau, n = c.tangent(), c.normal()
    gam = periodic_positions(c)
    return np.array([
        np.concatenate([n[0], tau[0]]),
        np.concatenate([n[1], tau[1]]),
        np.concatenate([np.sum(gam * tau, 0), -np.sum(gam * n, 0)]),
    ])


def constraint_gradients(c: Curve) -> np.ndarray:
    """``Psi_j = nabla_I C_j`` in ``<.,.>``, spanning ker M-dagger, shape (3, 2N).

    Notes
    -----
    # NOTE: position form (Conventions and errata, section 2):
    # Psi1 = (y - y0, (kappa (y - y0) + tau_x)/g),
    # Psi2 = (-(x - x0), (-kappa (x - x0) + tau_y)/g), Psi3 = (1, kappa/g). It equals
    # the paper's D-dagger form e:Psi1-e:Psi2 on closed curves but, unlike it, converges
    # with second-order differences -- with the positions' closure gap spread over S
    # (:func:`periodic_positions`); at the seam it would leave an O(1) defect.

    Parameters
    ----------
    c : Curve

    Returns
    -------
    ndarray, shape (3, 2N)
        Stacked ``[d_kappa C_j, d_g C_j]`` per row: gradients in
        ``<f, h> = int f h dsigma``, so ``C_j(U + d U1) ~= C_j(U) + d <Psi_j, U1>``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(65))
    >>> Psi = geometry.constraint_gradients(c)
    >>> U1 = np.concatenate([np.cos(2 * np.pi * c.grid.s), np.sin(4 * np.pi * c.grid.s)])
    >>> d = 1e-6
    >>> fd = (c.with_U(c.U + d * U1).closure() - c.with_U(c.U - d * U1).closure()) / (2 * d)
    >>> exact = Psi @ (U1 * np.concatenate([c.dsigma, c.dsigma]))
    >>> bool(np.allclose(fd, exact, atol=1e-7))
    True
    """
    x, y = periodic_positions(c)
    x0, y0 = c.origin
    tau = c.tangent()
    k, g = c.kappa, c.g
    return np.array([
        np.concatenate([y - y0, (k * (y - y0) + tau[0]) / g]),
        np.concatenate([-(x - x0), (-k * (x - x0) + tau[1]) / g]),
        np.concatenate([np.ones_like(k), k / g]),
    ])


def D_matrix(c: Curve) -> np.ndarray:
    """Dense matrix of ``D f = int_0^s f dsigma`` (e:D_def).

    Parameters
    ----------
    c : Curve

    Returns
    -------
    ndarray, shape (N, N)
        ``D_matrix(c) @ f == c.D(f)``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> bool(np.allclose(geometry.D_matrix(c) @ c.kappa, c.theta() - c.theta0))
    True
    """
    return c.grid.cumulative_matrix() * c.g[None, :]


def D_adjoint_matrix(c: Curve) -> np.ndarray:
    """Dense matrix of ``D-dagger f = int_s^1 f dsigma = int f dsigma - D f``.

    ``D-dagger`` is the adjoint of ``D`` in ``<f, h> = int f h dsigma`` (up to the
    quadrature of the discontinuous integrand at the seam).

    Parameters
    ----------
    c : Curve

    Returns
    -------
    ndarray, shape (N, N)

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> Dd = geometry.D_adjoint_matrix(c)
    >>> bool(np.allclose(Dd @ np.ones(17), 2 * np.pi * (1 - c.grid.s)))
    True
    """
    return c.dsigma[None, :] - D_matrix(c)


def constraint_hessians(c: Curve, form="dense") -> list:
    """Second variations of the closure constraints ``C_1, C_2, C_3``.

    With ``C(U + delta U1) = C + delta <Psi, U1> + delta^2/2 <H_C U1, U1>``: Hessians
    with respect to ``<f, h> = int f h dsigma``.

    Parameters
    ----------
    c : Curve
    form : {"dense", "factored", "auto"}
        How ``H_C1``, ``H_C2`` are returned (:func:`qsa.closure.closure_hessian`):
        dense ndarrays (default, O(N^2) memory) or, on finite-difference grids,
        :class:`~qsa.linalg.ReducedHessian` (O(N) storage and products).

    Returns
    -------
    list of three matrices, shape (2N, 2N)
        ``H_C1``, ``H_C2`` (they contain the integral operators D and D-dagger);
        ``H_C3`` has the grid's matrix type. Each is exactly dsigma-self-adjoint
        (H_C1 and H_C2 are symmetrised).

    Notes
    -----
    # NOTE: e:cC-Hessian and e:cC-Hessian3 as printed are wrong (Conventions and errata, section 4).
    # Implemented (qsa.closure): H_C3 = [[0, 1/g], [1/g, 0]], and for j = 1, 2 with
    # eta = kappa1 + kappa g1/g, B = D-dagger(tau'_j g1/g), C = D-dagger(tau_j D eta):
    #   (H_Cj U1)_kappa = (g1/g) D-dagger tau'_j + B - C,
    #   (H_Cj U1)_g     = (kappa1/g) D-dagger tau'_j + tau'_j (D eta)/g + (kappa/g)(B - C).
    # B, D eta and C jump across s = 0 == 1; with the mean value at node 0 the
    # quadratic form is second order on both grid kinds (checked against exact
    # second differences of C in the tests).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
    >>> H = geometry.constraint_hessians(c)
    >>> U1 = np.concatenate([np.cos(2 * np.pi * c.grid.s), 0.1 * np.ones(33)])
    >>> d, w = 1e-3, np.concatenate([c.dsigma, c.dsigma])
    >>> C = lambda t: c.with_U(c.U + t * U1).closure()
    >>> second = (C(d) - 2 * C(0) + C(-d)) / d**2
    >>> exact = np.array([(Hj @ U1) @ (U1 * w) for Hj in H])
    >>> bool(np.allclose(second, exact, atol=1e-2 * np.abs(exact).max()))  # O(h^2)
    True
    """
    if form not in ("dense", "factored", "auto"):
        raise ValueError(f"form must be 'dense', 'factored' or 'auto', got {form!r}")
    return [closure_hessian(c, np.eye(3)[0], form), closure_hessian(c, np.eye(3)[1], form),
            curvature_closure_hessian(c)]


def reparameterization_mode(c: Curve, v) -> np.ndarray:
    """``M (0, v) = (v nabla_s kappa, g nabla_s v)``: the intrinsic change under a tangential flow.

    Parameters
    ----------
    c : Curve
    v : array_like, shape (N,)
        Tangential velocity.

    Returns
    -------
    ndarray, shape (2N,)
        Stacked ``[kappa_t, g_t]``, equal to ``M(c) @ [0, v]``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
    >>> v = np.sin(2 * np.pi * c.grid.s)
    >>> rep = geometry.reparameterization_mode(c, v)
    >>> bool(np.allclose(rep, geometry.M(c) @ np.concatenate([np.zeros(33), v])))
    True
    """
    v = np.asarray(v, dtype=float)
    return np.concatenate([v * c.grad_s(c.kappa), c.g * c.grad_s(v)])
