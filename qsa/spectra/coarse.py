"""Solves with the shift-invert core when a two-point term is compressed to a coarse state.

A panel-interpolated pair Hessian (:mod:`qsa.energies.adhesion_interp`) enters the
implicit state of :class:`~qsa.spectra.factored.ShiftInvert` as a coarse state ``z``
(``r = 3M`` rows, ``z = B^T S x``) with its adjoint ``m``; the coarse-coarse block is the
interpolated kernel ``C`` (dense in effect). Ordered as ``(x, z, m)``, ``x`` every other
unknown (the *narrow* system: the local ``3N`` rows, ``u``, ``v`` and the nodes' own
states and adjoints), the core is ::

    [[A, 0, W],
     [0, C, I],
     [V, I, 0]],      A narrow (a few entries per row), V, W sparse (r rows / columns).

Eliminating ``x`` leaves ``[[C, I], [I, -T]]`` with ``T = V A^{-1} W``, and then
``(I + C T) m = g - C h + C V A^{-1} f`` for the right-hand side ``(f, g, h)``::

    y = A^{-1} f,   m = (I + C T)^{-1} (g - C (h - V y)),
    x = y - A^{-1} W m,   z = h - V x.

``I + C T`` (``r x r``) is factored by LAPACK; a solve is two narrow sparse solves, a
product with ``C`` and ``O(r^2)`` with the dense factors.

``T`` is formed by substructuring along the curve. The narrow unknowns belong to nodes,
and ``A`` couples nodes at most ``s`` apart (``s = 1`` for CHA). Cut the nodes into
``K`` chunks and take the unknowns of the first ``s`` nodes of each chunk as the
interface ``G``; the interiors of different chunks are then uncoupled, so with
``A_k`` the interior blocks ::

    T = sum_k V_k A_k^{-1} W_k  +  E S^{-1} F,
    S = A_GG - sum_k A_Gk A_k^{-1} A_kG,   F = W_G - sum_k A_Gk A_k^{-1} W_k,
    E = V_G - sum_k V_k A_k^{-1} A_kG,

each interior solve has the few columns of ``W`` living on its chunk (a column of ``W``
is one interpolation panel's), ``S`` is ``|G| x |G|`` with ``|G|`` the unknowns of
``K s`` nodes, and ``C T`` costs ``2 r^2 |G| + 2 r^3 / K`` instead of the ``2 r^3`` of a
dense product. A sparse LU of the whole core factors the same coarse block at about a sixth
of LAPACK's rate and fills in beyond it.

The elimination is exact in exact arithmetic; :class:`~qsa.spectra.factored.ShiftInvert`
refines every solve against the residual of the whole core.
``det`` of the core is ``(-1)^r det A det(I + C T)``.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from qsa.linalg.lu import _lapack_sign, factorize

__all__ = ["CoarseSchurCore", "CHUNKS"]

#: Chunks of nodes for the substructured ``T`` (fewer when the chunks would be shorter
#: than eight times the coupling reach).
CHUNKS = 32


def _nodes(N, p, q, coarse):
    """Node of every unknown of the core ``[3N | p | p | q | q]``, -1 for the coarse ones.

    Blocks are nodal (``N`` consecutive unknowns per field); within the state and its
    adjoint the coarse rows are skipped.
    """
    if p % N or (q - coarse.size) % N:
        raise ValueError("the implicit state is not nodal: no substructuring")
    local = np.arange(3 * N + 2 * p) % N
    j = np.arange(q)
    is_coarse = np.zeros(q, dtype=bool)
    is_coarse[coarse] = True
    state = (j - np.cumsum(is_coarse) + is_coarse) % N  # rank among the nodal rows
    state[is_coarse] = -1
    return np.concatenate([local, state, state])


def _range(idx):
    """``idx`` (sorted, distinct) as a slice when it is a range (a view, not a copy)."""
    if idx.size and idx[-1] - idx[0] + 1 == idx.size:
        return slice(int(idx[0]), int(idx[-1]) + 1)
    return idx


class CoarseSchurCore:
    """Solutions with the shift-invert core of a compressed two-point term (module docstring).

    Parameters
    ----------
    core : sparse matrix, shape (n, n)
        ``n = 3N + 2p + 2q``, laid out as in :class:`~qsa.spectra.factored.ShiftInvert`.
    N : int
        Nodes.
    p, q : int
        Sizes of the implicit state's domain and state
        (:class:`~qsa.linalg.ReducedHessian`).
    coarse : ndarray of int
        The coarse state rows (``ReducedHessian.coarse_index``, within ``q``).
    chunks : int, optional
        Chunks of nodes (default :data:`CHUNKS`).

    Attributes
    ----------
    shape : tuple of int
    nnz : int
        Stored entries of the factors (narrow LU, ``C``, ``I + C T``).
    interface : int
        Unknowns of the interface ``G``.
    rcond : float
        LAPACK's estimate of the reciprocal 1-norm condition number of ``I + C T``.

    Raises
    ------
    ValueError
        The core does not have the structure above (the caller factors it otherwise).
    numpy.linalg.LinAlgError
        A block is singular to working precision.
    """

    def __init__(self, core, N, p, q, coarse, chunks=None):
        M = sp.csr_matrix(core)
        n = M.shape[0]
        if n != 3 * N + 2 * p + 2 * q:
            raise ValueError(f"core of size {n}, expected 3N + 2p + 2q = {3 * N + 2 * p + 2 * q}")
        coarse = np.asarray(coarse, dtype=np.intp)
        r = coarse.size
        if r == 0:
            raise ValueError("no coarse state")
        node = _nodes(N, p, q, coarse)
        X = np.nonzero(node >= 0)[0]
        # coarse unknowns in the order of the first node they act on (a chunk's coarse
        # rows and columns are then ranges)
        Mm = M[3 * N + 2 * p + q + coarse]
        first = Mm.tocoo()
        pos = np.full(r, N, dtype=np.intp)
        np.minimum.at(pos, first.row, np.where(node[first.col] >= 0, node[first.col], N))
        order = np.argsort(pos, kind="stable")
        coarse = coarse[order]
        zi = 3 * N + 2 * p + coarse
        mi = zi + q
        self.shape = (n, n)
        self._zi, self._mi, self._X = zi, mi, X
        MX, Mz, Mm = M[X], M[zi], Mm[order]
        A = MX[:, X].tocsr()
        self._W = MX[:, mi].tocsr()
        self._V = Mm[:, X].tocsr()
        self._C = Mz[:, zi].tocsr()
        eye = sp.identity(r, format="csr")
        if (MX[:, zi].count_nonzero() or Mz[:, X].count_nonzero()
                or Mm[:, mi].count_nonzero() or (Mz[:, mi] - eye).count_nonzero()
                or (Mm[:, zi] - eye).count_nonzero()):
            raise ValueError("the coarse rows are not [[0, C, I], [V, I, 0]]")
        del MX, Mz, Mm
        T_parts, E, S, F, self.interface = self._substructure(A, node[X], N, chunks)
        # I + C T = I + sum_k C[:, rows_k] T_k + (C E) S^{-1} F
        Cd = self._C.toarray()
        Q = (Cd @ E) @ sla.lu_solve(S, F, check_finite=False)
        del E, F
        for rows, cols, Tk in T_parts:
            Q[:, cols] += Cd[:, rows] @ Tk
        del Cd, T_parts
        Q[np.diag_indices(r)] += 1.0
        if not np.all(np.isfinite(Q)):
            raise np.linalg.LinAlgError("I + C T has non-finite entries")
        anorm = np.abs(Q).sum(axis=0).max()
        lu, piv = sla.lu_factor(Q, overwrite_a=True, check_finite=False)
        if np.any(np.diag(lu) == 0):
            raise np.linalg.LinAlgError("I + C T is singular")
        self._Q = (lu, piv)
        self.rcond = float(sla.lapack.dgecon(lu, anorm, norm="1")[0])
        self._A = factorize(A.tocsc())
        self.nnz = int(self._A.nnz + self._C.nnz + r * r)

    def _substructure(self, A, node, N, chunks):
        """``(T_parts, E, S_lu, F, |G|)``: ``T = sum T_parts + E S^{-1} F`` (module docstring)."""
        coo = A.tocoo()
        d = np.abs(node[coo.row] - node[coo.col])
        s = int(np.max(np.minimum(d, N - d), initial=0))
        K = int(CHUNKS if chunks is None else chunks)
        K = max(min(K, N // (8 * (s + 1))), 2)
        if N < 2 * 8 * (s + 1):
            raise ValueError("too few nodes to substructure")
        bounds = (np.arange(K + 1) * N) // K
        chunk = np.searchsorted(bounds, node, side="right") - 1
        label = np.where(node - bounds[chunk] < s, K, chunk)  # K: the interface
        if np.any((label[coo.row] != label[coo.col]) & (label[coo.row] < K)
                  & (label[coo.col] < K)):
            raise ValueError("chunk interiors are coupled")
        del coo
        order = np.argsort(label, kind="stable")
        ptr = np.searchsorted(label[order], np.arange(K + 2))
        Ap = A[order][:, order].tocsr()
        Wp = self._W[order].tocsr()
        Vp = self._V[:, order].tocsc()
        g0, nX = ptr[K], A.shape[0]
        nG = nX - g0
        AG = Ap[g0:]                               # interface rows
        S = AG[:, g0:].toarray()
        F = Wp[g0:].toarray()
        E = Vp[:, g0:].toarray()
        T_parts = []
        for k in range(K):
            a, b = ptr[k], ptr[k + 1]
            if b == a:
                continue
            lu = factorize(Ap[a:b, a:b].tocsc())
            AkG = Ap[a:b, g0:]
            gcols = np.unique(AkG.indices)
            Wk = Wp[a:b]
            wcols = np.unique(Wk.indices)
            Vk = Vp[:, a:b].tocsr()
            rows = np.nonzero(np.diff(Vk.indptr))[0]
            Z = lu.solve(AkG[:, gcols].toarray())
            Y = lu.solve(Wk[:, wcols].toarray())
            AGk = AG[:, a:b]
            S[:, gcols] -= AGk @ Z
            F[:, wcols] -= AGk @ Y
            Vr = Vk[rows]
            E[np.ix_(rows, gcols)] -= Vr @ Z
            T_parts.append((_range(rows), _range(wcols), Vr @ Y))
        S_lu = sla.lu_factor(S, overwrite_a=True, check_finite=False)
        if np.any(np.diag(S_lu[0]) == 0) or not np.all(np.isfinite(S_lu[0])):
            raise np.linalg.LinAlgError("the interface Schur complement is singular")
        return T_parts, E, S_lu, F, nG

    def solve(self, b):
        """``x`` with ``core x = b``; ``b`` of shape (n,) or (n, k)."""
        b = np.asarray(b, dtype=float)
        X, zi, mi = self._X, self._zi, self._mi
        f, g, h = b[X], b[zi], b[mi]
        y = self._A.solve(f)
        m = sla.lu_solve(self._Q, g - self._C @ (h - self._V @ y), check_finite=False)
        x = y - self._A.solve(self._W @ m)
        out = np.empty_like(b)
        out[X] = x
        out[zi] = h - self._V @ x
        out[mi] = m
        return out

    def det_sign(self) -> int:
        """Sign of the determinant of the core, ``(-1)^r sign(det A) sign(det(I + C T))``."""
        return int(self._A.det_sign() * _lapack_sign(*self._Q) * (-1) ** (self._zi.size % 2))
