"""Hierarchical (near field + low-rank far field) matrices of pair functions of points.

A matrix ``G`` with entries ``G[r, c] = f(r, c)`` for the pairs of points closer than a
cutoff (zero elsewhere and on the diagonal), ``f`` smooth away from ``r = c``, is held as ::

    G ~ Near + L S L^T,

* a **cluster tree** (:func:`cluster_tree`): the points' bounding box bisected along its
  longer side at the median point, down to leaves of at most ``leaf_size`` points;
* a **block partition** (:func:`block_partition`) by a dual-tree traversal: two clusters
  whose boxes are at least ``eta`` times the larger box radius apart are *admissible*
  (a far block); two leaves that are not stay in the *near field*, held exactly and
  sparsely (only the pairs within the cutoff); two clusters whose boxes are farther
  apart than the cutoff hold no pair and are dropped, exactly as a neighbour list
  drops their pairs;
* per far block a **low-rank factorization** ``U V^T`` by adaptive cross approximation
  (:func:`aca`): partial pivoting on rows and columns of the block evaluated on demand
  (``k (m + n)`` entries for rank ``k``, never the ``m n`` of the block), stopped when
  the last cross is below ``tol`` times the running Frobenius norm or below the block's
  share of ``tol ||G_near||_F`` (by its fraction of the pairs). The stopping rule is a
  heuristic, so each factorization is then checked a posteriori: the remainder
  ``R = B - U V^T`` of the block ``B`` at ``s`` entries drawn uniformly at random gives
  the unbiased estimate ``||R||_F^2 ~ (m n / s) sum R_ij^2``; a block whose estimate
  exceeds its bound gets more crosses from the row of the worst sampled entry (twice at
  most, each checked on fresh samples), then is evaluated densely and truncated by its
  SVD (exact Frobenius remainder). So ``||G_far - L S L^T||_F <~ tol ||G||_F``.
  Sampling sees errors spread over a block (the smooth case), not a few isolated
  entries: the function must be smooth on admissible blocks and negligible (below
  ``tol`` relative) at the cutoff, where the far blocks' entries are masked.

Adaptive cross approximation rather than interpolation: the admissible blocks of a
Gaussian-type kernel have numerical ranks of 10-35 at 1e-12, while tensor Chebyshev
interpolation in two dimensions needs ``p^2`` terms (100-200 at that accuracy), and
cross approximation adapts the rank per block and to the matrix actually assembled
(including the cutoff mask and any factors of the pair function).

The far factors ``U``, ``V`` of all blocks are stacked, each once, as the columns of one
sparse ``N x R`` matrix ``L`` (``R`` twice the sum of the ranks), and ``S`` pairs each
block's ``U`` columns with its ``V`` columns (with the function's symmetry sign for the
mirror block ``(t, s)``), so a product with a vector or a block of vectors is three
sparse products and a signed permutation, without a Python loop. Memory: the near
pairs plus ``sum_blocks k (m + n)`` factor entries (value and column index each).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

__all__ = ["ClusterTree", "BlockPartition", "HierarchicalMatrix", "cluster_tree",
           "block_partition", "aca", "hierarchical_matrix"]


@dataclass(frozen=True, eq=False)
class ClusterTree:
    """A bisection tree of points; cluster ``k`` holds ``perm[start[k]:stop[k]]``.

    Parameters
    ----------
    points : ndarray, shape (N, 2)
    perm : ndarray of intp, shape (N,)
        The points in tree order: every cluster is a contiguous range of it.
    start, stop : ndarray of intp, shape (n_clusters,)
    lo, hi : ndarray, shape (n_clusters, 2)
        The bounding boxes of the clusters' points.
    children : ndarray of intp, shape (n_clusters, 2)
        ``-1`` for leaves. Cluster 0 is the root.
    """

    points: np.ndarray
    perm: np.ndarray
    start: np.ndarray
    stop: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    children: np.ndarray

    @property
    def radius(self) -> np.ndarray:
        """Half the diagonal of each cluster's box."""
        return 0.5 * np.hypot(*(self.hi - self.lo).T)

    def is_leaf(self, k) -> bool:
        """Whether cluster ``k`` has no children."""
        return bool(self.children[k, 0] < 0)

    def indices(self, k) -> np.ndarray:
        """The (original) indices of the points of cluster ``k``."""
        return self.perm[self.start[k]:self.stop[k]]

    def gap(self, s, t) -> float:
        """Distance between the boxes of clusters ``s`` and ``t`` (0 if they overlap)."""
        d = np.maximum(0.0, np.maximum(self.lo[s] - self.hi[t], self.lo[t] - self.hi[s]))
        return float(np.hypot(*d))


