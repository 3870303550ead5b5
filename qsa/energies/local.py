"""First-order local energies ``E = int F(nabla_s kappa, kappa) dsigma`` (e:FOE).

Discretization
--------------
A density term ``f(p, k)`` (``p = nabla_s kappa``) is placed either on the
grid's *edges* or on its *nodes*:

* edge terms: ``E = sum_e w_e g_e f(p_e, k_e)`` with ``p_e = (E kappa)_e / g_e``,
  ``k_e = (A kappa)_e``, ``g_e = (A g)_e`` — ``E`` the grid's edge difference
  and ``A`` its edge average (midpoints for finite differences, which gives
  the compact Laplacian; the nodes themselves for Fourier);
* node terms: ``E = sum_j w_j g_j f(p_j, kappa_j)`` (for densities of kappa only).

The faceting energy puts ``alpha^2/2 |nabla_s kappa|^2`` on edges and ``W(kappa)``
on nodes; Canham-Helfrich puts ``eps/2 kappa^2`` on nodes. With the linear maps
``q = E kappa``, ``k_e = A kappa``, ``g_e = A g`` and ``Phi(g_e, q, k_e) =
g_e f(q/g_e, k_e)``, the exact derivatives of the discrete energy are ::

    dE/dkappa = E^T (w f_p) + A^T (w g_e f_k),   dE/dg = A^T (w (f - p f_p)),

and the Euclidean Hessian is ``T^T B T`` with ``T = [[E, 0], [A, 0], [0, A]]`` and
the 3x3 block of diagonals ``B = w * d^2 Phi``. The ``<.,.>`` gradient and
Hessian divide rows by ``dsigma``. In the continuum these are e:FoE_IG,
``nabla_I E = (-nabla_s F_1 + F_0, (-F_1 nabla_s kappa + F)/g)``, and e:cF-Hessian
(Conventions and errata, section 4: that printed Hessian is right).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from qsa._checks import real_number
from qsa.curve import Curve
from qsa.energies.base import Energy
from qsa.linalg import ReducedHessian

__all__ = ["Density", "LocalEnergy", "FirstOrderEnergy"]


@dataclass(frozen=True)
class Density:
    """A density ``f(p, k)`` with its first and second partial derivatives.

    Parameters
    ----------
    f, f_p, f_k, f_pp, f_pk, f_kk : callable
        Vectorised functions of ``(p, k)``; ``p = nabla_s kappa``, ``k = kappa``.
    placement : {"edge", "node"}
        Where the density is evaluated (see the module docstring). Use "node"
        only for densities that do not depend on ``p``.
    uses_p : bool
        Whether the density depends on ``p``.

    Examples
    --------
    >>> import numpy as np
    >>> zero = lambda p, k: 0 * k
    >>> d = Density(lambda p, k: k**2, zero, lambda p, k: 2 * k, zero, zero,
    ...             lambda p, k: 2 + 0 * k, placement="node", uses_p=False)
    >>> float(d.f(0.0, 3.0)), d.placement
    (9.0, 'node')
    """

    f: Callable[..., Any]
    f_p: Callable[..., Any]
    f_k: Callable[..., Any]
    f_pp: Callable[..., Any]
    f_pk: Callable[..., Any]
    f_kk: Callable[..., Any]
    placement: str = "edge"
    uses_p: bool = True

    def __post_init__(self):
        if self.placement not in ("edge", "node"):
            raise ValueError(f"placement must be 'edge' or 'node', got {self.placement!r}")

    def energy(self, c: Curve) -> float:
        """This term's discrete energy ``sum w g f(p, k)`` (module docstring)."""
        _, _, w, ge, ke, p = _maps(c, self)
        return float(np.sum(w * ge * _as_array(self.f(p, ke), ke)))

    def euclidean_gradient(self, c: Curve) -> np.ndarray:
        """This term's ``(dE/dkappa_j, dE/dg_j)``, shape (2N,) (plain partial derivatives)."""
        Ed, A, w, ge, ke, p = _maps(c, self)
        f = _as_array(self.f(p, ke), ke)
        fk = _as_array(self.f_k(p, ke), ke)
        dk = _apply_T(A, w * ge * fk)
        if self.uses_p:
            fp = _as_array(self.f_p(p, ke), ke)
            dk = dk + Ed.T @ (w * fp)
            dg = _apply_T(A, w * (f - p * fp))
        else:
            dg = _apply_T(A, w * f)
        return np.concatenate([dk, dg])

    def euclidean_hessian(self, c: Curve):
        """This term's Euclidean Hessian ``T^T B T`` (module docstring), shape (2N, 2N)."""
        grid = c.grid
        S = grid.sandwich  # S(X, b, Y) = X^T diag(b) Y
        Ed, A, w, ge, ke, p = _maps(c, self)
        fk = _as_array(self.f_k(p, ke), ke)
        fkk = _as_array(self.f_kk(p, ke), ke)
        if self.uses_p:
            fpp = _as_array(self.f_pp(p, ke), ke)
            fpk = _as_array(self.f_pk(p, ke), ke)
            # Phi = g_e f(q/g_e, k_e); its second derivatives in (q, k_e, g_e):
            Bqq, Bqk, Bqg = w * fpp / ge, w * fpk, -w * p * fpp / ge
            Bkk, Bkg, Bgg = w * ge * fkk, w * (fk - p * fpk), w * p**2 * fpp / ge
            kk = S(Ed, Bqq, Ed) + S(Ed, Bqk, A) + S(A, Bqk, Ed) + S(A, Bkk, A)
            kg = S(Ed, Bqg, A) + S(A, Bkg, A)
            gg = S(A, Bgg, A)
        else:
            kk = S(A, w * ge * fkk, A)
            kg = S(A, w * fk, A)
            gg = sp.csr_matrix((c.N, c.N)) if grid.sparse else np.zeros((c.N, c.N))
        if grid.sparse:
            return sp.bmat([[kk, kg], [kg.T, gg]], format="csr")
        return np.block([[kk, kg], [kg.T, gg]])


