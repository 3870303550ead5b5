"""The Canham-Helfrich adhesion-repulsion DAE (e:CHA-Energy, e:CHA-GF).

See :mod:`qsa.flows.dae` for the shared rows and sign conventions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from qsa._checks import real_number
from qsa.energies.adhesion import (
    AdhesionKernel,
    adhesion_energy,
    adhesion_pair_derivatives,
    dense_pairs,
    pair_list,
    uniform_weight_fields,
)
from qsa.flows.base import FlowModel
from qsa.flows.models.curve_dae import CurveDAE, _check_xy, equalize_chords

__all__ = ["CHA", "CHASystem"]


class CHASystem(CurveDAE):
    """The CHA DAE bound to initial positions (see :class:`CHA`)."""

    fields = ("x", "y", "kappa", "kss", "V")

    def __init__(self, model, x, y, *, adhesion_method="neighbours", L0=None, constraints=()):
        super().__init__(x, y, constraints)
        self.model = model
        self.kernel = model.kernel
        #: neighbour-list radius (``None`` without adhesion or on the dense path)
        self.cutoff = (self.kernel.cutoff_distance()
                       if self.kernel is not None and adhesion_method == "neighbours" else None)
        self.adhesion_method = adhesion_method
        x, y, L = equalize_chords(x, y)
        #: reference length of the penalty ``beta/2 (L - rho L0)^2``
        self.L0 = L if L0 is None else real_number(L0, "L0", positive=True)
        kappa = self.geometric_curvature(x, y, L)
        kss = self._d2(kappa) / L**2
        y0 = self._stack(x, y, kappa, kss, np.zeros(self.N), L=L)
        o = self.offset["V"]
        y0[o : o + self.N] = self._velocity(y0, *self._geometry(x, y)[:2])
        self.y0 = self._finish_setup(y0)

    def _adhesion(self, X, Y, L):
        """Pairs, ``B`` and the force at weights ``w = L/N`` (or zeros without adhesion)."""
        if self.kernel is None:
            return None, np.zeros(self.N), np.zeros((self.N, 2))
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y)) and np.isfinite(L)):
            # a diverged Newton iterate: a non-finite residual, not an exception
            nan = np.full(self.N, np.nan)
            return None, nan, np.column_stack([nan, nan])
        if self.cutoff is None:
            pairs = dense_pairs(self.N)
        else:
            pairs = pair_list(X, Y, self.cutoff)
        B, force = uniform_weight_fields(self.kernel, X, Y, L / self.N, *pairs)
        return pairs, B, force

    def adhesion_fields(self, y):
        """``(B, force)`` at state ``y`` (zeros when ``A0 = 0``)."""
        X, Y = self.positions(y)
        return self._adhesion(X, Y, self.length(y))[1:]

    def _velocity(self, y, tx, ty):
        m = self.model
        u = self.unpack(y)
        kappa, kss, L = u["kappa"], u["kss"], u["L"]
        _, B, force = self._adhesion(u["x"], u["y"], L)
        An = (force[:, 0] * ty - force[:, 1] * tx) / self._normal_scale(tx, ty, L)
        return m.eps * (kss + 0.5 * kappa**3) - (B + m.beta * (L - m.rho * self.L0)) * kappa - An

    def _normal_scale(self, tx, ty, L):
        """``|t|`` (unit normal) or ``L`` (the paper code's centred normal ``t^- / L``)."""
        return np.hypot(tx, ty) if self.model.force_normal == "unit" else L

    def _model_residual(self, y, tx, ty):
        N = self.N
        u = self.unpack(y)
        F = np.empty(2 * N)
        F[:N] = u["kss"] - self._d2(u["kappa"]) / u["L"] ** 2
        F[N:] = u["V"] - self._velocity(y, tx, ty)
        return F

    def _model_jacobian(self, T, y, tx, ty, TN=None):
        m, N, h = self.model, self.N, self.h
        j, jp, jm = self._j, self._jp, self._jm
        u = self.unpack(y)
        X, Y, kappa, L = u["x"], u["y"], u["kappa"], u["L"]
        iX, iY, iK, iS, iV, iL = j, N + j, 2 * N + j, 3 * N + j, 4 * N + j, self.iL
        # kss - D2 kappa / L^2
        r = 3 * N + j
        T.add(r, iS, 1.0)
        T.add(r, iK[jp], -1.0 / (h * L) ** 2)
        T.add(r, iK[jm], -1.0 / (h * L) ** 2)
        T.add(r, iK, 2.0 / (h * L) ** 2)
        T.add(r, iL, 2.0 * self._d2(kappa) / L**3)
        # V - eps (kss + kappa^3/2) + (B + beta (L - rho L0)) kappa + force . n
        r = 4 * N + j
        pairs, B, force = self._adhesion(X, Y, L)
        tn = np.hypot(tx, ty)
        if m.force_normal == "unit":
            nx, ny = ty / tn, -tx / tn
            An = force[:, 0] * nx + force[:, 1] * ny
            At = (force[:, 0] * tx + force[:, 1] * ty) / tn
            # d(force . n)/dt = -(force . t^) n / |t|, t = D1 X; force is linear in L
            gx, gy = -At * nx / tn, -At * ny / tn
            dAn_dL = An / L
        else:  # n = t^- / L: force . n does not depend on L (force ~ L/N)
            nx, ny = ty / L, -tx / L
            gx, gy = -force[:, 1] / L, force[:, 0] / L
            dAn_dL = 0.0
        T.add(r, iV, 1.0)
        T.add(r, iS, -m.eps)
        T.add(r, iK, -1.5 * m.eps * kappa**2 + B + m.beta * (L - m.rho * self.L0))
        T.add(r, iL, m.beta * kappa + kappa * B / L + dAn_dL)
        T.add(r, iX[jp], gx / (2 * h))
        T.add(r, iX[jm], -gx / (2 * h))
        T.add(r, iY[jp], gy / (2 * h))
        T.add(r, iY[jm], -gy / (2 * h))
        if pairs is not None:
            # kappa_p dB_p/dX_q + n_p^T dforce_p/dX_q, from per-pair terms (see
            # adhesion_pair_derivatives): -4 w (kappa_p A' d_pq + H n_p), d_qp = -d_pq
            t = adhesion_pair_derivatives(self.kernel, X, Y, pairs=pairs)
            c4 = -4.0 * L / N
            i, k = t.i, t.j
            vals = (
                c4 * (kappa[i] * t.dA * t.dx + nx[i] * t.hxx + ny[i] * t.hxy),
                c4 * (kappa[i] * t.dA * t.dy + nx[i] * t.hxy + ny[i] * t.hyy),
                c4 * (-kappa[k] * t.dA * t.dx + nx[k] * t.hxx + ny[k] * t.hxy),
                c4 * (-kappa[k] * t.dA * t.dy + nx[k] * t.hxy + ny[k] * t.hyy),
            )
            if TN is None:
                parts = [(T, slice(None))]
            else:  # index neighbours (|i - k| = 1 mod N) stay with the local stencil
                gap = k - i
                near = (gap == 1) | (gap == N - 1)
                parts = [(T, near), (TN, ~near)]
            for Tp, sel in parts:
                ii, kk = i[sel], k[sel]
                Tp.add(4 * N + ii, kk, vals[0][sel])
                Tp.add(4 * N + ii, N + kk, vals[1][sel])
                Tp.add(4 * N + kk, ii, vals[2][sel])
                Tp.add(4 * N + kk, N + ii, vals[3][sel])
            # diagonal: kappa_p force_p + n_p^T (4 w sum_q H_pq)
            Sxx = np.bincount(i, t.hxx, N) + np.bincount(k, t.hxx, N)
            Sxy = np.bincount(i, t.hxy, N) + np.bincount(k, t.hxy, N)
            Syy = np.bincount(i, t.hyy, N) + np.bincount(k, t.hyy, N)
            T.add(r, iX, kappa * force[:, 0] - c4 * (nx * Sxx + ny * Sxy))
            T.add(r, iY, kappa * force[:, 1] - c4 * (nx * Sxy + ny * Syy))

    def energy(self, y):
        """``E = eps/2 sum kappa^2 w + beta/2 (L - rho L0)^2 + E_A``, ``w = L/N`` (e:CHA-Energy)."""
        m = self.model
        u = self.unpack(y)
        L = u["L"]
        w = L / self.N
        E = 0.5 * m.eps * np.sum(u["kappa"] ** 2) * w + 0.5 * m.beta * (L - m.rho * self.L0) ** 2
        if self.kernel is not None:
            E += adhesion_energy(
                self.kernel, u["x"], u["y"], w, method=self.adhesion_method
            )
        return float(E)

    def normal_velocity(self, y):
        return self.unpack(y)["V"].copy()

    def bound_constants(self):
        return {"L0": float(self.L0), **super().bound_constants()}

    def metadata(self):
        m = self.model
        return {
            "model": "CHA",
            "N": int(self.N),
            "eps": m.eps,
            "beta": m.beta,
            "rho": m.rho,
            "A0": m.A0,
            "l_star": m.l_star,
            "a": m.a,
            "L0": float(self.L0),
            "adhesion_method": self.adhesion_method,
            "force_normal": m.force_normal,
            "unknowns": list(self.fields) + ["L"],
            **self._constraint_metadata(),
        }


@dataclass(frozen=True)
class CHA(FlowModel):
    """Canham-Helfrich + length penalty + adhesion-repulsion flow (e:CHA-Energy, e:CHA-GF).

    Energy (``L0`` = initial length, bound by :meth:`setup`)::

        E = eps/2 int kappa^2 dsigma + beta/2 (L - rho L0)^2 + E_A,

    outward normal velocity (Conventions and errata, section 3)::

        V = eps (Delta_s kappa + kappa^3/2) - (B + beta (L - rho L0)) kappa - force . n.

    Parameters
    ----------
    eps : float
        Bending rigidity, ``eps >= 0``.
    beta : float
        Length-penalty strength (the sigma of e:CHA-GF), ``beta >= 0``.
    rho : float
        Precompression factor, ``rho > 0``.
    A0, l_star, a : float
        Kernel e:LJ; ``A0 = 0`` switches adhesion off (then ``l_star, a`` are
        ignored).
    adhesion_method : {"neighbours", "dense"}
        Cutoff neighbour list (default, O(N) for short kernels) or all pairs
        (exact, for validation).
    force_normal : {"unit", "centred"}
        Normal used for the adhesion force ``force . n``: the unit normal
        ``t^- / |t|`` (default) or, as in the code behind the paper's
        convergence study, the centred-difference vector ``t^- / L``
        (``|t| / L = 1 - O(h^2)``). Both are second order; they differ in the
        error constant: the paper's Table ap:t1 differences are reproduced
        with ``"centred"`` (``qsa reproduce convergence``).

    Examples
    --------
    >>> import numpy as np
    >>> th = 2 * np.pi * np.arange(64) / 64
    >>> sys = CHA(eps=0.1, beta=1.0, rho=1.5, A0=10.0, l_star=0.5, a=1.0).setup(
    ...     np.cos(th), np.sin(th))
    >>> sys.size
    321
    """

    eps: float
    beta: float
    rho: float
    A0: float = 0.0
    l_star: float = 1.0
    a: float = 1.0
    adhesion_method: str = "neighbours"
    force_normal: str = "unit"
    name: str = field(default="CHA", init=False)

    def __post_init__(self):
        object.__setattr__(self, "eps", real_number(self.eps, "eps", nonnegative=True))
        object.__setattr__(self, "beta", real_number(self.beta, "beta", nonnegative=True))
        object.__setattr__(self, "rho", real_number(self.rho, "rho", positive=True))
        object.__setattr__(self, "A0", real_number(self.A0, "A0", nonnegative=True))
        object.__setattr__(self, "l_star", real_number(self.l_star, "l_star", positive=True))
        object.__setattr__(self, "a", real_number(self.a, "a", positive=True))
        if self.adhesion_method not in ("neighbours", "dense"):
            raise ValueError(
                f"adhesion_method must be 'neighbours' or 'dense', got {self.adhesion_method!r}"
            )
        if self.force_normal not in ("unit", "centred"):
            raise ValueError(
                f"force_normal must be 'unit' or 'centred', got {self.force_normal!r}")

    @property
    def kernel(self):
        """The :class:`AdhesionKernel`, or ``None`` when ``A0 = 0``."""
        return AdhesionKernel(self.A0, self.l_star, self.a) if self.A0 > 0 else None

    def check_resolution(self, x, y):
        """Raise ``ValueError`` for NaN, too few nodes, a clockwise curve, or ``L/N > l_star``."""
        x, y = _check_xy(x, y, self.min_nodes())
        if self.A0 > 0:
            L = float(np.sum(np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)))
            if L / x.size > self.l_star:
                raise ValueError(
                    f"N={x.size}: node spacing L/N = {L / x.size:.4g} exceeds l_star = "
                    f"{self.l_star:g}; the adhesion kernel is unresolved, use "
                    f"N >= {math.ceil(L / self.l_star)}"
                )

    def setup(self, x, y, *, L0=None, constraints=None):
        """Bind to initial positions (projected to equal chords).

        Parameters
        ----------
        x, y : array_like, shape (N,)
            Counter-clockwise nodes with (nearly) equal chords.
        L0 : float, optional
            Reference length of the penalty; default the length of ``x, y``
            (the paper's ``|Gamma_0|``). Pass the original ``L0`` when resuming
            from a later state (see ``CHASystem.bound_constants``).
        constraints : sequence of Constraint, optional
            ``FixedLength()`` / ``FixedArea()``: a length- or area-preserving flow
            (:mod:`qsa.flows.models.constrained`); ``None`` targets are the initial values.
        """
        self.check_resolution(x, y)
        return CHASystem(self, np.asarray(x, float), np.asarray(y, float),
                         adhesion_method=self.adhesion_method, L0=L0, constraints=constraints)
