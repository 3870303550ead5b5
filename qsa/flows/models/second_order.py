"""The gradient flow of any local energy (e:LIE) with a perimeter penalty, as a compact DAE.

``SecondOrderFlow(energy)`` evolves a closed curve by ``V^n = -G mu - kappa xi``
(e:L2grad, e:LIE_NV) for ``energy`` = local energies (``SecondOrderEnergy``,
``FunctionalizedCurvature``, ``Faceting``, ``CanhamHelfrich`` ...) plus perimeter
penalties ``Perimeter(beta, L*)``. See :mod:`qsa.flows.dae` for the shared geometric
rows and sign conventions.

Unknowns and rows
-----------------
Per node ``(x, y, kappa, mu, mss, V)`` plus the length ``L`` (``6N + 1``, the layout of
:class:`~qsa.flows.models.faceting.FacetingSystem`). In scaled arc length the metric is
``g = L`` at every node, so the energy is a function ``E(kappa, L)`` of the curvature
unknowns alone: the discrete energy of the local terms on ``FiniteDifference(N)`` at
``Curve(kappa, g = L)`` (:mod:`qsa.energies.second_order`, :mod:`qsa.energies.local`),
plus ``sum beta/2 (L - L*)^2``. With its exact Euclidean gradient ``(E_kappa, E_g)`` and
node weights ``w = 1/N`` the model rows are

    mu  - E_kappa / (w L)                                   = 0      (N)
    mss - D2 mu / L^2                                       = 0      (N)
    V   - (mss + kappa^2 mu - kappa xi),  xi = E_g / w + sum beta (L - L*)   (N)

``mu = d_kappa E`` and ``xi = g d_g E`` are the ``<f, h> = int f h dsigma`` gradient
(e:first_var), and ``mss = Delta_s mu`` with the compact Laplacian: ``V`` is exactly the
energy's own discrete ``V^n`` on that grid (``energy.normal_velocity``). For
``Faceting + Perimeter`` the rows are those of ``FacetingFlow``, to rounding.

Jacobian
--------
Exact, from the energy's Euclidean Hessian ``H`` (second partials of the density only,
never third): with ``1`` the vector of ones (``g_j = L`` for every ``j``, so
``d/dL = sum_j d/dg_j``),

    d mu_E / d kappa = H_kk / (w L),   d mu_E / dL = H_kg 1 / (w L) - mu_E / L,
    d xi / d kappa   = H_gk / w,       d xi / dL   = H_gg 1 / w + sum beta.

On finite differences ``H`` is banded (bandwidth 2 in each block for second-order
densities), so every row has a compact stencil and the Newton matrix has O(N) nonzeros.
A second-order density makes ``V`` of order 6 in ``kappa``: the DAE is stiff and needs
the implicit steppers of :func:`qsa.flows.solve_flow`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from qsa.curve import Curve
from qsa.discretize import FiniteDifference
from qsa.energies.base import Energy, Perimeter
from qsa.energies.faceting import Faceting
from qsa.energies.local import LocalEnergy
from qsa.flows.base import FlowModel
from qsa.flows.models.curve_dae import CurveDAE, _check_xy, equalize_chords
from qsa.flows.models.faceting import FacetingFlow

__all__ = ["SecondOrderFlow", "SecondOrderSystem", "flow_model"]


def _split(energy):
    """``(local terms, perimeter terms)`` of ``energy``; ``ValueError`` for anything else."""
    if not isinstance(energy, Energy):
        raise ValueError(f"energy must be a qsa Energy (local energies plus Perimeter terms), "
                         f"got {type(energy).__name__}")
    local, perimeters = [], []
    for t in energy.terms():
        if isinstance(t, LocalEnergy):
            local.append(t)
        elif isinstance(t, Perimeter):
            perimeters.append(t)
        else:
            raise ValueError(f"energy: SecondOrderFlow takes local energies and Perimeter "
                             f"terms only, got {type(t).__name__} (use the CHA model for "
                             f"adhesion)")
    if not local:
        raise ValueError("energy must contain a local energy (e.g. FunctionalizedCurvature)")
    return tuple(local), tuple(perimeters)


class SecondOrderSystem(CurveDAE):
    """The DAE of :class:`SecondOrderFlow` bound to initial positions (module docstring)."""

    fields = ("x", "y", "kappa", "mu", "mss", "V")

    def __init__(self, model, x, y):
        super().__init__(x, y)
        self.model = model
        self.grid = FiniteDifference(self.N)
        self.w = 1.0 / self.N
        self._local, self._perimeters = _split(model.energy)
        x, y, L = equalize_chords(x, y)
        kappa = self.geometric_curvature(x, y, L)
        mu, _ = self._gradient(kappa, L)
        mss = self._d2(mu) / L**2
        y0 = np.concatenate([x, y, kappa, mu, mss, np.zeros(self.N), [L]])
        o = self.offset["V"]
        y0[o : o + self.N] = self._velocity(y0)
        self.y0 = y0

    # ------------------------------------------------------------ energy
    def _curve(self, kappa, L):
        """``Curve(kappa, g = L)`` on ``FiniteDifference(N)``, or None for a diverged iterate."""
        if not (np.isfinite(L) and L > 0 and np.all(np.isfinite(kappa))):
            return None
        return Curve(kappa, L, self.grid)

    def _gradient(self, kappa, L):
        """``(mu_E, xi)``: ``d_kappa E`` and ``g d_g E`` (perimeters included), each (N,)."""
        c = self._curve(kappa, L)
        if c is None:
            nan = np.full(self.N, np.nan)
            return nan, nan
        G = sum(t.euclidean_gradient(c) for t in self._local)
        N = self.N
        mu = G[:N] / (self.w * L)
        xi = G[N:] / self.w + sum(p.beta * (L - p.L_star) for p in self._perimeters)
        return mu, xi

    def _velocity(self, y):
        """``V = mss + kappa^2 mu - kappa xi`` (e:L2grad) from the unknowns ``mss, mu``."""
        u = self.unpack(y)
        _, xi = self._gradient(u["kappa"], u["L"])
        return u["mss"] + u["kappa"] ** 2 * u["mu"] - u["kappa"] * xi

    def energy(self, y):
        """The local terms' discrete energy at ``Curve(kappa, L)`` + ``sum beta/2 (L - L*)^2``."""
        u = self.unpack(y)
        c = self._curve(u["kappa"], u["L"])
        if c is None:
            return float("nan")
        bulk = sum(t.energy(c) for t in self._local)
        return float(bulk + sum(0.5 * p.beta * (u["L"] - p.L_star) ** 2
                                for p in self._perimeters))

    # ------------------------------------------------------------- rows
    def _model_residual(self, y, tx, ty):
        N = self.N
        u = self.unpack(y)
        kappa, mu, L = u["kappa"], u["mu"], u["L"]
        mu_E, xi = self._gradient(kappa, L)
        F = np.empty(3 * N)
        F[:N] = mu - mu_E
        F[N : 2 * N] = u["mss"] - self._d2(mu) / L**2
        F[2 * N :] = u["V"] - (u["mss"] + kappa**2 * mu - kappa * xi)
        return F

    def _model_jacobian(self, T, y, tx, ty, TN=None):
        N, h, w = self.N, self.h, self.w
        j, jp, jm = self._j, self._jp, self._jm
        u = self.unpack(y)
        kappa, mu, L = u["kappa"], u["mu"], u["L"]
        iK, iM, iS, iV, iL = 2 * N + j, 3 * N + j, 4 * N + j, 5 * N + j, self.iL
        c = self._curve(kappa, L)
        if c is None:  # a diverged iterate: a non-finite matrix, as the residual
            T.add(3 * N + j, iK, np.full(N, np.nan))
            return
        G = sum(t.euclidean_gradient(c) for t in self._local)
        H = sum(t.euclidean_hessian(c) for t in self._local).tocsr()
        mu_E = G[:N] / (w * L)
        xi = G[N:] / w + sum(p.beta * (L - p.L_star) for p in self._perimeters)
        ones = np.ones(N)
        Hkk, Hkg, Hgk, Hgg = H[:N, :N], H[:N, N:], H[N:, :N], H[N:, N:]
        dmu_dL = (Hkg @ ones) / (w * L) - mu_E / L
        dxi_dL = (Hgg @ ones) / w + sum(p.beta for p in self._perimeters)
        # mu - mu_E(kappa, L)
        r = 3 * N
        T.add(r + j, iM, 1.0)
        _add_block(T, r, 2 * N, Hkk, -1.0 / (w * L))
        T.add(r + j, iL, -dmu_dL)
        # mss - D2 mu / L^2
        r = 4 * N + j
        s2 = 1.0 / (h * L) ** 2
        T.add(r, iS, 1.0)
        T.add(r, iM[jp], -s2)
        T.add(r, iM[jm], -s2)
        T.add(r, iM, 2 * s2)
        T.add(r, iL, 2 * self._d2(mu) / L**3)
        # V - mss - kappa^2 mu + kappa xi(kappa, L)
        r = 5 * N
        T.add(r + j, iV, 1.0)
        T.add(r + j, iS, -1.0)
        T.add(r + j, iM, -(kappa**2))
        T.add(r + j, iK, -2 * kappa * mu + xi)
        _add_block(T, r, 2 * N, Hgk, kappa / w)
        T.add(r + j, iL, kappa * dxi_dL)

    def metadata(self):
        return {
            "model": "SecondOrderFlow",
            "N": int(self.N),
            "energy": self.model.energy.params(),
            "energy_repr": repr(self.model.energy),
            "unknowns": list(self.fields) + ["L"],
        }