def cluster_tree(points, leaf_size=64) -> ClusterTree:
    """Bisection tree of 2-D points: boxes split along their longer side at the median.

    Parameters
    ----------
    points : array_like, shape (N, 2)
    leaf_size : int
        Clusters of more points are split (leaves hold ``leaf_size // 2`` to
        ``leaf_size`` points).

    Returns
    -------
    ClusterTree

    Examples
    --------
    >>> import numpy as np
    >>> t = cluster_tree(np.random.default_rng(0).random((100, 2)), leaf_size=16)
    >>> bool(np.array_equal(np.sort(t.perm), np.arange(100)))
    True
    >>> leaves = [k for k in range(len(t.start)) if t.is_leaf(k)]
    >>> sizes = [int(t.stop[k] - t.start[k]) for k in leaves]
    >>> sum(sizes), max(sizes) <= 16
    (100, True)
    """
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or not np.all(np.isfinite(pts)):
        raise ValueError(f"points must be a finite array of shape (N, 2), got shape {pts.shape}")
    leaf_size = int(leaf_size)
    if leaf_size < 1:
        raise ValueError(f"leaf_size must be a positive integer, got {leaf_size}")
    perm = np.arange(len(pts))
    start: list = []
    stop: list = []
    lo: list = []
    hi: list = []
    children: list = []

    def add(a, b):
        k = len(start)
        p = pts[perm[a:b]]
        start.append(a)
        stop.append(b)
        lo.append(p.min(axis=0) if b > a else np.zeros(2))
        hi.append(p.max(axis=0) if b > a else np.zeros(2))
        children.append([-1, -1])
        return k

    stack = [add(0, len(pts))]
    while stack:
        k = stack.pop()
        a, b = start[k], stop[k]
        if b - a <= leaf_size:
            continue
        axis = int(np.argmax(np.asarray(hi[k]) - lo[k]))
        seg = perm[a:b]
        half = (b - a) // 2
        order = np.argpartition(pts[seg, axis], half)
        perm[a:b] = seg[order]
        children[k] = [add(a, a + half), add(a + half, b)]
        stack.extend(children[k])
    arr = lambda v, dt: np.asarray(v, dtype=dt)
    return ClusterTree(pts, perm, arr(start, np.intp), arr(stop, np.intp), arr(lo, float),
                       arr(hi, float), arr(children, np.intp))


@dataclass(frozen=True, eq=False)
class BlockPartition:
    """Near pairs and admissible far blocks of a cluster tree under a cutoff.

    Parameters
    ----------
    tree : ClusterTree
    cutoff : float
        Pairs farther apart than this hold no entry (``inf``: none dropped).
    near_rows, near_cols : ndarray of intp, shape (P_near,)
        The near pairs within the cutoff, each unordered pair once (``r != c``).
    far : ndarray of intp, shape (n_far, 2)
        The admissible cluster pairs ``(s, t)``, each unordered pair once, whose
        boxes are within the cutoff.
    """

    tree: ClusterTree
    cutoff: float
    near_rows: np.ndarray
    near_cols: np.ndarray
    far: np.ndarray

    @property
    def n_far_entries(self) -> int:
        """Number of (unordered) point pairs in the far blocks."""
        t = self.tree
        s, u = self.far.T
        return int(np.sum((t.stop[s] - t.start[s]) * (t.stop[u] - t.start[u])))

    def within_cutoff(self, rows, cols) -> np.ndarray:
        """Boolean mask of the pairs ``(rows, cols)`` (broadcast) within the cutoff."""
        p = self.tree.points
        dx, dy = p[rows, 0] - p[cols, 0], p[rows, 1] - p[cols, 1]
        return dx * dx + dy * dy <= self.cutoff**2


