"""Eigen-solvers of the linearizations, each returning eigenvalues with error estimates.

Normal gauge (``J``, self-adjoint in ``<f, h> = int f h dsigma``):

* :func:`certified_eigenpairs` -- the eigenvalues nearest a shift from the factored
  operator (:mod:`qsa.spectra.factored`): ARPACK in shift-invert mode on the pencil
  ``(W J, W)`` with the rigid motions deflated, or, on small grids, the dense
  eigen-decomposition of the compressed inverse. The rigid motions contribute their
  Ritz values (the kernel eigenvalues), computed by the factored quadratic form.
* :func:`dense_normal` -- every eigenvalue, from the formed symmetric matrix
  ``W^{1/2} J W^{-1/2}`` (error ``eps |J|``), with the eigenvalues whose error exceeds
  ``rtol |lambda|`` replaced by the certified ones nearest 0.

Other gauges (non-normal ``2N x 2N`` or ``(N + 1) x (N + 1)`` matrices):
:func:`general_eigenpairs`, dense or shift-invert on the formed matrix, with the
first-order error ``(|r| + eps |A|) / s`` of each simple eigenvalue (``s`` the cosine
between its left and right eigenvectors, ``r`` the residual).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from qsa.linalg import SparsePlusLowRank, factorize, to_dense
from qsa.spectra.factored import FactoredNormalOperator

__all__ = ["EigenSolution", "certified_eigenpairs", "dense_normal", "general_eigenpairs",
           "DENSE_INVERSE_LIMIT", "MAX_CERTIFIED", "UNREFINED"]

_EPS = np.finfo(float).eps

#: Up to this N the certified eigenpairs come from the dense compressed inverse
#: (every eigenvalue at once); above it from ARPACK.
DENSE_INVERSE_LIMIT = 400

#: Largest number of eigenvalues near 0 recomputed from the factors when the dense
#: path leaves them uncertified.
MAX_CERTIFIED = 60

#: ARPACK runs on unrefined solves through a coarse state (then polished) when their
#: measured relative forward error is at most this.
UNREFINED = 1e-6


@dataclass(frozen=True, eq=False)
class EigenSolution:
    """Eigenpairs with error estimates, before the spectrum's bookkeeping.

    Attributes
    ----------
    values : ndarray, shape (m,)
    vectors : ndarray, shape (n, m)
        ``<.,.>``-normalised columns.
    errors : ndarray, shape (m,)
        Absolute error estimates of ``values``.
    is_kernel : ndarray of bool, shape (m,)
        Deflated rigid modes (their Ritz values).
    method : str
    roundoff : float
        ``eps |A|`` of the formed matrix (NaN when it was not formed).
    max_imag : float
        Largest relative imaginary part dropped (non-normal gauges).
    notes : tuple of str

    Parameters
    ----------
    The attributes above.
    """

    values: np.ndarray
    vectors: np.ndarray | None
    errors: np.ndarray
    is_kernel: np.ndarray
    method: str
    roundoff: float = np.nan
    max_imag: float = 0.0
    notes: tuple = ()


# ------------------------------------------------------------------ normal gauge
def _complement_basis(curve, R):
    """``<.,.>``-orthonormal basis (columns) of the complement of ``span R``, shape (N, N - m)."""
    rw = np.sqrt(curve.dsigma)
    if R.shape[0] == 0:
        return np.diag(1.0 / rw)
    Q, _ = np.linalg.qr((R * rw).T, mode="complete")
    return Q[:, R.shape[0]:] / rw[:, None]


def _dense_inverse(op, si, R):
    """All eigenpairs of the compressed inverse ``Q^T W (W J - sigma W)^{-1} W Q``."""
    w = op.w
    Q = _complement_basis(op.curve, R)
    X = si.solve(w[:, None] * Q)
    Kc = Q.T @ (w[:, None] * X)
    nu, Y = np.linalg.eigh(0.5 * (Kc + Kc.T))
    keep = nu != 0
    vals = si.sigma + 1.0 / nu[keep]
    vecs = Q @ Y[:, keep]
    return vals, vecs


def _arpack(op, si, R, k, seed=0):
    """The ``k`` eigenpairs nearest the shift by ARPACK on the inverse ``si``.

    Returns ``(values, vectors, errors)``, ``errors`` an :class:`EigenErrors` or None
    (not computed). When ``si`` solves through a capacitance
    (:mod:`qsa.spectra.capacitance`), whose solves are accurate to about ``1e-8`` before
    refinement and whose refinement costs two more passes over the two-point blocks,
    ARPACK runs on the unrefined solves and its Ritz subspace is then polished with
    refined ones (:func:`_polish`), which also give the errors. So it does through a
    coarse state (:mod:`qsa.spectra.coarse`) when the probe measures the unrefined
    solves' forward error at most :data:`UNREFINED`.
    """
    N = op.N
    w = op.w
    route = getattr(si, "core_solver", None)
    fast = route == "capacitance" or (route == "coarse" and si.unrefined_error() <= UNREFINED)
    matvec = (lambda x: si.solve(x, refine=0)) if fast else si.solve
    OPinv = spla.LinearOperator((N, N), matvec=matvec, dtype=float)
    A = spla.LinearOperator((N, N), matvec=lambda x: op.matvec(x) * w, dtype=float)
    v0 = np.random.default_rng(seed).standard_normal(N)
    if R.shape[0]:
        v0 -= R.T @ (R @ (w * v0))
    vals, vecs = spla.eigsh(A, k=k, M=sp.diags(w), sigma=si.sigma, OPinv=OPinv, which="LM",
                            v0=v0)
    if fast:
        return _polish(si, vecs)
    return vals, vecs, None


def _polish(si, V):
    """One step of subspace iteration and Rayleigh-Ritz with refined solves, with errors.

    ``V`` spans the Ritz subspace of an inverse ``K = (W J - sigma W)^{-1} W`` known to
    a small relative error ``delta``: one product with the refined ``K`` damps the
    subspace's components along the other eigenvectors by ``|nu_j / nu_i|`` (most of them
    far from the shift, so strongly), and Rayleigh-Ritz with the refined ``K`` on the
    result makes the eigenvalue error second order in what is left. The Rayleigh-Ritz
    solve also gives the Ritz vectors' residuals and forward errors
    (:meth:`~qsa.spectra.factored.ShiftInvert.ritz_pairs`).
    """
    w = si.op.w
    rw = np.sqrt(w)[:, None]
    X = np.linalg.qr(rw * si.solve(w[:, None] * V))[0] / rw  # <.,.>-orthonormal columns
    return si.ritz_pairs(X)


def certified_eigenpairs(op: FactoredNormalOperator, R, k=None, sigma=0.0,
                         rigid=None, constrain=None) -> EigenSolution:
    """Eigenpairs of ``J`` nearest ``sigma`` from the factors, with error estimates.

    Parameters
    ----------
    op : FactoredNormalOperator
    R : ndarray, shape (m, N)
        ``<.,.>``-orthonormal rows spanning the normal components of the rigid motions;
        deflated, and returned as the kernel (their Ritz values).
    k : int, optional
        Number of eigenvalues wanted (kernel included): the ``k`` nearest ``sigma``.
        Default: all of them (dense compressed inverse).
    sigma : float
    rigid : ndarray, optional
        Estimates of the rigid modes' eigenvalues, kept away from the shift (default:
        the Ritz values on ``R``; pass them when ``R`` is empty, i.e. no deflation).
    constrain : ndarray, shape (mc, N), optional
        ``<.,.>``-orthonormal rows spanning the normal variations of length / area
        constraints (orthogonal to ``R``): the eigenproblem is that of the constrained
        operator ``P J P`` on their complement (:class:`~qsa.spectra.factored.ShiftInvert`);
        these directions are excluded, not returned.

    Returns
    -------
    EigenSolution
        Sorted by distance to ``sigma``. Raises ``numpy.linalg.LinAlgError`` or an
        ARPACK error when a solve fails.
    """
    N = op.N
    Rc = np.zeros((0, N)) if constrain is None else np.asarray(constrain, float).reshape(-1, N)
    rows = np.vstack([R, Rc])
    estimate = op.ritz_values(R) if rigid is None else np.asarray(rigid, dtype=float)
    si = _shift(op, sigma, R, np.append(estimate, 0.0), Rc)
    rvals, rvecs, rerr = si.kernel_ritz(R)
    free = N - rows.shape[0]
    # a few more than asked: the shift may have moved, and the rigid Ritz values compete
    want = free if k is None else min(int(k) + 2, free - 1)
    errs = None
    if k is None or N <= DENSE_INVERSE_LIMIT or want >= free // 2:
        vals, vecs = _dense_inverse(op, si, rows)
        order = np.argsort(np.abs(vals - sigma))[:want]
        vals, vecs = vals[order], vecs[:, order]
        method = "factored dense"
    else:
        vals, vecs, errs = _arpack(op, si, rows, want)
        method = "factored shift-invert"
    if errs is None:
        vecs = vecs / np.sqrt(np.sum(op.w[:, None] * vecs**2, axis=0))
        errs = si.errors(vals, vecs)
    values = np.concatenate([rvals, vals])
    vectors = np.hstack([rvecs, vecs])
    errors = np.concatenate([rerr, errs.total])
    is_kernel = np.concatenate([np.ones(rvals.size, bool), np.zeros(vals.size, bool)])
    order = np.argsort(np.abs(values - sigma), kind="stable")
    if k is not None:
        order = order[: int(k)]
    return EigenSolution(values[order], vectors[:, order], errors[order], is_kernel[order],
                         method)


def _slow_scale(op, R, modes=8, seed=1):
    """``|phi^T W J phi|`` for a smooth random unit ``phi`` orthogonal to ``R``: the slow scale."""
    s = op.curve.grid.s
    rng = np.random.default_rng(seed)
    kmax = max(1, min(modes, (op.N - 1) // 6))
    phi = sum(rng.standard_normal() * np.cos(2 * np.pi * j * s)
              + rng.standard_normal() * np.sin(2 * np.pi * j * s) for j in range(kmax + 1))
    w = op.w
    if R.shape[0]:
        phi = phi - R.T @ (R @ (w * phi))
    nrm = float(np.sqrt(np.sum(w * phi * phi)))
    if nrm == 0:
        return 1.0
    val = abs(float(op.quadratic(phi / nrm)[0, 0]))
    return val if val > 0 else 1.0


def _shift(op, sigma, R, rigid, Rc=None):
    """The shift-invert factorization at a shift safely away from the rigid eigenvalues.

    The unbordered core is singular exactly when the shift is an eigenvalue of ``J``,
    and the rigid modes' eigenvalues are close to their Ritz values ``rigid``; a shift
    within ``1e-8`` of the slow scale of one of them is moved that far away (the
    eigenvalues found do not depend on the shift). A shift exactly on the spectrum
    elsewhere is moved off it.
    """
    delta = 1e-8 * _slow_scale(op, R if Rc is None else np.vstack([R, Rc]))
    if rigid.size:
        j = int(np.argmin(np.abs(sigma - rigid)))
        if abs(sigma - rigid[j]) < delta:
            sigma = rigid[j] + 2 * delta * (1.0 if sigma >= rigid[j] else -1.0)
    try:
        return op.shift_invert(sigma, deflate=R, constrain=Rc)
    except np.linalg.LinAlgError:
        return op.shift_invert(sigma + delta, deflate=R, constrain=Rc)


def dense_normal(op: FactoredNormalOperator, R, rtol, vectors=True, rigid=None,
                 constrain=None) -> EigenSolution:
    """Every eigenvalue of ``J``: the formed symmetric matrix, then the factors near 0.

    The formed ``S = W^{1/2} J W^{-1/2}`` gives all eigenvalues with absolute error
    ``eps |J|``; those with ``eps |J| > rtol |lambda|`` (a ball around 0, the rigid
    modes included) are replaced by :func:`certified_eigenpairs` nearest 0 (at most
    :data:`MAX_CERTIFIED`; any left over keep the dense error and fail the test).
    With ``constrain`` rows (see :func:`certified_eigenpairs`), ``W J`` is compressed to
    the ``<.,.>``-orthonormal basis ``Q`` of their complement: ``Q^T W J Q``, the
    constrained operator ``P J P`` on it.

    Returns
    -------
    EigenSolution
        Sorted by decreasing eigenvalue.
    """
    curve = op.curve
    rw = np.sqrt(op.w)
    J = op.form()
    Rc = np.zeros((0, op.N)) if constrain is None else np.asarray(constrain, float)
    if Rc.shape[0]:
        Q = _complement_basis(curve, Rc)  # <.,.>-orthonormal columns
        S = Q.T @ (op.w[:, None] * to_dense(J @ Q))
    else:
        Q = np.diag(1.0 / rw)
        S = to_dense(J) * rw[:, None] / rw[None, :]
    S = 0.5 * (S + S.T)
    if vectors:
        lam, Y = sla.eigh(S)
        vecs = Q @ Y
    else:
        lam, vecs = sla.eigvalsh(S), None
    normJ = float(np.max(np.abs(lam))) if lam.size else 0.0
    roundoff = _EPS * normJ
    err = np.full(lam.size, roundoff)
    bad = err > rtol * np.abs(lam)
    n_bad = int(np.sum(bad))
    m = R.shape[0]
    if n_bad:
        k = _window(np.abs(lam), max(n_bad, m) + 2, MAX_CERTIFIED + m)
        cert = certified_eigenpairs(op, R, k=k, sigma=0.0, rigid=rigid, constrain=Rc)
        drop = np.argsort(np.abs(lam), kind="stable")[: cert.values.size]
        keep = np.ones(lam.size, bool)
        keep[drop] = False
        cvals, cerr = cert.values.copy(), cert.errors.copy()
        cvecs = None if vecs is None or cert.vectors is None else cert.vectors.copy()
        # far from 0 the formed matrix may be the more accurate of the two: take, for each
        # non-kernel value of the window, the dense partner when its error is smaller
        used = np.zeros(drop.size, bool)
        for i in np.argsort(cvals):
            if cert.is_kernel[i]:
                continue
            free = np.flatnonzero(~used)
            j = free[np.argmin(np.abs(lam[drop[free]] - cvals[i]))]
            used[j] = True
            d = drop[j]
            if err[d] < cerr[i] and abs(lam[d] - cvals[i]) <= 3 * (err[d] + cerr[i]):
                cvals[i], cerr[i] = lam[d], err[d]
                if cvecs is not None:
                    cvecs[:, i] = vecs[:, d]
        values = np.concatenate([lam[keep], cvals])
        errors = np.concatenate([err[keep], cerr])
        is_kernel = np.concatenate([np.zeros(int(keep.sum()), bool), cert.is_kernel])
        vecs = None if vecs is None or cvecs is None else np.hstack([vecs[:, keep], cvecs])
        method = "dense + factored"
    else:
        values, errors, is_kernel = lam, err, _nearest_mask(lam, m)
        method = "dense"
    order = np.argsort(-values, kind="stable")
    return EigenSolution(values[order], None if vecs is None else vecs[:, order],
                         errors[order], is_kernel[order], method, roundoff)


def _window(magnitudes, n_min, n_max, gap=1e-3):
    """Size ``n >= n_min`` of a window of the smallest ``magnitudes`` that ends at a gap.

    The window never splits a (numerically) multiple eigenvalue: ``n`` is the first size
    with ``a[n] > (1 + gap) a[n - 1]`` (``a`` sorted), capped at ``n_max`` and ``len(a)``.
    """
    a = np.sort(magnitudes)
    n = min(int(n_min), a.size)
    while n < min(n_max, a.size) and a[n] <= (1 + gap) * a[n - 1]:
        n += 1
    return n


def _nearest_mask(values, m):
    mask = np.zeros(values.size, bool)
    mask[np.argsort(np.abs(values), kind="stable")[:m]] = True
    return mask


# ------------------------------------------------------------------ other gauges
def _condition_errors(A, vals, right, left, normA):
    """``(|A x - lambda x| + eps |A|) / s`` per eigenpair, ``s = |y^H x| / (|y| |x|)``."""
    out = np.empty(vals.size)
    for i in range(vals.size):
        x, y = right[:, i], left[:, i]
        s = abs(np.vdot(y, x)) / max(np.linalg.norm(y) * np.linalg.norm(x), 1e-300)
        r = np.linalg.norm(A @ x - vals[i] * x) / max(np.linalg.norm(x), 1e-300)
        out[i] = (r + _EPS * normA) / max(s, 1e-300)
    return out


def _shift_invert_general(A, sigma, transpose=False):
    """LinearOperator applying ``(A - sigma I)^{-1}`` (or its transpose) via :func:`factorize`."""
    n = A.shape[0]
    if isinstance(A, SparsePlusLowRank):
        S = A.S.T if transpose else A.S
        U, V = (A.V, A.U) if transpose else (A.U, A.V)
        F = factorize((S - sigma * sp.identity(n, format="csr")).tocsc(), U, V.T,
                      -np.eye(U.shape[1]))
        solve = lambda b: F.solve(np.concatenate([b, np.zeros(U.shape[1])]))[:n]
    elif sp.issparse(A):
        F = factorize(((A.T if transpose else A) - sigma * sp.identity(n, format="csr")).tocsc())
        solve = F.solve
    else:
        F = factorize((A.T if transpose else np.asarray(A)) - sigma * np.eye(n))
        solve = F.solve
    return spla.LinearOperator((n, n), matvec=solve, dtype=float)


def _as_operator(A):
    if isinstance(A, SparsePlusLowRank):
        return A.aslinearoperator()
    return spla.aslinearoperator(A)


def general_eigenpairs(A, weights, k=None, sigma=0.0, real=True, vectors=True,
                       normA=None) -> EigenSolution:
    """Eigenpairs of a non-normal matrix (dense, or the ``k`` nearest ``sigma``) with errors.

    Parameters
    ----------
    A : matrix, shape (n, n)
    weights : ndarray, shape (n,)
        Quadrature weights of the inner product normalising the eigenvectors.
    k : int, optional
    sigma : float
    real : bool
        Return real parts (the theory says the spectrum is real).
    vectors : bool
    normA : float, optional
        Operator norm of ``A`` (estimated if omitted).

    Returns
    -------
    EigenSolution
        Sorted by decreasing real part; ``max_imag`` is the largest relative imaginary
        part before taking real parts.
    """
    if k is None:
        Ad = to_dense(A)
        vals, left, right = sla.eig(Ad, left=True, right=True)
        normA = float(np.linalg.norm(Ad, 2)) if normA is None else normA
        errors = _condition_errors(Ad, vals, right, left, normA)
        method = "dense"
    else:
        n = A.shape[0]
        k = int(min(k, n - 2))
        v0 = np.random.default_rng(0).standard_normal(n)
        try:
            OPinv = _shift_invert_general(A, sigma)
            OPinvT = _shift_invert_general(A, sigma, transpose=True)
        except np.linalg.LinAlgError:
            sigma = sigma + 1e-10 * max(1.0, abs(sigma))
            OPinv = _shift_invert_general(A, sigma)
            OPinvT = _shift_invert_general(A, sigma, transpose=True)
        vals, right = spla.eigs(_as_operator(A), k=k, sigma=sigma, OPinv=OPinv, which="LM", v0=v0)
        lvals, left = spla.eigs(_as_operator(A).T if not isinstance(A, SparsePlusLowRank)
                                else A.T.aslinearoperator(), k=k, sigma=sigma, OPinv=OPinvT,
                                which="LM", v0=v0)
        # pair each right eigenvalue with the nearest left one
        idx = np.array([int(np.argmin(np.abs(lvals - v))) for v in vals])
        left = left[:, idx]
        if normA is None:
            normA = float(np.max(np.abs(vals)))
        errors = _condition_errors(A, vals, right, left, normA)
        method = "shift-invert"
    scale = np.max(np.abs(vals)) if vals.size else 1.0
    max_imag = float(np.max(np.abs(vals.imag)) / scale) if scale > 0 else 0.0
    if real:
        vals, right = vals.real, right.real
    norms = np.sqrt(np.sum(weights[:, None] * np.abs(right) ** 2, axis=0))
    right = right / np.where(norms > 0, norms, 1.0)
    order = np.lexsort((np.imag(vals), -np.real(vals)))
    return EigenSolution(vals[order], right[:, order] if vectors else None, errors[order],
                         np.zeros(vals.size, bool), method, _EPS * normA, max_imag)
