r"""The splice manifold on a quadrature grid: the fields the front-position ODE is made of.

On the manifold of heteroclinic splices ``psi_N(p)`` (e:psi_N; built by
:class:`qsa.equilibria.SpliceProfile`) the curve has uniform ``g = L`` and arc length
``sigma = L s``. One evaluation of the fronts gives everything the reduced dynamics
(:class:`qsa.reduction.FrontODE`) needs, collected in :class:`SpliceFields` on the
nodes of a :class:`PeriodicQuadrature`; the functions below turn them into the
pulled-back normal velocities (hence the metric), the energy and its gradient, the
closure constraints and, for a variable length, the derivatives in ``L``.

Derivation
----------
*The metric of the flow.* In intrinsic coordinates ``U = (kappa, g)`` the faceting
flow is ``U_t = -M M^dagger grad_I E + M(0, v)`` (e:FoE_IG), where ``M(0, v)`` is a
reparameterization (the tangential gauge; the DAE of :mod:`qsa.flows.dae` picks ``v``
so that ``g`` stays uniform). On ``range M`` the flow is the gradient flow of ``E``
for the metric ``<U1, (M M^dagger)^+ U1>``: with ``U1 = M w``, ``w = (phi, v)`` the
extrinsic (normal, tangential) velocity and ``M = A S B^T`` a singular value
decomposition, ``(M M^dagger)^+ M w = A S^{-1} B^T w`` and ::

    <M w, (M M^dagger)^+ M w> = |B^T w|^2 = min_{r in ker M} |w - r|^2_{L2(dsigma)},

the ``L^2(dsigma)`` norm of the velocity modulo rigid motions (``ker M``).
Reparameterizations cost nothing in the flow (the energy is invariant and the gauge
is free), so the metric the flow induces on shapes is the quotient by ``v``:
minimising over ``v`` removes the tangential part and the tangential components of
the rigid motions, leaving ::

    |U1|^2 = min_{c in R^3} int (phi - c . r^n)^2 dsigma,
    r^n = (e1 . n, e2 . n, gamma . tau),

the normal velocity modulo rigid normal velocities. This is the metric of
``V^n = -[M^dagger grad_I E]_1`` itself: ``dE/dt = -int (V^n)^2 dsigma``.

*Pull-back.* On the splice manifold (``L = L*`` so the perimeter penalty is
balanced) the curve is ``gamma(sigma) = int_0^sigma tau(theta) dsigma'`` with
``theta(sigma) = int_0^sigma psi_N``. A change of ``p_j`` changes the angle by
``Theta_j(sigma) = int_0^sigma d psi_N / d p_j`` and, since ``d tau / d theta = -n``,
the position by ``d gamma / d p_j = -int_0^sigma n Theta_j dsigma'``. Its normal
velocity is ::

    phi_j = n . d gamma / d p_j,   phi_j^perp = phi_j - (projection on span r^n)

(:func:`normal_velocities`), and the pulled-back metric is the Gram matrix ::

    G_ij = int phi_i^perp phi_j^perp dsigma       (2N x 2N, positive semi-definite).

A common shift of all ``p_j`` only moves the base point (a rigid motion of the
shape): ``G 1 = 0``.

*Energy and constraints.* With ``L`` fixed,
``E(p) = int alpha^2/2 psi_N'^2 + W(psi_N) dsigma`` (:func:`energy`) and, integrating
by parts, ::

    dE/dp_j = int R_kappa d psi_N / d p_j dsigma,    R_kappa = -alpha^2 psi_N'' + W'(psi_N)

(:func:`energy_gradient`), an exponentially small interaction force
(``~ exp(-kstar d / (sqrt 2 alpha))``, ``d`` the spacing of neighbouring fronts). The
closure constraints ``C(p) = 0`` (e:C1 two components, e:C2 the total turning; see
:func:`qsa.equilibria.splice_closure`) are :func:`closure`.

*Variable length.* Lengthening the curve at fixed ``p`` inserts arc at the base point
``sigma = L ~ 0`` (the middle of the last facet) and moves no point of ``[0, L)``: it
has no normal velocity, but it changes ``C`` and, through the images of the fronts
across the base point, ``E`` (:func:`length_derivatives`). Both are evaluated without
seam errors by writing ``d psi/dL = g_L - (sigma/L) psi'`` with ``g_L`` smooth and
periodic (:attr:`SpliceFields.g_L`) and integrating the last term by parts.

All integrals are of smooth periodic functions, so the trapezoid sums and the
spectral cumulative integrals of :class:`PeriodicQuadrature` are spectrally accurate.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsa.discretize import Fourier
from qsa.equilibria.profile import SpliceProfile

__all__ = ["PeriodicQuadrature", "SpliceFields", "splice_fields", "normal_velocities",
           "closure", "residual", "energy", "energy_gradient", "length_derivatives",
           "quadrature_size"]


def quadrature_size(length, width, points_per_width):
    """Nodes ``M`` for ``points_per_width`` nodes per front ``width`` on ``length`` (>= 255).

    The smallest odd ``M`` with no prime factor above 7 (fast FFTs; odd: no Nyquist mode).

    Examples
    --------
    >>> quadrature_size(3.0, 0.01, 3.0)  # 900 -> 945 = 3^3 5 7
    945
    """
    M = int(np.ceil(max(points_per_width * length / width, 255)))
    M += 1 - M % 2
    while True:
        r = M
        for q in (3, 5, 7):
            while r % q == 0:
                r //= q
        if r == 1:
            return M
        M += 2


@dataclass(frozen=True)
class PeriodicQuadrature:
    """Nodes, weights and batched cumulative integrals on ``S = [0, 1)`` (Fourier, odd ``M``).

    Parameters
    ----------
    M : int
        Number of nodes ``s_i = i / M`` (odd).

    Examples
    --------
    >>> import numpy as np
    >>> quad = PeriodicQuadrature(17)
    >>> F = quad.cumulative(np.cos(2 * np.pi * quad.s)[:, None])
    >>> bool(np.allclose(F[:, 0], np.sin(2 * np.pi * quad.s) / (2 * np.pi)))
    True
    """

    M: int
    grid: Fourier = field(init=False, repr=False, compare=False)
    _inv_ik: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        M = int(self.M)
        if M < 3 or M % 2 == 0:
            raise ValueError(f"M must be an odd number of nodes >= 3, got {self.M!r}")
        object.__setattr__(self, "grid", Fourier(M))
        kk = np.arange(M // 2 + 1)
        object.__setattr__(self, "_inv_ik", np.where(
            kk == 0, 0.0, 1 / (2j * np.pi * np.maximum(kk, 1)))[:, None])

    @property
    def s(self):
        """Nodes on ``[0, 1)``, shape (M,)."""
        return self.grid.s

    @property
    def weights(self):
        """Quadrature weights on ``[0, 1)`` (the trapezoid rule, ``1/M``), shape (M,)."""
        return self.grid.weights

    def cumulative(self, F, twice=None):
        """``int_0^s F`` (unit period, along axis 0) of periodic columns by one real FFT pair.

        Parameters
        ----------
        F : ndarray, shape (M, n)
        twice : sequence of int, optional
            Column indices whose double integral ``int_0^s int_0^s' F`` is also wanted.

        Returns
        -------
        ndarray, shape (M, n)
            Same as ``Fourier.cumulative``; with ``twice`` also the double integrals of
            those columns, shape (M, len(twice)), as a second result.
        """
        M = F.shape[0]
        s = self.grid.s[:, None]
        Fh = np.fft.rfft(F, axis=0)
        mean = Fh[0].real / M
        inv = self._inv_ik
        Ph = Fh * inv
        if twice is not None:
            Ph = np.concatenate([Ph, Ph[:, twice] * inv], axis=1)
        P = np.fft.irfft(Ph, n=M, axis=0)
        n = F.shape[1]
        out = P[:, :n] - P[0, :n] + mean * s
        if twice is None:
            return out
        P1, Q, mt = P[:, twice], P[:, n:], mean[twice]
        return out, Q - Q[0] - P1[0] * s + 0.5 * mt * s**2


    def cumulative_transpose(self, Y):
        """The transpose of :meth:`cumulative` (as a linear map of the columns), shape (M, n).

        ``y . cumulative(F) = cumulative_transpose(y) . F`` for all ``F``: the exact
        gradient of a functional of the cumulative integrals on the nodes.
        """
        M = Y.shape[0]
        Yh = np.fft.rfft(Y, axis=0) * np.conj(self._inv_ik)
        Pt = np.fft.irfft(Yh, n=M, axis=0)  # transpose of the periodic part
        e0 = np.zeros((M, 1))
        e0[0] = 1.0
        P0 = np.fft.irfft(np.fft.rfft(e0, axis=0) * np.conj(self._inv_ik), n=M, axis=0)
        return Pt - P0 * Y.sum(axis=0) + (self.grid.s @ Y) / M


@dataclass(frozen=True, eq=False)
class SpliceFields:
    """The splice ``psi_N(p)`` and what the reduction needs of it, on ``sigma_i = L s_i``.

    Attributes
    ----------
    psi, dpsi, d2psi : ndarray, shape (M,)
        ``psi_N``, ``psi_N'``, ``psi_N''`` (derivatives in arc length).
    dpsi_dp : ndarray, shape (M, 2N)
        ``d psi_N / d p_j``.
    weights : ndarray, shape (M,)
        Quadrature weights ``dsigma`` (``L / M``): ``int f dsigma ~ f @ weights``.
    theta : ndarray, shape (M,)
        Tangent angle ``int_0^sigma psi_N`` (``theta(0) = 0``).
    Theta : ndarray, shape (M, 2N)
        ``Theta_j = int_0^sigma d psi_N / d p_j``.
    length : float
        ``L``.
    s : ndarray, shape (M,)
        Nodes on ``[0, 1)``.
    d2psi_dp2 : ndarray, shape (M, 2N), or None
        ``d^2 psi_N / d p_j^2`` (each front's own second derivative).
    g_L, dg_L, Theta_L : ndarray, shape (M,), or None
        Variable length only: ``g_L = d psi_N/dL + (sigma/L) psi_N'`` (smooth and
        periodic; ``d/dL`` at fixed ``p``), its derivative in ``sigma`` and
        ``int_0^sigma d psi_N/dL``.
    dpsi_dp_L : ndarray, shape (M, 2N), or None
        Variable length only: ``d/dL`` of ``dpsi_dp`` on the nodes (at fixed ``s``,
        like ``g_L``; smooth and periodic).
    """

    psi: np.ndarray
    dpsi: np.ndarray
    d2psi: np.ndarray
    dpsi_dp: np.ndarray
    weights: np.ndarray
    theta: np.ndarray
    Theta: np.ndarray
    length: float
    s: np.ndarray
    d2psi_dp2: np.ndarray | None = None
    g_L: np.ndarray | None = None
    dg_L: np.ndarray | None = None
    Theta_L: np.ndarray | None = None
    dpsi_dp_L: np.ndarray | None = None


def splice_fields(front, positions, length, cutoff, quadrature, variable=False):
    """:class:`SpliceFields` of the splice at ``positions`` from one evaluation of the fronts.

    Parameters
    ----------
    front : Heteroclinic
    positions : array_like, shape (2N,)
        Front positions (up, down, up, ...; see :func:`qsa.equilibria.splice`).
    length : float
        ``L``.
    cutoff : (float, float)
        ``(l1, l2)`` of the cut fronts (:class:`qsa.equilibria.SpliceProfile`).
    quadrature : PeriodicQuadrature
    variable : bool
        Also the fields of ``d/dL`` (``g_L``, ``dg_L``, ``Theta_L``).

    Returns
    -------
    SpliceFields

    Examples
    --------
    >>> import numpy as np
    >>> from qsa.equilibria import default_cutoff, heteroclinic
    >>> from qsa.equilibria.splice import polygon_positions
    >>> p, L = polygon_positions(np.radians([120, 120, 120]), [1.0, 1.0, 1.0], 5.0)
    >>> f = splice_fields(heteroclinic(0.1, kstar=5.0), p, L, default_cutoff(p, L),
    ...                   PeriodicQuadrature(1215))
    >>> f.dpsi_dp.shape, bool(abs(f.psi @ f.weights - 2 * np.pi) < 1e-12)  # e:C2
    ((1215, 6), True)
    """
    L = float(length)
    prof = SpliceProfile(front, positions, L, cutoff)
    s = L * quadrature.s
    y = s[:, None] - prof.c
    y -= L * np.floor(y / L + 0.5)  # prof.local(s): wrapped into [-L/2, L/2)
    M, m = s.size, prof.a.size
    X = np.empty((M, 2 * m))  # columns up_1, down_1, up_2, ... (the order of p)
    X[:, 0::2] = y + prof.a
    X[:, 1::2] = y - prof.a
    v0, v1, v2 = prof.cut_front(X)
    sgn = np.tile([1.0, -1.0], m)  # psi_N = sum up - sum down
    psi, d1, d2 = v0 @ sgn, v1 @ sgn, v2 @ sgn
    dpsi = -sgn * v1
    w = L * quadrature.weights
    common = {"psi": psi, "dpsi": d1, "d2psi": d2, "dpsi_dp": dpsi, "weights": w,
              "length": L, "s": quadrature.s, "d2psi_dp2": sgn * v2}
    if not variable:
        cum = L * quadrature.cumulative(np.column_stack([psi, dpsi]))
        return SpliceFields(theta=cum[:, 0], Theta=cum[:, 1:], **common)
    # d/dL at fixed p moves the periodic images: y = (sigma - c) - k L, dy/dL = -k
    # psi_L jumps at the seam sigma = L ~ 0; g = psi_L + (sigma/L) psi' is smooth
    k = np.repeat(np.rint((s[:, None] - prof.c - y) / L), 2, axis=1) * sgn
    x = s / L
    g = -(k * v1).sum(axis=1) + x * d1
    dg = -(k * v2).sum(axis=1) + d1 / L + x * d2
    F = np.empty((M, 2 * m + 2))
    F[:, 0], F[:, 1:-1], F[:, -1] = psi, dpsi, g
    cum = L * quadrature.cumulative(F)
    theta, Theta = cum[:, 0], cum[:, 1:-1]
    Theta_L = cum[:, -1] - x * psi + theta / L  # int_0^sigma psi_L, pointwise
    # d/dL at fixed s of -sgn v1(y +- a): -sgn v2 (s - image index)
    dP_L = k * v2 - x[:, None] * common["d2psi_dp2"]
    return SpliceFields(theta=theta, Theta=Theta, g_L=g, dg_L=dg, Theta_L=Theta_L,
                        dpsi_dp_L=dP_L, **common)


def normal_velocities(fields, quadrature):
    """``phi_j^perp``: normal velocity per unit ``p_j'`` modulo rigid motions, shape (M, 2N).

    ``d gamma / d p_j = -int_0^sigma n Theta_j``. ``Theta_j = (periodic) + c_j s``, so
    with ``m = int_0^s n ds'`` (periodic on a closed curve) and ``int_0^s s' n ds' =
    s m - int_0^s m ds'`` every cumulative integral is of a periodic function:
    spectral accuracy, no end corrections, one real FFT pair for all of them. The
    rigid normal velocities ``r^n`` are projected out in ``L^2(dsigma)``.

    Parameters
    ----------
    fields : SpliceFields
    quadrature : PeriodicQuadrature
        The grid ``fields`` live on.

    Returns
    -------
    ndarray, shape (M, 2N)
    """
    theta, Theta, w = fields.theta, fields.Theta, fields.weights
    L, s = fields.length, fields.s
    k = Theta.shape[1]
    c = (L / s.size) * fields.dpsi_dp.sum(axis=0)  # Theta_j(L)
    cs, sn_ = np.cos(theta), np.sin(theta)
    Y = np.empty((s.size, 4 + 2 * k))
    Y[:, 0], Y[:, 1], Y[:, 2], Y[:, 3] = cs, sn_, sn_, -cs  # tau, n
    periodic = Theta - s[:, None] * c
    np.multiply(sn_[:, None], periodic, out=Y[:, 4:4 + k])
    np.multiply(-cs[:, None], periodic, out=Y[:, 4 + k:])
    cum, mm = quadrature.cumulative(Y, twice=[2, 3])  # mm = int_0^s m
    gx, gy = L * cum[:, 0], L * cum[:, 1]
    m = cum[:, 2:4]
    sn = s[:, None] * m - mm  # int_0^s s' n ds'
    dgx = -L * (cum[:, 4:4 + k] + sn[:, 0:1] * c)
    dgy = -L * (cum[:, 4 + k:] + sn[:, 1:2] * c)
    phi = sn_[:, None] * dgx - cs[:, None] * dgy
    R = np.column_stack([sn_, -cs, gx * cs + gy * sn_])
    Rw = R.T * w
    coef = np.linalg.solve(Rw @ R, Rw @ phi)
    return phi - R @ coef


def closure(fields):
    """``C(p)`` (shape (3,), as :func:`qsa.equilibria.splice_closure`) and ``dC/dp`` (3, 2N).

    ``C = (int cos theta, int sin theta, int psi_N - 2 pi)`` (e:C1, e:C2);
    ``dC/dp_j = (-int sin theta Theta_j, int cos theta Theta_j, int d psi_N/d p_j)``.
    """
    c, s, w = np.cos(fields.theta), np.sin(fields.theta), fields.weights
    C = np.array([c @ w, s @ w, fields.psi @ w - 2 * np.pi])
    return C, np.vstack([-(s * w) @ fields.Theta, (c * w) @ fields.Theta, w @ fields.dpsi_dp])


def residual(fields, alpha, well):
    """``R_kappa = -alpha^2 psi_N'' + W'(psi_N)`` on the nodes, shape (M,)."""
    return -(alpha**2) * fields.d2psi + well.dW(fields.psi)