def _add_block(T, row0, col0, B, scale):
    """Add ``diag(scale) B`` (a sparse ``N x N`` block; ``scale`` scalar or per row)."""
    B = B.tocoo()
    s = scale if np.ndim(scale) == 0 else np.asarray(scale)[B.row]
    T.add(row0 + B.row, col0 + B.col, B.data * s)


@dataclass(frozen=True)
class SecondOrderFlow(FlowModel):
    """The ``L^2(dsigma)`` gradient flow of a local energy with perimeter penalties (e:LIE_NV).

    Outward normal velocity (e:L2grad)::

        V = -G mu - kappa xi,   G = -Delta_s - kappa^2,
        mu = d_kappa E = Delta_s F_q - nabla_s F_p + F_k,
        xi = g d_g E = F - F_q Delta_s kappa + nabla_s F_q nabla_s kappa - F_p nabla_s kappa
                       + sum beta (L - L*)

    for ``E = int F(Delta_s kappa, nabla_s kappa, kappa) dsigma + sum beta/2 (L - L*)^2``
    (e:first_var). The DAE, its unknowns and its exact Jacobian are described in the
    module docstring; its discrete energy and ``V`` are the energy's own on
    ``FiniteDifference(N)`` at constant ``g = L``, so its equilibria are those that
    :func:`qsa.equilibria.polish` finds on that grid.

    Parameters
    ----------
    energy : Energy
        Local energies (:class:`~qsa.energies.SecondOrderEnergy`,
        :class:`~qsa.energies.FunctionalizedCurvature`, :class:`~qsa.energies.Faceting`,
        :class:`~qsa.energies.CanhamHelfrich`, ...) plus any number of
        :class:`~qsa.energies.Perimeter` terms, e.g.
        ``FunctionalizedCurvature(0.2, 1.0, 5.0) + Perimeter(5.0, 6.0)``.

    Raises
    ------
    ValueError
        ``energy`` is not an Energy, has no local term, or has a term that is neither
        local nor a perimeter (e.g. adhesion: use :class:`~qsa.flows.CHA`).

    Examples
    --------
    A perturbed circle under the functionalized energy relaxes (the circle of radius
    ``1/kstar`` is critical and stable here):

    >>> import numpy as np
    >>> from qsa.energies import FunctionalizedCurvature, Perimeter
    >>> from qsa.flows import SecondOrderFlow, solve_flow
    >>> E = FunctionalizedCurvature(alpha=0.2, eta=0.5, kstar=1.0)
    >>> model = SecondOrderFlow(E + Perimeter(1.0, 2 * np.pi))
    >>> th = 2 * np.pi * np.arange(200) / 200
    >>> r = 1 + 0.05 * np.cos(3 * th)
    >>> res = solve_flow(model, (r * np.cos(th), r * np.sin(th)), 0.5, N=48, tol=1e-4)
    >>> res.success, bool(np.all(np.diff(res.energy_steps) <= 0))
    (True, True)
    """

    energy: object
    name: str = field(default="SecondOrderFlow", init=False)

    def __post_init__(self):
        _split(self.energy)  # ValueError for an energy the model cannot evolve

    def check_resolution(self, x, y):
        """Raise ``ValueError`` for NaN, too few nodes or a clockwise curve."""
        _check_xy(x, y, self.min_nodes())

    def setup(self, x, y):
        """Bind to initial positions (projected to equal chords)."""
        self.check_resolution(x, y)
        return SecondOrderSystem(self, np.asarray(x, float), np.asarray(y, float))


