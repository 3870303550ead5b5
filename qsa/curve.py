"""The intrinsic state of a closed planar curve: U = (kappa, g) on a periodic grid.

A :class:`Curve` stores the curvature ``kappa`` and the arc-length density
``g = |d gamma / ds|`` at the grid nodes, plus the base point ``gamma(0)`` and
the base angle ``theta(0)``: together they fix the curve, rigid motion included.
Everything else is derived (paper section 2, e:tau-n, e:theta-kappa, e:C1-e:C2):

* ``theta = theta0 + D kappa``, with ``D f = int_0^s f dsigma``;
* ``tau = (cos theta, sin theta)``, ``n = (sin theta, -cos theta)`` (outward for
  counter-clockwise curves, Conventions and errata, section 1);
* ``gamma = gamma0 + D tau``;
* the closure ``C(U) = (int tau dsigma, int kappa dsigma - 2 pi)``.

Curves are immutable; ``with_kappa`` / ``with_g`` return modified copies.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsa.discretize import Fourier, Grid
from qsa.polygon import check_simple, polygon_self_intersects, self_intersections
from qsa.resample import PeriodicInterpolant, closed_samples, equal_arclength_parameters

__all__ = ["Curve", "polygon_self_intersects", "self_intersections", "check_simple"]


def _readonly(a, name, N):
    a = np.array(a, dtype=float)
    if a.ndim == 0:
        a = np.full(N, float(a))
    if a.shape != (N,):
        raise ValueError(f"{name} has shape {a.shape}, but the grid has N={N} nodes")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or inf")
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Curve:
    """A closed curve in intrinsic coordinates.

    Parameters
    ----------
    kappa : array_like, shape (N,)
        Signed curvature at the nodes (a counter-clockwise circle of radius R has
        ``kappa = 1/R``).
    g : array_like, shape (N,) or scalar
        Arc-length density ``|d gamma/ds| > 0``; a scalar means constant g.
    grid : Grid
        The periodic grid (``FiniteDifference`` or ``Fourier``).
    theta0 : float
        Tangent angle at ``s = 0``.
    origin : (float, float)
        Base point ``gamma(0)``.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(2.0, Fourier(33))
    >>> round(c.length(), 12), float(c.kappa[0])
    (12.566370614359, 0.5)
    """

    kappa: np.ndarray
    g: np.ndarray
    grid: Grid
    theta0: float = 0.0
    origin: tuple = (0.0, 0.0)
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        if not isinstance(self.grid, Grid):
            raise ValueError(f"grid must be a FiniteDifference or Fourier grid, got {self.grid!r}")
        N = self.grid.N
        object.__setattr__(self, "kappa", _readonly(self.kappa, "kappa", N))
        g = _readonly(self.g, "g", N)
        if np.any(g <= 0):
            raise ValueError("g must be strictly positive (it is the arc-length density)")
        object.__setattr__(self, "g", g)
        theta0 = float(self.theta0)
        origin = tuple(float(v) for v in np.asarray(self.origin, dtype=float).ravel())
        if not np.isfinite(theta0) or len(origin) != 2 or not np.all(np.isfinite(origin)):
            raise ValueError("theta0 must be a finite float and origin a finite (x, y) pair")
        object.__setattr__(self, "theta0", theta0)
        object.__setattr__(self, "origin", origin)

    def __repr__(self):
        return (f"Curve(N={self.N}, grid={self.grid!r}, L={self.length():.6g}, "
                f"kappa in [{self.kappa.min():.4g}, {self.kappa.max():.4g}])")

    # ----------------------------------------------------------- derived data
    @property
    def N(self) -> int:
        """Number of nodes of the grid."""
        return self.grid.N

    @property
    def dsigma(self) -> np.ndarray:
        """Quadrature weights of ``dsigma = g ds``: ``int f dsigma ~= f @ c.dsigma``.

        Returns
        -------
        ndarray, shape (N,)
            The weights of the inner product ``<f, h> = int f h dsigma``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> round(float(c.dsigma.sum() / np.pi), 12)
        2.0
        """
        return self.grid.weights * self.g

    @property
    def U(self) -> np.ndarray:
        """Stacked unknowns ``[kappa, g]``, shape (2N,)."""
        return np.concatenate([self.kappa, self.g])

    def D(self, f) -> np.ndarray:
        """The paper's ``D f = int_0^s f dsigma`` (e:D_def), at the nodes.

        Parameters
        ----------
        f : array_like, shape (N,) or (N, ...)

        Returns
        -------
        ndarray, shape like ``f``
            ``(D f)_0 = 0``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> bool(np.allclose(c.D(np.ones(17)), 2 * np.pi * c.grid.s))
        True
        """
        f = np.asarray(f, dtype=float)
        gg = self.g.reshape((-1,) + (1,) * (f.ndim - 1))
        return self.grid.cumulative(f * gg)

    def theta(self) -> np.ndarray:
        """Tangent angle ``theta = theta0 + D kappa`` (e:theta-kappa).

        Returns
        -------
        ndarray, shape (N,)
            Not reduced modulo ``2 pi``: it grows by ``int kappa dsigma`` along S.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> bool(np.allclose(c.theta(), np.pi / 2 + 2 * np.pi * c.grid.s))
        True
        """
        if "theta" not in self._cache:
            self._cache["theta"] = self.theta0 + self.D(self.kappa)
        return self._cache["theta"]

    def tangent(self) -> np.ndarray:
        """Unit tangent ``tau = (cos theta, sin theta)``.

        Returns
        -------
        ndarray, shape (2, N)

        Examples
        --------
        >>> from qsa import Curve, Fourier
        >>> (Curve.circle(1.0, Fourier(17)).tangent()[:, 0].round(12) + 0.0).tolist()
        [0.0, 1.0]
        """
        th = self.theta()
        return np.array([np.cos(th), np.sin(th)])

    def normal(self) -> np.ndarray:
        """Outward unit normal ``n = (sin theta, -cos theta)`` (counter-clockwise curves).

        Returns
        -------
        ndarray, shape (2, N)

        Examples
        --------
        >>> from qsa import Curve, Fourier
        >>> (Curve.circle(1.0, Fourier(17)).normal()[:, 0].round(12) + 0.0).tolist()
        [1.0, 0.0]
        """
        th = self.theta()
        return np.array([np.sin(th), -np.cos(th)])

    def positions(self) -> np.ndarray:
        """Node positions ``gamma = gamma0 + D tau``: ``x, y = c.positions()``.

        Returns
        -------
        ndarray, shape (2, N)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> x, y = Curve.circle(2.0, Fourier(17), center=(1.0, 0.0)).positions()
        >>> bool(np.allclose(np.hypot(x - 1.0, y), 2.0))
        True
        """
        if "positions" not in self._cache:
            tau = self.tangent()
            self._cache["positions"] = np.asarray(self.origin)[:, None] + self.D(tau.T).T
        return self._cache["positions"]

    def length(self) -> float:
        """Curve length ``L = int g ds``.

        Returns
        -------
        float

        Examples
        --------
        >>> from qsa import Curve, FiniteDifference
        >>> round(Curve.circle(0.5, FiniteDifference(16)).length(), 12)
        3.14159265359
        """
        return float(self.grid.integrate(self.g))

    def closure(self) -> np.ndarray:
        """Closure defect ``C(U) = (int tau dsigma, int kappa dsigma - 2 pi)``, shape (3,).

        Zero for a smoothly closed curve (e:C1, e:C2), up to quadrature error.

        Returns
        -------
        ndarray, shape (3,)
            ``(int cos theta dsigma, int sin theta dsigma, int kappa dsigma - 2 pi)``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> bool(np.linalg.norm(c.closure()) < 1e-12)
        True
        >>> np.round(c.with_kappa(1.1 * c.kappa).closure()[2], 6)  # turns by 2.2 pi
        np.float64(0.628319)
        """
        tau = self.tangent()
        return np.array([tau[0] @ self.dsigma, tau[1] @ self.dsigma,
                         self.kappa @ self.dsigma - 2 * np.pi])

    def area(self) -> float:
        """Enclosed area (positive for counter-clockwise curves), defined off closure too.

        With the closure defects spread linearly over ``s in [0, 1)`` -- the excess
        turning ``K - 2 pi`` (``K = int kappa dsigma``) out of ``theta``, and the mean
        out of ``tau g`` -- the curve becomes the closed one with tangent angle
        ``theta_hat = theta - (K - 2 pi) s`` and centred positions
        ``gamma_hat = Q (g tau_hat)`` (``Q`` the periodic antiderivative of mean-zero
        functions), whose area is

            A = 1/2 int (v~ Q u~ - u~ Q v~) ds,

        ``u~ = g cos theta_hat - mean``, ``v~ = g sin theta_hat - mean`` (the mean in
        ``ds``). On a closed curve it is ``1/2 int gamma . n dsigma``; off closure it is a
        smooth function of ``U`` with periodic integrands only, invariant under
        rotations and translations (it does not see ``theta0`` or ``gamma(0)``). ``Q`` is
        the grid's cumulative integral (spectral on Fourier grids, trapezoidal on finite
        differences); :func:`qsa.constraints.area_gradient` and
        :func:`qsa.constraints.area_hessian` are its exact derivatives.

        Returns
        -------
        float

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> round(Curve.circle(2.0, Fourier(17), center=(1.0, -3.0)).area() / np.pi, 12)
        4.0
        """
        w = self.grid.weights
        th = self.theta() - (self.kappa @ self.dsigma - 2 * np.pi) * self.grid.s
        u = self.g * np.cos(th)
        v = self.g * np.sin(th)
        u = u - w @ u
        v = v - w @ v
        cu, cv = self.grid.cumulative(u), self.grid.cumulative(v)
        return float(0.5 * ((w * v) @ cu - (w * u) @ cv))

    def grad_s(self, f) -> np.ndarray:
        """Surface gradient ``nabla_s f = (1/g) df/ds`` at the nodes.

        Parameters
        ----------
        f : array_like, shape (N,)

        Returns
        -------
        ndarray, shape (N,)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> bool(np.allclose(c.grad_s(c.theta() - 2 * np.pi * c.grid.s), 0.0))
        True
        """
        return (self.grid.derivative() @ np.asarray(f, dtype=float)) / self.g

    # ---------------------------------------------------------------- copies
    def with_kappa(self, kappa) -> Curve:
        """Copy with new curvature (same g, base point and angle).

        Parameters
        ----------
        kappa : array_like, shape (N,)

        Returns
        -------
        Curve

        Examples
        --------
        >>> from qsa import Curve, Fourier
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> float(c.with_kappa(2 * c.kappa).kappa[0]), float(c.kappa[0])
        (2.0, 1.0)
        """
        return Curve(kappa, self.g, self.grid, self.theta0, self.origin)

    def with_g(self, g) -> Curve:
        """Copy with new arc-length density (same kappa, base point and angle).

        Parameters
        ----------
        g : array_like, shape (N,) or scalar

        Returns
        -------
        Curve

        Examples
        --------
        >>> from qsa import Curve, Fourier
        >>> round(Curve.circle(1.0, Fourier(17)).with_g(1.0).length(), 12)
        1.0
        """
        return Curve(self.kappa, g, self.grid, self.theta0, self.origin)

    def with_U(self, U) -> Curve:
        """Copy from stacked unknowns ``U = [kappa, g]``.

        Parameters
        ----------
        U : array_like, shape (2N,)

        Returns
        -------
        Curve

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> bool(np.array_equal(c.with_U(c.U).U, c.U)), c.U.shape
        (True, (34,))
        """
        U = np.asarray(U, dtype=float)
        if U.shape != (2 * self.N,):
            raise ValueError(f"U has shape {U.shape}, expected ({2 * self.N},)")
        return Curve(U[: self.N], U[self.N :], self.grid, self.theta0, self.origin)

    def on_grid(self, grid: Grid) -> Curve:
        """The same curve sampled on another grid (interpolating kappa and g).

        Parameters
        ----------
        grid : Grid

        Returns
        -------
        Curve
            Same ``theta0`` and base point; Fourier to Fourier is exact for
            band-limited ``kappa, g``.

        Examples
        --------
        >>> from qsa import Curve, Fourier
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
        >>> fine = c.on_grid(Fourier(65))
        >>> fine.N, round(fine.length(), 8) == round(c.length(), 8)
        (65, True)
        """
        return Curve(self.grid.resample(self.kappa, grid), self.grid.resample(self.g, grid),
                     grid, self.theta0, self.origin)

    def self_intersects(self) -> bool:
        """Whether the node polygon crosses itself (non-adjacent segments intersect).

        Returns
        -------
        bool

        Examples
        --------
        >>> from qsa import Curve, Fourier
        >>> Curve.circle(1.0, Fourier(17)).self_intersects()
        False
        """
        x, y = self.positions()
        return polygon_self_intersects(x, y)

    # ----------------------------------------------------------- constructors
    @classmethod
    def circle(cls, R, grid: Grid, center=(0.0, 0.0)) -> Curve:
        """Counter-clockwise circle of radius ``R`` (``kappa = 1/R``, ``g = 2 pi R``).

        The base point is ``center + (R, 0)``.

        Parameters
        ----------
        R : float
            Radius, ``> 0``.
        grid : Grid
        center : (float, float)

        Returns
        -------
        Curve
            ``kappa = 1/R``, ``g = 2 pi R``, ``theta0 = pi/2``.

        Examples
        --------
        >>> from qsa import Curve, FiniteDifference
        >>> c = Curve.circle(0.5, FiniteDifference(16))
        >>> float(c.kappa[0]), float(c.g[0] / np.pi)
        (2.0, 1.0)
        """
        R = float(R)
        if not (np.isfinite(R) and R > 0):
            raise ValueError(f"R must be a positive radius, got {R}")
        cx, cy = (float(v) for v in center)
        return cls(np.full(grid.N, 1.0 / R), 2 * np.pi * R, grid, np.pi / 2, (cx + R, cy))

    @classmethod
    def polar(cls, r, grid: Grid, n_fine=None) -> Curve:
        """Star-shaped curve ``gamma(phi) = r(phi) (cos phi, sin phi)``, constant g.

        Parameters
        ----------
        r : callable
            Vectorised ``r(phi) > 0`` on ``[0, 2 pi)``, smooth and periodic.
        grid : Grid
        n_fine : int, optional
            Resolution of the internal trigonometric interpolant (default: 8N,
            at least 2048, doubled until r's Fourier coefficients are resolved).

        Notes
        -----
        The curve is resampled to constant arc length by Newton on the exact
        (spectrally interpolated) arc-length function; curvature comes from the
        interpolant's derivatives, ``kappa = (x'y'' - y'x'') / |gamma'|^3``.

        Returns
        -------
        Curve
            Constant ``g = L``, the first node at ``phi = 0``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(65))
        >>> bool(np.ptp(c.g) == 0), bool(np.linalg.norm(c.closure()) < 1e-9)
        (True, True)
        """
        if not callable(r):
            raise ValueError("r must be a callable r(phi)")
        M = int(n_fine or max(8 * grid.N, 2048))
        for _ in range(6):
            phi = 2 * np.pi * np.arange(M) / M
            rv = np.asarray(r(phi), dtype=float)
            if rv.shape != phi.shape or not np.all(np.isfinite(rv)) or np.any(rv <= 0):
                raise ValueError("r(phi) must return finite positive values of the same shape")
            rh = np.abs(np.fft.rfft(rv))
            if rh[-M // 16 :].max() <= 1e-15 * rh.max() or n_fine:
                break
            M *= 2
        return cls._from_interpolant(PeriodicInterpolant(rv * np.cos(phi), rv * np.sin(phi),
                                                         "fourier"), grid)

    @classmethod
    def from_positions(cls, x, y, grid: Grid, interpolant="auto") -> Curve:
        """Curve through closed samples, resampled to constant arc length.

        Parameters
        ----------
        x, y : array_like, shape (M,)
            Samples of a closed curve, counter-clockwise (the segment from the
            last sample back to the first closes it; a repeated end point is
            dropped). The first sample becomes the first node.
        grid : Grid
        interpolant : {"auto", "fourier", "spline"}
            ``"auto"`` uses trigonometric interpolation on Fourier grids
            (spectral accuracy for samples of a smooth curve at uniform parameter
            values) and a periodic quintic spline otherwise.

        Notes
        -----
        On finite-difference grids the curvature is computed from the resampled
        positions with the grid's second-order stencils (as the paper's code does);
        on Fourier grids from the interpolant's derivatives.

        Returns
        -------
        Curve
            Constant ``g = L`` (the interpolant's length); ``origin`` the first sample.

        Raises
        ------
        ValueError
            Invalid samples (see :func:`qsa.resample.closed_samples`), clockwise
            data, or samples of a curve that is not simple: crossing segments, or
            a total turning ``int kappa dsigma`` other than ``2 pi`` (a limaçon
            with an inner loop turns twice).

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> t = 2 * np.pi * np.arange(64) / 64
        >>> c = Curve.from_positions(2 * np.cos(t), np.sin(t), Fourier(33))
        >>> round(c.length(), 6)  # ellipse with semi-axes 2 and 1
        9.688448
        >>> r = 0.5 + np.cos(t)  # limaçon with an inner loop: turning number 2
        >>> try:
        ...     Curve.from_positions(r * np.cos(t), r * np.sin(t), Fourier(33))
        ... except ValueError as exc:
        ...     print(str(exc)[:48])
        from_positions: the samples intersect themselves
        """
        x, y = closed_samples(x, y, name="from_positions(x, y)")
        if interpolant == "auto":
            interpolant = "fourier" if isinstance(grid, Fourier) else "spline"
        area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
        if area <= 0:
            raise ValueError("from_positions: the samples run clockwise (or enclose no area); "
                             "pass them counter-clockwise")
        crossings = self_intersections(x, y)
        if crossings.shape[0]:
            i, j = crossings[0]
            raise ValueError(f"from_positions: the samples intersect themselves (segments {i} "
                             f"and {j} cross); a curve must be simple (turning number 1)")
        curve = cls._from_interpolant(PeriodicInterpolant(x, y, interpolant), grid,
                                      stencil_kappa=grid.sparse)
        turning = float(curve.kappa @ curve.dsigma) / (2 * np.pi)
        if abs(turning - 1) > 0.25:
            raise ValueError(f"from_positions: the resampled curve turns {turning:.3g} times "
                             f"(int kappa dsigma = {2 * np.pi * turning:.4g}, not 2 pi); it is "
                             "not simple, or the grid is too coarse for it")
        return curve

    @classmethod
    def _from_interpolant(cls, curve: PeriodicInterpolant, grid: Grid,
                          stencil_kappa=False) -> Curve:
        t, L = equal_arclength_parameters(curve, grid.N)
        z1 = curve.derivative(t, 1)
        if stencil_kappa:
            # Finite-difference grids: curvature from the resampled positions with the
            # grid's stencils (the paper's preprocessing), whose O(h^2) error is smooth.
            z = curve.derivative(t)
            D, D2 = grid.derivative(), grid.second_derivative()
            x1, y1, x2, y2 = D @ z.real, D @ z.imag, D2 @ z.real, D2 @ z.imag
            kappa = (x1 * y2 - y1 * x2) / np.hypot(x1, y1) ** 3
        else:
            z2 = curve.derivative(t, 2)
            kappa = (z1.real * z2.imag - z1.imag * z2.real) / np.abs(z1) ** 3
        z0 = curve.derivative(t[:1])[0]
        return cls(kappa, L, grid, float(np.angle(z1[0])), (z0.real, z0.imag))
