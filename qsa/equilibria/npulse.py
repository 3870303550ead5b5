"""Periodic N-pulse faceted equilibria (and the circle) of ``Faceting + Perimeter``.

Construction (section "Formal Equilibrium and Quasi-Steady Analysis", e:Facet-CP,
e:Fint; Conventions and errata, section 5). With constant arc length ``g = L`` the equilibrium
equations reduce to ``alpha^2 psi'' - W'(psi) = nu1`` in arc length ``sigma = L s``,
with first integral ``alpha^2 psi'^2/2 = P(psi) = W(psi) + nu1 psi + nu2``. Pick the
periodic orbit (:mod:`qsa.equilibria.orbit`) whose pulse turns the tangent by
``int_pulse psi dsigma = 2 pi / N``; then ``N`` pulses give ``int kappa dsigma = 2 pi``
(e:C2) and the curve closes (e:C1) because it is made of N copies of one arc, each
rotated by ``2 pi / N`` from the previous. Its length is ``L = N T`` (T the period).

On such a state ``d_kappa E = -nu1`` and ``g d_g E = -(nu1 psi + nu2) + beta (L - L*)``,
so (Conventions and errata, section 5) ::

    V^n = -G(-nu1) - psi (-(nu1 psi + nu2) + beta (L - L*)) = psi (nu2 - beta (L - L*)),

which vanishes for ``L* = L - nu2 / beta``. The multipliers of e:Abs-CP are
``Lambda = (0, 0, -nu1)``.

NOTE: the paper prints ``g d_g E = nu1 psi + nu2 + beta(|Gamma| - L*)`` and hence
``V^n = -nu2 - beta(|Gamma| - L*)``; the sign of the ``nu`` terms is wrong (Conventions and errata,
section 5, "Sign slip"): V^n = 0 needs ``beta (L - L*) = nu2 < 0``, i.e. ``L < L*``.

Existence. Along the family of periodic orbits (``nu2`` from the centre value to
the separatrix) the turning per pulse ``Theta`` runs from the small-oscillation
limit ``Theta_0 = c T_0``, ``T_0 = 2 pi alpha / sqrt(-W''(c))`` (linearise
``alpha^2 psi'' = P'(psi)`` at the maximum ``c`` of P), to the separatrix limit,
where the period diverges logarithmically and ``Theta -> s * infinity`` with ``s`` the
well of P whose level is reached first. For ``nu1 = 0`` and a symmetric well
(``W(k) = W(kstar - k)``) the orbit is symmetric about ``c = kstar/2``, so
``Theta = kstar T / 2`` increases from ``Theta_0 = pi alpha kstar / sqrt(-W''(kstar/2))``
to infinity and an N-pulse exists iff ``N Theta_0 < 2 pi``, i.e.
``N alpha kstar < 2 sqrt(-W''(kstar/2))``. For the quartic ``W''(kstar/2) = -kstar^2/4``: ::

    N alpha < 1.

In general (any ``nu1``, any well) the N-pulse exists iff ``2 pi / N`` is in the range
of ``Theta`` over the family; :func:`npulse` scans it and says so when it is not.
"""

from __future__ import annotations

import numpy as np

from qsa._checks import integer, real_number
from qsa.curve import Curve
from qsa.discretize import Fourier, Grid
from qsa.energies import Faceting, Perimeter
from qsa.energies.wells import resolve_well
from qsa.equilibria.orbit import orbit_with_turning
from qsa.equilibria.result import Equilibrium

__all__ = ["npulse", "circle", "resolving_size", "faceting_residual"]


def resolving_size(kappa_of_s, tol=1e-14, max_size=20001):
    """Smallest odd Fourier size resolving a periodic function to ``tol`` (relative).

    Parameters
    ----------
    kappa_of_s : callable
        Periodic function of ``s in [0, 1)`` (vectorised).
    tol : float
        Coefficients below ``tol * max|coef|`` are considered negligible.

    Returns
    -------
    int
        Odd ``N`` with all Fourier modes ``|k| > (N-1)/2`` below the tolerance.

    Examples
    --------
    >>> import numpy as np
    >>> resolving_size(lambda s: np.cos(2 * np.pi * 3 * s))  # mode 3: floor of 9 nodes
    9
    >>> resolving_size(lambda s: np.exp(np.cos(2 * np.pi * s))) < 51
    True
    """
    M = 1025
    while True:
        s = np.arange(M) / M
        c = np.abs(np.fft.rfft(kappa_of_s(s))) / M
        big = np.nonzero(c > tol * c.max())[0]
        kmax = int(big[-1]) if big.size else 0
        if kmax < 0.4 * M or M >= 4 * max_size:
            break
        M = 2 * M + 1
    N = 2 * kmax + 3
    if N > max_size:
        raise ValueError(f"resolving the fronts needs N={N} > max_size={max_size} nodes")
    return max(N, 9)


