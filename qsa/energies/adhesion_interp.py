"""The adhesion pair Hessian by panel interpolation in the curve parameter (rank free of N).

The pair Hessian ``K`` of ``E^(X, w)`` (:meth:`AdhesionDerivatives.pair_hessian
<qsa.energies.adhesion_hessian.AdhesionDerivatives.pair_hessian>`) is built from six
pair functions ``G(r, c) = g(X_r - X_c)`` (:mod:`qsa.energies.adhesion_far`) ::

    K_xx = -W G_xx W + diag(W G_xx w)   (likewise xy, yy),
    K_xw = W G_x + diag(G_x w),   K_yw = W G_y + diag(G_y w),   K_ww = G_w + 2 A0 I,

``W = diag(w)``, ``w = dsigma``. The kernel ``A(l)`` is entire in ``l = |d|^2``, so
every ``g`` is analytic in ``d`` (also at ``d = 0``) and ``G(r, c)`` is a smooth
function of the two curve parameters ``s_r, s_c`` (``s_i = i / N``). Cut the parameter
circle into panels and interpolate on each side by Lagrange polynomials through ``p``
fine nodes of each panel (those nearest to its Chebyshev points; a panel with at most
``p`` fine nodes keeps all of them). Panels start at arc length ``panel_length l*``;
each takes the lowest degree ``p`` of ``degrees`` at which the six functions
``g(X(s) - y)`` interpolate to ``tol`` (relative to their largest values) for probes
``y`` on and beside the panel (normal offsets up to ``l*``), and is bisected if none
does, so tight turns get short panels ::

    G ~ Pi Ghat Pi^T,   Pi (N x M) sparse,  Ghat[a, b] = g(X_{i(a)} - X_{i(b)}),

with ``Pi[i(a), a] = 1`` (coarse points are fine nodes, ``Ghat`` exact kernel values).
Then ::

    K ~ B C B^T + D,   B = blockdiag(W Pi, W Pi, Pi),
    C = [[-Gxx, -Gxy, Gx], [-Gxy, -Gyy, Gy], [Gx^T, Gy^T, Gw]]   (hats omitted),

``C`` symmetric (``Gx, Gy`` antisymmetric), with the blocks of panel pairs whose
bounding circles are farther apart than the neighbour list's cutoff dropped (``K`` has
no pair there; within the kept blocks the coarse pairs beyond the cutoff at
``tol / 100`` are dropped too), and ``D`` block diagonal (one 3 x 3 block per node): the exact
diagonal blocks of ``K`` (row sums over the neighbour list, streamed panel by panel)
minus those of ``B C B^T``. ``M`` depends on the curve's length over ``l*`` and its
curvature, not on ``N``, once the panels hold more nodes than their degrees (below
that, short panels keep all their nodes and ``M`` grows with ``N`` up to its limit);
storage is O(N + nnz(C)), the kernel values of the pairs are never stored.

Error control: rows of ``K`` at one random node per panel (at most ``samples``) are
evaluated exactly (O(N) each) and compared with the compressed rows;
``error_estimate`` is the largest relative error ``||K~_r - K_r|| / ||K_r||`` over the
sampled nodes (the three rows ``x_r, y_r, w_r`` together). Above ``tol`` the panels
are shortened and the compression rebuilt (``attempts`` times), then a warning.

The reduced Hessian of ``local + S^T (B C B^T + D) S``
(:func:`interpolated_reduced_hessian`) is an exact-form
:class:`~qsa.linalg.ReducedHessian` with the implicit state extended by
``z = B^T S (u, y)`` in ``R^{3M}``.
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from qsa.curve import Curve
from qsa.energies.adhesion_hessian import adjoint_fields, local_reduced_parts, pair_vectors
from qsa.linalg import ReducedHessian

__all__ = ["InterpolatedPairHessian", "interpolated_pair_hessian", "coarse_rank",
           "interpolated_reduced_hessian", "interpolated_hessian", "DEGREES",
           "ERROR_SAFETY"]

#: Default candidate degrees of :func:`interpolated_pair_hessian`.
DEGREES = (8, 10, 12, 14, 16, 18, 20, 22, 24, 28, 32)

#: Factor on the sampled error estimate in :func:`interpolated_hessian`'s error bound (the
#: sampled rows missed the largest row error by up to 1.5x in the measurements).
ERROR_SAFETY = 3.0

_NAMES = ("w", "x", "y", "xx", "xy", "yy")


def _pair_values(kernel, dx, dy):
    """The six pair functions ``{name: g(d)}`` at differences ``d = (dx, dy)``."""
    A, dA, d2A = kernel.derivatives(dx * dx + dy * dy)
    t = 8.0 * d2A
    return {"w": 2.0 * A, "x": 4.0 * dA * dx, "y": 4.0 * dA * dy,
            "xx": t * dx * dx + 4.0 * dA, "xy": t * dx * dy, "yy": t * dy * dy + 4.0 * dA}


# ------------------------------------------------------------------ panels
def _chebyshev(degree):
    """Chebyshev points of the first kind on ``[0, 1]``."""
    return 0.5 * (1.0 - np.cos((2 * np.arange(degree) + 1) * np.pi / (2 * degree)))


def _chosen(f0, f1, degree):
    """The interpolation nodes of a panel with fine nodes ``f0 .. f1 - 1``: all of them if
    there are at most ``degree``, else the ``degree`` nearest to its Chebyshev points
    (made distinct, in order)."""
    n = f1 - f0
    if n <= degree:
        return np.arange(f0, f1)
    idx = np.rint(_chebyshev(degree) * n - 0.5).astype(np.int64)
    k = np.arange(degree)
    # idx - k nondecreasing in [0, n - degree]: idx strictly increasing in [0, n - 1]
    return f0 + np.maximum.accumulate(np.clip(idx - k, 0, n - degree)) + k


def _panel_error(kernel, x, y, nx, ny, f0, f1, degree, scale):
    """Largest interpolation error of the six pair functions on one panel, relative to
    their largest values ``scale``, at probes on and beside the panel's nodes."""
    fine = np.arange(f0, f1)
    ch = _chosen(f0, f1, degree)
    if ch.size == fine.size:
        return 0.0
    L = _barycentric(ch.astype(float), fine.astype(float))
    off = kernel.l_star * np.array([-1.0, -0.5, 0.0, 0.5, 1.0])
    px = (x[ch, None] + nx[ch, None] * off).ravel()
    py = (y[ch, None] + ny[ch, None] * off).ravel()
    G = _pair_values(kernel, x[fine, None] - px, y[fine, None] - py)
    pos = np.searchsorted(fine, ch)
    return max(float(np.max(np.abs(L @ G[n][pos] - G[n]))) / scale[n] for n in _NAMES)


