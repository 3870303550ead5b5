"""qsa — quasi-steady and spectral analysis of closed planar interfaces.

The mathematics is Nguyen, Promislow & Wetton, "Quasisteady patterns in
interfaces: folding and faceting"; conventions and corrections of its printed
formulas are cited in each module (``# NOTE:`` marks a departure from the paper).
References of the form "Conventions and errata, section N" are to the page of
that name in the documentation, which lists every convention and every erratum
of the paper with the test that guards it.

Results
-------
Every solver returns a frozen result (:class:`~qsa.equilibria.PolishResult`,
:class:`~qsa.spectra.Spectrum`, :class:`~qsa.continuation.Branch`,
:class:`~qsa.reduction.FrontODEResult`, :class:`~qsa.flows.FlowResult`) that reports
how it ended in the same way:

* ``status`` -- ``0`` success; positive: success with a caveat (e.g. converged to
  the round-off floor, stopped by a callback, some eigenvalues unresolved);
  negative: failure (the result keeps the last good state).
* ``success`` -- ``status >= 0``.
* ``message`` -- starts with ``MESSAGES[status]``, where ``MESSAGES`` is the table of
  the result's module (:data:`qsa.equilibria.newton.MESSAGES`,
  :data:`qsa.spectra.result.MESSAGES`, :data:`qsa.continuation.branch.MESSAGES`,
  :data:`qsa.reduction.integrate.MESSAGES`, :data:`qsa.flows.solve.MESSAGES`), followed
  by the particulars of the run.
* counters, where they apply: ``n_steps`` (accepted steps), ``n_rejected`` (rejected
  steps), ``n_newton`` (Newton iterations), ``n_lu`` (factorizations of a Newton or
  Jacobian matrix), ``n_rhs`` (evaluations of a right-hand side). Earlier names
  (``n_iter``, ``n_factorizations``, ``nfev``) remain as read-only aliases.

Bad input is not a status: it raises ``ValueError`` naming the argument.

Imports
-------
Imports sit at the top of each module. The exceptions are optional dependencies
(numba, dask, tqdm), imported where they are used, and the command line, which loads
a subcommand only when it runs. The layers import one way (``tests/test_layering.py``
states the rules): discretize, curve, geometry, energies and constraints at the
bottom; equilibria, spectra and flows side by side above them; continuation above
equilibria and spectra; reduction, paper, plotting and the command line on top.

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