def faceting_residual(energy, curve, alpha, well):
    """``(max |V^n|, largest single term of V^n)`` for faceting (+ perimeter) energies.

    ``V^n = Delta_s mu + kappa^2 mu - kappa g d_g E`` with
    ``mu = -alpha^2 Delta_s kappa + W'(kappa)`` (e:Facet-NV); the single terms are
    ``alpha^2 Delta_s^2 kappa``, ``Delta_s W'(kappa)``, ``kappa^2 mu`` and ``kappa g d_g E``.

    Parameters
    ----------
    energy : Energy
        ``Faceting`` (+ ``Perimeter``) with the given ``alpha`` and ``well``.
    curve : Curve
    alpha : float
    well : object
        The double well (``dW`` is used).

    Returns
    -------
    residual : float
        ``max |V^n|``.
    scale : float
        The largest single term; ``residual / scale`` is the relative residual.

    Examples
    --------
    >>> from qsa.energies import DoubleWell
    >>> eq = circle(1.0, 0.1, kstar=5.0)
    >>> res, scale = faceting_residual(eq.energy, eq.curve, 0.1, DoubleWell(5.0))
    >>> bool(res < 1e-10 * scale), round(scale, 6)
    (True, 6.0)
    """
    Vn = np.asarray(energy.normal_velocity(curve))
    N = curve.N
    grad = np.asarray(energy.gradient(curve))
    D = curve.grid.derivative()
    g = curve.g

    def lap(f):
        return (D @ ((D @ f) / g)) / g

    k = curve.kappa
    mu = grad[:N]
    terms = [alpha**2 * lap(lap(k)), lap(well.dW(k)), k**2 * mu, k * g * grad[N:]]
    scale = max(float(np.max(np.abs(t))) for t in terms)
    return float(np.max(np.abs(Vn))), scale


def _finish(curve, energy, params, multipliers, alpha, well, kind, extra):
    res, scale = faceting_residual(energy, curve, alpha, well)
    clo = float(np.linalg.norm(curve.closure()))
    ok = clo <= 1e-10 and res <= 1e-8 * scale
    msg = (f"{kind}: |C(U)| = {clo:.2e}, max|V^n| = {res:.2e} "
           f"({res / scale:.1e} of the largest term)")
    if not ok:
        msg += "; above tolerance (grid too coarse for the fronts?)"
    return Equilibrium(curve, energy, params, np.asarray(multipliers, dtype=float), res, clo,
                       scale, kind, ok, msg, extra)


def _grid(grid, kappa_of_s):
    if grid is None:
        return Fourier(resolving_size(kappa_of_s))
    if isinstance(grid, Grid):
        return grid
    if isinstance(grid, (int, np.integer)) and not isinstance(grid, bool):
        return Fourier(int(grid))
    raise ValueError(f"grid must be a Grid, an odd int (Fourier size) or None, got {grid!r}")


def _centred(Curve, kappa, L, grid):
    c = Curve(kappa, L, grid)
    xy = c.positions()
    centre = (xy @ c.dsigma) / c.length()
    return Curve(kappa, L, grid, 0.0, tuple(-centre))


