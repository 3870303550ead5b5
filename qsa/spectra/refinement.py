"""Refined solves with a bordered system, and the estimate of their forward error.

The shift-invert system of :class:`~qsa.spectra.factored.ShiftInvert` is a sparse (or,
on Fourier grids, dense) core bordered by a few dense rows and columns,
``[[C, B1], [B2, D]]``; it is solved by some factorization (sparse LU, the capacitance
elimination, dense LU) and every solve is improved by iterative refinement with the
residual of the whole system. :class:`BorderedSystem` computes that residual in three
precisions:

* ``"working"`` (float64): classical refinement, which converges to
  ``cond(A) eps |x|``;
* ``"extended"`` (``np.longdouble`` accumulation; the float64 entries are widened
  exactly inside the products, so no extended copy of the core is kept): refinement
  converges to the rounding level of the solution itself, ``eps |x|``, however close
  the shift is to an eigenvalue;
* ``"mixed"``: extended, except the wide blocks of a sparse core
  (:meth:`~qsa.linalg.BlockSparse.wide`, the implicit state's two-point blocks: nearly
  all of its entries, and of the cost of an extended product), taken in working
  precision.

:func:`probe` solves two random right-hand sides and refines them once in working
precision, then computes one more correction with the residual in extended and in mixed
precision (the first step's size is the unrefined solve's forward error,
:attr:`Probe.unrefined`). If the extended correction still exceeds ``1e-10`` of the solution,
working-precision refinement stalls (the shifted system is nearly singular) and every
refinement and estimate is done in extended precision. Otherwise the probe compares the
rounding noise of the mixed residual, ``rho = |dx_mixed - dx_ext| / |x|``, with the
forward error itself, ``alpha = |dx_ext| / |x|`` (largest and smallest over its columns).

:func:`refined_solve` returns, with ``estimate=True``, one further correction that is
not applied. Its residual is the mixed one when ``rho <= alpha / 2``: the forward error
of the solution is then at most the correction's size plus the noise of its residual
(``|x - x_true| <= |dx| + |dx - dx_true|``), the latter taken as ``2 rho |x|``
(measured on CHA states at N = 2400: rho ~ 0.1-0.6 alpha, and the column-to-column
spread of the noise within 1.3 of the probe's). Otherwise (at N = 4800 the noise of the
working-precision wide blocks is as large as the error it would measure) the residual
is extended throughout, as it is for a dense core.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from qsa.linalg import BlockSparse

__all__ = ["BorderedSystem", "Probe", "probe", "refined_solve", "column_norms",
           "MIXED_NOISE", "STALL"]

#: Relative size of the extended-precision correction above which working-precision
#: refinement is taken to stall.
STALL = 1e-10


def column_norms(x, w):
    """``<.,.>`` norms of the columns of the first ``w.size`` rows of ``x``."""
    N = w.size
    ww = w if np.ndim(x) == 1 else w[:, None]
    return np.sqrt(np.sum(ww * np.asarray(x)[:N] ** 2, axis=0))


@dataclass(frozen=True, eq=False)
class BorderedSystem:
    """``[[C, B1], [B2, D]]`` with a sparse (:class:`~qsa.linalg.BlockSparse`) or dense core.

    Only the first ``p`` border columns take part in a product (a factorization with a
    shorter border, e.g. without the deflation rows).

    Attributes
    ----------
    core : BlockSparse or ndarray, shape (n, n)
    B1 : ndarray, shape (n, r)
    B2 : ndarray, shape (r, n)
    D : ndarray, shape (r, r)
    wide : ndarray of bool or None
        The wide blocks of a sparse core (None: none, or a dense core).
    """

    core: Any
    B1: np.ndarray
    B2: np.ndarray
    D: np.ndarray
    wide: Any = field(init=False)

    def __post_init__(self):
        wide = self.core.wide() if isinstance(self.core, BlockSparse) else None
        object.__setattr__(self, "wide", wide if wide is not None and wide.any() else None)

    @property
    def n(self) -> int:
        """Rows of the core."""
        return self.core.shape[0]

    def residual(self, rhs, x, p, precision="working"):
        """``rhs - A x`` (float64) for the core with the first ``p`` border columns.

        Parameters
        ----------
        rhs, x : ndarray, shape (n + p,) or (n + p, k)
        p : int
        precision : {"working", "extended", "mixed"}
            See the module docstring.

        Returns
        -------
        ndarray, shape like ``rhs``
        """
        n = self.n
        if precision == "working":
            y = self.core @ x[:n] + self.B1[:, :p] @ x[n:]
            z = self.B2[:p] @ x[:n] + self.D[:p, :p] @ x[n:]
            return rhs - np.concatenate([y, z], axis=0)
        ld = np.longdouble
        xl = np.asarray(x, dtype=ld)
        if precision == "mixed" and self.wide is not None:
            y = (self.core.product(xl[:n], ~self.wide)
                 + self.core.product(np.asarray(x, dtype=float)[:n], self.wide))
        else:
            y = self.core @ xl[:n]
        y = y + self.B1[:, :p] @ xl[n:]
        z = self.B2[:p] @ xl[:n] + self.D[:p, :p] @ xl[n:]
        return (np.asarray(rhs, dtype=ld) - np.concatenate([y, z], axis=0)).astype(float)


#: The estimate uses the mixed residual when the probe's noise is at most this fraction
#: of the forward error it estimates.
MIXED_NOISE = 0.5


@dataclass(frozen=True)
class Probe:
    """What :func:`probe` found for one factorization.

    Attributes
    ----------
    extended : bool
        Working-precision refinement stalls: refine and estimate in extended precision.
    noise : float
        The largest relative rounding noise ``|dx_mixed - dx_ext| / |x|`` of a mixed
        residual's correction (0 for a dense core, whose mixed residual is the extended one).
    accuracy : float
        The smallest relative forward error ``|dx_ext| / |x|`` after one working-precision
        refinement.
    unrefined : float
        The largest relative size ``|dx_1| / |x|`` of the first refinement step: the
        forward error of an unrefined solve.

    Parameters
    ----------
    The attributes above.
    """

    extended: bool
    noise: float
    accuracy: float
    unrefined: float = 0.0

    @property
    def mixed(self) -> bool:
        """Whether forward-error estimates may take the mixed residual."""
        return not self.extended and self.noise <= MIXED_NOISE * self.accuracy


def probe(solve, system: BorderedSystem, p, w, seed=3) -> Probe:
    """Probe the refinement of ``solve`` (see the module docstring).

    Parameters
    ----------
    solve : callable
        Solves the bordered system (with ``p`` border columns) for a block of columns.
    system : BorderedSystem
    p : int
    w : ndarray, shape (N,)
        ``dsigma``: the right-hand sides are ``w`` times standard normals in the first
        ``N`` rows, the norms those of :func:`column_norms`.
    seed : int

    Returns
    -------
    Probe
    """
    N = w.size
    rng = np.random.default_rng(seed)
    rhs = np.zeros((system.n + p, 2))
    for j in range(2):
        rhs[:N, j] = rng.standard_normal(N) * w
    x = solve(rhs)
    first = solve(system.residual(rhs, x, p))
    x = x + first
    unrefined = float(np.max(column_norms(first, w) / column_norms(x, w)))
    residuals = [system.residual(rhs, x, p, "extended")]
    if system.wide is not None:
        residuals.append(system.residual(rhs, x, p, "mixed"))
    dx = solve(np.hstack(residuals))  # the corrections in one block solve
    extended = bool(np.any(np.linalg.norm(dx[:, :2], axis=0)
                           > STALL * np.linalg.norm(x, axis=0)))
    xn = column_norms(x, w)
    noise = 0.0
    if system.wide is not None:
        noise = float(np.max(column_norms(dx[:, 2:] - dx[:, :2], w) / xn))
    return Probe(extended, noise, float(np.min(column_norms(dx[:, :2], w) / xn)), unrefined)


def refined_solve(solve, system: BorderedSystem, p, rhs, refine, found: Probe, w,
                  estimate=False):
    """``refine`` steps of iterative refinement, and optionally the forward-error estimate.

    Parameters
    ----------
    solve : callable
    system : BorderedSystem
    p : int
    rhs : ndarray, shape (n + p,) or (n + p, k)
    refine : int
    found : Probe
        The factorization's probe (:func:`probe`).
    w : ndarray, shape (N,)
    estimate : bool

    Returns
    -------
    x : ndarray, shape like ``rhs``
    dx : ndarray or None
        With ``estimate``: the first ``N`` rows of one more correction, not applied.
    noise : float
        ``2 found.noise`` with the mixed residual, else 0: the estimate of the forward error
        of the first ``N`` rows of (a combination of) the columns is
        ``|dx| + noise |x|`` (:func:`column_norms`).
    """
    x = solve(rhs)
    precision = "extended" if found.extended else "working"
    for _ in range(refine):
        x = x + solve(system.residual(rhs, x, p, precision))
    if not estimate:
        return x, None, 0.0
    precision = "mixed" if found.mixed else "extended"
    dx = solve(system.residual(rhs, x, p, precision))[: w.size]
    return x, dx, 2.0 * found.noise if found.mixed else 0.0