def block_partition(tree: ClusterTree, eta=1.0, cutoff=np.inf) -> BlockPartition:
    """Dual-tree traversal: near leaf pairs (sparse by cutoff) and admissible far blocks.

    Clusters ``s != t`` are admissible when ``gap(s, t) >= eta max(radius_s, radius_t)``;
    pairs of clusters farther apart than ``cutoff`` are dropped (all their pairs are
    beyond it); the rest is refined (the larger cluster first) down to leaf pairs,
    whose pairs within the cutoff form the near field.

    Parameters
    ----------
    tree : ClusterTree
    eta : float
        Admissibility parameter (> 0): larger is more accurate and more near field.
    cutoff : float
        Distance beyond which pairs hold no entry.

    Returns
    -------
    BlockPartition

    Examples
    --------
    >>> import numpy as np
    >>> pts = np.random.default_rng(1).random((300, 2))
    >>> part = block_partition(cluster_tree(pts, 16), cutoff=0.5)
    >>> n_cut = int(np.sum(np.triu(np.hypot(*(pts[:, None] - pts[None]).T) <= 0.5, 1)))
    >>> far_cut = 0
    >>> for s, t in part.far:
    ...     I, J = part.tree.indices(s), part.tree.indices(t)
    ...     far_cut += int(part.within_cutoff(I[:, None], J[None, :]).sum())
    >>> part.near_rows.size + far_cut == n_cut
    True
    """
    eta = float(eta)
    if not eta > 0:
        raise ValueError(f"eta must be positive, got {eta!r}")
    cutoff = float(cutoff)
    if not cutoff > 0:
        raise ValueError(f"cutoff must be positive (or inf), got {cutoff!r}")
    rad = tree.radius
    size = tree.stop - tree.start
    near, far = [], []
    stack = [(0, 0)]
    while stack:
        s, t = stack.pop()
        if s == t:
            if tree.is_leaf(s):
                near.append((s, s))
            else:
                a, b = tree.children[s]
                stack.extend([(a, a), (a, b), (b, b)])
            continue
        gap = tree.gap(s, t)
        if gap > cutoff:
            continue
        if gap >= eta * max(rad[s], rad[t]) and gap > 0:
            far.append((s, t))
        elif tree.is_leaf(s) and tree.is_leaf(t):
            near.append((s, t))
        elif tree.is_leaf(t) or (not tree.is_leaf(s) and size[s] >= size[t]):
            stack.extend((c, t) for c in tree.children[s])
        else:
            stack.extend((s, c) for c in tree.children[t])
    rows, cols = [], []
    pts = tree.points
    for s, t in near:
        I, J = tree.indices(s), tree.indices(t)
        d = pts[I][:, None, :] - pts[J][None, :, :]
        keep = np.einsum("ijk,ijk->ij", d, d) <= cutoff**2
        if s == t:
            keep &= np.triu(np.ones(keep.shape, dtype=bool), 1)
        a, b = np.nonzero(keep)
        rows.append(I[a])
        cols.append(J[b])
    cat = lambda v: np.concatenate(v) if v else np.zeros(0, dtype=np.intp)
    return BlockPartition(tree, cutoff, cat(rows), cat(cols),
                          np.asarray(far, dtype=np.intp).reshape(-1, 2))


