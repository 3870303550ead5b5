r"""The slow-manifold correction: one Newton step from a splice towards the quasi-steady profile.

The splice ``psi_N`` superposes the fronts' tails linearly; the true quasi-steady
profile differs from it by the nonlinear response (through the curvature of ``W'``)
to the overlapping tails, of relative size ``O(exp(-lambda d / 2))`` in the centre of
a gap of width ``d``. One Newton step on the profile equation
``R(kappa) = -alpha^2 kappa'' + W'(kappa) = 0`` modulo the slow directions predicts it: ::

    H delta = -R(psi_N) - B mu,    B^T delta = 0,
    H = -alpha^2 d^2 + W''(psi_N),    B = [d psi_N / d p_1, ..., d psi_N / d p_2N, 1],

i.e. ``delta`` is orthogonal to the front translation modes and to a constant (the
positions and the total turning are kept), and ``mu`` absorbs the residual's component
along them (the force on the positions is what the reduction keeps). ``H delta = -R -
B mu`` gives the residual of ``psi_N + delta`` without applying ``d^2`` again: ::

    R(psi_N + delta) = N(delta) - B mu,    N(delta) = W'(psi + delta) - W'(psi) - W''(psi) delta,

quadratic in ``delta``. :func:`newton_correction` solves the bordered system with
periodic 8th-order central differences for ``d^2`` (:data:`D2_STENCIL`): a band
matrix (half-bandwidth 8) once the nodes are taken in folded order
(:func:`folded_band`), so one banded LU of ``H`` and the Schur complement
``B^T H^{-1} B`` (size ``2N + 1``) cost ``O(M (2N + 2))``.
:func:`newton_correction_dense` is the reference: spectral ``d^2``, a dense solve of
the bordered system (``O(M^3)``); the two agree to the difference error of ``d^2``.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dgbsv

__all__ = ["D2_STENCIL", "folded_band", "newton_correction", "newton_correction_dense"]

#: Periodic central differences for ``d^2/dx^2`` at unit spacing, 8th order: weights of
#: the offsets 0, +-1, ..., +-4.
D2_STENCIL = np.array([-205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560])


def folded_band(M, c):
    """A symmetric periodic band stencil as an ordinary band matrix in folded order.

    Ordering the nodes ``0, M-1, 1, M-2, ...`` puts periodic neighbours (also across
    the seam) at most ``2 m`` apart, so the periodic matrix is banded with half-bandwidth
    ``2 m`` and no corners.

    Parameters
    ----------
    M : int
        Number of nodes.
    c : ndarray, shape (m + 1,)
        Stencil weights of the offsets ``0, +-1, ..., +-m``.

    Returns
    -------
    perm : ndarray of int, shape (M,)
        The folded order: row ``i`` of the band matrix is node ``perm[i]``.
    ab : ndarray, shape (6 m + 1, M)
        The matrix in LAPACK ``gbsv`` layout (``kl = ku = 2 m``; ``2 m`` leading rows
        of fill-in space), Fortran order.

    Examples
    --------
    >>> import numpy as np
    >>> perm, ab = folded_band(7, np.array([-2.0, 1.0]))  # periodic second difference
    >>> kb = 2
    >>> A = np.zeros((7, 7))
    >>> for j in range(7):
    ...     for i in range(max(0, j - kb), min(7, j + kb + 1)):
    ...         A[i, j] = ab[2 * kb + i - j, j]
    >>> P = np.roll(np.eye(7), 1, 0) + np.roll(np.eye(7), -1, 0) - 2 * np.eye(7)
    >>> bool(np.array_equal(A, P[np.ix_(perm, perm)]))
    True
    """
    m = c.size - 1
    h = (M + 1) // 2
    perm = np.empty(M, dtype=int)
    perm[0::2] = np.arange(h)
    perm[1::2] = np.arange(M - 1, h - 1, -1)
    pos = np.empty(M, dtype=int)
    pos[perm] = np.arange(M)
    kb = 2 * m
    ab = np.zeros((3 * kb + 1, M))
    for d in range(-m, m + 1):
        i = np.arange(M)
        j = (i + d) % M
        ab[2 * kb + pos[i] - pos[j], pos[j]] += c[abs(d)]
    return perm, np.asfortranarray(ab)


def newton_correction(psi, d2psi, dpsi_dp, length, alpha, well, band):
    """One Newton step ``delta`` from ``psi`` and the residual of ``psi + delta`` (banded).

    Parameters
    ----------
    psi, d2psi : ndarray, shape (M,)
        The profile and its second arc-length derivative on ``sigma_i = L i / M``
        (``d2psi`` enters only the residual ``R = -alpha^2 d2psi + W'(psi)``).
    dpsi_dp : ndarray, shape (M, n)
        The slow directions (the front translation modes ``d psi_N / d p_j``); the
        constant is added.
    length : float
        ``L`` (the period in arc length).
    alpha : float
    well : object
        Double well with ``dW``, ``d2W``.
    band : (ndarray, ndarray)
        ``folded_band(M, D2_STENCIL)``.

    Returns
    -------
    delta : ndarray, shape (M,)
        Orthogonal (in the discrete sum) to the columns of ``dpsi_dp`` and to 1.
    R : ndarray, shape (M,)
        ``R(psi + delta) = N(delta) - B mu`` (see the module docstring).

    Notes
    -----
    Falls back to :func:`newton_correction_dense` when ``H`` is singular, and to least
    squares when the Schur complement is.
    """
    W, a2 = well, alpha**2
    M = psi.size
    perm, band = band
    kb = (band.shape[0] - 1) // 3
    d2W = W.d2W(psi)
    dW = W.dW(psi)
    R = -a2 * d2psi + dW
    ab = (-a2 * (M / length) ** 2) * band  # -alpha^2 d^2, unit-spacing stencil scaled
    ab[2 * kb] += d2W[perm]
    nb = dpsi_dp.shape[1] + 1
    rhs = np.empty((M, 1 + nb), order="F")
    rhs[:, 0] = -R[perm]
    rhs[:, 1:-1] = dpsi_dp[perm]
    rhs[:, -1] = 1.0
    _, _, X, info = dgbsv(kb, kb, ab, rhs, overwrite_ab=True, overwrite_b=True)
    if info != 0:  # H singular: the dense reference copes (least squares)
        return newton_correction_dense(psi, d2psi, dpsi_dp, length, alpha, well)
    B = np.column_stack([dpsi_dp[perm], np.ones(M)])
    S = B.T @ X[:, 1:]
    try:
        mu = np.linalg.solve(S, B.T @ X[:, 0])
    except np.linalg.LinAlgError:
        mu = np.linalg.lstsq(S, B.T @ X[:, 0], rcond=1e-12)[0]
    d = X[:, 0] - X[:, 1:] @ mu
    # B^T delta = 0 holds to the solve's round-off, which the near kernel of H
    # (the translation modes) amplifies to ~1e-9 relative: project it out exactly
    d -= B @ np.linalg.solve(B.T @ B, B.T @ d)
    delta = np.empty(M)
    delta[perm] = d
    Rc = (W.dW(psi + delta) - dW - d2W * delta) - dpsi_dp @ mu[:-1] - mu[-1]
    return delta, Rc


def newton_correction_dense(psi, d2psi, dpsi_dp, length, alpha, well):
    """Reference for :func:`newton_correction`: spectral ``d^2``, dense bordered solve.

    Same parameters and results (without ``band``); ``R`` is the residual of
    ``psi + delta`` with the spectral ``d^2`` applied to ``delta``.
    """
    W, a2, L = well, alpha**2, length
    M = psi.size
    k = 2 * np.pi * np.fft.fftfreq(M, d=1.0 / M)  # unit-length wavenumbers
    D2 = np.fft.ifft(-(k**2)[:, None] * np.fft.fft(np.eye(M), axis=0), axis=0).real / L**2
    R = -a2 * d2psi + W.dW(psi)
    B = np.column_stack([dpsi_dp, np.ones(M)])
    nb = B.shape[1]
    K = np.block([[-a2 * D2 + np.diag(W.d2W(psi)), B], [B.T, np.zeros((nb, nb))]])
    rhs = np.concatenate([-R, np.zeros(nb)])
    try:
        delta = np.linalg.solve(K, rhs)[:M]
    except np.linalg.LinAlgError:
        delta = np.linalg.lstsq(K, rhs, rcond=1e-12)[0][:M]
    Rc = -a2 * (d2psi + D2 @ delta) + W.dW(psi + delta)
    return delta, Rc
