"""The heteroclinic front of the faceting energy (section "Formal Equilibrium").

The front ``psi_h`` solves ``alpha^2 psi'' = W'(psi)`` on the line (``sigma`` is arc
length, ``' = d/dsigma``; e:Facet-CP with ``nu1 = 0``) and connects the wells,
``psi_h(-inf) = 0``, ``psi_h(+inf) = kstar``; it is centred so that
``psi_h(0) = kstar / 2``. Its first integral ``alpha^2 psi'^2 / 2 = W(psi)``
(e:Fint with ``nu1 = nu2 = 0``) gives ::

    sigma(psi) = int_{kstar/2}^{psi} alpha / sqrt(2 W(p)) dp.

For the quartic ``W = k^2 (k - kstar)^2 / 4`` this is the closed form (Conventions and errata,
section 5) ::

    psi_h(sigma) = kstar / (1 + exp(-kstar sigma / (sqrt(2) alpha))),

with tails ``psi_h ~ exp(lambda_- sigma)``, ``kstar - psi_h ~ exp(-lambda_+ sigma)``
and ``lambda_-+ = sqrt(W''(0 | kstar)) / alpha`` (``= kstar / (sqrt(2) alpha)`` for the
quartic).

For any other well the quadrature is done in the logistic variable
``x = log(psi / (kstar - psi))``: then ``dsigma/dx = alpha psi (kstar - psi) /
(kstar sqrt(2 W(psi)))`` is smooth and tends to the constants ``1/lambda_-+`` at
``x -> -+inf``, so the logarithmic endpoint singularities of ``sigma(psi)``
disappear. ``sigma(x)`` is integrated with composite Gauss-Legendre panels on
``|x| <= X`` and with its first-order tail expansion beyond, and inverted by
Newton's method.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from qsa._checks import real_number
from qsa.energies.wells import is_quartic, resolve_well

if TYPE_CHECKING:
    from qsa.energies.wells import DoubleWell, Well

__all__ = ["Heteroclinic", "heteroclinic"]

# Gauss-Legendre rule used for panels and partial panels.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(20)
# Beyond |x| = _X_TAIL (psi / kstar < 3e-6 from a well) the tail expansion is used.
_X_TAIL = 12.7
_PANEL = 0.5


def _logistic(x, kstar):
    """``psi = kstar / (1 + e^-x)`` and ``z = kstar - psi``, accurate at both tails."""
    x = np.asarray(x)
    neg = x.real < 0
    e = np.exp(np.where(neg, x, -x))  # real part <= 0: no overflow, no cancellation
    p, q = e / (1 + e), 1 / (1 + e)
    return kstar * np.where(neg, p, q), kstar * np.where(neg, q, p)


@dataclass(frozen=True, eq=False)
class Heteroclinic:
    """The front ``psi_h(sigma)`` from the well 0 (``sigma -> -inf``) to ``kstar``.

    Call it like a function of arc length: ``psi_h(sigma)``; complex ``sigma`` is
    accepted (complex-step differentiation) when the well accepts complex input.

    Attributes
    ----------
    alpha, kstar : float
        Parameters of the faceting energy.
    well : object
        The double well (``W``, ``dW``, ``d2W``).
    rates : tuple of float
        ``(lambda_minus, lambda_plus)``: ``psi_h ~ exp(lambda_minus sigma)`` as
        ``sigma -> -inf`` and ``kstar - psi_h ~ exp(-lambda_plus sigma)`` as
        ``sigma -> +inf``; ``lambda = sqrt(W'') / alpha`` at the wells.
    closed_form : bool
        True for the quartic well (exact logistic formula).

    Examples
    --------
    >>> import numpy as np
    >>> h = heteroclinic(0.1, kstar=5.0)
    >>> float(np.round(h(0.0), 12)), h.closed_form  # centred at psi = kstar / 2
    (2.5, True)
    >>> bool(np.isclose(h.width, np.sqrt(2) * 0.1 / 5.0))
    True
    >>> bool(np.isclose(h.tension, 0.1 * 5.0**3 / (6 * np.sqrt(2))))
    True
    """

    alpha: float
    kstar: float
    well: DoubleWell | Well
    rates: tuple
    closed_form: bool
    _tab: dict | None = field(default=None, repr=False)

    # ------------------------------------------------------------ evaluation
    @property
    def decay_rate(self) -> float:
        """The slower of the two tail rates, ``min(rates)``.

        Examples
        --------
        >>> round(float(heteroclinic(0.1, kstar=5.0).decay_rate), 8)  # kstar / (sqrt(2) alpha)
        35.35533906
        """
        return min(self.rates)

    @property
    def width(self) -> float:
        """Front width ``1 / decay_rate`` (``sqrt(2) alpha / kstar`` for the quartic)."""
        return 1.0 / self.decay_rate

    def _x_of_sigma(self, sigma):
        """Logistic variable ``x(sigma)``; shape like ``sigma``."""
        sigma = np.asarray(sigma)
        if self.closed_form:
            return self.rates[0] * sigma
        tab = self._tab
        xr = np.interp(sigma.real, tab["S"], tab["xb"])
        lo, hi = sigma.real < tab["S"][0], sigma.real > tab["S"][-1]
        xr = np.where(lo, tab["xb"][0] + (sigma.real - tab["S"][0]) / tab["G0"], xr)
        xr = np.where(hi, tab["xb"][-1] + (sigma.real - tab["S"][-1]) / tab["G1"], xr)
        x = xr + 0j * sigma if np.iscomplexobj(sigma) else xr
        for _ in range(60):
            dx = (self._sigma_of_x(x) - sigma) / self._G(x)
            x = x - dx
            # converged when the step no longer moves psi (quadrature noise in sigma(x)
            # near the wells limits x itself to ~1e-11, psi to ~1e-16 kstar)
            psi, z = _logistic(x.real, self.kstar)
            if np.all((np.abs(dx) <= 1e-15 * (1 + np.abs(x)))
                      | (np.abs(dx) * psi * z <= 1e-16 * self.kstar**2)):
                break
        return x

    def __call__(self, sigma):
        """``psi_h(sigma)``, shape like ``sigma``."""
        return _logistic(self._x_of_sigma(sigma), self.kstar)[0]

    def complement(self, sigma):
        """``kstar - psi_h(sigma)`` without cancellation (the upper tail); shape like sigma.

        Parameters
        ----------
        sigma : array_like
            Arc length from the front centre (``psi_h(0) = kstar / 2`` for symmetric wells).

        Returns
        -------
        ndarray, shape like ``sigma``

        Examples
        --------
        >>> h = heteroclinic(0.1, kstar=5.0)
        >>> bool(h.complement(2.0) / (5.0 * np.exp(-2.0 * h.decay_rate)) > 0.99)
        True
        """
        return _logistic(self._x_of_sigma(sigma), self.kstar)[1]

    def derivative(self, sigma):
        """``psi_h'(sigma) = psi (kstar - psi) / (kstar dsigma/dx)``, shape like ``sigma``.

        Computed from the quadrature (not from the first integral), so it is an
        independent check of the ODE.

        Parameters
        ----------
        sigma : array_like

        Returns
        -------
        ndarray, shape like ``sigma``

        Examples
        --------
        >>> import numpy as np
        >>> h = heteroclinic(0.1, kstar=5.0)
        >>> s = np.linspace(-0.2, 0.2, 5)
        >>> bool(np.allclose(h.derivative(s), h(s) * h.complement(s) / (np.sqrt(2) * 0.1)))
        True
        """
        x = self._x_of_sigma(sigma)
        psi, z = _logistic(x, self.kstar)
        return psi * z / (self.kstar * self._G(x))

    def second_derivative(self, sigma):
        """``psi_h''(sigma) = W'(psi_h) / alpha^2`` (from the ODE itself).

        Parameters
        ----------
        sigma : array_like

        Returns
        -------
        ndarray, shape like ``sigma``

        Examples
        --------
        >>> import numpy as np
        >>> h, d = heteroclinic(0.1, kstar=5.0), 1e-5
        >>> fd = (h.derivative(0.03 + d) - h.derivative(0.03 - d)) / (2 * d)
        >>> bool(np.isclose(fd, h.second_derivative(0.03), rtol=1e-6))
        True
        """
        return self.well.dW(self(sigma)) / self.alpha**2

    def position(self, psi):
        """Arc length ``sigma`` where ``psi_h(sigma) = psi``, for ``0 < psi < kstar``.

        Parameters
        ----------
        psi : float or array_like
            Values in ``(0, kstar)``.

        Returns
        -------
        float or ndarray, shape like ``psi``

        Examples
        --------
        >>> h = heteroclinic(0.1, kstar=5.0)
        >>> round(float(h(h.position(1.0))), 10)
        1.0
        """
        psi = np.asarray(psi, dtype=float)
        if np.any((psi <= 0) | (psi >= self.kstar)):
            raise ValueError("psi must lie strictly between the wells 0 and kstar")
        x = np.log(psi) - np.log(self.kstar - psi)
        return self._sigma_of_x(x)

    @property
    def tension(self) -> float:
        """Front energy ``int (alpha^2/2 psi'^2 + W) dsigma = int_0^kstar alpha sqrt(2W) dpsi``.

        ``alpha kstar^3 / (6 sqrt 2)`` for the quartic.

        Examples
        --------
        >>> round(float(heteroclinic(0.1, kstar=5.0).tension), 8)  # alpha kstar^3 / (6 sqrt 2)
        1.47313913
        """
        if self.closed_form:
            return self.alpha * self.kstar**3 / (6 * np.sqrt(2))
        p = 0.5 * self.kstar * (1 + np.polynomial.legendre.leggauss(60)[0])
        w = 0.5 * self.kstar * np.polynomial.legendre.leggauss(60)[1]
        return float(self.alpha * w @ np.sqrt(2 * np.asarray(self.well.W(p), dtype=float)))

    # ------------------------------------------------------------ quadrature
    def _G(self, x):
        """``dsigma/dx``; shape like ``x``."""
        if self.closed_form:
            return np.full_like(np.asarray(x), 1.0 / self.rates[0])
        x = np.asarray(x)
        tab = self._tab
        psi, z = _logistic(x, self.kstar)
        xr = x.real
        inner = np.abs(xr) <= _X_TAIL
        with np.errstate(all="ignore"):
            direct = self.alpha * psi * z / (self.kstar * np.sqrt(2 * self.well.W(psi)))
        low = tab["G0"] * (1 + tab["c0"] * psi)
        high = tab["G1"] * (1 + tab["c1"] * z)
        return np.where(inner, direct, np.where(xr < 0, low, high))

    def _sigma_of_x(self, x):
        """``sigma(x)`` with ``sigma(0) = 0``; shape like ``x``."""
        x = np.asarray(x)
        if self.closed_form:
            return x / self.rates[0]
        tab = self._tab
        k, xb, S = self.kstar, tab["xb"], tab["S"]
        xr = x.real
        # inner part: panel start + partial Gauss-Legendre panel
        xc = np.clip(xr, xb[0], xb[-1])
        j = np.clip(np.searchsorted(xb, xc, side="right") - 1, 0, len(xb) - 2)
        x_in = np.where(np.abs(xr) <= _X_TAIL, x, xc)
        half = 0.5 * (x_in - xb[j])
        nodes = xb[j][..., None] + half[..., None] * (1 + _GL_X)
        inner = S[j] + half * (self._G(nodes) @ _GL_W)
        X = _X_TAIL
        lower = S[0] - tab["G0"] * ((-X - x) + tab["c0"] * k * (np.log1p(np.exp(-X))
                                                               - np.log1p(np.exp(x))))
        upper = S[-1] + tab["G1"] * ((x - X) + tab["c1"] * k * (np.log1p(np.exp(-X))
                                                               - np.log1p(np.exp(-x))))
        return np.where(xr < -X, lower, np.where(xr > X, upper, inner))


def _tail_coefficients(well, k0, kstar, alpha, sign):
    """``(G_inf, c)`` with ``dsigma/dx ~ G_inf (1 + c d)``, d = distance to the well k0."""
    W2 = float(well.d2W(k0))
    step = 1e-4 * kstar
    W3 = float(well.d2W(k0 + step) - well.d2W(k0 - step)) / (2 * step)
    return alpha / np.sqrt(W2), -1.0 / kstar - sign * W3 / (6 * W2)


def heteroclinic(alpha, well=None, kstar=None) -> Heteroclinic:
    """The front ``psi_h`` of ``alpha^2 psi'' = W'(psi)`` from 0 to ``kstar``.

    Parameters
    ----------
    alpha : float
        ``> 0``, the surface-diffusion length of the faceting energy.
    well : object, optional
        Double well with vectorised ``W``, ``dW``, ``d2W`` and equal-depth minima
        ``W(0) = W(kstar) = 0``; default the quartic ``k^2 (k - kstar)^2 / 4``.
    kstar : float, optional
        Second well; defaults to ``well.kstar`` or 5.0.

    Returns
    -------
    Heteroclinic
        Callable ``psi_h(sigma)`` centred at ``psi_h(0) = kstar / 2``, with
        ``.derivative``, ``.rates`` (tail decay rates), ``.width``, ``.tension``.

    Notes
    -----
    Section "Formal Equilibrium and Quasi-Steady Analysis", e:Facet-CP and
    e:Fint with ``nu1 = nu2 = 0``; closed form from Conventions and errata, section 5.

    Examples
    --------
    >>> import numpy as np
    >>> psi = heteroclinic(0.1, kstar=5.0)
    >>> float(psi(0.0)), bool(np.isclose(psi.rates[0], 5 / (np.sqrt(2) * 0.1)))
    (2.5, True)
    """
    alpha = real_number(alpha, "alpha", positive=True)
    well, kstar = resolve_well(well, kstar)
    lam0 = np.sqrt(float(well.d2W(0.0))) / alpha
    lam1 = np.sqrt(float(well.d2W(kstar))) / alpha
    if is_quartic(well, kstar):
        return Heteroclinic(alpha, kstar, well, (lam0, lam1), True)
    G0, c0 = _tail_coefficients(well, 0.0, kstar, alpha, +1)
    G1, c1 = _tail_coefficients(well, kstar, kstar, alpha, -1)
    n = 2 * int(np.ceil(_X_TAIL / _PANEL))
    xb = np.linspace(-_X_TAIL, _X_TAIL, n + 1)
    tab = {"xb": xb, "G0": G0, "c0": c0, "G1": G1, "c1": c1, "S": None}
    h = Heteroclinic(alpha, kstar, well, (lam0, lam1), False, tab)
    half = 0.5 * np.diff(xb)
    nodes = xb[:-1, None] + half[:, None] * (1 + _GL_X)
    pieces = half * (h._G(nodes) @ _GL_W)
    S = np.concatenate([[0.0], np.cumsum(pieces)])
    S -= S[n // 2]  # sigma(0) = 0: psi_h(0) = kstar / 2
    tab["S"] = S
    if not np.all(np.isfinite(S)) or not np.all(pieces > 0):
        raise ValueError("well: the front quadrature failed (is W positive between the wells?)")
    return h
