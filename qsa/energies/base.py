"""The Energy protocol, sums of energies, and the perimeter penalty.

Every energy provides, for a :class:`~qsa.curve.Curve` ``c``:

``energy(c) -> float``
    The discrete energy.
``gradient(c) -> ndarray (2N,)``
    ``nabla_I E = (d_kappa E, d_g E)`` with respect to ``<f, h> = int f h dsigma``:
    ``d/d delta E(U + delta U1) = <nabla_I E, U1>`` exactly (for the discrete
    energy and the discrete inner product ``sum f h dsigma``).
``hessian(c) -> matrix (2N, 2N)``
    ``nabla_I^2 E`` with respect to ``<.,.>``: ``d^2/d delta^2 E(U + delta U1) =
    <H U1, U1>`` along straight paths; dsigma-self-adjoint.
``normal_velocity(c) -> ndarray (N,)``
    ``V^n = -[M-dagger nabla_I E]_1 = -G d_kappa E - kappa (g d_g E)`` (e:L2grad),
    outward; the L2(dsigma) gradient flow dissipates ``dE/dt = -int (V^n)^2 dsigma``.

Energies add: ``Faceting(...) + Perimeter(...)`` is an :class:`EnergySum`, whose
normal velocity applies the Laplace-Beltrami operator once for all the summands
that use the generic formula (:func:`generic_normal_velocity`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from qsa._checks import real_number
from qsa.curve import Curve
from qsa.geometry import apply_laplace_s
from qsa.linalg import ReducedHessian, SparsePlusLowRank

__all__ = ["Energy", "EnergySum", "Perimeter", "add_matrices", "generic_normal_velocity"]


def add_matrices(a, b):
    """Sum of two operator matrices of possibly different kinds (dense, sparse, low rank).

    Parameters
    ----------
    a, b : ndarray, sparse matrix, SparsePlusLowRank or ReducedHessian, shape (n, m)

    Returns
    -------
    ndarray, sparse matrix, SparsePlusLowRank or ReducedHessian, shape (n, m)
        Dense if either is dense; else a :class:`~qsa.linalg.ReducedHessian` if either
        is one (the others' terms join its sparse and low-rank parts); a
        :class:`~qsa.linalg.SparsePlusLowRank` if either is one and the other is
        sparse; sparse if both are.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> type(add_matrices(sp.identity(2), np.eye(2))).__name__
    'ndarray'
    >>> sp.issparse(add_matrices(sp.identity(2), sp.identity(2)))
    True
    >>> type(add_matrices(np.eye(2), sp.identity(2))).__name__
    'ndarray'
    """
    if isinstance(b, ReducedHessian) and not isinstance(a, ReducedHessian):
        return b + a
    if isinstance(a, ReducedHessian):
        return a + b
    if isinstance(b, SparsePlusLowRank) and not isinstance(a, SparsePlusLowRank):
        return b + a
    if sp.issparse(a) and isinstance(b, np.ndarray):
        return b + a.toarray()
    if isinstance(a, np.ndarray) and sp.issparse(b):  # ndarray + sparse would be np.matrix
        return a + b.toarray()
    return a + b


# The name under which the energies' modules imported the scalar check.
_check_param = real_number


def generic_normal_velocity(c: Curve, mu, xi) -> np.ndarray:
    """``V^n = -G mu - kappa xi = (Delta_s + kappa^2) mu - kappa xi`` (e:L2grad), shape (N,).

    ``V^n = -[M-dagger nabla_I E]_1`` for ``nabla_I E = (mu, xi / g)``, with the
    adjoint in ``<f, h> = int f h dsigma`` and ``Delta_s`` applied without forming
    its matrix (:func:`qsa.geometry.apply_laplace_s`).

    Parameters
    ----------
    c : Curve
    mu : ndarray, shape (N,)
        ``d_kappa E``.
    xi : ndarray, shape (N,)
        ``g d_g E``.

    Returns
    -------
    ndarray, shape (N,)

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> c = Curve.circle(2.0, Fourier(17))
    >>> # CanhamHelfrich(eps=1): mu = kappa, xi = kappa^2 / 2, so V^n = kappa^3 / 2
    >>> bool(np.allclose(generic_normal_velocity(c, c.kappa, c.kappa**2 / 2), 1 / 16))
    True
    """
    return apply_laplace_s(c, mu) + c.kappa**2 * mu - c.kappa * xi


def _uses_generic_normal_velocity(energy) -> bool:
    """Whether ``energy.normal_velocity`` is the generic formula of its gradient."""
    return type(energy).normal_velocity is Energy.normal_velocity


class Energy(ABC):
    """An energy of a closed curve in intrinsic coordinates (see the module docstring).

    Subclasses implement :meth:`energy`, :meth:`gradient` and :meth:`hessian`; the
    normal velocity and ``+`` (an :class:`EnergySum`) come for free. Energies take no
    constructor arguments here; the models (``Faceting``, ``Perimeter`` ...) do.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting, Perimeter
    >>> E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
    >>> isinstance(E, Energy), len(E.terms())
    (True, 2)
    """

    @abstractmethod
    def energy(self, c: Curve) -> float:
        """The discrete energy ``E(U)``.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        float

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies import CanhamHelfrich
        >>> round(CanhamHelfrich(eps=1.0).energy(Curve.circle(0.5, Fourier(17))) / np.pi, 12)
        2.0
        """

    @abstractmethod
    def gradient(self, c: Curve) -> np.ndarray:
        """``nabla_I E = (d_kappa E, d_g E)`` with respect to ``<f, h> = int f h dsigma``.

        ``d/d delta E(U + delta U1) = <nabla_I E, U1>`` exactly for the discrete energy
        and the discrete inner product ``sum f h dsigma``.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray, shape (2N,)
            Stacked ``[d_kappa E, d_g E]``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies import Faceting, Perimeter
        >>> E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
        >>> U1 = np.concatenate([np.cos(2 * np.pi * c.grid.s), np.ones(33)])
        >>> d, w = 1e-6, np.concatenate([c.dsigma, c.dsigma])
        >>> fd = (E.energy(c.with_U(c.U + d * U1)) - E.energy(c.with_U(c.U - d * U1))) / (2 * d)
        >>> bool(np.isclose(fd, E.gradient(c) @ (U1 * w), rtol=1e-6))
        True
        """

    @abstractmethod
    def hessian(self, c: Curve):
        """``nabla_I^2 E`` with respect to ``<f, h> = int f h dsigma``; dsigma-self-adjoint.

        ``d^2/d delta^2 E(U + delta U1) = <H U1, U1>`` along straight paths.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        matrix, shape (2N, 2N)
            Dense ``ndarray`` (Fourier), sparse CSR,
            :class:`~qsa.linalg.SparsePlusLowRank` or :class:`~qsa.linalg.ReducedHessian`
            (finite differences).

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies import Faceting, Perimeter
        >>> E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
        >>> U1 = np.concatenate([np.cos(2 * np.pi * c.grid.s), np.ones(33)])
        >>> d, w = 1e-6, np.concatenate([c.dsigma, c.dsigma])
        >>> f = lambda t: E.energy(c.with_U(c.U + t * U1))
        >>> d = 1e-4
        >>> second = (f(d) - 2 * f(0) + f(-d)) / d**2
        >>> bool(np.isclose(second, (E.hessian(c) @ U1) @ (U1 * w), rtol=1e-5))
        True
        >>> A = w[:, None] * E.hessian(c)  # W H is symmetric
        >>> bool(np.allclose(A, A.T))
        True
        """


    def factored_hessian(self, c: Curve):
        """``nabla_I^2 E`` in the form spectral solvers want: high-order blocks as factors.

        Equal to :meth:`hessian` as an operator. Energies whose Hessian has blocks of
        order 4 (second-order densities, :class:`~qsa.energies.SecondOrderEnergy`) return,
        on finite-difference grids, a :class:`~qsa.linalg.ReducedHessian`
        ``S + Lf B Rf`` holding those blocks as their order-2 factors: formed, the
        rounding of their ``h^-4`` entries adds up coherently and limits the slow
        eigenvalues at large ``N`` (:mod:`qsa.spectra.factored` solves with the factors).
        The default is :meth:`hessian`.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        matrix, shape (2N, 2N)
            As :meth:`hessian`, or a :class:`~qsa.linalg.ReducedHessian`.
        """
        return self.hessian(c)
    def normal_velocity(self, c: Curve) -> np.ndarray:
        """Outward normal velocity ``V^n = -G d_kappa E - kappa (g d_g E)`` (e:L2grad).

        ``V^n = -[M-dagger nabla_I E]_1`` with the adjoint in ``<f, h> = int f h dsigma``.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray, shape (N,)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies import CanhamHelfrich
        >>> c = Curve.circle(2.0, Fourier(17))
        >>> Vn = CanhamHelfrich(eps=1.0).normal_velocity(c)  # eps kappa^3 / 2
        >>> bool(np.allclose(Vn, 1 / 16))
        True
        """
        grad = self.gradient(c)
        return generic_normal_velocity(c, grad[: c.N], c.g * grad[c.N :])

    def terms(self) -> tuple:
        """The summands (a single energy is its own only term).

        Returns
        -------
        tuple of Energy

        Examples
        --------
        >>> from qsa.energies import CanhamHelfrich
        >>> E = CanhamHelfrich(1.0)
        >>> E.terms() == (E,)
        True
        """
        return (self,)

    def gradient_parts(self, c: Curve) -> tuple:
        """Parts of ``nabla_I E`` that add up to :meth:`gradient`: the terms of ``V^n``.

        A single energy is one part; a local energy has one part per density and a
        sum the parts of its summands. :func:`qsa.energies.residual_scale` measures
        ``V^n`` against the largest term of ``V^n`` of any part.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        tuple of ndarray, each shape (2N,)
            Gradients in ``<f, h> = int f h dsigma``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies import Faceting, Perimeter
        >>> E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), Fourier(33))
        >>> parts = E.gradient_parts(c)  # |p|^2 and W(kappa) densities, then the perimeter
        >>> len(parts), bool(np.allclose(sum(parts), E.gradient(c)))
        (3, True)
        """
        return (self.gradient(c),)

    def __add__(self, other):
        if not isinstance(other, Energy):
            return NotImplemented
        return EnergySum(self.terms() + other.terms())

    def params(self) -> dict:
        """JSON-serialisable parameters, with the energy's class name.

        Returns
        -------
        dict
            ``{"energy": class name, <scalar attributes>}``; a sum gives
            ``{"energy": "sum", "terms": [...]}``.

        Examples
        --------
        >>> from qsa.energies import CanhamHelfrich
        >>> CanhamHelfrich(0.5).params()
        {'energy': 'CanhamHelfrich', 'eps': 0.5}
        """
        out: dict[str, Any] = {"energy": type(self).__name__}
        for k, v in getattr(self, "__dict__", {}).items():
            if isinstance(v, (int, float, str)):
                out[k] = v
        return out


@dataclass(frozen=True)
class EnergySum(Energy):
    """Sum of energies; each method adds its summands' results.

    Built by ``+`` on energies (sums are flattened).

    Parameters
    ----------
    parts : tuple of Energy

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import CanhamHelfrich, Perimeter
    >>> E = CanhamHelfrich(1.0) + Perimeter(beta=1.0, L_star=6.0)
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> type(E).__name__, len(E.terms())
    ('EnergySum', 2)
    >>> bool(abs(E.energy(c) - sum(e.energy(c) for e in E.terms())) < 1e-14)
    True
    """

    parts: tuple

    def terms(self):
        return tuple(self.parts)

    def energy(self, c):
        return float(sum(e.energy(c) for e in self.parts))

    def gradient(self, c):
        return sum(e.gradient(c) for e in self.parts)

    def hessian(self, c):
        H = self.parts[0].hessian(c)
        for e in self.parts[1:]:
            H = add_matrices(H, e.hessian(c))
        return H

    def factored_hessian(self, c):
        H = self.parts[0].factored_hessian(c)
        for e in self.parts[1:]:
            H = add_matrices(H, e.factored_hessian(c))
        return H

    def gradient_parts(self, c):
        return tuple(g for e in self.parts for g in e.gradient_parts(c))

    def normal_velocity(self, c):
        """``V^n`` of the sum: the summands' own velocities plus one generic term.

        The summands that use the generic formula :func:`generic_normal_velocity`
        contribute their ``(mu, xi)``, which are added first, so that ``Delta_s``
        is applied once (O(N^2) per application on Fourier grids); the others
        (e.g. :class:`Perimeter`, two-point energies) add their own ``V^n``.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray, shape (N,)
            Equal (to round-off) to ``sum(e.normal_velocity(c) for e in self.terms())``.
        """
        N = c.N
        V = np.zeros(N)
        mu = np.zeros(N)
        xi = np.zeros(N)
        generic = False
        for e in self.parts:
            if _uses_generic_normal_velocity(e):
                grad = e.gradient(c)
                mu += grad[:N]
                xi += c.g * grad[N:]
                generic = True
            else:
                V += e.normal_velocity(c)
        if generic:
            V += generic_normal_velocity(c, mu, xi)
        return V

    def params(self):
        return {"energy": "sum", "terms": [e.params() for e in self.parts]}

    def __repr__(self):
        return " + ".join(repr(e) for e in self.parts)


@dataclass(frozen=True)
class Perimeter(Energy):
    """Perimeter penalty ``beta/2 (L - L*)^2``, ``L = int g ds`` (e:Facet).

    Parameters
    ----------
    beta : float
        Penalty strength, ``>= 0``.
    L_star : float
        Reference length, ``> 0``.

    Notes
    -----
    Gradient ``(0, beta (L - L*) / g)``. The Hessian is rank one,
    ``(H U1)_g = (beta / g) int g1 ds`` (Conventions and errata, section 4); on finite-difference
    grids it is returned factored as :class:`~qsa.linalg.SparsePlusLowRank`.

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Perimeter
    >>> c = Curve.circle(1.0, Fourier(17))
    >>> E = Perimeter(beta=2.0, L_star=6.0)
    >>> bool(abs(E.energy(c) - (2 * np.pi - 6.0) ** 2) < 1e-12)  # beta/2 (L - L*)^2
    True
    """

    beta: float
    L_star: float

    def __post_init__(self):
        object.__setattr__(self, "beta", real_number(self.beta, "beta", nonnegative=True))
        object.__setattr__(self, "L_star", real_number(self.L_star, "L_star", positive=True))

    def energy(self, c):
        return 0.5 * self.beta * (c.length() - self.L_star) ** 2

    def gradient(self, c):
        return np.concatenate([np.zeros(c.N), self.beta * (c.length() - self.L_star) / c.g])

    def normal_velocity(self, c):
        return -self.beta * (c.length() - self.L_star) * c.kappa

    def hessian(self, c):
        N = c.N
        U = np.concatenate([np.zeros(N), self.beta / c.g])
        V = np.concatenate([np.zeros(N), c.grid.weights])
        if c.grid.sparse:
            return SparsePlusLowRank(sp.csr_matrix((2 * N, 2 * N)), U, V)
        return np.outer(U, V)
