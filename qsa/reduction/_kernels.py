r"""Compiled (numba) evaluation of the front ODE's right-hand side: the optional ``fast`` backend.

One call of :func:`front_rhs` does what :meth:`FrontODE._velocity` does with numpy
(fronts, angle, normal velocities, metric, force, closure, saddle-point solve) for the
quartic well (logistic fronts) in fused loops, without temporaries of numpy call
overhead. Differences from the numpy reference (see :mod:`qsa.reduction.ode`, "Cost"):

* ``Theta_j = int_0^sigma d psi_N / d p_j`` in closed form: ``d psi_N / d p_j = -+ v_1``
  is the derivative of the cut front, so ``Theta_j = -+ (U_j(sigma) - U_j(0))`` with
  ``U_j`` the cut front made continuous across the periodic wrap (``+ kstar`` per wrap).
* The remaining cumulative integrals (of ``psi``, ``tau``, ``n Theta_j``, the length
  field ``g``) use a local periodic quadrature of order ``2 r`` (:func:`cell_weights`:
  each cell integral from the Lagrange interpolant through the ``2 r`` nearest nodes)
  instead of the FFT; a translation-invariant rule, so the integral over a full period
  is the trapezoid sum (spectrally exact) and the partial integrals carry an
  ``O(h^{2r})`` error (``~1e-10`` relative at the default 3 nodes per front width,
  ``r = 8``; tested against the spectral path).
* The banded Newton correction uses an unblocked banded LU with partial pivoting
  (the algorithm of LAPACK ``dgbtf2``) on the same folded 8th-order difference matrix.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from numba import njit

__all__ = ["cell_weights", "front_rhs", "band_rows"]


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


def band_rows(perm, ab):
    """The folded band matrix (LAPACK ``gbsv`` layout, ``kl = ku = kb``) stored by rows.

    Row ``i`` holds the columns ``i - kb ... i + 2 kb`` (room for the pivoting fill-in):
    ``R[i, t] = A[i, i - kb + t]``.
    """
    kb = (ab.shape[0] - 1) // 3
    M = ab.shape[1]
    R = np.zeros((M, 3 * kb + 1))
    for i in range(M):
        for j in range(max(0, i - kb), min(M, i + kb + 1)):
            R[i, j - i + kb] = ab[2 * kb + i - j, j]
    return R


@njit(cache=True)
def _cumulative(F, wq, out):
    """``out[c, i] = int_0^{s_i} F[c]`` (unit period, ``s_i = i/M``) by the local rule."""
    nc, M = F.shape
    r = wq.size
    pad = np.empty(M + 2 * r)
    h = 1.0 / M
    for c in range(nc):
        for i in range(M):
            pad[r + i] = F[c, i]
        for i in range(r):
            pad[i] = F[c, M - r + i]
            pad[M + r + i] = F[c, i]
        acc = 0.0
        for i in range(M):
            out[c, i] = acc
            cell = 0.0
            for k in range(1, r + 1):
                cell += wq[k - 1] * (pad[r + i + 1 - k] + pad[r + i + k])
            acc += h * cell


@njit(cache=True)
def _gauss_solve(K, b):
    """Solve ``K x = b`` (b of shape (n, m)) by Gaussian elimination with partial pivoting.

    Works on copies. Returns ``(x, ok)``; ``ok`` is False on an exactly zero pivot (as
    LAPACK ``gesv``'s ``info > 0``).
    """
    A = K.copy()
    x = b.copy()
    n = A.shape[0]
    m = x.shape[1]
    for j in range(n):
        ip = j
        big = abs(A[j, j])
        for i in range(j + 1, n):
            if abs(A[i, j]) > big:
                big = abs(A[i, j])
                ip = i
        if big == 0.0:
            return x, False
        if ip != j:
            for c in range(n):
                A[j, c], A[ip, c] = A[ip, c], A[j, c]
            for c in range(m):
                x[j, c], x[ip, c] = x[ip, c], x[j, c]
        for i in range(j + 1, n):
            f = A[i, j] / A[j, j]
            if f != 0.0:
                for c in range(j + 1, n):
                    A[i, c] -= f * A[j, c]
                for c in range(m):
                    x[i, c] -= f * x[j, c]
    for j in range(n - 1, -1, -1):
        for c in range(m):
            v = x[j, c]
            for i in range(j + 1, n):
                v -= A[j, i] * x[i, c]
            x[j, c] = v / A[j, j]
    return x, True


@njit(cache=True)
def _band_solve(A, kb, x):
    """Solve the banded system stored by rows (:func:`band_rows`) in place: ``x`` (M, m).

    Partial pivoting within the band (LAPACK ``dgbtf2``); ``A`` is overwritten. False
    on an exactly zero pivot.
    """
    M = A.shape[0]
    m = x.shape[1]
    for j in range(M):
        last = min(j + kb, M - 1)
        ip = j
        big = abs(A[j, kb])
        for i in range(j + 1, last + 1):
            v = abs(A[i, j - i + kb])
            if v > big:
                big = v
                ip = i
        if big == 0.0:
            return False
        hi = min(j + 2 * kb, M - 1)
        if ip != j:
            for col in range(j, hi + 1):
                tj = col - j + kb
                ti = col - ip + kb
                A[j, tj], A[ip, ti] = A[ip, ti], A[j, tj]
            for c in range(m):
                x[j, c], x[ip, c] = x[ip, c], x[j, c]
        piv = A[j, kb]
        for i in range(j + 1, last + 1):
            f = A[i, j - i + kb] / piv
            if f != 0.0:
                A[i, j - i + kb] = 0.0
                for col in range(j + 1, hi + 1):
                    A[i, col - i + kb] -= f * A[j, col - j + kb]
                for c in range(m):
                    x[i, c] -= f * x[j, c]
    for j in range(M - 1, -1, -1):
        hi = min(j + 2 * kb, M - 1)
        for c in range(m):
            v = x[j, c]
            for col in range(j + 1, hi + 1):
                v -= A[j, col - j + kb] * x[col, c]
            x[j, c] = v / A[j, kb]
    return True


@njit(cache=True)
def _fronts(p, L, l1, l2, k, lam, M, variable):
    """Cut logistic fronts on ``sigma_i = L i / M``: ``psi, psi', psi''``, ``d psi/d p_j``,
    ``Theta_j`` (closed form) and, with ``variable``, ``g`` and ``g'`` of the length field.
    Front-major arrays, shape (2N, M)."""
    n = p.size
    psi = np.zeros(M)
    d1 = np.zeros(M)
    d2 = np.zeros(M)
    dpsi = np.empty((n, M))
    Theta = np.empty((n, M))
    g = np.zeros(M)
    dg = np.zeros(M)
    w = l2 - l1
    for jc in range(n // 2):
        c = 0.5 * (p[2 * jc] + p[2 * jc + 1])
        a = 0.5 * (p[2 * jc + 1] - p[2 * jc])
        for side in range(2):
            j = 2 * jc + side
            sgn = 1.0 if side == 0 else -1.0
            u0 = 0.0
            for i in range(M):
                s = L * i / M
                y = s - c
                nw = np.floor(y / L + 0.5)
                y -= L * nw
                x = y + a if side == 0 else y - a
                pos = x > 0
                r = abs(x)
                if r < l2:
                    sg = -k if pos else k
                    q = np.exp(-lam * r)
                    q /= 1.0 + q
                    q1 = q * (1.0 - q)
                    gap = sg * q
                    v0 = gap + (k if pos else 0.0)
                    v1 = (lam * k) * q1
                    v2 = (lam * lam) * sg * q1 * (1.0 - 2.0 * q)
                    if r > l1:
                        t = (l2 - r) / w
                        tu = 1.0 - t
                        qq = 1.0 / tu - 1.0 / t
                        S = 1.0 / (1.0 + np.exp(-qq))
                        dq = 1.0 / (tu * tu) + 1.0 / (t * t)
                        d2q = 2.0 / (tu * tu * tu) - 2.0 / (t * t * t)
                        aS = S * (1.0 - S)
                        S1 = aS * dq
                        S2 = aS * (1.0 - 2.0 * S) * dq * dq + aS * d2q
                        dchi = (-S1 if pos else S1) / w
                        d2chi = S2 / (w * w)
                        v0 = v0 + (S - 1.0) * gap
                        v2 = d2chi * gap + 2.0 * dchi * v1 + S * v2
                        v1 = dchi * gap + S * v1
                else:
                    v0 = k if pos else 0.0
                    v1 = 0.0
                    v2 = 0.0
                psi[i] += sgn * v0
                d1[i] += sgn * v1
                d2[i] += sgn * v2
                dpsi[j, i] = -sgn * v1
                u = v0 + k * nw  # continuous across the wrap
                if i == 0:
                    u0 = u
                Theta[j, i] = -sgn * (u - u0)
                if variable:
                    # d/dL at fixed p moves the images: dy/dL = -nw
                    g[i] -= nw * sgn * v1
                    dg[i] -= nw * sgn * v2
    if variable:
        for i in range(M):
            x = i / M
            dg[i] += d1[i] / L + x * d2[i]
            g[i] += x * d1[i]
    return psi, d1, d2, dpsi, Theta, g, dg


@njit(cache=True)
def front_rhs(p, L, l1, l2, k, lam, a2, M, wq, correction, band, perm, variable, beta,
              L_star):
    """The reduced velocity and its ingredients (see :meth:`FrontODE._velocity`).

    Returns ``sol`` (``p'`` [, ``L'``] and the multipliers), ``ok`` (False: a singular
    solve, the caller falls back to the numpy path), ``phi`` (2N, M), ``G``, ``dE``
    (the force, corrected with ``correction``), ``C`` (3,), ``J`` (3, 2N) and ``K``,
    ``rhs`` (the saddle-point system).
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
    _cumulative(F, wq, cum)
    theta = L * cum[0]
    cs = np.cos(theta)
    sn = np.sin(theta)
    # normal velocities: d gamma/dp_j = -int_0^sigma n Theta_j, Theta_j = periodic - s k_j
    cj = np.empty(n)
    for j in range(n):
        cj[j] = -k if j % 2 == 0 else k  # Theta_j(L) = -+ kstar
    F2 = np.empty((2 + 2 * n, M))
    for i in range(M):
        s = i * h
        F2[0, i] = cs[i]
        F2[1, i] = sn[i]
        for j in range(n):
            per = Theta[j, i] - s * cj[j]
            F2[2 + j, i] = sn[i] * per
            F2[2 + n + j, i] = -cs[i] * per
    cum2 = np.empty((2 + 2 * n, M))
    _cumulative(F2, wq, cum2)
    Fm = np.empty((2, M))  # m = int n = (int sin, -int cos)
    for i in range(M):
        Fm[0, i] = cum2[1, i]
        Fm[1, i] = -cum2[0, i]
    mm = np.empty((2, M))
    _cumulative(Fm, wq, mm)
    phi = np.empty((n, M))
    Rr = np.empty((3, M))
    for i in range(M):
        s = i * h
        gx = L * cum2[0, i]
        gy = L * cum2[1, i]
        sn0 = s * Fm[0, i] - mm[0, i]
        sn1 = s * Fm[1, i] - mm[1, i]
        for j in range(n):
            dgx = -L * (cum2[2 + j, i] + sn0 * cj[j])
            dgy = -L * (cum2[2 + n + j, i] + sn1 * cj[j])
            phi[j, i] = sn[i] * dgx - cs[i] * dgy
        Rr[0, i] = sn[i]
        Rr[1, i] = -cs[i]
        Rr[2, i] = gx * cs[i] + gy * sn[i]
    # rigid projection
    RR = np.zeros((3, 3))
    Rp = np.zeros((3, n))
    for i in range(M):
        for a in range(3):
            ra = Rr[a, i] * wv
            for b in range(3):
                RR[a, b] += ra * Rr[b, i]
            for j in range(n):
                Rp[a, j] += ra * phi[j, i]
    coef, ok = _gauss_solve(RR, Rp)
    G = np.zeros((kk, kk))
    C = np.zeros(3)
    Cc = np.zeros(3)
    J = np.zeros((3, n))
    for i in range(M):
        for j in range(n):
            phi[j, i] -= coef[0, j] * Rr[0, i] + coef[1, j] * Rr[1, i] + coef[2, j] * Rr[2, i]
        # compensated sums: C is checked against 1e-12 (closure) and the totals are O(1)
        for a in range(3):
            v = (cs[i] if a == 0 else (sn[i] if a == 1 else psi[i])) * wv - Cc[a]
            t = C[a] + v
            Cc[a] = (t - C[a]) - v
            C[a] = t
        for j in range(n):
            J[0, j] -= sn[i] * wv * Theta[j, i]
            J[1, j] += cs[i] * wv * Theta[j, i]
            J[2, j] += wv * dpsi[j, i]
    C[2] -= 2.0 * np.pi
    for a in range(n):
        for b in range(a, n):
            v = 0.0
            for i in range(M):
                v += phi[a, i] * phi[b, i]
            G[a, b] = v * wv
            G[b, a] = v * wv
    # force
    dE = np.zeros(kk)
    Rk = np.empty(M)
    for i in range(M):
        x = psi[i]
        Rk[i] = -a2 * d2[i] + 0.5 * x * (x - k) * (2.0 * x - k)
    if correction:
        kb = (band.shape[1] - 1) // 3
        A = np.empty_like(band)
        scale = -a2 * (M / L) ** 2
        for i in range(M):
            for t in range(band.shape[1]):
                A[i, t] = scale * band[i, t]
            x = psi[perm[i]]
            A[i, kb] += 0.5 * (6.0 * x * x - 6.0 * x * k + k * k)
        nb = n + 1
        X = np.empty((M, 1 + nb))
        for i in range(M):
            X[i, 0] = -Rk[perm[i]]
            for j in range(n):
                X[i, 1 + j] = dpsi[j, perm[i]]
            X[i, nb] = 1.0
        if not _band_solve(A, kb, X):
            return np.zeros(kk + 4), False, phi, G, dE, C, J, np.zeros((kk + 4, kk + 4)), \
                np.zeros(kk + 4)
        S = np.zeros((nb, nb))
        Bx = np.zeros((nb, 1))
        BB = np.zeros((nb, nb))
        for i in range(M):
            for a in range(nb):
                ba = dpsi[a, perm[i]] if a < n else 1.0
                Bx[a, 0] += ba * X[i, 0]
                for b in range(nb):
                    S[a, b] += ba * X[i, 1 + b]
                    bb = dpsi[b, perm[i]] if b < n else 1.0
                    BB[a, b] += ba * bb
        mu, ok2 = _gauss_solve(S, Bx)
        d = np.empty((M, 1))
        for i in range(M):
            v = X[i, 0]
            for b in range(nb):
                v -= X[i, 1 + b] * mu[b, 0]
            d[i, 0] = v
        Bd = np.zeros((nb, 1))
        for i in range(M):
            for a in range(nb):
                ba = dpsi[a, perm[i]] if a < n else 1.0
                Bd[a, 0] += ba * d[i, 0]
        e, ok3 = _gauss_solve(BB, Bd)
        ok = ok and ok2 and ok3
        for i in range(M):
            pi = perm[i]
            v = d[i, 0]
            for a in range(n):
                v -= dpsi[a, pi] * e[a, 0]
            v -= e[n, 0]
            # corrected residual R(psi + delta) = N(delta) - B mu
            x = psi[pi]
            xd = x + v
            Nd = 0.5 * xd * (xd - k) * (2.0 * xd - k) - 0.5 * x * (x - k) * (2.0 * x - k) \
                - 0.5 * (6.0 * x * x - 6.0 * x * k + k * k) * v
            for a in range(n):
                Nd -= dpsi[a, pi] * mu[a, 0]
            Rk[pi] = Nd - mu[n, 0]
    for i in range(M):
        rw = Rk[i] * wv
        for j in range(n):
            dE[j] += rw * dpsi[j, i]
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
        # dE/dL and dC/dL at fixed p (FrontODE._length_derivatives)
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
    return sol[:, 0], ok and ok4, phi, G, dE, C, J, K, rhs
