r"""Compiled (numba) evaluation of the front ODE's right-hand side: the optional ``fast`` backend.

One call of :func:`front_rhs` evaluates what the numpy backend
(:class:`qsa.reduction.backends.NumpyBackend`) evaluates -- fronts, angle, normal
velocities, metric, force (optionally Newton-corrected), closure, saddle-point solve --
for the quartic well (logistic fronts) in fused loops, without the temporaries and
call overhead of numpy. It differs from the numpy reference only by round-off:

* ``Theta_j = int_0^sigma d psi_N / d p_j`` in closed form: ``d psi_N / d p_j = -+ v_1``
  is the derivative of the cut front, so ``Theta_j = -+ (U_j(sigma) - U_j(0))`` with
  ``U_j`` the cut front made continuous across the periodic wrap (``+ kstar`` per wrap).
* The remaining cumulative integrals (of ``psi``, ``tau``, ``n Theta_j``, the length
  field ``g``) use a local periodic quadrature of order ``2 r`` (:func:`cell_weights`:
  each cell integral from the Lagrange interpolant through the ``2 r`` nearest nodes)
  instead of the FFT; a translation-invariant rule, so the integral over a full period
  is the trapezoid sum (spectrally exact) and the partial integrals carry an
  ``O(h^{2r})`` error (``r = 8``; the order is tested, and the results against the
  spectral path).
* The banded Newton correction (:mod:`qsa.reduction.correction`) eliminates the folded
  8th-order difference matrix without pivoting when the growth factor stays below
  :data:`GROWTH_LIMIT` (an ``L D L^T`` factorization) and with partial pivoting (the
  algorithm of LAPACK ``dgbtf2``) otherwise (:mod:`qsa.reduction._linalg`).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from numba import njit

from qsa.reduction._linalg import (
    _FM,
    GROWTH_LIMIT,
    _back_substitute_1,
    _band_forward_nopivot,
    _band_solve,
    _dot,
    _gauss_solve,
    _schur,
    band_rows,
)

__all__ = ["cell_weights", "end_weights", "front_rhs", "front_velocity", "band_rows"]


def cell_weights(r=8):
    """Weights ``w_k`` (k = 1..r): ``int_{s_i}^{s_i+1} f ~ h sum_k w_k (f_{i+1-k} + f_{i+k})``.

    Integrals over ``[0, 1]`` of the Lagrange basis on the nodes ``-r+1, ..., r``,
    computed exactly (rational arithmetic); they sum to ``1/2``.
    """
    nodes = list(range(-r + 1, r + 1))
    out = []
    for k in range(1, r + 1):
        # basis polynomial of node k: prod_{m != k} (x - m) / (k - m), integrated on [0, 1]
        poly = [Fraction(1)]
        den = Fraction(1)
        for m in nodes:
            if m == k:
                continue
            poly = [Fraction(0)] + poly  # multiply by x
            for i in range(len(poly) - 1):
                poly[i] -= m * poly[i + 1]
            den *= k - m
        out.append(float(sum(c / (i + 1) for i, c in enumerate(poly)) / den))
    return np.array(out)


def end_weights(wq):
    """The local rule in telescoped form: ``c_k = 1/2 - sum_{l <= k} w_l`` (k = 1..r-1).

    ``int_0^{s_i} f = h (T_i + sum_k c_k [(f_{i+k} - f_{i-k}) - (f_k - f_{-k})])`` with
    ``T_i`` the trapezoid sum: the same rule as the cell weights ``w`` (an end
    correction of the trapezoid rule by centred differences), half the work.
    """
    return 0.5 - np.cumsum(wq)[:-1]


@njit(cache=True, fastmath=_FM, error_model="numpy")
def _corrections8(pad, ck, corr):
    """``corr_i = sum_{k=1}^{7} c_k (f_{i+k} - f_{i-k})`` from the padded column (r = 8)."""
    r = 8
    M = corr.size
    c1, c2, c3, c4, c5, c6, c7 = ck[0], ck[1], ck[2], ck[3], ck[4], ck[5], ck[6]
    a1, b1 = pad[r + 1:r + 1 + M], pad[r - 1:r - 1 + M]
    a2, b2 = pad[r + 2:r + 2 + M], pad[r - 2:r - 2 + M]
    a3, b3 = pad[r + 3:r + 3 + M], pad[r - 3:r - 3 + M]
    a4, b4 = pad[r + 4:r + 4 + M], pad[r - 4:r - 4 + M]
    a5, b5 = pad[r + 5:r + 5 + M], pad[r - 5:r - 5 + M]
    a6, b6 = pad[r + 6:r + 6 + M], pad[r - 6:r - 6 + M]
    a7, b7 = pad[r + 7:r + 7 + M], pad[r - 7:r - 7 + M]
    for i in range(M):
        corr[i] = (c1 * (a1[i] - b1[i]) + c2 * (a2[i] - b2[i]) + c3 * (a3[i] - b3[i])
                   + c4 * (a4[i] - b4[i]) + c5 * (a5[i] - b5[i]) + c6 * (a6[i] - b6[i])
                   + c7 * (a7[i] - b7[i]))


@njit(cache=True, fastmath=_FM, error_model="numpy")
def _cumulative(F, ck, out):
    """``out[c, i] = int_0^{s_i} F[c]`` (unit period, ``s_i = i/M``) by the local rule.

    ``out`` first receives the end corrections (loops vectorized over the nodes), then
    the trapezoid prefix sums are added four columns at a time (independent chains).
    """
    nc, M = F.shape
    r = ck.size + 1
    pad = np.empty(M + 2 * r)
    h = 1.0 / M
    for c in range(nc):
        pad[r:r + M] = F[c]
        pad[:r] = F[c, M - r:]
        pad[M + r:] = F[c, :r]
        corr = out[c]
        if r == 8:  # the default rule: one fused pass
            _corrections8(pad, ck, corr)
        else:
            corr[:] = 0.0
            for k in range(1, r):  # shifted views: no negative-index checks, vectorized
                w = ck[k - 1]
                a = pad[r + k:r + k + M]
                b = pad[r - k:r - k + M]
                for i in range(M):
                    corr[i] += w * (a[i] - b[i])
        c0 = corr[0]
        for i in range(M):
            corr[i] -= c0
    for c in range(0, nc, 4):
        q = min(4, nc - c)
        a0 = a1 = a2 = a3 = 0.0
        if q == 4:
            f0, f1, f2, f3 = F[c], F[c + 1], F[c + 2], F[c + 3]
            o0, o1, o2, o3 = out[c], out[c + 1], out[c + 2], out[c + 3]
            for i in range(M - 1):
                o0[i] = h * (o0[i] + a0)
                o1[i] = h * (o1[i] + a1)
                o2[i] = h * (o2[i] + a2)
                o3[i] = h * (o3[i] + a3)
                a0 += 0.5 * (f0[i] + f0[i + 1])
                a1 += 0.5 * (f1[i] + f1[i + 1])
                a2 += 0.5 * (f2[i] + f2[i + 1])
                a3 += 0.5 * (f3[i] + f3[i + 1])
            o0[M - 1] = h * (o0[M - 1] + a0)
            o1[M - 1] = h * (o1[M - 1] + a1)
            o2[M - 1] = h * (o2[M - 1] + a2)
            o3[M - 1] = h * (o3[M - 1] + a3)
        else:
            for cc in range(c, c + q):
                f, o = F[cc], out[cc]
                acc = 0.0
                for i in range(M - 1):
                    o[i] = h * (o[i] + acc)
                    acc += 0.5 * (f[i] + f[i + 1])
                o[M - 1] = h * (o[M - 1] + acc)


@njit(cache=True, fastmath=_FM, error_model="numpy")
def _newton_residual(psi, Rk, dpsi, a2, k, L, band, perm):
    """Overwrite ``Rk`` with the residual of ``psi + delta`` (as
    :func:`qsa.reduction.correction.newton_correction`).

    ``H = -alpha^2 d^2 + W''(psi)`` in folded order (band rows :func:`band_rows`), the
    bordered system by one banded LU and the Schur complement on ``B = [dpsi, 1]``.
    Returns 0; 1 on a singular ``H`` or Schur complement (the numpy path has
    fallbacks); 2 on a singular ``B^T B`` (the numpy path raises).
    """
    n, M = dpsi.shape
    kb = (band.shape[1] - 1) // 3
    nb = n + 1
    scale = -a2 * (M / L) ** 2
    A = np.empty_like(band)
    Bf = np.empty((M, nb))
    X = np.empty((M, 1 + nb))
    for i in range(M):
        pi = perm[i]
        for j in range(n):
            Bf[i, j] = dpsi[j, pi]
        Bf[i, n] = 1.0
    BT = np.ascontiguousarray(Bf.T)
    BB = np.empty((nb, nb))
    for a in range(n):
        for b in range(a, n):
            BB[a, b] = _dot(dpsi[a], dpsi[b])
            BB[b, a] = BB[a, b]
        v = 0.0
        for i in range(M):
            v += dpsi[a, i]
        BB[a, n] = v
        BB[n, a] = v
    BB[n, n] = M
    d = np.empty(M)
    for attempt in range(2):
        for i in range(M):
            for t in range(band.shape[1]):
                A[i, t] = scale * band[i, t]
            x = psi[perm[i]]
            A[i, kb] += 0.5 * (6.0 * x * x - 6.0 * x * k + k * k)
            X[i, 0] = -Rk[perm[i]]
            for j in range(nb):
                X[i, 1 + j] = Bf[i, j]
        if attempt == 0:
            # H is symmetric and nearly positive definite (its near kernel is the
            # translation modes): elimination without pivoting is stable unless the
            # entries grow (measured growth 2 ... 120 along the scenarios' paths).
            # Then H = L D L^T (U = D L^T), so with Y = L^{-1} [-R, B] (the forward
            # elimination) B^T H^{-1} B = Y_B^T D^{-1} Y_B and B^T H^{-1} (-R) =
            # Y_B^T D^{-1} Y_R: one back substitution (of Y_R - Y_B mu) instead of nb + 1.
            if _band_forward_nopivot(A, kb, X) > GROWTH_LIMIT:
                continue
            YT = np.ascontiguousarray(X.T)
            W = np.empty((nb, M))
            for a in range(nb):
                for i in range(M):
                    W[a, i] = YT[1 + a, i] / A[i, kb]
            mu, ok2 = _schur(W, YT, d, True)
            _back_substitute_1(A, kb, d)
            break
        if not _band_solve(A, kb, X):
            return 1
        mu, ok2 = _schur(BT, np.ascontiguousarray(X.T), d, False)
    Bd = np.empty((nb, 1))
    for a in range(nb):
        Bd[a, 0] = _dot(BT[a], d)
    e, ok3 = _gauss_solve(BB, Bd)
    for b in range(nb):
        bb = BT[b]
        m = e[b, 0]
        for i in range(M):
            d[i] -= m * bb[i]
    for i in range(M):
        pi = perm[i]
        v = d[i]
        # corrected residual R(psi + delta) = N(delta) - B mu
        x = psi[pi]
        xd = x + v
        Nd = 0.5 * xd * (xd - k) * (2.0 * xd - k) - 0.5 * x * (x - k) * (2.0 * x - k) \
            - 0.5 * (6.0 * x * x - 6.0 * x * k + k * k) * v
        for a in range(n):
            Nd -= Bf[i, a] * mu[a, 0]
        Rk[pi] = Nd - mu[n, 0]
    return 0 if ok3 and ok2 else (2 if not ok3 else 1)


@njit(cache=True, error_model="numpy")
def _ksum(x, wv):
    """Compensated (Kahan) sum of ``x * wv``."""
    s = 0.0
    c = 0.0
    for i in range(x.size):
        v = x[i] * wv - c
        t = s + v
        c = (t - s) - v
        s = t
    return s


@njit(cache=True, error_model="numpy")
def _closure(cs, sn, psi, wv):
    """``C`` by compensated sums (C is checked against 1e-12; the terms are O(1))."""
    C = np.empty(3)
    C[0] = _ksum(cs, wv)
    C[1] = _ksum(sn, wv)
    C[2] = _ksum(psi, wv) - 2.0 * np.pi
    return C


@njit(cache=True, fastmath=_FM, error_model="numpy")
def _fronts(p, L, l1, l2, k, lam, M, variable):
    """Cut logistic fronts on ``sigma_i = L i / M``: ``psi, psi', psi''``, ``d psi/d p_j``,
    ``Theta_j`` (closed form) and, with ``variable``, ``g`` and ``g'`` of the length field.
    Front-major arrays, shape (2N, M).

    ``e^{-lambda |x|}`` of both fronts of a corner (``x = y +- a``) come from one
    ``e^{-lambda y} = e^{-lambda sigma} e^{lambda (c + n L)}`` (tabulated ``e^{-lambda
    sigma}``, one exponential per corner and wrap ``n``): products of exact
    exponentials, a few ulp. The logistic part is branch-free (vectorized); the cutoff
    band ``l1 < |x| < l2`` is gathered first and its exponentials taken in one loop.
    """
    n = p.size
    psi = np.zeros(M)
    d1 = np.zeros(M)
    d2 = np.zeros(M)
    dpsi = np.empty((n, M))
    Theta = np.empty((n, M))
    g = np.zeros(M)
    dg = np.zeros(M)
    iw = 1.0 / (l2 - l1)
    hs = L / M
    invL = 1.0 / L
    es = np.empty(M)
    for i in range(M):
        es[i] = np.exp(-lam * (hs * i))
    lk = lam * k
    l2k = lam * lam
    Y = np.empty(M)
    NW = np.empty(M)
    EY = np.empty(M)
    V0 = np.empty(M)
    V1 = np.empty(M)
    V2 = np.empty(M)
    idx = np.empty(M, dtype=np.int64)
    IT = np.empty(M)
    ITU = np.empty(M)
    ARG = np.empty(M)
    for jc in range(n // 2):
        c = 0.5 * (p[2 * jc] + p[2 * jc + 1])
        a = 0.5 * (p[2 * jc + 1] - p[2 * jc])
        ea = np.exp(-lam * a)
        last = np.nan
        fac = 0.0
        for i in range(M):
            y = hs * i - c
            nw = np.floor(y * invL + 0.5)
            Y[i] = y - L * nw
            NW[i] = nw
            if nw != last:
                fac = np.exp(lam * (c + nw * L))
                last = nw
            EY[i] = es[i] * fac
        for side in range(2):
            j = 2 * jc + side
            sa = a if side == 0 else -a
            eas = ea if side == 0 else 1.0 / ea
            sgn = 1.0 if side == 0 else -1.0
            for i in range(M):  # branch-free: vectorized
                x = Y[i] + sa
                r = abs(x)
                pos = x > 0
                e = EY[i] * eas
                e = e if pos else 1.0 / e
                live = r < l2
                q = e / (1.0 + e)
                q1 = q * (1.0 - q)
                sg = (-k if pos else k) if live else 0.0
                gap = sg * q
                V0[i] = gap + (k if pos else 0.0)
                V1[i] = lk * q1 if live else 0.0
                V2[i] = l2k * sg * q1 * (1.0 - 2.0 * q)
            cnt = 0
            for i in range(M):  # nodes in the cutoff band (branch-free compaction)
                r = abs(Y[i] + sa)
                idx[cnt] = i
                cnt += (r > l1) & (r < l2)
            for m in range(cnt):  # there chi = S((l2 - r) / w): arguments first
                i = idx[m]
                x = Y[i] + sa
                t = (l2 - abs(x)) * iw
                tu = 1.0 - t
                itt = 1.0 / (t * tu)
                IT[m] = tu * itt
                ITU[m] = t * itt
                ARG[m] = IT[m] - ITU[m]
            for m in range(cnt):  # (the exponentials alone: independent calls)
                ARG[m] = np.exp(ARG[m])
            for m in range(cnt):
                i = idx[m]
                x = Y[i] + sa
                pos = x > 0
                e = EY[i] * eas
                e = e if pos else 1.0 / e
                gap = (-k if pos else k) * (e / (1.0 + e))
                it = IT[m]
                itu = ITU[m]
                S = 1.0 / (1.0 + ARG[m])
                dq = itu * itu + it * it
                d2q = 2.0 * (itu * itu * itu - it * it * it)
                aS = S * (1.0 - S)
                S1 = aS * dq
                S2 = aS * ((1.0 - 2.0 * S) * dq * dq + d2q)
                dchi = (-S1 if pos else S1) * iw
                d2chi = S2 * iw * iw
                v1 = V1[i]
                V0[i] = V0[i] + (S - 1.0) * gap
                V2[i] = d2chi * gap + 2.0 * dchi * v1 + S * V2[i]
                V1[i] = dchi * gap + S * v1
            u0 = V0[0] + k * NW[0]
            dp = dpsi[j]
            Th = Theta[j]
            for i in range(M):
                psi[i] += sgn * V0[i]
                d1[i] += sgn * V1[i]
                d2[i] += sgn * V2[i]
                dp[i] = -sgn * V1[i]
                Th[i] = -sgn * (V0[i] + k * NW[i] - u0)
            if variable:
                for i in range(M):
                    g[i] -= NW[i] * sgn * V1[i]
                    dg[i] -= NW[i] * sgn * V2[i]
    if variable:
        for i in range(M):
            x = i / M
            dg[i] += d1[i] / L + x * d2[i]
            g[i] += x * d1[i]
    return psi, d1, d2, dpsi, Theta, g, dg


@njit(cache=True, fastmath=_FM, error_model="numpy")
def front_rhs(p, L, l1, l2, k, lam, a2, M, ck, correction, band, perm, variable, beta,
              L_star):
    """The reduced velocity and its ingredients (as
    :meth:`qsa.reduction.backends.NumpyBackend.evaluate`).

    Returns ``sol`` (``p'`` [, ``L'``] and the multipliers), ``status`` (0; 1: the
    saddle-point matrix ``K`` is exactly singular, the caller solves it by least squares;
    2: the rigid-motion projection or ``B^T B`` of the Newton correction is singular,
    ``np.linalg.solve`` raises in the numpy path; 3: another solve of the correction is
    singular, the caller uses the numpy path and its fallbacks),
    ``phi`` (2N, M), ``G``, ``dE`` (the force, corrected with ``correction``), ``C``
    (3,), ``J`` (3, 2N) and ``K``, ``rhs`` (the saddle-point system).
    """
    n = p.size
    kk = n + 1 if variable else n
    psi, d1, d2, dpsi, Theta, g, dg = _fronts(p, L, l1, l2, k, lam, M, variable)
    h = 1.0 / M
    wv = L * h  # quadrature weight
    # theta (and the length field's cumulative integral)
    nf = 2 if variable else 1
    F = np.empty((nf, M))
    F[0] = psi
    if variable:
        F[1] = g
    cum = np.empty((nf, M))
    _cumulative(F, ck, cum)
    theta = np.empty(M)
    cs = np.empty(M)
    sn = np.empty(M)
    for i in range(M):  # (one loop: sin and cos of the same angle fuse into sincos)
        th = L * cum[0, i]
        theta[i] = th
        cs[i] = np.cos(th)
        sn[i] = np.sin(th)
    # normal velocities: d gamma/dp_j = -int_0^sigma n Theta_j, Theta_j = periodic - s k_j
    cj = np.empty(n)
    for j in range(n):
        cj[j] = -k if j % 2 == 0 else k  # Theta_j(L) = -+ kstar
    sv = np.empty(M)
    for i in range(M):
        sv[i] = i * h
    F2 = np.empty((2 + 2 * n, M))
    F2[0] = cs
    F2[1] = sn
    for j in range(n):  # (loops over the nodes innermost: contiguous, vectorized)
        Tj, c, fa, fb = Theta[j], cj[j], F2[2 + j], F2[2 + n + j]
        for i in range(M):
            per = Tj[i] - sv[i] * c
            fa[i] = sn[i] * per
            fb[i] = -cs[i] * per
    cum2 = np.empty((2 + 2 * n, M))
    _cumulative(F2, ck, cum2)
    Fm = np.empty((2, M))  # m = int n = (int sin, -int cos)
    Fm[0] = cum2[1]
    for i in range(M):
        Fm[1, i] = -cum2[0, i]
    mm = np.empty((2, M))
    _cumulative(Fm, ck, mm)
    sn0 = np.empty(M)
    sn1 = np.empty(M)
    Rr = np.empty((3, M))
    for i in range(M):
        sn0[i] = sv[i] * Fm[0, i] - mm[0, i]
        sn1[i] = sv[i] * Fm[1, i] - mm[1, i]
        Rr[0, i] = sn[i]
        Rr[1, i] = -cs[i]
        Rr[2, i] = L * (cum2[0, i] * cs[i] + cum2[1, i] * sn[i])
    phi = np.empty((n, M))
    for j in range(n):
        ca, cb, c, ph = cum2[2 + j], cum2[2 + n + j], cj[j], phi[j]
        for i in range(M):
            ph[i] = -L * (sn[i] * (ca[i] + sn0[i] * c) - cs[i] * (cb[i] + sn1[i] * c))
    # rigid projection
    RR = np.empty((3, 3))
    Rp = np.empty((3, n))
    for a in range(3):
        for b in range(3):
            RR[a, b] = wv * _dot(Rr[a], Rr[b])
        for j in range(n):
            Rp[a, j] = wv * _dot(Rr[a], phi[j])
    coef, ok = _gauss_solve(RR, Rp)
    okc = 0
    G = np.zeros((kk, kk))
    C = _closure(cs, sn, psi, wv)
    J = np.empty((3, n))
    for j in range(n):
        ph, c0, c1, c2 = phi[j], coef[0, j], coef[1, j], coef[2, j]
        for i in range(M):
            ph[i] -= c0 * Rr[0, i] + c1 * Rr[1, i] + c2 * Rr[2, i]
        J[0, j] = -wv * _dot(sn, Theta[j])
        J[1, j] = wv * _dot(cs, Theta[j])
        v = 0.0
        for i in range(M):
            v += dpsi[j, i]
        J[2, j] = wv * v
    for a in range(n):
        for b in range(a, n):
            v = wv * _dot(phi[a], phi[b])
            G[a, b] = v
            G[b, a] = v
    # force
    dE = np.zeros(kk)
    Rk = np.empty(M)
    for i in range(M):
        x = psi[i]
        Rk[i] = -a2 * d2[i] + 0.5 * x * (x - k) * (2.0 * x - k)
    if correction:
        okc = _newton_residual(psi, Rk, dpsi, a2, k, L, band, perm)
    for j in range(n):
        dE[j] = wv * _dot(Rk, dpsi[j])
    # saddle-point system
    K = np.zeros((kk + 4, kk + 4))
    rhs = np.zeros(kk + 4)
    for a in range(n):
        for b in range(n):
            K[a, b] = G[a, b]
        rhs[a] = -dE[a]
        for c in range(3):
            K[a, kk + c] = J[c, a]
            K[kk + c, a] = J[c, a]
        K[a, kk + 3] = 1.0 / np.sqrt(n)
        K[kk + 3, a] = 1.0 / np.sqrt(n)
    if variable:
        # dE/dL and dC/dL at fixed p (qsa.reduction.manifold.length_derivatives)
        e_int = 0.0
        gdE = 0.0
        gw = 0.0
        pw = 0.0
        dC1 = 0.0
        dC2 = 0.0
        for i in range(M):
            x = psi[i]
            e_i = 0.5 * a2 * d1[i] ** 2 + 0.25 * x * x * (x - k) ** 2
            e_int += (e_i - a2 * d1[i] ** 2) * wv
            gdE += (0.5 * x * (x - k) * (2.0 * x - k) * g[i] + a2 * d1[i] * dg[i]) * wv
            gw += g[i] * wv
            pw += x * wv
        dEL = gdE + e_int / L + beta * (L - L_star)
        int_psi_L = gw - psi[0] + pw / L
        tL = theta[0] + pw
        for i in range(M):
            ThL = L * cum[1, i] - (i * h) * psi[i] + theta[i] / L
            dC1 -= sn[i] * ThL * wv
            dC2 += cs[i] * ThL * wv
        h2 = 0.5 * wv
        dC1 += np.cos(tL) - h2 * np.sin(tL) * int_psi_L
        dC2 += np.sin(tL) + h2 * np.cos(tL) * int_psi_L
        dC3 = psi[0] + int_psi_L
        dE[n] = dEL
        rhs[n] = -dEL
        K[n, kk] = dC1
        K[n, kk + 1] = dC2
        K[n, kk + 2] = dC3
        K[kk, n] = dC1
        K[kk + 1, n] = dC2
        K[kk + 2, n] = dC3
    b2 = np.empty((kk + 4, 1))
    b2[:, 0] = rhs
    sol, ok4 = _gauss_solve(K, b2)
    status = 0 if ok4 else 1
    if okc:
        status = 3 if okc == 1 else 2
    if not ok:
        status = 2
    return sol[:, 0], status, phi, G, dE, C, J, K, rhs


@njit(cache=True, error_model="numpy")
def front_velocity(p, L, l1, l2, k, lam, a2, M, ck, correction, band, perm, variable, beta,
                   L_star):
    """:func:`front_rhs` returning only ``(sol, status)`` (no boxing of the rest)."""
    out = front_rhs(p, L, l1, l2, k, lam, a2, M, ck, correction, band, perm, variable, beta,
                    L_star)
    return out[0], out[1]