def _panels(kernel, c: Curve, degrees, panel_length, tol):
    """Panels (first fine node of each, ``fine_ptr``) and their degrees.

    Arc length ``panel_length l*`` to start with; each panel takes the lowest of
    ``degrees`` whose :func:`_panel_error` is at most ``tol``, or is bisected if none is
    (a panel too short to pick points from keeps all its nodes and passes).
    """
    N = c.N
    x, y = c.positions()
    th = c.theta()
    nx, ny = -np.sin(th), np.cos(th)
    r = np.linspace(0.0, kernel.cutoff_distance(1e-16), 2001)
    G = _pair_values(kernel, r, 0.0 * r)
    G["y"], G["yy"], G["xy"] = G["x"], G["xx"], 0.5 * G["xx"]
    scale = {n: float(np.max(np.abs(v))) for n, v in G.items()}
    Q = np.concatenate([[0.0], np.cumsum(c.g) / N])
    n = max(int(math.ceil(Q[-1] / (panel_length * kernel.l_star) - 1e-9)), 1)
    b = np.interp(np.linspace(0.0, Q[-1], n + 1), Q, np.arange(N + 1) / N)
    todo = [(int(f0), int(f1)) for f0, f1 in itertools.pairwise(
        np.unique(np.concatenate([[0], np.ceil(b * N - 1e-9).astype(np.int64), [N]])))]
    done = []
    while todo:
        f0, f1 = todo.pop()
        for p in degrees:
            if _panel_error(kernel, x, y, nx, ny, f0, f1, p, scale) <= tol:
                done.append((f0, f1, p))
                break
        else:
            m = (f0 + f1) // 2
            todo += [(f0, m), (m, f1)]
    done.sort()
    fine_ptr = np.array([d[0] for d in done] + [N])
    return fine_ptr, np.array([d[2] for d in done])


def _barycentric(nodes, points):
    """Lagrange weights, shape (len(points), len(nodes)), exactly 1 at the nodes."""
    lo, hi = nodes.min(), nodes.max()
    scale = 2.0 / (hi - lo) if hi > lo else 1.0
    t = (nodes - lo) * scale
    diff = t[:, None] - t[None, :]
    np.fill_diagonal(diff, 1.0)
    bw = 1.0 / np.prod(diff, axis=1)
    d = (points - lo)[:, None] * scale - t[None, :]
    hit = d == 0.0
    d[hit] = 1.0
    L = bw[None, :] / d
    L /= L.sum(axis=1, keepdims=True)
    rows = hit.any(axis=1)
    L[rows] = hit[rows].astype(float)
    return L


