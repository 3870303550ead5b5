"""qsa — quasi-steady and spectral analysis of closed planar interfaces.

The mathematics is Nguyen, Promislow & Wetton, "Quasisteady patterns in
interfaces: folding and faceting"; conventions and corrections of its printed
formulas are cited in each module (``# NOTE:`` marks a departure from the paper).
References of the form "Conventions and errata, section N" are to the page of
that name in the documentation, which lists every convention and every erratum
of the paper with the test that guards it.

Examples
--------
>>> import numpy as np
>>> from qsa import Curve, Fourier
>>> from qsa.energies import Faceting, Perimeter
>>> c = Curve.polar(lambda t: 1 + 0.2 * np.cos(3 * t), Fourier(65))
>>> E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
>>> V = E.normal_velocity(c)
"""

from qsa import geometry
from qsa._version import __version__
from qsa.curve import Curve
from qsa.discretize import FiniteDifference, Fourier, Grid

__all__ = ["__version__", "Curve", "FiniteDifference", "Fourier", "Grid", "geometry"]
