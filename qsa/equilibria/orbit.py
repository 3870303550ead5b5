"""Periodic orbits of the faceting equilibrium equation (phase-plane construction).

Equilibria with constant arc length solve (e:Facet-CP, ``' = d/dsigma``) ::

    alpha^2 psi'' - W'(psi) = nu1,

whose first integral (e:Fint) is ``alpha^2 psi'^2 / 2 = P(psi) := W(psi) + nu1 psi + nu2``.
Since ``alpha^2 psi'' = P'(psi)``, periodic orbits circle a local *maximum* ``c`` of
``P`` (a point of the spinodal region ``W''(c) < 0``) and oscillate between the two
roots ``a < c < b`` of ``P``; they exist for ``nu2_c < nu2 < nu2_sep`` with
``nu2_c = -(W(c) + nu1 c)`` (the centre, small oscillations) and
``nu2_sep = -max(W(s) + nu1 s)`` over the two neighbouring minima ``s`` of ``P``
(the separatrix, infinitely long plateaus). For ``nu1 = 0`` and the quartic well,
``-kstar^4/64 < nu2 < 0`` (Conventions and errata, section 5); ``nu2 -> 0`` is the separatrix.

Period and curvature per pulse
------------------------------
With ``psi = m + h tanh v`` (``m = (a+b)/2``, ``h = (b-a)/2``; i.e. ``psi = m + h sin u``
with ``u = gd(v)``, Conventions and errata, section 5) the turning-point singularities disappear:
``P = (psi - a)(b - psi) R(psi)`` with ``R > 0`` on ``[a, b]`` and ::

    dsigma/dv = alpha sech(v) / sqrt(2 R),

a smooth, bounded function of ``v`` that decays like ``exp(-|v|)`` once ``psi`` is
closer to a turning point than to the nearest other root of ``P``. Near the
separatrix it equals ``sqrt(2) alpha / h`` over a long stretch -- exactly the
heteroclinic, whose logistic variable ``v`` is. Half a period is
``T/2 = int dsigma/dv dv`` and the curvature per pulse (the turning of the
tangent) ``Theta = int_period psi dsigma = 2 int psi dsigma/dv dv``, both with
composite Gauss-Legendre panels of width 1 in ``v``. ``R`` is evaluated without
cancellation: for the quartic with ``nu1 = 0`` from the exact roots
(``R = (d + x_a)(d + x_b)/4``, ``x_a = psi - a``, ``x_b = b - psi``, ``d`` the gap to the
outer roots); for polynomial wells (the quartic with ``nu1 != 0``, or a well with a
``coefficients`` attribute in ``numpy.polyval`` order) the orbit is labelled by the
offset ``ystar`` of its turning point from the separatrix well ``s*`` of P, the other
turning point by its offset from the other well, and near each turning point
``P/x`` is the exact difference quotient of the Taylor polynomial of P about that
well -- accurate for offsets down to ~1e-150, where double-precision roots would
only resolve ``1e-16 kstar``. For other wells ``P(psi) = x_a * mean(P')`` on
``[a, psi]`` (or its mirror at ``b``), which stays accurate at ordinary turning
points: non-polynomial wells are limited to plateau depths well above
``1e-16 kstar`` (:func:`orbit_with_turning` says so). The orbit is sampled by
inverting ``sigma(v)`` with safeguarded Newton steps.

No multiple precision is needed on these paths; ``mpmath`` serves the tests as
an independent reference.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import brentq
from scipy.special import expit

from qsa._checks import real_number
from qsa.energies.wells import is_quartic, resolve_well

if TYPE_CHECKING:
    from qsa.energies.wells import DoubleWell, Well

__all__ = ["PeriodicOrbit", "periodic_orbit", "periodic_range"]

_GL_X, _GL_W = np.polynomial.legendre.leggauss(20)
_MEAN_X, _MEAN_W = np.polynomial.legendre.leggauss(16)
_MEAN_X = 0.5 * (_MEAN_X + 1)
_MEAN_W = 0.5 * _MEAN_W
_TAIL = 38.0  # exp(-38) ~ 3e-17: the part of sigma(v) beyond the panels is negligible


# ---------------------------------------------------------------- phase plane
@dataclass(frozen=True)
class _Family:
    """Critical points of ``P`` for one ``nu1``: centre ``c``, minima ``s_lo < c < s_hi``."""

    well: DoubleWell | Well
    kstar: float
    nu1: float
    c: float
    s_lo: float
    s_hi: float
    nu2_c: float
    nu2_sep: float
    closed: bool  # quartic well and nu1 == 0: exact roots
    star: float | None = None  # polynomial path: the well of P whose level is the separatrix
    q: np.ndarray | None = None  # Taylor coefficients of W + nu1 psi about `star` (ascending)
    q_wells: tuple | None = None  # the same about s_lo and about s_hi

    def P(self, psi, nu2):
        return self.well.W(psi) + self.nu1 * psi + nu2

    def dP(self, psi):
        return self.well.dW(psi) + self.nu1


def _poly(well, kstar):
    """Ascending coefficients of W if it is a polynomial (quartic or ``well.coefficients``)."""
    if is_quartic(well, kstar):
        return np.array([0.0, 0.0, 0.25 * kstar**2, -0.5 * kstar, 0.25])
    c = getattr(well, "coefficients", None)  # numpy.polyval order (highest first)
    return None if c is None else np.asarray(c, dtype=float)[::-1].copy()


def _poly_family(well, kstar, nu1, coef) -> _Family:
    """Critical points from the polynomial; Taylor coefficients about the separatrix well."""
    P0 = np.polynomial.Polynomial(coef + np.r_[0.0, nu1, np.zeros(len(coef) - 2)])
    dP, d2P = P0.deriv(), P0.deriv(2)
    roots: list[float] = []
    for r in dP.roots():
        if abs(r.imag) > 1e-9 * kstar:
            continue
        x = r.real
        for _ in range(3):  # polish the root in double precision
            d2 = d2P(x)
            if d2 != 0:
                x -= dP(x) / d2
        roots.append(float(x))
    crit = np.sort(np.array(roots))
    best = None
    for j in range(1, len(crit) - 1):
        if d2P(crit[j]) < 0 < d2P(crit[j - 1]) and d2P(crit[j + 1]) > 0:
            if best is None or abs(crit[j] - 0.5 * kstar) < abs(crit[best] - 0.5 * kstar):
                best = j
    if best is None:
        raise ValueError(
            f"nu1={nu1}: W'(psi) + nu1 has no maximum of P between two minima, so "
            "alpha^2 psi'' - W'(psi) = nu1 has no periodic orbits (|nu1| too large)"
        )
    c, s_lo, s_hi = float(crit[best]), float(crit[best - 1]), float(crit[best + 1])
    if nu1 == 0.0 and abs(s_lo) < 1e-8 * kstar and abs(s_hi - kstar) < 1e-8 * kstar:
        s_lo, s_hi = 0.0, kstar  # the wells themselves, exactly

    def taylor(s0):
        q = (P0(np.polynomial.Polynomial([s0, 1.0]))).coef
        q = np.r_[q, np.zeros(max(0, 3 - len(q)))]
        q[1] = 0.0  # s0 is a critical point of P0 (exactly, in the shifted coordinate)
        return q

    q_lo, q_hi = taylor(s_lo), taylor(s_hi)
    if nu1 == 0.0:  # equal-depth wells (checked by resolve_well): equal levels exactly
        q_lo[0] = q_hi[0] = 0.0
    star = s_hi if q_hi[0] >= q_lo[0] else s_lo
    q = q_hi if star == s_hi else q_lo
    return _Family(well, kstar, float(nu1), c, s_lo, s_hi, -float(P0(c)), -float(q[0]),
                   False, star, q, (q_lo, q_hi))


def _family(well, kstar, nu1) -> _Family:
    if is_quartic(well, kstar) and nu1 == 0.0:
        k = kstar
        return _Family(well, k, 0.0, 0.5 * k, 0.0, k, -(k**4) / 64, 0.0, True)
    coef = _poly(well, kstar)
    if coef is not None:
        return _poly_family(well, kstar, nu1, coef)
    k = np.linspace(-1.0, 2.0, 3001) * kstar
    dP = np.asarray(well.dW(k), dtype=float) + nu1
    idx = np.nonzero(np.sign(dP[:-1]) * np.sign(dP[1:]) <= 0)[0]
    roots: list[float] = []
    for i in idx:
        if dP[i] == 0:
            r = k[i]
        elif dP[i + 1] == 0:
            continue
        else:
            r = brentq(lambda x: float(well.dW(x)) + nu1, k[i], k[i + 1], xtol=1e-15, rtol=1e-15)
        if not roots or abs(r - roots[-1]) > 1e-12 * kstar:
            roots.append(float(r))
    crit = np.array(roots)
    best = None
    for j in range(1, len(crit) - 1):
        if float(well.d2W(crit[j])) < 0 and float(well.d2W(crit[j - 1])) > 0 \
                and float(well.d2W(crit[j + 1])) > 0:
            if best is None or abs(crit[j] - 0.5 * kstar) < abs(crit[best] - 0.5 * kstar):
                best = j
    if best is None:
        raise ValueError(
            f"nu1={nu1}: W'(psi) + nu1 has no maximum of P between two minima, so "
            "alpha^2 psi'' - W'(psi) = nu1 has no periodic orbits (|nu1| too large)"
        )
    c, s_lo, s_hi = crit[best], crit[best - 1], crit[best + 1]
    Pc = float(well.W(c)) + nu1 * c
    Ps = max(float(well.W(s_lo)) + nu1 * s_lo, float(well.W(s_hi)) + nu1 * s_hi)
    return _Family(well, kstar, float(nu1), c, s_lo, s_hi, -Pc, -Ps, False)


# ---------------------------------------------------------------- the orbit
@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """One periodic solution ``psi(sigma)`` of ``alpha^2 psi'' - W'(psi) = nu1``.

    Call it with arc length: ``orbit(sigma)``; ``psi(0) = a`` (a minimum of the
    pulse, the middle of a flat facet) and ``psi(period/2) = b``.

    Attributes
    ----------
    alpha, nu1, nu2, kstar : float
    well : object
    a, b : float
        Turning points (roots of ``P``), ``a < b``.
    period : float
        Arc length of one pulse, ``T``.
    turning : float
        Curvature per pulse ``Theta = int_0^T psi dsigma`` (the angle by which the
        tangent turns over one pulse).
    depth : float
        ``min(a - s_lo, s_hi - b)``: distance of the plateaus from the wells of P
        (exponentially small near the separatrix).

    Parameters
    ----------
    Constructed by :func:`periodic_orbit` (not directly).

    Examples
    --------
    >>> import numpy as np
    >>> orb = periodic_orbit(0.1, nu2=-1.0, kstar=5.0)
    >>> bool(orb.a < 2.5 < orb.b), bool(np.isclose(orb(0.0), orb.a))
    (True, True)
    >>> bool(np.isclose(orb(orb.period / 2), orb.b)), bool(np.isclose(orb(orb.period), orb.a))
    (True, True)
    """

    alpha: float
    nu1: float
    nu2: float
    kstar: float
    well: DoubleWell | Well
    a: float
    b: float
    period: float
    turning: float
    depth: float
    _t: dict | None = field(repr=False, default=None)

    # --------------------------------------------------------- evaluation
    def _v_of_sigma(self, sig):
        """Invert ``sigma(v)`` (sigma from the turning point a); sig in [0, T/2]."""
        t = self._t
        vb, S = t["vb"], t["S"]
        sig = np.clip(sig, 0.0, S[-1])
        j = np.clip(np.searchsorted(S, sig, side="right") - 1, 0, len(vb) - 2)
        lo, hi = vb[j].copy(), vb[j + 1].copy()
        frac = np.where(S[j + 1] > S[j], (sig - S[j]) / np.maximum(S[j + 1] - S[j], 1e-300), 0.5)
        v = lo + frac * (hi - lo)
        hw = 0.5 * (self.b - self.a) / max(abs(self.a), abs(self.b))
        act = np.arange(v.size)
        for _ in range(80):
            jj, va = j[act], v[act]
            half = 0.5 * (va - vb[jj])
            nodes = vb[jj][:, None] + half[:, None] * (1 + _GL_X)
            f = S[jj] + half * (t["F"](nodes) @ _GL_W) - sig[act]
            lo[act] = np.where(f < 0, va, lo[act])
            hi[act] = np.where(f > 0, va, hi[act])
            new = va - f / t["F"](va)
            bad = ~((new > lo[act]) & (new < hi[act])) | ~np.isfinite(new)
            new = np.where(bad, 0.5 * (lo[act] + hi[act]), new)
            # converged once the step no longer moves psi = m + h tanh(v)
            step = np.abs(new - va)
            done = (step <= 1e-15 * (1 + np.abs(va))) | (hw * step / np.cosh(va) ** 2 <= 1e-16)
            v[act] = new
            act = act[~done]
            if act.size == 0:
                break
        return v

    def _split(self, sigma):
        sigma = np.asarray(sigma, dtype=float)
        T = self.period
        loc = np.mod(sigma, T)
        rising = loc <= 0.5 * T
        sig = np.where(rising, loc, T - loc)
        return self._v_of_sigma(sig.ravel()).reshape(sig.shape), rising

    def __call__(self, sigma):
        """``psi(sigma)``, periodic with period ``T``; shape like ``sigma``."""
        v, _ = self._split(sigma)
        xa, xb = self._t["xaxb"](v)
        return np.where(v <= 0, self.a + xa, self.b - xb)

    def derivative(self, sigma):
        """``psi'(sigma) = (dpsi/dv) / (dsigma/dv)``, from the quadrature; shape like sigma.

        Parameters
        ----------
        sigma : array_like

        Returns
        -------
        ndarray, shape like ``sigma``

        Examples
        --------
        >>> import numpy as np
        >>> orb, d = periodic_orbit(0.1, nu2=-1.0, kstar=5.0), 1e-6
        >>> fd = (orb(0.1 + d) - orb(0.1 - d)) / (2 * d)
        >>> bool(np.isclose(orb.derivative(0.1), fd, rtol=1e-6))
        True
        """
        v, rising = self._split(sigma)
        h = 0.5 * (self.b - self.a)
        slope = h / (np.cosh(v) ** 2 * self._t["F"](v))
        return np.where(rising, slope, -slope)


def _Q(q, y):
    """``P0(star + y) - P0(star)`` from the Taylor coefficients (no cancellation)."""
    return sum(q[k] * y**k for k in range(2, len(q)))


def _Q_difference_quotient(q, y, x):
    """``(Q(y + x) - Q(y)) / x`` by ``A^k - B^k = (A - B) sum A^(k-1-j) B^j``."""
    A = y + x
    out = 0.0
    for k in range(2, len(q)):
        out = out + q[k] * sum(A ** (k - 1 - j) * y**j for j in range(k))
    return out


def _poly_orbit(fam, nu2, ystar):
    """Turning points and ``R`` for a polynomial well, exact near both wells of P.

    The orbit is labelled by ``ystar`` = (turning point near ``star``) - ``star``; then
    ``nu2 = nu2_sep - Q*(ystar)`` with ``Q*`` the Taylor polynomial of P about ``star``
    without its constant. The other turning point is ``s_o + y_o`` with
    ``Q_o(y_o) = Q*(ystar) + (P(star) - P(s_o))`` about the other well ``s_o``. Near each
    turning point ``P(t + x) / x`` is the difference quotient of the Taylor polynomial
    there -- sums of same-sign terms, accurate even when the offsets are far below
    the rounding unit of the wells' positions.
    """
    q_lo, q_hi = fam.q_wells
    high = fam.star == fam.s_hi  # the separatrix is reached at the upper well
    if ystar is None:  # from nu2: Q*(ystar) = nu2_sep - nu2 on the segment star -> c
        target = fam.nu2_sep - nu2
        ystar = brentq(lambda y: _Q(fam.q, y) - target, 0.0, fam.c - fam.star, xtol=1e-300,
                       rtol=1e-15, maxiter=500)
    else:
        nu2 = fam.nu2_sep - _Q(fam.q, ystar)
    level = _Q(fam.q, ystar)
    s_o, q_o = (fam.s_lo, q_lo) if high else (fam.s_hi, q_hi)
    level_o = level + (fam.q[0] - q_o[0])
    y_o = brentq(lambda y: _Q(q_o, y) - level_o, 0.0, fam.c - s_o, xtol=1e-300, rtol=1e-15,
                 maxiter=500)
    y_a, y_b = (y_o, ystar) if high else (ystar, y_o)
    a, b = fam.s_lo + y_a, fam.s_hi + y_b

    def R(xa, xb, v):
        low = v <= 0
        pa = _Q_difference_quotient(q_lo, y_a, np.where(low, xa, 0.0))  # P(a + x_a) / x_a
        pb = -_Q_difference_quotient(q_hi, y_b, -np.where(low, 0.0, xb))  # P(b - x_b) / x_b
        return np.where(low, pa / xb, pb / xa)

    depth = min(abs(y_a), abs(y_b))
    return a, b, nu2, depth, R, abs(y_a), abs(y_b)


def _build(fam: _Family, alpha, nu2, *, rho=None, ystar=None) -> PeriodicOrbit:
    """Orbit for ``nu2`` (exact quartic path: ``rho = 2 sqrt(-nu2)``; polynomial path:
    ``ystar``, the offset of the separatrix-side turning point from its well)."""
    k = fam.kstar
    if fam.closed:
        if rho is None:
            rho = 2.0 * np.sqrt(-nu2)
        nu2 = -0.25 * rho**2
        a = 2 * rho / (k + np.sqrt(k * k - 4 * rho))
        b = k - a
        d = a + 2 * rho / (k + np.sqrt(k * k + 4 * rho))  # a - r1 = r4 - b
        h = 0.5 * np.sqrt(k * k - 4 * rho)
        d_lo = d_hi = d
        depth = a

        def R(xa, xb, v):
            return 0.25 * (d + xa) * (d + xb)
    elif fam.q is not None:
        a, b, nu2, depth, R, d_lo, d_hi = _poly_orbit(fam, nu2, ystar)
        h = 0.5 * (b - a)
    else:
        opts = {"xtol": 1e-300, "rtol": 1e-15, "maxiter": 500}
        a = brentq(lambda x: float(fam.P(x, nu2)), fam.s_lo, fam.c, **opts)
        b = brentq(lambda x: float(fam.P(x, nu2)), fam.c, fam.s_hi, **opts)
        h = 0.5 * (b - a)
        d_lo = abs(float(fam.dP(a)) / float(fam.well.d2W(a)))
        d_hi = abs(float(fam.dP(b)) / float(fam.well.d2W(b)))
        depth = min(a - fam.s_lo, fam.s_hi - b)

        def R(xa, xb, v):
            low = v <= 0
            x = np.where(low, xa, xb)
            base = np.where(low, a, b)
            sgn = np.where(low, 1.0, -1.0)
            pts = base[..., None] + (sgn * x)[..., None] * _MEAN_X
            mean = sgn * (fam.dP(pts) @ _MEAN_W)
            return mean / np.where(low, xb, xa)

    def xaxb(v):
        return 2 * h * expit(2 * v), 2 * h * expit(-2 * v)

    def F(v):
        xa, xb = xaxb(v)
        return alpha / (np.cosh(v) * np.sqrt(2 * R(xa, xb, v)))

    X_lo = 0.5 * np.log(max(2 * h / max(d_lo, 1e-300), 1.0)) + _TAIL
    X_hi = 0.5 * np.log(max(2 * h / max(d_hi, 1e-300), 1.0)) + _TAIL
    n = int(np.ceil(X_lo + X_hi))
    vb = np.linspace(-X_lo, X_hi, n + 1)
    half = 0.5 * np.diff(vb)
    nodes = vb[:-1, None] + half[:, None] * (1 + _GL_X)
    with np.errstate(invalid="ignore", divide="ignore"):
        Fn = F(nodes)
    pieces = half * (Fn @ _GL_W)
    xa, xb = xaxb(nodes)
    psi = np.where(nodes <= 0, a + xa, b - xb)
    theta_half = float(np.sum(half * ((psi * Fn) @ _GL_W)))
    S = np.concatenate([[0.0], np.cumsum(pieces)])
    if not (np.all(np.isfinite(S)) and np.all(pieces >= 0)):
        raise ValueError(
            f"nu2={nu2!r}: the orbit is too close to the separatrix to evaluate this well in "
            "double precision (P has lost its sign structure near the turning points); "
            "use a larger alpha, fewer pulses, or the quartic well (exact roots)"
        )
    t = {"vb": vb, "S": S, "F": F, "xaxb": xaxb, "family": fam}
    return PeriodicOrbit(alpha, fam.nu1, float(nu2), k, fam.well, float(a), float(b),
                         2 * float(S[-1]), 2 * theta_half, float(depth), t)


# ---------------------------------------------------------------- public API
def periodic_range(nu1=0.0, well=None, kstar=None):
    """The open interval ``(nu2_c, nu2_sep)`` of ``nu2`` with periodic orbits.

    Independent of ``alpha``. For the quartic well and ``nu1 = 0`` it is
    ``(-kstar^4/64, 0)``.

    Raises
    ------
    ValueError
        If ``nu1`` is so large that ``P`` has no maximum between two minima.

    Parameters
    ----------
    nu1 : float
        Multiplier of the total-curvature constraint.
    well : object, optional
        Double well (default quartic).
    kstar : float, optional

    Returns
    -------
    nu2_c, nu2_sep : float
        Centre (small oscillations) and separatrix values.

    Examples
    --------
    >>> lo, hi = periodic_range(kstar=4.0)
    >>> round(lo, 12), round(hi, 12)  # (-kstar^4 / 64, 0)
    (-4.0, 0.0)
    """
    well, kstar = resolve_well(well, kstar)
    fam = _family(well, kstar, real_number(nu1, "nu1"))
    return fam.nu2_c, fam.nu2_sep


def periodic_orbit(alpha, nu2, nu1=0.0, well=None, kstar=None) -> PeriodicOrbit:
    """The periodic orbit of ``alpha^2 psi'' - W'(psi) = nu1`` with first-integral level nu2.

    Parameters
    ----------
    alpha : float
        ``> 0``.
    nu2 : float
        Level of the first integral ``alpha^2 psi'^2/2 = W(psi) + nu1 psi + nu2``;
        must lie in :func:`periodic_range` (open interval).
    nu1 : float
        Multiplier of the total-curvature constraint.
    well, kstar
        As in :func:`heteroclinic`.

    Returns
    -------
    PeriodicOrbit

    Raises
    ------
    ValueError
        ``alpha <= 0`` or ``nu2`` outside the periodic range (the message gives it).

    Examples
    --------
    >>> orb = periodic_orbit(0.1, nu2=-1.0, kstar=5.0)
    >>> bool(orb.a < 2.5 < orb.b), round(orb.turning / orb.period, 12)  # mean = kstar/2
    (True, 2.5)
    """
    alpha = real_number(alpha, "alpha", positive=True)
    well, kstar = resolve_well(well, kstar)
    fam = _family(well, kstar, real_number(nu1, "nu1"))
    nu2 = real_number(nu2, "nu2")
    if not fam.nu2_c < nu2 < fam.nu2_sep:
        raise ValueError(
            f"nu2={nu2!r} is outside the periodic range ({fam.nu2_c!r}, {fam.nu2_sep!r}) "
            f"for nu1={fam.nu1!r}: no periodic orbit (below: P < 0 everywhere near the "
            "centre; above: orbits are unbounded or homoclinic)"
        )
    return _build(fam, alpha, nu2)


def orbit_with_turning(alpha, turning, nu1=0.0, well=None, kstar=None):
    """The periodic orbit whose curvature per pulse ``int psi dsigma`` equals ``turning``.

    Solves for ``nu2`` along the family, parametrised by ``t > 0`` with
    ``nu2 = nu2_sep - (nu2_sep - nu2_c) exp(-t)`` (``rho = kstar^2/4 exp(-t)`` on the
    exact quartic path), which makes the period grow linearly in ``t`` near the
    separatrix.

    Raises
    ------
    ValueError
        When no orbit of the family turns by ``turning``; the message gives the
        range of turnings found and, for ``nu1 = 0``, the existence condition.
    """
    alpha = real_number(alpha, "alpha", positive=True)
    well, kstar = resolve_well(well, kstar)
    fam = _family(well, kstar, real_number(nu1, "nu1"))
    target = float(turning)

    if fam.closed:
        def orbit(t):
            return _build(fam, alpha, None, rho=0.25 * kstar**2 * np.exp(-t))
        t_max = 650.0
    elif fam.q is not None:
        y0 = fam.c - fam.star

        def orbit(t):
            return _build(fam, alpha, None, ystar=y0 * np.exp(-t))
        t_max = float(np.log(abs(y0) / 1e-150))  # keep Q(ystar) ~ ystar^2 above underflow
    else:
        span = fam.nu2_sep - fam.nu2_c
        floor = 64 * np.finfo(float).eps * max(abs(fam.nu2_sep), abs(fam.nu2_c))
        t_max = min(650.0, np.log(span / floor)) if fam.nu2_sep != 0 else 650.0

        def orbit(t):
            return _build(fam, alpha, fam.nu2_sep - span * np.exp(-t))

    def f(t):
        return orbit(t).turning - target

    c = fam.c
    theta0 = 2 * np.pi * alpha * c / np.sqrt(-float(well.d2W(c)))
    ts = [1e-6, 1e-3, 0.03, 0.1, 0.3, 1.0]
    while ts[-1] < t_max:
        ts.append(min(2 * ts[-1], t_max))
    prev_t, prev_f, seen, depth = None, None, [], None
    for t in ts:
        orb = orbit(t)
        ft = orb.turning - target
        depth = orb.depth
        seen.append(ft + target)
        if ft == 0:
            return orbit(t)
        if prev_f is not None and np.sign(ft) != np.sign(prev_f):
            root = brentq(f, prev_t, t, xtol=1e-14, rtol=1e-15)
            return orbit(root)
        prev_t, prev_f = t, ft
    lo, hi = min(seen), max(seen)
    cond = ""
    if fam.nu1 == 0.0:
        cond = (
            f" The small-oscillation limit turns by Theta_0 = 2 pi alpha c / sqrt(-W''(c)) = "
            f"{theta0:.6g} (c = {c:.6g}); for an N-pulse, N Theta_0 < 2 pi is needed, i.e. "
            "N alpha < 1 for the quartic well."
        )
    raise ValueError(
        f"no periodic orbit turns by {target:.6g}: the family with alpha={alpha}, "
        f"nu1={fam.nu1} turns by {lo:.6g} ... {hi:.6g} per pulse (followed to plateau "
        f"depth {depth:.1e} from the separatrix).{cond}"
    )