def _interpolation(N, fine_ptr, degrees):
    """``Pi`` (N x M, CSR), the fine node of each coarse point and the panels' coarse ranges.

    Returns ``Pi, nodes, coarse_ptr``: panel ``k`` holds fine nodes
    ``fine_ptr[k]:fine_ptr[k+1]`` and coarse points ``coarse_ptr[k]:coarse_ptr[k+1]``.
    """
    rows, cols, vals, nodes, coarse_ptr = [], [], [], [], [0]
    for k in range(fine_ptr.size - 1):
        f0, f1 = int(fine_ptr[k]), int(fine_ptr[k + 1])
        fine = np.arange(f0, f1)
        chosen = _chosen(f0, f1, degrees[k])
        L = _barycentric(chosen.astype(float), fine.astype(float))
        m0 = coarse_ptr[-1]
        rows.append(np.repeat(fine, chosen.size))
        cols.append(np.tile(np.arange(m0, m0 + chosen.size), fine.size))
        vals.append(L.ravel())
        nodes.append(chosen)
        coarse_ptr.append(m0 + chosen.size)
    M = coarse_ptr[-1]
    Pi = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(N, M))
    Pi.eliminate_zeros()
    return Pi, np.concatenate(nodes), np.asarray(coarse_ptr)


def _panel_pairs(x, y, fine_ptr, cutoff):
    """Panel pairs ``(P, Q)`` (both orders, with ``P = Q``) whose bounding circles come
    within ``cutoff``: every fine pair closer than the cutoff lies in one of them."""
    n = fine_ptr.size - 1
    idx = np.repeat(np.arange(n), np.diff(fine_ptr))
    cnt = np.diff(fine_ptr)
    cx, cy = np.bincount(idx, x, n) / cnt, np.bincount(idx, y, n) / cnt
    rad = np.sqrt(np.maximum.reduceat((x - cx[idx]) ** 2 + (y - cy[idx]) ** 2, fine_ptr[:-1]))
    gap = np.hypot(cx[:, None] - cx[None, :], cy[:, None] - cy[None, :]) - rad[:, None] - rad
    return np.nonzero(gap <= cutoff)


# --------------------------------------------------------------- pieces
def _signed_blocks(G):
    """``C``'s nine blocks from the pair functions at ``(r, c)``, shape (3, 3, ...)
    (``C_wx[r, c] = Gx(c, r) = -Gx(r, c)``)."""
    return np.stack([np.stack([-G["xx"], -G["xy"], G["x"]]),
                     np.stack([-G["xy"], -G["yy"], G["y"]]),
                     np.stack([-G["x"], -G["y"], G["w"]])])


def _coarse_matrix(kernel, xc, yc, coarse_ptr, P, Q, drop):
    """``C`` (3M x 3M, CSR, exactly symmetric) on the panel pairs ``(P, Q)`` (both orders),
    without the coarse pairs farther apart than ``drop``.

    Assembled in place row panel by row panel (a first pass counts the entries).
    """
    M = xc.size
    n = coarse_ptr.size - 1
    order = np.lexsort((Q, P))
    P, Q = P[order], Q[order]
    starts = np.searchsorted(P, np.arange(n + 1))

    def panel(p):
        r = np.arange(coarse_ptr[p], coarse_ptr[p + 1])
        cols = np.concatenate([np.arange(coarse_ptr[q], coarse_ptr[q + 1])
                               for q in Q[starts[p]:starts[p + 1]]])
        dx, dy = xc[r, None] - xc[cols], yc[r, None] - yc[cols]
        return r, cols, dx, dy, dx * dx + dy * dy <= drop * drop

    counts = np.zeros(M, dtype=np.int64)
    for p in range(n):
        r, _, _, _, keep = panel(p)
        counts[r] = 3 * keep.sum(axis=1)
    indptr = np.concatenate([[0], np.cumsum(np.tile(counts, 3))])
    itype = np.int32 if indptr[-1] < 2**31 and 3 * M < 2**31 else np.int64
    data = np.empty(indptr[-1])
    indices = np.empty(indptr[-1], dtype=itype)
    for p in range(n):
        r, cols, dx, dy, keep = panel(p)
        V = _signed_blocks(_pair_values(kernel, dx, dy))  # (a, b, row, column)
        keep3 = np.broadcast_to(keep[:, None, :], (r.size, 3, cols.size))
        allcols = np.broadcast_to(np.stack([cols, M + cols, 2 * M + cols]), keep3.shape)
        idx = allcols[keep3].astype(itype)  # row-major (row, block b, column): CSR order
        for a in range(3):
            k0, k1 = indptr[a * M + r[0]], indptr[a * M + r[-1] + 1]
            data[k0:k1] = V[a].transpose(1, 0, 2)[keep3]
            indices[k0:k1] = idx
    return sp.csr_matrix((data, indices, indptr.astype(itype)), shape=(3 * M, 3 * M))