def _maps(c: Curve, term: Density):
    grid = c.grid
    if term.placement == "edge":
        Ed, A, w = grid.edge_difference(), grid.edge_average(), grid.edge_weights
        if not grid.sparse:
            A = None  # Fourier: the edges are the nodes
    else:
        Ed, A, w = grid.derivative(), None, grid.weights
    ge = c.g if A is None else A @ c.g
    ke = c.kappa if A is None else A @ c.kappa
    p = (Ed @ c.kappa) / ge if term.uses_p else np.zeros_like(ke)
    return Ed, A, w, ge, ke, p


def _apply_T(A, v):
    """``A^T v``; ``A = None`` is the identity."""
    return v if A is None else A.T @ v


def _as_array(v, like):
    return np.broadcast_to(np.asarray(v, dtype=float), like.shape)


class LocalEnergy(Energy):
    """Sum of local density terms (see the module docstring); subclasses define ``densities``.

    Gradients and Hessians are those of the discrete energy, exactly: Euclidean
    (plain partial derivatives) or with respect to ``<f, h> = int f h dsigma`` (rows
    divided by ``dsigma``). A density term is any object with ``energy(c)``,
    ``euclidean_gradient(c)`` and ``euclidean_hessian(c)``: a first-order
    :class:`Density`, or a second-order
    :class:`~qsa.energies.second_order.SecondOrderDensity`.

    Examples
    --------
    >>> import numpy as np
    >>> from qsa import Curve, Fourier
    >>> from qsa.energies import Faceting
    >>> E = Faceting(alpha=0.1, kstar=5.0)
    >>> isinstance(E, LocalEnergy), len(E.densities())
    (True, 2)
    """

    def densities(self) -> tuple:
        """The density terms.

        Returns
        -------
        tuple of Density or SecondOrderDensity
        """
        raise NotImplementedError

    def energy(self, c):
        total = 0.0
        for t in self.densities():
            total += t.energy(c)
        return total

    def euclidean_gradient(self, c) -> np.ndarray:
        """``(dE/dkappa_j, dE/dg_j)``: plain partial derivatives (Euclidean gradient).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray, shape (2N,)
            Equal to ``gradient(c) * [dsigma, dsigma]``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies import Faceting
        >>> E, c = Faceting(0.1, 5.0), Curve.circle(1.0, Fourier(17))
        >>> w = np.concatenate([c.dsigma, c.dsigma])
        >>> bool(np.allclose(E.euclidean_gradient(c), E.gradient(c) * w))
        True
        """
        out = np.zeros(2 * c.N)
        for t in self.densities():
            out += t.euclidean_gradient(c)
        return out

    def gradient(self, c):
        """``nabla_I E`` in ``<f, h> = int f h dsigma`` (e:FoE_IG).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        ndarray, shape (2N,)
            ``[d_kappa E, d_g E]``; continuum ``(-nabla_s F_1 + F_0, (-F_1 nabla_s kappa
            + F)/g)``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies import Faceting, DoubleWell
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> grad = Faceting(0.1, 5.0).gradient(c)  # (W'(1), W(1)/g) on the unit circle
        >>> bool(np.allclose(grad[:17], DoubleWell(5.0).dW(1.0)))
        True
        >>> bool(np.allclose(grad[17:], DoubleWell(5.0).W(1.0) / (2 * np.pi)))
        True
        """
        ds = c.dsigma
        return self.euclidean_gradient(c) / np.concatenate([ds, ds])

    def euclidean_hessian(self, c):
        """Second partial derivatives of the discrete energy (Euclidean Hessian).

        Parameters
        ----------
        c : Curve

        Returns
        -------
        sparse CSR matrix or ndarray, shape (2N, 2N)
            Symmetric; ``hessian(c)`` is it with rows divided by ``dsigma``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, FiniteDifference
        >>> from qsa.energies import Faceting
        >>> c = Curve.circle(1.0, FiniteDifference(16))
        >>> H = Faceting(0.1, 5.0).euclidean_hessian(c)
        >>> H.shape, bool(abs(H - H.T).max() < 1e-12)
        ((32, 32), True)
        """
        total = None
        for t in self.densities():
            H = t.euclidean_hessian(c)
            total = H if total is None else total + H
        return total

    def hessian(self, c):
        """``nabla_I^2 E`` in ``<f, h> = int f h dsigma`` (e:cF-Hessian); dsigma-self-adjoint.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        sparse CSR matrix or ndarray, shape (2N, 2N)
            ``d^2/d delta^2 E(U + delta U1) = <H U1, U1>``.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies import CanhamHelfrich
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> H = CanhamHelfrich(eps=2.0).hessian(c)
        >>> U1 = np.concatenate([np.ones(17), np.zeros(17)])  # kappa -> kappa + 1
        >>> w = np.concatenate([c.dsigma, c.dsigma])
        >>> round(float((H @ U1) @ (U1 * w) / np.pi), 10)  # eps int 1 dsigma = 4 pi
        4.0
        """
        ds = c.dsigma
        winv = 1.0 / np.concatenate([ds, ds])
        H = self.euclidean_hessian(c)
        if c.grid.sparse:
            return (sp.diags(winv) @ H).tocsr()
        return H * winv[:, None]

    def factored_hessian(self, c):
        """:meth:`hessian` with the order-4 blocks of second-order densities kept factored.

        On finite-difference grids, when a density provides
        ``euclidean_hessian_parts`` (``H_rest + T2^T B2 T2``,
        :class:`~qsa.energies.second_order.SecondOrderDensity`), the result is the
        :class:`~qsa.linalg.ReducedHessian` ``W^-1 (H_rest + T^T B T)`` with no implicit
        state (``T`` the stacked ``T2``, ``B`` their block-diagonal ``B2``,
        ``W = diag(dsigma, dsigma)``); otherwise :meth:`hessian`.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        sparse CSR matrix, ndarray or ReducedHessian, shape (2N, 2N)

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, FiniteDifference
        >>> from qsa.energies import FunctionalizedCurvature
        >>> c = Curve.polar(lambda t: 1 + 0.1 * np.cos(3 * t), FiniteDifference(48))
        >>> E = FunctionalizedCurvature(0.1, 8.0, kstar=4.0)
        >>> H = E.factored_hessian(c)
        >>> type(H).__name__, bool(np.allclose(H.toarray(), E.hessian(c).toarray()))
        ('ReducedHessian', True)
        """
        if not c.grid.sparse or not any(hasattr(t, "euclidean_hessian_parts")
                                        for t in self.densities()):
            return self.hessian(c)
        rest, Ts, Bs = None, [], []
        for t in self.densities():
            if hasattr(t, "euclidean_hessian_parts"):
                H, T2, B2 = t.euclidean_hessian_parts(c)
                Ts.append(T2)
                Bs.append(B2)
            else:
                H = t.euclidean_hessian(c)
            rest = H if rest is None else rest + H
        ds = c.dsigma
        winv = sp.diags(1.0 / np.concatenate([ds, ds]))
        T = sp.vstack(Ts).tocsr()
        p = T.shape[0]
        empty = sp.csr_matrix((0, p))
        return ReducedHessian(sp.block_diag(Bs, format="csr"), empty, sp.csr_matrix((0, 0)),
                              sp.csr_matrix((0, 0)), empty, left=(winv @ T.T).tocsr(), right=T,
                              S=(winv @ rest).tocsr())

    def gradient_parts(self, c):
        """``nabla_I`` of each density term separately, in ``<f, h> = int f h dsigma``.

        Parameters
        ----------
        c : Curve

        Returns
        -------
        tuple of ndarray, each shape (2N,)
            One per :meth:`densities` entry; they add up to :meth:`gradient`.

        Examples
        --------
        >>> import numpy as np
        >>> from qsa import Curve, Fourier
        >>> from qsa.energies import Faceting
        >>> c = Curve.circle(1.0, Fourier(17))
        >>> smooth, well = Faceting(0.1, 5.0).gradient_parts(c)  # |p|^2 vanishes on a circle
        >>> bool(np.allclose(smooth, 0)), bool(np.allclose(well[:17], 6.0))  # W'(1) = 6
        (True, True)
        """
        return tuple(_OneDensity(d).gradient(c) for d in self.densities())