def flow_model(energy) -> FlowModel:
    """The DAE flow model of ``energy``: ``FacetingFlow`` or ``SecondOrderFlow``.

    ``Faceting + Perimeter`` (exactly one of each) gives the paper's hand-coded
    :class:`~qsa.flows.FacetingFlow` (same rows as ``SecondOrderFlow`` of that energy,
    to rounding, and several times cheaper); any other sum of local energies and
    perimeters gives :class:`SecondOrderFlow` ``(energy)``.

    Parameters
    ----------
    energy : Energy

    Returns
    -------
    FlowModel

    Raises
    ------
    ValueError
        For an energy neither model evolves (see :class:`SecondOrderFlow`).

    Examples
    --------
    >>> from qsa.energies import Faceting, FunctionalizedCurvature, Perimeter
    >>> type(flow_model(Faceting(0.1, 5.0) + Perimeter(5.0, 6.0))).__name__
    'FacetingFlow'
    >>> type(flow_model(FunctionalizedCurvature(0.1, 1.0, 5.0) + Perimeter(5.0, 6.0))).__name__
    'SecondOrderFlow'
    """
    local, perimeters = _split(energy)
    if len(local) == 1 and type(local[0]) is Faceting and len(perimeters) == 1:
        f, p = local[0], perimeters[0]
        return FacetingFlow(alpha=f.alpha, kstar=f.kstar, beta=p.beta, L_star=p.L_star,
                            well=f.well)
    return SecondOrderFlow(energy)