def _diagonal_blocks(kernel, Pi, x, y, w, nodes, fine_ptr, coarse_ptr, drop):
    """The node-diagonal 3 x 3 blocks of ``B C B^T``, shape (3, 3, N): each node's row of
    ``Pi`` lives in its own panel, so only the panel's own block of ``C`` enters."""
    N = x.size
    out = np.empty((3, 3, N))
    for k in range(fine_ptr.size - 1):
        f = slice(fine_ptr[k], fine_ptr[k + 1])
        m = nodes[coarse_ptr[k]:coarse_ptr[k + 1]]
        L = Pi[f, coarse_ptr[k]:coarse_ptr[k + 1]].toarray()
        dx, dy = x[m, None] - x[m], y[m, None] - y[m]
        V = _signed_blocks(_pair_values(kernel, dx, dy)) * (dx * dx + dy * dy <= drop * drop)
        out[:, :, f] = np.einsum("ij,abjk,ik->abi", L, V, L)
    sc = np.stack([w, w, np.ones(N)])
    return out * sc[:, None, :] * sc[None, :, :]


def _exact_rows(kernel, x, y, w, A0, nodes, cutoff):
    """Rows ``x_r, y_r, w_r`` of ``K`` at nodes ``r`` (dense, shape (3k, 3N)), by the
    neighbour list's pairs ``0 < |X_r - X_c| <= cutoff``."""
    N = x.size
    k = nodes.size
    G = _pair_values(kernel, x[nodes, None] - x[None, :], y[nodes, None] - y[None, :])
    keep = ((x[nodes, None] - x) ** 2 + (y[nodes, None] - y) ** 2 <= cutoff * cutoff)
    keep[np.arange(k), nodes] = False
    G = {n: np.where(keep, v, 0.0) for n, v in G.items()}
    wr = w[nodes, None]
    out = np.zeros((3, k, 3, N))
    for a, b, name in ((0, 0, "xx"), (0, 1, "xy"), (1, 0, "xy"), (1, 1, "yy")):
        out[a, :, b] = -wr * G[name] * w
        out[a, np.arange(k), b, nodes] = (wr[:, 0] * (G[name] @ w))
    for a, name in ((0, "x"), (1, "y")):
        out[a, :, 2] = wr * G[name]
        out[2, :, a] = -G[name] * w  # K_wx[r, c] = K_xw[c, r] = w_c Gx(c, r)
        diag = G[name] @ w
        out[a, np.arange(k), 2, nodes] = diag
        out[2, np.arange(k), a, nodes] = diag
    out[2, :, 2] = G["w"]
    out[2, np.arange(k), 2, nodes] = 2.0 * A0
    return out.reshape(3 * k, 3 * N)