def aca(row, col, m, n, tol, max_rank=None, *, atol=0.0, start=None):
    """Adaptive cross approximation with partial pivoting of an ``m x n`` block.

    Parameters
    ----------
    row, col : callable
        ``row(i)`` -> the block's row ``i`` (shape (n,)), ``col(j)`` -> column ``j``.
    m, n : int
    tol : float
        Stop when the last cross ``|u_k| |v_k| <= tol ||U V^T||_F``.
    max_rank : int, optional
        Default ``min(m, n)``.
    atol : float
        Also stop, without keeping it, at a cross ``|u_k| |v_k| <= atol``.
    start : tuple (U, V, i), optional
        Continue an earlier approximation ``U V^T`` from pivot row ``i``.

    Returns
    -------
    U : ndarray, shape (m, k)
    V : ndarray, shape (n, k)
        ``block ~ U V^T``.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.linspace(0, 1, 40), np.linspace(3, 4, 30)
    >>> S = 1.0 / np.abs(x[:, None] - y[None, :])
    >>> U, V = aca(lambda i: S[i], lambda j: S[:, j], 40, 30, 1e-10)
    >>> bool(np.linalg.norm(S - U @ V.T) <= 1e-8 * np.linalg.norm(S)), U.shape[1] < 15
    (True, True)
    """
    kmax = min(m, n) if max_rank is None else min(int(max_rank), m, n)
    U = np.zeros((m, kmax))
    V = np.zeros((n, kmax))
    used = np.zeros(m, dtype=bool)
    norm2, k, i = 0.0, 0, 0
    if start is not None:
        U0, V0, i = start
        k = min(U0.shape[1], kmax)
        U[:, :k], V[:, :k] = U0[:, :k], V0[:, :k]
        norm2 = float(np.sum((U0.T @ U0) * (V0.T @ V0)))
    while k < kmax:
        used[i] = True
        r = row(i) - V[:, :k] @ U[i, :k]
        j = int(np.argmax(np.abs(r)))
        if r[j] == 0.0:  # a zero row of the remainder: try another one
            free = np.flatnonzero(~used)
            if free.size == 0:
                break
            i = int(free[0])
            continue
        v = r / r[j]
        u = col(j) - U[:, :k] @ V[j, :k]
        if np.sqrt((u @ u) * (v @ v)) <= atol:
            break
        norm2 += (u @ u) * (v @ v) + 2.0 * ((U[:, :k].T @ u) @ (V[:, :k].T @ v))
        U[:, k], V[:, k] = u, v
        k += 1
        if np.sqrt((u @ u) * (v @ v)) <= tol * np.sqrt(max(norm2, 0.0)):
            break
        score = np.where(used, -1.0, np.abs(u))
        i = int(np.argmax(score))
        if score[i] < 0:
            break
    return U[:, :k], V[:, :k]


def _truncated_svd(S, tol, atol=0.0):
    """``U V^T`` with ``||S - U V^T||_F <= max(tol ||S||_F, atol)`` (the optimal rank)."""
    W, sig, Zt = np.linalg.svd(S, full_matrices=False)
    tail = np.sqrt(np.cumsum((sig**2)[::-1]))[::-1]  # tail[k] = ||sig[k:]||
    k = int(np.sum(tail > max(tol * (tail[0] if tail.size else 0.0), atol)))
    return W[:, :k] * sig[:k], Zt[:k].T


