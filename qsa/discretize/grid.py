"""The interface of the periodic grids on S = [0, 1): :class:`Grid` and its helpers.

Nodes ``s_j = j / N``, quadrature weights, the nodal and edge derivatives, diagonal
scalings, the cumulative integral ``int_0^s f ds`` (e:D_def: the paper's
``D f = cumulative(f * g)``) and its transpose, interpolation and resampling. The two
implementations are :class:`~qsa.discretize.finite_difference.FiniteDifference` and
:class:`~qsa.discretize.fourier.Fourier` (:mod:`qsa.discretize` describes both).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from qsa._checks import integer

__all__ = ["Grid", "MIN_NODES", "cumulative_factors"]

#: Smallest number of nodes a grid accepts.
MIN_NODES = 8


def _check_N(N, kind):
    return integer(N, "N", minimum=MIN_NODES, what="number of nodes",
                   too_small="{name}={value} is too small for a " + kind
                   + " grid: need {name} >= {minimum}")


def cumulative_factors(N):
    """Sparse ``(Bd, R)`` with ``Bd^{-1} R`` the trapezoid cumulative integral on N nodes.

    ``(Bd z)_0 = z_0``, ``(Bd z)_j = z_j - z_{j-1}``; ``(R f)_0 = 0``,
    ``(R f)_j = (f_{j-1} + f_j) / (2 N)``: ``z = Bd^{-1} R f`` is
    :meth:`FiniteDifference.cumulative`. Operators that contain the cumulative
    integral (``D`` of e:D_def) become sparse equations for an implicit state.

    Parameters
    ----------
    N : int

    Returns
    -------
    Bd, R : scipy.sparse.csr_matrix, shape (N, N)

    Examples
    --------
    >>> import numpy as np, scipy.sparse.linalg as spla
    >>> from qsa import FiniteDifference
    >>> Bd, R = cumulative_factors(8)
    >>> f = np.arange(8.0) ** 2
    >>> bool(np.allclose(spla.spsolve(Bd.tocsc(), R @ f), FiniteDifference(8).cumulative(f)))
    True
    """
    N = int(N)
    Bd = (sp.identity(N) - sp.eye(N, k=-1)).tocsr()
    R = sp.lil_matrix(0.5 / N * (sp.identity(N) + sp.eye(N, k=-1)))
    R[0, 0] = 0.0
    return Bd, R.tocsr()


def _as_values(f, N, name="f"):
    f = np.asarray(f)
    if f.shape[:1] != (N,):
        raise ValueError(f"{name} has shape {f.shape}, expected ({N}, ...) on this grid")
    return f


@dataclass(frozen=True, eq=False)
class Grid:
    """Common interface of the periodic grids (abstract).

    Use :class:`FiniteDifference` or :class:`Fourier`; operators are ``scipy.sparse``
    CSR matrices for the former and dense ``ndarray`` for the latter.

    Parameters
    ----------
    N : int
        Number of nodes ``s_j = j / N``, ``>= MIN_NODES``.

    Attributes
    ----------
    N : int
        Number of nodes ``s_j = j / N``.
    kind : str
        ``"fd"`` or ``"fourier"``.
    sparse : bool
        Whether operators are sparse matrices.

    Examples
    --------
    >>> from qsa import FiniteDifference, Fourier
    >>> FiniteDifference(16).sparse, Fourier(17).sparse
    (True, False)
    >>> Fourier(17) == Fourier(17), Fourier(17) == Fourier(19)
    (True, False)
    """

    N: int
    kind: str = field(init=False, default="grid")
    sparse: bool = field(init=False, default=False)

    # ------------------------------------------------------------------ nodes
    @property
    def h(self) -> float:
        """Node spacing ``1 / N``."""
        return 1.0 / self.N

    @cached_property
    def s(self) -> np.ndarray:
        """Nodes ``s_j = j / N``, shape (N,)."""
        return np.arange(self.N) / self.N

    @cached_property
    def weights(self) -> np.ndarray:
        """Quadrature weights on S (periodic rectangle = trapezoid rule), shape (N,).

        ``f @ grid.weights`` approximates ``int_S f ds``; multiply by ``g`` for
        ``dsigma``.
        """
        return np.full(self.N, 1.0 / self.N)

    @property
    def edge_weights(self) -> np.ndarray:
        """Quadrature weights of the edge points, shape (N,) (equal to ``weights``)."""
        return self.weights

    def integrate(self, f) -> np.ndarray:
        """``int_S f ds`` with the grid's quadrature (periodic integrand).

        Parameters
        ----------
        f : array_like, shape (N,) or (N, ...)
            Nodal values (along the first axis).

        Returns
        -------
        float or ndarray, shape f.shape[1:]
            The integral over ``S = [0, 1)`` (with ``dsigma`` use ``curve.dsigma``).

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import FiniteDifference
        >>> grid = FiniteDifference(16)
        >>> round(float(grid.integrate(np.cos(2 * np.pi * grid.s) ** 2)), 12)
        0.5
        """
        return self.weights @ _as_values(f, self.N)

    # ------------------------------------------------------------- operators
    def derivative(self):
        """First derivative ``d/ds`` at the nodes; skew-symmetric.

        Returns
        -------
        sparse matrix or ndarray, shape (N, N)
            ``(f[j+1] - f[j-1]) / 2h`` (finite differences) or the Fourier
            collocation matrix.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import FiniteDifference
        >>> D = FiniteDifference(16).derivative()
        >>> D.shape, bool(abs(D + D.T).max() == 0)
        ((16, 16), True)
        """
        raise NotImplementedError

    def second_derivative(self):
        """Second derivative ``d^2/ds^2`` at the nodes; symmetric.

        Returns
        -------
        sparse matrix or ndarray, shape (N, N)
            The compact 3-point stencil (finite differences) or ``D @ D`` (Fourier).

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Fourier
        >>> grid = Fourier(17)
        >>> f = np.sin(2 * np.pi * grid.s)
        >>> bool(np.allclose(grid.second_derivative() @ f, -(2 * np.pi) ** 2 * f))
        True
        """
        raise NotImplementedError

    def edge_difference(self):
        """``d/ds`` from nodes to edge points.

        Returns
        -------
        sparse matrix or ndarray, shape (N, N)
            ``(f_{j+1} - f_j) / h`` at the midpoints ``s_{j+1/2}`` (finite differences)
            or the nodal derivative (Fourier, whose edges are the nodes).

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import FiniteDifference
        >>> grid = FiniteDifference(8)
        >>> (grid.edge_difference() @ grid.s)[:3].tolist()
        [1.0, 1.0, 1.0]
        """
        raise NotImplementedError

    def edge_average(self):
        """Values at the edge points from nodal values.

        Returns
        -------
        sparse matrix or ndarray, shape (N, N)
            ``(f_j + f_{j+1}) / 2`` (finite differences) or the identity (Fourier).

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import FiniteDifference
        >>> grid = FiniteDifference(8)
        >>> (grid.edge_average() @ grid.s)[:2].tolist()
        [0.0625, 0.1875]
        """
        raise NotImplementedError

    def identity(self):
        """Identity of the grid's matrix type.

        Returns
        -------
        sparse matrix or ndarray, shape (N, N)

        Examples
        --------
        >>> from qsa import Fourier
        >>> float(Fourier(9).identity().trace())
        9.0
        """
        return sp.identity(self.N, format="csr") if self.sparse else np.eye(self.N)

    def diag(self, v):
        """Diagonal matrix of the grid's matrix type.

        Parameters
        ----------
        v : array_like, shape (N,)

        Returns
        -------
        sparse matrix or ndarray, shape (N, N)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import FiniteDifference
        >>> FiniteDifference(8).diag(np.arange(8.0)).diagonal().tolist()[:3]
        [0.0, 1.0, 2.0]
        """
        v = np.asarray(v, dtype=float)
        return sp.diags(v, format="csr") if self.sparse else np.diag(v)

    def scale_rows(self, v, A):
        """``diag(v) @ A`` without a dense diagonal product (O(N^2) for dense A).

        Parameters
        ----------
        v : array_like, shape (N,)
        A : sparse matrix or ndarray, shape (N, M)

        Returns
        -------
        sparse CSR matrix or ndarray, shape (N, M)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Fourier
        >>> Fourier(9).scale_rows(np.arange(9.0), np.ones((9, 2)))[:3].tolist()
        [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]
        """
        v = np.asarray(v, dtype=float)
        if sp.issparse(A):
            return (sp.diags(v) @ A).tocsr()
        return v[:, None] * A

    def sandwich(self, X, b, Y):
        """``X^T diag(b) Y`` for the grid's matrix type; ``None`` stands for the identity.

        With ``b = f * dsigma`` weights this is the matrix of the bilinear form
        ``(u, v) -> int (X u) f (Y v) dsigma``.

        Parameters
        ----------
        X : sparse matrix, ndarray of shape (N, M), or None
        b : array_like, shape (N,)
        Y : sparse matrix, ndarray of shape (N, K), or None

        Returns
        -------
        sparse matrix or ndarray, shape (M, K)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Fourier
        >>> grid = Fourier(9)
        >>> D = grid.derivative()
        >>> bool(np.allclose(grid.sandwich(D, np.ones(9), D), D.T @ D))
        True
        """
        b = np.asarray(b, dtype=float)
        if Y is None:
            if X is not None and not sp.issparse(X):
                return X.T * b[None, :]  # X^T diag(b) without a dense O(N^3) product
            right = self.diag(b)
        else:
            right = self.scale_rows(b, Y)
        return right if X is None else X.T @ right

    # ----------------------------------------------------------- integration
    def cumulative(self, f) -> np.ndarray:
        """``F_j = int_0^{s_j} f ds`` of a periodic integrand ``f``.

        The paper's ``D f`` (e:D_def) is ``cumulative(f * g)``: trapezoid rule (second
        order) for finite differences, spectral for Fourier.

        Parameters
        ----------
        f : array_like, shape (N,) or (N, ...)
            Nodal values (along the first axis).

        Returns
        -------
        ndarray, shape like ``f``
            ``F_0 = 0``; ``F`` is not periodic unless ``int_S f ds = 0``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Fourier
        >>> grid = Fourier(17)
        >>> F = grid.cumulative(np.cos(2 * np.pi * grid.s))
        >>> bool(np.allclose(F, np.sin(2 * np.pi * grid.s) / (2 * np.pi)))
        True
        """
        raise NotImplementedError

    def cumulative_transpose(self, v) -> np.ndarray:
        """``C^T v`` for the matrix ``C`` of :meth:`cumulative` (``C f = cumulative(f)``).

        The adjoint integration of reverse-mode derivatives through ``D``: O(N) for
        finite differences (a reversed cumulative sum), O(N log N) for Fourier.

        Parameters
        ----------
        v : array_like, shape (N,) or (N, ...)
            Nodal values (along the first axis).

        Returns
        -------
        ndarray, shape like ``v``

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import FiniteDifference, Fourier
        >>> v = np.cos(np.arange(9.0))
        >>> [bool(np.allclose(gr.cumulative_transpose(v), gr.cumulative_matrix().T @ v))
        ...  for gr in (FiniteDifference(9), Fourier(9))]
        [True, True]
        """
        return self.cumulative_matrix().T @ np.asarray(_as_values(v, self.N), dtype=float)

    def cumulative_matrix(self) -> np.ndarray:
        """Dense matrix ``C`` with ``C @ f == cumulative(f)``.

        Returns
        -------
        ndarray, shape (N, N)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import FiniteDifference
        >>> grid = FiniteDifference(8)
        >>> bool(np.allclose(grid.cumulative_matrix() @ grid.s, grid.cumulative(grid.s)))
        True
        """
        return self.cumulative(np.eye(self.N))

    # --------------------------------------------------------- interpolation
    def interpolate(self, f, s) -> np.ndarray:
        """Values of the periodic interpolant of nodal ``f`` at parameters ``s``.

        A periodic cubic spline (finite differences) or the trigonometric interpolant
        (Fourier).

        Parameters
        ----------
        f : array_like, shape (N,) or (N, ...)
            Nodal values.
        s : array_like
            Parameters, taken modulo 1.

        Returns
        -------
        ndarray, shape ``s.shape + f.shape[1:]``

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Fourier
        >>> grid = Fourier(9)
        >>> v = grid.interpolate(np.cos(2 * np.pi * grid.s), [0.125, 0.5])
        >>> np.round(v, 10).tolist()
        [0.7071067812, -1.0]
        """
        raise NotImplementedError

    def resample(self, f, other: Grid) -> np.ndarray:
        """Nodal values of ``f`` (on this grid) transferred to grid ``other``.

        Fourier to Fourier is exact (zero padding or truncation of the spectrum);
        otherwise the grid's interpolant is evaluated at ``other.s``.

        Parameters
        ----------
        f : array_like, shape (N,)
        other : Grid

        Returns
        -------
        ndarray, shape (other.N,)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Fourier
        >>> a, b = Fourier(9), Fourier(15)
        >>> f = np.sin(4 * np.pi * a.s)
        >>> bool(np.allclose(a.resample(f, b), np.sin(4 * np.pi * b.s)))
        True
        """
        return self.interpolate(f, other.s)

    def __repr__(self):
        return f"{type(self).__name__}({self.N})"

    def __eq__(self, other):
        return type(self) is type(other) and self.N == other.N

    def __hash__(self):
        return hash((type(self).__name__, self.N))