def _row_sums(kernel, x, y, w, fine_ptr, P, Q, cutoff, chunk=2_000_000):
    """Exact ``(sum_c Gxx w_c, Gxy, Gyy, Gx, Gy, Gw)`` over the neighbour pairs of each
    node, shape (6, N): panel by panel against its near panels (no pair list kept)."""
    N = x.size
    out = np.zeros((6, N))
    order = np.argsort(P, kind="stable")
    P, Q = P[order], Q[order]
    starts = np.searchsorted(P, np.arange(fine_ptr.size))
    for p in range(fine_ptr.size - 1):
        rows = np.arange(fine_ptr[p], fine_ptr[p + 1])
        near = Q[starts[p]:starts[p + 1]]
        cols = np.concatenate([np.arange(fine_ptr[q], fine_ptr[q + 1]) for q in near])
        step = max(1, chunk // max(cols.size, 1))
        for s0 in range(0, rows.size, step):
            r = rows[s0:s0 + step]
            dx, dy = x[r, None] - x[cols], y[r, None] - y[cols]
            keep = (dx * dx + dy * dy <= cutoff * cutoff) & (r[:, None] != cols)
            G = _pair_values(kernel, dx, dy)
            wc = np.where(keep, w[cols], 0.0)
            for n, name in enumerate(("xx", "xy", "yy", "x", "y", "w")):
                out[n, r] = np.einsum("ij,ij->i", G[name], wc)
    return out


@dataclass(frozen=True, eq=False)
class InterpolatedPairHessian:
    """The adhesion pair Hessian ``K ~ B C B^T + D`` (module docstring).

    Built by :func:`interpolated_pair_hessian`.

    Parameters
    ----------
    Pi : scipy.sparse.csr_matrix, shape (N, M)
        Interpolation from the coarse points to the nodes.
    nodes : ndarray of int, shape (M,)
        The node of each coarse point (``Pi[nodes[a], a] = 1``).
    fine_ptr, coarse_ptr : ndarray of int, shape (n_panels + 1,)
        Panel ``k``'s nodes ``fine_ptr[k]:fine_ptr[k+1]`` and coarse points
        ``coarse_ptr[k]:coarse_ptr[k+1]``.
    w : ndarray, shape (N,)
        Quadrature weights ``dsigma``.
    C : scipy.sparse.csr_matrix, shape (3M, 3M)
        Symmetric (exactly).
    D : scipy.sparse.csr_matrix, shape (3N, 3N)
        Block diagonal: one 3 x 3 block per node (rows and columns ``n, N + n, 2N + n``).
    F : ndarray, shape (N, 2)
        ``dE^/dX`` (exact, from the same row sums).
    Bw : ndarray, shape (N,)
        ``dE^/dw`` (exact).
    A0 : float
    tol : float
        The requested relative tolerance.
    error_estimate : float
        The largest sampled relative row error (module docstring).
    degrees : ndarray of int, shape (n_panels,)
        Each panel's interpolation degree (nodes; all of its nodes if it has no more).
    """

    Pi: sp.csr_matrix
    nodes: np.ndarray
    fine_ptr: np.ndarray
    coarse_ptr: np.ndarray
    w: np.ndarray
    C: sp.csr_matrix
    D: sp.csr_matrix
    F: np.ndarray
    Bw: np.ndarray
    A0: float
    tol: float
    error_estimate: float
    degrees: np.ndarray

    @property
    def N(self) -> int:
        return int(self.w.size)

    @property
    def M(self) -> int:
        """Coarse points."""
        return int(self.Pi.shape[1])

    @property
    def rank(self) -> int:
        """``3 M``, the inner dimension of ``B C B^T``."""
        return 3 * self.M

    @property
    def n_panels(self) -> int:
        return int(self.fine_ptr.size - 1)

    @property
    def shape(self):
        """Shape ``(3N, 3N)`` of ``K``."""
        return (3 * self.N, 3 * self.N)

    @property
    def B(self) -> sp.csr_matrix:
        """``blockdiag(W Pi, W Pi, Pi)``, shape (3N, 3M)."""
        WPi = sp.diags(self.w) @ self.Pi
        return sp.block_diag([WPi, WPi, self.Pi], format="csr")

    @property
    def nbytes(self) -> int:
        """Bytes of ``Pi``, ``C``, ``D`` and the node arrays."""
        mats = (self.Pi, self.C, self.D)
        return int(sum(m.data.nbytes + m.indices.nbytes + m.indptr.nbytes for m in mats)
                   + self.w.nbytes + self.F.nbytes + self.Bw.nbytes + self.nodes.nbytes)

    def matvec(self, V) -> np.ndarray:
        """``K~ V``.

        Parameters
        ----------
        V : array_like, shape (3N,) or (3N, m)

        Returns
        -------
        ndarray, shape like ``V``
        """
        V = pair_vectors(V, self.N)
        B = self.B
        return B @ (self.C @ (B.T @ V)) + self.D @ V

    def __matmul__(self, V):
        return self.matvec(V)

    def rows(self, idx) -> np.ndarray:
        """Dense rows ``idx`` of ``K~``, shape (len(idx), 3N)."""
        idx = np.asarray(idx, dtype=np.int64)
        B = self.B
        return np.asarray(((B[idx] @ self.C) @ B.T + self.D[idx]).todense())

    def toarray(self) -> np.ndarray:
        """``K~`` dense, shape (3N, 3N) (for tests at small N)."""
        return self.rows(np.arange(3 * self.N))


def _build(kernel, c, cutoff, drop, degrees, panel_length, panel_tol, sample):
    x, y = c.positions()
    w = c.dsigma
    N = c.N
    fine_ptr, degree = _panels(kernel, c, degrees, panel_length, panel_tol)
    Pi, nodes, coarse_ptr = _interpolation(N, fine_ptr, degree)
    P, Q = _panel_pairs(x, y, fine_ptr, cutoff)
    near = _panel_pairs(x, y, fine_ptr, drop) if drop < cutoff else (P, Q)
    C = _coarse_matrix(kernel, x[nodes], y[nodes], coarse_ptr, *near, drop)
    sums = _row_sums(kernel, x, y, w, fine_ptr, P, Q, cutoff)
    # exact diagonal blocks of K, order (x, y, w) x (x, y, w)
    exact = np.empty((3, 3, N))
    exact[0, 0], exact[0, 1], exact[1, 1] = w * sums[0], w * sums[1], w * sums[2]
    exact[0, 2], exact[1, 2] = sums[3], sums[4]
    exact[2, 2] = 2.0 * kernel.A0
    exact[1, 0], exact[2, 0], exact[2, 1] = exact[0, 1], exact[0, 2], exact[1, 2]
    exact -= _diagonal_blocks(kernel, Pi, x, y, w, nodes, fine_ptr, coarse_ptr, drop)
    n = np.arange(N)
    rr = np.concatenate([a * N + n for a in range(3) for _ in range(3)])
    cc = np.concatenate([bb * N + n for _ in range(3) for bb in range(3)])
    D = sp.csr_matrix((exact.reshape(-1), (rr, cc)), shape=(3 * N, 3 * N))
    F = w[:, None] * sums[3:5].T
    Bw = 2.0 * kernel.A0 * w + sums[5]
    ip = InterpolatedPairHessian(Pi, nodes, fine_ptr, coarse_ptr, w, C, D, F, Bw,
                                 float(kernel.A0), 0.0, 0.0, degree)
    # a posteriori: one random node per panel, at most `sample`
    rng = np.random.default_rng(0)
    picks = fine_ptr[:-1] + (rng.random(fine_ptr.size - 1) * np.diff(fine_ptr)).astype(int)
    if picks.size > sample:
        picks = np.sort(rng.choice(picks, sample, replace=False))
    err = 0.0
    for s0 in range(0, picks.size, 32):
        r = picks[s0:s0 + 32]
        exact_rows = _exact_rows(kernel, x, y, w, kernel.A0, r, cutoff)
        approx = ip.rows(np.concatenate([r, N + r, 2 * N + r]))  # rows (a, node) as exact
        e = np.sum(((approx - exact_rows) ** 2).reshape(3, r.size, -1), axis=(0, 2))
        nrm = np.sum((exact_rows**2).reshape(3, r.size, -1), axis=(0, 2))
        err = max(err, float(np.max(np.sqrt(e / np.maximum(nrm, 1e-300)))))
    return ip, err


def coarse_rank(kernel, c: Curve, *, tol=1e-10, degrees=DEGREES, panel_length=2.0) -> int:
    """The rank ``3M`` :func:`interpolated_pair_hessian` takes at its first build, without
    building it: the panels and their degrees alone (a small fraction of the build's cost).

    Parameters
    ----------
    kernel : AdhesionKernel
    c : Curve
    tol, degrees, panel_length
        As for :func:`interpolated_pair_hessian`.

    Returns
    -------
    int

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, FiniteDifference
    >>> from qsa.energies import Adhesion
    >>> c = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), FiniteDifference(400))
    >>> k = Adhesion(10.0, 0.5, 1.0).kernel
    >>> coarse_rank(k, c) == interpolated_pair_hessian(k, c).rank
    True
    """
    fine_ptr, degree = _panels(kernel, c, degrees, panel_length, tol)
    return int(3 * np.minimum(degree, np.diff(fine_ptr)).sum())


def interpolated_pair_hessian(kernel, c: Curve, *, tol=1e-10, degrees=DEGREES,
                              panel_length=2.0,
                              rel=1e-16, samples=256, attempts=3) -> InterpolatedPairHessian:
    """The adhesion pair Hessian ``K`` of ``c`` compressed by panel interpolation.

    Parameters
    ----------
    kernel : AdhesionKernel
    c : Curve
        Its nodes ``X_i`` are the interpolated function's samples at ``s_i = i / N``.
    tol : float
        Target of the sampled relative row error (module docstring).
    degrees : sequence of int
        Candidate interpolation degrees (nodes per panel), tried in increasing order.
    panel_length : float
        Initial panel arc length in units of ``l*``. Each panel takes the lowest degree at
        which the six pair functions interpolate to ``tol`` of their largest values at
        probes on and beside the panel, and is bisected if none does.
    rel : float
        The neighbour list's cutoff threshold (:meth:`AdhesionKernel.cutoff_distance`).
        ``C`` keeps the coarse pairs within the cutoff at ``max(rel, tol / 100)``.
    samples : int
        Nodes whose rows are checked exactly (one per panel, at most this many).
    attempts : int
        Builds (panels shortened by 0.7, panel test ten times stricter each time) while
        the estimate exceeds ``tol``.

    Returns
    -------
    InterpolatedPairHessian
        With ``error_estimate``; a :class:`RuntimeWarning` if it stayed above ``tol``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, FiniteDifference
    >>> from qsa.energies.adhesion import AdhesionKernel, adhesion_pairs
    >>> from qsa.energies.adhesion_hessian import adhesion_derivatives
    >>> c = Curve.polar(lambda t: 1 + 0.2 * np.cos(5 * t), FiniteDifference(1200))
    >>> k = AdhesionKernel(10.0, 0.5, 1.0)
    >>> H = interpolated_pair_hessian(k, c, tol=1e-10)
    >>> K = adhesion_derivatives(k, c, adhesion_pairs(k, *c.positions())).pair_hessian()
    >>> V = np.random.default_rng(0).standard_normal((3600, 3))
    >>> bool(np.linalg.norm(H @ V - K @ V) <= 1e-9 * np.linalg.norm(K @ V)), H.M < 1200
    (True, True)
    """
    tol = float(tol)
    if not (0.0 < tol < 1.0):
        raise ValueError(f"tol must lie in (0, 1), got {tol!r}")
    degrees = sorted({int(p) for p in np.atleast_1d(degrees)})
    if not degrees or degrees[0] < 2:
        raise ValueError(f"degrees must be integers >= 2, got {degrees}")
    panel_length = float(panel_length)
    if panel_length <= 0.0:
        raise ValueError(f"panel_length must be positive, got {panel_length}")
    if c.N < 2:
        raise ValueError(f"c must have at least 2 nodes, got {c.N}")
    cutoff = kernel.cutoff_distance(rel)
    drop = kernel.cutoff_distance(max(rel, 0.01 * tol))
    attempts = max(int(attempts), 1)
    for attempt in range(attempts):
        ip, err = _build(kernel, c, cutoff, drop, degrees, panel_length * 0.7**attempt,
                         tol * 0.1**attempt, int(samples))
        if err <= tol:
            break
    else:
        warnings.warn(f"interpolated_pair_hessian: sampled relative error {err:.2e} above "
                      f"tol = {tol:.1e} after {attempts} builds; raise degrees or lower "
                      f"panel_length", RuntimeWarning, stacklevel=2)
    return replace(ip, tol=tol, error_estimate=err)


def _block_diagonal(A, C):
    """``blockdiag(A, C)`` (CSR) by concatenating the CSR arrays: one copy of ``C`` and
    no COO intermediate."""
    n = A.shape[0]
    nnz = A.nnz + C.nnz
    itype = np.int32 if nnz < 2**31 and n + C.shape[1] < 2**31 else np.int64
    indptr = np.concatenate([A.indptr.astype(np.int64), A.nnz + C.indptr[1:].astype(np.int64)])
    data, indices = np.empty(nnz), np.empty(nnz, dtype=itype)
    data[:A.nnz], data[A.nnz:] = A.data, C.data
    indices[:A.nnz] = A.indices
    np.add(C.indices, n, out=indices[A.nnz:], casting="unsafe")
    return sp.csr_matrix((data, indices, indptr.astype(itype)),
                         shape=(n + C.shape[0], A.shape[1] + C.shape[1]))


def interpolated_reduced_hessian(c: Curve, ip: InterpolatedPairHessian,
                                 fields=None) -> ReducedHessian:
    """The adhesion Hessian ``nabla_I^2 E_A`` with the pair term ``B C B^T + D``, factored.

    The reduced Hessian of ``local + S^T (B C B^T + D) S``
    (:func:`~qsa.energies.adhesion_hessian.local_reduced_parts`) with the state
    ``(theta, x, y)`` extended by ``z = B^T (Su u + Sy y)`` (shape (3M,)) ::

        cY_ext = [[cY, 0], [-B^T Sy, I]],   cU_ext = [[cU], [-B^T Su]],
        Luu = local Luu + Su^T D Su,   Lyu_ext = [[local Lyu + Sy^T D Su], [0]],
        Lyy_ext = blockdiag(local Lyy + Sy^T D Sy, C).

    ``cY_ext`` is lower triangular (``cY`` is).

    Parameters
    ----------
    c : Curve
        On a finite-difference grid; the curve ``ip`` was built at.
    ip : InterpolatedPairHessian
    fields : tuple of ndarray, optional
        ``(a, p, beta)``; default from ``ip.F`` (:func:`adjoint_fields`), so no pair
        list is needed.

    Returns
    -------
    ReducedHessian, shape (2N, 2N)
        On ``(kappa, g)``, in ``<f, h> = sum f h dsigma`` like
        :meth:`AdhesionDerivatives.reduced_hessian
        <qsa.energies.adhesion_hessian.AdhesionDerivatives.reduced_hessian>`.
    """
    if not c.grid.sparse:
        raise ValueError("interpolated_reduced_hessian needs a finite-difference grid")
    if ip.N != c.N:
        raise ValueError(f"ip was built for N = {ip.N}, the curve has N = {c.N}")
    return _extended(c, ip, fields)[0]


def _extended(c, ip, fields=None):
    """``(H, local, Su, Sy)``: :func:`interpolated_reduced_hessian` and the local parts."""
    N = c.N
    a, p, beta = adjoint_fields(c, ip.F)[1:] if fields is None else fields
    local, Su, Sy = local_reduced_parts(c, a, p, beta)
    D, C = ip.D, ip.C
    BT = ip.B.T.tocsr()
    m = C.shape[0]
    Luu = local.Luu + Su.T @ D @ Su
    Lyu = sp.vstack([local.Lyu + Sy.T @ D @ Su, sp.csr_matrix((m, 2 * N))], format="csr")
    Lyy = _block_diagonal(sp.csr_matrix(local.Lyy + Sy.T @ D @ Sy), C)
    cY = sp.bmat([[local.cY, None], [-(BT @ Sy), sp.identity(m, format="csr")]], format="csr")
    cU = sp.vstack([local.cU, -(BT @ Su)], format="csr")
    return ReducedHessian(Luu, Lyu, Lyy, cY, cU, left=local.left), local, Su, Sy


def interpolated_hessian(kernel, c: Curve, *, tol=1e-10, max_rank=None, rel=1e-16):
    """The interpolated adhesion Hessian with its error estimate, or None if not smaller.

    :func:`interpolated_pair_hessian` and :func:`interpolated_reduced_hessian`, the
    latter carrying an estimate of what the compression changes in a quadratic form
    (:attr:`~qsa.linalg.ReducedHessian.approximations`): for ``l, u`` in the domain
    ``(kappa, g)``, with ``x_u = S (u, Z u)`` the pair coordinates ``(x, y, omega g)``
    of the variation (``Z`` the state's response), ::

        l^T dK u = sum_r x_l(r) . (dK x_u)(r) ~ t = sum_panels n_p v_p,
        v_p = x_l(r_p) . (dK x_u)(r_p),

    with the error rows ``dK_(r_p)`` (exact minus compressed, ``x, y, w`` rows) taken at
    one random node ``r_p`` of each panel (``n_p`` nodes; a stratified sample, with a
    fixed seed). The estimate is ``ERROR_SAFETY (|t| + 2 s)``, ``s^2 = sum n_p^2 v_p^2``
    (the sample's second moment, above its variance), and at most the Cauchy-Schwarz
    form ``ERROR_SAFETY ||x_l|| (sum n_p |(dK x_u)(r_p)|^2)^(1/2)``. The mode's smooth
    variation averages the interpolation error's oscillations, which the sampled sum
    keeps and the Cauchy-Schwarz form does not (about ten times larger).

    Parameters
    ----------
    kernel : AdhesionKernel
    c : Curve
        On a finite-difference grid.
    tol : float
        Compression tolerance.
    max_rank : int, optional
        Largest rank ``3M`` worth returning (default ``N - 1``: the coarse state must be
        smaller than the node count for the solvers to gain).
    rel : float
        The neighbour list's cutoff threshold.

    Returns
    -------
    ReducedHessian or None
    """
    if not c.grid.sparse:
        raise ValueError("interpolated_hessian needs a finite-difference grid")
    ip = interpolated_pair_hessian(kernel, c, tol=tol, rel=rel)
    if ip.rank > (c.N - 1 if max_rank is None else max_rank):
        return None
    H, local, Su, Sy = _extended(c, ip)
    # the error rows at one node of each panel (stratified sample)
    ptr = np.asarray(ip.fine_ptr)
    sizes = np.diff(ptr)
    rng = np.random.default_rng(20261207)
    nodes = ptr[:-1] + np.floor(rng.random(sizes.size) * sizes).astype(np.int64)
    x, y = c.positions()
    idx = np.concatenate([nodes + k * c.N for k in range(3)])
    dK = (_exact_rows(kernel, x, y, ip.w, ip.A0, nodes, kernel.cutoff_distance(rel))
          - ip.rows(idx)).astype(np.float32)
    weight = np.tile(sizes.astype(float), 3)[:, None]

    def coordinates(u):
        return Su @ u + Sy @ (-local._solve_cY(local.cU @ u))

    def estimate(l, u):
        xl, xu = coordinates(l), coordinates(u)
        e = (dK @ xu.astype(np.float32)).astype(float)
        wt = weight.reshape((-1,) + (1,) * (e.ndim - 1))
        cs = np.linalg.norm(xl, axis=0) * np.sqrt(np.sum(wt * e * e, axis=0))
        v = (xl[idx] * e).reshape((3, -1) + e.shape[1:]).sum(axis=0)  # per sampled node
        n = sizes.astype(float).reshape((-1,) + (1,) * (e.ndim - 1))
        sampled = np.abs(np.sum(n * v, axis=0)) + 2.0 * np.sqrt(np.sum((n * v) ** 2, axis=0))
        return ERROR_SAFETY * np.minimum(sampled, cs)

    H.approximations = (estimate,)
    # dense, the last rows of the extended state: the shift-invert core is eliminated
    # onto them (qsa.spectra.coarse)
    H.coarse_states = ip.rank
    H.coarse_index = np.arange(H.cY.shape[0] - ip.rank, H.cY.shape[0])
    return H
