r"""The manifold of constrained quasi-steady profiles: the splice corrected to convergence.

The splice ``psi_N(p)`` (:mod:`qsa.reduction.manifold`) superposes the fronts' tails
linearly and keeps the plateaus at the wells; the one-Newton-step correction
(:mod:`qsa.reduction.correction`) keeps them there too (``delta`` orthogonal to 1).
Where two fronts overlap strongly -- the corners of a polygon with many corners,
``2 pi / (n kstar)`` long -- the equilibrium is not like that: the N-pulse's residual
is the turning multiplier ``nu``, which lifts every plateau by ``nu / W''`` (0.042
on the octagon with facets 0.35), so the facets curve and the corners shorten, and
every interaction changes with them. The slow eigenvalues depend on that at
second order in the corner overlap, which exceeds the facets' first-order
interaction. This module builds the manifold that contains the exact equilibrium.

*The profile.* At positions ``p`` the profile ``kappa = psi_N + delta`` solves ::

    R(kappa) = -alpha^2 kappa'' + W'(kappa) = sum_j m_j psi_j + nu_1 + nu_2 c_x + nu_3 c_y,
    <delta, psi_j t_j> = 0  for every t with  dC/dp . t = 0,
    int delta = 0,   C1(kappa) = C1(psi_N),

``psi_j = d psi_N / d p_j``, ``m`` tangent to the closure (``dC/dp . m = 0``, ``C``
the splice's closure, :func:`qsa.reduction.manifold.closure`), and ``(c_x, c_y) = d
C1 / d kappa`` (:func:`closure_gradients`). So the profile's residual is a force
along the reduced tangent space plus the multipliers of all three closure
constraints (``nu_1`` the turning multiplier), and the closure is the splice's: the
translation directions that change the closure are left to the multipliers, so a
perturbation that breaks the closure by moving fronts and restores it by bending the
facets costs what it costs in the full problem. ``2N`` gauge conditions, ``2N``
multipliers. On a regular polygon at the N-pulse's length the profile is the
N-pulse (``m = 0``, ``nu_2 = nu_3 = 0``; tested).

*Newton's method.* Each step solves the bordered system of the one-step correction
with ``B = [psi_p T, 1, c_x, c_y]`` (``T`` an orthonormal basis of the closure's
tangent space) at the current profile: one banded LU of ``H = -alpha^2 d^2 +
W''(kappa)`` (periodic 8th-order differences), from ``delta = 0``; 3-5 steps reach
round-off. ``d (c_x, c_y) / d kappa`` is not differentiated (its multipliers
``nu_2, nu_3`` are of the size of the slow forces).

*Tangents.* Differentiating the system in ``p_j`` gives ``kappa_j = d kappa / d p_j``
from the same factorization (2N more right-hand sides): ::

    H kappa_j = B dmu_j + m_j psi_jj + psi_p w_j - E_j,
    T^T psi_p^T kappa_j = T^T (psi_p^T psi_j - e_j <psi_jj, delta> + (d_j A)^T eta),
    sum kappa_j = sum psi_j,   dC1/dkappa . kappa_j = dC1/dp_j,

``psi_jj = d^2 psi_N / d p_j^2``; ``psi_p^T delta = A^T eta`` and ``w_j = -A^+ (d_j
A) m`` carry the turning of the tangent space with ``p`` (``A = dC/dp``, its
derivatives :func:`closure_hessians`), ``E_j`` the difference between the exact and
the differenced ``psi_j''`` (``R`` uses the exact ``psi_N''``). Checked against
differences of ``kappa(p)``: 1e-8 on a regular polygon, 1e-6 on an unequal triangle
(the undifferentiated ``nu_2, nu_3``).

*Variable length.* With ``L`` free the profile also depends on ``L``; on the nodes
(fixed ``s = sigma / L``) ``kappa_L = d kappa / dL`` comes from the same
factorization, differentiating the system at fixed ``p``: ::

    H kappa_L = B dmu_L + psi_pL m + psi_p w_L - E_L - 2 alpha^2 kappa'' / L,
    T^T psi_p^T kappa_L = T^T (psi_p^T g_L - psi_pL^T delta + A_L^T eta),
    sum kappa_L = sum g_L,   d C1(kappa, L) / dL = d C1(psi_N, L) / dL,

``g_L``, ``psi_pL`` the splice's and its tangents' ``d/dL`` at fixed ``s``
(:class:`qsa.reduction.manifold.SpliceFields`), ``A_L = dA/dL``,
``w_L = -A^+ A_L m`` the normal part of ``dm/dL``, ``E_L`` the exact minus the
differenced ``g_L''`` and ``-2 kappa'' / L`` the scaling of the second derivative.
Checked against differences of ``kappa(p, L)``: 3e-10 on the octagon, 3e-7 on an
unequal triangle. Unlike the splice's, whose lengthening moves no point of the curve,
the profile changes everywhere with ``L`` (the turning multiplier that lifts the
plateaus depends on it), so the length has a normal velocity ``phi_L``
(:func:`profile_normal_velocities`), a metric row and column, and a row and column
of the lag matrix; ``dE/dL`` and ``dC/dL`` are those of
:func:`qsa.reduction.manifold.length_derivatives` on ``kappa``. The rest point of the
length-free reduction on a regular polygon is then the N-pulse with its length
(the octagon with facets 0.35 and ``beta = 5``: 1.66e-3 longer than the splice, to
1e-13; the splice manifold rests 5e-4 *shorter*).

The reduction (:class:`qsa.reduction.FrontODE`, ``correction="profile"``) then uses
``kappa`` and ``kappa_j`` wherever the splice used ``psi_N`` and ``psi_j``: the metric,
the closure and the force ``dE/dp_j = int R(kappa) kappa_j``, the derivative of the
energy along the manifold (tested). It is the restriction of the gradient flow to
the manifold, so at a rest point on it the reduced Jacobian is the Rayleigh-Ritz
approximation of the full linearization on the manifold's tangent space.

*The lag.* A front moving at ``p'`` drags its profile, and the profile lags
behind by ``z = -H^{-1} r p'`` (``H`` on the complement of ``B``), ``r_j`` the
curvature covector of the metric (``r_j . X = int phi_j phi(X)``,
:func:`metric_covectors`). Eliminating ``z`` at first order gives
``G p' - C p'' = -dE/dp`` with the lag matrix ``C = r^T H^{-1} r`` (symmetric,
positive semi-definite; ``lag=True``). It moves a slow eigenvalue ``lambda`` by
``lambda^2 C / G``: the corner modes of the octagon by 1-3%, the facet modes by
nothing visible. ``correction="profile-lag"`` puts ``p''`` = the acceleration of the
``"profile"`` flow (a directional difference: two more evaluations).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.linalg.lapack import dgbtrf, dgbtrs

from qsa.reduction.correction import D2_STENCIL
from qsa.reduction.manifold import SpliceFields, closure, normal_velocities

__all__ = ["QuasiSteadyProfile", "quasisteady_profile", "closure_gradients", "closure_hessians",
           "metric_covectors", "periodic_d2", "profile_normal_velocities"]


def periodic_d2(f, length):
    """``d^2 f / d sigma^2`` by the periodic 8th-order stencil (:data:`D2_STENCIL`), axis 0."""
    M = f.shape[0]
    out = D2_STENCIL[0] * f
    for k in range(1, D2_STENCIL.size):
        out = out + D2_STENCIL[k] * (np.roll(f, k, axis=0) + np.roll(f, -k, axis=0))
    return out * (M / length) ** 2


@dataclass(frozen=True, eq=False)
class QuasiSteadyProfile:
    """Result of :func:`quasisteady_profile`.

    Attributes
    ----------
    fields : SpliceFields
        The fields of the profile ``kappa`` (``psi``, ``dpsi``, ``d2psi`` are
        ``kappa`` and its derivatives, ``dpsi_dp`` its tangents ``kappa_j``, ``theta``,
        ``Theta`` their integrals; no ``d2psi_dp2``): what the reduction evaluates the
        metric, the force and the constraints with.
    delta : ndarray, shape (M,)
        ``kappa - psi_N``.
    residual : ndarray, shape (M,)
        ``R(kappa)`` (the exact ``psi_N''``, 8th-order differences of ``delta``).
    multipliers : ndarray, shape (2N,)
        The coefficients of ``R(kappa)`` along ``B = [psi_p T, 1, c_x, c_y]``: the
        translation part in the basis ``T`` (``2N - 3``), then ``nu_1`` (the
        turning multiplier), ``nu_2``, ``nu_3``.
    iterations : int
    converged : bool
        The last Newton step was below ``tol`` (relative to ``kstar``).
    lag : ndarray, shape (2N, 2N), or None
        With ``lag=True``: the lag matrix ``C`` (module docstring).
    """

    fields: SpliceFields
    delta: np.ndarray
    residual: np.ndarray
    multipliers: np.ndarray
    iterations: int
    converged: bool
    lag: np.ndarray | None = None


def closure_gradients(theta, quadrature, length):
    """Exact gradients of ``C1 = sum dsigma (cos, sin) theta`` in the nodal ``kappa``, (M, 2).

    ``theta = L cumulative(kappa)``; the columns are ``d C1 / d kappa_k`` divided by
    ``dsigma`` (the samples of ``(-int_sigma^L sin theta, int_sigma^L cos theta)`` up to
    the quadrature's own treatment of the seam ``sigma = 0``, where these jump).
    """
    L = length
    return L * quadrature.cumulative_transpose(
        np.column_stack([-np.sin(theta), np.cos(theta)]))


def closure_hessians(fields, quadrature):
    """``d^2 C1 / d p_i d p_j`` of the splice, shape (2, 2N, 2N) (``C1 = int (cos, sin) theta``)."""
    th, Th, w = fields.theta, fields.Theta, fields.weights
    Tjj = fields.length * quadrature.cumulative(fields.d2psi_dp2)
    cs, sn = np.cos(th), np.sin(th)
    Hx = -(Th.T * (cs * w)) @ Th
    Hy = -(Th.T * (sn * w)) @ Th
    Hx[np.diag_indices_from(Hx)] -= (sn * w) @ Tjj
    Hy[np.diag_indices_from(Hy)] += (cs * w) @ Tjj
    return np.stack([Hx, Hy])


def _factor(kappa, alpha, well, band, length):
    perm, band0 = band
    kb = (band0.shape[0] - 1) // 3
    M = kappa.size
    ab = (-(alpha**2) * (M / length) ** 2) * band0
    ab[2 * kb] += well.d2W(kappa)[perm]
    lu, piv, info = dgbtrf(ab, kb, kb)
    if info != 0:
        raise np.linalg.LinAlgError("H is singular")
    return lu, piv, kb


def _solve(fac, perm, Y):
    lu, piv, kb = fac
    X, info = dgbtrs(lu, kb, kb, np.asfortranarray(Y[perm]), piv)
    if info != 0:
        raise np.linalg.LinAlgError("band solve failed")
    out = np.empty_like(X)
    out[perm] = X
    return out


def quasisteady_profile(fields, alpha, well, band, quadrature, tol=1e-11, maxiter=20,
                        lag=False, length=False):
    """The constrained quasi-steady profile at the splice's positions (module docstring).

    Parameters
    ----------
    fields : SpliceFields
        Of the splice at ``p`` (:func:`qsa.reduction.manifold.splice_fields`).
    alpha : float
    well : object
        Double well with ``dW``, ``d2W``.
    band : (ndarray, ndarray)
        ``folded_band(M, D2_STENCIL)``.
    quadrature : PeriodicQuadrature
        The grid ``fields`` live on.
    tol : float
        Newton stops when the step is below ``tol * max|psi_N|``.
    maxiter : int
    lag : bool
        Also the lag matrix ``C``.
    length : bool
        Also the profile's tangent in the length ``L`` (a variable length; needs
        ``fields`` of ``splice_fields(..., variable=True)``): the result's fields then
        carry ``g_L``, ``dg_L``, ``Theta_L`` of ``kappa`` (module docstring), and the
        lag matrix, with ``lag``, a row and column for ``L``.

    Returns
    -------
    QuasiSteadyProfile
        ``converged=False`` when Newton did not reach ``tol`` in ``maxiter`` steps.

    Raises
    ------
    numpy.linalg.LinAlgError
        A singular factorization of ``H`` or of the bordered system.

    Examples
    --------
    The octagon's corners overlap: the turning multiplier lifts the facets (kappa 0.020
    -> 0.067 in their middle, s = 0).

    >>> import numpy as np
    >>> from qsa.equilibria import default_cutoff
    >>> from qsa.equilibria.splice import polygon_positions
    >>> from qsa.reduction import FrontODE
    >>> p, L = polygon_positions(np.full(8, np.pi / 4), np.full(8, 0.35), 5.0)
    >>> ode = FrontODE(0.1, 5.0, L, correction="profile")
    >>> ev = ode.evaluator
    >>> qs = quasisteady_profile(ev.fields(p, default_cutoff(p, L)), 0.1, ode.front.well,
    ...                          ev.band, ev.quadrature)
    >>> qs.converged, round(float(qs.multipliers[-3]), 2), round(float(qs.delta[0]), 3)
    (True, 0.53, 0.047)
    """
    perm = band[0]
    psi, P, L = fields.psi, fields.dpsi_dp, fields.length
    M, n = P.shape
    h = L / M
    a2 = alpha**2
    C0, A = closure(fields)
    _, _, Vt = np.linalg.svd(A)
    Tc = Vt[3:].T  # displacements keeping the closure (the reduced tangent space)
    PT = P @ Tc
    scale = float(np.max(np.abs(psi)))
    delta = np.zeros(M)
    converged = False
    iterations = 0
    for iterations in range(1, maxiter + 1):  # noqa: B007 (reported)
        kappa = psi + delta
        theta = L * quadrature.cumulative(kappa[:, None])[:, 0]
        B = np.column_stack([PT, np.ones(M), closure_gradients(theta, quadrature, L)])
        R = -a2 * (fields.d2psi + periodic_d2(delta, L)) + well.dW(kappa)
        fac = _factor(kappa, alpha, well, band, L)
        X = _solve(fac, perm, np.column_stack([-R, B]))
        S = B.T @ X[:, 1:]
        C1 = h * np.array([np.cos(theta).sum(), np.sin(theta).sum()])
        rhs = np.concatenate([-PT.T @ delta, [-delta.sum()], (C0[:2] - C1) / h])
        mult = np.linalg.solve(S, rhs - B.T @ X[:, 0])
        d = X[:, 0] + X[:, 1:] @ mult
        delta = delta + d
        if np.max(np.abs(d)) < tol * scale:
            converged = True
            break
    kappa = psi + delta
    R = -a2 * (fields.d2psi + periodic_d2(delta, L)) + well.dW(kappa)
    # tangents kappa_j from the last factorization (at kappa - d, |d| < tol)
    k = PT.shape[1]
    m = Tc @ mult[:k]
    Pjj = fields.d2psi_dp2
    H1 = closure_hessians(fields, quadrature)
    AAt = A @ A.T
    # the part of psi_p^T delta normal to the reduced tangent space, and of dm/dp_j
    eta = np.linalg.solve(AAt, A @ (P.T @ delta))
    dA_m = np.zeros((3, n))
    dA_m[:2] = H1 @ m  # (d_j A) m, column j
    W = -A.T @ np.linalg.solve(AAt, dA_m)  # column j: the normal part of dm/dp_j
    # d R / d p_j = H kappa_j + E_j: the band d^2 acts on delta only, psi_N'' is exact
    E = -a2 * (_spectral_d2(P, L) - periodic_d2(P, L))
    rhs = Pjj * m + P @ W - E
    Xr = _solve(fac, perm, rhs)
    g = P.T @ P - np.diag(Pjj.T @ delta) + np.tensordot(eta[:2], H1, axes=1)
    b = np.vstack([Tc.T @ g, P.sum(axis=0)[None, :], A[:2] / h])
    dmu = np.linalg.solve(S, b - B.T @ Xr)
    K = Xr + X[:, 1:] @ dmu
    cum = L * quadrature.cumulative(np.column_stack([kappa, K]))
    dk = _spectral_d(kappa[:, None], L)
    length_fields = {}
    if length:
        if fields.g_L is None:
            raise ValueError("length=True needs fields of splice_fields(..., variable=True)")
        eta3 = np.linalg.solve(AAt, A @ (P.T @ delta))
        KL = _length_tangent(fields, delta, cum[:, 0], (fac, perm, X, S, B, Tc, A, AAt),
                             m, eta3, alpha, quadrature)
        cL = _spectral_d(KL[:, None], L)
        length_fields = {"g_L": KL, "dg_L": cL[:, 0],
                         "Theta_L": L * quadrature.cumulative(KL[:, None])[:, 0]
                         - fields.s * kappa + cum[:, 0] / L}
    f = SpliceFields(psi=kappa, dpsi=dk[:, 0], d2psi=dk[:, 1], dpsi_dp=K,
                     weights=fields.weights, theta=cum[:, 0], Theta=cum[:, 1:],
                     length=L, s=fields.s, **length_fields)
    C = None
    if lag:
        r = metric_covectors(f, quadrature, profile_normal_velocities(f, quadrature))
        Z = _solve(fac, perm, r)
        Z -= X[:, 1:] @ np.linalg.solve(S, B.T @ Z)  # H Z = r + B eta, B^T Z = 0
        C = (r.T @ Z) / h
        C = 0.5 * (C + C.T)
    return QuasiSteadyProfile(f, delta, R, mult, iterations, converged, C)


def _length_tangent(fields, delta, theta_k, system, m, eta, alpha, quadrature):
    """``d kappa / dL`` on the nodes (fixed ``s``, fixed ``p``) from the factorization.

    ``system = (fac, perm, X, S, B, Tc, A, AAt)`` of the last Newton step; ``theta_k``
    the profile's angle; ``eta`` with ``psi_p^T delta = A^T eta`` (module docstring).
    """
    fac, perm, X, S, B, Tc, A, AAt = system
    L, x = fields.length, fields.s
    M = x.size
    h = L / M
    a2 = alpha**2
    P, PL, g = fields.dpsi_dp, fields.dpsi_dp_L, fields.g_L
    th, Th = fields.theta, fields.Theta
    cs, sn = np.cos(th), np.sin(th)
    # the splice's angles at fixed s: d theta / dL = theta / L + L int_0^s g_L
    cum = L * quadrature.cumulative(np.column_stack([g, PL]))
    thL = th / L + cum[:, 0]
    ThL = Th / L + cum[:, 1:]
    # d/dL of the splice's closure and of its Jacobian A = dC/dp (at fixed s)
    dC1 = np.array([cs.sum(), sn.sum()]) / M + h * np.array([-(sn @ thL), cs @ thL])
    AL = np.vstack([-(sn @ Th) / M - h * ((cs * thL) @ Th) - h * (sn @ ThL),
                    (cs @ Th) / M - h * ((sn * thL) @ Th) + h * (cs @ ThL),
                    P.sum(axis=0) / M + h * PL.sum(axis=0)])
    wL = -A.T @ np.linalg.solve(AAt, AL @ m)  # the normal part of dm/dL
    # d R / dL = H kappa_L + E_L + 2 alpha^2 kappa'' / L (psi_N'' exact, delta'' differenced)
    EL = -a2 * (_spectral_d2(g[:, None], L)[:, 0] - periodic_d2(g, L))
    d2k = fields.d2psi + periodic_d2(delta, L)
    Xr = _solve(fac, perm, (PL @ m + P @ wL - EL - 2 * a2 * d2k / L)[:, None])[:, 0]
    ck, sk = np.cos(theta_k), np.sin(theta_k)
    C1k = h * np.array([ck.sum(), sk.sum()])
    bc = (dC1 - C1k / L) / h - np.array([-(sk @ theta_k), ck @ theta_k]) / L
    b = np.concatenate([Tc.T @ (P.T @ g - PL.T @ delta + AL.T @ eta), [g.sum()], bc])
    dmu = np.linalg.solve(S, b - B.T @ Xr)
    return Xr + X[:, 1:] @ dmu


def profile_normal_velocities(fields, quadrature):
    """``phi_j^perp`` of the profile's tangents, and of ``L`` when ``fields`` has ``g_L``.

    The length column: at fixed ``s`` the curve ``Gamma(s) = L int_0^s tau(theta)``
    moves by ``Gamma / L - L int_0^s n theta_L`` (``theta_L = theta / L + L int_0^s
    g_L``), whose normal part is that at fixed ``sigma`` (they differ by ``s tau``);
    rigid motions projected out like the others. Shape (M, 2N), or (M, 2N + 1).
    """
    if fields.g_L is None:
        return normal_velocities(fields, quadrature)
    L, x, kappa = fields.length, fields.s, fields.psi
    thL = fields.Theta_L + x * kappa
    aug = replace(fields, dpsi_dp=np.column_stack([fields.dpsi_dp, kappa / L + fields.g_L]),
                  Theta=np.column_stack([fields.Theta, thL]))
    phi = normal_velocities(aug, quadrature)
    th = fields.theta
    cs, sn = np.cos(th), np.sin(th)
    gam = L * quadrature.cumulative(np.column_stack([cs, sn]))
    dil = (sn * gam[:, 0] - cs * gam[:, 1]) / L  # the normal part of Gamma / L
    Rr = np.column_stack([sn, -cs, gam[:, 0] * cs + gam[:, 1] * sn])
    Rw = Rr.T * fields.weights
    phi[:, -1] += dil - Rr @ np.linalg.solve(Rw @ Rr, Rw @ dil)
    return phi


def metric_covectors(fields, quadrature, phi):
    """``r_j`` with ``r_j . X = int phi_j phi(X) dsigma`` for every curvature change ``X``.

    ``phi(X)`` is the normal velocity of the curve when ``kappa`` changes by ``X`` at
    fixed ``sigma`` (``Theta = int_0^sigma X``, ``d gamma = -int_0^sigma n Theta``,
    ``phi = n . d gamma``, rigid motions projected out in ``L^2(dsigma)``); ``r_j`` is
    its transpose applied to ``phi_j`` (exact on the nodes: transposes of the
    cumulative integrals). Shape (M, k) like ``phi``.
    """
    L = fields.length
    th = fields.theta
    sn, cs = np.sin(th), np.cos(th)
    y = fields.weights[:, None] * phi  # phi is orthogonal to the rigid motions already
    cumT = quadrature.cumulative_transpose
    ax = L * cumT(sn[:, None] * y)  # phi = sn dgx - cs dgy, dgx = -L cum(sn Theta)
    ay = L * cumT(-cs[:, None] * y)  # dgy = L cum(cs Theta)
    bT = -sn[:, None] * ax + cs[:, None] * ay
    return L * cumT(bT)



def _spectral_d(F, length):
    """First and second ``sigma``-derivatives of one periodic column by FFT, (M, 2)."""
    M = F.shape[0]
    ik = 2j * np.pi * np.fft.rfftfreq(M, d=1.0 / M) / length
    Fh = np.fft.rfft(F[:, 0])
    return np.column_stack([np.fft.irfft(ik * Fh, n=M), np.fft.irfft(ik**2 * Fh, n=M)])


def _spectral_d2(F, length):
    """``d^2 F / d sigma^2`` of periodic columns by FFT (odd ``M``)."""
    M = F.shape[0]
    k = 2 * np.pi * np.fft.rfftfreq(M, d=1.0 / M) / length
    return np.fft.irfft(-(k**2)[:, None] * np.fft.rfft(F, axis=0), n=M, axis=0)