@dataclass(frozen=True, eq=False)
class HierarchicalMatrix:
    """``G ~ Near + L S L^T``: a pair function's matrix in near-field + low-rank form.

    Built by :func:`hierarchical_matrix`; behaves as an ``N x N`` operator (``@`` with
    vectors and blocks of vectors, ``shape``).

    Parameters
    ----------
    near : scipy.sparse.csr_matrix, shape (N, N)
        The exact entries at the near pairs, each unordered pair once; the near field
        is ``near + symmetry near^T``.
    symmetry : {1, -1}
    left : scipy.sparse.csr_matrix, shape (N, R)
        The far factors ``L``, each block's ``U`` then ``V`` columns.
    pairing : ndarray of intp, shape (R,)
    signs : ndarray, shape (R,)
        ``S``: ``(S z)[q] = signs[q] z[pairing[q]]``; the far field is ``L S L^T``.
    ranks : ndarray of intp, shape (n_far,)
        The rank of each far block.
    norm_estimate : float
        ``||G||_F`` (near part exact, far part estimated).
    error_estimate : float
        Estimate of ``||G - (Near + L S L^T)||_F`` (root sum of squares of the blocks'
        sampled remainders; SVD-truncated blocks contribute their exact remainder).
    n_fallback : int
        Blocks that failed the a posteriori check and were SVD-truncated.
    """

    near: sp.csr_matrix
    symmetry: int
    left: sp.csr_matrix
    pairing: np.ndarray
    signs: np.ndarray
    ranks: np.ndarray
    norm_estimate: float
    error_estimate: float
    n_fallback: int

    @property
    def shape(self):
        """``(N, N)``."""
        return self.near.shape

    @property
    def relative_error_estimate(self) -> float:
        """``error_estimate / norm_estimate`` (0 for a zero matrix)."""
        return self.error_estimate / self.norm_estimate if self.norm_estimate > 0 else 0.0

    @property
    def nbytes(self) -> int:
        """Bytes of the stored arrays (near entries, far factors, pairing)."""
        return int(sum(a.data.nbytes + a.indices.nbytes + a.indptr.nbytes
                       for a in (self.near, self.left))
                   + self.pairing.nbytes + self.signs.nbytes)

    def __matmul__(self, v):
        v = np.asarray(v, dtype=float)
        z = self.left.T @ v
        sg = self.signs if z.ndim == 1 else self.signs[:, None]
        return (self.near @ v + self.symmetry * (self.near.T @ v)
                + self.left @ (sg * z[self.pairing]))

    def toarray(self) -> np.ndarray:
        """Dense ``N x N`` (tests and small cases only)."""
        L = self.left.toarray()
        Nr = self.near.toarray()
        return Nr + self.symmetry * Nr.T + (L * self.signs) @ L[:, self.pairing].T


def _stack(blocks, N, R, tree):
    """Sparse ``N x R`` matrix of the factors ``U`` placed at their clusters' rows."""
    rows, cols, vals = [], [], []
    offset = 0
    for k_cluster, F in blocks:
        idx = tree.indices(k_cluster)
        k = F.shape[1]
        rows.append(np.repeat(idx, k))
        cols.append(np.tile(np.arange(offset, offset + k), idx.size))
        vals.append(F.ravel())
        offset += k
    cat = lambda v, dt: np.concatenate(v).astype(dt) if v else np.zeros(0, dtype=dt)
    return sp.csr_matrix((cat(vals, float), (cat(rows, np.intp), cat(cols, np.intp))),
                         shape=(N, R))


