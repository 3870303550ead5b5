"""Periodic grids on the parameter circle S = [0, 1).

Two discretizations share one interface:

``FiniteDifference(N)``
    Second-order centred stencils, the paper's (appendix "Discussion of
    Numerical Scheme"): a skew-symmetric first derivative
    ``(f[j+1] - f[j-1]) / 2h`` and the compact second difference. Operators are
    ``scipy.sparse`` CSR matrices, so every local operator costs O(N).
``Fourier(N)``
    Pseudo-spectral differentiation on N equispaced nodes (odd N only: with even
    N the derivative annihilates the Nyquist mode, which then shows up as a fake
    eigenvalue, Conventions and errata, section 4). Operators are dense ``ndarray``.

Besides the nodal derivative, each grid exposes an *edge* pair used by energies
that contain ``|grad_s kappa|^2``: ``edge_difference`` (nodes -> edges) and
``edge_average``. For finite differences the edges are the midpoints
``s_{j+1/2}``, which makes the discrete Laplacian compact (3-point) and keeps the
highest mode properly penalised; for Fourier the edges are the nodes.

The cumulative integral ``cumulative(f)`` approximates ``int_0^s f ds`` (so the
paper's ``D f = cumulative(f * g)``), to second order (trapezoid) or spectrally.

The interface is :mod:`qsa.discretize.grid`, the two grids
:mod:`qsa.discretize.finite_difference` and :mod:`qsa.discretize.fourier`.

Notes
-----
Equation labels: e:D_def (the operator D and its adjoint D-dagger).
"""

from qsa.discretize.finite_difference import FiniteDifference
from qsa.discretize.fourier import Fourier
from qsa.discretize.grid import MIN_NODES, Grid, cumulative_factors

__all__ = ["Grid", "FiniteDifference", "Fourier", "MIN_NODES", "cumulative_factors"]
