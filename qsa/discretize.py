"""Periodic grids on the parameter circle S = [0, 1).

Two discretizations share one interface:

``FiniteDifference(N)``
    Second-order centred stencils, the paper's (appendix "Discussion of
    Numerical Scheme"): a skew-symmetric first derivative
    ``(f[j+1] - f[j-1]) / 2h`` and the compact second difference. Operators are
    ``scipy.sparse`` CSR matrices, so every local operator costs O(N).
``Fourier(N)``
    Pseudo-spectral differentiation on N equispaced nodes (odd N only: with even
    N the derivative annihilates the Nyquist mode, which then shows up as a fake
    eigenvalue, MATH.md section 4). Operators are dense ``ndarray``.

Besides the nodal derivative, each grid exposes an *edge* pair used by energies
that contain ``|grad_s kappa|^2``: ``edge_difference`` (nodes -> edges) and
``edge_average``. For finite differences the edges are the midpoints
``s_{j+1/2}``, which makes the discrete Laplacian compact (3-point) and keeps the
highest mode properly penalised; for Fourier the edges are the nodes.

The cumulative integral ``cumulative(f)`` approximates ``int_0^s f ds`` (so the
paper's ``D f = cumulative(f * g)``), to second order (trapezoid) or spectrally.

Notes
-----
Equation labels: e:D_def (the operator D and its adjoint D-dagger).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.interpolate import CubicSpline

__all__ = ["Grid", "FiniteDifference", "Fourier", "MIN_NODES"]

#: Smallest number of nodes a grid accepts.
MIN_NODES = 8


def _check_N(N, kind):
    if isinstance(N, bool) or not isinstance(N, (int, np.integer)):
        raise ValueError(f"N must be an integer number of nodes, got {N!r}")
    N = int(N)
    if N < MIN_NODES:
        raise ValueError(f"N={N} is too small for a {kind} grid: need N >= {MIN_NODES}")
    return N


def _as_values(f, N, name="f"):
    f = np.asarray(f)
    if f.shape[:1] != (N,):
        raise ValueError(f"{name} has shape {f.shape}, expected ({N}, ...) on this grid")
    return f


@dataclass(frozen=True, eq=False)
class Grid:
    """Common interface of the periodic grids (abstract).

    Attributes
    ----------
    N : int
        Number of nodes ``s_j = j / N``.
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
        """Quadrature weights of the edge points, shape (N,)."""
        return self.weights

    def integrate(self, f) -> np.ndarray:
        """``int_S f ds`` with the grid's quadrature (periodic integrand)."""
        return self.weights @ _as_values(f, self.N)

    # ------------------------------------------------------------- operators
    def derivative(self):
        """First derivative ``d/ds`` at the nodes, shape (N, N); skew-symmetric."""
        raise NotImplementedError

    def second_derivative(self):
        """Second derivative ``d^2/ds^2`` at the nodes, shape (N, N); symmetric."""
        raise NotImplementedError

    def edge_difference(self):
        """``d/ds`` from nodes to edge points, shape (N, N)."""
        raise NotImplementedError

    def edge_average(self):
        """Values at the edge points from nodal values, shape (N, N)."""
        raise NotImplementedError

    def identity(self):
        """Identity of the grid's matrix type."""
        return sp.identity(self.N, format="csr") if self.sparse else np.eye(self.N)

    def diag(self, v):
        """Diagonal matrix of the grid's matrix type."""
        v = np.asarray(v, dtype=float)
        return sp.diags(v, format="csr") if self.sparse else np.diag(v)

    # ----------------------------------------------------------- integration
    def cumulative(self, f) -> np.ndarray:
        """``F_j = int_0^{s_j} f ds`` of a periodic integrand ``f``, shape like ``f``."""
        raise NotImplementedError

    def cumulative_matrix(self) -> np.ndarray:
        """Dense matrix ``C`` with ``C @ f == cumulative(f)``, shape (N, N)."""
        return self.cumulative(np.eye(self.N))

    # --------------------------------------------------------- interpolation
    def interpolate(self, f, s) -> np.ndarray:
        """Values of the periodic interpolant of nodal ``f`` at parameters ``s``."""
        raise NotImplementedError

    def resample(self, f, other: Grid) -> np.ndarray:
        """Nodal values of ``f`` (on this grid) transferred to grid ``other``."""
        return self.interpolate(f, other.s)

    def __repr__(self):
        return f"{type(self).__name__}({self.N})"

    def __eq__(self, other):
        return type(self) is type(other) and self.N == other.N

    def __hash__(self):
        return hash((type(self).__name__, self.N))


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

    def interpolate(self, f, s):
        f = np.asarray(_as_values(f, self.N), dtype=float)
        s = np.asarray(s, dtype=float) % 1.0
        x = np.append(self.s, 1.0)
        y = np.concatenate([f, f[:1]], axis=0)
        return CubicSpline(x, y, bc_type="periodic", axis=0)(s)


