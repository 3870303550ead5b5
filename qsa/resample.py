"""Closed sampled curves: periodic interpolants and resampling to constant arc length.

The paper's preprocessing step (appendix, "a pre-processing step is conducted
with Newton iterations to convert to scaled arc length") takes arbitrary closed
samples to N points equally spaced in arc length. Two notions are offered:

``method="arclength"``
    Points equally spaced in arc length along a smooth periodic interpolant of
    the samples (a trigonometric interpolant, spectrally accurate for smooth
    samples, or a periodic quintic spline). This is what the intrinsic ``Curve``
    needs: ``g`` constant in the continuum sense.
``method="chord"``
    Points on the interpolant with equal chord lengths
    ``|X_{j+1} - X_j| = L_h / N`` (the paper's discrete scaled arc length,
    ap:scaled), found by Newton from the arc-length guess. This is what the DAE
    flow solver's constraint expects at t = 0.

In both cases the first sample is kept as the first node.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.interpolate import make_interp_spline

__all__ = [
    "PeriodicInterpolant",
    "closed_samples",
    "resample_closed",
    "equal_arclength_parameters",
]

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(10)


def closed_samples(x, y, name="x, y"):
    """Validate closed samples and return them as float arrays without a repeated end point.

    Parameters
    ----------
    x, y : array_like, shape (M,)
        Samples of a closed curve; a last point equal to the first is dropped.
    name : str
        How the arguments are named in error messages.

    Returns
    -------
    x, y : ndarray, shape (M,) or (M - 1,)
        Flattened float copies, last point different from the first.

    Raises
    ------
    ValueError
        For NaN/inf, fewer than 4 distinct points, mismatched shapes, repeated
        consecutive points, or data that is visibly not closed (the gap from the
        last point to the first is over 5 times the median spacing).

    Examples
    --------
    >>> x, y = closed_samples([0, 1, 1, 0, 0], [0, 0, 1, 1, 0])
    >>> x.tolist(), y.tolist()
    ([0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 1.0, 1.0])
    """
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise ValueError(f"{name}: x and y have different lengths {x.size} and {y.size}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError(f"{name}: the samples contain NaN or inf")
    if x.size >= 2 and np.hypot(x[-1] - x[0], y[-1] - y[0]) <= 1e-12 * (np.ptp(x) + np.ptp(y)):
        x, y = x[:-1], y[:-1]
    if x.size < 4:
        raise ValueError(f"{name}: need at least 4 distinct points on a closed curve, got {x.size}")
    seg = np.hypot(np.diff(x), np.diff(y))
    if np.any(seg <= 1e-14 * (np.ptp(x) + np.ptp(y))):
        raise ValueError(f"{name}: consecutive samples coincide")
    gap = np.hypot(x[0] - x[-1], y[0] - y[-1])
    if gap > 5.0 * np.median(seg):
        raise ValueError(
            f"{name}: the data is not closed: the gap between the last and the first sample "
            f"({gap:.3g}) is {gap / np.median(seg):.1f} times the median spacing; pass samples "
            f"of a closed curve (the segment from the last point back to the first closes it)"
        )
    return x, y


@dataclass(frozen=True)
class PeriodicInterpolant:
    """A smooth closed curve ``t -> (x(t), y(t))``, ``t`` in [0, 1), through samples.

    Parameters
    ----------
    x, y : ndarray, shape (M,)
        Samples, first point at ``t = 0``; the curve closes from the last back to
        the first.
    kind : {"fourier", "spline"}
        Trigonometric interpolation at uniform ``t`` (spectrally accurate when
        the samples come from a smooth parameterization at uniform parameter
        values) or a periodic quintic spline with chord-length parameterization
        (robust for any polygon; sixth-order positions).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(32) / 32
    >>> ellipse = PeriodicInterpolant(np.cos(2*np.pi*t), 0.5*np.sin(2*np.pi*t))
    >>> t_table, S = ellipse.arclength_table()
    >>> round(float(S[-1]), 6)  # the perimeter, 4 E(e^2 = 3/4)
    4.844224
    >>> z = ellipse.derivative(0.25)
    >>> round(float(z.real), 12) + 0.0, round(float(z.imag), 12)
    (0.0, 0.5)
    """

    x: np.ndarray
    y: np.ndarray
    kind: str = "fourier"
    # set in __post_init__, by kind
    _zh: np.ndarray = field(init=False, repr=False, compare=False)
    _k: np.ndarray = field(init=False, repr=False, compare=False)
    _kmax: int = field(init=False, repr=False, compare=False)
    _spl: Any = field(init=False, repr=False, compare=False)
    _knots: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.kind not in ("fourier", "spline"):
            raise ValueError(f"kind must be 'fourier' or 'spline', got {self.kind!r}")
        z = np.asarray(self.x) + 1j * np.asarray(self.y)
        M = z.size
        if self.kind == "fourier":
            zh = np.fft.fft(z) / M
            # Coefficients at round-off level carry no information but are amplified
            # by k^2 in curvature (k ~ M): drop them.
            zh[np.abs(zh) < 1e-15 * np.abs(zh).max()] = 0.0
            k = np.fft.fftfreq(M, d=1.0 / M)
            if M % 2 == 0:  # split the Nyquist coefficient so the interpolant is real
                nyq = M // 2
                zh = np.append(zh, 0.5 * zh[nyq])
                zh[nyq] *= 0.5
                k = np.append(k, -k[nyq])
            keep = zh != 0
            object.__setattr__(self, "_zh", zh[keep])
            object.__setattr__(self, "_k", 2j * np.pi * k[keep])
            object.__setattr__(self, "_kmax", int(np.max(np.abs(k[keep]))))
        else:
            seg = np.abs(np.diff(np.append(z, z[0])))
            t = np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum()
            zz = np.append(z, z[0])
            spl = make_interp_spline(t, np.column_stack([zz.real, zz.imag]), k=5,
                                     bc_type="periodic")
            object.__setattr__(self, "_spl", spl)
            object.__setattr__(self, "_knots", t)

    def derivative(self, t, order=0) -> np.ndarray:
        """Complex position ``x + i y`` (order 0) or its ``order``-th t-derivative.

        Parameters
        ----------
        t : array_like
            Parameters in [0, 1) (periodic).
        order : int
            Derivative order, ``>= 0``.

        Returns
        -------
        ndarray of complex, shape like ``t``
        """
        t = np.asarray(t, dtype=float)
        if self.kind == "fourier":
            coef = self._zh * self._k**order
            flat = t.ravel()
            out = np.empty(flat.size, dtype=complex)
            chunk = max(1, 2_000_000 // coef.size)
            for i in range(0, flat.size, chunk):
                out[i : i + chunk] = np.exp(np.multiply.outer(flat[i : i + chunk], self._k)) @ coef
            return out.reshape(t.shape)
        v = self._spl(np.mod(t, 1.0), nu=order)
        return v[..., 0] + 1j * v[..., 1]

    def speed(self, t):
        """``|gamma'(t)|``, shape like ``t``."""
        return np.abs(self.derivative(t, 1))

    def arclength_table(self, M=None):
        """Cumulative arc length at a fine table of parameters: ``(t, S(t))``.

        Parameters
        ----------
        M : int, optional
            Number of intervals of the Fourier table (default ``max(8 k_max, 512)``);
            splines use their knots.

        Returns
        -------
        t, S : ndarray, shape (M + 1,)
            Breakpoints from 0 to 1 and ``S(t) = int_0^t |gamma'|`` (10-point Gauss per
            interval); ``S[-1]`` is the length.
        """
        if self.kind == "fourier":
            M = M or max(8 * self._kmax, 512)
            breaks = np.linspace(0.0, 1.0, M + 1)
        else:
            breaks = self._knots
        a, b = breaks[:-1], breaks[1:]
        tq = 0.5 * (a + b)[:, None] + 0.5 * (b - a)[:, None] * _GAUSS_X[None, :]
        seg = 0.5 * (b - a) * (self.speed(tq) @ _GAUSS_W)
        return breaks, np.concatenate([[0.0], np.cumsum(seg)])

    def arclength(self, t0, t1):
        """Arc length between parameters ``t0 <= t1`` (arrays allowed) by Gauss quadrature.

        Parameters
        ----------
        t0, t1 : array_like
            Broadcastable parameters; accurate when ``[t0, t1]`` is short or the
            speed smooth (one 10-point Gauss rule).

        Returns
        -------
        ndarray, broadcast shape of ``t0, t1``
        """
        t0, t1 = np.broadcast_arrays(np.asarray(t0, float), np.asarray(t1, float))
        tq = 0.5 * (t0 + t1)[..., None] + 0.5 * (t1 - t0)[..., None] * _GAUSS_X
        return 0.5 * (t1 - t0) * (self.speed(tq) @ _GAUSS_W)