def hierarchical_matrix(partition: BlockPartition, entries, *, symmetry=1, tol=1e-10,
                        n_samples=None, seed=0) -> HierarchicalMatrix:
    """Compress the pair function ``entries`` over a block partition.

    Parameters
    ----------
    partition : BlockPartition
    entries : callable
        ``entries(rows, cols)`` -> ``f(rows, cols)`` elementwise for broadcastable
        index arrays (original point indices, ``rows != cols``). Pairs beyond the
        partition's cutoff are set to zero here, so ``f`` need not know the cutoff.
    symmetry : {1, -1}
        ``f(c, r) = symmetry * f(r, c)``: each unordered pair and far block is computed
        once and used in both orientations.
    tol : float
        Relative Frobenius tolerance (``0 < tol < 1``): each far block ``B`` of ``m n``
        of the ``P`` point pairs (near and far) is approximated to
        ``max(tol ||B||_F, tol ||G_near||_F sqrt(m n / 2P))``, so that the whole far
        field is within ``tol ||G||_F`` while blocks far below the matrix's size get
        low ranks (or none).
    n_samples : int, optional
        Entries sampled per block for the a posteriori check; default
        ``min(m n, 64 + 2 (m + n))``.
    seed : int
        Seed of the sampling (deterministic results).

    Returns
    -------
    HierarchicalMatrix

    Examples
    --------
    >>> import numpy as np
    >>> pts = np.random.default_rng(2).random((400, 2))
    >>> part = block_partition(cluster_tree(pts, 32))
    >>> f = lambda r, c: np.exp(-np.sum((pts[r] - pts[c]) ** 2, axis=-1))
    >>> G = hierarchical_matrix(part, f, tol=1e-10)
    >>> D = f(np.arange(400)[:, None], np.arange(400)[None, :]) - np.eye(400)
    >>> bool(np.linalg.norm(G.toarray() - D) <= 1e-9 * np.linalg.norm(D))
    True
    """
    if symmetry not in (1, -1):
        raise ValueError(f"symmetry must be 1 or -1, got {symmetry!r}")
    tol = float(tol)
    if not 0.0 < tol < 1.0:
        raise ValueError(f"tol must lie in (0, 1), got {tol!r}")
    tree = partition.tree
    N = len(tree.points)
    inf_cut = not np.isfinite(partition.cutoff)

    def f(rows, cols):
        val = np.asarray(entries(rows, cols), dtype=float)
        return val if inf_cut else np.where(partition.within_cutoff(rows, cols), val, 0.0)

    r, c = partition.near_rows, partition.near_cols
    vn = f(r, c) if r.size else np.zeros(0)
    near = sp.csr_matrix((vn, (r, c)), shape=(N, N))
    norm2 = 2.0 * float(vn @ vn)
    # absolute share of each block (m n of the P point pairs) in tol ||G_near||_F
    n_pairs = r.size + partition.n_far_entries
    share = tol * np.sqrt(norm2 / (2.0 * max(n_pairs, 1)))
    err2 = 0.0
    rng = np.random.default_rng(seed)
    ranks, n_fallback = [], 0
    lefts: list = []
    pairing: list = []
    signs: list = []
    for s, t in partition.far:
        I, J = tree.indices(s), tree.indices(t)
        m, n = I.size, J.size
        row, col = (lambda i, I=I, J=J: f(I[i], J)), (lambda j, I=I, J=J: f(I, J[j]))
        atol = share * np.sqrt(m * n)
        U, V = aca(row, col, m, n, tol, atol=atol)
        ns = min(m * n, 64 + 2 * (m + n)) if n_samples is None else min(m * n, int(n_samples))
        for attempt in range(3):
            # a posteriori: the remainder at fresh random entries
            flat = rng.choice(m * n, size=ns, replace=False) if ns < m * n else np.arange(m * n)
            a, b = np.divmod(flat, n)
            exact = f(I[a], J[b])
            rem = exact - np.einsum("ik,ik->i", U[a], V[b])
            scale = m * n / ns
            e2 = scale * float(rem @ rem)
            s2 = max(float(np.sum((U.T @ U) * (V.T @ V))), scale * float(exact @ exact))
            if e2 <= max((tol**2) * s2, atol**2):
                break
            if attempt < 2:  # continue the crosses from the worst sampled row
                U, V = aca(row, col, m, n, tol, atol=atol,
                           start=(U, V, int(a[np.argmax(np.abs(rem))])))
                continue
            S = f(I[:, None], J[None, :])
            U, V = _truncated_svd(S, tol, atol)
            R = S - U @ V.T
            e2, s2 = float(np.sum(R**2)), float(np.sum(S**2))
            n_fallback += 1
        err2 += 2.0 * e2
        norm2 += 2.0 * s2
        ranks.append(U.shape[1])
        # block (s, t): U V^T; block (t, s): symmetry V U^T
        k, o = U.shape[1], len(pairing)
        lefts += [(s, U), (t, V)]
        pairing += list(range(o + k, o + 2 * k)) + list(range(o, o + k))
        signs += [1.0] * k + [float(symmetry)] * k
    R = len(pairing)
    left = _stack(lefts, N, R, tree)
    return HierarchicalMatrix(near, symmetry, left, np.asarray(pairing, dtype=np.intp),
                              np.asarray(signs), np.asarray(ranks, dtype=np.intp),
                              float(np.sqrt(norm2)), float(np.sqrt(err2)), n_fallback)