def npulse(n_pulses, alpha, well=None, grid=None, nu1=0.0, beta=5.0, kstar=None):
    """The N-fold symmetric faceted equilibrium built from N equal pulses.

    Parameters
    ----------
    n_pulses : int
        Number of pulses (rounded corners), ``>= 2``.
    alpha : float
        ``> 0``.
    well : object, optional
        Double well (default quartic ``k^2 (k - kstar)^2/4``).
    grid : Grid, int or None
        Grid of the returned curve; an int means ``Fourier(int)``; ``None`` picks the
        smallest odd Fourier size that resolves the fronts to 1e-14
        (:func:`resolving_size`).
    nu1 : float
        Multiplier of the total-curvature constraint (``Lambda_3 = -nu1``).
    beta : float
        Perimeter penalty, ``> 0``; ``L_star`` is chosen so that V^n = 0.
    kstar : float, optional
        Second well (default ``well.kstar`` or 5.0).

    Returns
    -------
    Equilibrium
        ``kind="npulse"``, ``params`` with ``nu1, nu2, L, L_star, alpha, beta, kstar,
        n_pulses, period, turning``; ``energy = Faceting(alpha, kstar, well) +
        Perimeter(beta, L_star)``; ``curve`` with ``g = L`` constant, ``s = 0`` in the
        middle of a facet and the perimeter centroid at the origin;
        ``extra["orbit"]`` the :class:`~qsa.equilibria.orbit.PeriodicOrbit`.

    Raises
    ------
    ValueError
        ``n_pulses < 2``, ``alpha <= 0``, ``beta <= 0``, or no orbit of the family
        turns by ``2 pi / N`` (for ``nu1 = 0`` and the quartic: ``N alpha >= 1``).

    Notes
    -----
    See the module docstring for the derivation (e:Facet-CP, e:Fint, e:Facet-NV)
    and the Conventions and errata, section 5 sign correction of ``V^n``.

    Examples
    --------
    >>> eq = npulse(3, 0.1, kstar=5.0)
    >>> bool(eq.success), eq.params["nu2"] < 0, eq.params["L"] < eq.params["L_star"]
    (True, True, True)
    """
    n = integer(n_pulses, "n_pulses", minimum=2, too_small=(
        "{name}={value}: need at least {minimum} pulses (one pulse turns by 2 pi in a "
        "single facet and cannot close into an N-fold symmetric curve)"))
    alpha = real_number(alpha, "alpha", positive=True)
    beta = real_number(beta, "beta", positive=True)
    nu1 = real_number(nu1, "nu1")
    well, kstar = resolve_well(well, kstar)
    try:
        orbit = orbit_with_turning(alpha, 2 * np.pi / n, nu1, well, kstar)
    except ValueError as exc:
        raise ValueError(f"no {n}-pulse equilibrium for alpha={alpha}: {exc}") from None
    L = n * orbit.period
    L_star = L - orbit.nu2 / beta

    def kappa_of_s(s):
        return orbit(L * np.asarray(s))

    grid = _grid(grid, kappa_of_s)
    curve = _centred(Curve, kappa_of_s(grid.s), L, grid)
    energy = Faceting(alpha, kstar, well) + Perimeter(beta, L_star)
    params = {"nu1": nu1, "nu2": orbit.nu2, "L": L, "L_star": L_star, "alpha": alpha,
              "beta": beta, "kstar": kstar, "n_pulses": n, "period": orbit.period,
              "turning": orbit.turning}
    return _finish(curve, energy, params, (0.0, 0.0, -nu1), alpha, well, "npulse",
                   {"orbit": orbit})


def circle(R, alpha, grid=None, beta=5.0, well=None, kstar=None):
    """The circle of radius R as an equilibrium of ``Faceting + Perimeter``.

    It is one when ``beta (2 pi R - L*) = k0 W'(k0) - W(k0)``, ``k0 = 1/R`` (Conventions and errata,
    section 4), so ``L* = 2 pi R - (k0 W'(k0) - W(k0)) / beta``; the multipliers are
    ``Lambda = (0, 0, W'(k0))``.

    Parameters
    ----------
    R, alpha, beta : float
        ``> 0``.
    grid : Grid, int or None
        As in :func:`npulse` (``None``: ``Fourier(33)``).

    Returns
    -------
    Equilibrium
        ``kind="circle"``, ``params`` with ``R, alpha, beta, kstar, L, L_star``.

    Examples
    --------
    >>> import numpy as np
    >>> eq = circle(1.0, 0.1, kstar=5.0)
    >>> bool(eq.success), eq.multipliers.tolist()  # Lambda_3 = W'(1) = 6
    (True, [0.0, 0.0, 6.0])
    >>> round(eq.params["L_star"], 10) == round(2 * np.pi - (6.0 - 4.0) / 5.0, 10)
    True
    """
    R = real_number(R, "R", positive=True)
    alpha = real_number(alpha, "alpha", positive=True)
    beta = real_number(beta, "beta", positive=True)
    well, kstar = resolve_well(well, kstar)
    grid = Fourier(33) if grid is None else _grid(grid, None)
    k0 = 1.0 / R
    L = 2 * np.pi * R
    nu = float(k0 * well.dW(k0) - well.W(k0))
    L_star = L - nu / beta
    curve = Curve(np.full(grid.N, k0), L, grid, 0.0, (0.0, -R))
    energy = Faceting(alpha, kstar, well) + Perimeter(beta, L_star)
    params = {"R": R, "L": L, "L_star": L_star, "alpha": alpha, "beta": beta, "kstar": kstar}
    return _finish(curve, energy, params, (0.0, 0.0, float(well.dW(k0))), alpha, well,
                   "circle", {})
