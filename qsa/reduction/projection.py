r"""The splice nearest a curve: least-squares projection onto the splice manifold.

After a collision (:func:`qsa.reduction.integrate.integrate_fronts`) the curve -- the
splice of the fronts before the pair's removal, the pair still a bump of curvature --
is not a splice of the surviving fronts. The flow relaxes it onto the slow manifold
along the fast directions, and those are, to first order, orthogonal to the manifold
in the flow's own metric: the faceting flow is the gradient flow of ``E`` for the
``L^2(dsigma)`` norm of the normal velocity modulo rigid motions (the derivation in
:mod:`qsa.reduction.manifold`), and the linearization of a gradient flow is
self-adjoint in its metric, so its fast and slow eigenspaces are orthogonal there.
:func:`nearest_splice` therefore picks the closed splice ``q`` (the front positions;
the length is the curve's) whose curve is nearest the given one in that norm ::

    min_q  min_{rigid}  int (n_q . (gamma - gamma_q))^2 dsigma   subject to  C(q) = 0,

with the two curves compared at equal arc length ``sigma`` (both have the length
``L``). Gauss-Newton steps: the displacement is put in the rigid frame nearest the
splice's (a weighted Procrustes fit of the positions), its rigid normal part is
projected out, and the step solves the same saddle-point system as the velocity of the
ODE (:class:`qsa.reduction.FrontODE`) with the force replaced by the displacement's
projection ``int phi_j^perp D dsigma``: ::

    [G  A^T] [dq]   [ Phi^T W D ]
    [A   0 ] [mu] = [ -C        ],    A = (dC/dq ; 1^T / sqrt(n)),

the last row fixing the common shift (it moves the base point only). Closing the
curve, not dropping the pair, decides where the pair's turning goes: where the
curve's shape changes least -- mostly to the neighbouring corners, as in the flow.
A splice is its own projection (the displacement vanishes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from qsa.equilibria.splice import default_cutoff
from qsa.reduction.manifold import closure, normal_velocities

__all__ = ["NearestSplice", "nearest_splice", "splice_distance"]


@dataclass(frozen=True)
class NearestSplice:
    """Result of :func:`nearest_splice`.

    Attributes
    ----------
    positions : ndarray, shape (2N,)
        The closed splice positions nearest the curve.
    distance : float
        ``sqrt(int D^2 dsigma)``, ``D`` the normal displacement modulo rigid
        motions, at ``positions``.
    initial_distance : float
        The same at the starting positions.
    closure : float
        ``|C|`` at ``positions`` (on the ODE's quadrature).
    iterations : int
    success : bool
        The last step was below ``tol`` times the front width.
    """

    positions: np.ndarray
    distance: float
    initial_distance: float
    closure: float
    iterations: int
    success: bool


def _curve(theta, quad, L):
    """Positions ``int_0^sigma tau(theta)`` on the quadrature, shape (M, 2)."""
    return L * quad.cumulative(np.column_stack([np.cos(theta), np.sin(theta)]))


def _target(ode, kappa, L):
    """The curve of ``kappa``: a periodic cubic spline of its positions in ``sigma``."""
    quad = ode._quadrature
    kappa = np.asarray(kappa, dtype=float)
    if kappa.shape != (quad.M,) or not np.all(np.isfinite(kappa)):
        raise ValueError(f"kappa must hold {quad.M} finite samples on the ODE's quadrature "
                         f"(sigma_i = L i / M), got shape {kappa.shape}")
    theta = L * quad.cumulative(kappa[:, None])[:, 0]
    X = _curve(theta, quad, L)
    sigma = L * np.append(quad.s, 1.0)
    return CubicSpline(sigma, np.vstack([X, X[:1]]), bc_type="periodic")


def _displacement(fields, target, quad, newton=4):
    """Normal distance ``D`` (M,) of the target curve from the splice, modulo rigid motions.

    The splice is put in the target's frame (weighted Procrustes fit at equal ``sigma``);
    at each node the foot on the target curve (where the chord is normal to the splice)
    is found by Newton steps along the target, so that ``D`` depends on the two shapes
    only, not on how their arc lengths are registered; its rigid normal part is
    projected out in ``L^2(dsigma)``.
    """
    th, w, L = fields.theta, fields.weights, fields.length
    sigma = L * fields.s
    X = _curve(th, quad, L)
    Xt = target(sigma)
    W = w / w.sum()
    xq, xt = X - W @ X, Xt - W @ Xt
    a = W @ (xt[:, 0] * xq[:, 0] + xt[:, 1] * xq[:, 1])
    b = W @ (xq[:, 0] * xt[:, 1] - xq[:, 1] * xt[:, 0])
    om = np.arctan2(b, a)  # rotates the splice onto the target
    Y = W @ Xt + np.column_stack([np.cos(om) * xq[:, 0] - np.sin(om) * xq[:, 1],
                                  np.sin(om) * xq[:, 0] + np.cos(om) * xq[:, 1]])
    t = np.column_stack([np.cos(th + om), np.sin(th + om)])
    u = sigma.copy()
    for _ in range(newton):
        d = target(u % L) - Y
        u -= np.einsum("ij,ij->i", t, d) / np.einsum("ij,ij->i", t, target(u % L, 1))
    d = target(u % L) - Y
    D = t[:, 1] * d[:, 0] - t[:, 0] * d[:, 1]  # n = (sin, -cos) of the rotated splice
    cs, sn = np.cos(th), np.sin(th)
    R = np.column_stack([sn, -cs, X[:, 0] * cs + X[:, 1] * sn])
    Rw = R.T * w
    return D - R @ np.linalg.solve(Rw @ R, Rw @ D)


def splice_distance(ode, kappa, positions, L=None, cutoff=None):
    """``sqrt(int D^2 dsigma)``: the curve of ``kappa`` from the splice at ``positions``.

    ``D`` is the normal displacement modulo rigid motions (see the module docstring).

    Parameters
    ----------
    ode : FrontODE
    kappa : ndarray, shape (M,)
        Curvature on the ODE's quadrature nodes ``sigma_i = L i / M``.
    positions : ndarray, shape (2N,)
    L : float, optional
        The length (default the ODE's).
    cutoff : (float, float), optional
        Default :func:`qsa.equilibria.default_cutoff` of ``positions``.

    Returns
    -------
    float
    """
    L = float(ode.length if L is None else L)
    target = _target(ode, kappa, L)
    q = np.asarray(positions, dtype=float)
    f = ode._reference.fields(q, cutoff or default_cutoff(q, L), L)
    D = _displacement(f, target, ode._quadrature)
    return float(np.sqrt(D**2 @ f.weights))


def nearest_splice(ode, kappa, positions, L=None, cutoff=None, tol=1e-6, max_iter=12):
    """The closed splice whose curve is nearest the curve of ``kappa`` (module docstring).

    Parameters
    ----------
    ode : FrontODE
        Supplies the front, the quadrature and the splice's fields (numpy reference).
    kappa : ndarray, shape (M,)
        Curvature of the curve on the ODE's quadrature nodes ``sigma_i = L i / M``
        (e.g. ``ode.fields(p, cut, L).psi`` of another splice); closed.
    positions : ndarray, shape (2N,)
        Starting positions (up, down, ...), increasing: the number of fronts and the
        first guess (e.g. :func:`qsa.reduction.integrate.remove_pair`'s).
    L : float, optional
        The curve's length (default the ODE's); kept.
    cutoff : (float, float), optional
        The splice's cutoff, fixed during the steps (default
        :func:`qsa.equilibria.default_cutoff` of ``positions``).
    tol : float
        Stop when the largest step is below ``tol`` front widths.
    max_iter : int

    Returns
    -------
    NearestSplice

    Raises
    ------
    ValueError
        Bad ``kappa``, or a step that makes fronts cross.

    Examples
    --------
    A splice is its own projection (from positions off it, with no common shift, which
    only moves the base point):

    >>> import numpy as np
    >>> from qsa.equilibria import splice_polygon
    >>> from qsa.reduction import FrontODE
    >>> quad = splice_polygon(np.radians([95, 85, 95, 85]), [0.5, 0.6, 0.5, 0.6], 0.1,
    ...                       kstar=5.0)
    >>> p, L = np.array(quad.params["positions"]), quad.params["L"]
    >>> ode = FrontODE(0.1, 5.0, L, backend="numpy")
    >>> off = p + 0.01 * np.array([1, -1, 0, 1, -1, 0, 1, -1])
    >>> r = nearest_splice(ode, ode.fields(p).psi, off)
    >>> bool(np.max(np.abs(r.positions - p)) < 1e-8), bool(r.distance < 1e-10)
    (True, True)
    """
    L = float(ode.length if L is None else L)
    target = _target(ode, kappa, L)
    q = np.asarray(positions, dtype=float).copy()
    n = q.size
    if n < 4 or n % 2 or np.any(np.diff(q) <= 0) or q[-1] - q[0] >= L:
        raise ValueError("positions must hold 2N >= 4 increasing positions spanning less "
                         "than L")
    cut = cutoff or default_cutoff(q, L)
    width = ode.front.width
    quad = ode._quadrature
    dist0, it, step = None, 0, np.inf
    while True:
        f = ode._reference.fields(q, cut, L)
        w = f.weights
        D = _displacement(f, target, quad)
        if dist0 is None:
            dist0 = float(np.sqrt(D**2 @ w))
        C, J = closure(f)
        if step <= tol * width or it >= max_iter:
            break
        phi = normal_velocities(f, quad)
        A = np.vstack([J, np.ones((1, n)) / np.sqrt(n)])
        K = np.zeros((n + 4, n + 4))
        K[:n, :n], K[:n, n:], K[n:, :n] = phi.T @ (w[:, None] * phi), A.T, A
        rhs = np.concatenate([phi.T @ (w * D), -C, [0.0]])
        dq = np.linalg.lstsq(K, rhs, rcond=1e-13)[0][:n]
        q = q + dq
        it += 1
        step = float(np.max(np.abs(dq)))
        if np.any(np.diff(q) <= 0) or q[-1] - q[0] >= L:
            raise ValueError("the projection onto the splice manifold makes fronts cross: "
                             "start from positions nearer the curve")
    return NearestSplice(q, float(np.sqrt(D**2 @ w)), dist0, float(np.linalg.norm(C)), it,
                         bool(step <= tol * width))