class Fourier(Grid):
    """Pseudo-spectral (Fourier collocation) grid on S with an odd number of nodes.

    Parameters
    ----------
    N : int
        Number of nodes; odd and ``>= 9``. Even N is refused: the spectral
        derivative then annihilates the Nyquist mode, which would appear as a
        spurious eigenvalue (MATH.md section 4).

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Fourier
    >>> grid = Fourier(33)
    >>> f = np.exp(np.sin(2*np.pi*grid.s))
    >>> exact = 2*np.pi*np.cos(2*np.pi*grid.s)*f
    >>> bool(np.max(np.abs(grid.derivative() @ f - exact)) < 1e-10)
    True
    """

    def __init__(self, N):
        N = _check_N(N, "Fourier")
        if N % 2 == 0:
            raise ValueError(
                f"N={N}: Fourier grids need an odd N (the Nyquist mode of an even grid is a "
                f"spurious kernel mode of d/ds); use N={N + 1}"
            )
        object.__setattr__(self, "N", N)
        object.__setattr__(self, "kind", "fourier")
        object.__setattr__(self, "sparse", False)

    @cached_property
    def wavenumbers(self) -> np.ndarray:
        """Integer wavenumbers in FFT order, shape (N,)."""
        return np.fft.fftfreq(self.N, d=1.0 / self.N)

    @cached_property
    def _D(self):
        N = self.N
        j = np.arange(N)
        diff = j[:, None] - j[None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            D = 0.5 * (-1.0) ** diff / np.sin(np.pi * diff / N)
        D[j, j] = 0.0
        D *= 2 * np.pi
        D.flags.writeable = False
        return D

    def derivative(self):
        return self._D.copy()

    def second_derivative(self):
        return self._D @ self._D

    def edge_difference(self):
        return self.derivative()

    def edge_average(self):
        return np.eye(self.N)

    def cumulative(self, f):
        f = np.asarray(_as_values(f, self.N), dtype=float)
        fh = np.fft.fft(f, axis=0)
        mean = fh[0].real / self.N
        k = self.wavenumbers.reshape((-1,) + (1,) * (f.ndim - 1))
        with np.errstate(divide="ignore", invalid="ignore"):
            Fh = np.where(k == 0, 0.0, fh / (2j * np.pi * k))
        F = np.fft.ifft(Fh, axis=0).real
        s = self.s.reshape((-1,) + (1,) * (f.ndim - 1))
        return F - F[:1] + mean * s

    def interpolate(self, f, s):
        f = np.asarray(_as_values(f, self.N), dtype=float)
        s = np.asarray(s, dtype=float)
        fh = np.fft.fft(f, axis=0) / self.N
        phase = np.exp(2j * np.pi * np.outer(s.ravel(), self.wavenumbers))
        out = (phase @ fh.reshape(self.N, -1)).real
        return out.reshape(s.shape + f.shape[1:])

    def resample(self, f, other):
        f = np.asarray(_as_values(f, self.N), dtype=float)
        if isinstance(other, Fourier) and f.ndim == 1:
            # Exact spectral transfer by zero-padding / truncation.
            fh = np.fft.fftshift(np.fft.fft(f)) / self.N
            M = other.N
            if M >= self.N:
                pad = (M - self.N) // 2
                gh = np.pad(fh, (pad, pad))
            else:
                cut = (self.N - M) // 2
                gh = fh[cut : cut + M]
            return np.fft.ifft(np.fft.ifftshift(gh)).real * M
        return self.interpolate(f, other.s)
