"""Compiled (numba) dense and banded linear solvers of the front ODE's kernel.

Small dense systems (:func:`_gauss_solve`: Gaussian elimination with partial pivoting,
as LAPACK ``gesv``) and band systems stored by rows (:func:`band_rows`): the pivoted LU
of LAPACK ``dgbtf2`` (:func:`_band_solve`) and the unpivoted elimination with a growth
guard (:func:`_band_forward_nopivot`, for the symmetric, nearly positive definite Newton
matrix of :mod:`qsa.reduction.correction`), and the Schur complement on a border
(:func:`_schur`). Used by :mod:`qsa.reduction._kernels`; needs the optional ``numba``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["GROWTH_LIMIT", "band_rows"]

#: Reassociation (vectorized reductions) and contraction (FMA); no finite-math or
#: approximate-function assumptions (the smoothstep relies on exp overflowing to inf).
_FM = {"reassoc", "contract", "nsz"}

#: Largest accepted growth factor of the unpivoted banded LU (backward error ~ growth eps).
GROWTH_LIMIT = 1e4


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



@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
def _band_solve(A, kb, x):
    """Solve the banded system stored by rows (:func:`band_rows`) in place: ``x`` (M, m).

    Partial pivoting within the band (LAPACK ``dgbtf2``); ``A`` is overwritten. False
    on an exactly zero pivot.
    """
    M = A.shape[0]
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
        span = min(j + 2 * kb, M - 1) - j + 1
        if ip != j:
            rj = A[j, kb:kb + span]
            ri = A[ip, j - ip + kb:j - ip + kb + span]
            for t in range(span):
                rj[t], ri[t] = ri[t], rj[t]
            xj, xi = x[j], x[ip]
            for c in range(xj.size):
                xj[c], xi[c] = xi[c], xj[c]
        _eliminate_column(A, kb, x, j, last, span)
    _back_substitute(A, kb, x, 2 * kb)
    return True


@njit(cache=True, error_model="numpy")
def _eliminate_column(A, kb, x, j, last, span):
    """Rows ``j+1 .. last`` minus multiples of row ``j`` (pivot ``A[j, kb]``, ``span``
    stored entries from the diagonal), and the same on the right-hand sides ``x``."""
    rowj = A[j, kb:kb + span]
    xj = x[j]
    piv = rowj[0]
    for i in range(j + 1, last + 1):
        f = A[i, j - i + kb] / piv
        if f != 0.0:
            rowi = A[i, j - i + kb:j - i + kb + span]
            rowi[0] = 0.0
            for t in range(1, span):
                rowi[t] -= f * rowj[t]
            xi = x[i]
            for c in range(xi.size):
                xi[c] -= f * xj[c]


@njit(cache=True, error_model="numpy")
def _band_forward_nopivot(A, kb, x):
    """Forward elimination of :func:`_band_solve` without pivoting: ``A -> U`` (upper
    half-bandwidth ``kb``: half the work), ``x -> L^{-1} x``.

    Returns the growth factor ``max |U| / max |A|`` (inf on a zero pivot); the backward
    error is ``O(growth eps)`` (Wilkinson), so the caller accepts the factorization only
    for a modest growth and otherwise redoes the solve with pivoting.
    """
    M = A.shape[0]
    amax = 0.0
    for i in range(M):
        for t in range(2 * kb + 1):
            amax = max(amax, abs(A[i, t]))
    umax = 0.0
    for j in range(M):
        span = min(j + kb, M - 1) - j + 1
        rowj = A[j, kb:kb + span]
        piv = rowj[0]
        if piv == 0.0:
            return np.inf
        for t in range(span):
            umax = max(umax, abs(rowj[t]))
        _eliminate_column(A, kb, x, j, j + span - 1, span)
    return umax / amax


@njit(cache=True, error_model="numpy")
def _back_substitute_1(A, kb, z):
    """:func:`_back_substitute` of one column ``z`` (M,), ``U`` of half-bandwidth ``kb``."""
    M = A.shape[0]
    for j in range(M - 1, -1, -1):
        span = min(j + kb, M - 1) - j + 1
        v = z[j]
        for t in range(1, span):
            v -= A[j, kb + t] * z[j + t]
        z[j] = v / A[j, kb]


@njit(cache=True, error_model="numpy")
def _back_substitute(A, kb, x, ku):
    """Solve ``U x = x`` in place, ``U`` (upper half-bandwidth ``ku``) in the rows of A."""
    M = A.shape[0]
    for j in range(M - 1, -1, -1):
        xj = x[j]
        span = min(j + ku, M - 1) - j + 1
        rowj = A[j, kb:kb + span]
        for t in range(1, span):
            xt = x[j + t]
            f = rowj[t]
            for c in range(xj.size):
                xj[c] -= f * xt[c]
        piv = rowj[0]
        for c in range(xj.size):
            xj[c] = xj[c] / piv


@njit(cache=True, fastmath=_FM, error_model="numpy")
def _schur(Wl, YT, d, symmetric):
    """``mu = (Wl Y_B^T)^{-1} Wl Y_R`` and ``d = Y_R - Y_B mu`` (``YT = [Y_R; Y_B^T]``)."""
    nb, M = Wl.shape
    S = np.empty((nb, nb))
    Bx = np.empty((nb, 1))
    for a in range(nb):
        Bx[a, 0] = _dot(Wl[a], YT[0])
        for b in range(a if symmetric else 0, nb):
            S[a, b] = _dot(Wl[a], YT[1 + b])
            if symmetric:
                S[b, a] = S[a, b]
    mu, ok = _gauss_solve(S, Bx)
    d[:] = YT[0]
    for b in range(nb):
        m = mu[b, 0]
        for i in range(M):
            d[i] -= m * YT[1 + b, i]
    return mu, ok



@njit(cache=True, fastmath=_FM, error_model="numpy")
def _dot(a, b):
    """``sum a * b`` (vectorized: reassociated)."""
    v = 0.0
    for i in range(a.size):
        v += a[i] * b[i]
    return v