def equal_arclength_parameters(curve: PeriodicInterpolant, N: int, tol=1e-14, maxiter=50):
    """Parameters ``t_j`` (``t_0 = 0``) splitting the curve into N equal arc lengths.

    Parameters
    ----------
    curve : PeriodicInterpolant
    N : int
        Number of arcs.
    tol : float
        Newton stops at ``max |S(t_j) - j L / N| <= tol L``.
    maxiter : int

    Returns
    -------
    t : ndarray, shape (N,)
    L : float
        Total length.

    Notes
    -----
    Newton on ``S(t_j) = j L / N`` with ``S' = |gamma'|``, started from the
    inverse of a fine arc-length table and kept inside its bracket.

    Examples
    --------
    >>> import numpy as np
    >>> s = np.arange(16) / 16
    >>> circle = PeriodicInterpolant(np.cos(2*np.pi*s), np.sin(2*np.pi*s))
    >>> t, L = equal_arclength_parameters(circle, 4)
    >>> np.round(t, 12).tolist(), round(float(L / np.pi), 12)
    ([0.0, 0.25, 0.5, 0.75], 2.0)
    """
    breaks, S = curve.arclength_table()
    L = S[-1]
    target = np.arange(N) * L / N
    idx = np.clip(np.searchsorted(S, target, side="right") - 1, 0, breaks.size - 2)
    lo, hi = breaks[idx], breaks[idx + 1]
    t = lo + (target - S[idx]) / np.maximum(S[idx + 1] - S[idx], 1e-300) * (hi - lo)
    for _ in range(maxiter):
        F = S[idx] + curve.arclength(lo, t) - target
        step = F / curve.speed(t)
        t = np.clip(t - step, lo, hi)
        if np.max(np.abs(F)) <= tol * L:
            break
    else:  # pragma: no cover - Newton on a monotone function of t
        raise RuntimeError("arc-length inversion did not converge")
    t[0] = 0.0
    return t, L