def energy(fields, alpha, well):
    """``E(psi_N(p)) = int alpha^2/2 psi_N'^2 + W(psi_N) dsigma``."""
    return float((0.5 * alpha**2 * fields.dpsi**2 + well.W(fields.psi)) @ fields.weights)


def energy_gradient(fields, alpha, well, R=None):
    """``dE/dp_j = int R d psi_N/d p_j dsigma``, shape (2N,).

    ``R`` defaults to the splice's own residual :func:`residual`; the Newton-corrected
    force passes the corrected one (:func:`qsa.reduction.correction.newton_correction`).
    """
    R = residual(fields, alpha, well) if R is None else R
    return (R * fields.weights) @ fields.dpsi_dp


def length_derivatives(fields, alpha, well):
    """``dE_facet/dL`` (float) and ``dC/dL`` (shape (3,)) at fixed ``p``.

    ``E = int_0^L e dsigma`` gains the density at the end and the change of the images'
    tails; ``C`` likewise (``theta(L) = 2 pi + C_3``). Needs the variable-length fields
    (``splice_fields(..., variable=True)``).
    """
    if fields.g_L is None:
        raise ValueError("length_derivatives needs fields of splice_fields(..., variable=True)")
    a2 = alpha**2
    psi, d1, w, L = fields.psi, fields.dpsi, fields.weights, fields.length
    # with psi_L = g - (sigma/L) psi' and integration by parts every integral is
    # of a smooth periodic function (spectral accuracy):
    e = 0.5 * a2 * d1**2 + well.W(psi)
    dE = (well.dW(psi) * fields.g_L + a2 * d1 * fields.dg_L) @ w + ((e - a2 * d1**2) @ w) / L
    int_psi_L = fields.g_L @ w - psi[0] + (psi @ w) / L
    tL = fields.theta[0] + psi @ w  # theta(L)
    c, s_ = np.cos(fields.theta), np.sin(fields.theta)
    # Theta_L jumps by int psi_L at the seam: end-corrected (trapezoid) sums
    h2 = 0.5 * w[0]
    dC1 = np.cos(tL) - (s_ * fields.Theta_L) @ w - h2 * np.sin(tL) * int_psi_L
    dC2 = np.sin(tL) + (c * fields.Theta_L) @ w + h2 * np.cos(tL) * int_psi_L
    dC = np.array([dC1, dC2, psi[0] + int_psi_L])
    return float(dE), dC
