"""Second variation of the closure constraints, dense or factored (e:cC-Hessian, e:cC-Hessian3).

The closure ``C(U) = (int tau dsigma, int kappa dsigma - 2 pi)`` (e:C1, e:C2) has the
Hessians (with respect to ``<f, h> = int f h dsigma``, convention
``C(U + delta U1) = C + delta <Psi, U1> + delta^2/2 <H_C U1, U1>``)

    H_C3 = [[0, 1/g], [1/g, 0]],

and for ``j = 1, 2``, with ``tau'_j = d tau_j / d theta``, ``eta = kappa1 + kappa g1/g``,
``B = D-dagger(tau'_j g1/g)`` and ``C = D-dagger(tau_j D eta)``,

    (H_Cj U1)_kappa = (g1/g) D-dagger tau'_j + B - C,
    (H_Cj U1)_g     = (kappa1/g) D-dagger tau'_j + tau'_j (D eta)/g + (kappa/g)(B - C)

(the printed e:cC-Hessian is wrong; this is its corrected form). ``D f = int_0^s f dsigma``
jumps across ``s = 0 == 1`` when ``int f dsigma != 0``; with ``D`` at node 0 replaced by
the mean of its one-sided limits, ``(D f)_0 = (1/2) int f dsigma`` (call it ``Dm``),
and ``D-dagger = 1 dsigma^T - Dm``, the quadratic form is second order on both grid
kinds (the periodic rule becomes the trapezoid rule for the jumping integrands).

Structure
---------
Only a combination ``sum_j Lambda_j H_Cj`` is ever needed (the Lagrangian Hessian
``nabla^2 E - Lambda . nabla^2 C``). Collecting the terms, with ``A = Dm tau_Lambda``,
``tau_Lambda = sum_j Lambda_j tau_j`` (likewise ``tau'_Lambda``, ``a = D-dagger tau'_Lambda``,
``A1 = int tau_Lambda dsigma``) and the two ``N x 2N`` maps

    E = [I, diag(kappa/g)]   (E U1 = eta),     P = [diag(A), diag((tau'_Lambda + kappa A)/g)],

the combination is

    H = [[0, diag(a/g)], [diag(a/g), 0]] + P^T Dm E - E^T Dm P
        + (E^T 1) r^T,   r = [dsigma (A - A1), dsigma (tau'_Lambda + kappa (A - A1)) / g],

symmetrised in ``<.,.>`` (``(H + W^{-1} H^T W) / 2``, ``W = diag(dsigma, dsigma)``).
``Dm = C diag(g) + e_0 dsigma^T / 2`` with ``C`` the grid's cumulative integral: so
``H`` is diagonal plus low rank plus two cumulative integrals. On finite-difference
grids ``C = Bd^{-1} R`` (:func:`~qsa.discretize.cumulative_factors`) and the two states
``Y = (C g P U1, C g E U1)`` solve sparse lower-triangular equations: ``H`` is the
:class:`~qsa.linalg.ReducedHessian` with

    K = Lyu^T Z + Z^T Lyu,   Lyu = (1/2) [-E W; P W],   Luu = Lyy = 0,
    cY = diag(Bd, Bd),       cU = -[R diag(g) P; R diag(g) E],

left factor ``W^{-1}``, the diagonal part as ``S`` and the symmetrised rank-three
remainder as ``U V^T``: O(N) storage and products at any N, exact (the same matrix as
the dense assembly, which is O(N^2)).

Examples
--------
>>> import numpy as np
>>> from qsa import Curve, FiniteDifference
>>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), FiniteDifference(64))
>>> Lam = np.array([0.3, -0.2, 0.5])
>>> Hf = closure_hessian(c, Lam, form="factored")
>>> Hd = closure_hessian(c, Lam, form="dense")
>>> bool(np.allclose(Hf.toarray(), Hd, atol=1e-12 * np.abs(Hd).max()))
True
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from qsa.curve import Curve
from qsa.discretize import cumulative_factors
from qsa.linalg import ReducedHessian

__all__ = ["closure_hessian", "curvature_closure_hessian", "CLOSURE_HESSIAN_FORMS"]

#: The forms of :func:`closure_hessian`.
CLOSURE_HESSIAN_FORMS = ("auto", "dense", "factored")


def curvature_closure_hessian(c: Curve):
    """``nabla^2 C_3 = [[0, 1/g], [1/g, 0]]`` (e:cC-Hessian3, corrected) in the grid's matrix type.

    Parameters
    ----------
    c : Curve

    Returns
    -------
    sparse CSR matrix (finite differences) or ndarray (Fourier), shape (2N, 2N)
        Hessian in ``<f, h> = int f h dsigma``: ``<H U1, U1> = 2 int kappa1 g1 ds``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(1.0, Fourier(9))
    >>> U1 = np.concatenate([np.ones(9), np.full(9, 2.0)])
    >>> H = curvature_closure_hessian(c)
    >>> round(float((H @ U1) @ (U1 * np.concatenate([c.dsigma] * 2))), 12)  # 2 * 1 * 2
    4.0
    """
    N = c.N
    if c.grid.sparse:
        d = sp.diags(1.0 / c.g)
        return sp.bmat([[None, d], [d, None]], format="csr")
    out = np.zeros((2 * N, 2 * N))
    idx = np.arange(N)
    out[idx, N + idx] = 1.0 / c.g
    out[N + idx, idx] = 1.0 / c.g
    return out


class _Pieces:
    """The vectors of the module docstring for weights ``(Lambda_1, Lambda_2)`` at ``c``."""

    def __init__(self, c: Curve, lam1, lam2):
        N = c.N
        self.c = c
        g, kappa, ds = c.g, c.kappa, c.dsigma
        th = c.theta()
        tau = lam1 * np.cos(th) + lam2 * np.sin(th)
        taup = -lam1 * np.sin(th) + lam2 * np.cos(th)      # d tau / d theta, combined
        A = self.Dm(tau)
        A1 = tau @ ds
        self.a = (taup @ ds) - self.Dm(taup)                # D-dagger tau'
        self.pk, self.pg = A, (taup + kappa * A) / g        # P = [diag(pk), diag(pg)]
        self.ek, self.eg = np.ones(N), kappa / g            # E = [I, diag(kappa/g)]
        self.r = np.concatenate([ds * (A - A1), ds * (taup + kappa * (A - A1)) / g])

    def Dm(self, f):
        """``D f`` with the mean of the one-sided limits at node 0."""
        c = self.c
        out = c.D(f)
        out[0] = 0.5 * (f @ c.dsigma)
        return out

    def low_rank(self) -> tuple[np.ndarray, np.ndarray]:
        """``(U, V)`` with ``H``'s rank-three part ``U V^T`` before symmetrisation.

        ``(E^T 1) r^T`` and the ``e_0 dsigma^T / 2`` parts of the two ``Dm``:
        ``P^T e_0 (E^T dsigma)^T / 2 - E^T e_0 (P^T dsigma)^T / 2``.
        """
        c = self.c
        N = c.N
        ds = c.dsigma
        Et1 = np.concatenate([self.ek, self.eg])
        e0 = np.zeros(N)
        e0[0] = 1.0
        Pt_e0 = np.concatenate([self.pk * e0, self.pg * e0])
        Et_e0 = np.concatenate([self.ek * e0, self.eg * e0])
        Pt_ds = np.concatenate([self.pk * ds, self.pg * ds])
        Et_ds = np.concatenate([self.ek * ds, self.eg * ds])
        U = np.column_stack([Et1, Pt_e0, -Et_e0])
        V = np.column_stack([self.r, 0.5 * Et_ds, 0.5 * Pt_ds])
        return U, V

    def diagonal_part(self):
        """``[[0, diag(a/g)], [diag(a/g), 0]]``, sparse."""
        d = sp.diags(self.a / self.c.g)
        return sp.bmat([[None, d], [d, None]], format="csr")


def _symmetrised_low_rank(U, V, w2):
    """``(U', V')`` with ``U' V'^T = (U V^T + W^{-1} V U^T W) / 2``, ``W = diag(w2)``."""
    return (np.hstack([0.5 * U, 0.5 * V / w2[:, None]]),
            np.hstack([V, U * w2[:, None]]))


def _dense(pieces: _Pieces) -> np.ndarray:
    c = pieces.c
    N = c.N
    w2 = np.concatenate([c.dsigma, c.dsigma])
    Cg = c.grid.cumulative_matrix() * c.g[None, :]          # D
    E = np.hstack([np.diag(pieces.ek), np.diag(pieces.eg)])
    P = np.hstack([np.diag(pieces.pk), np.diag(pieces.pg)])
    H = P.T @ (Cg @ E) - E.T @ (Cg @ P)
    U, V = pieces.low_rank()
    H += U @ V.T
    idx = np.arange(N)
    H[idx, N + idx] += pieces.a / c.g
    H[N + idx, idx] += pieces.a / c.g
    return 0.5 * (H + (H.T * w2[None, :]) / w2[:, None])


def _factored(pieces: _Pieces) -> ReducedHessian:
    c = pieces.c
    N = c.N
    w2 = np.concatenate([c.dsigma, c.dsigma])
    d = sp.diags
    E = sp.hstack([d(pieces.ek), d(pieces.eg)], format="csr")
    P = sp.hstack([d(pieces.pk), d(pieces.pg)], format="csr")
    Bd, R = cumulative_factors(N)
    W = d(w2)
    Lyu = 0.5 * sp.vstack([-(E @ W), P @ W], format="csr")
    Rg = R @ d(c.g)
    cY = sp.block_diag([Bd, Bd], format="csr")
    cU = -sp.vstack([Rg @ P, Rg @ E], format="csr")
    U, V = _symmetrised_low_rank(*pieces.low_rank(), w2)
    zero = sp.csr_matrix((2 * N, 2 * N))
    return ReducedHessian(zero, Lyu, sp.csr_matrix((2 * N, 2 * N)), cY, cU,
                          left=d(1.0 / w2), S=pieces.diagonal_part(), U=U, V=V)


def closure_hessian(c: Curve, weights, form="auto"):
    """``sum_j weights_j nabla^2 C_j``: the closure part of ``L_Lambda`` (e:cC-Hessian).

    Parameters
    ----------
    c : Curve
    weights : array_like, shape (3,)
        ``(Lambda_1, Lambda_2, Lambda_3)``.
    form : {"auto", "dense", "factored"}
        ``"dense"``: ndarray (O(N^2) memory). ``"factored"`` (finite differences only):
        a :class:`~qsa.linalg.ReducedHessian` with O(N) storage and products.
        ``"auto"``: factored on finite-difference grids, dense on Fourier grids; a
        sparse matrix whenever ``Lambda_1 = Lambda_2 = 0``.

    Returns
    -------
    ndarray, sparse matrix or ReducedHessian, shape (2N, 2N)
        Self-adjoint in ``<f, h> = int f h dsigma``.

    Raises
    ------
    ValueError
        ``weights`` not three finite numbers, an unknown ``form``, or ``"factored"``
        on a Fourier grid (its cumulative integral is dense).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier, geometry
    >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
    >>> H = closure_hessian(c, [1.0, 0.0, 0.0])
    >>> bool(np.allclose(H, geometry.constraint_hessians(c)[0]))
    True
    """
    lam = np.asarray(weights, dtype=float)
    if lam.shape != (3,) or not np.all(np.isfinite(lam)):
        raise ValueError(f"weights must be three finite numbers (Lambda_1..3), got {weights!r}")
    if form not in CLOSURE_HESSIAN_FORMS:
        raise ValueError(f"form must be one of {CLOSURE_HESSIAN_FORMS}, got {form!r}")
    if form == "factored" and not c.grid.sparse:
        raise ValueError("form='factored' needs a finite-difference grid (on Fourier grids the "
                         "cumulative integral is dense); use form='dense'")
    H3 = curvature_closure_hessian(c)
    if lam[0] == 0.0 and lam[1] == 0.0 and form == "auto":
        return lam[2] * H3
    pieces = _Pieces(c, lam[0], lam[1])
    if form == "dense" or (form == "auto" and not c.grid.sparse):
        out = _dense(pieces)
        return out + lam[2] * (H3.toarray() if sp.issparse(H3) else H3)
    return _factored(pieces) + lam[2] * H3