def _equal_chord(curve, t, maxiter=30, tol=1e-13):
    """Newton for equal chords: unknowns t_1..t_{N-1} and c (chord length), t_0 = 0.

    The Jacobian is cyclic bidiagonal plus one dense column (the chord length), so
    each step is a sparse solve, O(N). Stops at ``max |F| <= tol c^2`` or when the
    Newton steps stall at round-off.
    """
    N = t.size
    z = curve.derivative(t)
    c = np.mean(np.abs(np.roll(z, -1) - z))
    rows = np.arange(N)
    best = np.inf
    for _ in range(maxiter):
        z = curve.derivative(t)
        dz = curve.derivative(t, 1)
        d = np.roll(z, -1) - z  # chord j: from node j to node j+1
        F = np.abs(d) ** 2 - c**2
        err = np.max(np.abs(F))
        if err <= tol * c**2:
            return t
        if err >= 0.5 * best and best <= 1e3 * np.finfo(float).eps * c**2 * N:
            return t  # stalled at round-off
        best = min(best, err)
        # dF_j/dt_j = -2 Re(conj(d_j) dz_j); dF_j/dt_{j+1} = 2 Re(conj(d_j) dz_{j+1}); dF/dc = -2c
        a = -2 * np.real(np.conj(d) * dz)
        b = 2 * np.real(np.conj(d) * np.roll(dz, -1))
        r = np.concatenate([rows, rows, rows])
        col = np.concatenate([rows, (rows + 1) % N, np.zeros(N, dtype=int)])
        val = np.concatenate([a, b, np.full(N, -2 * c)])
        keep = col != 0  # column 0 holds the chord length, not t_0 (fixed at 0)
        keep[2 * N :] = True
        J = sp.csc_matrix((val[keep], (r[keep], col[keep])), shape=(N, N))
        delta = spla.spsolve(J, -F)
        c += delta[0]
        t = t.copy()
        t[1:] += delta[1:]
    raise RuntimeError("equal-chord Newton iteration did not converge")


def resample_closed(x, y, N, method="arclength", interpolant="spline"):
    """Resample closed samples to N points equally spaced along the curve.

    Parameters
    ----------
    x, y : array_like, shape (M,)
        Samples of a closed curve (a repeated end point is dropped).
    N : int
        Number of output points.
    method : {"arclength", "chord"}
        Equal arc length along the interpolant, or equal chord lengths (the
        paper's discrete constraint ap:scaled).
    interpolant : {"spline", "fourier"}
        See :class:`PeriodicInterpolant`.

    Returns
    -------
    X, Y : ndarray, shape (N,)
        Resampled points, ``(X[0], Y[0]) == (x[0], y[0])``.
    L : float
        Length of the interpolant.

    Examples
    --------
    >>> import numpy as np
    >>> th = np.linspace(0, 2*np.pi, 40, endpoint=False)
    >>> X, Y, L = resample_closed(np.cos(th), 2*np.sin(th), 64, method="chord")
    >>> chords = np.hypot(np.diff(np.append(X, X[0])), np.diff(np.append(Y, Y[0])))
    >>> bool(np.ptp(chords) < 1e-10)
    True
    """
    if method not in ("arclength", "chord"):
        raise ValueError(f"method must be 'arclength' or 'chord', got {method!r}")
    x, y = closed_samples(x, y)
    curve = PeriodicInterpolant(x, y, kind=interpolant)
    t, L = equal_arclength_parameters(curve, int(N))
    if method == "chord":
        t = _equal_chord(curve, t)
    z = curve.derivative(t)
    return z.real, z.imag, L
