"""Two-point energies in the polishing system of :func:`polish`: ``V^n`` through the positions.

The adhesion normal velocity ``V^n = -(force . n + kappa B)`` (e:Adh-NV) is evaluated
from the node positions, not by the generic formula ``-[M-dagger nabla_I E]_1`` of its
gradient; the two agree in the continuum only. Energies that provide
``normal_velocity_jacobian`` (:class:`~qsa.energies.Adhesion`) are therefore
differentiated exactly through the state ``Y = (theta, x, y)``
(:mod:`qsa.energies.adhesion_velocity`)::

    dV = V_U dU + V_Y dY,     cY dY + cU dU = 0,

with ``g = L`` constant in the scaled-arc-length unknowns (``d/dL`` sums the ``g``
columns). On finite-difference grids ``dY`` become extra unknowns of the Newton
matrix (:class:`StateBorder`: lower-bidiagonal state rows, pair-sparse ``V_Y``), which
keeps O(N + pairs) entries; on Fourier grids, or when most node pairs interact (a long
kernel), ``V_Y Z`` is formed densely instead.

The rigid-motion identities ``<V^n, phi_j> = 0`` behind the unfolding of
:mod:`qsa.equilibria.system` then hold to the grid's accuracy: spectrally on Fourier
grids, to O(h^2) on finite differences, where the unfolding parameters are O(h^2) and
carry ``max|V^n|`` (the polished state solves ``V^n = -a.phi`` exactly).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from qsa.energies import EnergySum

__all__ = ["split_velocity_terms", "StateBorder", "add_velocity_jacobians"]


def split_velocity_terms(energy):
    """``(rest, implicit)``: the summands differentiated through their Hessian, and the others.

    ``implicit`` holds the terms with their own ``normal_velocity_jacobian``.

    Parameters
    ----------
    energy : Energy or None

    Returns
    -------
    rest : Energy or None
    implicit : tuple of Energy

    Examples
    --------
    >>> from qsa.energies import Adhesion, CanhamHelfrich
    >>> split_velocity_terms(CanhamHelfrich(0.1) + Adhesion(10.0, 0.5))
    (CanhamHelfrich(eps=0.1), (Adhesion(A0=10.0, l_star=0.5, a=1.0),))
    """
    if energy is None:
        return None, ()
    terms = energy.terms()
    implicit = tuple(t for t in terms if hasattr(t, "normal_velocity_jacobian"))
    rest = tuple(t for t in terms if not hasattr(t, "normal_velocity_jacobian"))
    if not rest:
        return None, implicit
    return (rest[0] if len(rest) == 1 else EnergySum(rest)), implicit


@dataclass(frozen=True, eq=False)
class StateBorder:
    """Extra unknowns of the Newton matrix: an implicit state ``Y1`` with sparse equations.

    The ``V^n`` rows get ``VY Y1``; the state rows are ``cK dkappa + cL dL + cY Y1 = 0``
    (:func:`~qsa.equilibria.system.assemble_jacobian` puts them after every other
    unknown, with zero right-hand side).

    Attributes
    ----------
    VY : sparse matrix, shape (N, m)
    cY : sparse matrix, shape (m, m)
    cK : sparse matrix, shape (m, N)
    cL : ndarray, shape (m,)
    """

    VY: Any  # sparse or dense
    cY: Any
    cK: Any
    cL: np.ndarray

    @property
    def size(self) -> int:
        """Number ``m`` of extra unknowns."""
        return int(self.cY.shape[0])


def add_velocity_jacobians(implicit, c, A, VL, low):
    """``(A, VL)`` with the exact ``dV^n/d(kappa, L)`` of the ``implicit`` terms added.

    Parameters
    ----------
    implicit : tuple of Energy
        Terms with ``normal_velocity_jacobian``.
    c : Curve
        Constant ``g = L``.
    A : matrix, shape (N, N)
        ``dV^n/dkappa`` of the other terms (sparse on finite differences).
    VL : ndarray, shape (N,)
        ``dV^n/dL`` of the other terms.
    low : list
        Extra-unknown terms of the Newton matrix; a :class:`StateBorder` is appended on
        the sparse path.

    Returns
    -------
    A : matrix, shape (N, N)
        Sparse (finite differences, short-range kernels) or dense.
    VL : ndarray, shape (N,)
    """
    if not implicit:
        return A, VL
    J = implicit[0].normal_velocity_jacobian(c)
    for t in implicit[1:]:
        J = J + t.normal_velocity_jacobian(c)
    N = c.N
    ones = np.ones(N)
    if sp.issparse(A) and J.VY.nnz < N * N:
        cY, cU = J.state_equations()
        low.append(StateBorder(J.VY, cY, cU[:, :N].tocsr(), cU[:, N:] @ ones))
        return A + J.VU[:, :N], VL + J.VU[:, N:] @ ones
    # most node pairs interact: the sparse LU would fill in, the dense Jacobian is smaller
    Jd = J.dense()
    A = A.toarray() if sp.issparse(A) else np.asarray(A)
    return A + Jd[:, :N], VL + Jd[:, N:] @ ones
