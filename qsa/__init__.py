"""qsa — quasi-steady and spectral analysis of closed planar interfaces.

The mathematics is Nguyen, Promislow & Wetton, "Quasisteady patterns in
interfaces: folding and faceting"; conventions and corrections of its printed
formulas are listed in the project's MATH notes and cited in each module.
"""

from qsa._version import __version__
from qsa.discretize import FiniteDifference, Fourier, Grid

__all__ = ["__version__", "FiniteDifference", "Fourier", "Grid"]
