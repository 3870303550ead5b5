"""The faceting DAE (e:Facet-NV) with local auxiliary unknowns mu and Delta_s mu.

See :mod:`qsa.flows.dae` for the shared rows and sign conventions.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsa._checks import real_number
from qsa.energies.wells import resolve_well
from qsa.flows.base import FlowModel
from qsa.flows.models.curve_dae import CurveDAE, _check_xy, equalize_chords

__all__ = ["FacetingFlow", "FacetingSystem"]


class FacetingSystem(CurveDAE):
    """The faceting DAE bound to initial positions (see :class:`FacetingFlow`)."""

    fields = ("x", "y", "kappa", "mu", "mss", "V")

    def __init__(self, model, x, y, constraints=()):
        super().__init__(x, y, constraints)
        self.model = model
        self.well, _ = resolve_well(model.well, model.kstar, equal_depth=False)
        x, y, L = equalize_chords(x, y)
        kappa = self.geometric_curvature(x, y, L)
        mu = -(model.alpha**2) * self._d2(kappa) / L**2 + self.well.dW(kappa)
        mss = self._d2(mu) / L**2
        y0 = self._stack(x, y, kappa, mu, mss, np.zeros(self.N), L=L)
        o = self.offset["V"]
        y0[o : o + self.N] = self._velocity(y0)
        self.y0 = self._finish_setup(y0)

    def _edges(self, kappa, L):
        """Edge slopes and their nodal mean square.

        ``e_{j+1/2} = (kappa_{j+1} - kappa_j)/(h L)`` and
        ``q_j = (e_{j-1/2}^2 + e_{j+1/2}^2)/2`` (the nodal ``|grad_s kappa|^2``).
        """
        e = (kappa[self._jp] - kappa) / (self.h * L)
        return e, 0.5 * (e * e + e[self._jm] ** 2)

    def _velocity(self, y):
        """e:Facet-NV: ``V = Delta_s mu + kappa^2 mu - kappa (-alpha^2 q/2 + W + beta (L-L*))``."""
        m = self.model
        u = self.unpack(y)
        kappa, L = u["kappa"], u["L"]
        _, q = self._edges(kappa, L)
        gE = -0.5 * m.alpha**2 * q + self.well.W(kappa) + m.beta * (L - m.L_star)
        return u["mss"] + kappa**2 * u["mu"] - kappa * gE

    def _model_residual(self, y, tx, ty):
        m, N = self.model, self.N
        u = self.unpack(y)
        kappa, mu, L = u["kappa"], u["mu"], u["L"]
        F = np.empty(3 * N)
        F[:N] = mu + m.alpha**2 * self._d2(kappa) / L**2 - self.well.dW(kappa)
        F[N : 2 * N] = u["mss"] - self._d2(mu) / L**2
        F[2 * N :] = u["V"] - self._velocity(y)
        return F

    def _model_jacobian(self, T, y, tx, ty, TN=None):
        m, N, h = self.model, self.N, self.h
        j, jp, jm = self._j, self._jp, self._jm
        u = self.unpack(y)
        kappa, mu, L = u["kappa"], u["mu"], u["L"]
        a2 = m.alpha**2
        iK, iM, iS, iV, iL = 2 * N + j, 3 * N + j, 4 * N + j, 5 * N + j, self.iL
        s2 = 1.0 / (h * L) ** 2
        # mu + alpha^2 D2 kappa / L^2 - W'(kappa)
        r = 3 * N + j
        T.add(r, iM, 1.0)
        T.add(r, iK[jp], a2 * s2)
        T.add(r, iK[jm], a2 * s2)
        T.add(r, iK, -2 * a2 * s2 - self.well.d2W(kappa))
        T.add(r, iL, -2 * a2 * self._d2(kappa) / L**3)
        # mss - D2 mu / L^2
        r = 4 * N + j
        T.add(r, iS, 1.0)
        T.add(r, iM[jp], -s2)
        T.add(r, iM[jm], -s2)
        T.add(r, iM, 2 * s2)
        T.add(r, iL, 2 * self._d2(mu) / L**3)
        # V - mss - kappa^2 mu + kappa (-alpha^2/2 q + W + beta (L - L*))
        r = 5 * N + j
        e, q = self._edges(kappa, L)
        em = e[jm]
        gE = -0.5 * a2 * q + self.well.W(kappa) + m.beta * (L - m.L_star)
        hl = h * L
        T.add(r, iV, 1.0)
        T.add(r, iS, -1.0)
        T.add(r, iM, -(kappa**2))
        T.add(r, iK, -2 * kappa * mu + gE + kappa * self.well.dW(kappa)
              - 0.5 * a2 * kappa * (em - e) / hl)
        T.add(r, iK[jp], -0.5 * a2 * kappa * e / hl)
        T.add(r, iK[jm], 0.5 * a2 * kappa * em / hl)
        T.add(r, iL, kappa * (a2 * q / L + m.beta))

    def energy(self, y):
        """``E = sum_j w (alpha^2/2 e_{j+1/2}^2 + W(kappa_j)) + beta/2 (L - L*)^2``, ``w = L/N``."""
        m = self.model
        u = self.unpack(y)
        L = u["L"]
        e, _ = self._edges(u["kappa"], L)
        bulk = np.sum(0.5 * m.alpha**2 * e * e + self.well.W(u["kappa"])) * L / self.N
        return float(bulk + 0.5 * m.beta * (L - m.L_star) ** 2)

    def metadata(self):
        m = self.model
        return {
            "model": "FacetingFlow",
            "N": int(self.N),
            "alpha": m.alpha,
            "kstar": m.kstar,
            "beta": m.beta,
            "L_star": m.L_star,
            "well": repr(self.well),
            "unknowns": list(self.fields) + ["L"],
            **self._constraint_metadata(),
        }


@dataclass(frozen=True)
class FacetingFlow(FlowModel):
    """The faceting gradient flow (e:Facet-NV).

    Energy::

        E = int alpha^2/2 |grad_s kappa|^2 + W(kappa) dsigma + beta/2 (L - L*)^2.

    Outward normal velocity (Conventions and errata, section 3, e:Facet-NV)::

        V = -G(mu) - kappa (g d_g E),   G = -Delta_s - kappa^2,
        mu = -alpha^2 Delta_s kappa + W'(kappa),
        g d_g E = -alpha^2/2 |grad_s kappa|^2 + W(kappa) + beta (L - L*).

    Parameters
    ----------
    alpha : float
        Front width, ``alpha > 0``.
    kstar : float
        Second well of the default :class:`qsa.energies.DoubleWell`
        ``W = k^2 (k - kstar)^2 / 4``, ``kstar > 0``.
    beta : float
        Length-penalty strength, ``beta >= 0``.
    L_star : float
        Preferred length, ``L_star > 0``.
    well : object, optional
        A well with callables ``W(k)``, ``dW(k)``, ``d2W(k)`` (vectorised), e.g.
        :class:`qsa.energies.Well`; default ``DoubleWell(kstar)``.
    """

    alpha: float
    kstar: float
    beta: float
    L_star: float
    well: object = None
    name: str = field(default="FacetingFlow", init=False)

    def __post_init__(self):
        object.__setattr__(self, "alpha", real_number(self.alpha, "alpha", positive=True))
        object.__setattr__(self, "kstar", real_number(self.kstar, "kstar", positive=True))
        object.__setattr__(self, "beta", real_number(self.beta, "beta", nonnegative=True))
        object.__setattr__(self, "L_star", real_number(self.L_star, "L_star", positive=True))
        resolve_well(self.well, self.kstar, equal_depth=False)  # ValueError: incomplete well

    def check_resolution(self, x, y):
        """Raise ``ValueError`` for NaN, too few nodes or a clockwise curve."""
        _check_xy(x, y, self.min_nodes())

    def setup(self, x, y, *, constraints=None):
        """Bind to initial positions (projected to equal chords).

        Parameters
        ----------
        x, y : array_like, shape (N,)
        constraints : sequence of Constraint, optional
            ``FixedLength()`` / ``FixedArea()``: a length- or area-preserving flow
            (:mod:`qsa.flows.models.constrained`); ``None`` targets are the initial values.
        """
        self.check_resolution(x, y)
        return FacetingSystem(self, np.asarray(x, float), np.asarray(y, float),
                              constraints=constraints)
