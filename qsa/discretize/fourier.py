"""Pseudo-spectral (Fourier collocation) differentiation on S with an odd number of nodes.

Odd N only: with even N the derivative annihilates the Nyquist mode, which then shows up
as a fake eigenvalue (Conventions and errata, section 4). The edges are the nodes, the
cumulative integral and its transpose are spectral (FFT), transfers between Fourier
grids are exact (zero padding or truncation). Operators are dense ``ndarray``.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from qsa.discretize.grid import Grid, _as_values, _check_N

__all__ = ["Fourier"]


class Fourier(Grid):
    """Pseudo-spectral (Fourier collocation) grid on S with an odd number of nodes.

    Parameters
    ----------
    N : int
        Number of nodes; odd and ``>= 9``. Even N is refused: the spectral
        derivative then annihilates the Nyquist mode, which would appear as a
        spurious eigenvalue (Conventions and errata, section 4).

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

    def cumulative_transpose(self, v):
        # C = (I - 1 e_0^T) Q + s 1^T / N with Q the zero-mean antiderivative, a real
        # circulant with imaginary symbol 1/(2 pi i k): Q^T = -Q, hence
        # C^T v = -Q (v - e_0 sum(v)) + (s . v / N) 1.
        v = np.asarray(_as_values(v, self.N), dtype=float)
        u = v.copy()
        u[0] = u[0] - v.sum(axis=0)
        uh = np.fft.fft(u, axis=0)
        k = self.wavenumbers.reshape((-1,) + (1,) * (v.ndim - 1))
        with np.errstate(divide="ignore", invalid="ignore"):
            Qu = np.fft.ifft(np.where(k == 0, 0.0, uh / (2j * np.pi * k)), axis=0).real
        return -Qu + np.tensordot(self.s, v, axes=(0, 0)) / self.N

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
