"""Continuation of equilibria in one parameter: branches, folds, stability along a branch.

``continuation(energy_factory, curve, param, values, method=...)`` follows the
solutions of the square Newton system of :func:`qsa.equilibria.polish` by natural
or pseudo-arclength steps and returns a :class:`Branch` of :class:`BranchPoint` s,
with the :class:`Fold` s it passed and the points where ``det F_x`` changes sign
without a fold (possible branch points); ``stability=True`` counts the unstable
eigenvalues of every point with :func:`qsa.spectra.spectrum`.

This package stands above :mod:`qsa.equilibria` and :mod:`qsa.spectra` (it uses
both); ``qsa.equilibria.continuation`` is a deprecated alias of it.
"""

from qsa.continuation.branch import Branch, BranchPoint, Fold
from qsa.continuation.tracking import continuation

__all__ = ["Branch", "BranchPoint", "Fold", "continuation"]
