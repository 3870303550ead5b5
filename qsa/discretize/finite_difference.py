"""Second-order centred finite differences on S: the paper's stencils.

The appendix "Discussion of Numerical Scheme": a skew-symmetric first derivative
``(f[j+1] - f[j-1]) / 2h``, the compact second difference, edges at the midpoints
``s_{j+1/2}`` (a 3-point Laplacian that keeps the highest mode penalised), the
trapezoid cumulative integral. Operators are ``scipy.sparse`` CSR matrices: every
local operator costs O(N).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.interpolate import CubicSpline

from qsa.discretize.grid import Grid, _as_values, _check_N

__all__ = ["FiniteDifference"]


class FiniteDifference(Grid):
    """Second-order centred finite differences on S (the paper's stencils).

    Parameters
    ----------
    N : int
        Number of nodes, ``N >= 8``.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import FiniteDifference
    >>> grid = FiniteDifference(400)
    >>> D = grid.derivative()
    >>> err = np.max(np.abs(D @ np.sin(2*np.pi*grid.s) - 2*np.pi*np.cos(2*np.pi*grid.s)))
    >>> bool(err < 2e-3)
    True
    """

    def __init__(self, N):
        object.__setattr__(self, "N", _check_N(N, "finite-difference"))
        object.__setattr__(self, "kind", "fd")
        object.__setattr__(self, "sparse", True)

    def _shift(self, k):
        """Sparse periodic shift: ``(S f)_j = f_{j+k}``."""
        N = self.N
        rows = np.arange(N)
        return sp.csr_matrix((np.ones(N), (rows, (rows + k) % N)), shape=(N, N))

    # The operators depend only on N and are cached on the (immutable) grid; treat the
    # returned matrices as read-only.
    @cached_property
    def _ops(self):
        S1, Sm1, I = self._shift(1), self._shift(-1), self.identity()
        return {
            "d1": ((S1 - Sm1) * (0.5 * self.N)).tocsr(),
            "d2": ((S1 - 2 * I + Sm1) * self.N**2).tocsr(),
            "edge_diff": ((S1 - I) * self.N).tocsr(),
            "edge_avg": ((S1 + I) * 0.5).tocsr(),
        }

    def derivative(self):
        return self._ops["d1"]

    def second_derivative(self):
        return self._ops["d2"]

    def edge_difference(self):
        """Forward difference to the midpoints: ``(f_{j+1} - f_j) / h``."""
        return self._ops["edge_diff"]

    def edge_average(self):
        """Midpoint average ``(f_j + f_{j+1}) / 2``."""
        return self._ops["edge_avg"]

    def cumulative(self, f):
        f = np.asarray(_as_values(f, self.N), dtype=float)
        out = np.zeros_like(f)
        out[1:] = np.cumsum(0.5 * self.h * (f[1:] + f[:-1]), axis=0)
        return out

    def cumulative_transpose(self, v):
        # (C f)_i = h sum_{k<i} (f_k + f_{k+1})/2, so (C^T v)_j = h (tail_j + v_j/2) for
        # j >= 1 and h tail_0 / 2 for j = 0, with tail_j = sum_{i>j} v_i.
        v = np.asarray(_as_values(v, self.N), dtype=float)
        tail = np.zeros_like(v)
        tail[:-1] = np.cumsum(v[:0:-1], axis=0)[::-1]
        out = self.h * (tail + 0.5 * v)
        out[0] = 0.5 * self.h * tail[0]
        return out

    def interpolate(self, f, s):
        f = np.asarray(_as_values(f, self.N), dtype=float)
        s = np.asarray(s, dtype=float) % 1.0
        x = np.append(self.s, 1.0)
        y = np.concatenate([f, f[:1]], axis=0)
        return CubicSpline(x, y, bc_type="periodic", axis=0)(s)
