r"""Slow modes of the front-position ODE as normal perturbations of the curve, and mode pairing.

The reduced linearization (:meth:`qsa.reduction.FrontODE.jacobian`) acts on front
displacements ``q`` tangent to the closure constraints; the full linearization of the
faceting flow in the normal gauge (:func:`qsa.spectra.spectrum`, ``gauge="normal"``,
the operator ``J = -[M^dagger L_Lambda M(., 0)]_1``) acts on normal perturbations ``phi``
of the curve. To compare their eigenvalues mode by mode, both are brought to the
same space.

*From front displacements to normal perturbations.* Moving the fronts by ``q``
changes the curvature by ``kappa_1 = sum_j q_j d psi_N / d p_j`` (a front ``p_i``
moved by ``dp_i`` shifts its own profile: ``-(+-) psi_h'(sigma - p_i) dp_i``). In
intrinsic coordinates a perturbation is ``U_1 = M (phi, v)``, whose first row is
``kappa_1 = G phi + v kappa'`` (``G = -Delta_s - kappa^2``): the normal part ``phi``
solves ``G phi = kappa_1`` modulo the tangential gauge ``v`` and the rigid motions
(``ker M``). The splice manifold gives ``phi`` directly, without solving: ``phi_j`` is
the normal component of ``d gamma / d p_j`` (:func:`qsa.reduction.manifold.normal_velocities`;
its ``G phi_j`` equals ``d psi_N / d p_j`` up to ``v_j kappa'`` with ``v_j = tau . d
gamma / d p_j``), so

    phi(q) = sum_j q_j phi_j^perp,

the rigid normal motions projected out in ``L^2(dsigma)`` -- the space the deflated
full eigenvectors live in. :func:`normal_modes` returns these fields.

*Pairing.* With ``<f, h> = int f h dsigma`` on the full curve's nodes the cosine
``|<phi_a^full, phi_b^red>| / (|phi_a^full| |phi_b^red|)`` measures how far a reduced
mode is a full one; the full eigenvectors are orthonormal, so the squared cosines of
one reduced mode over all computed full modes sum to the part of it inside their
span (its *capture*). :func:`pair_modes` assigns every reduced mode one full mode by
maximal total squared cosine (the Hungarian method,
:func:`scipy.optimize.linear_sum_assignment`): degenerate pairs (regular polygons)
are paired within their eigenspace, where any assignment gives the same eigenvalues,
and a fast mode that happens to be nearer ``0`` than a slow one is never chosen,
because a front displacement has no component along it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

__all__ = ["ReducedModes", "ModePairing", "reduced_modes", "normal_modes",
           "trig_interpolate", "pair_modes"]


@dataclass(frozen=True, eq=False)
class ReducedModes:
    """Eigenpairs of the reduced Jacobian on the splice manifold (:func:`reduced_modes`).

    Attributes
    ----------
    eigenvalues : ndarray, shape (m,)
        ``m = 2N - 4`` (fixed length; ``2N - 3`` with a variable length), sorted by
        real part, descending.
    displacements : ndarray, shape (2N, m)
        Front displacements ``q = T y`` of the eigenvectors ``y`` of ``T^T J T``
        (:meth:`FrontODE.tangent_basis`), unit Euclidean norm (with a variable
        length shape (2N + 1, m), the change of length last).
    normals : ndarray, shape (M, m)
        Their normal perturbations ``phi(q)`` on the ODE's quadrature nodes
        (:func:`normal_modes`), unit ``L^2(dsigma)`` norm.
    weights : ndarray, shape (M,)
        ``dsigma`` of the quadrature.
    """

    eigenvalues: np.ndarray
    displacements: np.ndarray
    normals: np.ndarray
    weights: np.ndarray


@dataclass(frozen=True, eq=False)
class ModePairing:
    """Which full mode each reduced mode is (:func:`pair_modes`).

    Attributes
    ----------
    index : ndarray of int, shape (m,)
        Column of the full eigenvector paired with each reduced mode.
    cosine : ndarray, shape (m,)
        ``|<phi^full, phi^red>|`` of the pairs (unit vectors).
    capture : ndarray, shape (m,)
        Squared norm of each reduced mode's projection on the span of all the full
        eigenvectors offered (1: it lies in their span).
    cosines : ndarray, shape (n_full, m)
        All cosines.
    """

    index: np.ndarray
    cosine: np.ndarray
    capture: np.ndarray
    cosines: np.ndarray


def normal_modes(ode, p, q, cutoff=None, L=None):
    """Normal perturbations ``phi(q) = sum_j q_j phi_j^perp`` on the ODE's nodes, (M, k).

    Parameters
    ----------
    ode : FrontODE
    p : array_like, shape (2N,)
    q : array_like, shape (2N,) or (2N, k)
        Front displacements; with ``L`` (a variable length) shape (2N + 1, ...), the
        change of length last (``phi_L^perp``, zero on the splice manifold, whose
        lengthening moves no point of the curve).
    cutoff : (float, float), optional
    L : float, optional
        The length of the variable-length reduction.

    Returns
    -------
    phi : ndarray, shape (M, k)
        Rigid normal motions projected out (module docstring).
    weights : ndarray, shape (M,)
        ``dsigma``.
    """
    q = np.asarray(q, dtype=float)
    if L is None:
        phi, w = ode.normal_velocities(p, cutoff)
        return phi @ q.reshape(phi.shape[1], -1), w
    e = ode.evaluate(p, cutoff, L)
    q = q.reshape(np.size(p) + 1, -1)
    return e.normal_velocities @ q[:e.normal_velocities.shape[1]], e.weights


def reduced_modes(ode, p, cutoff=None, L=None):
    """Eigenvalues, front displacements and normal perturbations of the reduced Jacobian.

    Parameters
    ----------
    ode : FrontODE
        The eigenvalues are those of :meth:`FrontODE.eigenvalues`.
    p : array_like, shape (2N,)
    cutoff : (float, float), optional
    L : float, optional
        With a variable length (``ode.beta``): linearize ``(p, L)`` there; the
        displacements then have the change of length last and the ``2N - 3`` modes
        include the perimeter mode.

    Returns
    -------
    ReducedModes

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import splice_polygon
    >>> from qsa.reduction import FrontODE
    >>> eq = splice_polygon(np.full(4, np.pi / 2), [0.4] * 4, 0.1, kstar=5.0)
    >>> ode = FrontODE(0.1, 5.0, eq.params["L"], backend="numpy")
    >>> m = reduced_modes(ode, eq.params["positions"])
    >>> m.eigenvalues.shape, m.normals.shape[1], bool(np.allclose(m.displacements.sum(0), 0))
    ((4,), 4, True)
    """
    p = np.asarray(p, dtype=float)
    _, JT = ode.jacobian(p, cutoff, L=L)
    T = ode.tangent_basis(p, cutoff, L)
    lam, Y = np.linalg.eig(JT)
    order = np.argsort(-lam.real)
    # a gradient flow in a metric: the eigenvalues are real (up to the differencing)
    lam, Y = lam[order].real, Y[:, order].real
    Q = T @ Y
    Q /= np.linalg.norm(Q, axis=0)
    phi, w = normal_modes(ode, p, Q, cutoff, L)
    phi /= np.sqrt(w @ phi**2)
    return ReducedModes(lam, Q, phi, w)


def trig_interpolate(values, s):
    """Trigonometric interpolation of periodic samples at ``i / M`` to the points ``s``.

    Parameters
    ----------
    values : ndarray, shape (M,) or (M, k)
        Samples at ``s_i = i / M`` (``M`` odd: no Nyquist mode).
    s : ndarray, shape (n,)
        Points in ``[0, 1)``.

    Returns
    -------
    ndarray, shape (n,) or (n, k)

    Examples
    --------
    >>> import numpy as np
    >>> f = np.cos(2 * np.pi * 3 * np.arange(15) / 15)
    >>> bool(np.allclose(trig_interpolate(f, np.array([0.1, 0.37])),
    ...                  np.cos(2 * np.pi * 3 * np.array([0.1, 0.37]))))
    True
    """
    v = np.asarray(values, dtype=float)
    M = v.shape[0]
    if M % 2 == 0:
        raise ValueError(f"values must have an odd number of samples, got {M}")
    c = np.fft.rfft(v, axis=0) / M
    k = np.arange(c.shape[0])
    E = np.exp(2j * np.pi * np.outer(np.asarray(s, dtype=float), k))
    coef = c.copy()
    coef[1:] *= 2
    return (E @ coef).real


def pair_modes(full, reduced, weights):
    """Pair reduced with full eigenvectors by maximal total squared cosine (Hungarian).

    Parameters
    ----------
    full : ndarray, shape (n, n_full)
        Full eigenvectors (normal perturbations) on the full curve's nodes.
    reduced : ndarray, shape (n, m)
        Reduced modes' normal perturbations on the same nodes (:func:`normal_modes`
        interpolated there), ``m <= n_full``.
    weights : ndarray, shape (n,)
        ``dsigma`` of the nodes.

    Returns
    -------
    ModePairing

    Raises
    ------
    ValueError
        Fewer full than reduced modes.

    Examples
    --------
    >>> import numpy as np
    >>> s = np.arange(31) / 31
    >>> full = np.column_stack([np.cos(2 * np.pi * k * s) for k in (1, 2, 3)])
    >>> red = full[:, [2, 0]] + 0.01 * np.sin(2 * np.pi * s)[:, None]
    >>> pair_modes(full, red, np.full(31, 1 / 31)).index.tolist()
    [2, 0]
    """
    F = np.asarray(full, dtype=float)
    R = np.asarray(reduced, dtype=float)
    w = np.asarray(weights, dtype=float)
    if R.shape[1] > F.shape[1]:
        raise ValueError(f"need at least as many full modes as reduced ones, got "
                         f"{F.shape[1]} < {R.shape[1]}")
    Fn = F / np.sqrt(w @ F**2)
    Rn = R / np.sqrt(w @ R**2)
    C = np.abs(Fn.T @ (w[:, None] * Rn))  # (n_full, m)
    rows, cols = linear_sum_assignment(-(C**2))
    index = np.empty(R.shape[1], dtype=int)
    index[cols] = rows
    m = np.arange(R.shape[1])
    return ModePairing(index, C[index, m], np.sum(C**2, axis=0), C)
