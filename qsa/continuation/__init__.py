"""Continuation of equilibria in one parameter: branches, stability, bifurcations, switching.

``continuation(energy_factory, curve, param, values, method=...)`` follows the
solutions of the square Newton system of :func:`qsa.equilibria.polish` by natural
or pseudo-arclength steps and returns a :class:`Branch` of :class:`BranchPoint` s:
the unstable eigenvalues of every point are counted per Bloch sector of the branch's
symmetry (:mod:`qsa.spectra.symmetry`), every change of the count is located and
reported as a :class:`Bifurcation` (folds included), with its critical eigenvectors
(:class:`CriticalMode`) and their symmetry label; ``switch_branch(branch, bifurcation)``
follows the bifurcating branches, one per symmetry-distinct direction.

This package stands above :mod:`qsa.equilibria` and :mod:`qsa.spectra` (it uses
both); ``qsa.equilibria.continuation`` is a deprecated alias of it.
"""

from qsa.continuation.branch import (
    MESSAGES,
    Bifurcation,
    Branch,
    BranchPoint,
    CriticalMode,
    Fold,
)
from qsa.continuation.files import save_branch, save_branches
from qsa.continuation.switching import switch_branch
from qsa.continuation.tracking import continuation

__all__ = ["Bifurcation", "Branch", "BranchPoint", "CriticalMode", "Fold", "MESSAGES",
           "continuation", "save_branch", "save_branches", "switch_branch"]