class _OneDensity(LocalEnergy):
    """One density term of a local energy, as an energy of its own."""

    def __init__(self, density: Density):
        self._density = density

    def densities(self):
        return (self._density,)


class FirstOrderEnergy(LocalEnergy):
    """A user-defined first-order energy ``int F(nabla_s kappa, kappa) dsigma``.

    Parameters
    ----------
    F, F_p, F_k, F_pp, F_pk, F_kk : callable
        The density and its partial derivatives, vectorised in ``(p, k)``
        (``F_1 = F_p``, ``F_0 = F_k`` in the paper's notation).

    Examples
    --------
    >>> from qsa import Curve, Fourier
    >>> E = FirstOrderEnergy(F=lambda p, k: 0.5 * k**2, F_p=lambda p, k: 0 * p,
    ...     F_k=lambda p, k: k, F_pp=lambda p, k: 0 * p, F_pk=lambda p, k: 0 * p,
    ...     F_kk=lambda p, k: 1 + 0 * k)
    >>> round(E.energy(Curve.circle(1.0, Fourier(17))), 12)  # = pi for the unit circle
    3.14159265359
    """

    def __init__(self, F, F_p, F_k, F_pp, F_pk, F_kk):
        for name, fn in dict(F=F, F_p=F_p, F_k=F_k, F_pp=F_pp, F_pk=F_pk, F_kk=F_kk).items():
            if not callable(fn):
                raise ValueError(f"{name} must be callable")
        self._density = Density(F, F_p, F_k, F_pp, F_pk, F_kk, placement="edge")

    def densities(self):
        """``(Density(F, ...),)`` on edges."""
        return (self._density,)


def quadratic_gradient_density(coef: float) -> Density:
    """``coef/2 |p|^2`` on edges (any real ``coef``; negative in
    :class:`~qsa.energies.FunctionalizedCurvature`)."""
    coef = real_number(coef, "coefficient")
    zero = lambda p, k: np.zeros_like(p)
    return Density(f=lambda p, k: 0.5 * coef * p**2, f_p=lambda p, k: coef * p, f_k=zero,
                   f_pp=lambda p, k: np.full_like(p, coef), f_pk=zero, f_kk=zero,
                   placement="edge")


def curvature_density(F, dF, d2F) -> Density:
    """A density of kappa alone, ``F(kappa)``, on nodes."""
    zero = lambda p, k: np.zeros_like(k)
    return Density(f=lambda p, k: F(k), f_p=zero, f_k=lambda p, k: dF(k), f_pp=zero, f_pk=zero,
                   f_kk=lambda p, k: d2F(k), placement="node", uses_p=False)
