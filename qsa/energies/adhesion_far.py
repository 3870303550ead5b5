"""The adhesion Hessian's two-point blocks as hierarchical matrices (near field + low rank).

The pair Hessian ``K`` of ``E^(X, w)`` (:meth:`AdhesionDerivatives.pair_hessian
<qsa.energies.adhesion_hessian.AdhesionDerivatives.pair_hessian>`) has six ``N x N``
blocks. With ``d = X_r - X_c``, ``l = |d|^2`` and the pairs of the neighbour list
(``|d| <= cutoff``, ``r != c``), they are built from six pair functions ::

    G_w  = 2 A(l),                    (symmetric)
    G_x  = 4 A'(l) d_x,   G_y  = 4 A'(l) d_y,                              (antisymmetric)
    G_xx = 4 (2 A'' d_x^2 + A'),  G_xy = 8 A'' d_x d_y,  G_yy = 4 (2 A'' d_y^2 + A'),

as ::

    K_xx = -W G_xx W + diag(W G_xx w)     (likewise xy, yy),
    K_xw = W G_x + diag(G_x w),   K_yw = W G_y + diag(G_y w),
    K_ww = G_w + 2 A0 I,

with ``W = diag(w)``, ``w`` the quadrature weights ``dsigma``: exactly the values,
mirror images and diagonals of the assembled blocks, and ``K`` itself is
``[[K_xx, K_xy, K_xw], [K_xy, K_yy, K_yw], [K_xw^T, K_yw^T, K_ww]]``.

Each ``G`` is a :class:`~qsa.linalg.hierarchical.HierarchicalMatrix` on one shared
cluster tree and block partition (near pairs exact, admissible blocks by adaptive
cross approximation to a relative Frobenius tolerance ``tol``, checked a posteriori
by sampled remainders; blocks of clusters farther apart than the cutoff dropped, and
the far blocks' pairs beyond it set to zero, so the approximated matrix is the one
the neighbour list assembles). The diagonals are the row sums of the *approximated*
``G``, so translations stay exact null vectors of ``K_XX`` (``K_xx 1 + K_xy 0 = 0``).

Error control: ``||G - G~||_F <~ tol ||G||_F`` for each of the six functions
(``error_estimates``), so a product with a block of random vectors has a relative
error of about ``tol`` (the diagonals add at most the same again).

Memory: the near pairs (about 250-300 per node for compact states at ``l* = 0.1``,
independent of ``N``) plus the far factors, against ~0.8 kB per pair for the assembled
blocks. :meth:`AdhesionDerivatives.operator_reduced_hessian
<qsa.energies.adhesion_hessian.AdhesionDerivatives.operator_reduced_hessian>` takes it
as the pair term of the reduced Hessian; the spectrum solvers do not use it yet.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

from qsa.energies.adhesion_hessian import pair_vectors
from qsa.linalg.hierarchical import (
    BlockPartition,
    HierarchicalMatrix,
    block_partition,
    cluster_tree,
    hierarchical_matrix,
)

__all__ = ["HierarchicalPairHessian", "hierarchical_pair_hessian", "PAIR_BLOCKS"]

#: The blocks of ``K``, in the names of the assembled Hessian.
PAIR_BLOCKS = ("xx", "xy", "yy", "xw", "yw", "ww")

_SYMMETRY = {"w": 1, "x": -1, "y": -1, "xx": 1, "xy": 1, "yy": 1}


def _pair_functions(kernel, x, y):
    """``{name: entries(rows, cols)}`` of the six pair functions ``G``."""

    def geometry(r, c):
        dx, dy = x[r] - x[c], y[r] - y[c]
        return dx, dy, dx * dx + dy * dy

    def gw(r, c):
        return 2.0 * kernel.derivatives(geometry(r, c)[2], order=1)[0]

    def gx(r, c, axis):
        d = geometry(r, c)
        return 4.0 * kernel.derivatives(d[2], order=1)[1] * d[axis]

    def gxx(r, c, a, b):
        d = geometry(r, c)
        _, dA, d2A = kernel.derivatives(d[2])
        return 4.0 * (2.0 * d2A * d[a] * d[b] + (dA if a == b else 0.0))

    return {"w": gw, "x": lambda r, c: gx(r, c, 0), "y": lambda r, c: gx(r, c, 1),
            "xx": lambda r, c: gxx(r, c, 0, 0), "xy": lambda r, c: gxx(r, c, 0, 1),
            "yy": lambda r, c: gxx(r, c, 1, 1)}


@dataclass(frozen=True, eq=False)
class HierarchicalPairHessian:
    """The adhesion pair Hessian ``K`` with its six pair functions in hierarchical form.

    Built by :func:`hierarchical_pair_hessian`; symbols as in the module docstring.

    Parameters
    ----------
    partition : BlockPartition
        The cluster tree and its near / far blocks (shared by all six functions).
    G : dict of str -> HierarchicalMatrix
        Keys ``"w", "x", "y", "xx", "xy", "yy"``.
    w : ndarray, shape (N,)
        Quadrature weights.
    A0 : float
    diagonals : dict of str -> ndarray, shape (N,)
        The diagonals of the blocks ``PAIR_BLOCKS``.
    tol : float
        The compression tolerance.
    """

    partition: BlockPartition
    G: dict[str, HierarchicalMatrix]
    w: np.ndarray
    A0: float
    diagonals: dict
    tol: float

    @property
    def N(self) -> int:
        return int(self.w.size)

    @property
    def shape(self):
        """Shape ``(3N, 3N)`` of ``K``."""
        return (3 * self.N, 3 * self.N)

    @property
    def nbytes(self) -> int:
        """Bytes of the near pairs, far factors and diagonals."""
        return int(sum(g.nbytes for g in self.G.values())
                   + sum(d.nbytes for d in self.diagonals.values()))

    @property
    def near_nnz(self) -> int:
        """Near pairs of one ``G`` (each unordered pair once)."""
        return int(self.G["w"].near.nnz)

    @property
    def far_factor_entries(self) -> int:
        """Stored far-factor entries over the six functions."""
        return int(sum(g.left.nnz for g in self.G.values()))

    @property
    def error_estimates(self) -> dict:
        """``{name: estimated ||G - G~||_F / ||G||_F}`` of the six functions."""
        return {k: g.relative_error_estimate for k, g in self.G.items()}

    def block_matvec(self, name, V) -> np.ndarray:
        """The block ``name`` of ``K`` (one of ``PAIR_BLOCKS``) times ``V``.

        Parameters
        ----------
        name : str
        V : array_like, shape (N,) or (N, m)

        Returns
        -------
        ndarray, shape like ``V``
        """
        if name not in PAIR_BLOCKS:
            raise ValueError(f"name must be one of {PAIR_BLOCKS}, got {name!r}")
        V = np.asarray(V, dtype=float)
        if V.shape[:1] != (self.N,) or V.ndim > 2:
            raise ValueError(f"V has shape {V.shape}, expected ({self.N},) or ({self.N}, m)")
        col = (lambda a: a) if V.ndim == 1 else (lambda a: a[:, None])
        w, D = col(self.w), col(self.diagonals[name])
        if name == "ww":
            return self.G["w"] @ V + D * V
        if name in ("xw", "yw"):
            return w * (self.G[name[0]] @ V) + D * V
        return D * V - w * (self.G[name] @ (w * V))

    def matvec(self, V) -> np.ndarray:
        """``K V`` in the ordering ``(x, y, w)`` of the assembled pair Hessian.

        Parameters
        ----------
        V : array_like, shape (3N,) or (3N, m)

        Returns
        -------
        ndarray, shape like ``V``
        """
        N = self.N
        V = pair_vectors(V, N)
        vx, vy, vw = V[:N], V[N:2 * N], V[2 * N:]
        b = self.block_matvec
        col = (lambda a: a) if V.ndim == 1 else (lambda a: a[:, None])
        w = col(self.w)
        # K_xw^T v = -W G_x ... : G_x is antisymmetric, so K_xw^T = -G_x W + diag
        wT = lambda axis, v: col(self.diagonals[axis + "w"]) * v - self.G[axis] @ (w * v)
        return np.concatenate([b("xx", vx) + b("xy", vy) + b("xw", vw),
                               b("xy", vx) + b("yy", vy) + b("yw", vw),
                               wT("x", vx) + wT("y", vy) + b("ww", vw)])

    def __matmul__(self, V):
        return self.matvec(V)

    def aslinearoperator(self) -> spla.LinearOperator:
        """``K`` as a symmetric :class:`scipy.sparse.linalg.LinearOperator`."""
        return spla.LinearOperator(self.shape, matvec=self.matvec, matmat=self.matvec,
                                   rmatvec=self.matvec, dtype=float)


def hierarchical_pair_hessian(kernel, x, y, w, *, tol=1e-10, leaf_size=64, eta=1.0,
                              rel=1e-16) -> HierarchicalPairHessian:
    """The adhesion pair Hessian ``K`` at nodes ``(x, y)`` with weights ``w``, compressed.

    Parameters
    ----------
    kernel : AdhesionKernel
    x, y : array_like, shape (N,)
        Node positions.
    w : array_like, shape (N,)
        Quadrature weights (``curve.dsigma``).
    tol : float
        Relative Frobenius tolerance of each far block's factorization.
    leaf_size : int
        Points per leaf of the cluster tree.
    eta : float
        Admissibility: clusters at least ``eta`` times the larger box radius apart.
    rel : float
        The neighbour list's cutoff threshold (:meth:`AdhesionKernel.cutoff_distance`):
        the pairs are those of ``adhesion_pairs(kernel, x, y, rel=rel)``.

    Returns
    -------
    HierarchicalPairHessian

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, FiniteDifference
    >>> from qsa.energies.adhesion import AdhesionKernel, adhesion_pairs
    >>> from qsa.energies.adhesion_hessian import adhesion_derivatives
    >>> c = Curve.polar(lambda t: 1 + 0.2 * np.cos(5 * t), FiniteDifference(400))
    >>> k = AdhesionKernel(10.0, 0.3, 1.0)
    >>> H = hierarchical_pair_hessian(k, *c.positions(), c.dsigma, tol=1e-10, leaf_size=32)
    >>> K = adhesion_derivatives(k, c, adhesion_pairs(k, *c.positions())).pair_hessian()
    >>> V = np.random.default_rng(0).standard_normal((1200, 3))
    >>> bool(np.linalg.norm(H @ V - K @ V) <= 1e-9 * np.linalg.norm(K @ V))
    True
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    w = np.asarray(w, dtype=float)
    if x.ndim != 1 or x.shape != y.shape or w.shape != x.shape:
        raise ValueError(f"x, y, w must be 1-D arrays of one length, got shapes "
                         f"{x.shape}, {y.shape}, {w.shape}")
    tree = cluster_tree(np.column_stack([x, y]), leaf_size)
    part = block_partition(tree, eta, kernel.cutoff_distance(rel))
    funcs = _pair_functions(kernel, x, y)
    G = {name: hierarchical_matrix(part, f, symmetry=_SYMMETRY[name], tol=tol)
         for name, f in funcs.items()}
    diag = {name: w * (G[name] @ w) for name in ("xx", "xy", "yy")}
    diag.update({a + "w": G[a] @ w for a in ("x", "y")})
    diag["ww"] = np.full(x.size, 2.0 * kernel.A0)
    return HierarchicalPairHessian(part, G, w, float(kernel.A0), diag, float(tol))
